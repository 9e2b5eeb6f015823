"""File formats at the edge of indoorloc: dataset loaders (WiFi, foot IMU, Indoor Location
Competition 2.0 walks), road-network files and floor plans (GeoJSON).

io imports nothing from indoorloc but the compiled ``indoorloc._core`` (plain arrays and
dataclasses in, ``_core`` types out), so that facades may use it inside functions (e.g.
``indoorloc.mapmatch.warehouse_network``) without an import cycle; docs/architecture.md, "Layers".
"""

# Each format module lists its public names once, in its __all__; they are all importable from
# here (indoorloc.io.X) as well.
from indoorloc.io import floor_plan, ilc2020, pdr_datasets, road_network, wifi_datasets
from indoorloc.io.errors import FormatError, RecordingWarning
from indoorloc.io.floor_plan import *  # noqa: F401,F403
from indoorloc.io.ilc2020 import *  # noqa: F401,F403
from indoorloc.io.pdr_datasets import *  # noqa: F401,F403
from indoorloc.io.road_network import *  # noqa: F401,F403
from indoorloc.io.wifi_datasets import *  # noqa: F401,F403

__all__ = ["FormatError", "RecordingWarning", *wifi_datasets.__all__, *pdr_datasets.__all__, *ilc2020.__all__,
           *floor_plan.__all__, *road_network.__all__]
