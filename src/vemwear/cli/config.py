"""TOML configuration files: parsing and validation into a :class:`Problem`.

A configuration file is data only (read with :mod:`tomllib`, never evaluated).
Every key is checked before any computation: unknown keys (with the closest valid
key as a suggestion), wrong types, missing sections and keys, signs of the data,
output times that are not time levels and missing mesh files are reported as a
:class:`ConfigError` whose message starts with the file name and names the key,
e.g. ``config.toml: [contact] mu must be >= 0, got -0.2``.

The schema is documented key by key in ``docs/config.md``.
"""

from __future__ import annotations

import contextlib
import difflib
import inspect
import io
import math
import re
import tomllib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import meshio
import numpy as np
from numpy.typing import NDArray

from ..contact import (
    ComplianceLaw,
    LinearCompliance,
    TableCompliance,
    contact_boundary,
    nodal_values,
)
from ..mesh import Mesh, MeshError, segment_predicate, side_predicate
from ..mesh.boundary import SIDES
from ..mesh.checks import check_cells, check_conforming, check_vertices
from ..mesh.io import from_meshio
from ..mesh.polymesh import PARTS, part_code
from ..simulate import Problem, SolverOptions, TimeGrid
from ..solvers import BACKENDS, SOLVERS, resolve_backend
from ..vem import STABILIZATIONS, Material, body_force_vector, traction_vector
from .expr import Expression, ExpressionError, parse_expression

__all__ = [
    "Config",
    "ConfigError",
    "OutputOptions",
    "build_mesh",
    "load_config",
    "mesh_families",
    "parse_config",
    "smallness_report",
]


class ConfigError(ValueError):
    """Invalid input: the message names the file, the key path and the problem."""


@dataclass(frozen=True)
class OutputOptions:
    """What ``vemwear run`` writes besides ``result.npz`` and ``summary.json``.

    Parameters
    ----------
    times : tuple of float
        Times of the contact-profile figure; each is a level of the time grid.
    figures : bool
        Write the PNG figures.
    vtk : bool
        Write the VTK series (``vtk/*.vtu`` and a ``.pvd`` collection).
    """

    times: tuple[float, ...] = ()
    figures: bool = True
    vtk: bool = True


@dataclass(frozen=True, eq=False)
class Config:
    """A validated configuration file.

    Attributes
    ----------
    path : Path or None
        The file it was read from (None for a dictionary parsed directly).
    data : dict
        The raw TOML data (JSON-friendly; stored in ``summary.json``).
    title : str
        The ``title`` key, or the file stem.
    problem : Problem
        The contact problem with its mesh, data and time grid.
    solver : SolverOptions
        The ``[solver]`` section.
    output : OutputOptions
        The ``[output]`` section.
    """

    path: Path | None
    data: dict[str, Any]
    title: str
    problem: Problem
    solver: SolverOptions
    output: OutputOptions
    mesh_source: dict[str, Any] = field(default_factory=dict)


# ---------------------------------------------------------------------------- schema
#: Sections, their keys and whether the section is required.
_SECTIONS: dict[str, tuple[tuple[str, ...], bool]] = {
    "mesh": ((), True),  # keys depend on the generator, checked in _mesh
    "boundary": (("clamped", "traction", "contact"), False),
    "material": (("lam", "eta"), True),
    "vem": (("stabilization",), False),
    "loads": (("f1", "f2"), False),
    "contact": (("p", "g", "mu", "kappa", "v_star"), True),
    "time": (("T", "steps", "dt", "pattern", "levels"), True),
    "solver": (("method", "tol", "max_iter", "backend"), False),
    "output": (("times", "figures", "vtk"), False),
}
_TOP_SCALARS = ("title",)
_GRID_KEYS = ("size", "origin", "divisions")
_TOML_TYPE = {
    str: "a string",
    int: "an integer",
    float: "a float",
    bool: "a boolean",
    list: "an array",
    dict: "a table",
}


def _kind(v: Any) -> str:
    for t, name in _TOML_TYPE.items():
        if type(v) is t:
            return name
    return f"a {type(v).__name__}"


def _show(v: Any) -> str:
    s = repr(v)
    return s if len(s) <= 60 else s[:57] + "..."


