"""Shape measures of polyhedral meshes (the 3D analogue of :mod:`vemwear.mesh.quality`).

The 3D virtual element theory asks, as in 2D, for cells star-shaped with respect to a
ball of radius ``>= gamma1 * h_K`` and for faces and edges not too small against
``h_K`` (Beirao da Veiga, Dassi, Russo 2017, assumptions on the mesh). Measured here,
per cell ``K`` of diameter ``h_K``:

* ``|K|^(1/3) / h_K``, the chunkiness (0.577 for a cube, 0.27 for a Kuhn tetrahedron);
* ``rho_K / h_K`` with ``rho_K`` the distance from the centroid to the nearest face plane
  (for a convex cell, the radius of a ball about the centroid inside the cell, a lower
  bound of the largest inscribed ball; a cell whose centroid is outside one of its
  face planes gets a value <= 0);
* the shortest edge over ``h_K`` and the smallest face area over ``h_K^2``;
* faces and distinct vertices per cell, and the planarity of the faces (the largest
  distance of a vertex to its face's plane over the face's diameter).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from .geometry3d import face_planarity, loop_next
from .polyhedra import Mesh3D

__all__ = ["QualityReport3D", "quality_report3d"]

FloatArray = NDArray[np.float64]


def _stats(a: NDArray) -> tuple[float, float, float]:
    a = np.asarray(a, dtype=float)
    return float(np.min(a)), float(np.mean(a)), float(np.max(a))


@dataclass
class QualityReport3D:
    """Per-cell shape measures and their summary (``print`` it for a table).

    Attributes
    ----------
    diameter, volume_ratio, rho_ratio, edge_ratio, face_area_ratio, planarity : arrays
        Per cell: ``h_K``, ``|K|^(1/3) / h_K``, ``rho_K / h_K``, shortest edge over
        ``h_K``, smallest face area over ``h_K^2``, largest planarity of its faces.
    n_faces, n_vertices : int arrays
        Faces and distinct vertices per cell.
    warnings : list of str
        Findings outside the thresholds (empty for a good mesh).
    """

    n_cells: int
    n_faces_total: int
    n_points: int
    diameter: FloatArray
    volume_ratio: FloatArray
    rho_ratio: FloatArray
    edge_ratio: FloatArray
    face_area_ratio: FloatArray
    planarity: FloatArray
    n_faces: NDArray[np.int64]
    n_vertices: NDArray[np.int64]
    warnings: list[str] = field(default_factory=list)

    @property
    def h(self) -> float:
        """Largest cell diameter."""
        return float(np.max(self.diameter))

    @property
    def ok(self) -> bool:
        """No finding."""
        return not self.warnings

    def summary(self) -> dict[str, tuple[float, float, float]]:
        """``{quantity: (min, mean, max)}`` of the per-cell measures."""
        return {
            "|K|^(1/3) / h_K": _stats(self.volume_ratio),
            "rho_K / h_K": _stats(self.rho_ratio),
            "min edge / h_K": _stats(self.edge_ratio),
            "min face area / h_K^2": _stats(self.face_area_ratio),
            "face planarity": _stats(self.planarity),
            "h_K": _stats(self.diameter),
            "faces per cell": _stats(self.n_faces),
            "vertices per cell": _stats(self.n_vertices),
        }

    def __str__(self) -> str:
        lines = [
            f"Mesh quality (3D): {self.n_cells} cells, {self.n_faces_total} faces, "
            f"{self.n_points} vertices",
            f"{'quantity':<26}{'min':>11}{'mean':>11}{'max':>11}",
        ]
        for name, (lo, mean, hi) in self.summary().items():
            lines.append(f"{name:<26}{lo:>11.4g}{mean:>11.4g}{hi:>11.4g}")
        lines.extend(f"WARNING: {w}" for w in self.warnings)
        if not self.warnings:
            lines.append("no warnings")
        return "\n".join(lines)


def _per_cell_min(values: FloatArray, cells: NDArray[np.int64], n: int) -> FloatArray:
    out = np.full(n, np.inf)
    np.minimum.at(out, cells, values)
    return out


def quality_report3d(
    mesh: Mesh3D,
    rho_min: float = 0.05,
    edge_min: float = 0.005,
    planarity_max: float = 1e-8,
) -> QualityReport3D:
    """Shape measures of every cell of a polyhedral mesh.

    Parameters
    ----------
    mesh : Mesh3D
    rho_min : float
        Cells with ``rho_K / h_K`` below this are reported.
    edge_min : float
        Cells with an edge shorter than ``edge_min * h_K`` are reported.
    planarity_max : float
        Faces less planar than this are reported.

    Returns
    -------
    QualityReport3D
    """
    n = mesh.n_cells
    diam = mesh.cell_diameters
    ent_cell, f = mesh.cell_of_entry, mesh.cell_faces
    # distance from the centroid to every face plane, positive inside
    dist = mesh.cell_face_signs * np.einsum(
        "ij,ij->i", mesh.face_centroids[f] - mesh.cell_centroids[ent_cell], mesh.face_normals[f]
    )
    rho = _per_cell_min(dist, ent_cell, n)
    # edges of every face, per cell
    sizes = mesh.face_sizes[f]
    e = np.repeat(np.arange(len(f)), sizes)
    k = np.repeat(mesh.face_offsets[f] - np.cumsum(sizes) + sizes, sizes) + np.arange(sizes.sum())
    P, fv = mesh.points, mesh.face_vertices
    length = np.linalg.norm(P[fv[loop_next(mesh.face_offsets)[k]]] - P[fv[k]], axis=1)
    edge = _per_cell_min(length, ent_cell[e], n)
    area = _per_cell_min(mesh.face_areas[f], ent_cell, n)
    flat_f = face_planarity(P, mesh.face_offsets, fv, mesh._face_geometry)
    flat = np.zeros(n)
    np.maximum.at(flat, ent_cell, flat_f[f])
    rep = QualityReport3D(
        n_cells=n,
        n_faces_total=mesh.n_faces,
        n_points=mesh.n_points,
        diameter=diam,
        volume_ratio=np.cbrt(np.abs(mesh.cell_volumes)) / diam,
        rho_ratio=rho / diam,
        edge_ratio=edge / diam,
        face_area_ratio=area / diam**2,
        planarity=flat,
        n_faces=np.diff(mesh.cell_offsets),
        n_vertices=np.diff(mesh.cell_vertex_offsets),
    )
    for name, values, limit, below in (
        ("rho_K / h_K", rep.rho_ratio, rho_min, True),
        ("shortest edge / h_K", rep.edge_ratio, edge_min, True),
        ("face planarity", rep.planarity, planarity_max, False),
    ):
        bad = np.flatnonzero(values < limit if below else values > limit)
        if bad.size:
            worst = bad[np.argsort(values[bad])] if below else bad[np.argsort(-values[bad])]
            extreme = values[worst[0]]
            rep.warnings.append(
                f"{bad.size} cells have {name} {'<' if below else '>'} {limit:g} "
                f"({'min' if below else 'max'} {extreme:.3g}), e.g. cells {worst[:10].tolist()}"
            )
    return rep
