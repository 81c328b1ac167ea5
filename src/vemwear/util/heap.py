"""Freed memory kept by the C allocator for the next array, instead of returned to the OS.

A run allocates and frees arrays of the same sizes again and again (right-hand-side
blocks, recovered displacements, the factorization's work arrays), and so do the runs
of a study in one worker. glibc's ``malloc`` returns every freed block above its mmap
threshold (128 KiB at first) to the kernel at once and trims the top of its heap
beyond 128 KiB of free memory, so each new array page-faults again; NumPy also asks
for transparent huge pages on large arrays, and where the kernel compacts memory to
find them (``defrag = madvise``) a fault can stall for milliseconds. On the 2-core
machine, a run at 66,048 unknowns that follows a factorization made 17,490 page faults
and spent 0.063 s in the kernel with glibc's default, against 359 and 0.008 s with
freed memory kept (``benchmarks/bench_threads.py --n 128``).

:func:`keep_freed_memory` raises both thresholds (``mallopt``): blocks up to 32 MiB
come from the heap and go back to it, and up to 128 MiB of free heap is kept. Blocks
above 32 MiB (the big arrays of big runs) are still mapped and unmapped, so the peak
memory of a big run does not grow. The setting is process-wide: the command line and
the study workers make it at start, :func:`vemwear.simulate.simulate` at its first
call.
"""

from __future__ import annotations

import ctypes
import platform
from functools import cache

__all__ = ["keep_freed_memory"]

_M_TRIM_THRESHOLD = -1  # glibc's mallopt parameters (malloc.h)
_M_MMAP_THRESHOLD = -3

#: blocks up to this size are reused from the heap (glibc's own upper bound of its
#: dynamic threshold on 64-bit systems)
MMAP_THRESHOLD = 32 * 2**20
#: free memory at the top of the heap kept for the next arrays
TRIM_THRESHOLD = 128 * 2**20


@cache
def keep_freed_memory() -> bool:
    """Make this process's allocator keep freed memory for reuse (glibc only).

    Returns
    -------
    bool
        True if the setting was made (Linux with glibc), False elsewhere.
    """
    if platform.system() != "Linux" or platform.libc_ver()[0] != "glibc":
        return False
    try:
        libc = ctypes.CDLL(None)
        mallopt = libc.mallopt
    except (OSError, AttributeError):  # pragma: no cover - glibc always has mallopt
        return False
    mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
    mallopt.restype = ctypes.c_int
    ok = mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD) == 1
    return mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD) == 1 and ok
