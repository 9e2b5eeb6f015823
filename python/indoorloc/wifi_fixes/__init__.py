"""Deprecated alias of :mod:`indoorloc.fusion.wifi_fixes` (moved after 0.1.0; see docs/api_changes.md).

Importing it warns once (DeprecationWarning) and binds the name to the new module itself, so every
attribute, private helper and monkeypatch behaves as before. It will be removed in the next release.
(A package rather than ``wifi_fixes.py``, so that git follows the moved file as a rename.)
"""

import sys
import warnings

from indoorloc.fusion import wifi_fixes as _wifi_fixes

warnings.warn("indoorloc.wifi_fixes is deprecated and will be removed in the next release: "
              "import indoorloc.fusion.wifi_fixes instead (docs/api_changes.md)", DeprecationWarning, stacklevel=2)
sys.modules[__name__] = _wifi_fixes
