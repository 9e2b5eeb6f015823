"""Property-based probe of the pdr entry points (issue 17): see property_harness.py."""

from property_runner import run_group


def test_pdr_entry_points_reject_bad_input_clearly():
    run_group("pdr")
