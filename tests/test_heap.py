"""The allocator keeps freed memory for the next arrays (glibc), so that repeated
allocations of the same size do not page-fault again."""

from __future__ import annotations

import json
import platform
import subprocess
import sys

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
