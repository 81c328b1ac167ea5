"""Convergence of the VEM for linear elasticity alone, against a manufactured solution.

No contact: on the unit square with the exact displacement

    u1 = sin(pi x) sin(pi y),    u2 = x^2 y,

the isotropic law ``sigma = 2 eta eps + lam tr(eps) I`` (``lam = 2``, ``eta = 1``: unequal
Lamé coefficients catch a swapped pair), the body force ``f1 = -div sigma(u)``, the
traction ``f2 = sigma(u) n`` on the top and bottom sides (Gamma_N) and ``u`` itself
imposed at the vertices of the left and right sides (Gamma_D; on the right side
``u2 = y`` is not zero). The discrete problem ``K u_h = F`` is the one of the contact
code without Gamma_C: the stiffness of :func:`vemwear.vem.stiffness`, the load of
the paper's Section 3.3 (:func:`vemwear.vem.body_force_vector`) and the traction by
:func:`vemwear.vem.edge_load_vector`.

Derivatives, written out by hand (checked symbolically in the tests)::

    grad u = [[pi cos(pi x) sin(pi y), pi sin(pi x) cos(pi y)],
              [2 x y,                  x^2                  ]]
    sigma11 = (2 eta + lam) pi cos(pi x) sin(pi y) + lam x^2
    sigma22 = (2 eta + lam) x^2 + lam pi cos(pi x) sin(pi y)
    sigma12 = eta (pi sin(pi x) cos(pi y) + 2 x y)
    (div sigma)_1 = -(3 eta + lam) pi^2 sin(pi x) sin(pi y) + 2 (lam + eta) x
    (div sigma)_2 = (lam + eta) pi^2 cos(pi x) cos(pi y) + 2 eta y

Errors (:func:`vemwear.post.norms.exact_errors`), on a degree-5 rule on the fan
triangulation of every cell: ``H1``: ``||grad(Pi u_h) - grad u||_{L2}`` (expected order
1); ``L2``: ``||Pi u_h - u||_{L2}`` (expected order 2); ``nodal``: the cell-weighted
nodal L2 error (order 2). Orders use the mean cell size ``sqrt(|Omega| / n_cells)``,
which halves with every level for all families.

With ``order=2`` the same study runs on the second-order space (:class:`vemwear.vem.space.
P2Space`): u imposed on Gamma_D through its dofs there (vertex values and edge means), the
load of ``load_rule`` (``"projection"`` by default: ``int f1 . Pi v``, whose consistency
error is O(h^3); the paper's P_0 load of Section 3.3 limits the L2 order to 2 for k = 2,
docs/method.md, section 9), and the errors of the quadratic ``Pi u_h`` (expected orders:
H1 2, L2 3; nodal 3 on the vertex values).
"""

from __future__ import annotations

import csv
import io
import math
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

from ..mesh import Mesh, tag_rectangle
from ..post.norms import exact_errors
from ..vem import Material, body_force_vector, edge_load_vector, stiffness
from ..vem.dofs2 import interpolate2
from ..vem.quadrature import polygon_quadrature
from ..vem.space import P2Space

__all__ = [
    "DEFAULT_FAMILIES",
    "ETA",
    "LAM",
    "LEVEL_OPTIONS",
    "available_families",
    "body_force",
    "convergence_study",
    "exact_displacement",
    "exact_errors2",
    "exact_gradient",
    "exact_stress",
    "family_mesh",
    "solve",
    "solve2",
    "table_csv",
    "table_text",
    "traction",
]

LAM, ETA = 2.0, 1.0
PARTS: dict[str, Any] = {"clamped": ["left", "right"], "traction": ["top", "bottom"]}
SIZE = (1.0, 1.0)
PI = math.pi

#: The families of the study (names of :data:`vemwear.mesh.registry.FAMILIES`), with the
#: options of level ``n`` beyond ``size``: about ``n`` cells per side, fixed seeds.
LEVEL_OPTIONS: dict[str, Callable[[int], dict[str, Any]]] = {
    "squares": lambda n: {"divisions": (n, n)},
    "triangles": lambda n: {"divisions": (n, n)},  # the VEM equals P1 finite elements here
    "voronoi": lambda n: {"n_cells": n * n, "seed": 0},
    "hanging": lambda n: {"divisions": (n, n), "pattern": "checkerboard"},
    "distorted": lambda n: {"divisions": (n, n), "amplitude": 0.2, "seed": 0},
    "hexagons": lambda n: {"divisions": n},
    "nonconvex": lambda n: {"divisions": (n, n)},
}
DEFAULT_FAMILIES: tuple[str, ...] = ("squares", "triangles", "voronoi", "hanging")


