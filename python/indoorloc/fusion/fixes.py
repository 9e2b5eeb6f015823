"""Position fixes for the tracker from any external locator (e.g. fingerprint kNN on a crowdsourced
map, :mod:`indoorloc.fusion.wifi_fixes`): per fix a Gaussian mixture plus an outlier floor
(docs/fusion.md, position_fix.h)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Tuple

import numpy as np

from indoorloc._core.fusion import ANY_FLOOR
from indoorloc.validate import argument_error as _error
from indoorloc.validate import real_array


@dataclass
class Fixes:
    """Position fixes for the tracker: per fix a Gaussian mixture over the floor plus an outlier
    floor (``TrackerOptions.fix_outlier_probability``):
    p(fix | z) = ε / A + (1 - ε) Σ_k w_k N(z; μ_k, σ_k² I) (docs/fusion.md, position_fix.h).

    times_s (F,) [s] non-decreasing; means_m (F, K, 2) [m]; sds_m (F, K) [m] > 0; weights (F, K)
    >= 0 (normalised per fix; weight 0 marks padding, whose mean and sd are ignored); floors
    (F, K) floor number of each component, or ``ANY_FLOOR`` where it holds on every floor
    (components on several floors let the fixes identify the floor)."""

    times_s: np.ndarray
    means_m: np.ndarray
    sds_m: np.ndarray
    weights: np.ndarray
    floors: np.ndarray

    @classmethod
    def from_arrays(cls, times_s, means_m, sds_m, weights=None, floors=None) -> "Fixes":
        """Checks shapes and copies. means_m (F, K, 2) or (F, 2) (one component each); sds_m
        (F, K), (F,) or a scalar; weights default equal; floors (F, K), (F,) (one floor per fix)
        or a scalar, default ``ANY_FLOOR``."""
        # Means and sds of padding components (weight 0) may be NaN: only complex, strings and
        # objects are refused here; the C++ side checks the used components by name.
        t = real_array(times_s, "times_s").reshape(-1)
        f = t.shape[0]
        m = real_array(means_m, "means_m", finite=False)
        if m.ndim == 2 and m.shape == (f, 2):
            m = m[:, None, :]
        if m.ndim != 3 or m.shape[0] != f or m.shape[2] != 2:
            raise _error("means_m", f"expected shape ({f}, K, 2) or ({f}, 2), got {m.shape}")
        k = m.shape[1]
        sd = real_array(sds_m, "sds_m", finite=False)
        if sd.ndim == 1 and sd.shape == (f,):
            sd = sd[:, None]
        try:
            sd = np.array(np.broadcast_to(sd, (f, k)))
        except ValueError:
            raise _error("sds_m", f"expected shape ({f}, {k}), ({f},) or a scalar, got {sd.shape}") from None
        w = np.ones((f, k)) if weights is None else real_array(weights, "weights")
        if w.shape != (f, k):
            raise _error("weights", f"expected shape ({f}, {k}), got {w.shape}")
        fl = real_array(ANY_FLOOR if floors is None else floors, "floors")
        if np.any(fl != np.round(fl)) or np.any(np.abs(fl) > 2**31):
            raise _error("floors", "must be whole numbers that fit in 32 bits (floor numbers or ANY_FLOOR)")
        if fl.ndim == 1 and fl.shape == (f,):
            fl = fl[:, None]
        try:
            fl = np.array(np.broadcast_to(fl, (f, k)), dtype=np.int64)
        except ValueError:
            raise _error("floors", f"expected shape ({f}, {k}), ({f},) or a scalar, got {fl.shape}") from None
        if f > 1 and np.any(np.diff(t) < 0):
            raise _error("times_s", "must be non-decreasing")
        # NaN is allowed only in padding (weight 0): a used component must be a number.
        used = w > 0
        if not np.all(np.isfinite(m[used])):
            raise _error("means_m", "must be finite where the weight is > 0 (NaN only in padding)")
        if not np.all(np.isfinite(sd[used])):
            raise _error("sds_m", "must be finite where the weight is > 0 (NaN only in padding)")
        return cls(t, m, sd, w, fl)

    def __len__(self) -> int:
        return int(self.times_s.shape[0])

    def as_arrays(self) -> Tuple[np.ndarray, ...]:
        """The tuple the C++ ``track`` takes: means flattened to (F, 2K), padding (weight 0)
        given placeholder means and sds (the C++ side drops it)."""
        f, k = self.sds_m.shape
        pad = self.weights == 0
        means = np.where(pad[:, :, None], 0.0, self.means_m).reshape(f, 2 * k)
        sds = np.where(pad, 1.0, self.sds_m)
        return (self.times_s, means, sds, self.weights, self.floors)


__all__ = ["Fixes"]
