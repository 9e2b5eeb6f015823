"""File formats at the edge of indoorloc: dataset loaders."""

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

__all__ = [
    "RSS_RTT_GRID_M",
    "RSS_RTT_ROOMS",
    "SURIMI_NAMES",
    "FingerprintDataset",
    "FingerprintSplit",
    "available_datasets",
    "load_rss_rtt_room",
    "load_surimi",
    "load_uji_library",
]
