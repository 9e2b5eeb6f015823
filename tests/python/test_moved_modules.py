"""Modules that moved (docs/api_changes.md): each old path still works for one release, warns when
first imported, and is the new module itself (attributes, private helpers and monkeypatching behave
as before)."""

from __future__ import annotations

import subprocess
import sys

import pytest

MOVED_MODULES = {
    "indoorloc.pdr_handheld": "indoorloc.pdr.handheld",
    "indoorloc.wifi_crowdsource": "indoorloc.fusion.crowdsourced_map",
    "indoorloc.wifi_fixes": "indoorloc.fusion.wifi_fixes",
    "indoorloc.wifi_matcher": "indoorloc.wifi.matcher",
}


@pytest.mark.parametrize("old", sorted(MOVED_MODULES))
def test_old_module_warns_and_is_the_new_module(old):
    # a fresh interpreter: the alias warns once, when first imported
    new = MOVED_MODULES[old]
    code = (f"import warnings, sys; warnings.simplefilter('error', DeprecationWarning)\n"
            f"try:\n    import {old}\nexcept DeprecationWarning as e:\n    print('warned', e)\n"
            f"warnings.simplefilter('ignore')\nimport importlib, indoorloc\n"
            f"new = importlib.import_module('{new}')\n"
            f"print(importlib.import_module('{old}') is new, indoorloc.{old.split('.')[1]} is new)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert "warned" in out and new in out
    assert out.strip().endswith("True True")
