"""Deciders of ``floor_generalization_study`` on its cached per-walk evidence, chosen on some fold
seeds and scored on the others, and by leave-one-floor-out (that module's docstring).

A decider is a score per walk and floor (the argmax is the walk's floor):

    s_f = ω log p_grid(f) + λ L_f + μ n^(γ − 1) K_f − ν D_f + η H_f,

ω the grid filter's weight (1 in ``fusion evaluate``), L_f the AP rates' evidence (``floor_evidence``, m 20, α 0.1, ε 0.1 fixed), K_f = Σ_q log(ε + (1 − ε)
p_C(f | q)) the classifier's over the walk's n queries (γ = 1: summed as ``fusion evaluate`` does;
γ < 1: pooled over the walk, so that a long walk's correlated queries do not outweigh the grid;
γ = 0: the mean per query), D_f [dB] the walk's fingerprint match distance on floor f (the median
over queries of the distance to the floor's closest reference: the floor whose fingerprints fit
best), weight ν [nats/dB]. ``margin_gate`` g: ν applies only to walks whose score without it has a
margin below g nats (a second opinion when the first is unsure). H_f, the strong APs' home floor:
each AP the walk hears at -55 dBm or more (near it: through a floor an AP is rarely that strong)
votes for the floor whose survey heard it strongest, with weight min(1, gap / 10 dB), gap the
difference between that floor's strongest reading and the next floor's (a floor that never heard
it: -110 dBm); weight η [nats per vote].
"""

from __future__ import annotations

import itertools
from typing import Any, Dict, List, Sequence

import numpy as np

from indoorloc.experiments import floor_identification_study as fis

#: The decider grid (module docstring). The first point of each list is the current default's value
#: where it has one (λ 2, C 1, ε 0.2, μ 10, γ 1, ν 0).
GRID: Dict[str, Sequence[float]] = {
    "grid_weight": (1.0, 0.3, 0.1),
    "ap_weight": (2.0, 0.0, 1.0, 5.0),
    "l2_scale": (1.0, 0.1, 0.3, 3.0),
    "outlier_probability": (0.2, 0.01, 0.05, 0.5),
    "classifier_weight": (10.0, 0.0, 2.0, 5.0, 20.0, 50.0),
    "pooling_exponent": (1.0, 0.0, 0.5),
    "distance_weight": (0.0, 0.1, 0.3, 1.0),
    "margin_gate": (np.inf, 5.0, 20.0),
    "home_weight": (0.0, 1.0, 3.0),
}
#: The strong-AP home-floor vote's fixed constants (set in advance): the walk's reading [dBm] from
#: which an AP counts as near, the floor gap [dB] of a full vote, the level of "never heard" [dBm].
HOME_NEAR_DBM, HOME_FULL_GAP_DB, HOME_NEVER_DBM = -55.0, 10.0, -110.0
#: The coverage split of the report [m]: a walk's own floor is "covered" when the median over its
#: waypoints of the distance to the closest training reference of its floor is at most this.
COVERED_M = 20.0
DEFAULT = {k: v[0] for k, v in GRID.items()}


class Evidence:
    """The cached walks of several seeds as arrays: label (W,), waypoints (W,), seed (W,), the
    grid's and rates' scores (W, F), the classifier's K per (C, ε) (W, F), query counts (W,) and
    match distances (W, F)."""

    def __init__(self, parts: Sequence[dict]):
        self.names = parts[0]["floors"]
        self.walks = [w for p in parts for w in p["walks"]]
        w = self.walks
        self.label = np.array([x["floor_index"] for x in w])
        self.n_wp = np.array([x["n_waypoints"] for x in w])
        self.seed = np.array([x["seed"] for x in w])
        self.floor = self.label
        self.grid = np.stack([x["grid"] for x in w])
        self.rates = np.stack([x["ap"][(20, 0.1, 0.1)] for x in w])
        self.n_q = np.array([max(x["n_queries"], 1) for x in w], float)
        self.dist = np.stack([x["match_distance_db"] for x in w])
        self.home = np.stack([_home_votes(x, len(self.names)) for x in w])
        self.k = {}
        for c in GRID["l2_scale"]:
            for e in GRID["outlier_probability"]:
                self.k[(c, e)] = np.stack([_robust_sum(x["clf_query_logp"][c], e, len(self.names)) for x in w])

    def score(self, p: Dict[str, float]) -> np.ndarray:
        pool = self.n_q ** (p["pooling_exponent"] - 1.0)
        s = p["grid_weight"] * self.grid + p["ap_weight"] * self.rates + p["classifier_weight"] * pool[:, None] \
            * self.k[(p["l2_scale"], p["outlier_probability"])]
        if p["home_weight"] > 0:
            s = s + p["home_weight"] * self.home
        if p["distance_weight"] > 0:
            top = np.sort(s, axis=1)
            unsure = (top[:, -1] - top[:, -2]) < p["margin_gate"]
            s = s - p["distance_weight"] * self.dist * unsure[:, None]
        return s


