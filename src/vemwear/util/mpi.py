"""Whether this process was started by an MPI launcher, read from its environment.

Nothing here imports MPI: a process started by ``mpirun`` (Open MPI) or ``mpiexec``
(MPICH's Hydra, Intel MPI) carries the size of the job and its own rank in its
environment, so a run can refuse to be run N times over before any MPI library is
loaded.
"""

from __future__ import annotations

import os
from typing import NamedTuple

__all__ = ["Launch", "launched"]

#: (size, rank) variables of the launchers: Open MPI, then the PMI of MPICH and Intel MPI
_VARIABLES = (("OMPI_COMM_WORLD_SIZE", "OMPI_COMM_WORLD_RANK"), ("PMI_SIZE", "PMI_RANK"))


class Launch(NamedTuple):
    """The MPI job this process belongs to: its number of ranks and this rank."""

    size: int
    rank: int


def launched() -> Launch:
    """The size of the MPI job and this process's rank (1, 0 outside a launcher)."""
    for size_var, rank_var in _VARIABLES:
        size = os.environ.get(size_var, "")
        if size.isdigit():
            rank = os.environ.get(rank_var, "0")
            return Launch(int(size), int(rank) if rank.isdigit() else 0)
    return Launch(1, 0)
