"""Deprecated alias of :mod:`indoorloc.wifi.matcher` (moved into the wifi package; see docs/api_changes.md).

Importing it warns once (DeprecationWarning) and binds the name to the new module itself, so every
attribute, private helper and monkeypatch behaves as before. It will be removed in the next release.
"""

import sys
import warnings

from indoorloc.wifi import matcher as _matcher

warnings.warn("indoorloc.wifi_matcher is deprecated and will be removed in the next release: "
              "import indoorloc.wifi.matcher instead (docs/api_changes.md)", DeprecationWarning, stacklevel=2)
sys.modules[__name__] = _matcher
