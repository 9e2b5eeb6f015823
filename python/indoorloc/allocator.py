"""Process-wide memory allocator settings for long batch runs (``indoorloc fusion evaluate``).

A batch evaluation allocates and frees the same large buffers walk after walk (numpy arrays of
a fold's databases, the trackers' results, scratch grids). With glibc's defaults, blocks above a
moving threshold are handed back to the kernel when freed and the next walk's allocation faults
every page in again, zero-filled: several per cent of an evaluation's CPU time in the kernel.
:func:`retain_freed_memory` makes glibc keep freed memory for reuse instead. It changes no
result, only where the bytes come from; the process keeps up to its peak use (plus
``trim_threshold_bytes`` of free memory) until it exits, so it is for a command that runs to
completion, not for a library call inside someone else's process.
"""

from __future__ import annotations

import ctypes
import ctypes.util

_M_TRIM_THRESHOLD = -1
_M_TOP_PAD = -2
_M_MMAP_THRESHOLD = -3


def retain_freed_memory(mmap_threshold_bytes: int = 256 << 20, trim_threshold_bytes: int = 1 << 30,
                        top_pad_bytes: int = 64 << 20) -> bool:
    """glibc's ``mallopt``: blocks below ``mmap_threshold_bytes`` [B] come from the heap (not
    fresh mappings), free memory at the heap's top is returned to the kernel only beyond
    ``trim_threshold_bytes`` [B], and the heap grows by ``top_pad_bytes`` [B] extra at a time.
    Returns True when applied, False where the C library has no ``mallopt`` (not glibc: nothing
    changes). Each value must be in (0, 2**31) (ValueError naming the argument)."""
    for name, value in (("mmap_threshold_bytes", mmap_threshold_bytes), ("trim_threshold_bytes", trim_threshold_bytes),
                        ("top_pad_bytes", top_pad_bytes)):
        if not isinstance(value, int) or isinstance(value, bool) or not 0 < value < 1 << 31:
            raise ValueError(f"indoorloc: argument '{name}': expected an integer in (0, 2**31) bytes (mallopt "
                             f"takes an int), got {value!r}")
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
    mallopt.restype = ctypes.c_int
    ok = mallopt(_M_MMAP_THRESHOLD, mmap_threshold_bytes) == 1
    ok &= mallopt(_M_TRIM_THRESHOLD, trim_threshold_bytes) == 1
    ok &= mallopt(_M_TOP_PAD, top_pad_bytes) == 1
    return bool(ok)


__all__ = ["retain_freed_memory"]
