"""Floor identification by leave-one-floor-out (docs/fusion_real.md, "Floor identification").

``python -m indoorloc.experiments.floor_identification_study [--data-root DIR] [--floors ...]
[--json FILE] [--markdown FILE]``

Protocol: the folds of ``indoorloc fusion evaluate`` (per floor 4-fold by walk, seed 0; fold j of
every floor shares one all-floor fingerprint database built from the training walks of fold j).
For each test walk it computes, once:

- the all-floor grid filter's per-floor evidence (``site_model.identify_floor`` without the APs:
  the identification tracker of ``fusion evaluate``, steps rotated by
  ``site_model.identification_calibration`` as there and in ``track --floor auto``);
- the per-floor AP evidence L_f (``fusion.floor_evidence``) for every (m, α, ε) of :data:`GRID`;
- the floor classifier's evidence K_f (``fusion.floor_classifier``, fitted per fold on the same
  all-floor database) for every (C, ε) of :data:`CLASSIFIER_GRID`;
- for reference, a WiFi-only vote (each query's best reference's floor, most votes).

Each decider is a score per floor, log p_grid + λ L_f + μ K_f (μ = 0: the rates alone, as before
the classifier; reported apart); a walk's floor is its argmax and every waypoint of the walk counts. For each held-out floor the grid point with the most waypoints right
on the other five floors (ties: the highest mean log-probability of the true floor, the
normalised combined score) is scored on it; ``chosen_all`` is the same choice on all floors,
the default of ``site_model.TrackSettings``.

Calibration of the reported probabilities (``floor_evidence.FloorCalibration``): with each
held-out floor's chosen score, the temperature T, error probability δ_10 and slope b of
:data:`CALIBRATION_GRID` with the lowest log loss over the other five floors' walks calibrate the
held-out floor's walks (δ from each walk's match distance on its chosen floor); the pooled held-out probabilities give the reliability table (per bin of
the probability reported for the chosen floor: walks, mean reported, fraction right).
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence

import numpy as np

from indoorloc.fusion import wifi_fixes as wfx
from indoorloc.fusion import floor_classifier, floor_evidence, site_model
from indoorloc.experiments import fusion_real as fr
from indoorloc.experiments import study_cli

#: (m strongest APs, α rate floor, ε outlier probability) of the AP evidence, and λ its weight
#: (0: the grid filter alone). (m, α, ε) are fixed at the values this study chose before the
#: classifier (over m 1-50, α 0.001-0.1, ε 0.05-0.6): the floor sequence (``fusion.floor_sequence``,
#: ``floor_change_study``) uses the same rates and its change rate was chosen with them; λ stays free.
GRID: Dict[str, Sequence[Any]] = {
    "ap_count": (20,),
    "rate_floor": (0.1,),
    "outlier_probability": (0.1,),
    "weight": (0.5, 1.0, 2.0, 3.0, 5.0, 10.0, 30.0),
}


#: The floor classifier's L2 scale C, outlier probability ε and weight μ (``fusion.floor_classifier``;
#: μ = 0, the rates alone, is always a candidate).
CLASSIFIER_GRID: Dict[str, Sequence[float]] = {
    "l2_scale": (0.1, 1.0),
    "outlier_probability": (0.01, 0.05, 0.2),
    "weight": (0.5, 1.0, 2.0, 5.0, 10.0),
}


#: Temperature T, error probability δ_10 at a match distance of 10 dB and slope b of logit δ in
#: the log of the distance (``floor_evidence.FloorCalibration``; b = 0: one δ for every walk).
#: δ_10 = 0 is not a candidate: a held-out floor whose training floors had no wrong walk would
#: otherwise be told that the evidence never misleads (probability 0 for the true floor of its
#: first wrong walk; it happened to F8 once the classifier left no wrong walk elsewhere).
CALIBRATION_GRID: Dict[str, Sequence[float]] = {
    "temperature": (0.5, 1.0, 2.0, 3.0, 5.0, 10.0, 20.0, 50.0),
    "error_probability_at_10db": (1e-3, 3e-3, 0.01, 0.02, 0.03, 0.05, 0.1, 0.2, 0.3, 0.5),
    "error_slope": (0.0, 1.0, 2.0, 3.0, 4.0, 6.0),
}
#: Bins of the reported probability of the chosen floor in the reliability table.
RELIABILITY_BINS = floor_evidence.RELIABILITY_BINS


def walk_evidence(data_root: Optional[Path] = None, floors: Sequence[str] = (),
                  grid: Optional[Dict[str, Sequence[Any]]] = None, progress=None, seed: int = 0,
                  per_fold=None, per_walk=None) -> dict:
    """Per test walk: floor index, waypoints, the grid filter's log-evidence (F,), the WiFi vote
    (F,), the AP evidence (F,) per (m, α, ε) of ``grid``, the classifier's evidence (F,) per (C, ε)
    of :data:`CLASSIFIER_GRID` and the match distance per floor (F,) [dB]. ``seed``: the fold assignment and tracker seed (``fusion evaluate --seed``).
    Hooks for other studies on the same folds: ``per_fold(database, plan_floors, classifiers)`` (the fold's fitted
    classifiers by C) returns a
    fold context, ``per_walk(rec, walk, queries, database, context)`` adds keys to a walk's record."""
    grid = grid or GRID
    settings = fr.RealSettings(seed=seed)
    _, data = fr.load_site(data_root, floors)
    all_plan = fr._all_floor_plan(data)
    plan_floors = [int(f) for f in all_plan.floors]
    fold_of = {fl.name: fr._folds(len(fl.walks), settings.folds, settings.seed) for fl in data}
    ap_points = list(itertools.product(grid["ap_count"], grid["rate_floor"], grid["outlier_probability"]))
    walks: List[Dict[str, Any]] = []
    for j in range(settings.folds):
        models = fr._fold_models(data, fold_of, j, settings, all_plan, with_crowd_map=False)
        db = next(iter(models.values())).all_database
        rates = {a: floor_evidence.ApFloorRates.from_references(db.rss_dbm, db.floors, plan_floors, a)
                 for a in grid["rate_floor"]}
        classifiers = {c: floor_classifier.FloorClassifier.fit(db.rss_dbm, db.floors, plan_floors, c)
                       for c in CLASSIFIER_GRID["l2_scale"]}
        context = per_fold(db, plan_floors, classifiers) if per_fold else None
        for fl in data:
            m = models[fl.name]
            for i in fold_of[fl.name][j]:
                walk = fl.walks[i]
                rec: Dict[str, Any] = {"floor": fl.name, "floor_index": plan_floors.index(fl.number),
                                       "walk": walk.walk_id, "fold": j, "n_waypoints": len(walk.waypoint_t_s)}
                _, q = wfx.walk_queries(walk, db)
                rec["vote"] = np.zeros(len(plan_floors))
                if q.shape[0]:
                    best = wfx.nearest(q, db)[0][:, 0]
                    votes = [plan_floors.index(int(f)) for f in db.floors[best]]
                    rec["vote"] = np.bincount(votes, minlength=len(plan_floors)).astype(float)
                rec["ap"] = {p: floor_evidence.walk_floor_log_likelihood(rates[p[1]], q, p[0], p[2]) for p in ap_points}
                rec["classifier"] = {(c, e): classifiers[c].walk_log_likelihood(q, e) for c in classifiers
                                     for e in CLASSIFIER_GRID["outlier_probability"]}
                rec["match_distance_db"] = np.array([floor_evidence.walk_match_distance_db(db.rss_dbm, db.floors, f, q)
                                                     for f in plan_floors])
                # As fusion evaluate and track --floor auto: not the walk's own floor's calibration.
                id_cal, id_spread = site_model.identification_calibration(m.all_calibrations)
                steps = site_model.tracker_steps(fl.steps[i], id_cal, settings.track_settings())
                rec["grid"] = np.zeros(len(plan_floors))
                if len(steps):
                    tracker = fr._grid_tracker(all_plan, fr._identification_options(settings, id_spread), "all")
                    found = site_model.identify_floor(tracker, plan_floors, steps, wfx.fixes_for_walk(walk, db))
                    p = np.array([found["grid_probabilities"][f] for f in plan_floors])
                    rec["grid"] = np.log(np.maximum(p, 1e-300))
                if per_walk:
                    per_walk(rec, walk, q, db, context)
                walks.append(rec)
                if progress:
                    progress()
    return {"floors": [next(fl.name for fl in data if fl.number == f) for f in plan_floors],
            "walks": walks, "grid": grid}


