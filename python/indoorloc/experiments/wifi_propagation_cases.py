"""The folds of ``indoorloc fusion evaluate`` prepared for the propagation-model study
(:mod:`indoorloc.experiments.wifi_propagation_study`): per floor and fold the training
fingerprint database (its arrays), and per test walk its waypoints, coverage, query fingerprints
(in the database's columns) and default kNN fixes. Cached in a pickle so that a sweep does not
redo the PDR and the matching.
"""

from __future__ import annotations

import pickle
from pathlib import Path
from types import SimpleNamespace
from typing import Any, Dict, Optional, Sequence

import numpy as np


def build_cases(data_root: Path, floors: Sequence[str], seed: int, log=print) -> Dict[str, Any]:
    """Per floor: ``{"geojson_path", "number", "folds": [{"database": SimpleNamespace(rss_dbm (N, K),
    positions_m (N, 2), floors (N,), walk_index (N,), bssids), "walks": [dict]}]}``; each walk dict
    holds ``walk_id, duration_s, waypoint_t_s (W,), waypoint_xy_m (W, 2), coverage_m (W,),
    query_t_s (Q,), query_rss_dbm (Q, K), knn_fixes`` (``fusion.Fixes``)."""
    from indoorloc.experiments.wifi_study_folds import floor_cases
    from indoorloc.fusion import wifi_fixes as wfx

    def record(fl, fold):
        db = fold.database
        walks = []
        for fw in fold.walks:
            w = fw.walk
            qt, qrss = wfx.walk_queries(w, db)
            walks.append({"walk_id": w.walk_id, "fold": fold.index, "duration_s": float(w.duration_s),
                          "waypoint_t_s": fw.waypoint_t_s, "waypoint_xy_m": fw.waypoint_xy_m,
                          "coverage_m": fw.coverage_m,
                          "query_t_s": qt, "query_rss_dbm": qrss.astype(np.float32),
                          "knn_fixes": wfx.fixes_for_walk(w, db)})
        return {"database": SimpleNamespace(rss_dbm=np.asarray(db.rss_dbm, np.float32),
                                            positions_m=np.asarray(db.positions_m), floors=np.asarray(db.floors),
                                            walk_index=np.asarray(db.walk_index), bssids=list(db.bssids)),
                "walks": walks}

    return floor_cases(data_root, floors, seed, record, log)


def load_cases(data_root: Path, floors: Sequence[str], seed: int, cache_dir: Optional[Path], log=print
               ) -> Dict[str, Any]:
    """:func:`build_cases`, one pickle per floor and seed in ``cache_dir`` (built when absent)."""
    out = {}
    for name in floors:
        path = None if cache_dir is None else Path(cache_dir) / f"propagation_cases_{name}_seed{seed}.pkl"
        if path is not None and path.exists():
            with open(path, "rb") as fh:
                out[name] = pickle.load(fh)
            continue
        out[name] = build_cases(data_root, [name], seed, log)[name]
        if path is not None:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = Path(str(path) + ".tmp")
            with open(tmp, "wb") as fh:
                pickle.dump(out[name], fh)
            tmp.replace(path)
    return out


__all__ = ["build_cases", "load_cases"]