class _Checker:
    """Type and value checks that raise :class:`ConfigError` with the key path."""

    def __init__(self, source: str) -> None:
        self.source = source

    def fail(self, where: str, msg: str) -> ConfigError:
        return ConfigError(f"{self.source}: {where} {msg}" if where else f"{self.source}: {msg}")

    # -- structure
    def table(self, v: Any, where: str) -> dict[str, Any]:
        if not isinstance(v, dict):
            raise self.fail(where, f"must be a table, got {_kind(v)} ({_show(v)})")
        return v

    def keys(
        self,
        tbl: Mapping[str, Any],
        allowed: Sequence[str],
        where: str,
        required: Sequence[str] = (),
    ) -> None:
        for k in tbl:
            if k not in allowed:
                raise self.fail(where, f"unknown key {k!r}{_suggest(k, allowed)}")
        for k in required:
            if k not in tbl:
                raise self.fail(where, f"missing required key {k!r}")

    # -- scalars
    def number(
        self, v: Any, where: str, *, gt: float | None = None, ge: float | None = None
    ) -> float:
        if isinstance(v, bool) or not isinstance(v, int | float):
            raise self.fail(where, f"must be a number, got {_kind(v)} ({_show(v)}){_unit_hint(v)}")
        x = float(v)
        if not math.isfinite(x):
            raise self.fail(where, f"must be a finite number, got {v}")
        if gt is not None and not x > gt:
            raise self.fail(where, f"must be > {gt:g}, got {v}")
        if ge is not None and not x >= ge:
            raise self.fail(where, f"must be >= {ge:g}, got {v}")
        return x

    def integer(self, v: Any, where: str, *, ge: int | None = None) -> int:
        if isinstance(v, bool) or not isinstance(v, int):
            raise self.fail(where, f"must be an integer, got {_kind(v)} ({_show(v)})")
        if ge is not None and v < ge:
            raise self.fail(where, f"must be >= {ge}, got {v}")
        return int(v)

    def string(self, v: Any, where: str, choices: Sequence[str] | None = None) -> str:
        if not isinstance(v, str):
            raise self.fail(where, f"must be a string, got {_kind(v)} ({_show(v)})")
        if choices is not None and v not in choices:
            raise self.fail(
                where,
                f"must be one of {', '.join(repr(c) for c in choices)}, got {v!r}"
                f"{_suggest(v, choices)}",
            )
        return v

    def boolean(self, v: Any, where: str) -> bool:
        if not isinstance(v, bool):
            raise self.fail(where, f"must be true or false, got {_kind(v)} ({_show(v)})")
        return v

    def array(self, v: Any, where: str, *, min_len: int = 1) -> list[Any]:
        if not isinstance(v, list):
            raise self.fail(where, f"must be an array, got {_kind(v)} ({_show(v)})")
        if len(v) < min_len:
            raise self.fail(where, f"must have at least {min_len} entries, got {len(v)}")
        return v

    def vector(self, v: Any, where: str) -> tuple[float, float]:
        if not isinstance(v, list) or len(v) != 2:
            raise self.fail(where, f"must be an array of 2 numbers [x, y], got {_show(v)}")
        return (self.number(v[0], f"{where}[0]"), self.number(v[1], f"{where}[1]"))

    def numbers(
        self,
        v: Any,
        where: str,
        *,
        min_len: int = 1,
        gt: float | None = None,
        ge: float | None = None,
        increasing: bool = False,
    ) -> list[float]:
        arr = self.array(v, where, min_len=min_len)
        out = [self.number(x, f"{where}[{i}]", gt=gt, ge=ge) for i, x in enumerate(arr)]
        if increasing:
            for i in range(len(out) - 1):
                if not out[i + 1] > out[i]:
                    raise self.fail(
                        where,
                        f"must increase strictly, but entry {i + 1} ({out[i + 1]:g}) "
                        f"<= entry {i} ({out[i]:g})",
                    )
        return out


_UNIT_RE = re.compile(r"^\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*[A-Za-z%\u00b5]")


def _unit_hint(v: Any) -> str:
    """A hint for numbers written with a unit, e.g. ``"4 GPa"``."""
    if isinstance(v, str) and _UNIT_RE.match(v):
        return (
            "; units are not accepted: write plain numbers in consistent units "
            "(docs/config.md, 'Units')"
        )
    return ""


def _suggest(word: str, valid: Sequence[str]) -> str:
    close = difflib.get_close_matches(word, list(valid), n=1, cutoff=0.6)
    if close:
        return f"; did you mean {close[0]!r}?"
    if valid:
        return f"; valid keys: {', '.join(valid)}"
    return ""


# ---------------------------------------------------------------------------- mesh
_NOT_FAMILIES = frozenset({"read_mesh", "write_mesh", "check_mesh", "tag_rectangle"})


def _returns_mesh(fn: Callable[..., Any]) -> bool:
    try:
        ann = inspect.signature(fn).return_annotation
    except (TypeError, ValueError):  # pragma: no cover - builtins
        return False
    text = ann if isinstance(ann, str) else getattr(ann, "__name__", repr(ann))
    return "Mesh" in str(text)


def _takes_no_mesh(fn: Callable[..., Any]) -> bool:
    """True unless the first parameter is a mesh (a transformation, not a generator)."""
    try:
        params = list(inspect.signature(fn).parameters)
    except (TypeError, ValueError):  # pragma: no cover
        return True
    return not params or params[0] != "mesh"


def mesh_families() -> dict[str, Callable[..., Mesh]]:
    """Mesh generators available as ``[mesh] generator = NAME``.

    The short names of :data:`vemwear.mesh.GENERATORS` (those of ``vemwear mesh
    generate``), and every public generator function of :mod:`vemwear.mesh` (one
    returning a ``Mesh`` without taking one) under its function name.
    """
    from .. import mesh as mesh_pkg

    fams: dict[str, Callable[..., Mesh]] = {}
    for n in list(getattr(mesh_pkg, "__all__", dir(mesh_pkg))):
        obj = getattr(mesh_pkg, n, None)
        if (
            not n.startswith("_")
            and n not in _NOT_FAMILIES
            and inspect.isfunction(obj)
            and _returns_mesh(obj)
            and _takes_no_mesh(obj)
        ):
            fams[n] = obj
    fams.update(mesh_pkg.GENERATORS)
    return fams


def _family_names(fams: Mapping[str, Callable[..., Mesh]]) -> list[str]:
    """Names to show: one per generator, the short one if there is one."""
    seen: dict[int, str] = {}
    for name, fn in sorted(fams.items(), key=lambda kv: (len(kv[0]), kv[0])):
        seen.setdefault(id(fn), name)
    return sorted(seen.values())


