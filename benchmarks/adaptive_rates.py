"""Effectivity of the residual estimator and convergence rates of adaptive meshes
(docs/method.md, section 11).

Tables printed:

1. **Effectivity** eta / ||u - Pi u_h||_E (energy norm):
   - the manufactured solution of :mod:`vemwear.paper.manufactured` (no contact, exact
     gradient) on four mesh families;
   - the 2D Hertz line contact of :mod:`vemwear.paper.hertz` (load control, Signorini)
     against the same mesh refined uniformly three times;
2. **Error against dofs**, uniform and adaptive (theta = 0.5, neighbours within one
   level), both against a uniform reference of h = 1/``--reference``:
   - ``corner``: Example 5.2's data (mu = 0.2), one step, no wear: the step problem of
     Example 5.5, whose clamped side meets Gamma_C and Gamma_N at singular corners;
   - ``lshape``: the same data on (0, 2) x (0, 1) without (1, 2) x (1/2, 1): a re-entrant
     corner with traction-free sides.

   The rate is the least-squares slope of log(error) against log(N) (N the dofs): -k/2
   is optimal for the space of order k (``--order``, 1 or 2). The adaptive rate is fitted over the passes with N up to the
   dofs of the uniform h = 1/32 mesh (cells no finer than h = 1/``2 * cap``, so the
   reference is at least one level finer everywhere).

Usage::

    python benchmarks/adaptive_rates.py                 # reference h = 1/256
    python benchmarks/adaptive_rates.py --reference 128 --quick
    python benchmarks/adaptive_rates.py --order 2 --reference 128
"""

from __future__ import annotations

import argparse
import dataclasses
import math
from collections.abc import Callable
from typing import Any

import numpy as np

from vemwear import simulate
from vemwear.mesh import Mesh, rectangle_squares
from vemwear.mesh.refine import refine_cells
from vemwear.paper import ex52
from vemwear.paper import manufactured as M
from vemwear.paper.hertz import line_contact
from vemwear.post.energy import (
    energy_error_exact,
    energy_error_exact2,
    energy_error_reference,
    energy_error_reference2,
)
from vemwear.simulate import Problem
from vemwear.simulate.adapt import adapt
from vemwear.simulate.estimate import estimate
from vemwear.vem import Material
from vemwear.vem.estimator import elasticity_terms
from vemwear.vem.estimator2 import elasticity_terms2

#: The order of the space of every run (``--order``).
ORDER = 1


def _u(result: Any) -> np.ndarray:
    """The displacement of the last level the estimator and the errors read: the vertex
    values for k = 1, every dof for k = 2."""
    return result.u[-1] if result.dofs is None else result.dofs[-1]


def _error_sq(pr: Problem, u: np.ndarray, ref: Problem, u_ref: np.ndarray) -> float:
    f = energy_error_reference2 if ORDER == 2 else energy_error_reference
    return float(f(pr.mesh, pr.material, u, ref.mesh, u_ref).sum())


def lshape_mesh(n: int) -> Mesh:
    """(0, 2) x (0, 1) without (1, 2) x (1/2, 1) in squares of side 1/n; clamped at x = 0,
    contact at y = 0, traction-free elsewhere."""
    m = rectangle_squares((2.0, 1.0), (2 * n, n))
    sizes = m.cell_sizes
    centre = np.zeros((m.n_cells, 2))
    np.add.at(centre, m.edge_cells, m.points[m.cell_vertices])
    centre /= sizes[:, None]
    keep = ~((centre[:, 0] > 1.0) & (centre[:, 1] > 0.5))
    cells = np.asarray(m.cell_vertices).reshape(-1, 4)[keep]
    used = np.unique(cells)
    new = np.full(m.n_points, -1, dtype=np.int64)
    new[used] = np.arange(len(used))
    mesh = Mesh.from_cells(m.points[used], new[cells])
    tol = 1e-9
    return mesh.with_boundary(
        {
            "clamped": lambda x: x[:, 0] < tol,
            "contact": lambda x: x[:, 1] < tol,
            "traction": "rest",
        }
    )


def corner(n: int) -> Problem:
    pr = ex52.problem(0.2, 0.0, divisions=(2 * n, n), steps=1)
    return dataclasses.replace(pr, order=ORDER)


def lshape(n: int) -> Problem:
    pr = ex52.problem(0.2, 0.0, steps=1, tagged_mesh=lshape_mesh(n))
    return dataclasses.replace(pr, order=ORDER)


CASES: dict[str, Callable[[int], Problem]] = {"corner": corner, "lshape": lshape}


def slope(N: list[int], e: list[float]) -> float:
    return float(np.polyfit(np.log(N), np.log(e), 1)[0])


