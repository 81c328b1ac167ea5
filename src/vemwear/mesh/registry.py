"""The mesh families, registered once for configuration files and ``vemwear mesh generate``.

Each family is a generator of meshes of a rectangle (Voronoi meshes: of any polygon)
with a name, the names it is also known by (its function's name), a one-line
description and the options it takes (name, type, default, one-line help). The
configuration schema builds the keys of ``[mesh] generator = NAME`` from
:data:`FAMILIES` (:mod:`vemwear.config.mesh_forms`), and ``vemwear mesh generate`` its
``--cells``, ``--divisions``, ``--seed`` and ``--param`` options. Defaults are those of
the generator functions' signatures. Option types are Python annotations (tuples for
fixed-size arrays, ``Literal`` for choices); values are checked by the generators.
:func:`generate_mesh` turns a family and a cell count or grid into a tagged mesh of a
rectangle (the work behind ``vemwear mesh generate``).

The 3D families (meshes of a box, :class:`Mesh3D`) are registered apart, in
:data:`vemwear.mesh.registry3d.FAMILIES_3D` (``registry3d.family3d`` finds them); the
configuration schema and the command line know the 2D families only so far.
"""

from __future__ import annotations

import difflib
import inspect
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Generic, Literal, TypeVar

from numpy.typing import ArrayLike

from .families import distorted_quads, hexagons, nonconvex_mesh, squares_with_hanging_nodes
from .generate import rectangle_squares, rectangle_triangles
from .polymesh import Mesh, MeshError
from .voronoi import rectangle_domain, voronoi_from_seeds, voronoi_mesh

__all__ = ["FAMILIES", "Family", "Option", "family", "generate_mesh", "voronoi"]

Pair = tuple[float, float]
Counts = tuple[int, int]
Points = tuple[Pair, ...]


@dataclass(frozen=True)
class Option:
    """A keyword argument of a generator.

    Attributes
    ----------
    name : str
    type : type annotation
        ``float``, ``int``, ``bool``, ``tuple[float, float]``, ``Literal[...]``, ...
    help : str
        One line.
    default : object
        The generator's default (None: required, or absent unless given).
    replaces : tuple of str
        Options that must not be given together with this one.
    """

    name: str
    type: Any
    help: str
    default: Any = None
    replaces: tuple[str, ...] = ()


#: The mesh type a family makes (:class:`Mesh` in 2D, :class:`~vemwear.mesh.polyhedra.Mesh3D`).
M = TypeVar("M")


@dataclass(frozen=True)
class Family(Generic[M]):
    """A mesh family: its generator and the options it takes.

    Attributes
    ----------
    name : str
        The name in configuration files and on the command line.
    function : callable
        The generator, called with options as keyword arguments; returns a :class:`Mesh`.
    description : str
        One line.
    options : tuple of Option
    aliases : tuple of str
        Other names accepted in configuration files (the function's name).
    cells_per_division : int
        Cells per grid rectangle (1 quadrilaterals, 2 triangles; 1 hexahedra, 6
        tetrahedra), so that a cell count can be turned into ``divisions``; 0 if the
        count depends on them otherwise.
    dim : int
        2 for meshes of a rectangle (:class:`Mesh`), 3 for meshes of a box (:class:`Mesh3D`).
    """

    name: str
    function: Callable[..., M]
    description: str
    options: tuple[Option, ...]
    aliases: tuple[str, ...] = ()
    cells_per_division: int = 0
    dim: int = 2

    def estimate_cells(self, options: Mapping[str, Any]) -> int:
        """About how many cells :meth:`generate` makes with ``options``, without making
        them (for planning a run)."""
        merged = {o.name: o.default for o in self.options} | dict(options)
        if merged.get("seeds") is not None:
            return len(merged["seeds"])
        layers = int(merged.get("layers") or 1)  # prisms: 2D cells times layers
        if merged.get("n_cells") is not None:
            return int(merged["n_cells"]) * layers
        d = merged.get("divisions") or (1, 1)
        d = (d, 1) if isinstance(d, int) else d  # one count (hexagons): at least a row
        return math.prod(int(n) for n in d) * max(self.cells_per_division, 1)

    def option(self, name: str) -> Option | None:
        """The option called ``name``, or None."""
        return next((o for o in self.options if o.name == name), None)

    def generate(self, **options: Any) -> M:
        """The mesh for the given options (the others keep their defaults).

        Raises
        ------
        ValueError
            For an option the family does not take, two options that replace each
            other, or values the generator rejects (the message names them).
        """
        for key in options:
            opt = self.option(key)
            if opt is None:
                names = [o.name for o in self.options]
                close = difflib.get_close_matches(key, names, n=1)
                hint = f"did you mean {close[0]!r}? " if close else ""
                raise ValueError(
                    f"{key}: family {self.name!r} has no such option; {hint}"
                    f"its options: {', '.join(names)}"
                )
            both = [r for r in opt.replaces if r in options]
            if both:
                raise ValueError(f"give either {key!r} or {'/'.join(map(repr, both))}, not both")
        return self.function(**options)


