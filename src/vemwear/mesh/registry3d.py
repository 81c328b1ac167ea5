"""The 3D mesh families: meshes of the box ``[0, lx] x [0, ly] x [0, lz]``.

Registered as the 2D families of :mod:`vemwear.mesh.registry` (the same
:class:`~vemwear.mesh.registry.Family` and :class:`~vemwear.mesh.registry.Option`), with
``dim = 3``: ``hexahedra``, ``tetrahedra``, ``prisms`` (any 2D family's mesh of the
rectangle extruded in layers) and ``voronoi3d``. :func:`generate_mesh3d` turns a family
and a cell count or grid into a mesh whose six sides are the parts ``xmin`` ... ``zmax``.
They are kept apart from :data:`~vemwear.mesh.registry.FAMILIES` until the configuration
schema and ``vemwear mesh generate`` handle 3D meshes.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any, Literal

import numpy as np

from .generate3d import BOX_SIDES, box_hexahedra, box_tetrahedra, extrude, tag_box
from .polyhedra import Mesh3D
from .polymesh import PARTS, Mesh, MeshError, part_names_with
from .registry import _SEED, FAMILIES, Family, _options, generate_mesh, lookup
from .voronoi3d import box_voronoi

__all__ = ["FAMILIES_3D", "box_prisms", "family3d", "generate_mesh3d"]

Triple = tuple[float, float, float]
Counts3 = tuple[int, int, int]
Points3 = tuple[Triple, ...]


def box_prisms(
    size: Sequence[float] = (2.0, 1.0, 1.0),
    n_cells: int = 64,
    layers: int = 4,
    seed: int | None = 0,
    origin: Sequence[float] = (0.0, 0.0, 0.0),
    base: str = "voronoi",
) -> Mesh3D:
    """Prisms: a 2D mesh of the ``lx`` x ``ly`` rectangle with ``n_cells`` cells (family
    ``base``) extruded in ``layers`` layers over ``lz``; ``n_cells * layers`` cells, the
    box's sides tagged."""
    if len(size) != 3 or len(origin) != 3:
        raise ValueError("size and origin need three entries each")
    if base not in _PRISM_BASES:
        raise ValueError(f"base must be one of {', '.join(_PRISM_BASES)}, got {base!r}")
    lx, ly, lz = (float(v) for v in size)
    fam = FAMILIES[base]
    m2 = generate_mesh(
        base,
        size=(lx, ly),
        cells=int(n_cells),
        seed=seed if fam.option("seed") else None,
        boundary="none",
    )
    m2 = Mesh(
        m2.points + np.asarray(origin[:2], dtype=float),
        m2.cell_offsets,
        m2.cell_vertices,
        part_names=part_names_with(PARTS, BOX_SIDES),
    )
    return tag_box(extrude(m2, int(layers), lz, z0=float(origin[2])))


_PRISM_BASES = ("voronoi", "squares", "triangles", "distorted", "nonconvex")
_SIZE3 = (Triple, "side lengths [lx, ly, lz] of the box")
_ORIGIN3 = (Triple, "corner [x0, y0, z0] of the box with the smallest coordinates")
_GRID3 = {
    "size": _SIZE3,
    "divisions": (Counts3, "cells [nx, ny, nz] in x, y and z"),
    "origin": _ORIGIN3,
}

#: The 3D mesh families (of a box) by name.
FAMILIES_3D: Mapping[str, Family[Mesh3D]] = {
    f.name: f
    for f in (
        Family(
            "hexahedra",
            box_hexahedra,
            "axis-aligned hexahedra, nx * ny * nz cells",
            _options(box_hexahedra, **_GRID3),
            ("box_hexahedra",),
            cells_per_division=1,
            dim=3,
        ),
        Family(
            "tetrahedra",
            box_tetrahedra,
            "each grid hexahedron cut into six tetrahedra (Kuhn), 6 * nx * ny * nz cells",
            _options(box_tetrahedra, **_GRID3),
            ("box_tetrahedra",),
            cells_per_division=6,
            dim=3,
        ),
        Family(
            "prisms",
            box_prisms,
            "a 2D mesh of n_cells cells extruded in layers: polygonal prisms",
            _options(
                box_prisms,
                size=_SIZE3,
                n_cells=(int, "cells of the 2D mesh of [lx, ly]"),
                layers=(int, "layers of prisms over lz"),
                seed=_SEED,
                origin=_ORIGIN3,
                base=(Literal[_PRISM_BASES], "the 2D mesh family extruded"),
            ),
            ("box_prisms", "extrude"),
            dim=3,
        ),
        Family(
            "voronoi3d",
            box_voronoi,
            "centroidal Voronoi polyhedra, exactly n_cells cells",
            _options(
                box_voronoi,
                size=_SIZE3,
                n_cells=(int, "number of cells"),
                seed=_SEED,
                origin=_ORIGIN3,
                seeds=(
                    Points3,
                    "the seeds [[x, y, z], ...] of the cells instead of Halton points",
                    ("n_cells", "seed"),
                ),
                lloyd_iterations=(int, "Lloyd iterations"),
                collapse_tol=(float, "merge vertices closer than this times the cell size"),
            ),
            ("box_voronoi",),
            dim=3,
        ),
    )
}
BY_NAME_3D = {n: f for f in FAMILIES_3D.values() for n in (f.name, *f.aliases)}


