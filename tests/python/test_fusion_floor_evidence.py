"""indoorloc.fusion.floor_evidence (per-floor AP detection rates as floor evidence) and its use by
floor identification: ``site_model.identify_floor`` and ``Site.track(floor="auto")`` on a
synthetic two-floor site (simulate.ilc_site)."""

import math
import warnings
from pathlib import Path

import numpy as np
import pytest

from indoorloc.io.errors import RecordingWarning

from indoorloc.fusion import floor_evidence as fe
from indoorloc.fusion import site_model

NAN = np.nan


def _refs():
    # Floor 3: APs 0, 1 heard; floor 4: APs 1, 2; AP 3 heard by one floor-4 reference only.
    rss = np.array([[-50, -70, NAN, NAN],
                    [-55, -75, NAN, NAN],
                    [NAN, -60, -45, NAN],
                    [NAN, -65, -50, -80]], float)
    return rss, np.array([3, 3, 4, 4])


def test_rates_match_counts_and_a_floor_without_references_gets_the_floor_rate():
    rss, floors = _refs()
    r = fe.ApFloorRates.from_references(rss, floors, [4, 3, 7], rate_floor=0.01)
    expected = np.array([[0, 1, 1, 0.5], [1, 1, 0, 0], [0, 0, 0, 0]]) + 0.01
    np.testing.assert_allclose(r.log_rate, np.log(expected))
    assert list(r.floors) == [4, 3, 7]
    assert not np.shares_memory(r.log_rate, rss)


def test_walk_likelihood_against_the_formula():
    rss, floors = _refs()
    r = fe.ApFloorRates.from_references(rss, floors, [3, 4], rate_floor=0.05)
    q = np.array([[-40, -90, -60, NAN],    # strongest two: AP 0, AP 2
                  [NAN, -50, -52, -70],    # strongest two: AP 1, AP 2
                  [NAN, NAN, NAN, NAN]])   # hears nothing known: no evidence
    eps, m = 0.2, 2
    got = fe.walk_floor_log_likelihood(r, q, m, eps)
    total = np.zeros(2)
    for aps in ([0, 2], [1, 2]):
        like = np.array([math.prod(np.exp(r.log_rate[f, a]) for a in aps) for f in range(2)])
        total += np.log(eps + (1 - eps) * like / like.sum())
    np.testing.assert_allclose(got, total)
    assert got[1] > got[0]  # AP 2 is heard on floor 4 only
    # ε = 1: every query is an outlier, no evidence; no queries: zeros; ε = 0 stays finite.
    np.testing.assert_allclose(fe.walk_floor_log_likelihood(r, q, m, 1.0), 0.0)
    np.testing.assert_allclose(fe.walk_floor_log_likelihood(r, np.zeros((0, 4)), m, eps), 0.0)
    assert np.all(np.isfinite(fe.walk_floor_log_likelihood(r, q, m, 0.0)))


def test_bad_arguments_name_themselves():
    rss, floors = _refs()
    with pytest.raises(ValueError, match="rate_floor"):
        fe.ApFloorRates.from_references(rss, floors, [3, 4], rate_floor=0.0)
    with pytest.raises(ValueError, match="reference_floors"):
        fe.ApFloorRates.from_references(rss, floors[:3], [3, 4], rate_floor=0.1)
    r = fe.ApFloorRates.from_references(rss, floors, [3, 4], rate_floor=0.1)
    with pytest.raises(ValueError, match="queries_dbm"):
        fe.walk_floor_log_likelihood(r, np.zeros((2, 3)), 2, 0.1)
    with pytest.raises(ValueError, match="ap_count"):
        fe.walk_floor_log_likelihood(r, rss, 0, 0.1)
    with pytest.raises(ValueError, match="outlier_probability"):
        fe.walk_floor_log_likelihood(r, rss, 2, 1.5)


