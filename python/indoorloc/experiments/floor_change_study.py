"""Walks that change floor: the AP evidence's floor sequence (``fusion.floor_sequence``) on real
walks and on spliced ones, and its change rate chosen by leave-one-floor-out.

``python -m indoorloc.experiments.floor_change_study [--data-root DIR] [--floors ...] [--json FILE]
[--markdown FILE]``

No walk of the competition site changes floor, so walks that do are made: each test walk is
followed, 30 s later, by a test walk of another floor of the same fold (drawn with seed 0). The
folds are those of ``fusion evaluate`` (per floor 4-fold by walk, seed 0; fold j of every floor
shares one all-floor database built from the training walks of fold j). Per query: the robust AP
likelihood log(ε + (1 − ε) p(f | q)) with the default m, α, ε of ``site_model.TrackSettings``.

For each change rate r of :data:`RATES`: the real walks whose Viterbi sequence changes floor
(false alarms), the spliced walks where it does (detections), and the fraction of queries whose
Viterbi floor is right over real and spliced walks pooled (the objective). For each held-out
floor, the r best on the walks and pairs without that floor is scored on those with it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence

import numpy as np

from indoorloc.experiments import fusion_real as fr
from indoorloc.experiments import study_cli
from indoorloc.fusion import floor_evidence, site_model
from indoorloc.fusion import wifi_fixes as wfx
from indoorloc.fusion.floor_sequence import floor_sequence

#: Floor change rates r [1/s] tried (0: one floor per walk).
RATES = (0.0, 1 / 36000, 1 / 3600, 1 / 1200, 1 / 600, 1 / 300, 1 / 60)
#: Gap [s] between the two walks of a spliced walk.
SPLICE_GAP_S = 30.0


def query_evidence(data_root: Optional[Path] = None, floors: Sequence[str] = (), seed: int = 0) -> dict:
    """Per test walk: floor index, fold, query times (Q,) [s] and robust AP log-likelihoods (Q, F);
    ``seed``: the fold assignment (``fusion evaluate --seed``)."""
    settings = fr.RealSettings(seed=seed)
    ts = site_model.TrackSettings()
    _, data = fr.load_site(data_root, floors)
    all_plan = fr._all_floor_plan(data)
    plan_floors = [int(f) for f in all_plan.floors]
    fold_of = {fl.name: fr._folds(len(fl.walks), settings.folds, settings.seed) for fl in data}
    walks: List[Dict[str, Any]] = []
    for j in range(settings.folds):
        models = fr._fold_models(data, fold_of, j, settings, all_plan, with_crowd_map=False)
        some = next(iter(models.values()))
        for fl in data:
            for i in fold_of[fl.name][j]:
                t, q = wfx.walk_queries(fl.walks[i], some.all_database)
                log_p, used = floor_evidence.query_floor_log_posteriors(some.all_ap_rates, q,
                                                                        ts.identification_ap_count)
                walks.append({"floor": fl.name, "floor_index": plan_floors.index(fl.number), "fold": j,
                              "walk": fl.walks[i].walk_id, "t_s": t[used],
                              "log_likelihoods": floor_evidence.robust_query_log_likelihoods(
                                  log_p, ts.identification_ap_outlier_probability)})
    return {"floors": [next(fl.name for fl in data if fl.number == f) for f in plan_floors], "walks": walks}


def _cases(evidence: dict, seed: int = 0) -> List[Dict[str, Any]]:
    """Real walks and spliced pairs: ``e`` (Q, F), ``t`` (Q,), ``truth`` (Q,), ``floors`` (set),
    ``spliced``."""
    walks = [w for w in evidence["walks"] if len(w["t_s"])]
    rng = np.random.default_rng(seed)
    cases = [{"e": w["log_likelihoods"], "t": w["t_s"], "truth": np.full(len(w["t_s"]), w["floor_index"]),
              "floors": {w["floor_index"]}, "spliced": False} for w in walks]
    for a in walks:
        others = [b for b in walks if b["fold"] == a["fold"] and b["floor_index"] != a["floor_index"]]
        if not others:
            continue
        b = others[int(rng.integers(len(others)))]
        t_a = a["t_s"] - a["t_s"][0]
        t_b = b["t_s"] - b["t_s"][0] + t_a[-1] + SPLICE_GAP_S
        cases.append({"e": np.vstack([a["log_likelihoods"], b["log_likelihoods"]]), "t": np.r_[t_a, t_b],
                      "truth": np.r_[np.full(len(t_a), a["floor_index"]), np.full(len(t_b), b["floor_index"])],
                      "floors": {a["floor_index"], b["floor_index"]}, "spliced": True})
    return cases


def select_rate(evidence: dict) -> dict:
    """The table per rate and the leave-one-floor-out choice (module docstring)."""
    cases = _cases(evidence)
    paths = {r: [floor_sequence(c["e"], c["t"], r)["path"] for c in cases] for r in RATES}

    def score(r: float, keep) -> float:
        right = sum(int((p == c["truth"]).sum()) for p, c in zip(paths[r], cases) if keep(c))
        total = sum(len(c["truth"]) for c in cases if keep(c))
        return right / max(total, 1)

    rows = []
    for r in RATES:
        changed = [int(np.count_nonzero(np.diff(p))) > 0 for p in paths[r]]
        rows.append({"rate_per_s": r,
                     "real_walks_with_a_change": int(sum(ch for ch, c in zip(changed, cases) if not c["spliced"])),
                     "spliced_with_a_change": int(sum(ch for ch, c in zip(changed, cases) if c["spliced"])),
                     "queries_right_real": score(r, lambda c: not c["spliced"]),
                     "queries_right_spliced": score(r, lambda c: c["spliced"]),
                     "queries_right": score(r, lambda c: True)})
    held_right, held_total, chosen = 0, 0, {}
    for f, name in enumerate(evidence["floors"]):
        if not any(f in c["floors"] for c in cases):
            continue
        best = max(RATES, key=lambda r: score(r, lambda c: f not in c["floors"]))
        chosen[name] = best
        for p, c in zip(paths[best], cases):
            if f in c["floors"]:
                held_right += int((p == c["truth"]).sum())
                held_total += len(c["truth"])
    best_all = max(RATES, key=lambda r: score(r, lambda c: True))
    return {"rows": rows, "n_real": sum(not c["spliced"] for c in cases), "n_spliced": sum(c["spliced"] for c in cases),
            "lofo": {"chosen": chosen, "queries_right": held_right / max(held_total, 1)}, "chosen_all": best_all}


def markdown(result: dict) -> str:
    """The study's table."""
    lines = ["| change rate [1/s] | real walks with a change | spliced walks with a change | queries right: real "
             "| spliced | pooled |", "|---|---|---|---|---|---|"]
    for r in result["rows"]:
        lines.append(f"| {r['rate_per_s']:.3g} | {r['real_walks_with_a_change']} of {result['n_real']} | "
                     f"{r['spliced_with_a_change']} of {result['n_spliced']} | {r['queries_right_real']:.3f} | "
                     f"{r['queries_right_spliced']:.3f} | {r['queries_right']:.3f} |")
    lines += ["", "Chosen per held-out floor: " + "; ".join(f"{f}: {v:.3g}" for f, v in result["lofo"]["chosen"].items())
              + f"; held out, queries right {result['lofo']['queries_right']:.3f}. Chosen on all floors: "
              f"{result['chosen_all']:.3g} per s."]
    return "\n".join(lines)


def _one_seed(seeds: Sequence[int]) -> int:
    # The spliced walks pair walks of one fold: one fold assignment at a time.
    if len(seeds) != 1:
        raise ValueError(f"indoorloc: argument '--seed': this study takes one seed, got {list(seeds)}")
    return int(seeds[0])


def main(argv: Optional[Sequence[str]] = None) -> int:
    return study_cli.run_study(argv, __doc__.split("\n")[0],
                               lambda root, floors, seeds: select_rate(query_evidence(root, floors, _one_seed(seeds))), markdown)


if __name__ == "__main__":
    raise SystemExit(main())
