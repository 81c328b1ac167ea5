"""Freed memory kept by the C allocator for the next array, instead of returned to the OS.

A run allocates and frees arrays of the same sizes again and again (right-hand-side
blocks, recovered displacements, the factorization's work arrays), and so do the runs
of a study in one worker. glibc's ``malloc`` returns every freed block above its mmap
threshold (128 KiB at first) to the kernel at once and trims the top of its heap
beyond 128 KiB of free memory, so each new array page-faults again; NumPy also asks
for transparent huge pages on large arrays, and the first write into a fresh huge page
can stall for milliseconds (on the development machine, a KVM guest, with no
compaction counted by the kernel: :func:`small_zeros`). On the 2-core
machine, a run at 66,048 unknowns that follows a factorization made 33,842 page faults
and spent 0.064 s in the kernel with glibc's default, against 16,711 and 0.027 s with
freed memory kept, nearly all of them the first writes into its new result
(``benchmarks/bench_threads.py --n 128``).

:func:`keep_freed_memory` raises both thresholds (``mallopt``): blocks up to 32 MiB
come from the heap and go back to it, and up to 128 MiB of free heap is kept. Blocks
above 32 MiB (the big arrays of big runs) are still mapped and unmapped, so the peak
memory of a big run does not grow. The setting is process-wide: the command line and
the study workers make it at start, :func:`vemwear.simulate.simulate` at its first
call.

:func:`small_zeros` makes the large arrays of a result in fresh mappings of 4 KB
pages: they are written once, and their first writes into fresh huge pages stalled at
random on the development machine (a KVM guest).
"""

from __future__ import annotations

import ctypes
import mmap
import platform
import sys
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["SMALL_PAGES_FROM", "keep_freed_memory", "small_zeros"]

_M_TRIM_THRESHOLD = -1  # glibc's mallopt parameters (malloc.h)
_M_MMAP_THRESHOLD = -3

#: blocks up to this size are reused from the heap (glibc's own upper bound of its
#: dynamic threshold on 64-bit systems)
MMAP_THRESHOLD = 32 * 2**20
#: free memory at the top of the heap kept for the next arrays
TRIM_THRESHOLD = 128 * 2**20
#: arrays of :func:`small_zeros` from this size on get a mapping of their own (NumPy
#: asks for huge pages from the same size)
SMALL_PAGES_FROM = 4 * 2**20


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


def small_zeros(shape: Any, dtype: Any = np.float64) -> NDArray[Any]:
    """A zero array in 4 KB pages: from :data:`SMALL_PAGES_FROM` bytes on (on Linux), in
    a fresh private mapping of its own marked ``MADV_NOHUGEPAGE``, released with the
    array.

    NumPy asks the kernel for 2 MB pages on every array of 4 MB or more
    (``madvise(MADV_HUGEPAGE)``). A result array that a run writes once and hands back
    gains nothing from them, and on a virtual machine the first write into a fresh
    huge page can stall: at 66,048 unknowns, writing u into a new 68 MB result took
    0.09 s (0.07 s in the kernel) in 14 or 15 of 33 runs, against 0.02 s in the others
    (``benchmarks/bench_threads.py --n 128``). With 4 KB pages it takes 0.04 s in
    every run. Turning NumPy's request off is not enough: with freed memory kept
    (:func:`keep_freed_memory`) an array can come from heap memory that NumPy advised
    for huge pages before, for another array.
    """
    dt = np.dtype(dtype)
    nbytes = int(np.prod(shape, dtype=np.int64)) * dt.itemsize
    if nbytes < SMALL_PAGES_FROM or sys.platform != "linux":
        return np.zeros(shape, dtype=dt)
    mm = mmap.mmap(-1, nbytes, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS)
    mm.madvise(mmap.MADV_NOHUGEPAGE)  # also where the kernel gives huge pages always
    return np.frombuffer(mm, dtype=dt).reshape(shape)  # zero, writable, keeps mm alive