def pooled_evidence(data_root: Optional[Path], floors: Sequence[str], seeds: Sequence[int]) -> dict:
    """:func:`walk_evidence` of each fold seed, the walks pooled (each walk once per seed, with its
    ``seed``): the leave-one-floor-out choice then holds out a floor's walks of every seed."""
    parts = [walk_evidence(data_root, floors, seed=int(sd)) for sd in seeds]
    for sd, part in zip(seeds, parts):
        for w in part["walks"]:
            w["seed"] = int(sd)
    return dict(parts[0], walks=[w for part in parts for w in part["walks"]])


def _best(points, label: np.ndarray, n_wp: np.ndarray, mask: np.ndarray) -> tuple:
    """The (values, scores) of ``points`` (an iterable) with the most waypoints right on ``mask``
    (ties: the highest mean log-probability of the true floor; then the first)."""
    best, best_key = None, None
    for values, scores in points:
        key = (_accuracy(scores, label, n_wp, mask), _log_loss(scores, label, mask))
        if best_key is None or key > best_key:
            best, best_key = (values, scores), key
    return best


def _accuracy(scores: np.ndarray, label: np.ndarray, n_wp: np.ndarray, mask: np.ndarray) -> int:
    return int((n_wp * (np.argmax(scores, axis=1) == label))[mask].sum())


