"""The MMSE and ML fixes sum only the heard APs' entries (point_likelihood_table.h) and interpolate
only the APs off their background (RssModel.evaluate); their fixes must be those of the dense
pass over every AP that they replaced, to rounding. The reference fixes in
data/wifi_dense_pass_fixes.npz were recorded by `python wifi_fix_cases.py <file>` with the dense
build (main fd94ab6) on a map whose APs are heard over parts of the building and on a dense
random map, for the paper's and a capped model, one and three scans per fix."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import wifi_fix_cases as cases
from indoorloc import wifi

REFERENCE = Path(__file__).parent / "data" / "wifi_dense_pass_fixes.npz"


@pytest.mark.parametrize("case", list(cases.CASES))
@pytest.mark.parametrize("model_name", list(cases.MODELS))
@pytest.mark.parametrize("method", ["mmse", "ml"])
@pytest.mark.parametrize("group", [1, 3])
def test_fast_fixes_equal_the_dense_pass(case, model_name, method, group):
    reference = np.load(REFERENCE)
    got = cases.fixes(wifi, case, model_name, method, group)
    key = f"{case}/{model_name}/{method}/{group}"
    np.testing.assert_array_equal(got["floors"], reference[f"{key}/floors"])
    # Sums in another order: equal to rounding (ML refines by up to 25 Fisher steps from the
    # best reference points, which carries the rounding into the last digits only).
    np.testing.assert_allclose(got["positions_m"], reference[f"{key}/positions_m"], rtol=0, atol=1e-7)
    np.testing.assert_allclose(got["neg_log_likelihood"], reference[f"{key}/neg_log_likelihood"], rtol=1e-10)
    np.testing.assert_allclose(got["covariances_m2"], reference[f"{key}/covariances_m2"], rtol=1e-6, atol=1e-9)

