"""One BLAS thread pool at a time: OpenBLAS pools limited around the solver's kernels.

NumPy's and SciPy's wheels each bundle an OpenBLAS with its own pool of threads, and
MKL (PARDISO) brings a third. On a machine with few cores these pools spin against
each other: a multi-column SuperLU solve or a small dense Cholesky factorization can
become ten times slower, at random. :func:`solver_threads` limits the OpenBLAS pools
to one thread while the solver's dense and sparse kernels run, and
:func:`~vemwear.simulate.levels.run_levels` keeps them there for a whole run, so that
no pool woken by a NumPy product spins against MKL's threads (the multithreaded
PARDISO factorization and solves, which keep their threads). The limits are set and
restored through one cached :class:`threadpoolctl.ThreadpoolController` (about 20 µs
a context), so callers enter the context around whole kernels, not around tiny ones.

``VEMWEAR_BLAS_THREADS=keep`` in the environment turns the control off (for
measurements of the uncontrolled behaviour).
"""

from __future__ import annotations

import contextlib
import os
import threading
from collections.abc import Iterator
from functools import cache
from typing import Any


@cache
def _controller() -> Any:
    """The cached controller of the loaded BLAS libraries, or None without threadpoolctl."""
    try:
        from threadpoolctl import ThreadpoolController
    except ImportError:  # pragma: no cover - threadpoolctl is a dependency
        return None
    return ThreadpoolController()


@cache
def _openblas() -> Any:
    """The controller of the loaded OpenBLAS libraries only (NumPy's and SciPy's)."""
    ctl = _controller()
    return None if ctl is None else ctl.select(internal_api="openblas")


def _refresh() -> Any:
    """A controller that also sees the libraries loaded since (MKL by PARDISO)."""
    try:
        from threadpoolctl import ThreadpoolController
    except ImportError:  # pragma: no cover - threadpoolctl is a dependency
        return None
    return ThreadpoolController()


#: How deep this thread is in :func:`solver_threads` contexts: an inner one (a solve
#: of an iteration inside a run's context) finds the limits set and costs nothing.
_depth = threading.local()


@contextlib.contextmanager
def solver_threads() -> Iterator[None]:
    """Run the enclosed kernels with the OpenBLAS pools at one thread each."""
    depth = getattr(_depth, "n", 0)
    ctl = _openblas() if depth == 0 and os.environ.get("VEMWEAR_BLAS_THREADS") != "keep" else None
    if ctl is None:
        yield
        return
    _depth.n = depth + 1
    try:
        with ctl.limit(limits=1):
            yield
    finally:
        _depth.n = depth


def blas_info() -> list[dict[str, Any]]:
    """The loaded BLAS and OpenMP libraries with their thread counts (for benchmarks)."""
    ctl = _refresh()
    return [] if ctl is None else ctl.info()


__all__ = ["blas_info", "solver_threads"]
