"""Example 5.2 on uniform and on adaptive meshes: the wear's accuracy against dofs and
wall time.

Data set 1 (mu = 0.2, kappa = 2), 64 time steps. Every run's wear at T, interpolated
along Gamma_C onto the contact nodes of a uniform reference mesh (``--reference``,
default 512 x 256), gives the relative L2 error along Gamma_C; the table lists the
dofs at T, the wall time of the run (set-up included, in this process) and that error,
for uniform meshes 64 x 32 ... 256 x 128 and for adaptive runs
(:func:`vemwear.simulate.simulate_adaptive`: residual estimator, Doerfler marking,
graded refinement with hanging nodes) of several settings. The runs are repeated
``--repeat`` times, interleaved (every case once, then again), and the wall times are
given as min / median / max; the last columns compare each run's dofs and median wall
time with those of the uniform 256 x 128 mesh, measured in the same invocation.

Usage::

    python benchmarks/adaptive_ex52.py --repeat 5
    python benchmarks/adaptive_ex52.py --reference 256 --quick
"""

from __future__ import annotations

import argparse
import time

from adaptive_table import Case, measure, table, wear_error

from vemwear.paper import ex52
from vemwear.simulate import Result, SolverOptions, simulate, simulate_adaptive

STEPS = 64
UNIFORM = (64, 128, 256)
#: Adaptive settings: initial divisions, every, theta, max_cells, max_level, estimator.
ADAPTIVE = [
    ((64, 32), 16, 0.4, 5000, None, "residual"),
    ((48, 24), 16, 0.5, 5000, None, "residual"),
    ((64, 32), 16, 0.5, 5000, None, "residual"),
    ((32, 16), 8, 0.5, 5000, None, "residual"),
    ((48, 24), 16, 0.5, 5000, None, "wear"),
]


def _uniform(n: int) -> Case:
    def run() -> tuple[int, Result]:
        p = ex52.problem(0.2, 2.0, divisions=(n, n // 2), steps=STEPS)
        return p.space.n_dofs, simulate(p, SolverOptions("newton"))

    return run


def _adaptive(
    div: tuple[int, int], every: int, theta: float, max_cells: int, level: int | None, est: str
) -> Case:
    # the wear estimator with the cubic transfer it is meant for (docs/method.md section 11)
    transfer = "cubic" if est == "wear" else "linear"

    def run() -> tuple[int, Result]:
        p = ex52.problem(0.2, 2.0, divisions=div, steps=STEPS)
        segs = simulate_adaptive(
            p,
            every=every,
            theta=theta,
            max_cells=max_cells,
            max_level=level,
            estimator=est,
            transfer=transfer,
        )
        return segs[-1].problem.space.n_dofs, segs[-1].result

    return run


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reference", type=int, default=512, help="divisions of the reference")
    ap.add_argument("--repeat", type=int, default=3, help="interleaved repeats")
    ap.add_argument("--quick", action="store_true", help="the first two adaptive settings")
    a = ap.parse_args()
    n = a.reference
    t0 = time.perf_counter()
    ref = simulate(ex52.problem(0.2, 2.0, divisions=(n, n // 2), steps=STEPS), "newton")
    print(f"reference {n} x {n // 2}: {time.perf_counter() - t0:.1f} s")
    cases: dict[str, Case] = {f"uniform {m} x {m // 2}": _uniform(m) for m in UNIFORM}
    for div, every, theta, max_cells, level, est in ADAPTIVE[: 2 if a.quick else None]:
        name = f"adaptive from {div[0]} x {div[1]}, every {every}, theta {theta}, max_cells {max_cells}"
        name += f", max level {level}" if level is not None else ""
        cases[name + ("" if est == "residual" else f", {est}")] = _adaptive(
            div, every, theta, max_cells, level, est
        )
    times, found = measure(cases, a.repeat, wear_error(ref))
    base = f"uniform {UNIFORM[-1]} x {UNIFORM[-1] // 2}"
    print(table(times, found, base, ratio=lambda q: f"1/{1 / q:.1f}"))


if __name__ == "__main__":
    main()
