"""Assembly of the stiffness for k = 1 and k = 2 on Voronoi meshes, against a floor.

Per mesh (100,000 and 10,000 Voronoi cells on 2 x 1 by default), interleaved ``--repeat``
times in one process after a warm-up call of each (the mesh's cached edges and groups
built, the memory of the process grown): ``vemwear.vem.stiffness`` (k = 1) and
``vemwear.vem.dofs2.stiffness2`` (k = 2), and the floor measured in the same run: one
``np.bincount`` over as many entries as the k = 2 local matrices have, into as many sums
as the k = 2 matrix has nonzeros (positions in increasing order: a pure streaming pass,
no element work, no pattern). Reported: min / median / max seconds, the ratios k = 2 / k = 1
of the minima (the reliable figure on a shared machine) and of the medians, k = 2 / floor
(medians), the nonzeros of both matrices.

Usage::

    python benchmarks/bench_k2.py
    python benchmarks/bench_k2.py --cells 100000 10000 --repeat 5
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np


def _stats(v: list[float]) -> str:
    return f"{min(v):.3f} / {statistics.median(v):.3f} / {max(v):.3f}"


def table(n_cells: int, repeat: int) -> None:
    from vemwear.mesh.registry import FAMILIES
    from vemwear.vem import Material
    from vemwear.vem.assembly import stiffness
    from vemwear.vem.dofs2 import stiffness2
    from vemwear.vem.local2 import local_dof_count

    mesh = FAMILIES["voronoi"].generate(size=(2.0, 1.0), n_cells=n_cells, seed=0)
    mat = Material(4.0, 4.0)
    entries = sum(len(v) * local_dof_count(n) ** 2 for n, (_i, v) in mesh.groups.items())
    A1, A2 = stiffness(mesh, mat), stiffness2(mesh, mat)  # warm-up
    rng = np.random.default_rng(0)
    pos = np.sort(rng.integers(0, A2.nnz, entries))
    w = rng.random(entries)
    t1, t2, tf = [], [], []
    for _ in range(repeat):
        t = time.perf_counter()
        A1 = stiffness(mesh, mat)
        t1.append(time.perf_counter() - t)
        t = time.perf_counter()
        A2 = stiffness2(mesh, mat)
        t2.append(time.perf_counter() - t)
        t = time.perf_counter()
        np.bincount(pos, weights=w, minlength=A2.nnz)
        tf.append(time.perf_counter() - t)
    med = statistics.median
    print(
        f"{n_cells:>8} | {_stats(t1):>21} | {_stats(t2):>21} | {_stats(tf):>21} | "
        f"{min(t2) / min(t1):>9.2f} | {med(t2) / med(t1):>9.2f} | {med(t2) / med(tf):>6.1f} | "
        f"{A1.nnz:>10} | {A2.nnz:>10} | {entries:>10}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--cells", type=int, nargs="+", default=[100_000, 10_000])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    print(f"machine: {os.cpu_count()} cores; python {sys.version.split()[0]}")
    print("assembly of the stiffness on Voronoi cells (seconds, min / median / max)")
    print(
        f"{'cells':>8} | {'k = 1':>21} | {'k = 2':>21} | {'floor (bincount)':>21} | "
        f"{'k2/k1 min':>9} | {'k2/k1 med':>9} | {'k2/flr':>6} | {'nnz k = 1':>10} | "
        f"{'nnz k = 2':>10} | {'entries k=2':>10}"
    )
    for n in args.cells:
        table(n, args.repeat)


if __name__ == "__main__":
    main()
