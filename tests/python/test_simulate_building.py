"""Synthetic building for fusion (simulate/building.py, radio.py, walker.py): geometry, radio,
walker and PDR statistics against brute-force references."""

import numpy as np
import pytest

from indoorloc.simulate.building import BuildingConfig, make_building
from indoorloc.simulate.radio import RadioConfig
from indoorloc.simulate.walker import PdrErrorConfig, WalkConfig, dead_reckon, simulate_walk, wrap_angle


@pytest.fixture(scope="module")
def building():
    return make_building(3)


@pytest.fixture(scope="module")
def walks(building):
    return [simulate_walk(building, s) for s in range(4)]


def brute_segments_intersect(a, b, c, d, touching):
    """Parametric test for one pair of segments a-b and c-d (plain Python floats)."""
    r = (b[0] - a[0], b[1] - a[1])
    s = (d[0] - c[0], d[1] - c[1])
    den = r[0] * s[1] - r[1] * s[0]
    qp = (c[0] - a[0], c[1] - a[1])
    if den == 0.0:
        if not touching or qp[0] * r[1] - qp[1] * r[0] != 0.0:
            return False   # parallel, or collinear when counting proper crossings
        rr = r[0] * r[0] + r[1] * r[1]
        t0 = (qp[0] * r[0] + qp[1] * r[1]) / rr
        t1 = t0 + (s[0] * r[0] + s[1] * r[1]) / rr
        return max(t0, t1) >= 0.0 and min(t0, t1) <= 1.0
    t = (qp[0] * s[1] - qp[1] * s[0]) / den
    u = (qp[0] * r[1] - qp[1] * r[0]) / den
    if touching:
        return 0.0 <= t <= 1.0 and 0.0 <= u <= 1.0
    return 0.0 < t < 1.0 and 0.0 < u < 1.0


def test_geometry_has_the_floor_plan_format(building):
    cfg = building.config
    assert building.floor_numbers == [0]
    g = building.plan
    assert len(g.outlines) == 1 and g.outlines[0].shape == (4, 2)
    assert all(o.ndim == 2 and o.shape[1] == 2 and o.shape[0] >= 3 for o in g.obstacles)
    assert len(g.obstacles) == cfg.num_shafts + cfg.num_pillars
    assert g.walls.ndim == 2 and g.walls.shape[1] == 4 and g.walls.shape[0] > 50
    assert np.all(np.hypot(g.walls[:, 2] - g.walls[:, 0], g.walls[:, 3] - g.walls[:, 1]) > 1e-6)
    # Rooms: closed rooms (shafts) have no door, every other room one or two.
    n_doors = [len(r.doors) for r in building.rooms]
    assert all((n == 0) == (r.kind == "shaft") for n, r in zip(n_doors, building.rooms))
    assert max(n_doors) == 2 and len([r for r in building.rooms if r.kind == "room"]) >= 30
    # A door is a gap of door_width_m: its middle is door_width/2 from the nearest wall end.
    for d in building.doors:
        assert g.distance_to_wall(d.position_m)[0] == pytest.approx(d.width_m / 2, abs=1e-9)
        assert g.is_walkable(d.position_m + 0.3 * d.normal)[0] and g.is_walkable(d.position_m - 0.3 * d.normal)[0]


def test_walk_graph_edges_cross_no_wall(building):
    gr = building.graph
    edges = building.plan.edges()
    seg = gr.segments()
    for s in seg:
        for e in edges:
            assert not brute_segments_intersect(s[:2], s[2:], e[:2], e[2:], touching=True)
    assert gr.is_connected()
    for r in building.rooms:
        if r.kind == "room":
            assert r.contains(gr.nodes_m[gr.room_node[r.index]])[0]


def test_same_seed_same_arrays_and_independent_streams(building):
    again = make_building(3)
    np.testing.assert_array_equal(again.plan.walls, building.plan.walls)
    for a, b in zip(again.plan.obstacles, building.plan.obstacles):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(again.radio.ap_positions_m, building.radio.ap_positions_m)
    np.testing.assert_array_equal(again.survey.rss_dbm, building.survey.rss_dbm)  # NaN == NaN here
    np.testing.assert_array_equal(again.graph.edges, building.graph.edges)
    w1, w2 = simulate_walk(building, 11), simulate_walk(again, 11)
    for name in ("time_s", "length_m", "heading_rad", "true_position_m"):
        np.testing.assert_array_equal(getattr(w1.steps, name), getattr(w2.steps, name))
    np.testing.assert_array_equal(w1.scans.rss_dbm, w2.scans.rss_dbm)
    np.testing.assert_array_equal(w1.truth.position_m, w2.truth.position_m)
    # Another walk seed: another walk; another building seed: another plan.
    assert not np.array_equal(simulate_walk(building, 12).truth.position_m, w1.truth.position_m)
    other = make_building(4)
    assert other.plan.walls.shape != building.plan.walls.shape or not np.allclose(other.plan.walls, building.plan.walls)
    # The walk's streams depend on the walk seed only: same PDR errors in another building.
    w3 = simulate_walk(other, 11)
    assert w3.steps.scale == w1.steps.scale and w3.steps.heading_bias_rad == w1.steps.heading_bias_rad


