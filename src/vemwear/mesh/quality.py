"""Mesh quality with respect to the mesh assumption A1 of the paper.

Assumption A1 asks for constants ``gamma1, gamma2 > 0``, independent of the mesh
size, such that every cell ``K`` (diameter ``h_K``)

* is star-shaped with respect to a disk of radius ``rho_K >= gamma1 * h_K``, and
* has any two of its vertices at distance ``>= gamma2 * h_K``.

What is computed
----------------
``rho_K`` is *exact*: a polygon is star-shaped with respect to a disk if and only
if the disk lies in its kernel, the intersection of the inner half-planes of its
edges. The largest such disk solves the small linear program

    maximise r  subject to  nu_e . x - r >= nu_e . a_e  for every edge e,

(``nu_e`` the unit inward normal of edge ``e``, ``a_e`` one of its end points),
whose optimum is a vertex of the feasible set: it is found by enumerating all
triples of edge constraints, vectorized over cells of the same vertex count. For
a convex cell this is its inscribed circle; ``rho_K = 0`` marks a cell that is
not star-shaped (empty kernel or kernel without interior). Hanging nodes
(collinear vertices) are handled naturally (repeated constraints).

The vertex distance is the minimum over *all* pairs of vertices of the cell (not
only consecutive ones), divided by ``h_K``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import combinations

import numpy as np
from numpy.typing import NDArray

from ..util.arrays import unique as _unique
from .polymesh import Mesh

__all__ = ["QualityReport", "kernel_disks", "quality_report"]

FloatArray = NDArray[np.float64]


def _kernel_disk_group(
    X: FloatArray, chunk_elems: int = 2_000_000
) -> tuple[FloatArray, FloatArray]:
    """Largest disk in the kernel of ``m`` polygons with ``n`` vertices each, ``X`` (m, n, 2)."""
    m, n, _ = X.shape
    e = np.roll(X, -1, axis=1) - X
    L = np.hypot(e[..., 0], e[..., 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        nu = np.stack([-e[..., 1], e[..., 0]], axis=-1) / L[..., None]
    nu = np.nan_to_num(nu)
    beta = np.sum(nu * X, axis=-1)  # (m, n)
    diam = np.max(np.linalg.norm(X[:, :, None, :] - X[:, None, :, :], axis=-1), axis=(1, 2))
    tri = np.array(list(combinations(range(n), 3)), dtype=np.int64)  # (T, 3)
    centre = np.full((m, 2), np.nan)
    rho = np.zeros(m)
    step = max(1, chunk_elems // (len(tri) * n))
    for s in range(0, m, step):
        nu_c, be_c = nu[s : s + step], beta[s : s + step]
        c = len(nu_c)
        rows = np.concatenate([nu_c[:, tri], -np.ones((c, len(tri), 3, 1))], axis=-1)  # (c,T,3,3)
        r0, r1, r2 = rows[:, :, 0], rows[:, :, 1], rows[:, :, 2]
        c0, c1, c2 = np.cross(r1, r2), np.cross(r2, r0), np.cross(r0, r1)
        det = np.sum(r0 * c0, axis=-1)  # (c, T)
        b = be_c[:, tri]  # (c, T, 3)
        ok = np.abs(det) > 1e-12
        with np.errstate(divide="ignore", invalid="ignore"):
            sol = (b[..., 0:1] * c0 + b[..., 1:2] * c1 + b[..., 2:3] * c2) / det[..., None]
        sol[~ok] = 0.0
        # feasibility of every candidate (x, y, r) for all edge constraints
        slack = (
            np.einsum("cnk,ctk->ctn", nu_c, sol[..., :2]) - sol[..., 2:3] - be_c[:, None, :]
        )  # (c, T, n)
        tol = 1e-10 * diam[s : s + step, None, None]
        ok &= np.all(slack >= -tol, axis=-1) & np.isfinite(sol[..., 2])
        r = np.where(ok, sol[..., 2], -np.inf)
        best = np.argmax(r, axis=1)
        rb = r[np.arange(c), best]
        has = np.isfinite(rb)
        rho[s : s + step] = np.where(has, np.maximum(rb, 0.0), 0.0)
        centre[s : s + step] = np.where(has[:, None], sol[np.arange(c), best, :2], np.nan)
    return rho, centre


def kernel_disks(mesh: Mesh) -> tuple[FloatArray, FloatArray]:
    """Largest disk contained in the kernel of every cell.

    Parameters
    ----------
    mesh : Mesh

    Returns
    -------
    rho : (n_cells,) float array
        Radius of the largest disk with respect to which the cell is star-shaped;
        0 for a cell that is not star-shaped with respect to any disk.
    centre : (n_cells, 2) float array
        Centre of that disk (a point of the kernel; NaN if the kernel is empty).
    """
    rho = np.zeros(mesh.n_cells)
    centre = np.full((mesh.n_cells, 2), np.nan)
    for _n, (ids, verts) in mesh.groups.items():
        r, c = _kernel_disk_group(mesh.points[verts])
        rho[ids], centre[ids] = r, c
    return rho, centre


def _min_vertex_distance(mesh: Mesh) -> FloatArray:
    out = np.zeros(mesh.n_cells)
    for n, (ids, verts) in mesh.groups.items():
        X = mesh.points[verts]
        i, j = np.triu_indices(n, k=1)
        d = np.linalg.norm(X[:, i] - X[:, j], axis=-1)
        out[ids] = d.min(axis=1)
    return out


def _convex(mesh: Mesh) -> NDArray[np.bool_]:
    out = np.zeros(mesh.n_cells, dtype=bool)
    for _n, (ids, verts) in mesh.groups.items():
        X = mesh.points[verts]
        e1 = X - np.roll(X, 1, axis=1)
        e2 = np.roll(X, -1, axis=1) - X
        cr = e1[..., 0] * e2[..., 1] - e1[..., 1] * e2[..., 0]
        scale = np.hypot(e1[..., 0], e1[..., 1]) * np.hypot(e2[..., 0], e2[..., 1])
        out[ids] = np.all(cr >= -1e-12 * scale, axis=1)
    return out


def _stats(a: FloatArray) -> tuple[float, float, float]:
    return float(np.min(a)), float(np.mean(a)), float(np.max(a))


@dataclass
class QualityReport:
    """Per-cell shape measures of assumption A1 and their summary.

    Attributes
    ----------
    diameter : (n_cells,) array
        ``h_K``, the largest vertex-to-vertex distance.
    rho : (n_cells,) array
        Radius of the largest disk in the kernel (exact; 0 if not star-shaped).
    centre : (n_cells, 2) array
        Centre of that disk.
    rho_ratio : (n_cells,) array
        ``rho_K / h_K``; A1 asks for a uniform lower bound ``gamma1``.
    vertex_ratio : (n_cells,) array
        Minimum distance between two vertices of ``K`` over ``h_K``; A1's ``gamma2``.
    area_ratio : (n_cells,) array
        ``|K| / h_K**2`` (a chunkiness measure).
    convex : (n_cells,) bool array
    gamma1, gamma2 : float
        Smallest ``rho_ratio`` and ``vertex_ratio`` over the mesh.
    gamma1_min, gamma2_min : float
        Thresholds below which a cell counts as far outside A1.
    warnings : list of str
        Human-readable findings (empty for a good mesh).
    """

    n_cells: int
    h: float
    diameter: FloatArray
    rho: FloatArray
    centre: FloatArray
    rho_ratio: FloatArray
    vertex_ratio: FloatArray
    area_ratio: FloatArray
    n_vertices: NDArray[np.int64]
    convex: NDArray[np.bool_]
    gamma1_min: float
    gamma2_min: float
    warnings: list[str] = field(default_factory=list)

    @property
    def gamma1(self) -> float:
        """Smallest ``rho_K / h_K``."""
        return float(np.min(self.rho_ratio))

    @property
    def gamma2(self) -> float:
        """Smallest vertex distance over ``h_K``."""
        return float(np.min(self.vertex_ratio))

    @property
    def star_shaped(self) -> NDArray[np.bool_]:
        """Cells star-shaped with respect to a disk of positive radius."""
        return self.rho > 0

    @property
    def bad_rho(self) -> NDArray[np.int64]:
        """Cells with ``rho_K / h_K < gamma1_min`` (includes non-star-shaped cells)."""
        return np.flatnonzero(self.rho_ratio < self.gamma1_min)

    @property
    def bad_vertex(self) -> NDArray[np.int64]:
        """Cells with two vertices closer than ``gamma2_min * h_K``."""
        return np.flatnonzero(self.vertex_ratio < self.gamma2_min)

    @property
    def ok(self) -> bool:
        """No cell is far outside A1."""
        return not self.warnings

    def summary(self) -> dict[str, tuple[float, float, float]]:
        """``{quantity: (min, mean, max)}`` of the per-cell measures."""
        return {
            "rho_K / h_K": _stats(self.rho_ratio),
            "min vertex distance / h_K": _stats(self.vertex_ratio),
            "|K| / h_K^2": _stats(self.area_ratio),
            "h_K": _stats(self.diameter),
            "vertices per cell": _stats(self.n_vertices.astype(float)),
        }

    def __str__(self) -> str:
        lines = [
            f"Mesh quality (assumption A1): {self.n_cells} cells, "
            f"{int(np.sum(self.convex))} convex, {int(np.sum(~self.star_shaped))} not star-shaped",
            f"{'quantity':<28}{'min':>11}{'mean':>11}{'max':>11}",
        ]
        for name, (lo, mean, hi) in self.summary().items():
            lines.append(f"{name:<28}{lo:>11.4g}{mean:>11.4g}{hi:>11.4g}")
        lines.append(
            f"gamma1 = {self.gamma1:.4g}, gamma2 = {self.gamma2:.4g}; cells with rho/h < "
            f"{self.gamma1_min:g}: {len(self.bad_rho)}, with vertex distance/h < "
            f"{self.gamma2_min:g}: {len(self.bad_vertex)}"
        )
        if self.warnings:
            lines.extend(f"WARNING: {w}" for w in self.warnings)
        else:
            lines.append("no warnings")
        return "\n".join(lines)


def quality_report(
    mesh: Mesh, gamma1_min: float = 0.05, gamma2_min: float = 0.005
) -> QualityReport:
    """Shape regularity of a mesh in the sense of assumption A1.

    Parameters
    ----------
    mesh : Mesh
        Any valid polygonal mesh.
    gamma1_min : float
        Cells with ``rho_K / h_K`` below this count as far outside A1.
    gamma2_min : float
        Cells with two vertices closer than ``gamma2_min * h_K`` count as far
        outside A1.

    Returns
    -------
    QualityReport
        Per-cell measures, statistics, counts and warnings; ``print`` it for a table.

    Examples
    --------
    >>> from vemwear.mesh import rectangle_squares
    >>> rep = quality_report(rectangle_squares((1.0, 1.0), (4, 4)))
    >>> round(rep.gamma1, 6)  # 0.5 / sqrt(2)
    0.353553
    """
    diam = mesh.cell_diameters
    rho, centre = kernel_disks(mesh)
    dmin = _min_vertex_distance(mesh)
    rho_ratio = rho / diam
    vertex_ratio = dmin / diam
    area_ratio = np.abs(mesh.cell_areas) / diam**2
    rep = QualityReport(
        n_cells=mesh.n_cells,
        h=float(diam.max()),
        diameter=diam,
        rho=rho,
        centre=centre,
        rho_ratio=rho_ratio,
        vertex_ratio=vertex_ratio,
        area_ratio=area_ratio,
        n_vertices=mesh.cell_sizes.copy(),
        convex=_convex(mesh),
        gamma1_min=float(gamma1_min),
        gamma2_min=float(gamma2_min),
    )
    w = rep.warnings
    not_star = np.flatnonzero(rho <= 0)
    if len(not_star):
        w.append(
            f"{len(not_star)} cells are not star-shaped with respect to any disk, e.g. cells "
            f"{not_star[:10].tolist()}"
        )
    bad = np.setdiff1d(rep.bad_rho, not_star)
    if len(bad):
        w.append(
            f"{len(bad)} cells have rho_K / h_K < {gamma1_min:g} (min {rho_ratio[bad].min():.3g}), "
            f"e.g. cells {bad[np.argsort(rho_ratio[bad])][:10].tolist()}"
        )
    bad = rep.bad_vertex
    if len(bad):
        w.append(
            f"{len(bad)} cells have two vertices closer than {gamma2_min:g} h_K "
            f"(min {vertex_ratio[bad].min():.3g}), e.g. cells "
            f"{bad[np.argsort(vertex_ratio[bad])][:10].tolist()}"
        )
    return rep


def hanging_nodes(mesh: Mesh, rtol: float = 1e-10) -> NDArray[np.int64]:
    """Vertices lying on a straight side of a cell (interior angle 180 degrees there).

    Parameters
    ----------
    mesh : Mesh
    rtol : float
        A vertex is straight when ``|e_in x e_out| <= rtol |e_in| |e_out|`` and the
        two edges point the same way.

    Returns
    -------
    (k,) int array
        Sorted vertex ids.
    """
    found = [np.zeros(0, np.int64)]
    for _n, (_ids, verts) in mesh.groups.items():
        X = mesh.points[verts]
        e_in = X - np.roll(X, 1, axis=1)
        e_out = np.roll(X, -1, axis=1) - X
        cross = e_in[..., 0] * e_out[..., 1] - e_in[..., 1] * e_out[..., 0]
        dot = np.sum(e_in * e_out, axis=-1)
        scale = np.linalg.norm(e_in, axis=-1) * np.linalg.norm(e_out, axis=-1)
        found.append(verts[(np.abs(cross) <= rtol * scale) & (dot > 0)])
    return _unique(np.concatenate(found))
