"""Example 5.2 on uniform and on adaptive meshes: the wear's accuracy against dofs and
wall time.

Data set 1 (mu = 0.2, kappa = 2), 64 time steps. Every run's wear at T, interpolated
along Gamma_C onto the contact nodes of a uniform reference mesh (``--reference``,
default 512 x 256), gives the relative L2 error along Gamma_C; the table lists the
dofs at T, the wall time of the run (set-up included, in this process) and that error,
for uniform meshes 64 x 32 ... 256 x 128 and for adaptive runs
(:func:`vemwear.simulate.simulate_adaptive`: residual estimator, Doerfler marking,
graded refinement with hanging nodes) of several settings.

Usage::

    python benchmarks/adaptive_ex52.py
    python benchmarks/adaptive_ex52.py --reference 256 --quick
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from numpy.typing import NDArray

from vemwear.paper import ex52
from vemwear.simulate import Result, SolverOptions, simulate, simulate_adaptive

STEPS = 64
#: Adaptive settings: initial divisions, every, theta, max_cells, max_level.
ADAPTIVE = [
    ((16, 8), 8, 0.5, 1500, 4),
    ((16, 8), 4, 0.7, 20000, 6),
    ((32, 16), 4, 0.5, 20000, 5),
    ((32, 16), 2, 0.7, 20000, 6),
]


def wear_at_T(r: Result) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The wear at the last level along Gamma_C (the bottom side), by increasing x."""
    x = r.contact_points[:, 0]
    order = x.argsort()
    return x[order], np.asarray(r.wear[-1])[order]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reference", type=int, default=512, help="divisions of the reference")
    ap.add_argument("--quick", action="store_true", help="the first two adaptive settings")
    a = ap.parse_args()
    n = a.reference
    t0 = time.perf_counter()
    ref = simulate(ex52.problem(0.2, 2.0, divisions=(n, n // 2), steps=STEPS), "newton")
    xr, wr = wear_at_T(ref)
    print(f"reference {n} x {n // 2}: {time.perf_counter() - t0:.1f} s")

    def error(r: Result) -> float:
        x, w = wear_at_T(r)
        d = np.interp(xr, x, w) - wr
        return float(np.sqrt(np.trapezoid(d**2, xr) / np.trapezoid(wr**2, xr)))

    print("| mesh | dofs at T | wall time [s] | wear error |")
    print("|---|---|---|---|")
    for m in (64, 128, 256):
        t0 = time.perf_counter()
        p = ex52.problem(0.2, 2.0, divisions=(m, m // 2), steps=STEPS)
        r = simulate(p, SolverOptions("newton"))
        dt = time.perf_counter() - t0
        print(f"| uniform {m} x {m // 2} | {p.space.n_dofs} | {dt:.2f} | {error(r):.2e} |")
    for div, every, theta, max_cells, level in ADAPTIVE[: 2 if a.quick else None]:
        t0 = time.perf_counter()
        p = ex52.problem(0.2, 2.0, divisions=div, steps=STEPS)
        segs = simulate_adaptive(p, every=every, theta=theta, max_cells=max_cells, max_level=level)
        dt = time.perf_counter() - t0
        last = segs[-1]
        print(
            f"| adaptive from {div[0]} x {div[1]}, every {every}, theta {theta}, "
            f"max_cells {max_cells}, max level {level} | {last.problem.space.n_dofs} | "
            f"{dt:.2f} | {error(last.result):.2e} |"
        )


if __name__ == "__main__":
    main()
