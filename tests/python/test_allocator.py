"""indoorloc.allocator: the batch commands' allocator settings (no result depends on them)."""

import numpy as np
import pytest

from indoorloc.allocator import retain_freed_memory


def test_retain_freed_memory_applies_on_glibc_and_memory_still_works():
    assert retain_freed_memory() in (True, False)
    a = np.ones(10_000_000)  # 80 MB: below the new mmap threshold, from the heap
    assert a.sum() == 10_000_000
    del a
    b = np.zeros(10_000_000)
    assert not b.any()


@pytest.mark.parametrize("field, value", [("mmap_threshold_bytes", 0), ("trim_threshold_bytes", -1),
                                          ("top_pad_bytes", 1 << 31), ("mmap_threshold_bytes", 1.5),
                                          ("trim_threshold_bytes", True), ("top_pad_bytes", None)])
def test_retain_freed_memory_rejects_bad_values_naming_them(field, value):
    with pytest.raises(ValueError, match=field):
        retain_freed_memory(**{field: value})
