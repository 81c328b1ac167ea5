"""The cost of load control against displacement control on the same pad.

A pad of (0, 2) x (0, 1) on rollers (u_x = 0 on its sides) slides on Example 5.2's
soft layer (p(r) = 0.4 r_+, g = 0.1, mu = 0.2, kappa = 2, v* = (1, 0)), squares of the
given sizes, ``--steps`` uniform steps on [0, 1]. Two runs per size, interleaved
``--repeat`` times in one process after a warm-up of each:

* **load**: a traction (0, -0.06) on the top; contact alone holds the pad in y
  (docs/method.md section 1c);
* **displacement** (the floor): the top moved by the displacement the load gives at
  the first level, u_y = -delta; the constraints hold the pad.

Reported: the compute time of ``simulate`` (every level's u kept) as min / median /
max in milliseconds and the ratio of the medians, for the whole run of a fresh
problem (assembly, factorization, levels) and for the levels alone (the same problem
again: its factorization is kept).

Usage::

    python benchmarks/bench_load_control.py
    python benchmarks/bench_load_control.py --sizes 32 64 128 --steps 64 --repeat 5
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np


def problems(n: int, steps: int) -> tuple[Callable[[], Any], Callable[[], Any]]:
    """Makers of the two problems (fresh ones: nothing factorized yet)."""
    from vemwear import LinearCompliance, Material, Problem, TimeGrid, simulate
    from vemwear.mesh import rectangle_squares, tag_rectangle
    from vemwear.simulate import Prescribed

    def mesh(top: str) -> Any:
        return tag_rectangle(
            rectangle_squares((2.0, 1.0), (n, n // 2)),
            {"rollers": ["left", "right"], top: "top", "contact": "bottom"},
        )

    common = dict(
        material=Material(4.0, 4.0),
        time=TimeGrid.uniform(1.0, steps),
        p=LinearCompliance(0.4),
        g=0.1,
        mu=0.2,
        kappa=2.0,
        v_star=(1.0, 0.0),
        clamped=(),
    )

    def load() -> Any:
        return Problem(
            mesh("traction"),
            f2=(0.0, -0.06),
            displacement=(Prescribed("rollers", ux=0.0),),
            **common,
        )

    first = simulate(load(), "newton")
    top = np.abs(first.problem.mesh.points[:, 1] - 1.0) < 1e-12
    delta = float(-first.u[0][top, 1].mean())

    def disp() -> Any:
        return Problem(
            mesh("press"),
            displacement=(Prescribed("rollers", ux=0.0), Prescribed("press", uy=-delta)),
            **common,
        )

    return load, disp


def run(make: Callable[[], Any], problem: Any = None) -> float:
    """Seconds of ``simulate``: of a fresh problem (``problem`` None: the whole run,
    set-up included), or of ``problem`` again (its factorization kept: the levels)."""
    from vemwear import simulate

    tick = time.perf_counter()
    simulate(make() if problem is None else problem, "newton")
    return time.perf_counter() - tick


def _row(label: str, load: list[float], disp: list[float]) -> str:
    cols = [" ".join(f"{f(v):7.1f}" for f in (min, statistics.median, max)) for v in (load, disp)]
    ratio = statistics.median(load) / statistics.median(disp)
    return f"{label:>16} | {cols[0]:>24} | {cols[1]:>24} | {ratio:.2f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[32, 64, 128])
    ap.add_argument("--steps", type=int, default=64)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    print(f"pad 2 x 1 on rollers, {args.steps} steps; compute ms (min / median / max)")
    print(f"{'size, part':>16} | {'load control':>24} | {'displacement (floor)':>24} | ratio")
    for n in args.sizes:
        make_load, make_disp = problems(n, args.steps)
        kept = {"load": make_load(), "disp": make_disp()}
        run(make_load, kept["load"]), run(make_disp, kept["disp"])  # warm-up
        t: dict[str, list[float]] = {k: [] for k in ("load", "disp", "load1", "disp1")}
        for _ in range(args.repeat):
            t["load"].append(run(make_load) * 1e3)
            t["disp"].append(run(make_disp) * 1e3)
            t["load1"].append(run(make_load, kept["load"]) * 1e3)
            t["disp1"].append(run(make_disp, kept["disp"]) * 1e3)
        size = f"{n} x {n // 2}"
        print(_row(f"{size}, whole", t["load"], t["disp"]))
        print(_row(f"{size}, levels", t["load1"], t["disp1"]))


if __name__ == "__main__":
    main()
