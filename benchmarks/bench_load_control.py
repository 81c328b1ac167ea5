"""The cost of load control against displacement control on the same pad.

A pad of (0, 2) x (0, 1) on rollers (u_x = 0 on its sides) slides on Example 5.2's
soft layer (p(r) = 0.4 r_+, g = 0.1, mu = 0.2, kappa = 2, v* = (1, 0)), squares of the
given sizes, ``--steps`` uniform steps on [0, 1]. Two runs per size, interleaved
``--repeat`` times in one process after a warm-up of each:

* **load**: a traction (0, -0.06) on the top; contact alone holds the pad in y
  (docs/method.md section 1c);
* **displacement** (the floor): the top moved by the displacement the load gives at
  the first level, u_y = -delta; the constraints hold the pad.

Reported: the compute time of ``simulate`` (set-up and levels, every level's u kept)
as min / median / max in milliseconds and the ratio of the medians.

Usage::

    python benchmarks/bench_load_control.py
    python benchmarks/bench_load_control.py --sizes 32 64 128 --steps 64 --repeat 5
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np


def problems(n: int, steps: int):
    from vemwear import LinearCompliance, Material, Problem, TimeGrid, simulate
    from vemwear.mesh import rectangle_squares, tag_rectangle
    from vemwear.simulate import Prescribed

    def make(top: str) -> object:
        mesh = tag_rectangle(
            rectangle_squares((2.0, 1.0), (n, n // 2)),
            {"rollers": ["left", "right"], top: "top", "contact": "bottom"},
        )
        return mesh

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
    load = Problem(
        make("traction"),
        f2=(0.0, -0.06),
        displacement=(Prescribed("rollers", ux=0.0),),
        **common,
    )
    first = simulate(load, "newton")
    top = np.abs(load.mesh.points[:, 1] - 1.0) < 1e-12
    delta = float(-first.u[0][top, 1].mean())
    disp = Problem(
        make("press"),
        displacement=(Prescribed("rollers", ux=0.0), Prescribed("press", uy=-delta)),
        **common,
    )
    return load, disp


def run(problem) -> float:
    from vemwear import simulate

    tick = time.perf_counter()
    simulate(problem, "newton")
    return time.perf_counter() - tick


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[32, 64, 128])
    ap.add_argument("--steps", type=int, default=64)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    print(f"pad 2 x 1 on rollers, {args.steps} steps; compute ms (min / median / max)")
    print(f"{'size':>10} | {'load control':>24} | {'displacement (floor)':>24} | ratio")
    for n in args.sizes:
        load, disp = problems(n, args.steps)
        run(load), run(disp)  # warm-up
        times: dict[str, list[float]] = {"load": [], "disp": []}
        for _ in range(args.repeat):
            times["load"].append(run(load) * 1e3)
            times["disp"].append(run(disp) * 1e3)
        cols = [
            " ".join(f"{f(v):7.1f}" for f in (min, statistics.median, max))
            for v in (times["load"], times["disp"])
        ]
        ratio = statistics.median(times["load"]) / statistics.median(times["disp"])
        print(f"{n:>4} x {n // 2:<4}| {cols[0]:>24} | {cols[1]:>24} | {ratio:.2f}")


if __name__ == "__main__":
    main()
