"""experiments.floor_generalization_select on synthetic cached evidence: deciders chosen on some
fold seeds and scored on the others, the wrong walks' diagnostics, the strong-AP home vote."""

from __future__ import annotations

import numpy as np

from indoorloc.experiments import floor_generalization_select as sel


def _walk(i: int, f: int, seed: int, grid_wrong: bool, rng) -> dict:
    n_floors = 3
    wrong = (f + 1) % n_floors
    grid = np.full(n_floors, -8.0)
    grid[wrong if grid_wrong else f] = 0.0
    q = np.log(np.full((4, n_floors), 1.0 / n_floors))  # the classifier: no information
    dist = np.full(n_floors, 30.0)
    dist[f] = 5.0  # the walk's own floor's fingerprints fit best
    return {"floor": "ABC"[f], "floor_index": f, "walk": f"w{i}", "fold": i % 4, "n_waypoints": 3 + i % 4,
            "seed": seed, "grid": grid + rng.normal(0, 0.01, n_floors), "ap": {(20, 0.1, 0.1): np.zeros(n_floors)},
            "clf_query_logp": {c: q for c in sel.GRID["l2_scale"]}, "n_queries": 4, "n_aps": 10,
            "match_distance_db": dist, "several_floor_ap_share": 0.5, "coverage_m": np.full(n_floors, 3.0),
            "duration_s": 30.0, "ap_walk_max_dbm": np.array([-70.0]), "ap_floor_max_dbm": np.full((n_floors, 1), -80.0)}


def test_a_second_opinion_chosen_on_two_seeds_carries_to_the_others():
    rng = np.random.default_rng(1)
    parts = []
    for seed in range(4):
        walks = [_walk(i, i % 3, seed, grid_wrong=(i % 5 == 0), rng=rng) for i in range(30)]
        parts.append({"floors": ["A", "B", "C"], "walks": walks})
    r = sel.study(parts, choose_seeds=[0, 1])
    assert all(r["default"]["per_seed"][s]["accuracy"] < 1.0 for s in range(4))
    assert r["chosen"]["settings"]["distance_weight"] > 0
    assert all(r["chosen"]["per_seed"][s]["accuracy"] == 1.0 for s in (2, 3))  # held out
    assert all(r["lofo"]["per_seed"][s]["accuracy"] == 1.0 for s in range(4))
    wrong = r["default"]["wrong_walks"]
    assert len(wrong) == 4 * 6 and all(w["margin_nats"] > 0 and w["match_own_db"] == 5.0 for w in wrong)
    text = sel.markdown(r)
    assert "held out: [2, 3]" in text and "Walks wrong with the current default" in text


def test_home_votes_against_a_loop():
    rng = np.random.default_rng(2)
    for _ in range(20):
        n, n_floors = 7, 4
        walk = {"ap_walk_max_dbm": rng.uniform(-80, -40, n),
                "ap_floor_max_dbm": np.where(rng.random((n_floors, n)) < 0.3, -np.inf, rng.uniform(-90, -40, (n_floors, n)))}
        want = np.zeros(n_floors)
        for a in range(n):
            if walk["ap_walk_max_dbm"][a] < sel.HOME_NEAR_DBM:
                continue
            levels = [v if np.isfinite(v) else sel.HOME_NEVER_DBM for v in walk["ap_floor_max_dbm"][:, a]]
            best = int(np.argmax(levels))
            gap = sorted(levels)[-1] - sorted(levels)[-2]
            want[best] += min(1.0, max(0.0, gap / sel.HOME_FULL_GAP_DB))
        np.testing.assert_allclose(sel._home_votes(walk, n_floors), want)
