"""Loaders for public WiFi RSS fingerprint datasets (numpy only).

A package, one module per concept: ``dataset`` (the layout and shared parsing), ``uji_library``,
``rss_rtt_rooms``, ``surimi`` (one format each), ``discovery`` (datasets by name); every name
is importable as ``indoorloc.io.wifi_datasets.X``.

Three on-disk formats are read into one in-memory layout, :class:`FingerprintDataset`:

- the UJI long-term library dataset (``db/MM/trnNN{rss,crd,tms,ids}.csv`` and ``tstNN*``),
  :func:`load_uji_library`;
- the RSS/RTT rooms of Feng, Nguyen and Luo (``database_<room>_{train,test}.csv`` and
  ``AP_position.txt``), :func:`load_rss_rtt_room`;
- the SURIMI collection in the common ``.mat`` format of Torres-Sospedra et al.
  (``<NAME>.mat`` holding ``database``), :func:`load_surimi`.

RSS values are returned exactly as stored, "not heard" sentinel included: how a missing reading
is modelled is the estimator's decision, so :attr:`FingerprintDataset.not_heard_sentinel` tells
it which value to look for. Every loader raises ``ValueError("indoorloc: argument 'root': ...")``
naming the file when a file is missing or malformed.

Examples
--------
>>> from indoorloc.io import load_rss_rtt_room
>>> ds = load_rss_rtt_room("../shared/data/wifi/rss_rtt_rooms", "office")  # doctest: +SKIP
>>> ds.train.rss_dbm.shape, ds.not_heard_sentinel  # doctest: +SKIP
((4860, 5), -200.0)
"""

from indoorloc.io.wifi_datasets.dataset import FingerprintDataset, FingerprintSplit, PathLike  # noqa: F401
from indoorloc.io.wifi_datasets.discovery import available_datasets, load_wifi_dataset
from indoorloc.io.wifi_datasets.rss_rtt_rooms import RSS_RTT_GRID_M, RSS_RTT_ROOMS, load_rss_rtt_room
from indoorloc.io.wifi_datasets.surimi import SURIMI_NAMES, load_surimi
from indoorloc.io.wifi_datasets.uji_library import load_uji_library

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
    "load_wifi_dataset",
]