def _home_votes(walk: dict, n_floors: int) -> np.ndarray:
    """H_f of the module docstring (F,) for a cached walk."""
    near = walk["ap_walk_max_dbm"] >= HOME_NEAR_DBM
    top = np.where(np.isfinite(walk["ap_floor_max_dbm"][:, near]), walk["ap_floor_max_dbm"][:, near], HOME_NEVER_DBM)
    out = np.zeros(n_floors)
    if top.shape[1] == 0:
        return out
    order = np.sort(top, axis=0)
    weight = np.clip((order[-1] - order[-2]) / HOME_FULL_GAP_DB, 0.0, 1.0)
    np.add.at(out, np.argmax(top, axis=0), weight)
    return out


def _robust_sum(log_p: np.ndarray, eps: float, n_floors: int) -> np.ndarray:
    if log_p.shape[0] == 0:
        return np.zeros(n_floors)
    return np.logaddexp(np.log(eps), np.log1p(-eps) + log_p).sum(axis=0)


def _points() -> List[Dict[str, float]]:
    keys = list(GRID)
    out = []
    for v in itertools.product(*(GRID[k] for k in keys)):
        p = dict(zip(keys, v))
        if p["classifier_weight"] == 0 and (p["l2_scale"], p["outlier_probability"], p["pooling_exponent"]) != \
                (DEFAULT["l2_scale"], DEFAULT["outlier_probability"], DEFAULT["pooling_exponent"]):
            continue  # the classifier off: its settings do not matter
        if p["distance_weight"] == 0 and p["margin_gate"] != DEFAULT["margin_gate"]:
            continue
        out.append(p)
    return out


def _choose(ev: Evidence, points, mask: np.ndarray) -> tuple:
    """The point with the most waypoints right on ``mask`` and its scores; ties: the first in grid
    order, the current default first (a change must get more waypoints right where it is chosen;
    the raw scores' log loss, the floor study's tie-break, rewards shrinking every weight, which
    the calibration's temperature undoes anyway)."""
    best, best_key = None, None
    for p in points:
        s = ev.score(p)
        key = fis._accuracy(s, ev.label, ev.n_wp, mask)
        if best_key is None or key > best_key:
            best, best_key = (p, s), key
    return best


def _figures(ev: Evidence, ok: np.ndarray, mask: np.ndarray) -> dict:
    n = ev.n_wp * mask
    return {"accuracy": float((n * ok).sum() / n.sum()), "walks_right": int((ok & mask).sum()),
            "walks": int(mask.sum()), "waypoints_wrong": int((n * ~ok).sum())}


def _per_seed(ev: Evidence, ok: np.ndarray) -> Dict[int, dict]:
    return {int(s): _figures(ev, ok, ev.seed == s) for s in np.unique(ev.seed)}


def wrong_walks(ev: Evidence, scores: np.ndarray) -> List[dict]:
    """Per wrongly identified walk: seed, floor, walk id, waypoints, the floor taken, the margin
    [nats] by which the taken floor beat the true one, and the diagnostics of the cache."""
    out = []
    taken = np.argmax(scores, axis=1)
    for i in np.flatnonzero(taken != ev.label):
        w, t, f = ev.walks[i], int(taken[i]), int(ev.label[i])
        out.append({"seed": int(w["seed"]), "floor": w["floor"], "walk": w["walk"], "n_waypoints": int(w["n_waypoints"]),
                    "taken_for": ev.names[t], "margin_nats": float(scores[i, t] - scores[i, f]),
                    "grid_margin_nats": float(ev.grid[i, t] - ev.grid[i, f]),
                    "n_queries": int(w["n_queries"]), "n_aps": int(w["n_aps"]), "duration_s": float(w["duration_s"]),
                    "several_floor_ap_share": float(w["several_floor_ap_share"]),
                    "coverage_own_m": float(w["coverage_m"][f]), "coverage_taken_m": float(w["coverage_m"][t]),
                    "match_own_db": float(ev.dist[i, f]), "match_taken_db": float(ev.dist[i, t])})
    return out


