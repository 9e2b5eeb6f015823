"""File formats at the edge of indoorloc: dataset loaders (WiFi, foot IMU, Indoor Location
Competition 2.0 walks), road-network files and floor plans (GeoJSON).

io imports nothing from indoorloc but the compiled ``indoorloc._core`` (plain arrays and
dataclasses in, ``_core`` types out), so that facades may use it inside functions (e.g.
``indoorloc.mapmatch.warehouse_network``) without an import cycle; docs/architecture.md, "Layers".
"""

from indoorloc.io.errors import FormatError, RecordingWarning
from indoorloc.io.wifi_datasets import (
    RSS_RTT_GRID_M,
    RSS_RTT_ROOMS,
    SURIMI_NAMES,
    FingerprintDataset,
    FingerprintSplit,
    available_datasets,
    load_rss_rtt_room,
    load_surimi,
    load_uji_library,
    load_wifi_dataset,
)
from indoorloc.io.pdr_datasets import (
    STANDARD_GRAVITY_MPS2,
    ImuRecording,
    IrregularTimestampsWarning,
    MobgapTrial,
    check_imu_units,
    fit_sample_rate,
    list_mobgap_files,
    list_pyshoe_trials,
    load_mobgap_trials,
    load_openshoe,
    load_pyshoe_trial,
    load_xio,
)
from indoorloc.io.ilc2020 import (
    ILC_SENSOR_TYPES,
    BssidVocabulary,
    IlcBeacons,
    IlcFloor,
    IlcSensor,
    IlcWalk,
    IlcWifi,
    UnknownWalkError,
    describe_ilc_floor,
    ilc_floor_level,
    ilc_floor_names,
    ilc_floor_origin_lonlat,
    read_ilc_floor,
    read_ilc_site,
    read_ilc_walk,
)
from indoorloc.io.floor_plan import (
    GeoJsonFloor,
    floor_geometry_to_geojson,
    load_floor_plan,
    local_to_lonlat,
    lonlat_to_local,
    metres_per_degree,
    read_geojson_floor,
    write_geojson_floor,
)
from indoorloc.io.road_network import (
    grid_with_diagonals_segments,
    load_road_network,
    read_csv_segments,
    read_geojson_segments,
    warehouse_segments,
    write_geojson_segments,
)

from indoorloc.io.ilc2020 import __all__ as _ilc2020_all  # noqa: E402: the loader's names, listed once

__all__ = [
    "FormatError",
    "RecordingWarning",
    *_ilc2020_all,
    "GeoJsonFloor",
    "floor_geometry_to_geojson",
    "load_floor_plan",
    "local_to_lonlat",
    "lonlat_to_local",
    "metres_per_degree",
    "read_geojson_floor",
    "write_geojson_floor",
    "STANDARD_GRAVITY_MPS2",
    "ImuRecording",
    "IrregularTimestampsWarning",
    "MobgapTrial",
    "check_imu_units",
    "fit_sample_rate",
    "list_mobgap_files",
    "list_pyshoe_trials",
    "load_mobgap_trials",
    "load_openshoe",
    "load_pyshoe_trial",
    "load_xio",
    "RSS_RTT_GRID_M",
    "RSS_RTT_ROOMS",
    "SURIMI_NAMES",
    "FingerprintDataset",
    "FingerprintSplit",
    "available_datasets",
    "grid_with_diagonals_segments",
    "load_rss_rtt_room",
    "load_surimi",
    "load_road_network",
    "load_uji_library",
    "load_wifi_dataset",
    "read_csv_segments",
    "read_geojson_segments",
    "warehouse_segments",
    "write_geojson_segments",
]