def voronoi(
    size: Sequence[float] = (2.0, 1.0),
    n_cells: int = 256,
    seed: int | None = 0,
    origin: Sequence[float] = (0.0, 0.0),
    *,
    domain: ArrayLike | None = None,
    seeds: ArrayLike | None = None,
    **options: Any,
) -> Mesh:
    """Voronoi mesh of a rectangle, or of the polygon ``domain``.

    Centroidal with ``n_cells`` cells (:func:`~vemwear.mesh.voronoi.voronoi_mesh`,
    with ``seed`` and its ``options``), or the cells of the given ``seeds``
    (:func:`~vemwear.mesh.voronoi.voronoi_from_seeds`).
    """
    dom = rectangle_domain(size, origin) if domain is None else domain
    if seeds is not None:
        return voronoi_from_seeds(dom, seeds, **options)
    return voronoi_mesh(dom, n_cells, seed, **options)  # type: ignore[return-value]


def _options(*functions: Callable[..., Any], **specs: tuple[Any, ...]) -> tuple[Option, ...]:
    """Options ``name=(type, help[, replaces])``, defaults from the functions' signatures."""
    params: dict[str, inspect.Parameter] = {}
    for fn in reversed(functions):
        params.update(inspect.signature(fn).parameters)
    out = []
    for name, (tp, text, *replaces) in specs.items():
        d = params[name].default
        default = None if d is inspect.Parameter.empty else d
        out.append(Option(name, tp, text, default, tuple(replaces[0]) if replaces else ()))
    return tuple(out)


_SIZE = (Pair, "side lengths [lx, ly] of the rectangle")
_ORIGIN = (Pair, "lower-left corner [x0, y0] of the rectangle")
_GRID = {"size": _SIZE, "divisions": (Counts, "cells [nx, ny] in x and y"), "origin": _ORIGIN}
_SEED = (int, "seed of the random numbers")
_VORONOI = _options(
    voronoi,
    voronoi_mesh,
    size=_SIZE,
    n_cells=(int, "number of cells"),
    seed=_SEED,
    origin=_ORIGIN,
    domain=(
        Points,
        "corners [[x, y], ...] of a polygon (counter-clockwise) instead of the rectangle",
        ("size", "origin"),
    ),
    seeds=(
        Points,
        "the seeds [[x, y], ...] of the cells instead of a centroidal mesh",
        ("n_cells", "seed"),
    ),
    lloyd_iterations=(int, "largest number of Lloyd iterations"),
    lloyd_tol=(float, "stop when no seed moves by more than this times the cell size"),
    collapse_tol=(float, "merge vertices closer than this times the cell size"),
)