def study(parts: Sequence[dict], choose_seeds: Sequence[int]) -> dict:
    """The default's figures and wrong walks per seed; the point chosen on ``choose_seeds`` scored
    per seed; leave-one-floor-out over every seed (per held-out floor, the point chosen on the
    other floors' walks of every seed), split by seed; calibration chosen on ``choose_seeds``."""
    ev = Evidence(parts)
    points = _points()
    default_scores = ev.score(DEFAULT)
    default_ok = np.argmax(default_scores, axis=1) == ev.label
    choose = np.isin(ev.seed, list(choose_seeds))
    chosen, chosen_scores = _choose(ev, points, choose)
    chosen_ok = np.argmax(chosen_scores, axis=1) == ev.label
    lofo_ok, lofo_chosen = np.zeros(len(ev.walks), bool), {}
    for f, name in enumerate(ev.names):
        p, s = _choose(ev, points, ev.label != f)
        lofo_chosen[name] = p
        lofo_ok[ev.label == f] = (np.argmax(s, axis=1) == ev.label)[ev.label == f]
    # Classifier-family restrictions, each chosen on choose_seeds (which part carries a gain).
    families = {
        "summed classifier (gamma 1, no distance)": [p for p in points if p["pooling_exponent"] == 1
                                                     and p["distance_weight"] == 0 and p["home_weight"] == 0],
        "pooled classifier (gamma < 1, no distance)": [p for p in points if p["distance_weight"] == 0
                                                       and p["home_weight"] == 0],
        "second opinion (distance), summed classifier": [p for p in points if p["pooling_exponent"] == 1
                                                         and p["home_weight"] == 0],
        "strong APs' home floor, summed classifier": [p for p in points if p["pooling_exponent"] == 1
                                                      and p["distance_weight"] == 0],
    }
    family_rows = {}
    for name, pts in families.items():
        p, s = _choose(ev, pts, choose)
        family_rows[name] = {"chosen": p, "per_seed": _per_seed(ev, np.argmax(s, axis=1) == ev.label)}
    cal = fis.choose_calibration(chosen_scores[choose], ev.dist[choose], ev.label[choose])
    held = ~choose
    rel_held = fis.reliability(fis._calibrated(chosen_scores[held], ev.dist[held], cal), ev.label[held]) \
        if held.any() else None
    default_cal = {"temperature": 0.5, "error_probability_at_10db": 0.01, "error_slope": 3.0}  # TrackSettings'
    rel_default = fis.reliability(fis._calibrated(default_scores[held], ev.dist[held], default_cal), ev.label[held]) \
        if held.any() else None
    # Diagnostic (uses the true waypoints, not available to a decider): walks whose own floor's
    # training references lie within COVERED_M of them (median over waypoints) or not.
    own = np.array([w["coverage_m"][w["floor_index"]] for w in ev.walks])
    coverage = {}
    for name, sel_ in (("covered", own <= COVERED_M), ("not_covered", own > COVERED_M)):
        coverage[name] = {int(sd): _figures(ev, default_ok, sel_ & (ev.seed == sd)) for sd in np.unique(ev.seed)
                          if (sel_ & (ev.seed == sd)).any()}
    return {"floors": ev.names, "seeds": sorted(int(s) for s in np.unique(ev.seed)), "choose_seeds": list(choose_seeds),
            "n_points": len(points), "grid": {k: list(v) for k, v in GRID.items()},
            "default": {"settings": DEFAULT, "per_seed": _per_seed(ev, default_ok),
                        "wrong_walks": wrong_walks(ev, default_scores)},
            "chosen": {"settings": chosen, "per_seed": _per_seed(ev, chosen_ok),
                       "wrong_walks": wrong_walks(ev, chosen_scores), "calibration": cal,
                       "held_out_reliability": rel_held},
            "default_calibration_held_out_reliability": rel_default, "coverage_m": COVERED_M,
            "default_by_coverage": coverage,
            "families": family_rows,
            "lofo": {"chosen": lofo_chosen, "per_seed": _per_seed(ev, lofo_ok)}}


