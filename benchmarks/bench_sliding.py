"""The cost of a foundation velocity that turns in 3D (two friction rows per node).

A square pin (-0.5, 0.5)^2 x (0, 0.5) of ``n x n x n/4`` hexahedra pressed into the
layer on z = 0 by its top face (u = (0, 0, -0.05)), mu = 0.3, kappa = 2, p(r) = 0.4 r_+,
g = 0.1, ``--levels`` uniform steps on [0, 1], the last level stored. Per size, after a
warm-up run of each case, interleaved ``--repeat`` times in one process:

* **line**: v*(t) = (cos 2 pi t, 0, 0), one friction row per node, as ``simulate`` runs
  it (runs of levels on one piece between the turns of v*);
* **line-newton**: the same with the law given as a callable (not known to be piecewise
  linear), so that Newton solves every level: the cost of a level with one row;
* **circle**: v*(t) = (cos 2 pi t, sin 2 pi t, 0), two friction rows per node; its
  friction changes at every level, so Newton solves every level;
* **floor**: the arithmetic of one Newton iteration with one row, in a bare NumPy loop
  on the same matrices: one product with the (m, 2m) block ``[C_NN, C_NT]``, the law and
  one solve with LU factors of an (m, m) matrix.

Reported: microseconds per level of the time loop (``timings["time_loop"]`` / levels) as
min / median / max, the set-up (discretization, factorization, compliance blocks) of
line and circle, and the ratios of the medians.

Usage::

    python benchmarks/bench_sliding.py
    python benchmarks/bench_sliding.py --sizes 8 16 --levels 256 --repeat 5
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
import scipy.linalg as sla


def _stats(v: list[float]) -> str:
    return f"{min(v):9.1f} {statistics.median(v):9.1f} {max(v):9.1f}"


def _problem(n: int, levels: int, case: str):
    from vemwear.contact import CallableCompliance, ContactPart, LinearCompliance
    from vemwear.mesh.generate3d import box_hexahedra, tag_box
    from vemwear.simulate import Prescribed, Problem, TimeGrid
    from vemwear.vem import Material

    mesh = tag_box(
        box_hexahedra((1.0, 1.0, 0.5), (n, n, max(1, n // 4)), origin=(-0.5, -0.5, 0.0)),
        {"top": "zmax", "contact": "zmin", "free": ["xmin", "xmax", "ymin", "ymax"]},
    )
    if case == "circle":
        v = lambda t: (np.cos(2 * np.pi * t), np.sin(2 * np.pi * t), 0.0)  # noqa: E731
    else:
        v = lambda t: (np.cos(2 * np.pi * t), 0.0, 0.0)  # noqa: E731
    law: object = LinearCompliance(0.4)
    if case == "line-newton":
        law = CallableCompliance(
            lambda r: 0.4 * np.maximum(r, 0.0), lambda r: np.where(r > 0, 0.4, 0.0), 0.4
        )
    part = ContactPart("contact", law, g=0.1, mu=0.3, kappa=2.0, v_star=v)  # type: ignore[arg-type]
    return Problem(
        mesh,
        Material(4.0, 4.0),
        TimeGrid.uniform(1.0, levels),
        clamped=(),
        displacement=(Prescribed("top", ux=0.0, uy=0.0, uz=-0.05),),
        contacts=(part,),
    )


def _run(n: int, levels: int, case: str) -> tuple[float, float, int]:
    """(set-up seconds, time-loop seconds per level, friction rows)."""
    from vemwear.simulate import simulate

    t0 = time.perf_counter()
    pr = _problem(n, levels, case)
    d = pr.discrete
    from vemwear.simulate import SolverOptions

    d.step_solver(SolverOptions("newton"))
    setup = time.perf_counter() - t0
    r = simulate(pr, store="final", every=levels)
    assert r.residuals.max() < 1e-9
    return setup, r.timings["time_loop"] / (levels + 1), d.system.rows


def _floor(n: int, levels: int) -> float:
    """One Newton iteration's arithmetic with one row, per level."""
    from vemwear.simulate import SolverOptions

    pr = _problem(n, 2, "line")
    newton = pr.discrete.step_solver(SolverOptions("newton"))
    H, m = newton.H, pr.discrete.system.m
    lu, piv, _ = sla.lapack.dgetrf(np.eye(m) + newton.A_norm * 0.4)
    x, y, w = np.ones(2 * m), np.zeros(m), np.zeros(m)
    t0 = time.perf_counter()
    for _ in range(levels + 1):
        p = 0.4 * np.maximum(y - w, 0.0)
        x[:m] = p
        x[m:] = 0.3 * p
        R = H @ x
        y = y - sla.lapack.dgetrs(lu, piv, R)[0] * 1e-3
        w = w + 1e-6 * p
    return (time.perf_counter() - t0) / (levels + 1)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[8, 16])
    ap.add_argument("--levels", type=int, default=128)
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args()
    cases = ("line", "line-newton", "circle")
    for n in a.sizes:
        for c in cases:  # warm-up
            _run(n, 8, c)
        loops: dict[str, list[float]] = {c: [] for c in (*cases, "floor")}
        setups: dict[str, list[float]] = {c: [] for c in cases}
        rows = {}
        for _ in range(a.repeat):
            for c in cases:
                s, per, rows[c] = _run(n, a.levels, c)
                loops[c].append(1e6 * per)
                setups[c].append(s)
            loops["floor"].append(1e6 * _floor(n, a.levels))
        m = (n + 1) ** 2
        print(f"n = {n} (m = {m} contact nodes), {a.levels} levels, {a.repeat} repeats")
        print(f"  {'case':12s} {'rows':>4s} {'us/level min':>13s} {'median':>9s} {'max':>9s}")
        for c in (*cases, "floor"):
            print(f"  {c:12s} {rows.get(c, 1):4d} {_stats(loops[c])}")
        for c in ("line", "circle"):
            print(f"  set-up {c:6s} s   {_stats(setups[c])}")
        med = {c: statistics.median(v) for c, v in loops.items()}
        print(
            f"  circle / line-newton {med['circle'] / med['line-newton']:.2f}, circle / line "
            f"{med['circle'] / med['line']:.2f}, set-up circle / line "
            f"{statistics.median(setups['circle']) / statistics.median(setups['line']):.2f}"
        )


if __name__ == "__main__":
    main()