#: The mesh families by name.
FAMILIES: Mapping[str, Family[Mesh]] = {
    f.name: f
    for f in (
        Family(
            "squares",
            rectangle_squares,
            "axis-aligned rectangles, nx * ny cells",
            _options(rectangle_squares, **_GRID),
            ("rectangle_squares",),
            cells_per_division=1,
        ),
        Family(
            "triangles",
            rectangle_triangles,
            "each grid rectangle cut into two triangles, 2 * nx * ny cells",
            _options(
                rectangle_triangles,
                **_GRID,
                diagonal=(
                    Literal["right", "left", "alternate"],
                    "diagonals from lower-left to upper-right, from lower-right to "
                    "upper-left, or both in a checkerboard",
                ),
            ),
            ("rectangle_triangles",),
            cells_per_division=2,
        ),
        Family(
            "voronoi",
            voronoi,
            "centroidal Voronoi polygons, exactly n_cells cells (the paper's mesh B)",
            _VORONOI,
            ("rectangle_voronoi", "voronoi_mesh", "voronoi_from_seeds"),
        ),
        Family(
            "distorted",
            distorted_quads,
            "grid quadrilaterals with randomly moved interior vertices",
            _options(
                distorted_quads,
                **_GRID,
                amplitude=(float, "vertices move by up to amplitude * (lx/nx, ly/ny); < 0.25"),
                seed=_SEED,
                slide_boundary=(bool, "also move the vertices on the sides, along them"),
            ),
            ("distorted_quads",),
            cells_per_division=1,
        ),
        Family(
            "hexagons",
            hexagons,
            "hexagon-dominant (Voronoi cells of a triangular lattice)",
            _options(
                hexagons,
                size=_SIZE,
                divisions=(int | Counts, "hexagons per row, or [per row, rows]"),
                origin=_ORIGIN,
            ),
        ),
        Family(
            "nonconvex",
            nonconvex_mesh,
            "chevron-shaped non-convex cells, nx * ny cells",
            _options(
                nonconvex_mesh,
                **_GRID,
                depth=(float, "height of the chevrons in row heights, in (0, 1)"),
            ),
            ("nonconvex_mesh",),
            cells_per_division=1,
        ),
        Family(
            "hanging",
            squares_with_hanging_nodes,
            "squares, every other one split in four (hanging nodes in the others)",
            _options(
                squares_with_hanging_nodes,
                **_GRID,
                pattern=(
                    Literal["checkerboard", "random", "bottom", "corner"],
                    "the split squares: every other one, a random half, the bottom row or "
                    "the lower-left quarter",
                ),
                seed=_SEED,
            ),
            ("squares_with_hanging_nodes",),
        ),
    )
}
_BY_NAME = {n: f for f in FAMILIES.values() for n in (f.name, *f.aliases)}


def family(name: str) -> Family[Mesh]:
    """The family called ``name`` (or one of its aliases).

    Raises
    ------
    ValueError
        For an unknown name; the message suggests the closest one.
    """
    return lookup(name, _BY_NAME, FAMILIES)


def lookup(name: str, by_name: Mapping[str, Family[M]], families: Mapping[str, Any]) -> Family[M]:
    """The family called ``name`` in ``by_name`` (names and aliases), or a ValueError that
    suggests the closest name and lists ``families``."""
    if name not in by_name:
        close = difflib.get_close_matches(name, list(by_name), n=1, cutoff=0.6)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise ValueError(
            f"{name!r} is not a known mesh family; {hint}available: {', '.join(families)}"
        )
    return by_name[name]


