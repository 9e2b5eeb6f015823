"""The PDR studies' bookkeeping (issue 28): the swing-share cross-validation scores each
recording with a value chosen without it, its objective is the issue's goals in their own units,
and the health-signal table counts the failures past every good run."""

import numpy as np
import pytest

from indoorloc.experiments import pdr_gait_sweep as gs
from indoorloc.experiments import pdr_health_signals as hs
from indoorloc.experiments import pdr_low_motion as lm


def _row(armse, err=0, truth=10):
    return {"armse_m": armse, "stride_error": err, "strides_truth": truth}


def test_objective_weighs_groups_equally_in_goal_units():
    rows = [_row(0.12), _row(0.24, 1, 10), _row(0.0, 0, 100)]
    groups = np.array(["a", "a", "b"])
    keep = np.ones(3, dtype=bool)
    # group a: mean ARMSE 0.18 m / 0.12 + 1 of 20 strides / 1 % = 1.5 + 5; group b: 0
    assert gs._objective(rows, groups, keep) == pytest.approx((6.5 + 0.0) / 2)
    keep[1] = False
    assert gs._objective(rows, groups, keep) == pytest.approx((1.0 + 0.0) / 2)


def test_share_cv_never_scores_a_recording_with_a_value_chosen_on_it(monkeypatch):
    # Three recordings; share 0.1 is perfect on r0 and r1 and terrible on r2, share 0.3 the reverse
    # but mediocre: a held-out recording must get the value the other two prefer.
    armse = {0.1: [0.0, 0.0, 5.0], 0.3: [0.5, 0.5, 0.1]}

    class Rec:
        def __init__(self, i):
            self.i = i
            self.truth_xy_m = np.array([[0.0, 0.0], [1.0, 0.0]])

    def fake_score(rec, min_swing_share):
        return {"armse_m": armse[min_swing_share][rec.i], "stride_error": 0, "strides_truth": 10,
                "health": {"implausible": False}, "path_m": 1.0}

    monkeypatch.setattr(gs.lm, "score", fake_score)
    out = gs.share_cv({"g": [Rec(0), Rec(1), Rec(2)]}, grid=[0.1, 0.3])
    # without r0: 0.1 -> (0 + 5) / 2, 0.3 -> (0.5 + 0.1) / 2: 0.3 wins; same without r1; without r2: 0.1
    assert [h["armse_m"] for h in out["held"]] == [0.5, 0.5, 5.0]
    assert out["chosen"] == {0.3: 2, 0.1: 1}


def test_separation_counts_failures_beyond_every_good_run():
    base = {name: 1.0 for name in hs.SIGNALS}
    runs = [dict(base, armse_m=0.1, flagged=False, stance_motion_ratio=0.05, stride_count_ratio=0.9),
            dict(base, armse_m=0.2, flagged=False, stance_motion_ratio=0.08, stride_count_ratio=0.95),
            dict(base, armse_m=0.9, flagged=False, stance_motion_ratio=0.10, stride_count_ratio=0.6),
            dict(base, armse_m=0.9, flagged=False, stance_motion_ratio=0.07, stride_count_ratio=0.92),
            dict(base, armse_m=3.0, flagged=True, stance_motion_ratio=0.9, stride_count_ratio=0.1)]  # flagged: out
    rows = {r["signal"]: r for r in hs.separation(runs)}
    assert rows["stance_motion_ratio"]["beyond"] == 1 and rows["stance_motion_ratio"]["failures"] == 2
    assert rows["stride_count_ratio"]["beyond"] == 1  # lower is worse for this one
    assert rows["stance_motion_ratio"]["good_max"] == pytest.approx(0.08)
    assert "| stance_motion_ratio |" in hs.markdown(hs.separation(runs))


def test_the_gait_sweep_spans_its_axes():
    recs = gs.gait_sweep(steps=2)
    assert len(recs) == int(np.prod([len(v) for v in gs.SWEEP_AXES.values()]))
    assert len({r.name for r in recs}) == len(recs)  # names are unique (the studies key on them)
    assert recs[0].distance_m == pytest.approx(2 * 0.3) and recs[-1].distance_m == pytest.approx(2 * 1.4)


def test_a_health_limit_is_chosen_without_the_recording_it_scores():
    def run(name, good, value, reasons=()):
        return {"label": "PyShoe", "name": name, "good": good, "onset_speed_share": value, "gait_reasons": list(reasons),
                "ekf_flag": False}

    table = [run("a", True, 0.30), run("a", False, 0.90), run("b", True, 0.50), run("b", False, 0.40),
             run("c", True, 0.20), run("c", False, 3.0, ["the median swing lasts 0.05 s"])]  # c's failure: another check
    out = lm.onset_share_limit_cv(table)
    # without a: top good 0.50 -> 0.5; without b: 0.30 -> 0.3; without c: 0.50 -> 0.5
    assert out["chosen"] == {0.5: 2, 0.3: 1}
    assert (out["failures"], out["failures_caught"]) == (2, 2)      # a's 0.9 > 0.5, b's 0.4 > 0.3
    assert (out["good"], out["good_flagged"]) == (3, 1)             # b's 0.5 > 0.3: flagged held out


def test_setting_cv_labels_and_holds_out_every_recording(monkeypatch):
    class Rec:
        def __init__(self, i):
            self.i, self.name = i, f"r{i}"
            self.truth_xy_m = np.array([[0.0, 0.0], [1.0, 0.0]])

    armse = {(0.0, 0.0): [0.3, 0.3, 0.3], (1.5, 1.0): [0.1, 0.1, 0.9]}

    def fake_score(rec, split_swing_share, stance_core_decades):
        return {"armse_m": armse[(split_swing_share, stance_core_decades)][rec.i], "stride_error": 0,
                "strides_truth": 10, "health": {"implausible": False}, "path_m": 1.0}

    monkeypatch.setattr(gs.lm, "score", fake_score)
    settings = [{"split_swing_share": 0.0, "stance_core_decades": 0.0}, {"split_swing_share": 1.5, "stance_core_decades": 1.0}]
    out = gs.setting_cv({"g": [Rec(0), Rec(1), Rec(2)]}, settings)
    # without r2 the second setting wins (0.1 < 0.3); without r0 or r1 it averages 0.5 > 0.3
    assert [h["armse_m"] for h in out["held"]] == [0.3, 0.3, 0.9]
    assert out["chosen"] == {"split_swing_share 0, stance_core_decades 0": 2,
                             "split_swing_share 1.5, stance_core_decades 1": 1}
    assert "| g | after (CV, held out) |" in gs.markdown(out)
