"""indoorloc.fusion.floor_classifier (a logistic-regression floor classifier on the APs a scan hears)
and its place in floor identification (``site_model.ap_floor_rates``, ``walk_floor_evidence``,
``identify_floor``)."""

import math

import numpy as np
import pytest

from indoorloc.fusion import site_model
from indoorloc.fusion.floor_classifier import FloorClassifier

NAN = np.nan


def _survey(rng, n_per_floor=(40, 120, 60)):
    """Three floors (numbers 1, 2, 3) of unequal survey density. APs 0-5 are heard everywhere;
    APs 6-8 only on floor 1, 9-11 only on floor 2, 12-14 only on floor 3, each by half of its
    floor's references (weakly: -85 dBm)."""
    rows, floors = [], []
    for f, n in zip((1, 2, 3), n_per_floor):
        x = np.full((n, 15), NAN)
        x[:, :6] = rng.uniform(-80, -40, (n, 6))
        own = slice(6 + 3 * (f - 1), 9 + 3 * (f - 1))
        x[:, own] = np.where(rng.random((n, 3)) < 0.5, -85.0, NAN)
        rows.append(x)
        floors += [f] * n
    return np.concatenate(rows), np.array(floors)


def test_the_floor_only_its_survey_hears_wins_even_weak_and_against_survey_density():
    rng = np.random.default_rng(0)
    rss, floors = _survey(rng)
    clf = FloorClassifier.fit(rss, floors, [1, 2, 3], l2_scale=1.0)
    q = np.full((3, 15), NAN)
    q[:, :6] = -50.0
    q[0, 7] = q[1, 10] = q[2, 13] = -90.0  # one weak floor-own AP each
    log_p, used = clf.query_log_posteriors(q)
    assert used.all() and np.allclose(np.exp(log_p).sum(axis=1), 1.0)
    assert (np.argmax(log_p, axis=1) == [0, 1, 2]).all() and (np.exp(log_p.max(axis=1)) > 0.75).all()
    # Only shared APs: no floor is favoured much, whatever its survey density (class-balanced).
    shared = np.full((1, 15), NAN)
    shared[0, :6] = -60.0
    p = np.exp(clf.query_log_posteriors(shared)[0][0])
    assert p.max() < 0.6


def test_class_balance_holds_at_the_optimum_and_the_fit_is_deterministic():
    """At the optimum of the class-balanced loss (bias not penalised) the weighted mean predicted
    probability of each floor is 1/F: a check of the bias gradient."""
    rng = np.random.default_rng(1)
    rss, floors = _survey(rng)
    a = FloorClassifier.fit(rss, floors, [1, 2, 3], l2_scale=0.1)
    b = FloorClassifier.fit(rss, floors, [1, 2, 3], l2_scale=0.1)
    assert np.array_equal(a.weights, b.weights) and np.array_equal(a.bias, b.bias)
    log_p, _ = a.query_log_posteriors(rss)
    p = np.exp(log_p)
    w = np.array([1.0 / (floors == f).sum() for f in floors])
    mean = (p * w[:, None]).sum(axis=0) / w.sum()
    assert mean == pytest.approx(np.full(3, 1 / 3), abs=2e-3)


def test_a_stronger_penalty_gives_softer_posteriors():
    rng = np.random.default_rng(2)
    rss, floors = _survey(rng)
    soft = FloorClassifier.fit(rss, floors, [1, 2, 3], l2_scale=0.01)
    hard = FloorClassifier.fit(rss, floors, [1, 2, 3], l2_scale=10.0)
    assert np.abs(soft.weights).max() < np.abs(hard.weights).max()
    q = rss[:5]
    assert soft.query_log_posteriors(q)[0].max(axis=1).mean() < hard.query_log_posteriors(q)[0].max(axis=1).mean()


def test_walk_likelihood_against_the_formula_and_a_floor_without_references():
    rng = np.random.default_rng(3)
    rss, floors = _survey(rng)
    clf = FloorClassifier.fit(rss, floors, [1, 2, 3, 9], l2_scale=1.0)  # floor 9: no reference
    assert clf.trained.tolist() == [True, True, True, False]
    q = rss[[0, 50, 170]].copy()
    q = np.concatenate([q, np.full((1, 15), NAN)])  # a query that hears nothing carries no evidence
    log_p, used = clf.query_log_posteriors(q)
    assert used.tolist() == [True, True, True, False]
    assert log_p[:, 3] == pytest.approx(np.full(3, -math.log(4)))
    assert np.exp(log_p).sum(axis=1) == pytest.approx(np.ones(3))
    eps = 0.05
    want = np.log(eps + (1 - eps) * np.exp(log_p)).sum(axis=0)
    assert clf.walk_log_likelihood(q, eps) == pytest.approx(want)
    assert clf.walk_log_likelihood(np.zeros((0, 15)), eps) == pytest.approx(np.zeros(4))