def _generator_args(
    ck: _Checker, sec: dict[str, Any], fn: Callable[..., Mesh], gen: str
) -> dict[str, Any]:
    """Check the generator's parameters against its signature and convert arrays to tuples."""
    where = "[mesh]"
    try:
        sig = inspect.signature(fn)
        params = [
            p
            for p in sig.parameters.values()
            if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)
        ]
        has_var_kw = any(p.kind == p.VAR_KEYWORD for p in sig.parameters.values())
    except (TypeError, ValueError):  # pragma: no cover - builtins without signature
        params, has_var_kw = [], True
    allowed = [p.name for p in params]
    required = [p.name for p in params if p.default is inspect.Parameter.empty]
    kwargs: dict[str, Any] = {}
    # families on a polygonal ``domain`` (e.g. voronoi) also accept size/origin (a rectangle)
    rect_domain = "domain" in allowed and "size" not in allowed
    if rect_domain and ("size" in sec or "origin" in sec):
        if "domain" in sec:
            raise ck.fail(where, "must give either 'domain' or 'size'/'origin', not both")
        size = _size(ck, sec.get("size", [1.0, 1.0]), f"{where} size")
        x0, y0 = ck.vector(sec.get("origin", [0.0, 0.0]), f"{where} origin")
        kwargs["domain"] = (
            (x0, y0),
            (x0 + size[0], y0),
            (x0 + size[0], y0 + size[1]),
            (x0, y0 + size[1]),
        )
    for k, v in sec.items():
        if k in ("generator", "file") or (rect_domain and k in ("size", "origin")):
            continue
        if k == "return_seeds":
            raise ck.fail(where, f"unknown key {k!r} for generator {gen!r}")
        if k not in allowed and not has_var_kw:
            raise ck.fail(
                where,
                f"unknown key {k!r} for generator {gen!r}{_suggest(k, ['generator', *allowed])}",
            )
        if k in _GRID_KEYS and gen in ("squares", "triangles"):
            if k == "divisions":
                if not isinstance(v, list) or len(v) != 2:
                    raise ck.fail(
                        f"{where} divisions",
                        f"must be an array of 2 integers [nx, ny], got {_show(v)}",
                    )
                kwargs[k] = tuple(
                    ck.integer(x, f"{where} divisions[{i}]", ge=1) for i, x in enumerate(v)
                )
            elif k == "size":
                kwargs[k] = _size(ck, v, f"{where} size")
            else:
                kwargs[k] = ck.vector(v, f"{where} {k}")
            continue
        kwargs[k] = _to_python(ck, v, f"{where} {k}")
    missing = [r for r in required if r not in kwargs]
    if missing:
        raise ck.fail(where, f"missing required key {missing[0]!r} for generator {gen!r}")
    return kwargs


def _size(ck: _Checker, v: Any, where: str) -> tuple[float, float]:
    """Side lengths ``[lx, ly]`` of a rectangle, both > 0."""
    size = ck.vector(v, where)
    for i, x in enumerate(size):
        if not x > 0:
            raise ck.fail(f"{where}[{i}]", f"must be > 0, got {x:g}")
    return size


def _to_python(ck: _Checker, v: Any, where: str) -> Any:
    """Generic generator argument: arrays become tuples; numbers must be finite."""
    if isinstance(v, list):
        return tuple(_to_python(ck, x, f"{where}[{i}]") for i, x in enumerate(v))
    if isinstance(v, float) and not math.isfinite(v):
        raise ck.fail(where, f"must be a finite number, got {v}")
    if isinstance(v, dict):
        return {k: _to_python(ck, x, f"{where}.{k}") for k, x in v.items()}
    return v


def _check_dangling(ck: _Checker, raw: meshio.Mesh, where: str) -> None:
    """Vertices of a mesh file that no polygonal cell uses (the reader would drop them)."""
    n = len(raw.points)
    used = np.zeros(n, dtype=bool)
    for block in raw.cells:
        if block.type in ("triangle", "quad") or block.type.startswith("polygon"):
            data = np.asarray(block.data, dtype=np.int64).ravel()
            if data.size and (data.min() < 0 or data.max() >= n):
                raise ck.fail(where, f"cells refer to vertex ids outside 0..{n - 1}")
            used[data] = True
    if used.any() and not used.all():
        bad = np.flatnonzero(~used)
        more = f" and {bad.size - 10} more" if bad.size > 10 else ""
        raise ck.fail(
            where,
            f"vertices {bad[:10].tolist()}{more} belong to no cell "
            "(dangling); remove them from the file",
        )


def _check_tag_conflicts(ck: _Checker, raw: meshio.Mesh, where: str) -> None:
    """No edge of a mesh file is tagged with two different boundary parts."""
    names = {int(v[0]): k for k, v in (raw.field_data or {}).items() if len(v)}
    seen: dict[tuple[int, int], int] = {}
    for bi, block in enumerate(raw.cells):
        if block.type != "line":
            continue
        if "part" in raw.cell_data:
            codes = np.asarray(raw.cell_data["part"][bi], dtype=np.int64)
        elif "gmsh:physical" in raw.cell_data:
            phys = np.asarray(raw.cell_data["gmsh:physical"][bi], dtype=np.int64)
            codes = np.array(
                [PARTS.index(names[p]) + 1 if names.get(p) in PARTS else 0 for p in phys.tolist()],
                dtype=np.int64,
            )
        else:
            continue
        for (a, b), code in zip(np.asarray(block.data).tolist(), codes.tolist(), strict=False):
            if code <= 0 or code > len(PARTS):
                continue
            key = (min(a, b), max(a, b))
            old = seen.setdefault(key, code)
            if old != code:
                raise ck.fail(
                    where,
                    f"boundary edge ({a}, {b}) is tagged both "
                    f"{PARTS[old - 1]!r} and {PARTS[code - 1]!r}; every boundary "
                    "edge must belong to exactly one part",
                )