def test_walls_crossed_matches_a_brute_force_loop(building):
    rng = np.random.default_rng(0)
    pts = building.survey.positions_m[rng.choice(building.survey.num_points, 6, replace=False)]
    counts = building.walls_crossed(pts)
    aps = building.radio.ap_positions_m
    walls = building.plan.walls
    assert counts.shape == (6, aps.shape[0])
    for i, p in enumerate(pts):
        for k, a in enumerate(aps):
            n = sum(brute_segments_intersect(a, p, w[:2], w[2:], touching=False) for w in walls)
            assert counts[i, k] == n
    assert counts.max() >= 3


def test_route_never_crosses_a_wall_and_stays_walkable(building, walks):
    g = building.plan
    edges = g.edges()
    (x0, y0), (x1, y1) = g.outlines[0].min(axis=0), g.outlines[0].max(axis=0)
    for sc in walks:
        p = np.vstack([sc.start_position_m, sc.true_steps.position_m])
        for e in edges:   # every step segment against every wall edge, one edge at a time
            hits = [brute_segments_intersect(a, b, e[:2], e[2:], touching=True) for a, b in zip(p[:-1], p[1:])]
            assert not any(hits)
        dense = sc.truth.position_m
        assert np.all((dense[:, 0] > x0) & (dense[:, 0] < x1) & (dense[:, 1] > y0) & (dense[:, 1] < y1))
        for o in g.obstacles:   # rectangles
            lo, hi = o.min(axis=0), o.max(axis=0)
            assert not np.any(np.all((dense > lo) & (dense < hi), axis=1))
        assert g.is_walkable(dense).all()
        assert len(set(building.room_at(dense).tolist()) - {-1}) >= 2   # visits rooms


def test_walk_shape_and_dead_reckoning_with_true_steps(walks):
    for sc in walks:
        st = sc.true_steps
        assert 60 <= st.time_s[-1] <= sc.duration_s and np.all(np.diff(st.time_s) > 0)
        assert 0.5 < np.median(st.length_m) < 0.9
        cadence = 1.0 / np.median(st.time_s - st.start_time_s)
        assert 1.4 < cadence < 2.2
        # Smooth turns: no heading change above 100 degrees between consecutive steps.
        assert np.max(np.abs(wrap_angle(np.diff(st.heading_rad)))) < np.deg2rad(100)
        dr = dead_reckon(st.length_m, st.heading_rad, sc.start_position_m)
        np.testing.assert_allclose(dr[1:], st.position_m, atol=1e-9)
        np.testing.assert_allclose(sc.trajectory.position_at(st.time_s), st.position_m, atol=1e-12)
        np.testing.assert_allclose(sc.steps.true_position_m, sc.trajectory.position_at(sc.steps.time_s))
        assert np.all(np.diff(sc.steps.time_s) >= 0)
        assert sc.truth.position_m.shape == (sc.truth.time_s.size, 2)


def test_rss_falls_with_distance_and_by_w_per_wall(building):
    """Regression of the true mean RSS on log-distance, walls and obstacle faces recovers the
    model's exponent and per-wall loss (per-AP intercepts absorb P0; shadowing is the residual)."""
    c = building.radio_config
    pts = building.survey.positions_m
    mean = building.mean_rss_dbm(pts, 0)
    q, k = mean.shape
    r = building.radio
    d = np.sqrt(np.sum((pts[:, None, :] - r.ap_positions_m[None]) ** 2, axis=2) + c.ap_height_m**2)
    walls = building.walls_crossed(pts)
    obs = np.array([r.walls_crossed_pairs(pts, np.full(q, j))[1] for j in range(k)]).T
    x = np.column_stack([np.kron(np.ones((q, 1)), np.eye(k)), -10 * np.log10(d).ravel(), -walls.ravel(),
                         -obs.ravel()])
    coef, *_ = np.linalg.lstsq(x, mean.ravel(), rcond=None)
    n_hat, w_hat = coef[k], coef[k + 1]
    assert abs(n_hat - c.exponent) < 0.3
    assert abs(w_hat - c.wall_attenuation_db) < 0.8
    resid = mean.ravel() - x @ coef
    assert 0.7 * c.shadowing_sd_db < resid.std() < 1.3 * c.shadowing_sd_db
    # On average RSS falls with distance (line-of-sight pairs, binned by distance).
    los = (walls == 0) & (obs == 0)
    bins = np.digitize(d[los], [3, 6, 12, 24])
    means = [mean[los][bins == i].mean() for i in range(5) if np.sum(bins == i) > 20]
    assert len(means) >= 4 and np.all(np.diff(means) < 0)


