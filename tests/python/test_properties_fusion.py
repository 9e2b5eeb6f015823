"""Property-based probe of the fusion entry points (issue 17): see property_harness.py."""

from property_runner import run_group


def test_fusion_entry_points_reject_bad_input_clearly():
    run_group("fusion")
