"""Checks of a configuration that no library object makes, on the mesh and problem built.

The vectors of the file have as many components as the mesh has dimensions, and
``uz`` is given on 3D meshes only (:func:`check_dims`); ``v_star``
(:func:`check_velocity`) and the loads (:func:`check_loads`) given by expressions or
tables are finite at every time level (an expression may overflow or divide by zero).
Each failure is a :class:`~vemwear.config.errors.ConfigError` naming the key.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..contact import velocity_levels
from ..mesh.polyhedra import Mesh3D
from ..simulate import Problem
from ..vem import body_force_vector, edge_load_vector
from . import schema as s
from .errors import ConfigError
from .fields import FieldExpression, VelocityExpression
from .mesh_forms import MeshFile
from .parts import Roles

__all__ = ["check_dims", "check_loads", "check_velocity"]


def _pt(p: NDArray[np.float64]) -> str:
    return "(" + ", ".join(f"{v:.6g}" for v in p) + ")"


def check_dims(src: str, c: s.ConfigFile, raw: Mapping[str, Any], dim: int) -> None:
    """The vectors of the file have ``dim`` components (2 on a 2D mesh, 3 on a 3D one)
    and ``uz`` is given on 3D meshes only."""
    names = {2: "[x, y]", 3: "[x, y, z]"}
    what = f"a {dim}D mesh"
    if not isinstance(c.mesh, MeshFile):
        what += f" ({c.mesh.generator!r})"

    def need(path: str, v: Any) -> None:
        if isinstance(v, list) and len(v) != dim:
            raise ConfigError(
                f"{src}: {path} = {show_raw(v)} has {len(v)} components; {what} needs {dim} "
                f"{names[dim]}"
            )

    loads = raw.get("loads", {})
    for key in ("f1", "f2"):
        if key in loads:
            need(f"[loads] {key}", loads[key])
    b = raw.get("boundary")
    if isinstance(b, dict):
        tr = b.get("traction")
        if isinstance(tr, list):
            for i, t in enumerate(tr):
                if isinstance(t, dict):
                    need(f"[[boundary.traction]] {i + 1} f2", t.get("f2"))
        for i, d in enumerate(b.get("displacement") or []):
            if dim == 2 and isinstance(d, dict) and "uz" in d:
                raise ConfigError(
                    f"{src}: [[boundary.displacement]] {i + 1}: uz is a component of 3D meshes; "
                    f"{what} has ux and uy"
                )
    tables = raw["contact"] if isinstance(raw["contact"], list) else [raw["contact"]]
    for i, t in enumerate(tables):
        path = f"[[contact]] {i + 1}" if isinstance(raw["contact"], list) else "[contact]"
        v = t.get("v_star")
        if isinstance(v, dict):
            for j, row in enumerate(v.get("values", [])):
                need(f"{path} v_star.values[{j}]", row)
        else:
            need(f"{path} v_star", v)


def show_raw(v: Any) -> str:
    """A TOML array as written (short)."""
    text = "[" + ", ".join(repr(x) if isinstance(x, str) else f"{x:g}" for x in v) + "]"
    return text if len(text) <= 60 else text[:57] + "..."


def check_velocity(src: str, pr: Problem, parts: Roles) -> None:
    """``v_star`` is a finite 2-vector at every time level (an expression or a table of t
    may overflow or divide by zero)."""
    where = {name: path for name, _, _, path in parts.contacts}
    t = pr.time.t
    for pc in pr.parts:
        with np.errstate(all="ignore"):
            V = velocity_levels(pc.velocity, t)
        bad = np.flatnonzero(~np.all(np.isfinite(V), axis=1))
        if bad.size:
            n = int(bad[0])
            spec = pc.velocity.spec
            text = f" = {spec.__name__}" if isinstance(spec, VelocityExpression) else ""
            raise ConfigError(
                f"{src}: {where.get(pc.part, '[contact]')} v_star{text} is not finite at t = "
                f"{t[n]:g} (level {n}): v* = ({V[n, 0]:g}, {V[n, 1]:g})"
            )


def check_loads(src: str, pr: Problem, parts: Roles) -> None:
    """Loads given by expressions or tables give finite load vectors at every time level."""
    fields: list[tuple[str, Any, NDArray[np.int64] | None]] = [("[loads] f1", pr.f1, None)]
    three = isinstance(pr.mesh, Mesh3D)
    fields += [
        (
            f"{parts.where[n]} f2" if n in parts.tractions else "[loads] f2",
            f,
            pr.mesh.part_faces(n) if isinstance(pr.mesh, Mesh3D) else pr.mesh.part_edges(n),
        )
        for n, f in pr.tractions.items()
    ]
    for name, f, edges in fields:
        if not isinstance(f, FieldExpression):
            continue
        with np.errstate(all="ignore"):
            for n in range(len(pr.time.t)) if f.uses_t else range(1):
                t = float(pr.time.t[n])
                try:
                    if three:
                        sp = pr.space
                        F = sp.body_force(f, t) if edges is None else sp.boundary_load(edges, f, t)
                        F = F.reshape(-1, 3)
                    else:
                        F = (
                            body_force_vector(pr.mesh, f, t)
                            if edges is None
                            else edge_load_vector(pr.mesh, edges, f, t)
                        ).reshape(-1, 2)
                except ValueError as exc:  # a table
                    raise ConfigError(f"{src}: {name}{str(exc).removeprefix('f2')}") from None
                bad = np.flatnonzero(~np.all(np.isfinite(F), axis=1))
                if bad.size:
                    v = int(bad[0])
                    when = f" at t = {pr.time.t[n]:g} (level {n})" if f.uses_t else ""
                    raise ConfigError(
                        f"{src}: {name} = {f.__name__} is not finite near vertex {v} "
                        f"(x = {_pt(pr.mesh.points[v])}){when}"
                    )


#: Lengths a run can compute with: areas, volumes and the stiffness (lengths to the
#: power 1 to 3 and their inverses) stay far from IEEE underflow and overflow.
LENGTH_RANGE = (1e-100, 1e100)


def check_scales(src: str, mesh: Any, c: s.ConfigFile) -> None:
    """Refuse a body or a layer thickness of a size that floating point cannot compute
    with, naming it (a tiny body's cell areas underflow and the stiffness overflows,
    which else surfaced as a message on the material; a huge g overflowed the check of
    the compliance law)."""
    lo, hi = LENGTH_RANGE
    pts = np.asarray(mesh.points)
    extent = float(np.max(pts.max(axis=0) - pts.min(axis=0))) if pts.size else 0.0
    if not lo <= extent <= hi:
        raise ConfigError(
            f"{src}: [mesh] the body measures {extent:g} across: too small or too large to "
            f"compute with (its cell measures and the stiffness under- or overflow); use "
            f"units in which its size lies between {lo:g} and {hi:g}"
        )
    parts = c.contact if isinstance(c.contact, list) else [c.contact]  # [[contact]] parts
    for i, part in enumerate(parts):
        g = getattr(part, "g", None)
        if isinstance(g, int | float) and not abs(g) <= hi:
            where = "[contact]" if len(parts) == 1 else f"[[contact]] {i + 1}"
            raise ConfigError(
                f"{src}: {where} g = {g:g} is too large to compute with (the layer's "
                f"penetrations and the law p(r) on them overflow); use units in which it is "
                f"at most {hi:g}"
            )
