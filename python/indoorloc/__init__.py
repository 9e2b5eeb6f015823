"""indoorloc: indoor localization and inertial estimation.

A C++17 core (``indoorloc._core``) with Python facades, one per subsystem:

- ``indoorloc.core``: seeded random streams, log-space weights, resampling.
- ``mapmatch``, ``analog``, ``pdr``, ``network``, ``wifi``: the five methods of the papers in
  ``docs/`` (added as they are implemented).
- ``fusion``: their combination (so far the floor plan: walkable space and wall crossings).

Only the computational API is re-exported here; plots, file formats and the CLI live in
``indoorloc.plots``, ``indoorloc.io`` and ``indoorloc.cli`` and are imported on demand.
"""

from indoorloc import _core
from indoorloc import analog
from indoorloc import core
from indoorloc import fusion
from indoorloc import mapmatch
from indoorloc import metrics
from indoorloc import network
from indoorloc import pdr
from indoorloc import wifi

# One source of truth: project(VERSION) in CMakeLists.txt, compiled into _core.
__version__: str = _core.__version__

__all__ = ["__version__", "analog", "core", "fusion", "mapmatch", "metrics", "network", "pdr", "wifi"]


def __getattr__(name: str):  # noqa: ANN202 - module attribute hook
    # indoorloc.pdr_handheld moved to indoorloc.pdr.handheld and indoorloc.wifi_matcher to
    # indoorloc.wifi.matcher (docs/api_changes.md): the old attributes still work for one release,
    # importing the deprecated alias (which warns).
    if name in ("pdr_handheld", "wifi_matcher"):
        import importlib

        return importlib.import_module(f"indoorloc.{name}")
    raise AttributeError(f"module 'indoorloc' has no attribute {name!r}")
