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
import tomllib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..contact import ComplianceLaw, LinearCompliance, TableCompliance
from ..mesh import Mesh, read_mesh, segment_predicate, side_predicate
from ..mesh.boundary import SIDES
from ..simulate import Problem, SolverOptions, TimeGrid
from ..solvers import BACKENDS, SOLVERS, resolve_backend
from ..vem import STABILIZATIONS, Material

__all__ = [
    "Config",
    "ConfigError",
    "OutputOptions",
    "build_mesh",
    "load_config",
    "mesh_families",
    "parse_config",
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
    "time": (("T", "steps", "dt", "pattern"), True),
    "solver": (("method", "tol", "max_iter", "backend"), False),
    "output": (("times", "figures", "vtk"), False),
}
_TOP_SCALARS = ("title",)
_GRID_KEYS = ("size", "origin", "divisions")
_TOML_TYPE = {
    str: "a string", int: "an integer", float: "a float", bool: "a boolean",
    list: "an array", dict: "a table",
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
        self, tbl: Mapping[str, Any], allowed: Sequence[str], where: str,
        required: Sequence[str] = (),
    ) -> None:
        for k in tbl:
            if k not in allowed:
                raise self.fail(where, f"unknown key {k!r}{_suggest(k, allowed)}")
        for k in required:
            if k not in tbl:
                raise self.fail(where, f"missing required key {k!r}")

    # -- scalars
    def number(self, v: Any, where: str, *, gt: float | None = None,
               ge: float | None = None) -> float:
        if isinstance(v, bool) or not isinstance(v, int | float):
            raise self.fail(where, f"must be a number, got {_kind(v)} ({_show(v)})")
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

    def numbers(self, v: Any, where: str, *, min_len: int = 1, gt: float | None = None,
                ge: float | None = None, increasing: bool = False) -> list[float]:
        arr = self.array(v, where, min_len=min_len)
        out = [self.number(x, f"{where}[{i}]", gt=gt, ge=ge) for i, x in enumerate(arr)]
        if increasing:
            for i in range(len(out) - 1):
                if not out[i + 1] > out[i]:
                    raise self.fail(
                        where, f"must increase strictly, but entry {i + 1} ({out[i + 1]:g}) "
                        f"<= entry {i} ({out[i]:g})")
        return out


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

    ``squares`` and ``triangles`` always exist. Further families are the public
    generator functions of :mod:`vemwear.mesh` (those returning a ``Mesh`` without
    taking one): ``rectangle_NAME`` and ``NAME_mesh`` are available as ``NAME`` (the
    ``rectangle_`` one wins if both exist), every generator also under its full
    function name, and a ``GENERATORS`` or ``FAMILIES`` mapping of the package, if it
    defines one, adds or overrides names.
    """
    from .. import mesh as mesh_pkg

    short: dict[str, Callable[..., Mesh]] = {}
    full: dict[str, Callable[..., Mesh]] = {}
    for n in list(getattr(mesh_pkg, "__all__", dir(mesh_pkg))):
        obj = getattr(mesh_pkg, n, None)
        if (n.startswith("_") or n in _NOT_FAMILIES or not inspect.isfunction(obj)
                or not _returns_mesh(obj) or not _takes_no_mesh(obj)):
            continue
        full[n] = obj
        if n.endswith("_mesh") and n[: -len("_mesh")] not in short:
            short[n[: -len("_mesh")]] = obj
    for n, obj in full.items():
        if n.startswith("rectangle_"):
            short[n[len("rectangle_"):]] = obj
    fam = {**full, **short}
    for reg in ("GENERATORS", "FAMILIES"):
        table = getattr(mesh_pkg, reg, None)
        if isinstance(table, Mapping):
            fam.update({str(k): v for k, v in table.items() if callable(v)})
    return fam


def _family_names(fams: Mapping[str, Callable[..., Mesh]]) -> list[str]:
    """Names to show: one per generator, the short one if there is one."""
    seen: dict[int, str] = {}
    for name, fn in sorted(fams.items(), key=lambda kv: (len(kv[0]), kv[0])):
        seen.setdefault(id(fn), name)
    return sorted(seen.values())


def _generator_args(ck: _Checker, sec: dict[str, Any], fn: Callable[..., Mesh],
                    gen: str) -> dict[str, Any]:
    """Check the generator's parameters against its signature and convert arrays to tuples."""
    where = "[mesh]"
    try:
        sig = inspect.signature(fn)
        params = [p for p in sig.parameters.values()
                  if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]
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
        size = ck.vector(sec.get("size", [1.0, 1.0]), f"{where} size")
        for i, x in enumerate(size):
            if not x > 0:
                raise ck.fail(f"{where} size[{i}]", f"must be > 0, got {x:g}")
        x0, y0 = ck.vector(sec.get("origin", [0.0, 0.0]), f"{where} origin")
        kwargs["domain"] = ((x0, y0), (x0 + size[0], y0), (x0 + size[0], y0 + size[1]),
                            (x0, y0 + size[1]))
    for k, v in sec.items():
        if k in ("generator", "file") or (rect_domain and k in ("size", "origin")):
            continue
        if k == "return_seeds":
            raise ck.fail(where, f"unknown key {k!r} for generator {gen!r}")
        if k not in allowed and not has_var_kw:
            raise ck.fail(where, f"unknown key {k!r} for generator {gen!r}"
                          f"{_suggest(k, ['generator', *allowed])}")
        if k in _GRID_KEYS and gen in ("squares", "triangles"):
            if k == "divisions":
                if not isinstance(v, list) or len(v) != 2:
                    raise ck.fail(f"{where} divisions",
                                  f"must be an array of 2 integers [nx, ny], got {_show(v)}")
                kwargs[k] = tuple(ck.integer(x, f"{where} divisions[{i}]", ge=1)
                                  for i, x in enumerate(v))
            else:
                vec = ck.vector(v, f"{where} {k}")
                if k == "size":
                    for i, x in enumerate(vec):
                        if not x > 0:
                            raise ck.fail(f"{where} size[{i}]", f"must be > 0, got {x:g}")
                kwargs[k] = vec
            continue
        kwargs[k] = _to_python(ck, v, f"{where} {k}")
    missing = [r for r in required if r not in kwargs]
    if missing:
        raise ck.fail(where, f"missing required key {missing[0]!r} for generator {gen!r}")
    return kwargs


