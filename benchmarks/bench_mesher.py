"""Time and quality of the centroidal Voronoi mesher.

For each cell count: the wall time of ``rectangle_voronoi((2, 1), n, seed)`` with
the default Lloyd iterations (min / median / max over ``--repeat`` interleaved
runs, seeds 0, 1, ...), then the quality report (:func:`vemwear.mesh.quality_report`:
``rho_K / h_K``, minimum vertex distance / ``h_K``, ``|K| / h_K^2``) of the mesh of
seed 0, and the same for the L-shaped domain with ``--lshape``.

Usage::

    python benchmarks/bench_mesher.py --cells 1000 10000 100000 --repeat 3
"""

from __future__ import annotations

import argparse
import statistics
import time


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--cells", type=int, nargs="+", default=[1000, 10_000, 100_000])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--lshape", action="store_true", help="also the L-shaped domain")
    a = ap.parse_args(argv)
    from vemwear.mesh import l_shape_domain, quality_report, rectangle_domain, voronoi_mesh

    domains = {"rectangle 2x1": rectangle_domain((2.0, 1.0))}
    if a.lshape:
        domains["L-shape"] = l_shape_domain((2.0, 2.0), (1.0, 1.0))
    times: dict[tuple[str, int], list[float]] = {}
    meshes = {}
    for r in range(a.repeat):  # interleaved over sizes and domains
        for dname, dom in domains.items():
            for n in a.cells:
                t = time.perf_counter()
                mesh = voronoi_mesh(dom, n, seed=r)
                times.setdefault((dname, n), []).append(time.perf_counter() - t)
                assert mesh.n_cells == n
                if r == 0:
                    meshes[(dname, n)] = mesh
    print(f"{'domain':<14} {'cells':>7} {'min [s]':>8} {'median':>8} {'max':>8}")
    for (dname, n), v in times.items():
        print(f"{dname:<14} {n:7d} {min(v):8.2f} {statistics.median(v):8.2f} {max(v):8.2f}")
    for (dname, n), mesh in meshes.items():
        print(f"\n{dname}, {n} cells, seed 0:")
        print(quality_report(mesh))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
