"""From a validated configuration to the :class:`Problem`, solver and output options.

Every value is checked once, by the library object it becomes (``Material``, the
compliance laws, ``TimeGrid``, ``SolverOptions``, the mesh generators and reader,
``Problem``); each is built inside :func:`~vemwear.config.errors.at`, which turns
its ``ValueError`` into a :class:`ConfigError` naming the key. What no library object
checks is checked here (the boundary selectors: each selects an edge, no edge in two
parts; ``[output] times`` on the grid) or, on the mesh and the problem built, by
:mod:`vemwear.config.checks` (vectors with as many components as the mesh has
dimensions, loads and velocities given by expressions finite). Values written as
expressions become the callables of :mod:`vemwear.config.fields`.

One job, the path from a file to the library objects, in 2D and 3D; its length is the
one place each section becomes its object and each error gets its key path.
"""

from __future__ import annotations

import copy
import functools
import os
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ..contact import arc_length
from ..mesh import Mesh, MeshError, read_mesh, select_parts
from ..mesh.boundary3d import select_parts3d
from ..mesh.io3d import mesh_file_dim, read_mesh3d
from ..mesh.polyhedra import Mesh3D
from ..simulate import Problem, SolverOptions, TimeGrid
from ..solvers import resolve_backend
from ..vem import Material
from . import schema as s
from .adapt import adapt_settings, check_adapt_output
from .checks import check_dims, check_loads, check_scales, check_velocity
from .errors import ConfigError, at, from_library, from_validation
from .fields import FieldExpression, library_data, velocity_data
from .mesh_forms import MeshFile, mesh_family
from .parts import Roles, contact_law, contact_parts, roles

