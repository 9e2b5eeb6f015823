"""Regression tests of issue 17 for the fusion subsystem (found by test_properties_fusion.py):
options checked through the core validation vocabulary, argument names in every message, size
limits, and the batch API's dict/tuple arguments."""

import numpy as np
import pytest

from indoorloc import fusion
from indoorloc._core import fusion as cf


def _plan():
    outline = np.array([[0, 0], [20, 0], [20, 10], [0, 10]], float)
    block = np.array([[8, 3], [12, 3], [12, 7], [8, 7]], float)
    return fusion.FloorPlan([fusion.FloorGeometry(0, [outline], [block])])


def _track(**changes):
    n = 4
    kwargs = dict(plan=_plan(), wifi_model=None, corridors=None, step_times_s=0.5 * np.arange(1, n + 1),
                  displacements_m=np.tile([0.0, 0.7], (n, 1)), covariances_m2=np.tile([0.01, 0.0, 0.01], (n, 1)),
                  observations=[], start={"position_m": np.array([2.0, 1.5])},
                  options=fusion.tracker_options(num_particles=100), smoother=None, fixes=None)
    kwargs.update(changes)
    return cf.track(**kwargs)


@pytest.mark.parametrize("field, value, rule", [
    ("position_noise_m", 1e-300, "position_noise_m must be in"),   # 1/σ² was inf
    ("position_noise_m", float("nan"), "position_noise_m must be in"),
    ("min_scale", 2.0, "min_scale must be <= max_scale"),
    ("tempering", float("nan"), "tempering must be in (0, 1]"),
    ("max_term", float("nan"), "max_term must be > 0"),
    ("fix_tempering", 2.0, "fix_tempering must be in (0, 1]"),       # was "fix: tempering ..."
    ("fix_outlier_probability", 1.0, "fix_outlier_probability must be in (0, 1)"),
    ("ess_threshold", float("nan"), "ess_threshold must be in [0, 1]"),
    ("respread_sd_m", 1e300, "respread_sd_m must be finite and in"),
    ("start_position_sd_m", 1e300, "start_position_sd_m must be 0 or in"),
    ("start_scale_sd", 1e300, "start_scale_sd must be in [0, 100]"),
    ("unknown_start_heading_sd_rad", float("nan"), "unknown_start_heading_sd_rad must be in"),
    ("recovery_log_ratio", 1e300, "recovery_log_ratio must be in"),
    ("recovery_scans", 2**31 - 1, "recovery_scans must be in [1, 1000000]"),
    ("respread_after_blocked_steps", 2**31 - 1, "respread_after_blocked_steps must be in"),
])
def test_tracker_options_name_the_flattened_field_value_and_rule(field, value, rule):
    with pytest.raises(ValueError) as info:
        fusion.tracker_options(**{field: value})
    assert rule in str(info.value)
    assert "got" in str(info.value)


def test_tracker_options_wrong_type_names_the_field():
    with pytest.raises(TypeError, match="argument 'num_particles'"):
        fusion.tracker_options(num_particles="many")


def test_floor_plan_and_smoother_options_limits():
    with pytest.raises(ValueError, match="cell_size_m must be <= 0 .automatic. or in"):
        fusion.FloorPlanOptions(cell_size_m=1e-300)
    with pytest.raises(ValueError, match="target_edges_per_cell must be in"):
        fusion.FloorPlanOptions(target_edges_per_cell=1e300)
    with pytest.raises(ValueError, match=r"max_cells must be in \[1, 100000000\]"):
        fusion.FloorPlanOptions(max_cells=2**31 - 1)
    with pytest.raises(ValueError, match="max_particles"):
        fusion.SmootherOptions(num_trajectories=100000, max_particles=50000000)


def test_sample_walkable_refuses_more_than_the_memory_limit():
    with pytest.raises(ValueError, match="argument 'n': .* points would need .* GB"):
        _plan().sample_walkable(2**31 - 1)


def test_track_start_smoother_and_fixes_arguments_are_named():
    with pytest.raises(ValueError, match="argument 'start': expected None or a dict"):
        _track(start="here")
    with pytest.raises(ValueError, match="argument 'start': a known start needs 'position_m'"):
        _track(start={"floor": 0})  # was KeyError
    with pytest.raises(ValueError, match="argument 'start': unknown key 'postion_m'"):
        _track(start={"postion_m": [2.0, 1.5]})
    with pytest.raises(ValueError, match=r"argument 'start\['time_s'\]': expected a real number"):
        _track(start={"position_m": [2.0, 1.5], "time_s": "soon"})  # was RuntimeError (cast)
    with pytest.raises(ValueError, match=r"argument 'start\['time_s'\]': must be finite"):
        _track(start={"position_m": [2.0, 1.5], "time_s": float("nan")})
    with pytest.raises(ValueError, match=r"argument 'start\['floor'\]'"):
        _track(start={"position_m": [2.0, 1.5], "floor": 2**40})
    with pytest.raises(ValueError, match="argument 'smoother': expected None or a SmootherOptions"):
        _track(smoother=3)  # was RuntimeError (cast)
    with pytest.raises(ValueError, match="argument 'fixes': expected None or"):
        _track(fixes=[1.0])  # was RuntimeError (cast)
    with pytest.raises(ValueError, match="argument 'plan': must be None or a FloorPlan"):
        _track(plan="a plan")
    result = _track()
    assert np.isfinite(result["mean_m"]).all()
