"""The cost of a time level: runs on one piece, Newton at every level, and a floor.

Example 5.2's data (data set 1: mu = 0.2, kappa = 2, p(r) = 0.4 r_+, g = 0.1) on
squares of (0, 2) x (0, 1), ``--levels`` uniform steps on [0, T] with T = levels / 64 (the
paper's step 1/64, so long runs go on wearing the body until the rigid layer carries
load), storing the last level only. Per size, interleaved ``--repeat`` times in one
process after a warm-up run of each case:

* **pieces**: ``simulate`` as it is, with runs of levels on one piece of the step
  problem (``vemwear.solvers.pieces``);
* **newton**: the same law given as a callable (``CallableCompliance(p, p')``), which
  is not known to be piecewise linear, so Newton solves every level (the cost of a
  level before the runs on pieces);
* **floor**: the arithmetic a level cannot do without, in a bare NumPy loop on the
  same problem's matrices: one product with the piece's matrix, one solve with its LU
  factors, the law and the wear update (no certificate, no output).

Reported: microseconds per level of the time loop (``timings["time_loop"]`` / levels)
as min / median / max, the ratios of the medians, and the largest difference of the
final wear between pieces and newton (relative to its maximum).

``--reciprocating``: v*(t) = (cos 2 pi t, 0) instead of (1, 0), so the wear rate changes
at every level and the friction turns twice a period (a run of levels ends there).

Usage::

    python benchmarks/bench_levels.py
    python benchmarks/bench_levels.py --sizes 16 32 64 --levels 4000 --repeat 5
    python benchmarks/bench_levels.py --reciprocating --sizes 16 32 --repeat 3
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import statistics
import sys
import time

import numpy as np


def _stats(v: list[float]) -> str:
    return f"{min(v):7.1f} {statistics.median(v):7.1f} {max(v):7.1f}"


def _reciprocating(t: float) -> tuple[float, float]:
    """v*(t) = (cos 2 pi t, 0): the foundation turns at t = 1/4, 3/4, ..."""
    return (float(np.cos(2.0 * np.pi * t)), 0.0)


def _problem(nx: int, levels: int, reciprocating: bool = False):
    from vemwear.paper import ex52
    from vemwear.simulate import TimeGrid

    pr = ex52.problem(0.2, 2.0, divisions=(nx, nx // 2))  # data set 1
    pr = dataclasses.replace(pr, time=TimeGrid.uniform(levels / 64, levels))
    return dataclasses.replace(pr, v_star=_reciprocating) if reciprocating else pr


def _loop(problem) -> tuple[float, np.ndarray]:
    from vemwear.simulate import simulate

    r = simulate(problem, store="final", every=len(problem.time.t) - 1)
    return r.timings["time_loop"], r.wear[-1]


def _floor(problem) -> float:
    """The bare recurrence on the piece of the first levels (same sizes as a level's
    product and solve)."""
    from vemwear.simulate import SolverOptions

    d = problem.discrete
    newton = d.step_solver(SolverOptions("newton"))
    piece = newton.predictor.piece  # the last piece of the runs
    assert piece is not None
    M, c0, red, law = piece.M, piece.c0, piece.red, d.system.p
    rate = (problem.time.t[1] - problem.time.t[0]) * d.alpha(0.0)
    w = np.zeros(d.system.m)
    L = len(problem.time.t)
    t = time.perf_counter()
    for _ in range(L):
        b = M @ w
        b += c0
        z = red.solve(b)
        w = w + rate * law(z - w)
    return time.perf_counter() - t


def table(nx: int, levels: int, repeat: int, reciprocating: bool) -> None:
    from vemwear.contact import CallableCompliance

    pieces = _problem(nx, levels, reciprocating)
    law = pieces.p
    newton = dataclasses.replace(pieces, p=CallableCompliance(law, law.derivative))
    L = len(pieces.time.t)
    for pr in (pieces, newton):  # warm-up: factorizations, first calls
        _loop(pr)
    tp: list[float] = []
    tn: list[float] = []
    tf: list[float] = []
    diff = 0.0
    for _ in range(repeat):
        a, wa = _loop(pieces)
        b, wb = _loop(newton)
        tp.append(1e6 * a / L)
        tn.append(1e6 * b / L)
        tf.append(1e6 * _floor(pieces) / L)
        diff = max(diff, float(np.abs(wa - wb).max() / np.abs(wb).max()))
    med = statistics.median
    m = pieces.discrete.system.m
    print(
        f"{nx:>4} x {nx // 2:<4} {m:>5} {L:>7} | {_stats(tp)} | {_stats(tn)} | {_stats(tf)} |"
        f" {med(tn) / med(tp):6.2f} {med(tp) / med(tf):6.2f} | {diff:8.1e}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--sizes", type=int, nargs="+", default=[16, 32, 64, 128])
    ap.add_argument("--levels", type=int, default=2000)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--reciprocating", action="store_true", help="v*(t) = (cos 2 pi t, 0)")
    args = ap.parse_args()
    print(f"machine: {os.cpu_count()} cores; python {sys.version.split()[0]}")
    print("microseconds per level of the time loop, min / median / max")
    print(
        f"{'squares':>11} {'m':>5} {'levels':>7} | {'pieces':^23} | {'newton':^23} |"
        f" {'floor':^23} | {'new/pc':>6} {'pc/fl':>6} | {'wear diff':>8}"
    )
    if args.reciprocating:
        print("reciprocating sliding: v*(t) = (cos 2 pi t, 0)")
    for nx in args.sizes:
        table(nx, args.levels, args.repeat, args.reciprocating)


if __name__ == "__main__":
    main()
