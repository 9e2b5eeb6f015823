"""Property-based probe of metrics and the io helpers (issue 17): see property_harness.py."""

from property_runner import run_group


def test_metrics_and_io_helpers_reject_bad_input_clearly():
    run_group("metrics")