def build_mesh(
    sec: Any, base_dir: Path, source: str = "config", *, file_tags: bool = True
) -> tuple[Mesh, dict[str, Any]]:
    """The untagged (or file-tagged) mesh of a ``[mesh]`` section.

    A mesh file is checked before it is used: dangling vertices (except in ``.msh``
    files), duplicate vertices, bad cells and non-conforming edges are a
    :class:`ConfigError` naming the file and the vertex, cell or edge ids.

    Parameters
    ----------
    sec : dict
        The ``[mesh]`` table.
    base_dir : Path
        Directory that relative mesh file names refer to.
    source : str
        Name used in error messages (the config file).
    file_tags : bool
        The boundary parts of a mesh file are used (no ``[boundary]`` table): an edge
        tagged with two different parts in the file is then an error.

    Returns
    -------
    mesh : Mesh
    info : dict
        ``{"generator": name, ...}`` or ``{"file": absolute path}``.
    """
    ck = _Checker(source)
    sec = ck.table(sec, "[mesh]")
    has_gen, has_file = "generator" in sec, "file" in sec
    if has_gen == has_file:
        raise ck.fail(
            "[mesh]",
            "needs exactly one of 'generator' or 'file'" + (", not both" if has_gen else ""),
        )
    if has_file:
        ck.keys(sec, ("file",), "[mesh]")
        name = ck.string(sec["file"], "[mesh] file")
        path = Path(name).expanduser()
        if not path.is_absolute():
            path = base_dir / path
        if not path.is_file():
            raise ck.fail("[mesh] file", f"not found: {path}")
        chatter = io.StringIO()  # meshio prints its reasons; keep them for the message
        try:
            with contextlib.redirect_stdout(chatter), contextlib.redirect_stderr(chatter):
                raw = meshio.read(path)
        except SystemExit as exc:  # meshio calls sys.exit(1) on files it cannot parse
            why = " ".join(chatter.getvalue().split())
            raise ck.fail(
                "[mesh] file",
                f"{path} cannot be read: meshio could not parse it" + (f" ({why})" if why else ""),
            ) from exc
        except Exception as exc:  # meshio raises many kinds of errors on broken files
            raise ck.fail("[mesh] file", f"{path} cannot be read: {exc}") from exc
        shown = f"[mesh] file {name!r}:"
        if path.suffix.lower() != ".msh":  # gmsh files keep unused geometry points
            _check_dangling(ck, raw, shown)
        if file_tags:
            _check_tag_conflicts(ck, raw, shown)
        try:
            mesh = from_meshio(raw, source=str(path))
        except (ValueError, IndexError, TypeError) as exc:
            raise ck.fail("[mesh] file", f"{path} cannot be read: {exc}") from exc
        try:
            check_vertices(mesh)
            check_cells(mesh)
            check_conforming(mesh)
        except MeshError as exc:
            raise ck.fail(shown, str(exc)) from None
        return mesh, {"file": str(path.resolve())}
    fams = mesh_families()
    gen = ck.string(sec["generator"], "[mesh] generator")
    if gen not in fams:
        close = difflib.get_close_matches(gen, list(fams), n=1, cutoff=0.6)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise ck.fail(
            "[mesh] generator",
            f"= {gen!r} is not a known mesh family; {hint}available: "
            f"{', '.join(_family_names(fams))}",
        )
    fn = fams[gen]
    kwargs = _generator_args(ck, sec, fn, gen)
    try:
        mesh = fn(**kwargs)
    except (ValueError, TypeError) as exc:
        raise ck.fail("[mesh]", f"generator {gen!r} failed: {exc}") from exc
    if isinstance(mesh, tuple):  # families that also return auxiliary data
        mesh = next((x for x in mesh if isinstance(x, Mesh)), mesh)
    if not isinstance(mesh, Mesh):  # pragma: no cover - a broken family
        raise ck.fail("[mesh]", f"generator {gen!r} did not return a Mesh")
    return mesh, {"generator": gen, "function": getattr(fn, "__name__", gen), **kwargs}


def _boundary(ck: _Checker, data: dict[str, Any], mesh: Mesh, from_file: bool) -> Mesh:
    """Tag the boundary parts of ``mesh`` from the ``[boundary]`` section.

    Every part must select at least one edge and no edge may be selected by two
    parts (the error names both parts and an edge); ``clamped`` and ``contact`` are
    required. Edges in no part are reported by the mesh checks of the problem.
    """
    if "boundary" not in data:
        if from_file:
            return _file_tags(ck, mesh, data["mesh"]["file"])
        raise ck.fail(
            "",
            "missing required section [boundary] (which sides are clamped, traction and contact)",
        )
    b = data["boundary"]
    if isinstance(b, str):
        if b != "file":
            raise ck.fail("boundary", f"must be a table or the string 'file', got {b!r}")
        if not from_file:
            raise ck.fail("boundary", "= 'file' needs [mesh] file (generated meshes have no tags)")
        return _file_tags(ck, mesh, data["mesh"]["file"])
    b = ck.table(b, "[boundary]")
    allowed = _SECTIONS["boundary"][0]
    ck.keys(b, allowed, "[boundary]", required=("clamped", "contact"))
    rest = [name for name, v in b.items() if v == "rest"]
    if len(rest) > 1:
        raise ck.fail("[boundary]", f"only one part can be 'rest', got {', '.join(rest)}")
    edges = mesh.boundary_edges
    mid = mesh.edge_midpoints(edges)
    hits: dict[str, NDArray[np.bool_]] = {}
    for name, spec in b.items():
        where = f"[boundary] {name}"
        if spec == "rest":
            continue
        items = spec if isinstance(spec, list) else [spec]
        if not items:
            raise ck.fail(where, "must not be an empty array")
        hit = np.zeros(len(edges), dtype=bool)
        for i, it in enumerate(items):
            w = f"{where}[{i}]" if isinstance(spec, list) else where
            if isinstance(it, str):
                if it == "rest":
                    raise ck.fail(w, "'rest' must stand alone, not inside an array")
                ck.string(it, w, choices=(*SIDES, "rest"))
                hit |= np.asarray(side_predicate(mesh, it)(mid), dtype=bool)
            elif isinstance(it, dict):
                ck.keys(it, ("from", "to"), w, required=("from", "to"))
                a = ck.vector(it["from"], f"{w}.from")
                c = ck.vector(it["to"], f"{w}.to")
                try:
                    on_segment = segment_predicate(a, c)
                except ValueError:  # the end points coincide
                    raise ck.fail(w, f"has coinciding end points {list(a)}") from None
                hit |= np.asarray(on_segment(mid), dtype=bool)
            else:
                raise ck.fail(
                    w,
                    "must be a side name ('left', 'right', 'bottom', 'top'), 'rest', "
                    f"a segment {{ from = [x, y], to = [x, y] }} or an array of these, "
                    f"got {_kind(it)} ({_show(it)})",
                )
        if not hit.any():
            lo, hi = mesh.points.min(axis=0), mesh.points.max(axis=0)
            raise ck.fail(
                where,
                f"= {_show(spec)} selects no boundary edge (the mesh spans "
                f"[{lo[0]:g}, {hi[0]:g}] x [{lo[1]:g}, {hi[1]:g}]; segments select "
                "the boundary edges lying on them)",
            )
        for other, ohit in hits.items():
            both = np.flatnonzero(hit & ohit)
            if both.size:
                e = both[0]
                p0, p1 = mesh.points[edges[e, 0]], mesh.points[edges[e, 1]]
                more = f" and {both.size - 1} more" if both.size > 1 else ""
                raise ck.fail(
                    "[boundary]",
                    f"parts {other!r} and {name!r} overlap: both select the "
                    f"boundary edge ({edges[e, 0]}, {edges[e, 1]}) from {_pt(p0)} to "
                    f"{_pt(p1)}{more}; every boundary edge must belong to exactly one part",
                )
        hits[name] = hit
    preds: dict[str, Any] = {name: (lambda m, h=h: h) for name, h in hits.items()}
    preds.update({name: "rest" for name in rest})
    tagged = mesh.with_boundary(preds)
    for name in rest:
        if not np.any(tagged.boundary_tags == part_code(name)):
            raise ck.fail(
                f"[boundary] {name}",
                "= 'rest' selects no boundary edge (every edge is already in another part)",
            )
    return tagged