def test_bad_arguments_name_themselves():
    rss, floors = _survey(np.random.default_rng(4), (5, 5, 5))
    for kwargs, name in ((dict(l2_scale=0.0), "l2_scale"), (dict(l2_scale=math.nan), "l2_scale"),
                         (dict(reference_floors=floors[:-1]), "reference_floors"),
                         (dict(floors=[1, 1, 2]), "floors"), (dict(floors=[]), "floors"),
                         (dict(max_iterations=0), "max_iterations"), (dict(rss_dbm=rss[0]), "rss_dbm")):
        args = dict(rss_dbm=rss, reference_floors=floors, floors=[1, 2, 3], l2_scale=1.0) | kwargs
        with pytest.raises(ValueError, match=name):
            FloorClassifier.fit(**args)
    clf = FloorClassifier.fit(rss, floors, [1, 2, 3], 1.0)
    with pytest.raises(ValueError, match="queries_dbm"):
        clf.query_log_posteriors(rss[:, :4])
    with pytest.raises(ValueError, match="outlier_probability"):
        clf.walk_log_likelihood(rss[:2], 1.5)


def test_identify_floor_adds_the_weighted_classifier_evidence_and_settings_carry_it():
    s = site_model.TrackSettings(identification_classifier_weight=3.0, identification_classifier_l2_scale=0.5,
                                 identification_classifier_outlier_probability=0.2)
    back = site_model.TrackSettings.from_dict(s.to_dict())
    assert (back.identification_classifier_weight, back.identification_classifier_l2_scale,
            back.identification_classifier_outlier_probability) == (3.0, 0.5, 0.2)
    for bad in (dict(identification_classifier_weight=-1.0), dict(identification_classifier_l2_scale=0.0),
                dict(identification_classifier_outlier_probability=1.5)):
        with pytest.raises(ValueError, match=next(iter(bad))):
            site_model.TrackSettings(**bad).validate()
    # ap_floor_rates attaches the classifier only when its weight is > 0.
    from indoorloc.fusion import wifi_fixes

    rss, floors = _survey(np.random.default_rng(5), (10, 10, 10))
    db = wifi_fixes.FingerprintDatabase(rss, np.zeros((rss.shape[0], 2)), [f"ap{i}" for i in range(15)],
                                        wifi_fixes.FixSettings(), floors=floors)
    assert site_model.ap_floor_rates(db, [1, 2, 3], site_model.TrackSettings(
        identification_classifier_weight=0.0)).classifier is None
    rates = site_model.ap_floor_rates(db, [1, 2, 3], s)
    assert isinstance(rates.classifier, FloorClassifier) and rates.classifier.floors.tolist() == [1, 2, 3]


def test_study_chooses_the_classifier_when_it_alone_tells_the_floors_and_reports_both_deciders():
    """Synthetic study evidence: the grid and the rates are wrong on a third of the walks, the
    classifier's evidence right on all; the study's leave-one-floor-out choice takes the
    classifier (weight > 0) and reports the rates-only decider apart."""
    from indoorloc.experiments import floor_identification_study as study

    rng = np.random.default_rng(6)
    walks = []
    for i in range(60):
        f = i % 3
        wrong = (f + 1) % 3 if i % 3 == 0 and i % 2 == 0 else f
        grid = np.full(3, -5.0)
        grid[wrong] = 0.0
        ap = {p: grid.copy() for p in [(20, 0.1, 0.1)]}
        clf = np.full(3, -20.0)
        clf[f] = 0.0
        walks.append({"floor": "ABC"[f], "floor_index": f, "walk": f"w{i}", "fold": i % 4, "n_waypoints": 5,
                      "grid": grid + rng.normal(0, 0.1, 3), "vote": np.eye(3)[wrong], "ap": ap,
                      "classifier": {(c, e): clf for c in study.CLASSIFIER_GRID["l2_scale"]
                                     for e in study.CLASSIFIER_GRID["outlier_probability"]},
                      "match_distance_db": np.full(3, 5.0)})
    grid = {"ap_count": (20,), "rate_floor": (0.1,), "outlier_probability": (0.1,), "weight": (1.0, 2.0)}
    r = study.select({"floors": ["A", "B", "C"], "walks": walks, "grid": grid})
    assert r["chosen_all_figures"]["accuracy"] == 1.0 and r["chosen_all"]["classifier_weight"] > 0
    assert r["lofo"]["accuracy"] == 1.0 and r["classifier_alone"]["accuracy"] == 1.0
    assert r["rates_only"]["chosen_all_figures"]["accuracy"] < 0.9
    assert "grid + AP rates + classifier, held out (LOFO)" in study.markdown(r)


def test_the_fit_runs_blas_on_one_thread_and_restores_the_pool(monkeypatch):
    """L-BFGS-B's BLAS calls run on one thread during the fit (threaded BLAS sums would depend on
    the machine's core count, and its idle threads spin beside the caller's), and the caller's
    BLAS thread count is restored afterwards."""
    from threadpoolctl import threadpool_info

    from indoorloc.fusion import floor_classifier as fc

    def blas_threads():
        return [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]

    before = blas_threads()
    seen = []
    real_minimize = fc.minimize

    def recording_minimize(*args, **kwargs):
        seen.append(blas_threads())
        return real_minimize(*args, **kwargs)

    monkeypatch.setattr(fc, "minimize", recording_minimize)
    rss, floors = _survey(np.random.default_rng(0))
    FloorClassifier.fit(rss, floors, [1, 2, 3], l2_scale=1.0)
    assert seen and seen[0] and all(n == 1 for n in seen[0])
    assert blas_threads() == before