def family3d(name: str) -> Family[Mesh3D]:
    """The 3D family called ``name`` (or one of its aliases); a ValueError suggests the
    closest name."""
    return lookup(name, BY_NAME_3D, FAMILIES_3D)


# ---------------------------------------------------------------------------- a box
def _divisions3_for(n: int, per: int, size: tuple[float, float, float], family: str) -> Counts3:
    """Grid ``(nx, ny, nz)`` with ``per * nx * ny * nz == n`` whose cells are closest to cubes."""
    if n < 1 or n % per:
        raise MeshError(
            f"--cells {n}: family {family!r} has {per} cells per grid hexahedron, "
            f"so the count must be a positive multiple of {per}"
        )
    m = n // per
    divs = [d for d in range(1, m + 1) if m % d == 0]
    grids = [(a, b, m // (a * b)) for a in divs for b in divs if (m // a) % b == 0]

    def spread(g: Counts3) -> float:
        h = [math.log(s / d) for s, d in zip(size, g, strict=True)]
        return max(h) - min(h)

    best = min(grids, key=spread)
    if spread(best) > math.log(2.0) + 1e-12:
        raise MeshError(
            f"--cells {n}: the closest grid for family {family!r} on a "
            f"{' x '.join(f'{s:g}' for s in size)} box is {' x '.join(map(str, best))}, whose "
            "cells have aspect ratio > 2; choose another count or give --divisions NX NY NZ"
        )
    return best


def generate_mesh3d(
    family: str,
    *,
    size: Sequence[float] = (2.0, 1.0, 1.0),
    cells: int | None = None,
    divisions: Sequence[int] | None = None,
    seed: int | None = None,
    params: Mapping[str, Any] | None = None,
) -> Mesh3D:
    """Generate a mesh of the box ``[0, lx] x [0, ly] x [0, lz]`` of a 3D mesh family.

    Parameters
    ----------
    family : str
        A key of :data:`FAMILIES_3D` (or an alias).
    size : (lx, ly, lz)
    cells : int, optional
        Number of cells: exact for ``voronoi3d``; for ``prisms`` the cells of the 2D
        mesh (times ``layers``); for ``hexahedra`` and ``tetrahedra`` the grid with that
        many cells closest to cubes (aspect ratio at most 2).
    divisions : (nx, ny, nz), optional
        Grid divisions (``hexahedra``, ``tetrahedra``).
    seed : int, optional
        Random seed (``voronoi3d``, ``prisms``).
    params : mapping, optional
        Further keyword arguments of the generator (``layers``, ``base``, ...).

    Returns
    -------
    Mesh3D
        The sides tagged ``xmin`` ... ``zmax``.

    Raises
    ------
    MeshError
        For an unknown family, arguments the family does not take, or a generator that
        rejects its arguments.
    """
    try:
        fam = family3d(family)
    except ValueError as exc:
        raise MeshError(str(exc)) from None
    takes = {o.name for o in fam.options}
    lx, ly, lz = (float(s) for s in size)
    if not all(v > 0 and math.isfinite(v) for v in (lx, ly, lz)):
        raise MeshError(f"--size must be three positive numbers, got {lx:g} {ly:g} {lz:g}")
    kwargs: dict[str, Any] = {"size": (lx, ly, lz)}
    if cells is not None and divisions is not None:
        raise MeshError("give either --cells or --divisions, not both")
    if cells is not None:
        if "n_cells" in takes:
            kwargs["n_cells"] = int(cells)
        else:
            kwargs["divisions"] = _divisions3_for(
                int(cells), fam.cells_per_division, (lx, ly, lz), fam.name
            )
    if divisions is not None:
        if "divisions" not in takes:
            raise MeshError(f"family {fam.name!r} does not take --divisions; give --cells N")
        kwargs["divisions"] = tuple(int(d) for d in divisions)
    if seed is not None:
        if "seed" not in takes:
            raise MeshError(f"family {fam.name!r} is deterministic: --seed does not apply")
        kwargs["seed"] = int(seed)
    kwargs.update(params or {})
    try:
        mesh = fam.generate(**kwargs)
    except (TypeError, ValueError) as exc:
        raise MeshError(f"family {fam.name!r}: {exc}") from exc
    return mesh
