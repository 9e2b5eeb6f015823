"""The machine-readable PDR evaluation (``indoorloc pdr evaluate --json``): every recording under
the pdr data folder with the recommended pipeline, in the stable schema of docs/pdr.md ("JSON
output"), in process (:func:`evaluate_json`) or one Dask task per dataset
(:func:`evaluate_json_on_dask`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Union

import numpy as np

from indoorloc.experiments.pdr_scoring import score_pyshoe_trial
from indoorloc.io import pdr_datasets
from indoorloc.io.pdr_datasets import ImuRecording
from indoorloc.pdr import metrics as _metrics
from indoorloc.pdr import recommended as _recommended
from indoorloc.progress import progress, stage

PathLike = Union[str, Path]

#: The datasets ``indoorloc pdr evaluate --only`` accepts, and their folders under the data root.
DATASETS = {"pyshoe": "pyshoe_vicon", "xio": "xio_gait_tracking", "openshoe": "openshoe_figure8",
            "mobgap": "mobgap_lowerback"}

#: Keys of every row of :func:`evaluate_json` (the stable schema of docs/pdr.md).
JSON_ROW_KEYS = ("dataset", "name", "method", "armse_m", "final_error_m", "distance_m", "strides_truth",
                 "strides_detected", "health")


def _finite_or_none(v: Any) -> Optional[float]:
    if v is None:
        return None
    v = float(v)
    return v if math.isfinite(v) else None


def _health_json(health: Dict[str, Any]) -> Dict[str, Any]:
    out: Dict[str, Any] = {}
    for k, v in health.items():
        if isinstance(v, (bool, np.bool_)):
            out[k] = bool(v)
        elif isinstance(v, (int, np.integer)):
            out[k] = int(v)
        elif isinstance(v, (float, np.floating)):
            out[k] = _finite_or_none(v)
        elif isinstance(v, (list, tuple)):
            out[k] = [str(x) for x in v]
        else:
            out[k] = str(v)
    return out


def _zupt_row(dataset: str, rec: ImuRecording) -> Dict[str, Any]:
    r = _recommended.run_recommended(rec)
    pos, strides = r["positions_m"], r["stride_indices"]
    armse_m = final_m = None
    if rec.truth_xy_m is not None:
        sc = score_pyshoe_trial(rec, (pos, strides))
        armse_m, final_m = sc["armse_m"], sc["final_error_m"]
    elif rec.closed_loop:
        final_m = float(np.linalg.norm(pos[-1, :2] - pos[0, :2]))
    health = dict(r["health"])
    health["path_length_m"] = _metrics.path_length(pos[:, :2])
    si = rec.stride_indices
    return {"dataset": dataset, "name": rec.name, "method": _recommended.DEFAULT_METHOD, "armse_m": _finite_or_none(armse_m),
            "final_error_m": _finite_or_none(final_m), "distance_m": _finite_or_none(rec.distance_m),
            "strides_truth": None if si is None else max(0, int(si.size) - 1),
            "strides_detected": int(strides.size), "health": _health_json(health)}


def _datasets_to_run(r: Path, only: Optional[Sequence[str]]) -> List[str]:
    """The dataset names to evaluate (``only`` or all); ValueError on a missing root, an unknown
    name, or an ``only`` naming a dataset whose folder is missing."""
    if not r.is_dir():
        raise ValueError(f"indoorloc: argument 'root': {r} is not a folder")
    names = list(DATASETS) if not only else list(only)
    for nm in names:
        if nm not in DATASETS:
            raise ValueError(f"indoorloc: argument 'only': unknown dataset {nm!r}; one of {', '.join(DATASETS)}")
    if only:
        missing = [nm for nm in names if not (r / DATASETS[nm]).is_dir()]
        if missing:
            raise ValueError(f"indoorloc: argument 'only': no {', '.join(missing)} folder under {r}")
    return names


def evaluate_json(root: PathLike, only: Optional[Sequence[str]] = None) -> Dict[str, Any]:
    """Every recording under the pdr data folder ``root`` with the recommended method, as the
    stable JSON document of ``indoorloc pdr evaluate --json`` (docs/pdr.md, "JSON output").

    ``only``: dataset names out of :data:`DATASETS` (default all); datasets whose folder is
    missing are skipped (a data root may hold only some of them), and an ``only`` naming a
    missing one raises ValueError. PyShoe trials: ``armse_m`` and ``final_error_m`` after the
    alignment of :func:`score_pyshoe_trial` (null when a file has no per-sample truth);
    x-io / OpenShoe: ``final_error_m`` is the loop-closure error (2-D), ``armse_m`` null;
    mobgap (a lower-back sensor, no zero-velocity phases): the gyroscope step detector of
    paper 002 (0.5 rad/s), ``strides_truth`` / ``strides_detected`` count *steps* (initial
    contacts of both feet) inside the INDIP walking bouts, positions are not estimated
    (``armse_m`` and ``final_error_m`` null, ``health`` empty).
    """
    r = Path(root)
    names = _datasets_to_run(r, only)
    rows: List[Dict[str, Any]] = []
    for nm in names:
        folder = r / DATASETS[nm]
        if not folder.is_dir():
            continue
        if nm == "pyshoe":
            recs = [pdr_datasets.load_pyshoe_trial(p) for p in pdr_datasets.list_pyshoe_trials(folder)]
        elif nm == "xio":
            recs = [pdr_datasets.load_xio(folder / f) for f in ("short_walk.csv", "long_walk.csv")
                    if (folder / f).is_file()]
        elif nm == "openshoe":
            loop = folder / "OpenShoeDataSet.txt"
            recs = [pdr_datasets.load_openshoe(loop)] if loop.is_file() else []
        else:
            with stage("mobgap"):
                rows.extend(_mobgap_rows(folder))
            continue
        for rec in progress(recs, total=len(recs), desc=nm):
            rows.append(_zupt_row(nm, rec))
    return {"default_method": _recommended.DEFAULT_METHOD, "recordings": rows}


def dataset_task(params: Dict[str, Any], seed: int, root: str) -> Dict[str, Any]:
    """The Dask task of :func:`evaluate_json_on_dask`: the rows of one dataset."""
    return {"recordings": evaluate_json(root, only=[str(params["dataset"])])["recordings"]}


def evaluate_json_on_dask(root: PathLike, only: Optional[Sequence[str]], scheduler: Any) -> Dict[str, Any]:
    """:func:`evaluate_json` with one Dask task per dataset (the workers read ``root``, a path
    they must see); the same document, recordings in the same order."""
    from indoorloc import sweep

    r = Path(root)
    names = [nm for nm in _datasets_to_run(r, only) if (r / DATASETS[nm]).is_dir()]
    res = sweep.run_sweep(dataset_task, {"dataset": names}, scheduler=scheduler, shared={"root": str(r)})
    if res.failed:
        raise RuntimeError(f"indoorloc: dataset {res.failed[0]['params']['dataset']} failed: {res.failed[0]['error']}")
    return {"default_method": _recommended.DEFAULT_METHOD, "recordings": [rec for row in res.rows for rec in row["recordings"]]}


def _mobgap_rows(folder: Path) -> List[Dict[str, Any]]:
    from indoorloc import pdr
    from indoorloc.io.pdr_datasets import list_mobgap_files, load_mobgap_trials

    rows = []
    for f in list_mobgap_files(folder):
        for t in load_mobgap_trials(f):
            rec = t.recording
            if t.bout_bounds_s.shape[0] == 0:
                continue
            steps = np.asarray(pdr.steps_gyro(rec.gyro_radps, rec.rate_hz, options=pdr.GyroStepOptions(threshold_radps=0.5)))
            ref = det = 0
            for (a, b), contacts in zip(t.bout_bounds_s, t.bout_initial_contacts):
                lo, hi = a * rec.rate_hz, b * rec.rate_hz
                ref += int(len(contacts))
                det += int(np.sum((steps >= lo) & (steps <= hi)))
            rows.append({"dataset": "mobgap", "name": t.name, "method": "steps_gyro_lower_back",
                         "armse_m": None, "final_error_m": None, "distance_m": _finite_or_none(rec.distance_m),
                         "strides_truth": ref, "strides_detected": det, "health": {}})
    return rows