def test_track_settings_carry_the_ap_evidence_settings():
    s = site_model.TrackSettings(identification_ap_weight=0.0, identification_ap_count=7)
    back = site_model.TrackSettings.from_dict(s.to_dict())
    assert back.identification_ap_weight == 0.0 and back.identification_ap_count == 7
    # from_dict fills a missing key with the default (a site file's stored dict goes through
    # fusion.site_settings instead: test_fusion_site_settings.py).
    d = s.to_dict()
    for k in ("identification_ap_weight", "identification_ap_count", "identification_ap_rate_floor",
              "identification_ap_outlier_probability"):
        d.pop(k)
    assert site_model.TrackSettings.from_dict(d).identification_ap_count == site_model.TrackSettings().identification_ap_count
    for bad in (dict(identification_ap_weight=-1.0), dict(identification_ap_count=0),
                dict(identification_ap_rate_floor=0.0), dict(identification_ap_outlier_probability=2.0)):
        with pytest.raises(ValueError, match=next(iter(bad))):
            site_model.TrackSettings(**bad).validate()


@pytest.fixture(scope="module")
def two_floor_site(tmp_path_factory):
    from indoorloc.simulate.ilc_site import write_ilc_site

    return write_ilc_site(tmp_path_factory.mktemp("ilc2") / "site", floors=("F1", "F2"), walks_per_floor=5, seed=3)


def test_auto_floor_of_a_site_uses_the_ap_evidence(two_floor_site, tmp_path):
    """Site.track(floor='auto') on held-out walks of two floors: right floor, and the combined
    probabilities are the grid's moved by the AP evidence (weight 0: the grid's alone)."""
    import shutil
    from dataclasses import replace

    from indoorloc.fusion.site import Site

    survey = tmp_path / "survey"
    held_out = []
    for floor in ("F1", "F2"):
        shutil.copytree(two_floor_site / floor, survey / floor)
        walks = sorted((survey / floor / "path_data_files").glob("*.txt"))
        held_out.append((floor, tmp_path / f"{floor}_{walks[-1].name}"))
        walks[-1].rename(held_out[-1][1])
    site = Site.build(survey, tmp_path / "site.db")
    # The synthetic walks' first queries lean to the other floor: with the default change rate the
    # floor sequence flags F1's walk (below); r = 0 keeps every walk on one floor, no warning.
    default_rate = site.settings.identification_floor_change_rate_per_s
    site.settings = replace(site.settings, identification_floor_change_rate_per_s=0.0)
    for floor, path in held_out:
        with warnings.catch_warnings():
            warnings.simplefilter("error", RecordingWarning)
            t = site.track(path, floor="auto")
        assert t.floor == floor and t.floor_probability > 0.5
        assert sum(t.floor_probabilities.values()) == pytest.approx(1.0)
        # Calibrated (floor_evidence.calibrated_floor_probabilities): never above 1 - δ/2 on two floors.
        assert t.floor_probability < 1.0
    # Weight 0: the grid filter alone decides (the identification before the AP evidence).
    site.settings = replace(site.settings, identification_ap_weight=0.0)
    site._all = None
    t0 = site.track(held_out[0][1], floor="auto")
    assert t0.floor == held_out[0][0]
    # A walk whose AP evidence changes floor is tracked on one floor, with a warning naming it.
    site.settings = replace(site.settings, identification_ap_weight=2.0, identification_floor_change_rate_per_s=default_rate)
    with pytest.warns(RecordingWarning, match=r"its WiFi suggests it changes floor \(F2 -> F1 at \d+ s\); it is tracked "
                                              r"on one floor, F1"):
        t1 = site.track(held_out[0][1], floor="auto")
    assert t1.floor == "F1"


def test_calibrated_probabilities_against_the_formula():
    score = np.array([0.0, -3.0, -40.0, -np.inf])
    for t, d in ((1.0, 0.0), (5.0, 0.02), (0.5, 0.3)):
        p = fe.calibrated_floor_probabilities(score, t, d)
        soft = np.exp(np.where(np.isfinite(score), score / t, -np.inf))
        np.testing.assert_allclose(p, (1 - d) * soft / soft.sum() + d / 4)
        assert p.sum() == pytest.approx(1.0) and int(np.argmax(p)) == 0
        assert p.max() <= 1 - d * 3 / 4 + 1e-12 and p[3] == pytest.approx(d / 4)
    # An overconfident margin of 400 nats is still capped by δ; a constant shift changes nothing.
    p = fe.calibrated_floor_probabilities(np.array([400.0, 0.0]), 1.0, 0.02)
    np.testing.assert_allclose(p, [0.99, 0.01])
    np.testing.assert_allclose(fe.calibrated_floor_probabilities(score + 1e3, 2.0, 0.1),
                               fe.calibrated_floor_probabilities(score, 2.0, 0.1))