def _row(name: str, per_seed: Dict[Any, dict], seeds) -> str:
    acc = [100 * per_seed[s]["accuracy"] for s in seeds]
    walks = sum(per_seed[s]["walks_right"] for s in seeds)
    total = sum(per_seed[s]["walks"] for s in seeds)
    wp = sum(per_seed[s]["waypoints_wrong"] for s in seeds)
    return (f"| {name} | " + " | ".join(f"{a:.1f}" for a in acc)
            + f" | {np.mean(acc):.2f} ± {np.std(acc, ddof=1) if len(acc) > 1 else 0:.2f} | {wp} | {walks} of {total} |")


def markdown(result: dict) -> str:
    """Per seed % of waypoints on the right floor, the wrong walks and what the evidence said."""
    seeds = result["seeds"]
    held = [s for s in seeds if s not in result["choose_seeds"]]
    lines = [f"% of waypoints on the right floor per fold seed (chosen on seeds {result['choose_seeds']}, "
             f"held out: {held}; {result['n_points']} grid points):", "",
             "| decider | " + " | ".join(f"seed {s}" for s in seeds) + " | mean ± sd | waypoints wrong | walks right |",
             "|---|" + "---|" * (len(seeds) + 3)]
    lines.append(_row("current default", result["default"]["per_seed"], seeds))
    lines.append(_row("**chosen on the choose seeds**", result["chosen"]["per_seed"], seeds))
    for name, r in result["families"].items():
        lines.append(_row(f"{name}, chosen on the choose seeds", r["per_seed"], seeds))
    lines.append(_row("leave-one-floor-out over all seeds (held out by floor)", result["lofo"]["per_seed"], seeds))
    lines += ["", f"Chosen: {result['chosen']['settings']}; calibration {result['chosen']['calibration']}.",
              "Families: " + "; ".join(f"{n}: {r['chosen']}" for n, r in result["families"].items()),
              "LOFO choices: " + "; ".join(f"{f}: {v}" for f, v in result["lofo"]["chosen"].items())]
    cov = result.get("default_by_coverage", {})
    for name, title in (("covered", "within"), ("not_covered", "farther than")):
        if cov.get(name):
            lines.append(f"Current default, walks whose own floor's training references are {title} "
                         f"{result['coverage_m']:g} m (median over waypoints): " + "; ".join(
                             f"seed {sd}: {100 * r['accuracy']:.1f} % ({r['walks_right']} of {r['walks']} walks)"
                             for sd, r in cov[name].items()))
    rel = result["chosen"].get("held_out_reliability")
    rel_d = result.get("default_calibration_held_out_reliability")
    if rel_d:
        lines.append(f"The default calibration (T 0.5, δ_10 0.01, b 3) on the held-out seeds' walks: mean reported "
                     f"{rel_d['mean_reported']:.4f}, right {rel_d['fraction_right']:.4f}, log loss {rel_d['log_loss']:.3f}.")
    if rel:
        lines.append(f"Calibrated on the choose seeds, on the held-out seeds' walks: mean reported {rel['mean_reported']:.4f}, "
                     f"right {rel['fraction_right']:.4f}, log loss {rel['log_loss']:.3f}.")
    for key, title in (("default", "the current default"), ("chosen", "the chosen decider")):
        lines += ["", f"Walks wrong with {title}:", "",
                  "| seed | floor | walk | waypoints | taken for | margin [nats] | grid margin | queries | APs | "
                  "APs heard on ≥2 floors | s | own floor's survey, median distance [m] | taken floor's | match own [dB] | match taken |",
                  "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for w in result[key]["wrong_walks"]:
            lines.append(f"| {w['seed']} | {w['floor']} | {w['walk']} | {w['n_waypoints']} | {w['taken_for']} | "
                         f"{w['margin_nats']:.1f} | {w['grid_margin_nats']:.1f} | {w['n_queries']} | {w['n_aps']} | "
                         f"{100 * w['several_floor_ap_share']:.0f} % | {w['duration_s']:.0f} | {w['coverage_own_m']:.1f} | "
                         f"{w['coverage_taken_m']:.1f} | {w['match_own_db']:.1f} | {w['match_taken_db']:.1f} |")
    return "\n".join(lines)


__all__ = ["DEFAULT", "Evidence", "GRID", "markdown", "study", "wrong_walks"]