# ----------------------------------------------------------------------------- exact solution
def exact_displacement(x: NDArray[np.float64]) -> NDArray[np.float64]:
    """``u(x) = (sin(pi x) sin(pi y), x^2 y)`` for points of shape (q, 2)."""
    X, Y = x[:, 0], x[:, 1]
    return np.column_stack([np.sin(PI * X) * np.sin(PI * Y), X**2 * Y])


def exact_gradient(x: NDArray[np.float64]) -> NDArray[np.float64]:
    """``grad u``, shape (q, 2, 2), ``[:, i, j] = d_j u_i``."""
    X, Y = x[:, 0], x[:, 1]
    g = np.empty((len(x), 2, 2))
    g[:, 0, 0] = PI * np.cos(PI * X) * np.sin(PI * Y)
    g[:, 0, 1] = PI * np.sin(PI * X) * np.cos(PI * Y)
    g[:, 1, 0] = 2.0 * X * Y
    g[:, 1, 1] = X**2
    return g


def exact_stress(x: NDArray[np.float64], lam: float = LAM, eta: float = ETA) -> NDArray[np.float64]:
    """``sigma(u) = 2 eta eps(u) + lam tr(eps(u)) I``, shape (q, 2, 2)."""
    X, Y = x[:, 0], x[:, 1]
    c = PI * np.cos(PI * X) * np.sin(PI * Y)  # eps11
    s = np.empty((len(x), 2, 2))
    s[:, 0, 0] = (2.0 * eta + lam) * c + lam * X**2
    s[:, 1, 1] = (2.0 * eta + lam) * X**2 + lam * c
    s[:, 0, 1] = s[:, 1, 0] = eta * (PI * np.sin(PI * X) * np.cos(PI * Y) + 2.0 * X * Y)
    return s


def body_force(
    x: NDArray[np.float64], t: float = 0.0, lam: float = LAM, eta: float = ETA
) -> NDArray[np.float64]:
    """``f1 = -div sigma(u)`` (hand-derived, module docstring), shape (q, 2)."""
    X, Y = x[:, 0], x[:, 1]
    d1 = -(3.0 * eta + lam) * PI**2 * np.sin(PI * X) * np.sin(PI * Y) + 2.0 * (lam + eta) * X
    d2 = (lam + eta) * PI**2 * np.cos(PI * X) * np.cos(PI * Y) + 2.0 * eta * Y
    return -np.column_stack([d1, d2])


def traction(
    x: NDArray[np.float64], t: float = 0.0, lam: float = LAM, eta: float = ETA
) -> NDArray[np.float64]:
    """``f2 = sigma(u) n`` on the bottom (``n = (0, -1)``, y < 1/2) and top (``n = (0, 1)``)
    sides of the unit square, shape (q, 2)."""
    s = exact_stress(x, lam, eta)
    sign = np.where(x[:, 1] > 0.5, 1.0, -1.0)
    return s[:, :, 1] * sign[:, None]


# ----------------------------------------------------------------------------- meshes
def _builders() -> dict[str, Callable[[int], Mesh]]:
    from vemwear.mesh.registry import FAMILIES as REGISTRY

    def builder(name: str) -> Callable[[int], Mesh]:
        return lambda n: REGISTRY[name].generate(size=SIZE, **LEVEL_OPTIONS[name](n))

    return {name: builder(name) for name in LEVEL_OPTIONS}


def available_families() -> list[str]:
    """The families of :data:`LEVEL_OPTIONS` whose mesh generator is available."""
    b = _builders()
    return [f for f in LEVEL_OPTIONS if f in b]


def family_mesh(family: str, n: int) -> Mesh:
    """The tagged mesh of the unit square of a family at level ``n`` (about ``n`` cells per
    side); Gamma_D = left and right sides, Gamma_N = top and bottom sides.

    Raises
    ------
    ValueError
        If the family is unknown or its generator is not available.
    """
    b = _builders()
    if family not in b:
        known = ", ".join(available_families())
        raise ValueError(f"unknown or unavailable mesh family {family!r}; available: {known}")
    return tag_rectangle(b[family](int(n)), PARTS)


