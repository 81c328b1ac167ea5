"""Assigning the boundary parts of a polyhedral mesh: by side of its bounding box or by
the parts the mesh already has (a mesh file's physical groups).

The 3D analogue of :func:`vemwear.mesh.select_parts`: the sides are ``xmin``, ``xmax``,
``ymin``, ``ymax``, ``zmin`` and ``zmax`` (:data:`~vemwear.mesh.generate3d.BOX_SIDES`), a
boundary face lying on a side when all its vertices do; segments have no meaning on a
surface and are refused.
"""

from __future__ import annotations

import difflib
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .generate3d import BOX_SIDES, _on_sides
from .polyhedra import Mesh3D
from .polymesh import part_names_with

__all__ = ["select_parts3d"]


def _bounds(mesh: Mesh3D) -> str:
    lo, hi = mesh.points.min(axis=0), mesh.points.max(axis=0)
    return " x ".join(f"[{a:g}, {b:g}]" for a, b in zip(lo, hi, strict=True))


def _face_text(mesh: Mesh3D, f: int) -> str:
    c = mesh.face_centroids[f]
    return f"face {f} (centroid ({c[0]:.6g}, {c[1]:.6g}, {c[2]:.6g}))"


def _named(mesh: Mesh3D, part: str, it: Any) -> NDArray[np.bool_]:
    """The boundary faces of the mesh's own part ``it`` (for the selector of ``part``)."""
    if not isinstance(it, str):
        raise ValueError(
            f"{part}: a segment selects boundary edges of a 2D mesh; on a 3D mesh give a side "
            f"({', '.join(BOX_SIDES)}) or a part of the mesh file"
        )
    own = [n for n in mesh.part_names if len(mesh.part_faces(n))]
    if it in own:
        return np.asarray(mesh.boundary_tags == mesh.part_names.index(it) + 1)
    own = [n for n in own if n not in BOX_SIDES]  # the sides are listed anyway
    close = difflib.get_close_matches(it, [*BOX_SIDES, "rest", *own], n=1, cutoff=0.6)
    parts = f"; the mesh's parts are {', '.join(own)}" if own else ""
    hint = f"; did you mean {close[0]!r}?" if close else ""
    raise ValueError(
        f"{part} is neither a side ({', '.join(BOX_SIDES)}), 'rest' nor a part of "
        f"the mesh{parts}{hint}"
    )


def select_parts3d(mesh: Mesh3D, parts: Mapping[str, Any], rtol: float = 1e-9) -> Mesh3D:
    """Tag boundary parts of a polyhedral mesh given by selectors; every face in at most
    one part.

    Parameters
    ----------
    mesh : Mesh3D
    parts : mapping
        ``{part: selector}``. A selector is a side of the bounding box (``"xmin"``, ...,
        ``"zmax"``), the name of a part the mesh already has, a list of these, or
        ``"rest"`` (the faces no other part selects; one part at most).
    rtol : float
        A face lies on a side when its vertices are within ``rtol`` times the box's
        largest side of it.

    Returns
    -------
    Mesh3D
        With these parts tagged (other tags removed; faces of no part are untagged,
        i.e. traction-free).

    Raises
    ------
    ValueError
        If a selector is unknown or selects no face, or two parts select the same face;
        the message starts with the part.
    """
    bf = mesh.boundary_faces
    on = _on_sides(mesh, bf, rtol)
    hits: dict[str, NDArray[np.bool_]] = {}
    for name, spec in parts.items():
        if isinstance(spec, str) and spec == "rest":
            continue
        hit = np.zeros(len(bf), dtype=bool)
        for it in [spec] if isinstance(spec, str | tuple) else spec:
            if isinstance(it, str) and it in BOX_SIDES:
                hit |= on[:, BOX_SIDES.index(it)]
            else:
                hit |= _named(mesh, name, it)
        if not hit.any():
            raise ValueError(f"{name} selects no boundary face (the mesh spans {_bounds(mesh)})")
        for other, ohit in hits.items():
            both = np.flatnonzero(hit & ohit)
            if both.size:
                more = f" and {both.size - 1} more" if both.size > 1 else ""
                raise ValueError(
                    f"parts {other!r} and {name!r} overlap: both select the boundary "
                    f"{_face_text(mesh, int(bf[both[0]]))}{more}; every boundary face must "
                    "belong to exactly one part"
                )
        hits[name] = hit
    rest = [n for n in parts if n not in hits]
    if len(rest) > 1:
        raise ValueError(f"only one part can be 'rest', got {', '.join(rest)}")
    taken = np.any(list(hits.values()), axis=0) if hits else np.zeros(len(bf), dtype=bool)
    if rest and np.all(taken):
        raise ValueError(f"{rest[0]} selects no boundary face: every face is in another part")
    names = part_names_with(mesh.part_names, list(parts))
    tags = np.zeros(len(bf), dtype=np.int8)
    for name, hit in hits.items():
        tags[hit] = names.index(name) + 1
    for name in rest:
        tags[~taken] = names.index(name) + 1
    return mesh.with_tags(tags, names)
