"""Freed memory kept by the C allocator for the next array, instead of returned to the OS.

A run allocates and frees arrays of the same sizes again and again (right-hand-side
blocks, recovered displacements, the factorization's work arrays), and so do the runs
of a study in one worker. glibc's ``malloc`` returns every freed block above its mmap
threshold (128 KiB at first) to the kernel at once and trims the top of its heap
beyond 128 KiB of free memory, so each new array page-faults again; NumPy also asks
for transparent huge pages on large arrays, and the first write into a fresh huge page
can stall for milliseconds (on the development machine, a KVM guest, with no
compaction counted by the kernel: :func:`small_pages`). On the 2-core
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

:func:`small_pages` makes the arrays of a result without NumPy's request for huge
pages: they are written once, and their first writes into fresh huge pages stalled at
random on the development machine (a KVM guest).
"""

from __future__ import annotations

import contextlib
import ctypes
import platform
from collections.abc import Iterator
from functools import cache

__all__ = ["keep_freed_memory", "small_pages"]

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


@contextlib.contextmanager
def small_pages() -> Iterator[None]:
    """Allocate the enclosed NumPy arrays without asking for transparent huge pages.

    NumPy asks the kernel for 2 MB pages on every array of 4 MB or more
    (``madvise(MADV_HUGEPAGE)``). A result array that a run writes once and hands back
    gains nothing from them, and on a virtual machine the first write into a fresh
    huge page can stall: at 66,048 unknowns, writing u into a new 68 MB result took
    0.09 s (0.07 s in the kernel) in 14 or 15 of 33 runs, against 0.02 s in the others
    (``benchmarks/bench_threads.py --n 128``). With 4 KB pages it takes 0.04 s in
    every run. The switch is NumPy's own (``NUMPY_MADVISE_HUGEPAGE`` sets it at
    start); where this NumPy has none, nothing changes.
    """
    import numpy as np

    # numpy._core.multiarray since NumPy 2, numpy.core.multiarray before
    core = getattr(np, "_core", None) or getattr(np, "core", None)
    switch = getattr(getattr(core, "multiarray", None), "_set_madvise_hugepage", None)
    if switch is None:  # pragma: no cover - every NumPy since 1.20 has it
        yield
        return
    before = switch(False)
    try:
        yield
    finally:
        switch(before)
