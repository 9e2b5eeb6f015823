"""Python counterpart of the validation vocabulary (``indoorloc/core/validate.h``).

For the pure-Python entry points (metrics, io helpers): the same wording as the C++ checks,
``indoorloc: argument '<name>': <rule>, got <value>``, raised as ValueError (TypeError for an
object that is not a number at all).
"""

from __future__ import annotations

import math
import numbers
from typing import Any, Optional, Sequence

import numpy as np

# The defaults of core/validate.h.
MIN_SCALE = 1e-12
MAX_SCALE = 1e12


def argument_error(name: str, rule: str) -> ValueError:
    """The ValueError of a bad argument: ``indoorloc: argument '<name>': <rule>``."""
    return ValueError(f"indoorloc: argument '{name}': {rule}")


_error = argument_error


def real_array(value: Any, name: str, *, ndim: Optional[int] = None,
               shape: Optional[Sequence[Optional[int]]] = None, min_size: int = 0,
               max_abs: Optional[float] = None, finite: bool = True) -> np.ndarray:
    """A finite float64 array (copied when needed; the caller's array is never modified).

    Refuses None, strings, objects, complex numbers (their imaginary part would be dropped),
    NaN and inf (unless ``finite=False``, for arrays where NaN means "missing"), a wrong number
    of dimensions or shape (``None`` in `shape`: any), fewer than `min_size` entries and, with
    `max_abs`, entries beyond +-max_abs.
    """
    if value is None:
        raise _error(name, "is None, expected an array of numbers")
    try:
        raw = np.asarray(value)
    except ValueError as exc:  # ragged nested lists
        raise _error(name, f"cannot be converted to an array ({exc})") from None
    if raw.dtype.kind == "c":
        raise _error(name, f"is complex (dtype {raw.dtype}): cannot be converted to a float64 array "
                           "without dropping the imaginary part")
    if raw.dtype.kind not in "biuf":
        raise _error(name, f"cannot be converted to a float64 array (dtype {raw.dtype})")
    a = raw.astype(np.float64, copy=False)
    if ndim is not None and a.ndim != ndim:
        raise _error(name, f"expected a {ndim}-D array, got {a.ndim}-D")
    if shape is not None:
        if a.ndim != len(shape) or any(s is not None and s != d for s, d in zip(shape, a.shape)):
            want = "(" + ", ".join("any" if s is None else str(s) for s in shape) + ")"
            raise _error(name, f"expected shape {want}, got {a.shape}")
    if a.size < min_size:
        raise _error(name, f"needs at least {min_size} entries, got {a.size}")
    bad = ~np.isfinite(a) if finite else np.zeros(a.shape, bool)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise _error(name, f"entry {k} is {'NaN' if math.isnan(a.flat[k]) else 'infinite'}")
    if max_abs is not None and a.size:
        with np.errstate(invalid="ignore"):
            big = np.abs(a) > max_abs
        if big.any():
            k = int(np.flatnonzero(big)[0])
            raise _error(name, f"entry {k} must be in [{-max_abs:g}, {max_abs:g}], got {a.flat[k]:g}")
    return a


def real_scalar(value: Any, name: str, *, lo: float = -math.inf, hi: float = math.inf,
                finite: bool = True) -> float:
    """A real number (not bool, not complex) in [lo, hi]; finite unless finite=False."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise _error(name, f"expected a real number, got {type(value).__name__} {value!r}")
    v = float(value)
    if finite and not math.isfinite(v):
        raise _error(name, f"must be finite, got {v!r}")
    if not (lo <= v <= hi):
        raise _error(name, f"must be in [{lo:g}, {hi:g}], got {v!r}")
    return v


def integer(value: Any, name: str, *, lo: int, hi: int) -> int:
    """An integer (not bool) in [lo, hi]."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise _error(name, f"expected an integer, got {type(value).__name__} {value!r}")
    v = int(value)
    if not (lo <= v <= hi):
        raise _error(name, f"must be in [{lo}, {hi}], got {v}")
    return v


__all__ = ["MAX_SCALE", "MIN_SCALE", "integer", "real_array", "real_scalar"]