def test_calibrated_probabilities_of_many_walks_are_those_of_each():
    rng = np.random.default_rng(0)
    scores = rng.normal(0, 20, (7, 4))
    delta = rng.uniform(0, 0.3, 7)
    many = fe.calibrated_floor_probabilities(scores, 2.0, delta)
    for i in range(7):
        np.testing.assert_allclose(many[i], fe.calibrated_floor_probabilities(scores[i], 2.0, delta[i]))
    with pytest.raises(ValueError, match="error_probability"):
        fe.calibrated_floor_probabilities(scores, 2.0, delta[:3])


def test_error_probability_grows_with_the_match_distance():
    c = fe.FloorCalibration(temperature=1.0, error_probability_at_10db=0.03, error_slope=2.0)
    d = c.error_probability(np.array([2.5, 10.0, 40.0]))
    # logit δ = logit 0.03 + 2 ln(D / 10): odds x 1/16 at 2.5 dB, x 16 at 40 dB.
    odds = 0.03 / 0.97
    np.testing.assert_allclose(d, [odds / 16 / (1 + odds / 16), 0.03, odds * 16 / (1 + odds * 16)])
    assert c.error_probability(None) == pytest.approx(0.03) and c.error_probability(np.nan) == pytest.approx(0.03)
    assert fe.FloorCalibration(1.0, 0.03, 0.0).error_probability(40.0) == pytest.approx(0.03)
    p = c.probabilities(np.array([0.0, -100.0]), 40.0)
    assert p[0] == pytest.approx(1 - d[2] / 2)
    for kwargs, name in ((dict(temperature=-1.0), "temperature"), (dict(error_probability_at_10db=1.0), "error_prob"),
                         (dict(error_slope=-0.5), "error_slope")):
        with pytest.raises(ValueError, match=name):
            fe.FloorCalibration(**kwargs)


def test_match_distance_against_brute_force():
    rss, floors = _refs()
    q = np.array([[-52, -72, NAN, NAN],     # close to floor 3's first reference
                  [NAN, -62, -47, -90],     # close to floor 4's
                  [NAN, NAN, NAN, NAN]])    # hears nothing: skipped
    for floor in (3, 4):
        for m, cost in ((2, 30.0), (3, 10.0)):
            per_query = []
            for row in q[:2]:
                heard = [a for a in np.argsort(-np.nan_to_num(row, nan=-1e9)) if np.isfinite(row[a])][:m]
                per_query.append(min(np.mean([abs(ref[a] - row[a]) if np.isfinite(ref[a]) else cost for a in heard])
                                     for ref, f in zip(rss, floors) if f == floor))
            got = fe.walk_match_distance_db(rss, floors, floor, q, m, cost)
            assert got == pytest.approx(np.median(per_query))
    assert fe.walk_match_distance_db(rss, floors, 3, q, 2) < fe.walk_match_distance_db(rss, floors, 4, q[:1], 2)
    # Nothing to compare: the unheard cost.
    assert fe.walk_match_distance_db(rss, floors, 9, q) == fe.MATCH_UNHEARD_DB
    assert fe.walk_match_distance_db(rss, floors, 3, q[2:]) == fe.MATCH_UNHEARD_DB
    with pytest.raises(ValueError, match="queries_dbm"):
        fe.walk_match_distance_db(rss, floors, 3, np.zeros((1, 3)))
    with pytest.raises(ValueError, match="reference_floors"):
        fe.walk_match_distance_db(rss, floors[:2], 3, q)