def test_floor_attenuation_and_multi_floor_geometry():
    b = make_building(1, BuildingConfig(num_floors=2), RadioConfig(aps_per_floor=8, shadowing_sd_db=0.0,
                                                                  p0_sd_db=0.0))
    assert b.floor_numbers == [0, 1] and np.array_equal(b.floors[0].walls, b.floors[1].walls)
    assert b.radio.num_access_points == 16 and set(b.radio.ap_floors.tolist()) == {0, 1}
    pts = b.survey.positions_m[b.survey.floors == 0][::7]
    m0, m1 = b.mean_rss_dbm(pts, 0), b.mean_rss_dbm(pts, 1)
    c = b.radio_config
    same = b.radio.ap_floors == 0
    d_plan2 = np.sum((pts[:, None, :] - b.radio.ap_positions_m[None]) ** 2, axis=2)
    dist_term = 5 * c.exponent * (np.log10(d_plan2 + (c.ap_height_m + b.config.floor_height_m) ** 2)
                                  - np.log10(d_plan2 + c.ap_height_m**2))
    # Same plan walls on both floors, no shadowing: the difference is F + the longer distance.
    np.testing.assert_allclose((m0 - m1)[:, same], (c.floor_attenuation_db + dist_term)[:, same], atol=1e-9)
    with pytest.raises(ValueError, match="floor"):
        simulate_walk(b, 0, floor=5)


def test_survey_and_signal_map_conventions(building):
    sv = building.survey
    n, s, k = sv.rss_dbm.shape
    assert (n, s, k) == (sv.num_points, building.survey_config.scans_per_point, building.radio.num_access_points)
    assert building.plan.is_walkable(sv.positions_m).all()
    assert np.all(building.plan.distance_to_wall(sv.positions_m) >= building.survey_config.wall_clearance_m)
    heard = np.isfinite(sv.rss_dbm)
    assert 0.2 < heard.mean() < 0.9
    assert np.all(sv.rss_dbm[heard] >= building.radio_config.sensitivity_dbm)
    assert np.all(sv.rss_dbm[heard] == np.round(sv.rss_dbm[heard]))
    cnt = sv.heard_counts
    assert np.array_equal(np.isnan(sv.mean_dbm), cnt == 0) and np.array_equal(np.isnan(sv.variance_db2), cnt < 2)
    # Built from scans, not from the truth: close to the true field where always heard.
    full = cnt == s
    err = (sv.mean_dbm - building.mean_rss_dbm(sv.positions_m, 0))[full]
    noise = building.radio_config.noise_sd_db / np.sqrt(s)
    assert 0.7 * noise < err.std() < 1.5 * noise and abs(err.mean()) < 0.2
    assert np.sqrt(np.nanmean(sv.variance_db2[full])) == pytest.approx(building.radio_config.noise_sd_db, rel=0.15)
    pos, fl, rss = sv.scans()
    assert pos.shape == (n * s, 2) and fl.shape == (n * s,) and rss.shape == (n * s, k)
    m = building.signal_map()
    assert m.num_points == n
    cols = np.asarray(m.access_point_indices)
    floor_value = np.where(np.isnan(sv.rss_dbm), -105.0, sv.rss_dbm).mean(axis=1)
    np.testing.assert_allclose(np.asarray(m.mean_dbm), floor_value[:, cols], atol=1e-9)


