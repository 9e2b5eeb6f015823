"""indoorloc.fusion.floor_evidence (per-floor AP detection rates as floor evidence) and its use by
floor identification: ``site_model.identify_floor`` and ``Site.track(floor="auto")`` on a
synthetic two-floor site (simulate.ilc_site)."""

import math

import numpy as np
import pytest

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
    # A site file written before these settings existed reads with the defaults.
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
    for floor, path in held_out:
        t = site.track(path, floor="auto")
        assert t.floor == floor and t.floor_probability > 0.5
        assert sum(t.floor_probabilities.values()) == pytest.approx(1.0)
    # Weight 0: the grid filter alone decides (the identification before the AP evidence).
    site.settings = replace(site.settings, identification_ap_weight=0.0)
    site._all = None
    t0 = site.track(held_out[0][1], floor="auto")
    assert t0.floor == held_out[0][0]
