"""The allocator keeps freed memory for the next arrays (glibc), so that repeated
allocations of the same size do not page-fault again."""

from __future__ import annotations

import json
import platform
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.skipif(
    platform.system() != "Linux" or platform.libc_ver()[0] != "glibc",
    reason="mallopt is glibc's",
)

# 20 times 40 arrays of 1 MiB (256 pages each) written, held and freed together, after
# one untimed round: the 40 MiB freed at the top of the heap are trimmed by default
_CHILD = r"""
import ctypes, json, resource, sys
import numpy as np
# pages of 4 KiB, whatever the machine's transparent huge pages: a fault per page
ctypes.CDLL(None).prctl(41, 1, 0, 0, 0)  # PR_SET_THP_DISABLE
from vemwear.util.heap import keep_freed_memory
made = keep_freed_memory() if sys.argv[1] == "kept" else False
if sys.argv[1] == "simulate":  # a small run makes the setting itself
    from vemwear.paper import ex52
    from vemwear.simulate import simulate
    simulate(ex52.problem(0.2, 2.0, divisions=(4, 2), steps=2))
    made = True
def round_():
    arrays = [np.ones(2**17) for _ in range(40)]
    del arrays
round_()
r0 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(20):
    round_()
print(json.dumps({"made": made,
                  "faults": resource.getrusage(resource.RUSAGE_SELF).ru_minflt - r0}))
"""


def _faults(mode: str) -> dict[str, int]:
    out = subprocess.run(
        [sys.executable, "-c", _CHILD, mode], capture_output=True, text=True, check=True
    )
    return json.loads(out.stdout.splitlines()[-1])


def test_freed_arrays_are_reused_without_page_faults() -> None:
    kept, returned = _faults("kept"), _faults("returned")
    assert kept["made"]
    assert returned["faults"] > 20 * 40 * 200  # every array faulted again
    assert kept["faults"] < 200  # the same heap pages, already present


def test_simulate_makes_the_setting() -> None:
    """A library user's process keeps freed memory after its first ``simulate``, as the
    command line's does from its start."""
    assert _faults("simulate")["faults"] < 200


def _huge_kb(address: int) -> int:
    """AnonHugePages of the mapping of this process that holds ``address`` (smaps; an
    array's middle: NumPy madvises from its second page on, a mapping of its own)."""
    inside, huge = False, 0
    with open("/proc/self/smaps") as fh:
        for line in fh:
            head = line.split()[0]
            if "-" in head and not head.endswith(":"):  # a mapping's first line
                lo, hi = (int(x, 16) for x in head.split("-"))
                inside = lo <= address < hi
            elif inside and head == "AnonHugePages:":
                huge = int(line.split()[1])
    return huge


@pytest.fixture
def madvise_switch():
    """NumPy's huge-page switch, on (its default, whatever NUMPY_MADVISE_HUGEPAGE says)
    for the test and restored after it; skips where the kernel gives no huge pages on
    madvise."""
    import numpy as np

    try:
        with open("/sys/kernel/mm/transparent_hugepage/enabled") as fh:
            if "[madvise]" not in fh.read():
                pytest.skip("transparent huge pages are not given on madvise here")
    except OSError:
        pytest.skip("no transparent huge pages")
    switch = (getattr(np, "_core", None) or np.core).multiarray._set_madvise_hugepage
    before = switch(True)
    yield switch
    switch(before)


# in a new process, whose heap is fresh: NumPy's 16 MB zeros come from the top of the
# heap untouched, so NumPy's madvise gives them huge pages when the kernel has some
_ADVISED_CHILD = r"""
import json, sys
import numpy as np
np._core.multiarray._set_madvise_hugepage(True)
sys.path.insert(0, sys.argv[1])
from test_heap import _huge_kb
from vemwear.util.heap import keep_freed_memory, small_zeros
keep_freed_memory()
advised = np.zeros(2**21)  # 16 MB from the heap, advised by NumPy, written
advised[:] = 1.0
huge = _huge_kb(advised.ctypes.data + advised.nbytes // 2)
del advised
made = small_zeros((2**10, 2**11))  # NumPy's zeros would reuse that heap memory
fresh = made.shape == (2**10, 2**11) and made.flags.writeable and not made.any()
made[:] = 1.0
print(json.dumps({"advised": huge, "made": _huge_kb(made.ctypes.data + made.nbytes // 2),
                  "fresh": bool(fresh), "small": small_zeros(10).base is None}))
"""


def test_small_zeros_are_in_small_pages_also_in_advised_heap_memory(madvise_switch) -> None:
    """A ``small_zeros`` array gets no transparent huge pages, also where freed memory is
    kept and the heap holds memory NumPy advised for huge pages before (the case that
    turning NumPy's request off did not cover: 14 MB of huge pages there)."""
    out = subprocess.run(
        [sys.executable, "-c", _ADVISED_CHILD, str(Path(__file__).parent)],
        capture_output=True,
        text=True,
        check=True,
    )
    got = json.loads(out.stdout.splitlines()[-1])
    if got["advised"] == 0:
        pytest.skip("the kernel gave no huge pages to a madvised array")
    assert got["fresh"] and got["small"]  # zeros, writable; small arrays: NumPy's own
    assert got["made"] == 0


def test_simulate_writes_u_into_small_pages(madvise_switch) -> None:
    """The displacements of a result (8.7 MB here) are written into 4 KB pages."""
    from vemwear.paper import ex52
    from vemwear.simulate import simulate

    r = simulate(ex52.problem(0.2, 2.0, divisions=(128, 64), steps=64))
    assert r.u.nbytes > 8 * 2**20
    assert _huge_kb(r.u.ctypes.data + r.u.nbytes // 2) == 0
