"""Spread of repeated timings with and without the BLAS thread control.

NumPy's and SciPy's wheels each bundle an OpenBLAS with its own thread pool, and
PARDISO brings MKL's. The solver limits the OpenBLAS pools to one thread around its
kernels (:mod:`vemwear.solvers.threads`); ``VEMWEAR_BLAS_THREADS=keep`` turns that
off. This script runs the same work with the control on and off, interleaved, and
prints min / median / max, the spread (max / min - 1) and how many repeats lie within
10 % of the median, after one untimed call of each case (imports and first
allocations), of:

* ``superlu block``: a ``--rhs``-column solve with the condensed path's SuperLU
  factors (seconds per column);
* ``cholesky``: the inverse of a ``--dense`` x ``--dense`` SPD matrix by Cholesky
  (what follows every Schur complement), after a NumPy matrix product that wakes
  NumPy's own pool;
* ``condensed run``: a condensed-Newton run of Example 5.5's data at 1/h = ``--n``
  with the default backend; the problem keeps its factorization from the untimed first
  call, so a run is the steps and the recovery at every level. Also with MKL's pool
  (PARDISO's threads) at one thread, on a second problem factorized at one thread (a
  PARDISO solve keeps the thread count of its factorization).

These run with freed memory kept by the allocator, as in the command line
(:func:`vemwear.util.heap.keep_freed_memory`). Then ``condensed run`` again in child
processes, in turn with the allocator's freed memory kept, returned to the system
(glibc's default), and kept with MKL at one thread (``MKL_NUM_THREADS=1``): one
untimed run and ``--runs`` timed runs each, with the page faults and the kernel time
of each run (and, for the repeats more than 10 % above the median, their kernel time
against the others'). The problem keeps its factorization from run to run, so a run
is the time loop and the recovery of u at every level; its floor, measured right
after it, is the block solve it cannot do without: one column per level with the same
factorization (memory-bound, like most of the run). Then a new
factorization of the same matrix, the other large work of a study's worker between
its runs, whose freed memory the next run finds returned or kept. Last, the floors of
the machine itself, interleaved with the runs: a fixed single-threaded NumPy workload
of about the same duration that stays in the caches (sorts of 1.6 MB) and one that
streams through memory (copies of 128 MB).

Usage::

    python benchmarks/bench_threads.py --repeat 7 --n 64
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import time
from typing import Any


def _row(name: str, v: list[float], unit: str) -> str:
    lo, med, hi = min(v), statistics.median(v), max(v)
    near = sum(abs(x / med - 1) <= 0.1 for x in v)  # repeats within 10 % of the median
    return (
        f"{name:<48} {lo:10.4f} {med:10.4f} {hi:10.4f} {unit:<8} spread "
        f"{100 * (hi / lo - 1):6.1f} %  within 10 %: {near:2d}/{len(v)}"
    )


def _heap_child(n: int, runs: int, kept: bool) -> None:
    """Print, for ``runs`` condensed runs: the wall time, kernel time and page faults of
    the run, the wall time of its floor (the block solve of one column per level with
    the run's factorization), measured right after it, and that of a new factorization
    of the same matrix (other large work between runs, as in a study's worker); and the
    wall and kernel time of the run's writes of u into its result
    (``Discretization.full_dofs_block``, timed by a wrapper), the first touch of that
    freshly mapped array."""
    import importlib

    import numpy as np

    from vemwear.paper import ex52
    from vemwear.simulate import SolverOptions, simulate
    from vemwear.solvers.backends import schur_factorize
    from vemwear.util.heap import keep_freed_memory

    if kept:
        keep_freed_memory()
    else:  # simulate makes the setting at its first call: glibc's default needs it off
        importlib.import_module("vemwear.simulate.loop").keep_freed_memory = lambda: False
    writes = [0.0, 0.0]  # wall and kernel seconds of the writes of u, this run
    cls = importlib.import_module("vemwear.simulate.discrete").Discretization
    full_dofs_block = cls.full_dofs_block

    def timed(*args: Any, **kw: Any) -> Any:
        r, t = resource.getrusage(resource.RUSAGE_SELF), time.perf_counter()
        try:
            return full_dofs_block(*args, **kw)
        finally:
            writes[0] += time.perf_counter() - t
            writes[1] += resource.getrusage(resource.RUSAGE_SELF).ru_stime - r.ru_stime

    cls.full_dofs_block = timed
    pr = ex52.problem(0.2, 2.0, divisions=(2 * n, n), steps=n)
    s = pr.discrete.system
    opts = SolverOptions("newton")
    simulate(pr, opts)
    factor = pr.discrete.step_solver(opts).factor  # kept by the problem from run to run
    B = np.asfortranarray(np.random.default_rng(0).normal(size=(s.n_free, n + 1)))
    X = np.empty_like(B, order="F")
    rows = []
    for _ in range(runs):
        writes[:] = [0.0, 0.0]
        r0, t0 = resource.getrusage(resource.RUSAGE_SELF), time.perf_counter()
        simulate(pr, opts)
        t, r1 = time.perf_counter() - t0, resource.getrusage(resource.RUSAGE_SELF)
        t1 = time.perf_counter()
        factor.solve(B, out=X)
        floor = time.perf_counter() - t1
        t2 = time.perf_counter()
        schur_factorize(s.K, s.contact_dofs.ravel(), s.dof_points, "auto")
        other = time.perf_counter() - t2
        rows.append(
            (t, r1.ru_stime - r0.ru_stime, r1.ru_minflt - r0.ru_minflt, floor, other, *writes)
        )
    print(json.dumps(rows))


def _floor_work(x: Any, reps: int) -> float:
    """A fixed NumPy workload (copies and sorts of ``x``); its wall time."""
    import numpy as np

    t = time.perf_counter()
    for _ in range(reps):
        np.sort(x * 1.0001)
    return time.perf_counter() - t


def _stream_work(a: Any, b: Any, reps: int) -> float:
    """A fixed memory-bound NumPy workload (copies of ``a`` into ``b``); its wall time."""
    import numpy as np

    t = time.perf_counter()
    for _ in range(reps):
        np.copyto(b, a)
    return time.perf_counter() - t


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--n", type=int, default=64, help="1/h of the matrices and of the run")
    ap.add_argument("--rhs", type=int, default=32)
    ap.add_argument("--dense", type=int, default=300)
    ap.add_argument("--runs", type=int, default=3, help="timed runs per child process")
    ap.add_argument("--heap-child", choices=["kept", "returned"], help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.heap_child:
        _heap_child(a.n, a.runs, a.heap_child == "kept")
        return 0

    import numpy as np

    from vemwear.paper import ex52
    from vemwear.simulate import SolverOptions, simulate
    from vemwear.solvers.backends import compliance_from_schur
    from vemwear.solvers.backends.superlu import SuperLUSchur
    from vemwear.solvers.threads import blas_info
    from vemwear.util.heap import keep_freed_memory

    keep_freed_memory()  # as the command line does

    pr = ex52.problem(0.2, 2.0, divisions=(2 * a.n, a.n), steps=a.n)
    s = pr.discrete.system
    f = SuperLUSchur(s.K, s.contact_dofs.ravel(), s.dof_points)
    rng = np.random.default_rng(0)
    B = rng.normal(size=(s.n_free, a.rhs))
    G = rng.normal(size=(a.dense, a.dense))
    S = G @ G.T + a.dense * np.eye(a.dense)
    big = rng.normal(size=(600, 600))

    def superlu() -> float:
        t = time.perf_counter()
        f.solve(B)
        return (time.perf_counter() - t) / a.rhs

    def cholesky() -> float:
        _ = big @ big  # NumPy's pool runs (and spins) just before
        t = time.perf_counter()
        compliance_from_schur(S)
        return time.perf_counter() - t

    def run() -> float:
        t = time.perf_counter()
        simulate(pr, SolverOptions("newton"))
        return time.perf_counter() - t

    cases = {"superlu block": (superlu, "s/col"), "cholesky": (cholesky, "s")}
    cases["condensed run"] = (run, "s")
    times: dict[tuple[str, str], list[float]] = {}
    for fn, _unit in cases.values():  # first calls (imports, first allocations) untimed
        fn()
    # the run once more with MKL's pool (PARDISO) at one thread: the cost of the second
    # thread against the spread it brings on a machine with two cores. A PARDISO solve
    # keeps the thread count of its factorization, so this problem is factorized (in
    # its untimed first call) with the limit in place.
    from threadpoolctl import ThreadpoolController

    mkl = ThreadpoolController().select(internal_api="mkl")
    pr1 = ex52.problem(0.2, 2.0, divisions=(2 * a.n, a.n), steps=a.n)

    def run_mkl1() -> float:
        with mkl.limit(limits=1):
            t = time.perf_counter()
            simulate(pr1, SolverOptions("newton"))
            return time.perf_counter() - t

    run_mkl1()

    modes = ("controlled", "uncontrolled", "controlled, MKL 1 thread")
    for _ in range(a.repeat):
        for mode in modes:
            if mode == "uncontrolled":
                os.environ["VEMWEAR_BLAS_THREADS"] = "keep"
            else:
                os.environ.pop("VEMWEAR_BLAS_THREADS", None)
            if mode == modes[2]:
                times.setdefault(("condensed run", mode), []).append(run_mkl1())
                continue
            for name, (fn, _unit) in cases.items():
                times.setdefault((name, mode), []).append(fn())
    os.environ.pop("VEMWEAR_BLAS_THREADS", None)
    print(f"1/h = {a.n}: {s.n_free} unknowns, {a.repeat} interleaved repeats")
    print(f"{'case':<48} {'min':>10} {'median':>10} {'max':>10}")
    for name, (_fn, unit) in cases.items():
        for mode in modes:
            if (name, mode) in times:
                print(_row(f"{name} ({mode})", times[(name, mode)], unit))
    libs = ", ".join(f"{d['internal_api']}:{d['num_threads']}" for d in blas_info())
    print(f"BLAS pools: {libs}")
    _heap_table(a, statistics.median(times[("condensed run", "controlled")]))
    return 0


def _heap_table(a: argparse.Namespace, run_time: float) -> None:
    """Condensed runs in child processes with the allocator's freed memory kept or
    returned, each with its floor, interleaved with two fixed NumPy workloads of about
    the same duration on one thread: one in the caches, one streaming through memory."""
    import numpy as np
    from threadpoolctl import threadpool_limits

    x = np.random.default_rng(0).normal(size=200_000)
    big = np.random.default_rng(1).normal(size=2**24)
    to = big.copy()  # touched: the copies do not page-fault
    with threadpool_limits(limits=1):
        once = _floor_work(x, 10) / 10
        reps = max(1, round(run_time / once))
        once = _stream_work(big, to, 10) / 10
        copies = max(1, round(run_time / once))
    # the child's allocator setting, and MKL's threads (two, or one for every phase)
    children = {
        "kept": ("kept", {}),
        "returned": ("returned", {}),
        "kept, MKL 1 thread": ("kept", {"MKL_NUM_THREADS": "1"}),
    }
    rows: dict[str, list[tuple[float, ...]]] = {mode: [] for mode in children}
    sorts: list[float] = []
    streams: list[float] = []
    for _ in range(a.repeat):
        for mode, (heap, env) in children.items():
            cmd = [sys.executable, __file__, "--heap-child", heap, "--n", str(a.n)]
            out = subprocess.run(
                [*cmd, "--runs", str(a.runs)],
                capture_output=True,
                text=True,
                check=True,
                env={**os.environ, **env},
            )
            rows[mode] += [tuple(r) for r in json.loads(out.stdout.splitlines()[-1])]
            with threadpool_limits(limits=1):
                for _ in range(a.runs):
                    sorts.append(_floor_work(x, reps))
                    streams.append(_stream_work(big, to, copies))
    print(
        f"condensed run in child processes ({a.repeat} x {a.runs} runs each, interleaved; "
        "freed memory kept or returned, MKL at two threads or one); "
        "kernel time and page faults: medians per run; floor: the block solve of one "
        "column per level with the run's factorization, right after each run; then a "
        "new factorization of the same matrix"
    )
    for mode, v in rows.items():
        sys_t, faults = statistics.median(r[1] for r in v), statistics.median(r[2] for r in v)
        print(
            _row(f"condensed run (freed memory {mode})", [r[0] for r in v], "s")
            + f"  kernel {sys_t:.3f} s, {faults:.0f} page faults"
        )
        med = statistics.median(r[0] for r in v)
        slow = [r for r in v if r[0] > 1.1 * med]  # more than 10 % above the median
        if slow:
            rest = [r for r in v if r[0] <= 1.1 * med]
            print(
                f"  {len(slow)} repeats more than 10 % above the median: "
                f"{statistics.median(r[0] for r in slow) - med:+.3f} s wall, kernel time "
                f"{statistics.median(r[1] for r in slow):.3f} s against "
                f"{statistics.median(r[1] for r in rest):.3f} s in the others; writing u "
                f"into the result {statistics.median(r[5] for r in slow):.3f} s "
                f"(kernel {statistics.median(r[6] for r in slow):.3f} s) against "
                f"{statistics.median(r[5] for r in rest):.3f} s "
                f"(kernel {statistics.median(r[6] for r in rest):.3f} s) (medians)"
            )
        print(_row(f"  its floor (freed memory {mode})", [r[3] for r in v], "s"))
        print(_row(f"  run / floor (freed memory {mode})", [r[0] / r[3] for r in v], ""))
        print(_row(f"  factorization (freed memory {mode})", [r[4] for r in v], "s"))
    print(_row("NumPy sorts, one thread (in cache)", sorts, "s"))
    print(_row("NumPy copies, one thread (128 MB)", streams, "s"))


if __name__ == "__main__":
    raise SystemExit(main())
