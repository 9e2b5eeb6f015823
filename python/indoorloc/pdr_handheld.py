"""Deprecated alias of :mod:`indoorloc.pdr.handheld` (moved after 0.1.0; see docs/api_changes.md).

Importing it warns once (DeprecationWarning) and binds the name to the new module itself, so every
attribute, private helper and monkeypatch behaves as before. It will be removed in the next release.
"""

import sys
import warnings

from indoorloc.pdr import handheld as _handheld

warnings.warn("indoorloc.pdr_handheld is deprecated and will be removed in the next release: "
              "import indoorloc.pdr.handheld instead (docs/api_changes.md)", DeprecationWarning, stacklevel=2)
sys.modules[__name__] = _handheld