def _log_loss(scores: np.ndarray, label: np.ndarray, mask: np.ndarray) -> float:
    z = scores[mask] - scores[mask].max(axis=1, keepdims=True)
    lp = z - np.log(np.exp(z).sum(axis=1, keepdims=True))
    return float(lp[np.arange(int(mask.sum())), label[mask]].mean())


def _per_floor(ok: np.ndarray, label: np.ndarray, n_wp: np.ndarray, names: Sequence[str]) -> Dict[str, float]:
    return {n: float((n_wp * ok)[label == f].sum() / n_wp[label == f].sum()) for f, n in enumerate(names)
            if (label == f).any()}


def _calibrated(scores: np.ndarray, distances_db: np.ndarray, calibration: Dict[str, float]) -> np.ndarray:
    """Calibrated probabilities (W, F) of scores (W, F), δ from each walk's match distance on its
    chosen floor (``distances_db`` (W, F))."""
    chosen = distances_db[np.arange(len(scores)), np.argmax(scores, axis=1)]
    return floor_evidence.FloorCalibration(**calibration).probabilities(scores, chosen)


def _calibration_loss(p: np.ndarray, label: np.ndarray) -> float:
    return float(-np.log(p[np.arange(len(label)), label]).mean())


def choose_calibration(scores: np.ndarray, distances_db: np.ndarray, label: np.ndarray) -> Dict[str, float]:
    """The point of :data:`CALIBRATION_GRID` with the lowest mean log loss of the true floor over
    the walks (rows of ``scores`` (W, F) and ``distances_db`` (W, F), true floor indices
    ``label`` (W,)); ties: the first in grid order (the simpler: b = 0 first)."""
    keys = list(CALIBRATION_GRID)
    points = [dict(zip(keys, v)) for v in itertools.product(*(CALIBRATION_GRID[k] for k in keys))]
    return min(points, key=lambda c: _calibration_loss(_calibrated(scores, distances_db, c), label))


def reliability(p: np.ndarray, label: np.ndarray) -> dict:
    """Reliability over walks of probabilities ``p`` (W, F): per bin of the probability of the
    chosen floor (:data:`RELIABILITY_BINS`), walks, mean reported and fraction right; the mean
    log loss of the true floor [nats] and the Brier score."""
    conf, ok = p.max(axis=1), np.argmax(p, axis=1) == label
    rows = floor_evidence.reliability_table(conf, ok)
    onehot = np.eye(p.shape[1])[label]
    return {"bins": rows, "log_loss": _calibration_loss(p, label),
            "brier": float(((p - onehot) ** 2).sum(axis=1).mean()),
            "mean_reported": float(conf.mean()), "fraction_right": float(ok.mean())}


