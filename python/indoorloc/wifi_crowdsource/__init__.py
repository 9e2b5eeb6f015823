"""Deprecated alias of :mod:`indoorloc.fusion.crowdsourced_map` (moved after 0.1.0; see
docs/api_changes.md).

Importing it warns once (DeprecationWarning) and binds the name to the new module itself, so every
attribute, private helper and monkeypatch behaves as before. It will be removed in the next release.
(A package rather than ``wifi_crowdsource.py``, so that git follows the moved file as a rename.)
"""

import sys
import warnings

from indoorloc.fusion import crowdsourced_map as _crowdsourced_map

warnings.warn("indoorloc.wifi_crowdsource is deprecated and will be removed in the next release: "
              "import indoorloc.fusion.crowdsourced_map instead (docs/api_changes.md)", DeprecationWarning,
              stacklevel=2)
sys.modules[__name__] = _crowdsourced_map
