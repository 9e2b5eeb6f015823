"""File formats at the edge of indoorloc: dataset loaders (WiFi, foot IMU) and road-network files."""

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
)
from indoorloc.io.pdr_datasets import (
    STANDARD_GRAVITY_MPS2,
    ImuRecording,
    check_imu_units,
    list_pyshoe_trials,
    load_openshoe,
    load_pyshoe_trial,
    load_xio,
)
from indoorloc.io.road_network import (
    grid_with_diagonals_segments,
    load_road_network,
    read_csv_segments,
    read_geojson_segments,
    warehouse_segments,
    write_geojson_segments,
)

__all__ = [
    "STANDARD_GRAVITY_MPS2",
    "ImuRecording",
    "check_imu_units",
    "list_pyshoe_trials",
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
    "read_csv_segments",
    "read_geojson_segments",
    "warehouse_segments",
    "write_geojson_segments",
]
