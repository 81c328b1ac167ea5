"""Time and memory of the polyhedral mesher against its floor, Qhull's Voronoi diagram.

For each cell count: ``box_voronoi((2, 1, 1), n, seed=0)`` with the default 4 Lloyd
iterations (five Voronoi diagrams of the seeds and their mirrors) in a child process
of its own, so that its peak memory (``VmHWM``, :func:`vemwear.util.system.peak_memory`)
is the mesher's; the same child then times the floor, :class:`scipy.spatial.Voronoi`
of the mesh's ``n`` seeds (one diagram, not clipped, no cells built). Repeats are
interleaved (every size once, then again); times are given as min / median / max.

Usage::

    python benchmarks/bench_mesher3d.py                       # 1000, 3000, 10000 cells
    python benchmarks/bench_mesher3d.py --cells 10000 --repeat 5
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

SIZE = (2.0, 1.0, 1.0)


def run_case(n: int) -> dict[str, Any]:
    """The mesher, its peak memory, then the floor, in this process."""
    import numpy as np
    from scipy.spatial import Voronoi

    from vemwear.mesh.voronoi3d import box_voronoi, halton
    from vemwear.util.system import peak_memory

    t = time.perf_counter()
    mesh = box_voronoi(SIZE, n, seed=0)
    mesher = time.perf_counter() - t
    peak = peak_memory() / 2**20
    seeds = np.asarray(SIZE) * halton(n, 3, 0)
    t = time.perf_counter()
    Voronoi(seeds)
    floor = time.perf_counter() - t
    return {
        "cells": mesh.n_cells,
        "points": mesh.n_points,
        "faces": mesh.n_faces,
        "mesher": mesher,
        "floor": floor,
        "peak_mb": peak,
    }


def _child(n: int) -> dict[str, Any]:
    cmd = [sys.executable, os.path.abspath(__file__), "--child", str(n)]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"{n} cells failed:\n{proc.stderr.strip()[-2000:]}")
    out: dict[str, Any] = json.loads(proc.stdout.strip().splitlines()[-1])
    return out


def _mmm(v: list[float]) -> str:
    return f"{min(v):7.2f} {statistics.median(v):7.2f} {max(v):7.2f}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--cells", type=int, nargs="+", default=[1000, 3000, 10_000])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--child", type=int, help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.child is not None:
        print(json.dumps(run_case(a.child)))
        return 0
    runs: dict[int, list[dict[str, Any]]] = {n: [] for n in a.cells}
    for _ in range(a.repeat):  # interleaved over the sizes
        for n in a.cells:
            runs[n].append(_child(n))
    print(f"box (2, 1, 1), 4 Lloyd iterations; min / median / max of {a.repeat} runs")
    print(
        f"{'cells':>6} {'points':>7} {'faces':>7} | {'mesher [s]':^23} | "
        f"{'floor: qhull Voronoi [s]':^23} | {'ratio':>5} | {'peak MB':^23}"
    )
    for rs in runs.values():
        m = [r["mesher"] for r in rs]
        f = [r["floor"] for r in rs]
        ratio = statistics.median(x / y for x, y in zip(m, f, strict=True))
        r0 = rs[0]
        print(
            f"{r0['cells']:6d} {r0['points']:7d} {r0['faces']:7d} | {_mmm(m)} | {_mmm(f)} | "
            f"{ratio:5.1f} | {_mmm([r['peak_mb'] for r in rs])}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