def effectivity_manufactured(quick: bool) -> list[tuple[str, ...]]:
    mat = Material(M.LAM, M.ETA)
    rows = []
    for fam in ("squares", "voronoi", "hanging", "distorted"):
        for n in (8, 16) if quick else (8, 16, 32):
            mesh = M.family_mesh(fam, n)
            if ORDER == 2:
                U = M.solve2(mesh)
                terms, _ = elasticity_terms2(mesh, mat, U, M.body_force, {"traction": M.traction})
                e2 = energy_error_exact2(mesh, mat, U, M.exact_gradient)
            else:
                U = M.solve(mesh)
                terms, _ = elasticity_terms(mesh, mat, U, M.body_force, {"traction": M.traction})
                e2 = energy_error_exact(mesh, mat, U, M.exact_gradient)
            eta = math.sqrt(sum(float(v.sum()) for v in terms.values()))
            err = math.sqrt(float(e2.sum()))
            rows.append(
                (
                    f"manufactured {fam}",
                    str(n),
                    str(len(U) if ORDER == 2 else 2 * mesh.n_points),
                    f"{eta:.3e}",
                    f"{err:.3e}",
                    f"{eta / err:.2f}",
                )
            )
    return rows


def _uniform(problem: Problem, k: int) -> Problem:
    mesh = problem.mesh
    for _ in range(k):
        mesh = refine_cells(mesh, np.arange(mesh.n_cells))
    return dataclasses.replace(problem, mesh=mesh)


def effectivity_hertz(quick: bool) -> list[tuple[str, ...]]:
    rows = []
    for lv in (2, 3) if quick else (2, 3, 4):
        pr = dataclasses.replace(line_contact(0.05, lv, n=16), order=ORDER)
        ref = _uniform(pr, 3 if ORDER == 1 else 2)
        ur = _u(simulate(ref, "newton", store="final"))
        r = simulate(pr, "newton", store="final")
        est = estimate(pr, _u(r), r.p_rigid[-1])
        err = math.sqrt(_error_sq(pr, _u(r), ref, ur))
        rows.append(
            (
                f"hertz a = 0.05, {lv} levels",
                "-",
                str(pr.space.n_dofs),
                f"{est.total:.3e}",
                f"{err:.3e}",
                f"{est.total / err:.2f}",
            )
        )
    return rows


def table(head: tuple[str, ...], rows: list[tuple[str, ...]]) -> str:
    out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(out)


def rates(case: str, nref: int, cap: int, quick: bool) -> dict[str, Any]:
    build = CASES[case]
    ref = build(nref)
    u_ref = _u(simulate(ref, "newton", store="final"))

    def error(pr: Problem, u: np.ndarray) -> float:
        return math.sqrt(_error_sq(pr, u, ref, u_ref))

    rows = []
    uni_N, uni_e = [], []
    for n in (4, 8, 16, 32) if quick else (4, 8, 16, 32, 64):
        if nref % n or n >= nref:
            continue
        pr = build(n)
        r = simulate(pr, "newton", store="final")
        est = estimate(pr, _u(r), r.p_rigid[-1], r.wear[-1])
        e = error(pr, _u(r))
        uni_N.append(pr.space.n_dofs)
        uni_e.append(e)
        rows.append(
            (
                "uniform",
                f"1/{n}",
                str(pr.space.n_dofs),
                f"{e:.3e}",
                f"{est.total:.3e}",
                f"{est.total / e:.2f}",
            )
        )
    max_level = round(math.log2(cap / 4))
    steps = adapt(build(4), theta=0.5, max_level=max_level, max_passes=14 if quick else 22)
    ad_N, ad_e = [], []
    n32 = build(32).space.n_dofs if 32 < nref else uni_N[-1]
    for i, s in enumerate(steps):
        e = error(s.problem, _u(s.result))
        rows.append(
            (
                "adaptive",
                f"pass {i}, level <= {int(s.level.max())}",
                str(s.n_dofs),
                f"{e:.3e}",
                f"{s.estimate.total:.3e}",
                f"{s.estimate.total / e:.2f}",
            )
        )
        if s.n_dofs <= n32:
            ad_N.append(s.n_dofs)
            ad_e.append(e)
    return {
        "rows": rows,
        "uniform_rate": slope(uni_N, uni_e),
        "adaptive_rate": slope(ad_N, ad_e),
        "ref_cells": ref.mesh.n_cells,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reference", type=int, default=256, help="1/h of the reference")
    ap.add_argument("--cap", type=int, default=128, help="1/h of the finest adaptive cells")
    ap.add_argument("--quick", action="store_true", help="fewer meshes")
    ap.add_argument("--cases", nargs="*", default=list(CASES), choices=list(CASES))
    ap.add_argument("--order", type=int, default=1, choices=(1, 2), help="k of the space")
    args = ap.parse_args()
    global ORDER
    ORDER = args.order
    if args.cap >= args.reference:
        ap.error("--cap must be below --reference (the reference must be finer)")
    head = ("problem", "1/h", "dofs", "estimate", "error", "effectivity")
    print("## Effectivity of the estimator (energy norm)\n")
    print(table(head, effectivity_manufactured(args.quick) + effectivity_hertz(args.quick)))
    for case in args.cases:
        res = rates(case, args.reference, args.cap, args.quick)
        print(
            f"\n## {case}: error against dofs (reference h = 1/{args.reference}, "
            f"{res['ref_cells']} cells)\n"
        )
        print(table(("mesh", "size", "dofs", "error", "estimate", "effectivity"), res["rows"]))
        print(
            f"\nrate in N: uniform {res['uniform_rate']:.2f}, adaptive "
            f"{res['adaptive_rate']:.2f} (optimal {-ORDER / 2:.2f})"
        )


if __name__ == "__main__":
    main()
