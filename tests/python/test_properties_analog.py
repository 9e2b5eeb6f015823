"""Property-based probe of the analog entry points (issue 17): see property_harness.py."""

from property_runner import run_group


def test_analog_entry_points_reject_bad_input_clearly():
    run_group("analog")