def select(evidence: dict) -> dict:
    """Leave-one-floor-out choice over the grid (module docstring). Returns the grid filter alone,
    the WiFi vote, the classifier alone (the all-floor choice of (C, ε)), the rates without the
    classifier (``rates_only``: held out and chosen on all floors, the decider before the
    classifier), and with it the held-out figures (pooled and per floor, with each floor's choice)
    and the all-floor choice with its figures."""
    names, walks, grid = evidence["floors"], evidence["walks"], evidence["grid"]
    label = np.array([w["floor_index"] for w in walks])
    n_wp = np.array([w["n_waypoints"] for w in walks])
    g = np.stack([w["grid"] for w in walks])
    dist = np.stack([w["match_distance_db"] for w in walks])
    rate_points = [({"weight": 0.0}, g)]
    for (m, a, e) in walks[0]["ap"]:
        ap = np.stack([w["ap"][(m, a, e)] for w in walks])
        for lam in grid["weight"]:
            rate_points.append(({"ap_count": m, "rate_floor": a, "outlier_probability": e, "weight": lam}, g + lam * ap))
    classifier = {key: np.stack([w["classifier"][key] for w in walks]) for key in walks[0].get("classifier", {})}

    def all_points():
        for values, scores in rate_points:
            yield dict(values, classifier_weight=0.0), scores
            for (c, e), k in classifier.items():
                for mu in CLASSIFIER_GRID["weight"]:
                    yield dict(values, classifier_l2_scale=c, classifier_outlier_probability=e,
                               classifier_weight=mu), scores + mu * k

    def figures(scores: np.ndarray) -> dict:
        ok = np.argmax(scores, axis=1) == label
        return {"accuracy": float((n_wp * ok).sum() / n_wp.sum()), "walks_right": int(ok.sum()),
                "per_floor": _per_floor(ok, label, n_wp, names)}

    def held_out(points) -> tuple:
        ok, p = np.zeros(len(walks), bool), np.full(g.shape, np.nan)
        chosen, chosen_cal = {}, {}
        for f, name in enumerate(names):
            train = label != f
            if not (label == f).any():
                continue
            values, scores = _best(points(), label, n_wp, train)
            chosen[name] = values
            ok[label == f] = (np.argmax(scores, axis=1) == label)[label == f]
            chosen_cal[name] = choose_calibration(scores[train], dist[train], label[train])
            p[label == f] = _calibrated(scores[label == f], dist[label == f], chosen_cal[name])
        return {"accuracy": float((n_wp * ok).sum() / n_wp.sum()), "walks_right": int(ok.sum()),
                "per_floor": _per_floor(ok, label, n_wp, names), "chosen": chosen}, chosen_cal, p

    everything = np.ones(len(walks), bool)
    rates_lofo, _, _ = held_out(lambda: iter(rate_points))
    rates_values, rates_scores = _best(rate_points, label, n_wp, everything)
    lofo, chosen_calibration, held_p = held_out(all_points)
    values_all, scores_all = _best(all_points(), label, n_wp, everything)
    alone = _best((({"l2_scale": c, "outlier_probability": e}, k) for (c, e), k in classifier.items()),
                  label, n_wp, everything) if classifier else None
    calibration_all = choose_calibration(scores_all, dist, label)
    have = ~np.isnan(held_p).any(axis=1)
    wrong = [{"floor": w["floor"], "walk": w["walk"], "n_waypoints": int(w["n_waypoints"]), "seed": w.get("seed", 0),
              "identified": names[int(np.argmax(scores_all[i]))]}
             for i, w in enumerate(walks) if np.argmax(scores_all[i]) != label[i]]
    return {"grid_only": figures(g), "wifi_vote": figures(np.stack([w["vote"] for w in walks])),
            "classifier_alone": None if alone is None else dict(figures(alone[1]), chosen=alone[0]),
            "rates_only": {"lofo": rates_lofo, "chosen_all": rates_values,
                           "chosen_all_figures": figures(rates_scores)},
            "lofo": lofo, "chosen_all": values_all, "chosen_all_figures": figures(scores_all),
            "wrong_walks_chosen_all": wrong,
            "calibration": {"grid": {k: list(v) for k, v in CALIBRATION_GRID.items()},
                            "lofo": {"chosen": chosen_calibration,
                                     "reliability": reliability(held_p[have], label[have])},
                            "chosen_all": calibration_all,
                            "chosen_all_reliability": reliability(_calibrated(scores_all, dist, calibration_all), label),
                            "constant_reliability": reliability(_calibrated(scores_all, dist, dict(
                                calibration_all, error_slope=0.0)), label),
                            "uncalibrated_reliability": reliability(_calibrated(scores_all, dist, {}), label)},
            "n_walks": len(walks), "n_waypoints": int(n_wp.sum()), "grid": {k: list(v) for k, v in grid.items()},
            "classifier_grid": {k: list(v) for k, v in CLASSIFIER_GRID.items()}}