def test_calibration_bad_arguments_name_themselves():
    for kwargs, name in ((dict(temperature=0.0), "temperature"), (dict(error_probability=1.0), "error_probability"),
                         (dict(error_probability=-0.1), "error_probability"), (dict(temperature=np.nan), "temperature")):
        args = dict(score=np.zeros(3), temperature=1.0, error_probability=0.01) | kwargs
        with pytest.raises(ValueError, match=name):
            fe.calibrated_floor_probabilities(**args)
    for bad in (np.zeros(0), np.array([0.0, np.nan]), np.array([-np.inf, -np.inf]), np.array([np.inf, 0.0])):
        with pytest.raises(ValueError, match="score"):
            fe.calibrated_floor_probabilities(bad, 1.0, 0.0)


def test_track_settings_carry_the_calibration():
    s = site_model.TrackSettings(identification_temperature=3.0, identification_error_probability=0.05,
                                 identification_error_slope=1.5)
    back = site_model.TrackSettings.from_dict(s.to_dict())
    assert back.floor_calibration() == fe.FloorCalibration(3.0, 0.05, 1.5)
    d = s.to_dict()
    for k in ("identification_temperature", "identification_error_probability", "identification_error_slope"):
        d.pop(k)
    assert site_model.TrackSettings.from_dict(d).floor_calibration() == site_model.TrackSettings().floor_calibration()
    for bad in (dict(identification_temperature=0.0), dict(identification_temperature=math.inf),
                dict(identification_error_probability=1.0), dict(identification_error_probability=-0.5),
                dict(identification_error_slope=-1.0), dict(identification_floor_change_rate_per_s=-1.0)):
        with pytest.raises(ValueError, match=next(iter(bad))):
            site_model.TrackSettings(**bad).validate()


def test_study_calibration_recovers_an_overconfidence_factor_and_bins_every_walk():
    """Walks whose true floor is drawn from softmax(z) but whose score is 5 z (five times too
    confident; 5 is on the grid): the study's log-loss choice finds T = 5, and its reliability
    table then matches reported and realised frequencies; the uncalibrated one does not."""
    from indoorloc.experiments import floor_identification_study as study

    rng = np.random.default_rng(1)
    z = rng.normal(0.0, 2.0, (3000, 3))
    p_true = np.exp(z) / np.exp(z).sum(axis=1, keepdims=True)
    label = np.array([rng.choice(3, p=row) for row in p_true])
    dist = np.full(z.shape, 10.0)
    chosen = study.choose_calibration(5.0 * z, dist, label)
    assert chosen["temperature"] == 5.0 and chosen["error_probability_at_10db"] <= 0.01
    cal = study.reliability(study._calibrated(5.0 * z, dist, chosen), label)
    raw = study.reliability(study._calibrated(5.0 * z, dist, {}), label)
    assert sum(b["walks"] for b in cal["bins"]) == 3000 == sum(b["walks"] for b in raw["bins"])
    assert cal["log_loss"] < raw["log_loss"] and cal["brier"] < raw["brier"]
    assert abs(cal["mean_reported"] - cal["fraction_right"]) < 0.02
    assert raw["mean_reported"] - raw["fraction_right"] > 0.05


def test_study_markdown_prints_a_result_reloaded_from_json_with_an_infinite_log_loss():
    """An uncalibrated walk given probability 0 for its true floor has an infinite log loss, which
    the study's JSON stores as null: the reloaded result prints the same table as the run did."""
    import json

    from indoorloc.experiments import floor_identification_study as study

    path = Path(__file__).resolve().parents[2] / "benchmarks" / "results" / "floor_identification_study.json"
    reloaded = json.loads(path.read_text())
    assert reloaded["calibration"]["uncalibrated_reliability"]["log_loss"] is None
    in_memory = json.loads(path.read_text(), object_hook=lambda d: {
        k: (math.inf if k == "log_loss" and v is None else v) for k, v in d.items()})
    table = study.markdown(reloaded)
    assert table == study.markdown(in_memory)
    assert "| log loss / Brier |" in table and "| inf / " in table
    assert table in path.with_suffix(".md").read_text()


