"""What ``vemwear mesh inspect`` reports about a mesh: counts, validity and A1 quality."""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .checks import check_boundary, check_cells, check_conforming, check_vertices
from .polymesh import Mesh, MeshError
from .quality import hanging_nodes, quality_report

__all__ = ["contact_nodes", "mesh_summary"]


def contact_nodes(mesh: Mesh) -> NDArray[np.int64]:
    """Vertices on the closure of the contact part that are not on the clamped part.

    These carry the contact quadrature and the wear (docs/method.md, nodal contact
    quadrature).
    """
    return np.setdiff1d(mesh.part_vertices("contact"), mesh.part_vertices("clamped"))


def _try(check: Callable[[], None]) -> str | None:
    try:
        check()
    except MeshError as exc:
        return str(exc)
    return None


def mesh_summary(mesh: Mesh, *, quality: bool = True) -> dict[str, Any]:
    """Counts, validity and A1 quality of a mesh (what ``vemwear mesh inspect`` shows).

    Parameters
    ----------
    mesh : Mesh
    quality : bool
        Also compute :func:`vemwear.mesh.quality_report` (only for meshes whose cells
        are valid).

    Returns
    -------
    dict
        JSON-ready: ``points``, ``cells``, ``cells_by_vertices`` (``{n: count}``),
        ``h``, ``area``, ``boundary_edges`` (per part and ``untagged``),
        ``contact_nodes``, ``hanging_nodes``, ``valid`` and ``error`` (the first
        failed check of vertices, cells and conformity), ``boundary_error`` (untagged
        edges or a missing clamped/contact part; None if complete), and with
        ``quality`` the A1 statistics ``quality`` (``{quantity: [min, mean, max]}``,
        ``gamma1``, ``gamma2``, ``convex``, ``not_star_shaped``, ``warnings``). The
        :class:`~vemwear.mesh.QualityReport` itself is under the key ``_report``.
    """
    tags = mesh.boundary_tags
    error = None
    for check in (check_vertices, check_cells, check_conforming):
        error = _try(partial(check, mesh))
        if error is not None:
            break
    out: dict[str, Any] = {
        "points": mesh.n_points,
        "cells": mesh.n_cells,
        "cells_by_vertices": {int(n): len(ids) for n, (ids, _v) in sorted(mesh.groups.items())},
        "h": float(mesh.h),
        "area": float(np.sum(mesh.cell_areas)),
        "boundary_edges": {
            **mesh.part_counts(),
            "untagged": int(np.sum(tags == 0)),
        },
        "contact_nodes": len(contact_nodes(mesh)),
        "hanging_nodes": len(hanging_nodes(mesh)),
        "valid": error is None,
        "error": error,
        "boundary_error": _try(lambda: check_boundary(mesh, ("clamped", "contact"))),
    }
    if quality and error is None:
        rep = quality_report(mesh)
        out["quality"] = {
            "summary": {k: list(v) for k, v in rep.summary().items()},
            "gamma1": rep.gamma1,
            "gamma2": rep.gamma2,
            "convex": int(np.sum(rep.convex)),
            "not_star_shaped": int(np.sum(~rep.star_shaped)),
            "warnings": list(rep.warnings),
        }
        out["_report"] = rep
    return out
