"""Assigning boundary parts: by side of a bounding box, by segment, or by predicate."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .polymesh import Mesh

SIDES = ("left", "right", "bottom", "top")
#: The names of the 3D box's sides, accepted for the sides of a rectangle too.
SIDE_ALIASES = {"xmin": "left", "xmax": "right", "ymin": "bottom", "ymax": "top"}


def side_predicate(mesh: Mesh, side: str, rtol: float = 1e-9):
    """Predicate selecting edge midpoints on one side of the mesh's bounding box
    (``left``, ``right``, ``bottom``, ``top`` or ``xmin``, ``xmax``, ``ymin``, ``ymax``)."""
    side = SIDE_ALIASES.get(side, side)
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


def _pt(p: NDArray[np.float64]) -> str:
    return f"({p[0]:.6g}, {p[1]:.6g})"


def select_parts(mesh: Mesh, parts: Mapping[str, Any]) -> Mesh:
    """Tag boundary parts given by selectors; every edge selected by at most one part.

    Parameters
    ----------
    mesh : Mesh
    parts : mapping
        ``{part: selector}``. A selector is a side of the bounding box (``"left"``,
        ``"right"``, ``"bottom"``, ``"top"``), a segment ``(a, b)`` (the boundary edges
        lying on it), the name of a part the mesh already has (a gmsh physical group),
        a list of these, or ``"rest"`` (the edges no other part selects; one part at
        most). Edges are selected by their midpoints.

    Returns
    -------
    Mesh
        With these parts tagged (other tags removed).

    Raises
    ------
    ValueError
        If a selector selects no edge or two parts select the same edge; the message
        starts with the part and names an edge by its vertex ids and end points.
    """
    edges = mesh.boundary_edges
    mid = mesh.edge_midpoints(edges)
    hits: dict[str, NDArray[np.bool_]] = {}
    for name, spec in parts.items():
        if isinstance(spec, str) and spec == "rest":
            continue
        hit = np.zeros(len(edges), dtype=bool)
        for it in [spec] if isinstance(spec, str | tuple) else spec:
            if isinstance(it, str) and it not in SIDES and it not in SIDE_ALIASES:
                hit |= _named(mesh, name, it)
                continue
            try:
                pred = side_predicate(mesh, it) if isinstance(it, str) else segment_predicate(*it)
            except ValueError as exc:
                raise ValueError(f"{name}: {exc}") from None
            hit |= np.asarray(pred(mid), dtype=bool)
        if not hit.any():
            lo, hi = mesh.points.min(axis=0), mesh.points.max(axis=0)
            raise ValueError(
                f"{name} selects no boundary edge (the mesh spans [{lo[0]:g}, {hi[0]:g}] x "
                f"[{lo[1]:g}, {hi[1]:g}]; segments select the boundary edges lying on them)"
            )
        for other, ohit in hits.items():
            both = np.flatnonzero(hit & ohit)
            if both.size:
                a, b = edges[both[0]]
                more = f" and {both.size - 1} more" if both.size > 1 else ""
                raise ValueError(
                    f"parts {other!r} and {name!r} overlap: both select the boundary edge "
                    f"({a}, {b}) from {_pt(mesh.points[a])} to {_pt(mesh.points[b])}{more}; "
                    "every boundary edge must belong to exactly one part"
                )
        hits[name] = hit
    rest = [n for n in parts if n not in hits]
    if len(rest) > 1:
        raise ValueError(f"only one part can be 'rest', got {', '.join(rest)}")
    if rest and hits and np.all(np.any(list(hits.values()), axis=0)):
        raise ValueError(f"{rest[0]} selects no boundary edge: every edge is in another part")
    preds: dict[str, Any] = {n: (lambda m, h=h: h) for n, h in hits.items()}
    return mesh.with_boundary({**preds, **dict.fromkeys(rest, "rest")})


def _named(mesh: Mesh, part: str, it: str) -> NDArray[np.bool_]:
    """The boundary edges of the mesh's own part ``it`` (for the selector of ``part``)."""
    import difflib

    if it in mesh.parts:
        return np.asarray(mesh.boundary_tags == mesh.part_code(it))
    close = difflib.get_close_matches(it, [*SIDES, "rest", *mesh.parts], n=1, cutoff=0.6)
    own = f"; the mesh's parts are {', '.join(mesh.parts)}" if mesh.parts else ""
    hint = f"; did you mean {close[0]!r}?" if close else ""
    raise ValueError(
        f"{part} is neither a side ({', '.join(SIDES)}), 'rest' nor a part of the mesh{own}{hint}"
    )


def tag_rectangle(
    mesh: Mesh,
    parts: Mapping[str, Sequence[str] | str] | None = None,
) -> Mesh:
    """Tag the sides of a rectangular mesh; defaults to the paper's Section 5 layout.

    Parameters
    ----------
    mesh : Mesh
        A mesh of an axis-aligned rectangle.
    parts : mapping, optional
        Part name (``clamped`` = Gamma_D, ``traction`` = Gamma_N, ``contact`` = Gamma_C)
        to a side (``left``, ``right``, ``bottom``, ``top``) or a list of sides; the
        default is clamped = left, traction = top and right, contact = bottom.

    Returns
    -------
    Mesh
        The mesh with its boundary edges tagged.

    Examples
    --------
    >>> from vemwear.mesh import rectangle_squares, tag_rectangle
    >>> mesh = tag_rectangle(rectangle_squares((2.0, 1.0), (4, 2)))
    >>> mesh.part_names
    ('clamped', 'traction', 'contact')
    >>> parts = {"rollers": ["left", "right"], "contact": "bottom", "top": "top"}
    >>> rollers = tag_rectangle(rectangle_squares((2.0, 1.0), (4, 2)), parts)
    >>> rollers.part_counts()  # boundary edges per part
    {'clamped': 0, 'traction': 0, 'contact': 4, 'rollers': 4, 'top': 4}
    """
    if parts is None:
        parts = {"clamped": "left", "traction": ["top", "right"], "contact": "bottom"}
    preds = {}
    for name, sides in parts.items():
        sides = [sides] if isinstance(sides, str) else list(sides)
        fs = [side_predicate(mesh, s) for s in sides]
        preds[name] = lambda m, fs=fs: np.any([f(m) for f in fs], axis=0)
    return mesh.with_boundary(preds)
