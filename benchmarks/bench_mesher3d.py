"""Time and memory of the polyhedral mesher against its floor, Qhull's Voronoi diagram.

For each cell count: ``box_voronoi((2, 1, 1), n, seed=0)`` with the default 4 Lloyd
iterations (five Voronoi diagrams of the seeds and their mirrors) in a child process
of its own, so that its peak memory (``VmHWM``, :func:`vemwear.util.system.peak_memory`)
is the mesher's; the same child then times the floor, :class:`scipy.spatial.Voronoi`
of the mesh's ``n`` seeds (one diagram, not clipped, no cells built). Wall and CPU
seconds of the child are given (the CPU time of the process is less disturbed by other
work on a shared machine). Repeats are interleaved (every size once, then again);
times are given as min / median / max, the ratio to the floor as the median of the
runs' ratios. ``--src DIR ...`` runs the mesher of other source trees (the ``src`` of an
export of an earlier commit: ``git archive COMMIT src | tar -x -C DIR``) interleaved
with this one, for a before/after table from one run.

Usage::

    python benchmarks/bench_mesher3d.py                       # 1000, 3000, 10000 cells
    python benchmarks/bench_mesher3d.py --cells 10000 --repeat 5
    python benchmarks/bench_mesher3d.py --src /tmp/before/src src
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

    t, c = time.perf_counter(), time.process_time()
    mesh = box_voronoi(SIZE, n, seed=0)
    mesher, mesher_cpu = time.perf_counter() - t, time.process_time() - c
    peak = peak_memory() / 2**20
    seeds = np.asarray(SIZE) * halton(n, 3, 0)
    t, c = time.perf_counter(), time.process_time()
    Voronoi(seeds)
    floor, floor_cpu = time.perf_counter() - t, time.process_time() - c
    return {
        "cells": mesh.n_cells,
        "points": mesh.n_points,
        "faces": mesh.n_faces,
        "mesher": mesher,
        "floor": floor,
        "mesher_cpu": mesher_cpu,
        "floor_cpu": floor_cpu,
        "peak_mb": peak,
    }


def _child(n: int, src: str | None) -> dict[str, Any]:
    cmd = [sys.executable, os.path.abspath(__file__), "--child", str(n)]
    env = dict(os.environ)
    if src is not None:
        env["PYTHONPATH"] = os.path.abspath(src)
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
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
    ap.add_argument("--src", nargs="+", help="source trees to compare (default: as imported)")
    ap.add_argument("--child", type=int, help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.child is not None:
        print(json.dumps(run_case(a.child)))
        return 0
    trees: list[str | None] = list(a.src) if a.src else [None]
    runs: dict[tuple[str | None, int], list[dict[str, Any]]] = {
        (s, n): [] for s in trees for n in a.cells
    }
    for _ in range(a.repeat):  # interleaved over the sizes and source trees
        for n in a.cells:
            for s in trees:
                runs[(s, n)].append(_child(n, s))
    print(f"box (2, 1, 1), 4 Lloyd iterations; min / median / max of {a.repeat} runs")
    for what, key in (("wall", ""), ("CPU", "_cpu")):
        print(
            f"\n{'source':<22} {'cells':>6} {'points':>7} | {what + ' mesher [s]':^23} | "
            f"{what + ' floor: qhull Voronoi':^23} | {'ratio':>5} | {'peak MB':^23}"
        )
        for (s, _n), rs in runs.items():
            m = [r["mesher" + key] for r in rs]
            f = [r["floor" + key] for r in rs]
            ratio = statistics.median(x / y for x, y in zip(m, f, strict=True))
            r0 = rs[0]
            print(
                f"{(s or '(imported)')[-22:]:<22} {r0['cells']:6d} {r0['points']:7d} | "
                f"{_mmm(m)} | {_mmm(f)} | {ratio:5.1f} | {_mmm([r['peak_mb'] for r in rs])}"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
