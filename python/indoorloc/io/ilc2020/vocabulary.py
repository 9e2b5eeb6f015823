"""The WiFi vocabulary of a floor: every BSSID heard on its walks, in a stable column order
(BssidVocabulary).

Part of :mod:`indoorloc.io.ilc2020` (the format is described there)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Dict, Iterable, List, Sequence

import numpy as np

from indoorloc.io.ilc2020.walk_types import IlcWalk


@dataclass
class BssidVocabulary:
    """BSSIDs heard over a set of walks (e.g. a floor, or the training walks of a fold).

    Attributes
    ----------
    bssids : list of str, length V
        Sorted BSSIDs.
    ssids : list of str, length V
        First non-empty SSID seen with each BSSID, else ``""``.
    n_readings : numpy.ndarray, shape (V,), int64
        Readings of each BSSID.
    n_scans : numpy.ndarray, shape (V,), int64
        Scans in which each BSSID appears (at least once).
    n_walks : numpy.ndarray, shape (V,), int64
        Walks in which each BSSID appears.
    total_scans : int
        Scans over all the walks.
    total_walks : int
        Number of walks.
    """

    bssids: List[str]
    ssids: List[str]
    n_readings: np.ndarray
    n_scans: np.ndarray
    n_walks: np.ndarray
    total_scans: int
    total_walks: int

    def __post_init__(self) -> None:
        self._index = {b: k for k, b in enumerate(self.bssids)}

    @classmethod
    def from_walks(cls, walks: Iterable[IlcWalk]) -> "BssidVocabulary":
        """The union of the walks' BSSIDs with reading, scan and walk counts."""
        per_walk = []
        ssid_of: Dict[str, str] = {}
        total_scans = 0
        for w in walks:
            wf = w.wifi
            readings = np.bincount(wf.bssid_index, minlength=len(wf.bssids))
            pairs = np.unique(wf.scan_index * max(1, len(wf.bssids)) + wf.bssid_index)
            scans = np.bincount(pairs % max(1, len(wf.bssids)), minlength=len(wf.bssids))
            per_walk.append((wf.bssids, readings, scans))
            for b, s in zip(wf.bssids, wf.ssids):
                if s and not ssid_of.get(b):
                    ssid_of[b] = s
                ssid_of.setdefault(b, "")
            total_scans += wf.n_scans
        bssids = sorted(ssid_of)
        index = {b: k for k, b in enumerate(bssids)}
        n = len(bssids)
        n_readings = np.zeros(n, dtype=np.int64)
        n_scans = np.zeros(n, dtype=np.int64)
        n_walks = np.zeros(n, dtype=np.int64)
        for names, readings, scans in per_walk:
            lut = np.array([index[b] for b in names], dtype=np.int64)
            np.add.at(n_readings, lut, readings)
            np.add.at(n_scans, lut, scans)
            np.add.at(n_walks, lut, 1)
        return cls(bssids=bssids, ssids=[ssid_of[b] for b in bssids], n_readings=n_readings,
                   n_scans=n_scans, n_walks=n_walks, total_scans=total_scans,
                   total_walks=len(per_walk))

    @property
    def size(self) -> int:
        """Number of BSSIDs V."""
        return len(self.bssids)

    @property
    def scan_fraction(self) -> np.ndarray:
        """(V,) fraction of all scans in which each BSSID appears."""
        return self.n_scans / max(1, self.total_scans)

    def indices(self, bssids: Sequence[str]) -> np.ndarray:
        """(len(bssids),) int64 index of each BSSID in this vocabulary, -1 when absent."""
        return np.array([self._index.get(b, -1) for b in bssids], dtype=np.int64)

    def map_walk(self, walk: IlcWalk) -> np.ndarray:
        """(R,) int64: the index of each of the walk's WiFi readings' BSSID in this vocabulary,
        -1 for a BSSID it does not hold (e.g. a test walk against a training vocabulary)."""
        lut = self.indices(walk.wifi.bssids)
        return lut[walk.wifi.bssid_index] if lut.size else np.zeros(0, dtype=np.int64)

    def frequent(self, min_scan_fraction: float) -> np.ndarray:
        """Indices of the BSSIDs heard in at least ``min_scan_fraction`` of the scans."""
        return np.flatnonzero(self.scan_fraction >= min_scan_fraction)


# --------------------------------------------------------------------------------------------
# Floors and sites
