"""Modules moved into the indoorloc.fusion package (docs/api_changes.md): the new paths hold them,
the old paths still work for one release and warn (test_moved_modules.py); ``indoorloc.fusion`` offers ``Site`` without
loading file formats on ``import indoorloc``."""

from __future__ import annotations

import subprocess
import sys

import pytest

from indoorloc import fusion
from indoorloc.fusion import crowdsourced_map, fixes, steps, wifi_fixes

def _run(code: str) -> str:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout


def test_site_is_importable_from_the_facade():
    from indoorloc.fusion.site import Site

    assert fusion.Site is Site
    assert "Site" in fusion.__all__
    with pytest.raises(AttributeError, match="no attribute 'NoSuchName'"):
        fusion.NoSuchName  # noqa: B018 - the attribute hook refuses unknown names


def test_import_indoorloc_does_not_load_the_site():
    # Site reads files through indoorloc.io: it loads on first use only.
    out = _run("import warnings; warnings.simplefilter('error'); import sys, indoorloc\n"
               "print(sorted(m for m in sys.modules if m.startswith(('indoorloc.fusion.site', 'indoorloc.io'))))\n"
               "from indoorloc.fusion import Site\nprint('indoorloc.fusion.site' in sys.modules)")
    assert out.split("\n")[:2] == ["[]", "True"]


def test_the_facade_re_exports_the_tracker_inputs():
    assert fusion.Steps is steps.Steps and fusion.rotate is steps.rotate
    assert fusion.Fixes is fixes.Fixes
    assert wifi_fixes.Fixes is fixes.Fixes
    assert wifi_fixes.crowdsourced_map is crowdsourced_map
