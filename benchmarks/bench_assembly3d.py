"""Speed of the 3D stiffness assembly (``vemwear.vem.local3d.stiffness3d``) against its floor.

For each mesh: the assembly of ``a_h`` (3.11) on all dofs (local matrices batched by
vertex count, scattered once), and in the same invocation its floor, the scatter
alone: the same triplets (row, column, value) turned into a CSR matrix with duplicates
summed, which no assembly can avoid. Both are timed ``--repeat`` times, interleaved
(every mesh's assembly, then its floor, then again), and printed as min / median /
max with the median ratio. The meshes are made once, before any timing; the process
keeps freed memory as a run's does (:func:`vemwear.util.heap.keep_freed_memory`).

Run it with ``PYTHONPATH`` pointing at another source tree to compare two versions of
the library on the same machine state (the floor is the same code in both).

Usage::

    python benchmarks/bench_assembly3d.py --repeat 5
    python benchmarks/bench_assembly3d.py --meshes hex64 vor3000 --repeat 3
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any

#: name -> (family, keyword arguments of generate_mesh3d)
MESHES: dict[str, tuple[str, dict[str, Any]]] = {
    "hex32": ("hexahedra", {"divisions": (32, 16, 16)}),
    "hex64": ("hexahedra", {"divisions": (64, 32, 32)}),
    "tet16": ("tetrahedra", {"divisions": (16, 8, 8)}),
    "prism": ("prisms", {"cells": 2000, "seed": 0}),
    "vor1000": ("voronoi3d", {"cells": 1000, "seed": 0}),
    "vor3000": ("voronoi3d", {"cells": 3000, "seed": 0}),
}


def floor_input(mesh: Any) -> tuple[Any, Any, Any, int]:
    """The triplets of the assembled matrix (the local matrices' positions, with
    random values): what the scatter of any assembly receives."""
    import numpy as np

    from vemwear.vem.local3d import cell_geometry

    cg = cell_geometry(mesh)
    rows, cols = [], []
    for n, (_ids, slots) in cg.groups().items():
        v = cg.vertices[slots]
        d = (3 * v[:, :, None] + np.arange(3)).reshape(len(v), 3 * n).astype(np.int32)
        rows.append(np.repeat(d, 3 * n, axis=1).ravel())
        cols.append(np.tile(d, (1, 3 * n)).ravel())
    r, c = np.concatenate(rows), np.concatenate(cols)
    return r, c, np.random.default_rng(0).random(len(r)), 3 * mesh.n_points


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--meshes", nargs="+", default=["hex32", "tet16", "prism", "vor1000"])
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args(argv)
    import scipy.sparse as sp

    from vemwear.mesh.registry3d import generate_mesh3d
    from vemwear.util.heap import keep_freed_memory
    from vemwear.vem.local import Material
    from vemwear.vem.local3d import stiffness3d

    keep_freed_memory()  # as a run's process does
    material = Material(4.0, 4.0)
    meshes = {name: generate_mesh3d(MESHES[name][0], **MESHES[name][1]) for name in a.meshes}
    floors = {name: floor_input(m) for name, m in meshes.items()}
    times: dict[tuple[str, str], list[float]] = {}
    for _ in range(a.repeat):
        for name, mesh in meshes.items():
            t = time.perf_counter()
            stiffness3d(mesh, material)
            times.setdefault((name, "assembly"), []).append(time.perf_counter() - t)
            r, c, v, n = floors[name]
            t = time.perf_counter()
            A = sp.coo_matrix((v, (r, c)), shape=(n, n)).tocsr()
            A.sum_duplicates()
            times.setdefault((name, "floor"), []).append(time.perf_counter() - t)

    def mmm(x: list[float]) -> str:
        return f"{min(x):7.3f} {statistics.median(x):7.3f} {max(x):7.3f}"

    print(
        f"{'mesh':>8} {'cells':>7} | {'assembly s (min med max)':>23} | "
        f"{'floor s (min med max)':>23} | ratio | us/cell"
    )
    for name, mesh in meshes.items():
        ta, tf = times[(name, "assembly")], times[(name, "floor")]
        ratio = statistics.median(ta) / statistics.median(tf)
        per = 1e6 * statistics.median(ta) / mesh.n_cells
        print(f"{name:>8} {mesh.n_cells:>7} | {mmm(ta)} | {mmm(tf)} | {ratio:5.2f} | {per:7.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
