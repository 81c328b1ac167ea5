"""Local refinement on adaptive meshes: the array-based refine_cells against the loop.

The meshes: Example 5.2's 32 x 16 squares (``vemwear.paper.ex52.mesh``) refined in
graded rounds (``graded_closure``: neighbours one level apart at most) of a random
twelfth of the cells, marked anew each round, until the mesh has ``--cells`` cells or
more (6 rounds to 4076 cells by default), with hanging nodes of several levels and
tagged boundary parts. Two workloads:

* **half**: refine a random half of the cells of the last mesh (``return_parent=True``,
  as the adaptive runs call it);
* **rounds**: the refinements of all the graded rounds that built it, one after the
  other (the refinement part of an adaptive run's passes).

Each is timed, interleaved ``--repeat`` times in one process after a warm-up, for:

* **loop**: the loop over cells and sides that ``refine_cells`` was before, kept in
  ``tests/refine_reference.py`` (loaded from there by path) as the reference of the
  tests;
* **arrays**: ``vemwear.mesh.refine.refine_cells``;
* **floor**: building the refined meshes from their final arrays (``Mesh(points,
  offsets, vertices)``, which finds the boundary edges, then the tags), the part no
  refinement avoids.

The meshes' cached geometry (cell batches, edges, diameters) is warm, as after a solve
on them; ``--cold`` rebuilds every mesh before each call. The results of loop and arrays
are checked to be equal to the bit first. Reported: milliseconds as min / median / max
and the ratios of the medians.

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

from vemwear.mesh.adapt import graded_closure, refine_graded
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


def adaptive_rounds(cells: int, seed: int = 0) -> list[tuple[Mesh, np.ndarray]]:
    """The graded rounds from Example 5.2's mesh to ``cells`` cells or more: (mesh, cells
    refined in it) for every round, then (the last mesh, a random half of its cells)."""
    rng = np.random.default_rng(seed)
    mesh = ex52.mesh((32, 16))
    level = np.zeros(mesh.n_cells, dtype=np.int64)
    out = []
    while mesh.n_cells < cells:
        marked = rng.choice(mesh.n_cells, size=mesh.n_cells // 12, replace=False)
        out.append((mesh, graded_closure(mesh, level, marked)))
        mesh, level, _ = refine_graded(mesh, level, marked)
    half = rng.choice(mesh.n_cells, size=mesh.n_cells // 2, replace=False)
    return [*out, (mesh, half)]


def _fresh(mesh: Mesh) -> Mesh:
    return Mesh(mesh.points, mesh.cell_offsets, mesh.cell_vertices, mesh.boundary_tags)


def _same(a: tuple[Mesh, np.ndarray], b: tuple[Mesh, np.ndarray]) -> None:
    for name in ("points", "cell_offsets", "cell_vertices", "boundary_tags"):
        if not np.array_equal(getattr(a[0], name), getattr(b[0], name)):
            raise SystemExit(f"the two refinements differ in {name}")
    if not np.array_equal(a[1], b[1]) or a[0].part_names != b[0].part_names:
        raise SystemExit("the two refinements differ in their parents or part names")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--cells", type=int, default=4000, help="cells of the last mesh (at least)")
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--cold", action="store_true", help="new mesh objects before each call")
    a = ap.parse_args(argv)
    loop = _reference()
    work = adaptive_rounds(a.cells)
    results = [refine_cells(m, c, return_parent=True) for m, c in work]
    for (m, c), res in zip(work, results, strict=True):
        _same(res, loop(m, c, return_parent=True))
    workloads = {"half": [len(work) - 1], "rounds": list(range(len(work) - 1))}

    def inputs() -> list[tuple[Mesh, np.ndarray]]:
        return [(_fresh(m), c) for m, c in work] if a.cold else work

    def floor(m: Mesh, c: np.ndarray, k: int) -> None:
        new = results[k][0]
        Mesh(new.points, new.cell_offsets, new.cell_vertices).with_tags(new.boundary_tags)

    cases = {
        "loop": lambda m, c, k: loop(m, c, return_parent=True),
        "arrays": lambda m, c, k: refine_cells(m, c, return_parent=True),
        "floor": floor,
    }
    times = {(w, name): [] for w in workloads for name in cases}
    for rep in range(a.repeat + 1):  # the first is a warm-up
        for w, idx in workloads.items():
            for name, fn in cases.items():
                args = inputs()
                t0 = time.perf_counter()
                for k in idx:
                    fn(args[k][0], args[k][1], k)
                if rep:
                    times[w, name].append(1e3 * (time.perf_counter() - t0))
    last, half = work[-1]
    sizes = [m.n_cells for m, _ in work]
    print(
        f"rounds: {' -> '.join(map(str, sizes))} cells ({len(work) - 1} graded rounds,"
        f" {sum(c.size for _, c in work[:-1])} cells refined); half: {half.size} of the"
        f" {last.n_cells} cells ({int(np.sum(last.cell_sizes > 4))} with hanging nodes)"
        f" -> {results[-1][0].n_cells} cells"
    )
    print(f"repeats {a.repeat}, {'cold' if a.cold else 'warm'} mesh caches")
    print(f"{'workload':>8} {'case':>7} | {'min ms':>8} {'median':>8} {'max':>8}")
    for w in workloads:
        med = {n: statistics.median(times[w, n]) for n in cases}
        for n in cases:
            v = times[w, n]
            print(f"{w:>8} {n:>7} | {min(v):8.2f} {med[n]:8.2f} {max(v):8.2f}")
        print(
            f"{w:>8} loop / arrays {med['loop'] / med['arrays']:.1f}x,"
            f" arrays / floor {med['arrays'] / med['floor']:.1f}x (medians)"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
