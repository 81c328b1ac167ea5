"""Assigning boundary parts: by side of a bounding box, by segment, or by predicate."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from .polymesh import Mesh

SIDES = ("left", "right", "bottom", "top")


def side_predicate(mesh: Mesh, side: str, rtol: float = 1e-9):
    """Predicate selecting edge midpoints on one side of the mesh's bounding box."""
    lo, hi = mesh.points.min(axis=0), mesh.points.max(axis=0)
    tol = rtol * float(np.max(hi - lo))
    if side == "left":
        return lambda m: np.abs(m[:, 0] - lo[0]) <= tol
    if side == "right":
        return lambda m: np.abs(m[:, 0] - hi[0]) <= tol
    if side == "bottom":
        return lambda m: np.abs(m[:, 1] - lo[1]) <= tol
    if side == "top":
        return lambda m: np.abs(m[:, 1] - hi[1]) <= tol
    raise ValueError(f"unknown side {side!r}; expected one of {', '.join(SIDES)}")


def segment_predicate(a: Sequence[float], b: Sequence[float], rtol: float = 1e-9):
    """Predicate selecting edge midpoints that lie on the closed segment [a, b]."""
    a_ = np.asarray(a, dtype=float)
    b_ = np.asarray(b, dtype=float)
    d = b_ - a_
    L = float(np.linalg.norm(d))
    if L == 0.0:
        raise ValueError(f"segment end points coincide: {a_.tolist()}")
    tol = rtol * max(L, 1.0)

    def pred(m: NDArray[np.float64]) -> NDArray[np.bool_]:
        r = m - a_
        s = r @ d / L
        dist = np.abs(r[:, 0] * d[1] - r[:, 1] * d[0]) / L
        return (dist <= tol) & (s >= -tol) & (s <= L + tol)

    return pred


def tag_rectangle(
    mesh: Mesh,
    parts: Mapping[str, Sequence[str] | str] | None = None,
) -> Mesh:
    """Tag the sides of a rectangular mesh; defaults to the paper's Section 5 layout.

    ``parts`` maps part names to a side or a list of sides; the default is
    clamped = left, traction = top and right, contact = bottom.
    """
    if parts is None:
        parts = {"clamped": "left", "traction": ["top", "right"], "contact": "bottom"}
    preds = {}
    for name, sides in parts.items():
        sides = [sides] if isinstance(sides, str) else list(sides)
        fs = [side_predicate(mesh, s) for s in sides]
        preds[name] = lambda m, fs=fs: np.any([f(m) for f in fs], axis=0)
    return mesh.with_boundary(preds)