def _file_tags(ck: _Checker, mesh: Mesh, name: str) -> Mesh:
    """The mesh with the boundary parts of its file, which must tag clamped and contact."""
    for part in ("clamped", "contact"):
        if not np.any(mesh.boundary_tags == part_code(part)):
            raise ck.fail(
                f"[mesh] file {name!r}:",
                f"the file tags no {part!r} boundary edges (line cells "
                f"with cell data 'part' = {part_code(part)}, or a Gmsh "
                f"physical group {part!r}); tag them or add a [boundary] "
                "section",
            )
    return mesh


def _pt(p: NDArray[np.float64]) -> str:
    return f"({p[0]:.6g}, {p[1]:.6g})"


# ---------------------------------------------------------------------------- contact
def _compliance(ck: _Checker, v: Any) -> ComplianceLaw:
    where = "[contact] p"
    t = ck.table(v, where)
    if "type" not in t:
        raise ck.fail(where, "missing required key 'type' ('linear' or 'table')")
    typ = ck.string(t["type"], f"{where}.type", choices=("linear", "table"))
    if typ == "linear":
        ck.keys(t, ("type", "c"), where, required=("c",))
        return LinearCompliance(ck.number(t["c"], f"{where}.c", ge=0.0))
    ck.keys(t, ("type", "r", "p"), where, required=("r", "p"))
    r = ck.numbers(t["r"], f"{where}.r", min_len=2, increasing=True)
    p = ck.numbers(t["p"], f"{where}.p", min_len=2, ge=0.0)
    if len(r) != len(p):
        raise ck.fail(f"{where}:", f"r and p must have the same length, got {len(r)} and {len(p)}")
    try:
        return TableCompliance(tuple(r), tuple(p))
    except ValueError as exc:
        raise ck.fail(where, f"is not a valid compliance table: {exc}") from exc