def test_stale_readings_come_from_earlier_positions(building, walks):
    sigma = building.radio_config.noise_sd_db
    res_read, res_scan = [], []
    for sc in walks:
        sn = sc.scans
        sk = sn.rss_dbm.shape
        assert sn.age_s.shape == sk and sn.reading_position_m.shape == sk + (2,)
        assert np.array_equal(np.isnan(sn.age_s), np.isnan(sn.rss_dbm))
        age = sn.age_s
        ok = np.isfinite(age)
        assert np.all(age[ok] >= 0) and np.all((sn.time_s[:, None] - age)[ok] >= 0)
        assert np.all(np.diff(sn.time_s) > 0) and 1.7 < np.median(np.diff(sn.time_s)) < 2.3
        read_at = sc.trajectory.position_at(sn.last_seen_s[ok])
        np.testing.assert_allclose(sn.reading_position_m[ok], read_at, atol=1e-12)
        stale = ok & (age >= 1.0)
        assert 0.1 < stale.sum() / ok.sum() < 0.3
        moved = np.linalg.norm(sn.reading_position_m - sn.true_position_m[:, None, :], axis=2)
        assert np.median(moved[stale]) > 0.5 and np.all(moved[ok & (age < 0.01)] < 0.05)
        # Each stale reading fits the field where it was measured, not where the scan was taken.
        k = np.nonzero(stale)[1]
        rss = sn.rss_dbm[stale]
        res_read.append(rss - building.radio.mean_rss_pairs(sn.reading_position_m[stale], 0, k))
        res_scan.append(rss - building.radio.mean_rss_pairs(np.repeat(sn.true_position_m, sk[1], axis=0)
                                                          .reshape(sk + (2,))[stale], 0, k))
    rr, rs = np.concatenate(res_read), np.concatenate(res_scan)
    assert abs(rr.std() - sigma) < 0.5 and rs.std() > rr.std() + 0.5


def test_pdr_errors_have_the_configured_statistics(building):
    cfg = PdrErrorConfig()
    long = [simulate_walk(building, 100 + s, walk=WalkConfig(duration_s=600.0)) for s in range(3)]
    len_res, head_res, drift_inc, missed, extra, n_true = [], [], [], 0, 0, 0
    for sc in long:
        st, ts = sc.steps, sc.true_steps
        real = st.true_step >= 0
        j = st.true_step[real]
        len_res.append(st.length_m[real] - st.scale * ts.length_m[j])
        head_res.append(wrap_angle(st.heading_rad[real] - ts.heading_rad[j] - st.heading_bias_rad
                                   - st.heading_drift_rad[real]))
        drift_inc.append(np.diff(st.heading_drift_rad[real]) / np.sqrt(np.diff(j)))
        missed += int(ts.missed.sum())
        extra += int((~real).sum())
        n_true += ts.time_s.size
        assert np.array_equal(np.setdiff1d(np.arange(ts.time_s.size), j), np.flatnonzero(ts.missed))
        assert np.all(st.length_sd_m == cfg.length_noise_sd_m) and np.all(st.heading_sd_rad == cfg.heading_noise_sd_rad)
    lr, hr, di = map(np.concatenate, (len_res, head_res, drift_inc))
    assert n_true > 2500
    assert abs(lr.mean()) < 0.01 and lr.std() == pytest.approx(cfg.length_noise_sd_m, rel=0.1)
    assert abs(hr.mean()) < np.deg2rad(0.5) and hr.std() == pytest.approx(cfg.heading_noise_sd_rad, rel=0.1)
    assert di.std() == pytest.approx(cfg.heading_drift_sd_rad, rel=0.1)
    assert missed / n_true == pytest.approx(cfg.missed_step_probability, abs=0.008)
    assert extra / n_true == pytest.approx(cfg.extra_step_probability, abs=0.006)
    # Per-walk parameters over many short walks.
    short = [simulate_walk(building, 1000 + s, walk=WalkConfig(duration_s=8.0)) for s in range(150)]
    scale = np.array([sc.steps.scale for sc in short])
    bias = np.array([sc.steps.heading_bias_rad for sc in short])
    assert abs(scale.mean() - 1.0) < 0.025 and scale.std() == pytest.approx(cfg.scale_sd, rel=0.25)
    assert np.all(np.abs(bias) <= cfg.heading_bias_max_rad)
    assert bias.std() == pytest.approx(cfg.heading_bias_max_rad / np.sqrt(3), rel=0.25)


def test_bad_configurations_raise_value_error(building):
    with pytest.raises(ValueError, match="corridor_width_m"):
        make_building(0, BuildingConfig(corridor_width_m=1.0))
    with pytest.raises(ValueError, match="rooms_per_side"):
        make_building(0, BuildingConfig(rooms_per_side=2))
    with pytest.raises(ValueError, match="aps_per_floor"):
        make_building(0, radio=RadioConfig(aps_per_floor=0))
    with pytest.raises(ValueError, match="duration_s"):
        simulate_walk(building, 0, walk=WalkConfig(duration_s=-1.0))
    with pytest.raises(ValueError, match="step probabilities"):
        simulate_walk(building, 0, pdr=PdrErrorConfig(missed_step_probability=1.5))
