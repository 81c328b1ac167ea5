"""Whole runs against their floor, measured in the same run on the same matrix.

``--reference``: Example 5.5's reference run in-process (h = k = 1/n, n = 256 by
default: 263,168 unknowns, 257 levels, u stored at the 65 levels t = i/64), for each
backend in ``--backends``, interleaved ``--repeat`` times. Reported per run: mesh,
assembly, setup (ordering, factorization, Schur block), time loop (Newton, recovery of
u in blocks, resultants) and the whole run; and the floor of the run, measured on the
same stiffness right after it: assembly + the backend's factorization with its Schur
block + the block solves the run needs (65 right-hand sides in blocks of 32) + one
solve for the load. The ratio whole / floor is the overhead of everything else.

The time loop per level: ``benchmarks/bench_levels.py``.

``--example-5-5``, ``--n512``, ``--voronoi``: whole processes, wall time and peak memory
of the child: ``vemwear example 5.5`` (its reference solution computed, not read from a
cache), the 1/512 reference run (1,050,624 unknowns, 513 levels, u at 65 levels), and
Example 5.4's mesh B with 100,000 Voronoi cells instead of 2048 (mesh generation, 64
levels, u at 5 levels; figures and ParaView output off).

Usage::

    python benchmarks/bench_speed.py --reference --backends pardiso scipy --repeat 3
    python benchmarks/bench_speed.py --example-5-5 --n512 --voronoi --repeat 2
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np


def _problem(n: int, steps: int | None = None):
    from vemwear.contact import LinearCompliance
    from vemwear.mesh import rectangle_squares, tag_rectangle
    from vemwear.simulate import Problem, TimeGrid
    from vemwear.vem import Material

    mesh = tag_rectangle(rectangle_squares((2.0, 1.0), (2 * n, n)))
    return Problem(
        mesh,
        Material(4.0, 4.0),
        TimeGrid.uniform(1.0, steps or n),
        f1=(0.0, -0.06),
        p=LinearCompliance(0.4),
        g=0.1,
        mu=0.2,
        kappa=2.0,
        v_star=(1.0, 0.0),
    )


def reference_once(n: int, backend: str) -> dict[str, float]:
    from vemwear.simulate import SolverOptions, simulate
    from vemwear.solvers.backends import schur_factorize

    t0 = time.perf_counter()
    pr = _problem(n)
    t_mesh = time.perf_counter() - t0
    t1 = time.perf_counter()
    d = pr.discrete
    t_asm = time.perf_counter() - t1
    store = np.arange(65) / 64
    t2 = time.perf_counter()
    r = simulate(pr, SolverOptions("newton", backend=backend), store=store)
    t_run = time.perf_counter() - t2
    whole = t_mesh + t_asm + t_run
    # the floor on the same matrix: factorization + Schur, the block solves, a load solve
    s = d.system
    t3 = time.perf_counter()
    f = schur_factorize(s.K, s.contact_dofs.ravel(), s.dof_points, backend)
    t_fact = time.perf_counter() - t3
    B = np.random.default_rng(0).random((s.K.shape[0], 65))
    t4 = time.perf_counter()
    f.solve(B[:, :32])
    f.solve(B[:, 32:64])
    f.solve(B[:, 64])
    f.solve(B[:, 0])
    t_solves = time.perf_counter() - t4
    floor = t_asm + t_fact + t_solves
    tm = r.timings
    return {
        "mesh": t_mesh,
        "assembly": t_asm,
        "setup": tm["setup"],
        "loop": tm["time_loop"],
        "whole": whole,
        "floor": floor,
        "ratio": whole / floor,
        "max_wear": float(r.wear[-1].max()),
    }


def _stats(v: list[float]) -> str:
    return f"{min(v):6.2f} {statistics.median(v):6.2f} {max(v):6.2f}"


def reference_table(n: int, backends: list[str], repeat: int) -> None:
    print(f"Example 5.5 reference, h = k = 1/{n}, u at 65 levels (seconds, min med max)")
    cols = ["mesh", "assembly", "setup", "loop", "whole", "floor", "ratio"]
    rows: dict[str, dict[str, list[float]]] = {b: {c: [] for c in cols} for b in backends}
    wear: dict[str, float] = {}
    for _ in range(repeat):
        for b in backends:  # interleaved
            out = reference_once(n, b)
            for c in cols:
                rows[b][c].append(out[c])
            wear[b] = out["max_wear"]
    print(f"{'backend':>8} | " + " | ".join(f"{c:>20}" for c in cols))
    for b in backends:
        print(f"{b:>8} | " + " | ".join(f"{_stats(rows[b][c]):>20}" for c in cols))
    if len(wear) > 1:
        vals = list(wear.values())
        print(f"max wear at T: {vals[0]:.12g}; backends differ by {max(vals) - min(vals):.1e}")


def _child(cmd: list[str]) -> tuple[float, float, int]:
    t = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", _PEAK, *cmd], capture_output=True, text=True)
    wall = time.perf_counter() - t
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed: {proc.stderr.strip()[-400:]}")
    return wall, float(proc.stdout.strip().splitlines()[-1]) / 1024, proc.returncode


_PEAK = """
import sys
from vemwear.util.system import peak_memory
from vemwear.cli.main import main
code = main(sys.argv[1:])
print((peak_memory() // 1024))
sys.exit(code)
"""


def processes_table(example: bool, n512: bool, voronoi: bool, repeat: int) -> None:
    print("whole processes (wall s min med max; peak RSS MB of the child)")
    with tempfile.TemporaryDirectory() as d:
        cases: dict[str, list[str]] = {}
        if example:
            cases["vemwear example 5.5"] = [
                "example",
                "5.5",
                "-o",
                f"{d}/ex55",
                "--force",
                "--cache",
                f"{d}/cache-{{i}}",  # a new cache every time: the reference is computed
            ]
        if voronoi:
            from importlib.resources import files

            text = files("vemwear.examples").joinpath("example_5_4_voronoi.toml").read_text()
            text = text.replace("n_cells = 2048", "n_cells = 100000")
            text = text.replace("figures = true", "figures = false")
            text = text.replace("vtk = true", "vtk = false")
            cfg = os.path.join(d, "voronoi.toml")
            with open(cfg, "w") as fh:
                fh.write(text)
            cases["run Voronoi 100k cells"] = [
                "run",
                cfg,
                "-o",
                f"{d}/vor",
                "--force",
                "--no-progress",
            ]
        if n512:
            cfg = os.path.join(d, "n512.toml")
            with open(cfg, "w") as fh:
                fh.write(_N512)
            cases["run 1/512 (u at 65 levels)"] = [
                "run",
                cfg,
                "-o",
                f"{d}/n512",
                "--force",
                "--no-progress",
            ]
        walls: dict[str, list[float]] = {k: [] for k in cases}
        peaks: dict[str, float] = {}
        for i in range(repeat):
            for name, cmd in cases.items():
                w, peak, _ = _child([c.replace("{i}", str(i)) for c in cmd])
                walls[name].append(w)
                peaks[name] = max(peaks.get(name, 0.0), peak)
        for name in cases:
            print(f"{name:>28} | {_stats(walls[name]):>20} | {peaks[name]:8.0f} MB")


_N512 = (
    """title = "reference 1/512"
[mesh]
generator = "squares"
size = [2.0, 1.0]
divisions = [1024, 512]
[boundary]
clamped = "left"
traction = ["top", "right"]
contact = "bottom"
[material]
lam = 4.0
eta = 4.0
[loads]
f1 = [0.0, -0.06]
[contact]
p = { type = "linear", c = 0.4 }
g = 0.1
mu = 0.2
kappa = 2.0
v_star = [1.0, 0.0]
[time]
T = 1.0
steps = 512
[output]
figures = false
vtk = false
store_u = ["""
    + ", ".join(f"{i / 64!r}" for i in range(65))
    + """]
"""
)


def main() -> None:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--reference", action="store_true")
    ap.add_argument("--n", type=int, default=256)
    ap.add_argument("--backends", nargs="+", default=["pardiso", "scipy"])
    ap.add_argument("--example-5-5", action="store_true")
    ap.add_argument("--n512", action="store_true")
    ap.add_argument("--voronoi", action="store_true")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(f"machine: {os.cpu_count()} cores; python {sys.version.split()[0]}")
    from vemwear.util.heap import keep_freed_memory

    keep_freed_memory()  # in-process runs as in the command line's process
    if args.reference:
        reference_table(args.n, args.backends, args.repeat)
    if args.example_5_5 or args.n512 or args.voronoi:
        processes_table(args.example_5_5, args.n512, args.voronoi, args.repeat)


if __name__ == "__main__":
    main()