# ----------------------------------------------------------------------------- solve
def solve(
    mesh: Mesh, material: Material | None = None, stabilization: str = "paper"
) -> NDArray[np.float64]:
    """Solve ``K u_h = F`` with ``u_h = u`` at the vertices of Gamma_D.

    Parameters
    ----------
    mesh : Mesh
        Tagged with ``clamped`` (Dirichlet) and ``traction`` (Neumann) parts.
    material : Material, optional
        Default: ``lam = LAM, eta = ETA``.
    stabilization : str
        As in :func:`vemwear.vem.stiffness`.

    Returns
    -------
    (n_points, 2) array
        The vertex values of ``u_h``.
    """
    mat = material if material is not None else Material(lam=LAM, eta=ETA)

    def f1(x: NDArray[np.float64], t: float) -> NDArray[np.float64]:
        return body_force(x, t, mat.lam, mat.eta)

    def f2(x: NDArray[np.float64], t: float) -> NDArray[np.float64]:
        return traction(x, t, mat.lam, mat.eta)

    K = stiffness(mesh, mat, stabilization).tocsr()
    F = body_force_vector(mesh, f1) + edge_load_vector(mesh, mesh.part_edges("traction"), f2)
    ndof = 2 * mesh.n_points
    fixed = np.zeros(ndof, dtype=bool)
    dv = mesh.part_vertices("clamped")
    fixed[2 * dv] = fixed[2 * dv + 1] = True
    u = np.zeros(ndof)
    ud = exact_displacement(mesh.points[dv])
    u[2 * dv], u[2 * dv + 1] = ud[:, 0], ud[:, 1]
    free = np.flatnonzero(~fixed)
    rhs = F[free] - K[free][:, fixed] @ u[fixed]
    u[free] = spla.spsolve(K[free][:, free].tocsc(), rhs)
    return u.reshape(-1, 2)


def solve2(
    mesh: Mesh,
    material: Material | None = None,
    stabilization: str = "paper",
    load_rule: str = "projection",
) -> NDArray[np.float64]:
    """As :func:`solve` with the second-order space: all dofs of ``u_h`` (k = 2), with
    the dofs of u (vertex values, edge means) imposed on Gamma_D.

    Parameters
    ----------
    mesh : Mesh
    material : Material, optional
    stabilization : str
    load_rule : {"projection", "paper"}
        The body-force load (:func:`vemwear.vem.dofs2.body_force_vector2`).
    """
    mat = material if material is not None else Material(lam=LAM, eta=ETA)

    def f1(x: NDArray[np.float64], t: float) -> NDArray[np.float64]:
        return body_force(x, t, mat.lam, mat.eta)

    def f2(x: NDArray[np.float64], t: float) -> NDArray[np.float64]:
        return traction(x, t, mat.lam, mat.eta)

    V = P2Space(mesh, load_rule=load_rule)
    K = V.stiffness(mat, stabilization).tocsr()
    F = V.body_force(f1) + V.boundary_load(mesh.part_edges("traction"), f2)
    fixed = np.zeros(V.n_dofs, dtype=bool)
    for d in V.component_dofs(mesh.part_edges("clamped")):
        fixed[d] = True
    u = np.where(fixed, interpolate2(mesh, lambda x, t: exact_displacement(x)), 0.0)
    free = np.flatnonzero(~fixed)
    rhs = F[free] - K[free][:, fixed] @ u[fixed]
    u[free] = spla.spsolve(K[free][:, free].tocsc(), rhs)
    return u


def exact_errors2(mesh: Mesh, uh: NDArray[np.float64], material: Material) -> dict[str, float]:
    """The errors of :func:`vemwear.post.norms.exact_errors` for k = 2: of the quadratic
    ``Pi u_h`` (3.8) on the degree-5 rule, and the nodal error of the vertex values."""
    V = P2Space(mesh)
    x, w, cell = polygon_quadrature(mesh, 5)
    val, grad = V.projection(material, uh).at(x, cell)
    ue, ge = exact_displacement(x), exact_gradient(x)
    U = V.vertex_values(uh)
    nod = np.sum((U - exact_displacement(mesh.points)) ** 2, axis=1)
    per_cell = (
        np.bincount(mesh.edge_cells, weights=nod[mesh.cell_vertices], minlength=mesh.n_cells)
        / mesh.cell_sizes
    )
    return {
        "L2": math.sqrt(float(np.sum(w * np.sum((val - ue) ** 2, axis=1)))),
        "H1semi": math.sqrt(float(np.sum(w * np.sum((grad - ge) ** 2, axis=(1, 2))))),
        "nodal": math.sqrt(float(np.sum(mesh.cell_areas * per_cell))),
        "L2_u": math.sqrt(float(np.sum(w * np.sum(ue**2, axis=1)))),
        "H1semi_u": math.sqrt(float(np.sum(w * np.sum(ge**2, axis=(1, 2))))),
    }


