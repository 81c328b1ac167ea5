"""Sparse backends on the stiffness of Example 5.5's meshes (k = h, squares).

For each 1/h and each installed backend: the factorization with the Schur
complement on the contact dofs (ordering + factorization + Schur block + its
inverse), and the time per right-hand side of a block solve with ``--rhs``
columns (the recovery of the displacement). Every measurement is repeated
``--repeat`` times, interleaved (backend after backend, then again), and reported
as min / median / max.

The floor, on the same matrix in the same run:

* ``floor pardiso``: a plain SPD factorization by PARDISO (no Schur block) and its
  block solve (phase 33), if PARDISO is installed;
* ``pardiso 1 thread``: PARDISO's Schur factorization on one MKL thread, as ``"auto"``
  makes it below ``SCHUR_SERIAL_MAX`` unknowns (the crossover: ``--n 16 32 64 96 128
  --rhs 65``, 65 columns as in the 64-step runs of ``benchmarks/bench_getfem.py``);
* ``floor superlu``: SciPy's SuperLU with its default ordering, factorization and
  block solve (the plain path; skipped above ``--superlu-max`` unknowns).

MUMPS and CHOLMOD are not measured: no binding of theirs installs from a wheel
with NumPy 2 on Python 3.11.

Usage::

    python benchmarks/bench_backends.py --n 64 128 256 --repeat 5

Timings on a loaded machine are only indicative; run on a quiet one for figures.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections import defaultdict
from collections.abc import Callable


def _stats(v: list[float]) -> str:
    return f"{min(v):8.3f} {statistics.median(v):8.3f} {max(v):8.3f}"


def _cases(K, contact, points, rhs: int, superlu_max: int) -> dict[str, Callable[[], tuple]]:
    """Callables returning (factorization seconds, seconds per right-hand side)."""
    import numpy as np
    import scipy.sparse.linalg as spla

    from vemwear.solvers.backends import available_backends, schur_factorize
    from vemwear.solvers.threads import solver_threads

    B = np.random.default_rng(0).normal(size=(K.shape[0], rhs))
    cases: dict[str, Callable[[], tuple]] = {}

    def schur(backend: str) -> Callable[[], tuple]:
        def run() -> tuple:
            t = time.perf_counter()
            f = schur_factorize(K, contact, points, backend)
            tf = time.perf_counter() - t
            t = time.perf_counter()
            f.solve(B)
            return tf, (time.perf_counter() - t) / rhs

        return run

    for b in available_backends():
        cases[f"{b} + Schur"] = schur(b)
    if "pardiso" in available_backends():  # what "auto" does below SCHUR_SERIAL_MAX
        from threadpoolctl import ThreadpoolController

        serial = schur("pardiso")
        schur_factorize(K, contact, points, "pardiso")  # MKL loaded, seen by threadpoolctl
        mkl = ThreadpoolController().select(internal_api="mkl")

        def pardiso_one_thread() -> tuple:
            with mkl.limit(limits=1):  # the factorization keeps the count for its solves
                return serial()

        cases["pardiso 1 thread"] = pardiso_one_thread
        from vemwear.solvers.backends.pardiso import PardisoFactor

        def floor_pardiso() -> tuple:
            t = time.perf_counter()
            f = PardisoFactor(K, spd=True)
            tf = time.perf_counter() - t
            t = time.perf_counter()
            f.solve(B)
            return tf, (time.perf_counter() - t) / rhs

        cases["floor pardiso"] = floor_pardiso
    if K.shape[0] <= superlu_max:
        Kc = K.tocsc()

        def floor_superlu() -> tuple:
            with solver_threads():
                t = time.perf_counter()
                lu = spla.splu(Kc)
                tf = time.perf_counter() - t
                t = time.perf_counter()
                lu.solve(B)
            return tf, (time.perf_counter() - t) / rhs

        cases["floor superlu"] = floor_superlu
    return cases


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--n", type=int, nargs="+", default=[64, 128, 256], help="values of 1/h")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--rhs", type=int, default=32, help="columns of the block solve")
    ap.add_argument("--superlu-max", type=int, default=300_000)
    a = ap.parse_args(argv)
    from vemwear.paper import ex52
    from vemwear.solvers.threads import blas_info

    print(
        f"{'1/h':>5} {'unknowns':>9} {'contact':>7}  {'case':<16}"
        f" {'factor+Schur [s]: min   median      max':>40}"
        f" {'solve/rhs [ms]: min median      max':>37}"
    )
    for n in a.n:
        pr = ex52.problem(0.2, 2.0, divisions=(2 * n, n), steps=1)
        s = pr.discrete.system
        cases = _cases(s.K, s.contact_dofs.ravel(), s.dof_points, a.rhs, a.superlu_max)
        fac: dict[str, list[float]] = defaultdict(list)
        sol: dict[str, list[float]] = defaultdict(list)
        for _ in range(a.repeat):  # interleaved: every case once per round
            for name, run in cases.items():
                tf, ts = run()
                fac[name].append(tf)
                sol[name].append(1e3 * ts)
        for name in cases:
            print(
                f"{n:5d} {s.n_free:9d} {s.contact_dofs.size:7d}  {name:<16}"
                f" {_stats(fac[name]):>40} {_stats(sol[name]):>37}"
            )
    libs = ", ".join(f"{d['internal_api']}:{d['num_threads']}" for d in blas_info())
    print(f"BLAS pools (threads outside the solver's kernels): {libs}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