# ---------------------------------------------------------------------------- a rectangle
def _divisions_for(n: int, per: int, size: tuple[float, float], family: str) -> tuple[int, int]:
    """Grid ``(nx, ny)`` with ``per * nx * ny == n`` whose rectangles are closest to squares."""
    if n < 1 or n % per:
        raise MeshError(
            f"--cells {n}: family {family!r} has {per} cells per grid rectangle, "
            f"so the count must be a positive multiple of {per}"
        )
    m = n // per
    lx, ly = size
    small = [d for d in range(1, math.isqrt(m) + 1) if m % d == 0]
    best = min(
        {*small, *(m // d for d in small)},
        key=lambda nx: abs(math.log((lx / nx) / (ly / (m // nx)))),
    )
    nx, ny = best, m // best
    ratio = max((lx / nx) / (ly / ny), (ly / ny) / (lx / nx))
    if ratio > 2.0 + 1e-12:
        raise MeshError(
            f"--cells {n}: the closest grid for family {family!r} on a {lx:g} x {ly:g} "
            f"rectangle is {nx} x {ny}, whose cells have aspect ratio {ratio:.3g} > 2; "
            "choose another count or give --divisions NX NY"
        )
    return nx, ny


def generate_mesh(
    family: str,
    *,
    size: Sequence[float] = (2.0, 1.0),
    cells: int | None = None,
    divisions: Sequence[int] | None = None,
    seed: int | None = None,
    params: Mapping[str, Any] | None = None,
    refine_contact: int = 0,
    boundary: str = "paper",
) -> Mesh:
    """Generate a mesh of the rectangle ``[0, lx] x [0, ly]`` of a mesh family.

    Parameters
    ----------
    family : str
        A key of :data:`vemwear.mesh.registry.FAMILIES`.
    size : (lx, ly)
        Side lengths (default: the paper's ``(2, 1)``).
    cells : int, optional
        Number of cells: exact for ``voronoi``; for grid families (squares, triangles,
        distorted, nonconvex) the grid with that many cells whose rectangles are
        closest to squares (aspect ratio at most 2).
    divisions : (nx, ny), optional
        Grid divisions (not for ``voronoi``). Without ``cells`` and ``divisions``
        the generator's defaults apply.
    seed : int, optional
        Random seed (``voronoi``, ``distorted``, ``hanging`` with
        ``params={"pattern": "random"}``).
    params : mapping, optional
        Further keyword arguments of the generator (e.g. ``amplitude`` of
        ``distorted``, ``pattern`` of ``hanging``, ``diagonal`` of ``triangles``).
    refine_contact : int
        Refine the cells along the contact part this many times
        (:func:`vemwear.mesh.refine_along`; needs ``boundary="paper"``).
    boundary : {"paper", "none"}
        ``paper``: clamped = left, traction = top and right, contact = bottom
        (paper Section 5, :func:`vemwear.mesh.tag_rectangle`); ``none``: untagged.

    Returns
    -------
    Mesh

    Raises
    ------
    MeshError
        For an unknown family, arguments the family does not take, or a generator
        that rejects its arguments (the message says which).
    """
    from .boundary import tag_rectangle
    from .refine import refine_along

    if family not in FAMILIES:
        raise MeshError(f"unknown mesh family {family!r}; available: {', '.join(FAMILIES)}")
    fam = FAMILIES[family]
    takes = {o.name for o in fam.options}
    if boundary not in ("paper", "none"):
        raise MeshError(f"--boundary must be 'paper' or 'none', got {boundary!r}")
    lx, ly = (float(s) for s in size)
    if not (lx > 0 and ly > 0 and math.isfinite(lx) and math.isfinite(ly)):
        raise MeshError(f"--size must be two positive numbers, got {lx:g} {ly:g}")
    if refine_contact < 0:
        raise MeshError(f"--refine-contact must be >= 0, got {refine_contact}")
    if refine_contact and boundary != "paper":
        raise MeshError("--refine-contact needs the boundary parts (--boundary paper)")
    kwargs: dict[str, Any] = {"size": (lx, ly)}
    if cells is not None and divisions is not None:
        raise MeshError("give either --cells or --divisions, not both")
    if cells is not None:
        if "n_cells" in takes:
            if cells < 1:
                raise MeshError(f"--cells must be >= 1, got {cells}")
            kwargs["n_cells"] = int(cells)
        elif fam.cells_per_division:
            kwargs["divisions"] = _divisions_for(
                int(cells), fam.cells_per_division, (lx, ly), family
            )
        else:
            raise MeshError(
                f"family {family!r} does not take --cells (its cell count "
                "follows from the divisions); give --divisions NX NY"
            )
    if divisions is not None:
        if "divisions" not in takes:
            raise MeshError(f"family {family!r} does not take --divisions; give --cells N")
        nx, ny = (int(d) for d in divisions)
        if nx < 1 or ny < 1:
            raise MeshError(f"--divisions must be positive integers, got {nx} {ny}")
        kwargs["divisions"] = (nx, ny)
    if seed is not None:
        if "seed" not in takes:
            raise MeshError(f"family {family!r} is deterministic: --seed does not apply")
        kwargs["seed"] = int(seed)
    for key, value in (params or {}).items():
        if key in ("n_cells", "divisions", "seed", "size"):
            raise MeshError(f"--param {key}: use the option --{key.replace('n_', '')} instead")
        kwargs[key] = value
    try:
        mesh = fam.generate(**kwargs)
    except (TypeError, ValueError) as exc:
        msg = str(exc)
        raise MeshError(
            f"--param {msg}" if msg.startswith(tuple(params or ())) else f"family {family!r}: {msg}"
        ) from exc
    if boundary == "paper":
        mesh = tag_rectangle(mesh)
    if refine_contact:
        mesh = refine_along(mesh, "contact", int(refine_contact))
    return mesh