class NodalExpression:
    """``g``, ``mu`` or ``kappa`` given as an expression in ``x``, ``y``.

    Called with the (m, 2) coordinates of the contact nodes; ``__name__`` is the
    expression text (shown in ``summary.json``).
    """

    def __init__(self, expr: Expression) -> None:
        self.expr = expr
        self.__name__ = expr.text

    def __call__(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        P = np.asarray(points, dtype=float)
        return self.expr(x=P[..., 0], y=P[..., 1])


class FieldExpression:
    """A load ``f1`` or ``f2`` whose components are numbers or expressions in ``x, y, t``.

    Called as ``f(points, t)`` with (m, 2) points, it returns the (m, 2) values (the
    callable form of :data:`vemwear.vem.assembly.Field`).
    """

    def __init__(self, parts: Sequence[Expression | float], text: str) -> None:
        self.parts = tuple(parts)
        self.__name__ = text
        self.uses_t = any(isinstance(c, Expression) and "t" in c.names for c in self.parts)

    def __call__(self, x: NDArray[np.float64], t: float) -> NDArray[np.float64]:
        P = np.asarray(x, dtype=float).reshape(-1, 2)
        cols = [
            c(x=P[:, 0], y=P[:, 1], t=np.full(len(P), float(t)))
            if isinstance(c, Expression)
            else np.full(len(P), float(c))
            for c in self.parts
        ]
        return np.column_stack(cols)


class VelocityExpression:
    """``v_star`` whose components are numbers or expressions in ``t``: ``v(t)`` -> 2-vector."""

    def __init__(self, parts: Sequence[Expression | float], text: str) -> None:
        self.parts = tuple(parts)
        self.__name__ = text

    def values(self, t: NDArray[np.float64]) -> NDArray[np.float64]:
        """(L, 2) values at the times ``t``."""
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        return np.column_stack(
            [c(t=tt) if isinstance(c, Expression) else np.full(tt.shape, c) for c in self.parts]
        )

    def __call__(self, t: float) -> NDArray[np.float64]:
        return self.values(np.array([float(t)]))[0]


def _expression(ck: _Checker, text: str, where: str, names: Sequence[str]) -> Expression:
    try:
        return parse_expression(text, names, where=where)
    except ExpressionError as exc:
        raise ConfigError(f"{ck.source}: {exc}") from None


def _nodal(
    ck: _Checker, v: Any, name: str, *, gt: float | None = None, ge: float | None = None
) -> float | dict[str, Any] | NodalExpression:
    where = f"[contact] {name}"
    if isinstance(v, dict):
        ck.keys(v, ("along", "at", "values"), where, required=("at", "values"))
        along = ck.string(v.get("along", "x"), f"{where}.along", choices=("x", "y", "s"))
        at = ck.numbers(v["at"], f"{where}.at", increasing=True)
        vals = ck.numbers(v["values"], f"{where}.values", gt=gt, ge=ge)
        if len(at) != len(vals):
            raise ck.fail(
                f"{where}:",
                f"'at' and 'values' must have the same length, got {len(at)} and {len(vals)}",
            )
        return {"along": along, "at": at, "values": vals}
    if isinstance(v, str):
        e = _expression(ck, v, where, ("x", "y"))
        if e.is_constant:  # check the sign now; others at the contact nodes
            ck.number(float(e(x=0.0)), f"{where} = {v!r}:", gt=gt, ge=ge)
        return NodalExpression(e)
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise ck.fail(
            where,
            "must be a number, an expression string in x, y or a table "
            f"{{ along, at, values }}, got {_kind(v)} ({_show(v)})",
        )
    return ck.number(v, where, gt=gt, ge=ge)


def _components(
    ck: _Checker, v: Any, where: str, names: Sequence[str]
) -> tuple[list[Expression | float], bool]:
    """A 2-array of numbers or expression strings; returns the parts and whether any is a string."""
    if not isinstance(v, list) or len(v) != 2:
        raise ck.fail(
            where,
            "must be an array of 2 numbers [x, y] (or expression strings "
            f"in {', '.join(names)}), got {_kind(v)} ({_show(v)})",
        )
    parts: list[Expression | float] = []
    for i, c in enumerate(v):
        if isinstance(c, str):
            parts.append(_expression(ck, c, f"{where}[{i}]", names))
        else:
            if isinstance(c, bool) or not isinstance(c, int | float):
                raise ck.fail(
                    f"{where}[{i}]",
                    "must be a number or an expression string in "
                    f"{', '.join(names)}, got {_kind(c)} ({_show(c)})",
                )
            parts.append(ck.number(c, f"{where}[{i}]"))
    return parts, any(isinstance(c, str) for c in v)


def _load(ck: _Checker, v: Any, where: str) -> tuple[float, float] | FieldExpression:
    parts, has_expr = _components(ck, v, where, ("x", "y", "t"))
    if not has_expr:
        return (float(parts[0]), float(parts[1]))  # type: ignore[arg-type]
    return FieldExpression(parts, _show_list(v))


def _show_list(v: list[Any]) -> str:
    return "[" + ", ".join(repr(c) for c in v) + "]"


def _velocity(ck: _Checker, v: Any) -> tuple[float, float] | dict[str, Any] | VelocityExpression:
    where = "[contact] v_star"
    if isinstance(v, dict):
        ck.keys(v, ("t", "values"), where, required=("t", "values"))
        ts = ck.numbers(v["t"], f"{where}.t", increasing=True)
        vals_raw = ck.array(v["values"], f"{where}.values")
        vals = [list(ck.vector(x, f"{where}.values[{i}]")) for i, x in enumerate(vals_raw)]
        if len(ts) != len(vals):
            raise ck.fail(
                f"{where}:",
                f"'t' and 'values' must have the same length, got {len(ts)} and {len(vals)}",
            )
        return {"t": ts, "values": vals}
    if not isinstance(v, list):
        raise ck.fail(
            where,
            "must be an array [vx, vy] (numbers or expression strings in t) "
            f"or a table {{ t, values }}, got {_kind(v)} ({_show(v)})",
        )
    parts, has_expr = _components(ck, v, where, ("t",))
    if has_expr:
        return VelocityExpression(parts, _show_list(v))
    vec = (float(parts[0]), float(parts[1]))  # type: ignore[arg-type]
    if vec == (0.0, 0.0):
        raise ck.fail(where, "must not be zero (the foundation must move, H0(c))")
    return vec


# ---------------------------------------------------------------------------- time
def _time(ck: _Checker, sec: dict[str, Any]) -> TimeGrid:
    where = "[time]"
    ck.keys(sec, _SECTIONS["time"][0], where)
    kinds = [k for k in ("steps", "dt", "pattern", "levels") if k in sec]
    if len(kinds) != 1:
        raise ck.fail(
            where,
            "needs exactly one of 'steps' (uniform), 'dt' (explicit step "
            "sizes), 'pattern' (repeated step sizes) or 'levels' (explicit time "
            "levels)" + (f"; got {', '.join(kinds)}" if kinds else ""),
        )
    kind = kinds[0]
    T = ck.number(sec["T"], f"{where} T", gt=0.0) if "T" in sec else None
    if kind == "levels":
        lv = ck.numbers(sec["levels"], f"{where} levels", min_len=2)
        if lv[0] != 0.0:
            raise ck.fail(f"{where} levels", f"must start at t_0 = 0, got {lv[0]:g}")
        ck.numbers(lv, f"{where} levels", increasing=True)
        if T is not None and abs(lv[-1] - T) > 1e-9 * max(T, 1.0):
            raise ck.fail(f"{where} levels", f"end at {lv[-1]:.12g}, but T = {T:g}")
        return TimeGrid(np.array(lv))
    if kind == "dt":
        dt = ck.numbers(sec["dt"], f"{where} dt", gt=0.0)
        total = math.fsum(dt)
        if T is not None and abs(total - T) > 1e-9 * max(T, 1.0):
            raise ck.fail(f"{where} dt", f"sums to {total:.12g}, but T = {T:g}")
        grid = TimeGrid.from_steps(dt)
        if T is not None:  # end exactly at T
            t = np.array(grid.t)
            t[-1] = T
            grid = TimeGrid(t)
        return grid
    if T is None:
        raise ck.fail(where, f"missing required key 'T' (needed with {kind!r})")
    if kind == "steps":
        return TimeGrid.uniform(T, ck.integer(sec["steps"], f"{where} steps", ge=1))
    pat = ck.numbers(sec["pattern"], f"{where} pattern", gt=0.0)
    return TimeGrid.pattern(T, pat)


def _default_times(grid: TimeGrid) -> tuple[float, ...]:
    """Levels closest to T/4, T/2, 3T/4 and T."""
    T = grid.T
    idx = sorted({int(np.abs(grid.t - q * T).argmin()) for q in (0.25, 0.5, 0.75, 1.0)})
    return tuple(float(grid.t[i]) for i in idx)


# ---------------------------------------------------------------------------- data checks
def _check_velocity(ck: _Checker, v_star: Any, grid: TimeGrid) -> None:
    """``v*`` must be finite and non-zero at every time level (H0(c)), whatever its form."""
    where = "[contact] v_star"
    t = np.asarray(grid.t)
    if isinstance(v_star, VelocityExpression):
        V = v_star.values(t)
    elif isinstance(v_star, dict):
        ts, vals = np.asarray(v_star["t"]), np.asarray(v_star["values"], dtype=float)
        V = np.column_stack([np.interp(t, ts, vals[:, 0]), np.interp(t, ts, vals[:, 1])])
    else:
        return  # a constant vector, checked to be non-zero
    bad = np.flatnonzero(~np.all(np.isfinite(V), axis=1))
    if bad.size:
        n = int(bad[0])
        raise ck.fail(where, f"is not finite at t = {t[n]:g} (level {n}): {V[n].tolist()}")
    zero = np.flatnonzero(np.hypot(V[:, 0], V[:, 1]) == 0.0)
    if zero.size:
        n = int(zero[0])
        more = f" and {zero.size - 1} more levels" if zero.size > 1 else ""
        raise ck.fail(
            where,
            f"vanishes at t = {t[n]:g} (level {n}{more}); the foundation "
            "must move at every time level (H0(c), v* != 0)",
        )


def _check_contact_data(ck: _Checker, mesh: Mesh, specs: Mapping[str, tuple[Any, str]]) -> None:
    """g, mu, kappa at the contact nodes: finite, with their signs; the error names the node."""
    cb = contact_boundary(mesh)
    for name, (spec, rel) in specs.items():
        where = f"[contact] {name}"
        shown = f"= {spec.__name__!r} " if isinstance(spec, NodalExpression) else ""
        v = (
            nodal_values(spec, cb, name)
            if not isinstance(spec, NodalExpression)
            else np.broadcast_to(spec(cb.points), (cb.m,))
        )
        ok = np.isfinite(v) & ((v > 0) if rel == "> 0" else (v >= 0))
        if not np.all(ok):
            a = int(np.flatnonzero(~ok)[0])
            raise ck.fail(
                where,
                f"{shown}must be {rel} on the contact part, but it is "
                f"{v[a]:g} at contact node {a} (vertex {cb.nodes[a]}, x = "
                f"{_pt(cb.points[a])})",
            )


def _check_loads(ck: _Checker, mesh: Mesh, grid: TimeGrid, loads: Mapping[str, Any]) -> None:
    """Loads given by expressions give finite load vectors at every time level."""
    for name, f in loads.items():
        if not isinstance(f, FieldExpression):
            continue
        assemble = body_force_vector if name == "f1" else traction_vector
        levels = range(len(grid.t)) if f.uses_t else range(1)
        with np.errstate(all="ignore"):
            for n in levels:
                F = assemble(mesh, f, float(grid.t[n])).reshape(-1, 2)
                bad = np.flatnonzero(~np.all(np.isfinite(F), axis=1))
                if bad.size:
                    v = int(bad[0])
                    at = f" at t = {grid.t[n]:g} (level {n})" if f.uses_t else ""
                    raise ck.fail(
                        f"[loads] {name}",
                        f"= {f.__name__} is not finite near "
                        f"vertex {v} (x = {_pt(mesh.points[v])}){at}",
                    )


def smallness_report(problem: Problem, max_dofs: int = 200_000) -> tuple[str, str | None]:
    """The smallness condition of Theorem 3.4, estimated for ``vemwear check`` and ``run``.

    Parameters
    ----------
    problem : Problem
        A validated problem (its discretization is assembled here).
    max_dofs : int
        Skip the estimate (an eigenvalue problem) above this number of dofs.

    Returns
    -------
    row : str
        A one-line summary of the estimate ``L_p ||mu|| c_0^2 / C_1``, for the
        ``check`` table.
    warning : str or None
        A warning when the condition is doubtful (estimate >= 1), else None.
    """
    import warnings

    if 2 * problem.mesh.n_points > max_dofs:
        return f"not estimated (more than {max_dofs} dofs)", None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        est = problem.discrete.smallness_estimate()
    r = float(est.get("ratio", float("nan")))
    if not math.isfinite(r):
        return "not estimated", None
    if r < 1:
        return f"L_p ||mu|| c0^2/C1 ~= {r:.3g} < 1: holds", None
    row = (
        f"L_p ||mu|| c0^2/C1 ~= {r:.3g} >= 1: MAY FAIL (step problems may not be uniquely solvable)"
    )
    warning = (
        f"the smallness condition of Theorem 3.4 is doubtful: L_p ||mu|| c0^2/C1 "
        f"~= {r:.3g} >= 1 (L_p = {est.get('L_p', float('nan')):g}, max mu = "
        f"{est.get('mu_max', float('nan')):g}, c0^2/C1 ~= "
        f"{est.get('c0_sq_over_C1', float('nan')):.3g}); the step problems may not be "
        "uniquely solvable and the solver may fail; reduce mu or the stiffness of p"
    )
    return row, warning


# ---------------------------------------------------------------------------- entry points
def load_config(path: str | Path) -> Config:
    """Read and validate a TOML configuration file.

    Parameters
    ----------
    path : str or Path
        The ``.toml`` file; relative mesh file names refer to its directory.

    Returns
    -------
    Config

    Raises
    ------
    ConfigError
        If the file is missing, is not valid TOML, or any key is invalid.
    """
    path = Path(path)
    source = str(path)
    if not path.is_file():
        raise ConfigError(f"{source}: config file not found")
    try:
        with path.open("rb") as fh:
            data = tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{source}: not valid TOML: {exc}") from exc
    except OSError as exc:
        raise ConfigError(f"{source}: cannot read: {exc}") from exc
    return parse_config(data, source=source, base_dir=path.resolve().parent, path=path)


def parse_config(
    data: Mapping[str, Any],
    source: str = "config",
    base_dir: str | Path = ".",
    path: Path | None = None,
) -> Config:
    """Validate configuration data (a dict as read by :func:`tomllib.load`).

    Parameters
    ----------
    data : mapping
        The parsed TOML document.
    source : str
        Name of the file, used as the prefix of every error message.
    base_dir : str or Path
        Directory that relative mesh file names refer to.
    path : Path, optional
        The file, recorded in the returned :class:`Config`.

    Returns
    -------
    Config

    Raises
    ------
    ConfigError
        Naming the key path and the problem.
    """
    ck = _Checker(source)
    data = dict(data)
    base_dir = Path(base_dir)

    # -- top level: known sections, required sections, section types
    allowed_top = [*_TOP_SCALARS, *_SECTIONS]
    for k in data:
        if k not in allowed_top:
            sugg = difflib.get_close_matches(k, allowed_top, n=1, cutoff=0.6)
            hint = (
                f"; did you mean [{sugg[0]}]?"
                if sugg and sugg[0] in _SECTIONS
                else f"; did you mean {sugg[0]!r}?"
                if sugg
                else f"; valid sections: {', '.join(f'[{s}]' for s in _SECTIONS)}"
            )
            raise ck.fail("", f"unknown section or key {k!r}{hint}")
    for name, (_keys, required) in _SECTIONS.items():
        if required and name not in data:
            raise ck.fail("", f"missing required section [{name}]")
    title = ck.string(data["title"], "title") if "title" in data else Path(source).stem
    for name in _SECTIONS:
        if name in data and name not in ("boundary", "mesh"):
            ck.table(data[name], f"[{name}]")
            ck.keys(data[name], _SECTIONS[name][0], f"[{name}]")

    # -- material, vem, loads
    mat = data["material"]
    ck.keys(mat, _SECTIONS["material"][0], "[material]", required=("lam", "eta"))
    material = Material(
        ck.number(mat["lam"], "[material] lam", gt=0.0),
        ck.number(mat["eta"], "[material] eta", gt=0.0),
    )
    stab = ck.string(
        data.get("vem", {}).get("stabilization", "paper"),
        "[vem] stabilization",
        choices=STABILIZATIONS,
    )
    loads = data.get("loads", {})
    f1 = _load(ck, loads["f1"], "[loads] f1") if "f1" in loads else (0.0, 0.0)
    f2 = _load(ck, loads["f2"], "[loads] f2") if "f2" in loads else (0.0, 0.0)

    # -- contact
    con = data["contact"]
    ck.keys(con, _SECTIONS["contact"][0], "[contact]", required=("p", "g", "mu", "kappa", "v_star"))
    p = _compliance(ck, con["p"])
    g = _nodal(ck, con["g"], "g", gt=0.0)
    mu = _nodal(ck, con["mu"], "mu", ge=0.0)
    kappa = _nodal(ck, con["kappa"], "kappa", ge=0.0)
    v_star = _velocity(ck, con["v_star"])

    # -- time and output times
    try:
        grid = _time(ck, data["time"])
    except ConfigError:
        raise
    except (ValueError, MemoryError, OverflowError) as exc:  # e.g. far too many levels
        raise ck.fail("[time]", f"does not give a valid time grid: {exc}") from None
    _check_velocity(ck, v_star, grid)
    out = data.get("output", {})
    if "times" in out:
        times = ck.numbers(out["times"], "[output] times", ge=0.0)
        for i, t in enumerate(times):
            try:
                grid.index([t])
            except ValueError:
                near = float(grid.t[int(np.abs(grid.t - t).argmin())])
                raise ck.fail(
                    f"[output] times[{i}]",
                    f"= {t:g} is not a time level of the grid "
                    f"(T = {grid.T:g}, {grid.n_steps} steps; nearest level "
                    f"{near:.12g})",
                ) from None
        out_times = tuple(times)
    else:
        out_times = _default_times(grid)
    output = OutputOptions(
        times=out_times,
        figures=ck.boolean(out.get("figures", True), "[output] figures"),
        vtk=ck.boolean(out.get("vtk", True), "[output] vtk"),
    )

    # -- solver
    sol = data.get("solver", {})
    method = ck.string(sol.get("method", "newton"), "[solver] method", choices=list(SOLVERS))
    tol = ck.number(sol.get("tol", 1e-10), "[solver] tol", gt=0.0)
    max_iter = ck.integer(sol["max_iter"], "[solver] max_iter", ge=1) if "max_iter" in sol else None
    backend = ck.string(sol.get("backend", "auto"), "[solver] backend", choices=BACKENDS)
    try:
        resolve_backend(backend)
    except ValueError as exc:
        raise ck.fail("[solver] backend", f"= {backend!r} cannot be used: {exc}") from exc
    solver = SolverOptions(method=method, tol=tol, max_iter=max_iter, backend=backend)

    # -- mesh and boundary (after the cheap checks), then the problem itself
    mesh, mesh_info = build_mesh(
        data["mesh"], base_dir, source, file_tags=not isinstance(data.get("boundary"), dict)
    )
    from_file = "file" in mesh_info
    try:
        mesh = _boundary(ck, data, mesh, from_file=from_file)
        _check_contact_data(
            ck, mesh, {"g": (g, "> 0"), "mu": (mu, ">= 0"), "kappa": (kappa, ">= 0")}
        )
        _check_loads(ck, mesh, grid, {"f1": f1, "f2": f2})
        problem = Problem(
            mesh=mesh,
            material=material,
            time=grid,
            f1=f1,
            f2=f2,
            p=p,
            g=g,
            mu=mu,
            kappa=kappa,
            v_star=v_star,
            stabilization=stab,
        )
    except ConfigError:
        raise
    except ValueError as exc:  # MeshError is a ValueError
        raise ck.fail("", f"invalid problem: {exc}") from exc
    return Config(
        path=path,
        data=_jsonable(data),
        title=title,
        problem=problem,
        solver=solver,
        output=output,
        mesh_source=mesh_info,
    )


def _jsonable(x: Any) -> Any:
    """TOML data as JSON-friendly data (dates become ISO strings)."""
    if isinstance(x, Mapping):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_jsonable(v) for v in x]
    if isinstance(x, str | int | float | bool) or x is None:
        return x
    return str(x)