def markdown(result: dict) -> str:
    """The study's table (per floor % of waypoints on the right floor)."""
    floors = list(result["grid_only"]["per_floor"])
    head = "| decider | " + " | ".join(floors) + " | pooled | walks right |"
    lines = [head, "|---|" + "---|" * (len(floors) + 2)]
    rows = [("grid filter alone", result["grid_only"]), ("WiFi-only vote", result["wifi_vote"])]
    if result.get("classifier_alone"):
        rows.append(("floor classifier alone (C, ε chosen on all floors)", result["classifier_alone"]))
    if result.get("rates_only"):
        rows += [("grid + AP rates, held out (LOFO; before the classifier)", result["rates_only"]["lofo"]),
                 ("grid + AP rates, chosen on all floors (before the classifier)",
                  result["rates_only"]["chosen_all_figures"])]
    rows += [("**grid + AP rates + classifier, held out (LOFO)**", result["lofo"]),
             ("grid + AP rates + classifier, chosen on all floors", result["chosen_all_figures"])]
    for name, r in rows:
        lines.append(f"| {name} | " + " | ".join(f"{100 * r['per_floor'][f]:.1f}" for f in floors)
                     + f" | {100 * r['accuracy']:.1f} | {r['walks_right']} of {result['n_walks']} |")
    lines += ["", "Chosen per held-out floor: " + "; ".join(f"{f}: {v}" for f, v in result["lofo"]["chosen"].items()),
              f"Chosen on all floors: {result['chosen_all']}. Folds: 4-fold by walk, seed(s) "
              f"{' '.join(str(v) for v in result.get('seeds', [0]))} (several: each walk counted once per seed).",
              "Walks still wrong with it: " + (", ".join(f"{w['floor']} {w['walk']} ({w['n_waypoints']} waypoints, "
                                                         f"taken for {w['identified']}, seed {w.get('seed', 0)})"
                                                         for w in result["wrong_walks_chosen_all"]) or "none") + "."]
    cal = result.get("calibration")
    if cal:
        lines += ["", "Reliability over walks of the probability reported for the chosen floor "
                  "(held out: T, δ_10, b chosen on the other floors; " + "; ".join(
                      f"{f}: {_brief(v)}" for f, v in cal["lofo"]["chosen"].items())
                  + f"; on all floors: {_brief(cal['chosen_all'])}):",
                  "", "| reported p | held out: walks | mean reported | fraction right | all floors: walks | mean reported "
                  "| fraction right | uncalibrated (T 1, δ 0): walks | mean reported | fraction right |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        tables = [cal["lofo"]["reliability"], cal["chosen_all_reliability"], cal["uncalibrated_reliability"]]
        for lo, hi in zip(RELIABILITY_BINS[:-1], RELIABILITY_BINS[1:]):
            cells = []
            for t in tables:
                row = next((b for b in t["bins"] if b["from"] == lo), None)
                cells += (["0", "", ""] if row is None else
                          [str(row["walks"]), f"{row['mean_reported']:.4f}", f"{row['fraction_right']:.4f}"])
            lines.append(f"| {lo:g}-{hi:g} | " + " | ".join(cells) + " |")
        const = cal["constant_reliability"]
        lines_after = [f"With b = 0 (one δ for every walk, the rest as on all floors): log loss {_loss(const['log_loss'])}, "
                       f"Brier {const['brier']:.4f}."]
        lines.append("| log loss / Brier | " + " | ".join(f"{_loss(t['log_loss'])} / {t['brier']:.4f} |  | " for t in tables)
                     .rstrip() + "")
        lines += [""] + lines_after
    return "\n".join(lines)


def _loss(value: Optional[float]) -> str:
    """A log loss [nats] for the table: an infinite one (a walk given probability 0 for its true
    floor) is stored as JSON null by :func:`_jsonable`; a reloaded result prints it as the run did."""
    return "inf" if value is None or value == math.inf else f"{value:.3f}"


def _brief(c: Dict[str, float]) -> str:
    return f"T {c['temperature']:g}, δ_10 {c['error_probability_at_10db']:g}, b {c['error_slope']:g}"


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def main(argv: Optional[Sequence[str]] = None) -> int:
    return study_cli.run_study(argv, __doc__.split("\n")[0],
                               lambda root, floors, seeds: select(pooled_evidence(root, floors, seeds)), markdown,
                               _jsonable)


if __name__ == "__main__":
    raise SystemExit(main())