# ----------------------------------------------------------------------------- study
def convergence_study(
    families: Sequence[str] = DEFAULT_FAMILIES,
    levels: int = 4,
    n0: int = 4,
    *,
    stabilization: str = "paper",
    log: Callable[[str], None] | None = None,
    order: int = 1,
    load_rule: str = "projection",
) -> list[dict[str, Any]]:
    """Errors and orders on ``levels`` successive meshes ``n = n0, 2 n0, ...`` per family,
    with the space of order ``order`` (1 or 2; ``load_rule`` of :func:`solve2` for 2).

    Returns
    -------
    list of dict
        One row per (family, level): ``family``, ``order``, ``n``, ``cells``, ``dofs``, ``h``
        (largest cell diameter), ``h_mean`` (``sqrt(1 / cells)``), the errors ``H1``,
        ``L2``, ``nodal`` (absolute; ``H1_rel``, ``L2_rel`` relative to the norms of u),
        their orders ``H1_order``, ``L2_order``, ``nodal_order`` (NaN on the first level)
        and ``seconds``.
    """
    if levels < 1 or n0 < 1:
        raise ValueError(f"levels and n0 must be positive, got {levels}, {n0}")
    if order not in (1, 2):
        raise ValueError(f"order must be 1 or 2, got {order!r}")
    mat = Material(lam=LAM, eta=ETA)
    rows: list[dict[str, Any]] = []
    for fam in families:
        prev: dict[str, Any] | None = None
        for i in range(int(levels)):
            n = int(n0) * 2**i
            t0 = time.perf_counter()
            mesh = family_mesh(fam, n)
            if order == 1:
                uh = solve(mesh, stabilization=stabilization)
                e = exact_errors(mesh, uh, exact_displacement, exact_gradient)
                dofs = 2 * mesh.n_points
            else:
                uh = solve2(mesh, mat, stabilization, load_rule)
                e = exact_errors2(mesh, uh, mat)
                dofs = uh.size
            row: dict[str, Any] = {
                "family": fam,
                "order": order,
                "n": n,
                "cells": mesh.n_cells,
                "dofs": dofs,
                "h": mesh.h,
                "h_mean": math.sqrt(1.0 / mesh.n_cells),
                "H1": e["H1semi"],
                "L2": e["L2"],
                "nodal": e["nodal"],
                "H1_rel": e["H1semi"] / e["H1semi_u"],
                "L2_rel": e["L2"] / e["L2_u"],
            }
            for k in ("H1", "L2", "nodal"):
                row[f"{k}_order"] = (
                    float("nan")
                    if prev is None
                    else math.log(prev[k] / row[k]) / math.log(prev["h_mean"] / row["h_mean"])
                )
            row["seconds"] = time.perf_counter() - t0
            rows.append(row)
            prev = row
            if log is not None:
                log(f"{fam} n = {n}: H1 {row['H1']:.3e}, L2 {row['L2']:.3e}")
    return rows


def _o(v: float) -> str:
    return "-" if not math.isfinite(v) else f"{v:.2f}"


def table_text(rows: Sequence[dict[str, Any]], markdown: bool = False) -> str:
    """The rows of :func:`convergence_study` as a fixed-width (or Markdown) table."""
    head = [
        "family",
        "n",
        "cells",
        "dofs",
        "h",
        "H1 error",
        "order",
        "L2 error",
        "order",
        "nodal L2",
        "order",
    ]
    body = [
        [
            r["family"],
            str(r["n"]),
            str(r["cells"]),
            str(r["dofs"]),
            f"{r['h']:.4f}",
            f"{r['H1']:.3e}",
            _o(r["H1_order"]),
            f"{r['L2']:.3e}",
            _o(r["L2_order"]),
            f"{r['nodal']:.3e}",
            _o(r["nodal_order"]),
        ]
        for r in rows
    ]
    if markdown:
        lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        lines += ["| " + " | ".join(b) + " |" for b in body]
        return "\n".join(lines) + "\n"
    w = [max(len(h), *(len(b[i]) for b in body)) for i, h in enumerate(head)]
    fmt = "  ".join(f"{{:<{w[0]}}}" if i == 0 else f"{{:>{w[i]}}}" for i in range(len(head)))
    lines = [fmt.format(*head), fmt.format(*("-" * x for x in w))]
    last = None
    for r, b in zip(rows, body, strict=True):
        if last is not None and r["family"] != last:
            lines.append("")
        lines.append(fmt.format(*b))
        last = r["family"]
    return "\n".join(lines) + "\n"


def table_csv(rows: Sequence[dict[str, Any]]) -> str:
    """The rows of :func:`convergence_study` as CSV."""
    keys = [
        "family",
        "n",
        "cells",
        "dofs",
        "h",
        "h_mean",
        "H1",
        "H1_order",
        "L2",
        "L2_order",
        "nodal",
        "nodal_order",
        "H1_rel",
        "L2_rel",
        "seconds",
        "order",
    ]
    buf = io.StringIO()
    wr = csv.writer(buf, lineterminator="\n")
    wr.writerow(keys)
    for r in rows:
        wr.writerow(
            [
                r[k]
                if isinstance(r[k], (str, int))
                else ("" if not math.isfinite(r[k]) else f"{r[k]:.6e}")
                for k in keys
            ]
        )
    return buf.getvalue()
