"""From a validated configuration to the :class:`Problem`, solver and output options.

Every value is checked once, by the library object it becomes (``Material``, the
compliance laws, ``TimeGrid``, ``SolverOptions``, the mesh generators and reader,
``Problem``); each is built inside :func:`~vemwear.config.errors.at`, which turns
its ``ValueError`` into a :class:`ConfigError` naming the key. What no library object
checks is checked here: the boundary selectors (each selects an edge, no edge in two
parts), loads given by expressions being finite, and ``[output] times`` on the grid.

One job, the path from a file to the library objects, in 2D and 3D; its length is the
one place each section becomes its object and each error gets its key path.
"""

from __future__ import annotations

import copy
import functools
import os
import tomllib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..contact import arc_length, table_values, velocity_levels
from ..mesh import Mesh, MeshError, read_mesh, select_parts
from ..mesh.boundary3d import select_parts3d
from ..mesh.io3d import mesh_file_dim, read_mesh3d
from ..mesh.polyhedra import Mesh3D
from ..simulate import Problem, SolverOptions, TimeGrid
from ..simulate.cycles import CycleJump
from ..solvers import resolve_backend
from ..vem import Material, body_force_vector, edge_load_vector
from . import schema as s
from .errors import ConfigError, at, from_library, from_validation
from .expr import Expression
from .parts import Roles, contact_law, contact_parts, roles

__all__ = ["Config", "OutputOptions", "Sizes", "load_config", "parse_config"]


@dataclass(frozen=True)
class OutputOptions:
    """The ``[output]`` section with its times resolved to levels of the time grid.

    ``u_levels`` are the indices of the levels whose displacement is stored
    (``[output] store_u``; by default the levels of ``times`` and the final one).
    """

    times: tuple[float, ...] = ()
    figures: bool = True
    vtk: bool = True
    paraview: str = "xdmf"
    u_levels: tuple[int, ...] | NDArray[np.int64] = ()
    every: int = 1
    checkpoint: float = 60.0


@dataclass(frozen=True, eq=False)
class Config:
    """A validated configuration file.

    Attributes
    ----------
    path : Path or None
        The file it was read from (None for data parsed directly).
    data : dict
        The TOML data as written (JSON-friendly; stored in ``summary.json``).
    title : str
        The ``title`` key, or the file stem.
    problem : Problem
    solver : SolverOptions
    output : OutputOptions
    mesh_source : dict
        ``{"file": absolute path}`` or ``{"generator": name, "function": ..., options}``.
    model : ConfigFile
        The validated schema model.
    cycles : CycleJump or None
        ``[time] cycle_jump``: the grid is one cycle of a periodic loading.
    """

    path: Path | None
    data: dict[str, Any]
    title: str
    problem: Problem
    solver: SolverOptions
    output: OutputOptions
    mesh_source: dict[str, Any] = field(default_factory=dict)
    model: s.ConfigFile | None = None
    cycles: CycleJump | None = None


@dataclass(frozen=True)
class Sizes:
    """The sizes of a run known from the configuration before anything is built, each a
    lower bound of the real one (:mod:`vemwear.runner.plan`).

    Attributes
    ----------
    source : str
        The configuration file (the prefix of messages).
    levels : int
        Time levels L.
    cells : int
        The cells the generator makes (0 for a mesh file: not known before it is read).
    kept, stored_u : int
        Kept contact rows (at least ``ceil(L / every)``) and stored displacements (those
        ``store_u`` certainly asks for).
    paraview : bool
        Whether a ParaView series is written.
    dim : int
        2 or 3: the dimension of the generated mesh (2 for a mesh file).
    """

    source: str
    levels: int
    cells: int
    kept: int
    stored_u: int
    paraview: bool
    dim: int = 2


