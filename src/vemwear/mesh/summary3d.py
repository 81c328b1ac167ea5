"""What ``vemwear mesh inspect`` reports about a polyhedral mesh: counts, validity, quality."""

from __future__ import annotations

from typing import Any

import numpy as np

from .checks3d import check_boundary3d, check_mesh3d
from .polyhedra import Mesh3D
from .polymesh import MeshError

__all__ = ["mesh_summary3d"]


def mesh_summary3d(mesh: Mesh3D, *, quality: bool = True) -> dict[str, Any]:
    """Counts, validity and shape quality of a polyhedral mesh.

    Parameters
    ----------
    mesh : Mesh3D
    quality : bool
        Also compute :func:`vemwear.mesh.quality3d.quality_report3d` (only for a valid
        mesh).

    Returns
    -------
    dict
        JSON-ready: ``dim`` (3), ``points``, ``faces``, ``cells``, ``cells_by_faces``
        (``{n: count}``), ``h``, ``volume``, ``boundary_faces`` (per part with faces and
        ``untagged``), ``valid`` and ``error`` (the first failed check of
        :func:`~vemwear.mesh.checks3d.check_mesh3d`), ``boundary_error`` (untagged faces;
        None if every boundary face has a part), and with ``quality`` the statistics
        ``quality`` (``{"summary": {quantity: [min, mean, max]}, "warnings": [...]}``).
        The :class:`~vemwear.mesh.quality3d.QualityReport3D` itself is under ``_report``.
    """
    error: str | None = None
    try:
        check_mesh3d(mesh)
    except MeshError as exc:
        error = str(exc)
    boundary_error: str | None = None
    try:
        check_boundary3d(mesh)
    except MeshError as exc:
        boundary_error = str(exc)
    nf = np.diff(mesh.cell_offsets)
    by_faces = dict(zip(*(a.tolist() for a in np.unique(nf, return_counts=True)), strict=True))
    tags = np.asarray(mesh.boundary_tags)
    parts = {p: n for p, n in mesh.part_counts().items() if n}
    out: dict[str, Any] = {
        "dim": 3,
        "points": mesh.n_points,
        "faces": mesh.n_faces,
        "cells": mesh.n_cells,
        "cells_by_faces": {int(k): int(v) for k, v in by_faces.items()},
        "h": float(np.max(mesh.cell_diameters)) if mesh.n_cells else 0.0,
        "volume": float(np.sum(mesh.cell_volumes)),
        "boundary_faces": {**parts, "untagged": int(np.sum(tags == 0))},
        "valid": error is None,
        "error": error,
        "boundary_error": boundary_error,
    }
    if quality and error is None:
        from .quality3d import quality_report3d

        rep = quality_report3d(mesh)
        out["quality"] = {
            "summary": {k: list(v) for k, v in rep.summary().items()},
            "warnings": list(rep.warnings),
        }
        out["_report"] = rep
    return out
