"""Speed and memory of 3D contact with wear.

The 3D analogue of Section 5: Omega = (0, 2) x (0, 1) x (0, 1), clamped at x = 0,
contact on z = 0, traction-free elsewhere, f1 = (0, 0, -0.06), v* = (1, 0, 0),
lambda = eta = 4, p(r) = 0.4 r+, g = 0.1, mu = 0.2, kappa = 2, T = 1; condensed
semismooth Newton, the displacement recovered at the final level only
(``store="final"``).

Cases: hexahedra 8 x 4 x 4, 16 x 8 x 8, 32 x 16 x 16 and 64 x 32 x 32 cells with 64
steps (``hex8`` ... ``hex64``), centroidal Voronoi polyhedra of the box with 1000 and
8000 cells with 32 steps (``vor1000``, ``vor8000``).

Each run is a child process, so that its peak memory (``VmHWM``, from
:func:`vemwear.util.system.peak_memory`) is its own; with ``--repeat`` > 1 the runs
are interleaved (every case once, then again) and the times given as min, median,
max. Reported per case: the unknowns (free dofs), the contact nodes, the backend
``--backend`` resolved to, and in seconds: mesh (generation, side tags, problem),
assembly (the stiffness on the free dofs), setup (ordering, factorization and the
dense Schur block on the contact dofs; the three parts are given in a second
table), the time loop, their sum; the peak memory of the child (MB) and the largest
wear at T, which must agree across backends.

Usage::

    python benchmarks/bench_3d.py                                  # every case, once
    python benchmarks/bench_3d.py --cases hex8 hex16 hex32 hex64 --repeat 1
    python benchmarks/bench_3d.py --cases hex32 --backend scipy
    python benchmarks/bench_3d.py --cases vor1000 vor8000 --repeat 3
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from typing import Any

SIDES = {"clamped": "xmin", "contact": "zmin", "traction": ["xmax", "ymin", "ymax", "zmax"]}

#: name -> (family, cells: divisions or a count, steps)
CASES: dict[str, tuple[str, tuple[int, ...], int]] = {
    "hex8": ("hexahedra", (8, 4, 4), 64),
    "hex16": ("hexahedra", (16, 8, 8), 64),
    "hex32": ("hexahedra", (32, 16, 16), 64),
    "hex64": ("hexahedra", (64, 32, 32), 64),
    "vor1000": ("voronoi", (1000,), 32),
    "vor8000": ("voronoi", (8000,), 32),
}

TIMES = ["mesh", "assembly", "setup", "loop", "total"]
SETUP = ["ordering", "factorization", "schur"]


def run_case(name: str, backend: str) -> dict[str, Any]:
    """One whole run in this process: the timings, sizes, max wear and peak memory."""
    from vemwear.contact import LinearCompliance
    from vemwear.mesh.generate3d import box_hexahedra, tag_box
    from vemwear.mesh.voronoi3d import box_voronoi
    from vemwear.simulate import Problem, SolverOptions, TimeGrid, simulate
    from vemwear.util.system import peak_memory
    from vemwear.vem import Material

    family, cells, steps = CASES[name]
    t0 = time.perf_counter()
    if family == "hexahedra":
        nx, ny, nz = cells
        mesh = box_hexahedra((2.0, 1.0, 1.0), (nx, ny, nz))
    else:
        mesh = box_voronoi((2.0, 1.0, 1.0), cells[0], seed=0)
    pr = Problem(
        tag_box(mesh, SIDES),
        Material(4.0, 4.0),
        TimeGrid.uniform(1.0, steps),
        f1=(0.0, 0.0, -0.06),
        p=LinearCompliance(0.4),
        g=0.1,
        mu=0.2,
        kappa=2.0,
        v_star=(1.0, 0.0, 0.0),
    )
    t_mesh = time.perf_counter() - t0
    t1 = time.perf_counter()
    d = pr.discrete
    t_asm = time.perf_counter() - t1
    opts = SolverOptions("newton", backend=backend)
    r = simulate(pr, opts, store="final")
    tm = r.timings
    factor = getattr(d.step_solver(opts), "factor", None)
    return {
        "cells": int(mesh.n_cells),
        "dofs": int(d.system.K.shape[0]),
        "contact": int(d.system.m),
        "steps": steps,
        "backend": str(getattr(factor, "name", "?")),
        "mesh": t_mesh,
        "assembly": t_asm,
        "setup": tm["setup"],
        "ordering": tm.get("setup_ordering", float("nan")),
        "factorization": tm.get("setup_factorization", float("nan")),
        "schur": tm.get("setup_schur", float("nan")),
        "loop": tm["time_loop"],
        "total": t_mesh + t_asm + tm["setup"] + tm["time_loop"],
        "max_wear": float(r.wear[-1].max()),
        "peak_mb": peak_memory() / 2**20,
    }


def _child(name: str, backend: str) -> dict[str, Any]:
    """``run_case`` in a new interpreter: its peak memory is that of this case alone."""
    cmd = [sys.executable, os.path.abspath(__file__), "--child", name, "--backend", backend]
    t = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t
    if proc.returncode != 0:
        raise SystemExit(f"case {name} ({backend}) failed:\n{proc.stderr.strip()[-2000:]}")
    out: dict[str, Any] = json.loads(proc.stdout.strip().splitlines()[-1])
    out["wall"] = wall
    return out


def _stats(v: list[float], repeat: int) -> str:
    if repeat == 1:
        return f"{v[0]:7.2f}"
    return f"{min(v):7.2f} {statistics.median(v):7.2f} {max(v):7.2f}"


def _machine() -> str:
    import numpy as np
    import scipy

    from vemwear.solvers.backends import available_backends
    from vemwear.util.system import available_memory

    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    return (
        f"machine: {os.cpu_count()} cores, load average {load}, "
        f"{available_memory() / 2**30:.1f} GB available; python {sys.version.split()[0]}, "
        f"numpy {np.__version__}, scipy {scipy.__version__}; "
        f"backends installed: {', '.join(available_backends())}"
    )


def table(names: list[str], backend: str, repeat: int) -> None:
    rows: dict[str, list[dict[str, Any]]] = {n: [] for n in names}
    for _ in range(repeat):
        for n in names:  # interleaved
            rows[n].append(_child(n, backend))
            print(f"  done {n} ({rows[n][-1]['wall']:.1f} s wall)", file=sys.stderr, flush=True)
    what = "s" if repeat == 1 else "s, min med max"
    print(f"3D contact with wear, --backend {backend}, {repeat} run(s) per case ({what})")
    w = 7 if repeat == 1 else 23
    head = f"{'case':>8} {'cells':>7} {'steps':>5} {'dofs':>8} {'contact':>7} {'backend':>8} | "
    print(
        head + " | ".join(f"{c:>{max(w, len(c))}}" for c in TIMES) + f" | {'peak MB':>8} | max wear"
    )
    for n in names:
        rs = rows[n]
        r0 = rs[0]
        line = (
            f"{n:>8} {r0['cells']:>7} {r0['steps']:>5} {r0['dofs']:>8} {r0['contact']:>7} "
            f"{r0['backend']:>8} | "
        )
        line += " | ".join(
            f"{_stats([float(r[c]) for r in rs], repeat):>{max(w, len(c))}}" for c in TIMES
        )
        peak = max(float(r["peak_mb"]) for r in rs)
        wear = {float(r["max_wear"]) for r in rs}
        print(line + f" | {peak:8.0f} | {min(wear):.10g}" + ("" if len(wear) == 1 else " (!)"))
    print(f"setup split ({what})")
    print(f"{'case':>8} | " + " | ".join(f"{c:>{max(w, len(c))}}" for c in SETUP))
    for n in names:
        rs = rows[n]
        print(
            f"{n:>8} | "
            + " | ".join(
                f"{_stats([float(r[c]) for r in rs], repeat):>{max(w, len(c))}}" for c in SETUP
            )
        )


def main() -> None:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--cases", nargs="+", choices=list(CASES), default=list(CASES))
    ap.add_argument("--backend", choices=["auto", "scipy", "pardiso"], default="auto")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--child", choices=list(CASES), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(json.dumps(run_case(args.child, args.backend)))
        return
    print(_machine())
    table(args.cases, args.backend, args.repeat)
    print(f"load average after: {', '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
