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
* ``condensed run``: a whole condensed-Newton run of Example 5.5's data at 1/h =
  ``--n`` with the default backend (factorization, steps, recovery at every level);
  also with MKL's pool (PARDISO's threads) at one thread.

Usage::

    python benchmarks/bench_threads.py --repeat 7 --n 64
"""

from __future__ import annotations

import argparse
import os
import statistics
import time


def _row(name: str, v: list[float], unit: str) -> str:
    lo, med, hi = min(v), statistics.median(v), max(v)
    near = sum(abs(x / med - 1) <= 0.1 for x in v)  # repeats within 10 % of the median
    return (
        f"{name:<40} {lo:10.4f} {med:10.4f} {hi:10.4f} {unit:<8} spread "
        f"{100 * (hi / lo - 1):6.1f} %  within 10 %: {near:2d}/{len(v)}"
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--n", type=int, default=64, help="1/h of the matrices and of the run")
    ap.add_argument("--rhs", type=int, default=32)
    ap.add_argument("--dense", type=int, default=300)
    a = ap.parse_args(argv)

    import numpy as np

    from vemwear.paper import ex52
    from vemwear.simulate import SolverOptions, simulate
    from vemwear.solvers.backends import compliance_from_schur
    from vemwear.solvers.backends.superlu import SuperLUSchur
    from vemwear.solvers.threads import blas_info

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
    # the whole run once more with MKL's pool (PARDISO) at one thread: the cost of the
    # second thread against the spread it brings on a machine with two cores
    from threadpoolctl import ThreadpoolController

    mkl = ThreadpoolController().select(internal_api="mkl")

    def run_mkl1() -> float:
        with mkl.limit(limits=1):
            return run()

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
    print(f"{'case':<40} {'min':>10} {'median':>10} {'max':>10}")
    for name, (_fn, unit) in cases.items():
        for mode in modes:
            if (name, mode) in times:
                print(_row(f"{name} ({mode})", times[(name, mode)], unit))
    libs = ", ".join(f"{d['internal_api']}:{d['num_threads']}" for d in blas_info())
    print(f"BLAS pools: {libs}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