def test_identification_calibration_is_the_first_floors_with_the_widest_spread():
    """Floor identification (track --floor auto and fusion evaluate) rotates the steps of a walk
    of unknown floor with one calibration for every walk: never the walk's own floor's."""
    from indoorloc.pdr.handheld import HandheldCalibration, HandheldOptions

    def cal(offset, spread):
        return HandheldCalibration(HandheldOptions(), 0.5, 0.1, 10, offset, spread, 0.1, 0.2)

    cals = [cal(0.05, 0.1), cal(-0.04, 0.3), cal(0.1, math.nan)]
    first, spread = site_model.identification_calibration(cals)
    assert first is cals[0] and spread == pytest.approx(0.3)
    assert site_model.identification_calibration(cals[2:])[1] == pytest.approx(1e-3)  # no spread: the floor of 1e-3
    with pytest.raises(ValueError, match="calibrations"):
        site_model.identification_calibration([])


def test_reliability_table_bins_every_walk_once():
    reported = np.array([0.3, 0.85, 0.97, 0.995, 0.995, 1.0, 0.9999])
    right = np.array([False, True, True, True, False, True, True])
    rows = fe.reliability_table(reported, right)
    assert [r["walks"] for r in rows] == [1, 1, 1, 2, 2]
    assert rows[3]["fraction_right"] == 0.5 and rows[-1]["from"] == 0.999 and rows[-1]["mean_reported"] == pytest.approx(0.99995)
    with pytest.raises(ValueError, match="right"):
        fe.reliability_table(reported, right[:3])
    with pytest.raises(ValueError, match="reported"):
        fe.reliability_table(np.array([np.nan]), np.array([True]))


def _brute_force_sequence(e, t, rate):
    """Every floor sequence enumerated: posterior marginals, the best sequence and the evidence."""
    import itertools

    q, f = e.shape
    best, best_lp, marg, total = None, -np.inf, np.zeros((q, f)), 0.0
    for seq in itertools.product(range(f), repeat=q):
        lp = -math.log(f) + e[0, seq[0]]
        for k in range(1, q):
            keep = math.exp(-rate * (t[k] - t[k - 1]))
            step = keep * (seq[k] == seq[k - 1]) + (1 - keep) / f
            lp += (math.log(step) if step > 0 else -math.inf) + e[k, seq[k]]
        w = math.exp(lp)
        total += w
        marg[np.arange(q), list(seq)] += w
        if lp > best_lp + 1e-12:
            best, best_lp = seq, lp
    return marg / total, np.array(best), math.log(total)


def test_floor_sequence_against_brute_force_enumeration():
    from indoorloc.fusion.floor_sequence import floor_sequence

    rng = np.random.default_rng(4)
    for rate in (0.0, 0.01, 0.3):
        e = np.log(rng.uniform(0.05, 1.0, (5, 3)))
        t = np.cumsum(rng.uniform(0.5, 4.0, 5))
        got = floor_sequence(e, t, rate)
        marg, best, log_z = _brute_force_sequence(e, t, rate)
        np.testing.assert_allclose(got["posterior"], marg, atol=1e-12)
        np.testing.assert_array_equal(got["path"], best)
        assert got["log_evidence"] == pytest.approx(log_z)
        assert got["changes"] == int(np.count_nonzero(np.diff(best)))


def test_floor_sequence_without_changes_is_the_walks_posterior_and_finds_a_change():
    from indoorloc.fusion.floor_sequence import floor_sequence

    rng = np.random.default_rng(5)
    e = np.log(rng.uniform(0.05, 1.0, (12, 4)))
    t = np.arange(12.0) * 3
    walk = e.sum(axis=0)
    walk = np.exp(walk - walk.max())
    got = floor_sequence(e, t, 0.0)
    np.testing.assert_allclose(got["posterior"], np.tile(walk / walk.sum(), (12, 1)), atol=1e-12)
    assert got["changes"] == 0
    # Ten queries that say floor 0, then ten that say floor 2: one change, where it happened.
    strong = np.log(np.array([[0.9, 0.05, 0.05], [0.05, 0.05, 0.9]]))
    e2 = np.vstack([np.tile(strong[0], (10, 1)), np.tile(strong[1], (10, 1))])
    got = floor_sequence(e2, np.arange(20.0) * 3, 1.0 / 600)
    np.testing.assert_array_equal(got["path"], [0] * 10 + [2] * 10)
    assert got["changes"] == 1 and got["posterior"][0, 0] > 0.9 and got["posterior"][-1, 2] > 0.9
    assert floor_sequence(np.zeros((0, 3)), np.zeros(0), 0.1)["changes"] == 0
    for kwargs, name in ((dict(t_s=np.arange(20.0)[::-1]), "t_s"), (dict(t_s=np.arange(3.0)), "t_s"),
                         (dict(change_rate_per_s=-1.0), "change_rate_per_s"),
                         (dict(log_likelihoods=np.full((20, 3), np.nan)), "log_likelihoods")):
        args = dict(log_likelihoods=e2, t_s=np.arange(20.0), change_rate_per_s=0.01) | kwargs
        with pytest.raises(ValueError, match=name):
            floor_sequence(**args)


