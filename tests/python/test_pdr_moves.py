"""Names moved into the indoorloc.pdr package (docs/api_changes.md): the new paths hold them, the
old paths still work for one release and warn."""

from __future__ import annotations

import importlib
import subprocess
import sys

import pytest

from indoorloc import pdr
from indoorloc.pdr import handheld, metrics, recommended

MOVED_FROM_PDR_EVALUATE = {"align_2d": metrics, "armse": metrics, "path_length": metrics,
                           "run_recommended": recommended, "detect_stance": recommended,
                           "ZUPT_DETECTOR": recommended, "DEFAULT_METHOD": recommended,
                           "SHOE_WINDOW": recommended, "SHOE_SIGMA_ACC_MPS2": recommended,
                           "SHOE_SIGMA_GYRO_RADPS": recommended}


@pytest.mark.parametrize("name", sorted(MOVED_FROM_PDR_EVALUATE))
def test_old_pdr_evaluate_names_warn_and_are_the_new_objects(name):
    pe = importlib.import_module("indoorloc.experiments.pdr_evaluate")
    with pytest.warns(DeprecationWarning, match=f"indoorloc.pdr.*{name}"):
        old = getattr(pe, name)
    assert old is getattr(MOVED_FROM_PDR_EVALUATE[name], name)


def test_the_facade_re_exports_the_pipeline_and_metrics():
    assert pdr.run_recommended is recommended.run_recommended
    assert pdr.align_2d is metrics.align_2d and pdr.armse is metrics.armse
    assert pdr.handheld is handheld


def test_import_indoorloc_does_not_warn():
    code = "import warnings; warnings.simplefilter('error'); import indoorloc, indoorloc.pdr; print('ok')"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True).stdout.strip() == "ok"