def _to_python(ck: _Checker, v: Any, where: str) -> Any:
    """Generic generator argument: arrays become tuples; numbers must be finite."""
    if isinstance(v, list):
        return tuple(_to_python(ck, x, f"{where}[{i}]") for i, x in enumerate(v))
    if isinstance(v, float) and not math.isfinite(v):
        raise ck.fail(where, f"must be a finite number, got {v}")
    if isinstance(v, dict):
        return {k: _to_python(ck, x, f"{where}.{k}") for k, x in v.items()}
    return v


def build_mesh(sec: Any, base_dir: Path, source: str = "config") -> tuple[Mesh, dict[str, Any]]:
    """The untagged (or file-tagged) mesh of a ``[mesh]`` section.

    Parameters
    ----------
    sec : dict
        The ``[mesh]`` table.
    base_dir : Path
        Directory that relative mesh file names refer to.
    source : str
        Name used in error messages (the config file).

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
        raise ck.fail("[mesh]", "needs exactly one of 'generator' or 'file'"
                      + (", not both" if has_gen else ""))
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
                mesh = read_mesh(path)
        except (ValueError, OSError) as exc:
            raise ck.fail("[mesh] file", f"{path} cannot be read: {exc}") from exc
        except SystemExit as exc:  # meshio calls sys.exit(1) on files it cannot parse
            why = " ".join(chatter.getvalue().split())
            raise ck.fail("[mesh] file", f"{path} cannot be read: meshio could not parse it"
                          + (f" ({why})" if why else "")) from exc
        return mesh, {"file": str(path.resolve())}
    fams = mesh_families()
    gen = ck.string(sec["generator"], "[mesh] generator")
    if gen not in fams:
        close = difflib.get_close_matches(gen, list(fams), n=1, cutoff=0.6)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise ck.fail("[mesh] generator",
                      f"= {gen!r} is not a known mesh family; {hint}available: "
                      f"{', '.join(_family_names(fams))}")
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
    """Tag the boundary parts of ``mesh`` from the ``[boundary]`` section."""
    if "boundary" not in data:
        if from_file:
            return mesh  # keep the file's tags
        raise ck.fail("", "missing required section [boundary] (which sides are clamped, "
                      "traction and contact)")
    b = data["boundary"]
    if isinstance(b, str):
        if b != "file":
            raise ck.fail("boundary", f"must be a table or the string 'file', got {b!r}")
        if not from_file:
            raise ck.fail("boundary", "= 'file' needs [mesh] file (generated meshes "
                          "have no tags)")
        return mesh
    b = ck.table(b, "[boundary]")
    allowed = _SECTIONS["boundary"][0]
    ck.keys(b, allowed, "[boundary]")
    preds: dict[str, Any] = {}
    rest = [name for name, v in b.items() if v == "rest"]
    if len(rest) > 1:
        raise ck.fail("[boundary]", f"only one part can be 'rest', got {', '.join(rest)}")
    for name, spec in b.items():
        where = f"[boundary] {name}"
        if spec == "rest":
            preds[name] = "rest"
            continue
        items = spec if isinstance(spec, list) else [spec]
        if not items:
            raise ck.fail(where, "must not be an empty array")
        fs = []
        for i, it in enumerate(items):
            w = f"{where}[{i}]" if isinstance(spec, list) else where
            if isinstance(it, str):
                if it == "rest":
                    raise ck.fail(w, "'rest' must stand alone, not inside an array")
                ck.string(it, w, choices=(*SIDES, "rest"))
                fs.append(side_predicate(mesh, it))
            elif isinstance(it, dict):
                ck.keys(it, ("from", "to"), w, required=("from", "to"))
                a = ck.vector(it["from"], f"{w}.from")
                c = ck.vector(it["to"], f"{w}.to")
                if a == c:
                    raise ck.fail(w, f"has coinciding end points {list(a)}")
                fs.append(segment_predicate(a, c))
            else:
                raise ck.fail(
                    w, "must be a side name ('left', 'right', 'bottom', 'top'), 'rest', "
                    f"a segment {{ from = [x, y], to = [x, y] }} or an array of these, "
                    f"got {_kind(it)} ({_show(it)})")
        preds[name] = (lambda m, fs=fs: np.any([f(m) for f in fs], axis=0))
    return mesh.with_boundary(preds)


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


def _nodal(ck: _Checker, v: Any, name: str, *, gt: float | None = None,
           ge: float | None = None) -> float | dict[str, Any]:
    where = f"[contact] {name}"
    if isinstance(v, dict):
        ck.keys(v, ("along", "at", "values"), where, required=("at", "values"))
        along = ck.string(v.get("along", "x"), f"{where}.along", choices=("x", "y", "s"))
        at = ck.numbers(v["at"], f"{where}.at", increasing=True)
        vals = ck.numbers(v["values"], f"{where}.values", gt=gt, ge=ge)
        if len(at) != len(vals):
            raise ck.fail(f"{where}:", f"'at' and 'values' must have the same length, "
                          f"got {len(at)} and {len(vals)}")
        return {"along": along, "at": at, "values": vals}
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise ck.fail(where, "must be a number or a table { along, at, values }, "
                      f"got {_kind(v)} ({_show(v)})")
    return ck.number(v, where, gt=gt, ge=ge)


def _velocity(ck: _Checker, v: Any) -> tuple[float, float] | dict[str, Any]:
    where = "[contact] v_star"
    if isinstance(v, dict):
        ck.keys(v, ("t", "values"), where, required=("t", "values"))
        ts = ck.numbers(v["t"], f"{where}.t", increasing=True)
        vals_raw = ck.array(v["values"], f"{where}.values")
        vals = [list(ck.vector(x, f"{where}.values[{i}]")) for i, x in enumerate(vals_raw)]
        if len(ts) != len(vals):
            raise ck.fail(f"{where}:", f"'t' and 'values' must have the same length, "
                          f"got {len(ts)} and {len(vals)}")
        return {"t": ts, "values": vals}
    if not isinstance(v, list):
        raise ck.fail(where, "must be an array [vx, vy] or a table { t, values }, "
                      f"got {_kind(v)} ({_show(v)})")
    vec = ck.vector(v, where)
    if vec == (0.0, 0.0):
        raise ck.fail(where, "must not be zero (the foundation must move, H0(c))")
    return vec


# ---------------------------------------------------------------------------- time
def _time(ck: _Checker, sec: dict[str, Any]) -> TimeGrid:
    where = "[time]"
    ck.keys(sec, _SECTIONS["time"][0], where)
    kinds = [k for k in ("steps", "dt", "pattern") if k in sec]
    if len(kinds) != 1:
        raise ck.fail(where, "needs exactly one of 'steps' (uniform), 'dt' (explicit step "
                      "sizes) or 'pattern' (repeated step sizes)"
                      + (f"; got {', '.join(kinds)}" if kinds else ""))
    kind = kinds[0]
    T = ck.number(sec["T"], f"{where} T", gt=0.0) if "T" in sec else None
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
            hint = (f"; did you mean [{sugg[0]}]?" if sugg and sugg[0] in _SECTIONS
                    else f"; did you mean {sugg[0]!r}?" if sugg
                    else f"; valid sections: {', '.join(f'[{s}]' for s in _SECTIONS)}")
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
    material = Material(ck.number(mat["lam"], "[material] lam", gt=0.0),
                        ck.number(mat["eta"], "[material] eta", gt=0.0))
    stab = ck.string(data.get("vem", {}).get("stabilization", "paper"),
                     "[vem] stabilization", choices=STABILIZATIONS)
    loads = data.get("loads", {})
    f1 = ck.vector(loads["f1"], "[loads] f1") if "f1" in loads else (0.0, 0.0)
    f2 = ck.vector(loads["f2"], "[loads] f2") if "f2" in loads else (0.0, 0.0)

    # -- contact
    con = data["contact"]
    ck.keys(con, _SECTIONS["contact"][0], "[contact]",
            required=("p", "g", "mu", "kappa", "v_star"))
    p = _compliance(ck, con["p"])
    g = _nodal(ck, con["g"], "g", gt=0.0)
    mu = _nodal(ck, con["mu"], "mu", ge=0.0)
    kappa = _nodal(ck, con["kappa"], "kappa", ge=0.0)
    v_star = _velocity(ck, con["v_star"])

    # -- time and output times
    grid = _time(ck, data["time"])
    out = data.get("output", {})
    if "times" in out:
        times = ck.numbers(out["times"], "[output] times", ge=0.0)
        for i, t in enumerate(times):
            try:
                grid.index([t])
            except ValueError:
                near = float(grid.t[int(np.abs(grid.t - t).argmin())])
                raise ck.fail(f"[output] times[{i}]",
                              f"= {t:g} is not a time level of the grid "
                              f"(T = {grid.T:g}, {grid.n_steps} steps; nearest level "
                              f"{near:.12g})") from None
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
    if "mesh" not in data:  # pragma: no cover - caught above
        raise ck.fail("", "missing required section [mesh]")
    mesh, mesh_info = build_mesh(data["mesh"], base_dir, source)
    try:
        mesh = _boundary(ck, data, mesh, from_file="file" in mesh_info)
        problem = Problem(
            mesh=mesh, material=material, time=grid, f1=f1, f2=f2, p=p, g=g, mu=mu,
            kappa=kappa, v_star=v_star, stabilization=stab,
        )
    except ConfigError:
        raise
    except ValueError as exc:  # MeshError is a ValueError
        raise ck.fail("", f"invalid problem: {exc}") from exc
    return Config(path=path, data=_jsonable(data), title=title, problem=problem,
                  solver=solver, output=output, mesh_source=mesh_info)


def _jsonable(x: Any) -> Any:
    """TOML data as JSON-friendly data (dates become ISO strings)."""
    if isinstance(x, Mapping):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_jsonable(v) for v in x]
    if isinstance(x, str | int | float | bool) or x is None:
        return x
    return str(x)
