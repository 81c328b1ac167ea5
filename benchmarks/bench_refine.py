"""Local refinement on an adaptive mesh: the array-based refine_cells against the loop.

The mesh: Example 5.2's 32 x 16 squares (``vemwear.paper.ex52.mesh``), refined in graded
rounds (``refine_graded``, one level difference at most between neighbours) of a
random third of the cells until it has ``--cells`` cells or more, so that it carries
hanging nodes of several levels and tagged boundary parts. On it, interleaved
``--repeat`` times in one process after a warm-up of each case:

* **loop**: the loop over cells and sides that ``refine_cells`` was before, kept in
  ``tests/refine_reference.py`` (loaded from there by path) as the reference of the
  tests;
* **arrays**: ``vemwear.mesh.refine.refine_cells``;
* **floor**: building the refined mesh from its final arrays (``Mesh(points, offsets,
  vertices)`` with its boundary edges, then the tags), the part no refinement avoids.

Each case refines the same random half of the cells (``return_parent=True``, as the
adaptive runs call it) on a mesh whose cached geometry (cell batches, edges, diameters)
is warm, as after a solve on it; ``--cold`` rebuilds the mesh before every call. The
two results are checked to be bitwise equal. Reported: milliseconds as min / median /
max and the ratios of the medians.

Usage::

    python benchmarks/bench_refine.py
    python benchmarks/bench_refine.py --cells 16000 --repeat 9 --cold
"""

from __future__ import annotations

import argparse
import importlib.util
import statistics
import time
from pathlib import Path

import numpy as np

from vemwear.mesh.adapt import refine_graded
from vemwear.mesh.polymesh import Mesh
from vemwear.mesh.refine import refine_cells
from vemwear.paper import ex52

_REF = Path(__file__).resolve().parents[1] / "tests" / "refine_reference.py"


def _reference():  # the loop-based refine_cells of tests/refine_reference.py
    spec = importlib.util.spec_from_file_location("refine_reference", _REF)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.refine_cells_reference


def adaptive_mesh(cells: int, seed: int = 0) -> Mesh:
    """Example 5.2's mesh refined in graded rounds of a random third of the cells."""
    rng = np.random.default_rng(seed)
    mesh = ex52.mesh((32, 16))
    level = np.zeros(mesh.n_cells, dtype=np.int64)
    while mesh.n_cells < cells:
        marked = rng.choice(mesh.n_cells, size=mesh.n_cells // 3, replace=False)
        mesh, level, _ = refine_graded(mesh, level, marked)
    return mesh


def _fresh(mesh: Mesh) -> Mesh:
    return Mesh(mesh.points, mesh.cell_offsets, mesh.cell_vertices, mesh.boundary_tags)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--cells", type=int, default=4000, help="cells of the mesh (at least)")
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--cold", action="store_true", help="a new mesh object before each call")
    a = ap.parse_args(argv)
    loop = _reference()
    mesh = adaptive_mesh(a.cells)
    sel = np.random.default_rng(1).choice(mesh.n_cells, size=mesh.n_cells // 2, replace=False)
    new, parent = refine_cells(mesh, sel, return_parent=True)
    old, old_parent = loop(mesh, sel, return_parent=True)
    for name in ("points", "cell_offsets", "cell_vertices", "boundary_tags"):
        if not np.array_equal(getattr(new, name), getattr(old, name)):
            raise SystemExit(f"the two refinements differ in {name}")
    if not np.array_equal(parent, old_parent) or new.part_names != old.part_names:
        raise SystemExit("the two refinements differ in their parents or part names")

    def floor(m: Mesh) -> None:
        out = Mesh(new.points, new.cell_offsets, new.cell_vertices)
        out.with_tags(new.boundary_tags)

    cases = {
        "loop": lambda m: loop(m, sel, return_parent=True),
        "arrays": lambda m: refine_cells(m, sel, return_parent=True),
        "floor": floor,
    }
    times: dict[str, list[float]] = {k: [] for k in cases}
    for _ in range(a.repeat):
        for name, fn in cases.items():
            m = _fresh(mesh) if a.cold else mesh
            t0 = time.perf_counter()
            fn(m)
            times[name].append(1e3 * (time.perf_counter() - t0))
    hanging = int(np.sum(mesh.cell_sizes > 4))
    print(
        f"mesh: {mesh.n_cells} cells ({hanging} with hanging nodes), {mesh.n_points} vertices;"
        f" refining {sel.size} cells -> {new.n_cells} cells; repeats {a.repeat},"
        f" {'cold' if a.cold else 'warm'} mesh caches"
    )
    print(f"{'case':>8} | {'min ms':>8} {'median':>8} {'max':>8}")
    med = {k: statistics.median(v) for k, v in times.items()}
    for name, v in times.items():
        print(f"{name:>8} | {min(v):8.2f} {med[name]:8.2f} {max(v):8.2f}")
    print(
        f"loop / arrays (medians): {med['loop'] / med['arrays']:.1f}x;"
        f" arrays / floor: {med['arrays'] / med['floor']:.1f}x"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