def test_floor_change_study_detects_spliced_walks_and_keeps_real_ones():
    """Synthetic evidence: every query says its floor (with an occasional wrong one); spliced
    walks change floor, real ones do not. A rate > 0 finds the changes, r = 0 none."""
    from indoorloc.experiments import floor_change_study as study

    rng = np.random.default_rng(2)
    walks = []
    for i in range(24):
        f = i % 3
        e = np.log(np.full((15, 3), 0.1))
        e[:, f] = np.log(0.9)
        odd = rng.integers(15)
        e[odd] = np.log([0.9 if g == (f + 1) % 3 else 0.1 for g in range(3)])
        walks.append({"floor": "ABC"[f], "floor_index": f, "fold": i % 2, "walk": f"w{i}",
                      "t_s": np.arange(15.0) * 3, "log_likelihoods": e})
    r = study.select_rate({"floors": ["A", "B", "C"], "walks": walks})
    rows = {row["rate_per_s"]: row for row in r["rows"]}
    assert r["n_real"] == 24 and r["n_spliced"] == 24
    assert rows[0.0]["spliced_with_a_change"] == 0 and rows[0.0]["real_walks_with_a_change"] == 0
    assert rows[1 / 1200]["spliced_with_a_change"] == 24 and rows[1 / 1200]["real_walks_with_a_change"] == 0
    assert rows[1 / 1200]["queries_right"] == 1.0 and r["chosen_all"] > 0
    assert set(r["lofo"]["chosen"]) == {"A", "B", "C"} and r["lofo"]["queries_right"] > 0.9
    assert "| 0 | 0 of 24 |" in study.markdown(r)


def test_study_cli_passes_the_fold_seeds_and_refuses_bad_ones(tmp_path, capsys):
    """The floor studies' command line: ``--seed`` (one or several) reaches the study (the fold
    assignment, as ``fusion evaluate --seed``) and is recorded in the JSON; a negative or repeated
    seed is refused; the floor-change study takes one seed."""
    import json
    from indoorloc.experiments import floor_change_study, study_cli

    seen = []

    def compute(root, floors, seeds):
        seen.append((root, list(floors), seeds))
        return {"value": 1}

    out = tmp_path / "r.json"
    assert study_cli.run_study(["--floors", "F3", "--seed", "2", "--json", str(out)], "t", compute,
                               lambda r: f"seeds {r['seeds']}") == 0
    assert seen == [(None, ["F3"], [2])]
    assert json.loads(out.read_text())["seeds"] == [2] and "seeds [2]" in capsys.readouterr().out
    study_cli.run_study([], "t", compute, lambda r: "")
    assert seen[-1][2] == [0]
    study_cli.run_study(["--seed", "0", "3"], "t", compute, lambda r: "")
    assert seen[-1][2] == [0, 3]
    for bad in (["--seed", "-1"], ["--seed", "1", "1"]):
        with pytest.raises(SystemExit):
            study_cli.run_study(bad, "t", compute, lambda r: "")
        assert "--seed" in capsys.readouterr().err
    with pytest.raises(ValueError, match="--seed"):
        floor_change_study._one_seed([0, 1])
    assert floor_change_study._one_seed([3]) == 3