def _sizes(src: str, c: s.ConfigFile) -> Sizes:
    t = c.time
    if isinstance(t, s.Steps):
        L = t.steps + 1
    elif isinstance(t, s.Pattern):
        L = int(np.ceil(t.T / max(sum(t.pattern), 1e-300))) * len(t.pattern) + 1
    elif isinstance(t, s.Levels):
        L = len(t.levels)
    else:
        L = len(t.dt) + 1
    m = c.mesh
    cells, dim = 0, 2
    if not isinstance(m, s.MeshFile):
        fam = s.mesh_family(m.generator)
        cells = fam.estimate_cells(m.model_dump(exclude_unset=True))
        dim = fam.dim
    store, out = c.output.store_u, c.output
    stored = 1  # the final level; times and a list may fall on fewer levels than given
    if store == "all":
        stored = L
    elif isinstance(store, int) and not isinstance(store, bool):
        stored = -(-L // store)
    kept = max(-(-L // out.every), stored)
    return Sizes(src, L, int(cells), kept, min(stored, L), out.vtk, dim)


# ---------------------------------------------------------------------------- expressions
class NodalExpression:
    """``g``, ``mu`` or ``kappa`` as an expression in ``x, y, z``, called with the (m, 2)
    or (m, 3) contact nodes (``z = 0`` in 2D); ``__name__`` is its text."""

    def __init__(self, expr: Expression) -> None:
        self.expr, self.__name__ = expr, expr.text

    def __call__(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        P = np.asarray(points, dtype=float)
        if "z" not in self.expr.names:
            return self.expr(x=P[..., 0], y=P[..., 1])
        z = P[..., 2] if P.shape[-1] == 3 else np.zeros(P.shape[:-1])
        return self.expr(x=P[..., 0], y=P[..., 1], z=z)


class FieldExpression:
    """A load of numbers, expressions in ``x, y, z, t`` and (a traction) tables
    ``{along, at, values}``: ``f(points, t)`` -> (m, d), d = 2 or 3 its components
    (``z = 0`` in 2D).

    ``arc(points)`` gives the arc length along the load's boundary part (tables along
    ``s``)."""

    def __init__(
        self,
        parts: Sequence[Expression | float | s.Section],
        text: str,
        arc: Callable[[NDArray[np.float64]], NDArray[np.float64]] | None = None,
    ) -> None:
        self.parts = tuple(c.model_dump() if isinstance(c, s.Section) else c for c in parts)
        self.__name__, self.arc = text, arc
        self.uses_t = any(isinstance(c, Expression) and "t" in c.names for c in self.parts)

    def __call__(self, x: NDArray[np.float64], t: float) -> NDArray[np.float64]:
        X = np.asarray(x, dtype=float)
        P = X.reshape(-1, 3 if X.ndim == 2 and X.shape[1] == 3 else 2)
        env = {"x": P[:, 0], "y": P[:, 1], "t": np.full(len(P), float(t))}
        if any(isinstance(c, Expression) and "z" in c.names for c in self.parts):
            env["z"] = P[:, 2] if P.shape[1] == 3 else np.zeros(len(P))
        cols = []
        for i, c in enumerate(self.parts):
            if isinstance(c, dict):
                cols.append(table_values(c, P, functools.partial(self._arc, P), f"f2[{i}]"))
            else:
                cols.append(_value(c, env))
        return np.column_stack(cols)

    def _arc(self, P: NDArray[np.float64]) -> NDArray[np.float64]:
        if self.arc is None:
            raise ValueError("f2: a table along s needs a boundary part")
        return self.arc(P)


class VelocityExpression:
    """``v_star`` of numbers and expressions in ``t``: ``v(t)`` -> 2-vector."""

    def __init__(self, parts: Sequence[Expression | float], text: str) -> None:
        self.parts, self.__name__ = tuple(parts), text

    def __call__(self, t: float) -> NDArray[np.float64]:
        return np.array([float(_value(c, {"t": np.array([float(t)])})[0]) for c in self.parts])

    def at_times(self, t: NDArray[np.float64]) -> NDArray[np.float64]:
        """``v(t)`` at many times at once: (len(t), 2)."""
        ts = np.asarray(t, dtype=float).ravel()
        return np.column_stack(
            [np.broadcast_to(_value(c, {"t": ts}), ts.shape) for c in self.parts]
        )


def _value(c: Expression | float, env: dict[str, NDArray[np.float64]]) -> NDArray[np.float64]:
    return c(**env) if isinstance(c, Expression) else np.full(len(env["t"]), float(c))


def _data(v: Any, cls: type | None, raw: Any) -> Any:
    """A number, table (as a dict) or expression of the schema as the library takes it."""
    if isinstance(v, Expression):
        return NodalExpression(v)
    if isinstance(v, s.Section):
        return v.model_dump(by_alias=True)
    if cls and isinstance(v, list) and any(isinstance(c, Expression | s.Section) for c in v):
        return cls(v, "[" + ", ".join(repr(c) for c in raw) + "]")
    return tuple(v) if isinstance(v, list) else v


# ---------------------------------------------------------------------------- mesh, boundary
def _mesh(
    src: str, m: Any, raw: Mapping[str, Any], base_dir: Path
) -> tuple[Mesh | Mesh3D, dict[str, Any]]:
    if isinstance(m, s.MeshFile):
        path = Path(m.file).expanduser()
        path = path if path.is_absolute() else base_dir / path
        if not path.is_file():
            raise ConfigError(f"{src}: [mesh] file not found: {path}")
        try:
            read: Callable[[Path], Mesh | Mesh3D] = (
                read_mesh3d if mesh_file_dim(path) == 3 else read_mesh
            )
            return read(path), {"file": str(path.resolve())}
        except MeshError as exc:
            msg = str(exc).removeprefix(f"{path}: ")
            raise ConfigError(f"{src}: [mesh] file {m.file!r}: {msg}") from None
    fam = s.mesh_family(m.generator)
    options = m.model_dump(exclude_unset=True, exclude={"generator"})
    with at(src, "[mesh]", raw):
        try:
            mesh = fam.generate(**options)
        except TypeError as exc:  # options that do not go together (e.g. seeds and Lloyd)
            raise ValueError(f"generator {m.generator!r}: {exc}") from None
    return mesh, {"generator": m.generator, "function": fam.function.__name__, **options}


def _pt(p: NDArray[np.float64]) -> str:
    return "(" + ", ".join(f"{v:.6g}" for v in p) + ")"


def _check_dims(src: str, c: s.ConfigFile, raw: Mapping[str, Any], dim: int) -> None:
    """The vectors of the file have ``dim`` components (2 on a 2D mesh, 3 on a 3D one)
    and ``uz`` is given on 3D meshes only."""
    names = {2: "[x, y]", 3: "[x, y, z]"}
    what = f"a {dim}D mesh"
    if not isinstance(c.mesh, s.MeshFile):
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


# ---------------------------------------------------------------------------- time, loads
def _time(src: str, t: Any, raw: Mapping[str, Any]) -> TimeGrid:
    form = next(k for k in s.TIME_FORMS if k in raw)
    with at(src, "[time]", raw, key=form):
        try:
            if isinstance(t, s.Steps):
                return TimeGrid.uniform(t.T, t.steps)
            if isinstance(t, s.Pattern):
                return TimeGrid.pattern(t.T, t.pattern)
            if isinstance(t, s.Levels):
                grid = TimeGrid(np.array(t.levels))
            else:
                grid = TimeGrid.from_steps(t.dt)
        except (MemoryError, OverflowError) as exc:  # far too many levels
            raise ValueError(f"does not give a valid time grid ({type(exc).__name__})") from None
    if t.T is not None:
        if abs(grid.T - t.T) > 1e-9 * max(abs(t.T), 1.0):
            what = "sums to" if form == "dt" else "ends at"
            raise ConfigError(f"{src}: [time] {form} {what} {grid.T:.12g}, but T = {t.T:g}")
        grid = TimeGrid(np.concatenate([grid.t[:-1], [t.T]]))  # end exactly at T
    return grid


def _output_times(src: str, times: list[float] | None, grid: TimeGrid) -> tuple[float, ...]:
    if times is None:  # the levels nearest T/4, T/2, 3T/4 and T
        q = np.array([0.25, 0.5, 0.75, 1.0]) * grid.T
        return tuple(float(grid.t[i]) for i in sorted(set(np.abs(grid.t - q[:, None]).argmin(1))))
    for i, t in enumerate(times):
        try:
            grid.index([t])
        except ValueError:
            near = float(grid.t[int(np.abs(grid.t - t).argmin())])
            raise ConfigError(
                f"{src}: [output] times[{i}] = {t:g} is not a time level of the grid (T = "
                f"{grid.T:g}, {grid.n_steps} steps; nearest level {near:.12g})"
            ) from None
    return tuple(times)


def _u_levels(
    src: str, store: str | int | list[float] | None, times: tuple[float, ...], grid: TimeGrid
) -> NDArray[np.int64]:
    """``[output] store_u`` as sorted level indices (the final level always included)."""
    L = len(grid.t)
    if store is None:
        return np.union1d(grid.index(list(times)) if times else [], [L - 1]).astype(np.int64)
    if isinstance(store, str):
        return np.arange(L, dtype=np.int64) if store == "all" else np.array([L - 1], np.int64)
    if isinstance(store, int):
        return np.union1d(np.arange(0, L, store), [L - 1]).astype(np.int64)
    for i, t in enumerate(store):
        try:
            grid.index([t])
        except ValueError:
            near = float(grid.t[int(np.abs(grid.t - t).argmin())])
            raise ConfigError(
                f"{src}: [output] store_u[{i}] = {t:g} is not a time level of the grid (T = "
                f"{grid.T:g}, {grid.n_steps} steps; nearest level {near:.12g})"
            ) from None
    return np.union1d(grid.index(store) if store else [], [L - 1]).astype(np.int64)


def _problem(
    src: str,
    c: s.ConfigFile,
    raw: Mapping[str, Any],
    parts: Roles,
    mesh: Mesh | Mesh3D,
    material: Material,
    grid: TimeGrid,
    where: str,
) -> Problem:
    """The :class:`Problem` of the roles; its errors at their keys."""
    loads = raw.get("loads", {})
    f2: Any = _data(c.loads.f2, FieldExpression, loads.get("f2"))
    if parts.tractions:
        f2 = {n: _data(v, FieldExpression, rv) for n, (v, rv) in parts.tractions.items()}
        for n, f in f2.items():
            if isinstance(f, FieldExpression):
                f.arc = (
                    _x_coordinate
                    if isinstance(mesh, Mesh3D)
                    else functools.partial(arc_length, mesh, n)
                )
    name, ct, rt, _ = parts.contacts[0]
    single = len(parts.contacts) == 1 and name == "contact"
    try:
        if single:
            with at(src, "[contact]", rt, key="p"):
                law = contact_law(ct.p)
            top = {
                "p": law,
                "g": _data(ct.g, None, None),
                "mu": _data(ct.mu, None, None),
                "kappa": _data(ct.kappa, None, None),
                "v_star": _data(ct.v_star, VelocityExpression, rt["v_star"]),
                "gap": _data(ct.gap, None, None),
            }
            contacts: tuple[Any, ...] = ()
        else:
            top, contacts = {}, contact_parts(src, parts, _data, VelocityExpression)
        return Problem(
            mesh=mesh,
            material=material,
            time=grid,
            f1=_data(c.loads.f1, FieldExpression, loads.get("f1")),
            f2=f2,
            stabilization=c.vem.stabilization,
            order=c.vem.order,
            clamped=parts.clamped,
            displacement=tuple(parts.displacement),
            contacts=contacts,
            **top,
        )
    except ConfigError:
        raise
    except MeshError as exc:  # the boundary parts (the rest of the mesh is checked)
        hint = (
            "; tag the parts in the file (line cells with cell data 'part', or gmsh physical "
            "groups) or say in a [boundary] section what each part is"
        )
        raise ConfigError(f"{src}: {where} {exc}{hint if where != '[boundary]' else ''}") from None
    except ValueError as exc:
        section = "[contact]" if single else "[[contact]]"
        raise from_library(exc, src, section, rt if single else {}) from None


def _x_coordinate(P: NDArray[np.float64]) -> NDArray[np.float64]:
    """``s`` of a 3D mesh: the x coordinate (a surface has no arc length)."""
    return np.asarray(P[:, 0])


def _check_velocity(src: str, pr: Problem, parts: Roles) -> None:
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


def _check_loads(src: str, pr: Problem, parts: Roles) -> None:
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


# ---------------------------------------------------------------------------- entry points
def load_config(
    path: str | os.PathLike[str], *, admit: Callable[[Sizes], None] | None = None
) -> Config:
    """Read and validate a TOML configuration file.

    Parameters
    ----------
    path : str or Path
        The ``.toml`` file; relative mesh file names refer to its directory.
    admit : callable, optional
        Called with the :class:`Sizes` of the run once the file is valid and before the
        mesh and the time grid are built; it may refuse the run by raising.

    Returns
    -------
    Config

    Raises
    ------
    ConfigError
        If the file is missing, is not valid TOML, or any key is invalid.
    """
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"{path}: config file not found")
    try:
        with path.open("rb") as fh:
            data = tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: not valid TOML: {exc}") from exc
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read: {exc}") from exc
    return parse_config(
        data, source=str(path), base_dir=path.resolve().parent, path=path, admit=admit
    )


def parse_config(
    data: Mapping[str, Any],
    source: str = "config",
    base_dir: str | Path = ".",
    path: Path | None = None,
    admit: Callable[[Sizes], None] | None = None,
) -> Config:
    """Validate configuration data (a dict as read by :func:`tomllib.load`).

    Parameters
    ----------
    data : mapping
        The parsed TOML document.
    source : str
        Name of the file, the prefix of every error message.
    base_dir : str or Path
        Directory that relative mesh file names refer to.
    path : Path, optional
        The file, recorded in the returned :class:`Config`.
    admit : callable, optional
        As for :func:`load_config`.

    Returns
    -------
    Config

    Raises
    ------
    ConfigError
        Naming the key path and the problem.
    """
    from pydantic import ValidationError

    src = source
    try:
        c = s.ConfigFile.model_validate(data)
    except ValidationError as exc:
        raise from_validation(exc, src) from None
    if admit is not None:
        admit(_sizes(src, c))
    raw: dict[str, Any] = copy.deepcopy(dict(data))  # valid, so plain TOML types only
    with at(src, "[material]"):
        material = Material(c.material.lam, c.material.eta)
    parts = roles(src, c, raw)
    grid = _time(src, c.time, raw["time"])
    times = _output_times(src, c.output.times, grid)
    output = OutputOptions(
        times,
        c.output.figures,
        c.output.vtk,
        c.output.paraview,
        _u_levels(src, c.output.store_u, times, grid),
        c.output.every,
        c.output.checkpoint,
    )
    sol = c.solver
    with at(src, "[solver]", raw.get("solver", {})):
        solver = SolverOptions(sol.method, sol.tol, sol.max_iter, sol.backend)
        resolve_backend(sol.backend)

    mesh, mesh_source = _mesh(src, c.mesh, raw["mesh"], Path(base_dir))
    _check_dims(src, c, raw, 3 if isinstance(mesh, Mesh3D) else 2)
    if parts.selectors:
        with at(src, "[boundary]", raw.get("boundary", {})):
            if isinstance(mesh, Mesh3D):
                mesh = select_parts3d(mesh, parts.selectors)
            else:
                mesh = select_parts(mesh, parts.selectors)
        where = "[boundary]"
    else:
        where = f"[mesh] file {c.mesh.file!r}:"
    problem = _problem(src, c, raw, parts, mesh, material, grid, where)
    _check_velocity(src, problem, parts)
    _check_loads(src, problem, parts)
    title = c.title if c.title is not None else Path(source).stem
    cycles = None
    cj = c.time.cycle_jump
    if cj is not None:
        if cj.period is not None and abs(cj.period - grid.T) > 1e-12 * max(grid.T, 1.0):
            raise ConfigError(
                f"{src}: [time] cycle_jump: period = {cj.period:g} but the time grid (one "
                f"cycle) ends at T = {grid.T:g}; make them equal"
            )
        with at(src, "[time]", raw["time"], key="cycle_jump"):
            cycles = CycleJump(cj.cycles, cj.jump, cj.max_increment)
    return Config(path, raw, title, problem, solver, output, mesh_source, c, cycles)