if TYPE_CHECKING:
    from ..simulate.cycles import CycleJump
    from ..simulate.mesh_change import AdaptSettings

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
    adapt : AdaptSettings or None
        ``[adapt]``: the mesh changes every few levels (:mod:`vemwear.config.adapt`).
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
    adapt: AdaptSettings | None = None


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
    points, contact : int
        Once the mesh is built (before the time grid): its vertices, and the vertices of
        the contact parts that are on no other part (a lower bound of the contact
        nodes); 0 before.
    """

    source: str
    levels: int
    cells: int
    kept: int
    stored_u: int
    paraview: bool
    dim: int = 2
    points: int = 0
    contact: int = 0


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
    if not isinstance(m, MeshFile):
        fam = mesh_family(m.generator)
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


def _mesh_sizes(sizes: Sizes, mesh: Mesh | Mesh3D, contacts: list[str]) -> Sizes:
    """``sizes`` with those of the built mesh: vertices, cells, dimension, and the
    vertices of the contact parts on no other boundary part (each one a contact node)."""
    three = isinstance(mesh, Mesh3D)

    def vertices(name: str) -> NDArray[np.int64]:
        if not isinstance(mesh, Mesh3D):
            return mesh.part_vertices(name)
        f = mesh.part_faces(name)
        starts, ends = mesh.face_offsets[f], mesh.face_offsets[f + 1]
        lens = ends - starts
        first = np.repeat(starts - np.cumsum(lens) + lens, lens)  # each face's start - rank
        return np.unique(mesh.face_vertices[first + np.arange(int(lens.sum()))])

    names = [str(n) for n in mesh.part_names]
    on_contact = [vertices(n) for n in names if n in contacts]
    elsewhere = [vertices(n) for n in names if n not in contacts]
    own = np.setdiff1d(
        np.concatenate([np.zeros(0, np.int64), *on_contact]),
        np.concatenate([np.zeros(0, np.int64), *elsewhere]),
    )
    return replace(
        sizes, cells=mesh.n_cells, points=mesh.n_points, dim=3 if three else 2, contact=len(own)
    )


# ---------------------------------------------------------------------------- mesh
def _mesh(
    src: str, m: Any, raw: Mapping[str, Any], base_dir: Path
) -> tuple[Mesh | Mesh3D, dict[str, Any]]:
    if isinstance(m, MeshFile):
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
    fam = mesh_family(m.generator)
    options = m.model_dump(exclude_unset=True, exclude={"generator"})
    with at(src, "[mesh]", raw):
        try:
            mesh = fam.generate(**options)
        except TypeError as exc:  # options that do not go together (e.g. seeds and Lloyd)
            raise ValueError(f"generator {m.generator!r}: {exc}") from None
    return mesh, {"generator": m.generator, "function": fam.function.__name__, **options}


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
        return tuple(float(grid.t[i]) for i in sorted(set(grid.nearest(q).tolist())))
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
    f2: Any = library_data(c.loads.f2, FieldExpression, loads.get("f2"))
    if parts.tractions:
        f2 = {n: library_data(v, FieldExpression, rv) for n, (v, rv) in parts.tractions.items()}
        for n, f in f2.items():
            if isinstance(f, FieldExpression):
                f.arc = (
                    _x_coordinate
                    if isinstance(mesh, Mesh3D)
                    else functools.partial(arc_length, mesh, n)
                )
    name, ct, rt, _ = parts.contacts[0]
    # one part with the paper's friction and wear: the Problem's own keys (its
    # fingerprint as before); otherwise contact parts
    single = (
        len(parts.contacts) == 1
        and name == "contact"
        and ct.friction_on == "soft"
        and ct.wear_on == "soft"
    )
    try:
        if single:
            with at(src, "[contact]", rt, key="p"):
                law = contact_law(ct.p)
            top = {
                "p": law,
                "g": library_data(ct.g, None, None),
                "mu": library_data(ct.mu, None, None),
                "kappa": library_data(ct.kappa, None, None),
                "v_star": velocity_data(ct.v_star, rt["v_star"]),
                "gap": library_data(ct.gap, None, None),
            }
            contacts: tuple[Any, ...] = ()
        else:
            top, contacts = {}, contact_parts(src, parts, library_data, velocity_data)
        return Problem(
            mesh=mesh,
            material=material,
            time=grid,
            f1=library_data(c.loads.f1, FieldExpression, loads.get("f1")),
            f2=f2,
            stabilization=c.vem.stabilization,
            order=c.vem.order,
            clamped=parts.clamped,
            displacement=tuple(parts.displacement),
            rigid=tuple(parts.rigid),
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
    from ..util.text import NotUtf8Error, read_utf8

    try:
        data = tomllib.loads(read_utf8(path))
    except NotUtf8Error as exc:
        raise ConfigError(f"{path}: {exc}") from None
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
    sizes = _sizes(src, c)
    if admit is not None:
        admit(sizes)
    raw: dict[str, Any] = copy.deepcopy(dict(data))  # valid, so plain TOML types only
    with at(src, "[material]"):
        material = Material(c.material.lam, c.material.eta)
    parts = roles(src, c, raw)
    sol = c.solver
    with at(src, "[solver]", raw.get("solver", {})):
        solver = SolverOptions(sol.method, sol.tol, sol.max_iter, sol.backend)
        resolve_backend(sol.backend)

    if c.adapt is not None:
        check_adapt_output(src, raw)
    mesh, mesh_source = _mesh(src, c.mesh, raw["mesh"], Path(base_dir))
    dim = 3 if isinstance(mesh, Mesh3D) else 2
    adapt = None
    if c.adapt is not None:
        kw = {"dim": dim, "order": c.vem.order, "n_cells": mesh.n_cells, "levels": sizes.levels}
        adapt = adapt_settings(src, c.adapt, raw, **kw)
    check_dims(src, c, raw, dim)
    check_scales(src, mesh, c)
    if parts.selectors:
        with at(src, "[boundary]", raw.get("boundary", {})):
            if isinstance(mesh, Mesh3D):
                mesh = select_parts3d(mesh, parts.selectors)
            else:
                mesh = select_parts(mesh, parts.selectors)
        where = "[boundary]"
    else:
        where = f"[mesh] file {c.mesh.file!r}:"
    if admit is not None:  # with the mesh's sizes, before arrays of L levels are made
        admit(_mesh_sizes(sizes, mesh, [name for name, *_ in parts.contacts] or ["contact"]))
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
    problem = _problem(src, c, raw, parts, mesh, material, grid, where)
    check_velocity(src, problem, parts)
    check_loads(src, problem, parts)
    title = c.title if c.title is not None else Path(source).stem
    cycles = None
    cj = c.time.cycle_jump
    if cj is not None:
        if cj.period is not None and abs(cj.period - grid.T) > 1e-12 * max(grid.T, 1.0):
            raise ConfigError(
                f"{src}: [time] cycle_jump: period = {cj.period:g} but the time grid (one "
                f"cycle) ends at T = {grid.T:g}; make them equal"
            )
        from ..simulate.cycles import CycleJump  # a cycle-jump run's module only

        with at(src, "[time]", raw["time"], key="cycle_jump"):
            cycles = CycleJump(cj.cycles, cj.jump, cj.max_increment)
    return Config(path, raw, title, problem, solver, output, mesh_source, c, cycles, adapt)
