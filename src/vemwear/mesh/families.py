"""Families of polygonal meshes of a rectangle, for tests and convergence studies.

Every generator returns a valid, conforming mesh with counter-clockwise cells and
an untagged boundary whose edges lie exactly on the sides of the rectangle, so
:func:`~vemwear.mesh.boundary.tag_rectangle` applies directly. All are
deterministic (random ones for a given ``seed``).

* :func:`distorted_quads` -- structured quadrilaterals with randomly moved
  interior vertices (convex for ``amplitude < 0.25``).
* :func:`hexagons` -- hexagon-dominant mesh (Voronoi cells of a triangular
  lattice, clipped at the rectangle).
* :func:`nonconvex_mesh` -- chevron (arrow-shaped) non-convex cells.
* :func:`squares_with_hanging_nodes` -- squares, some split in four, so their
  neighbours carry hanging nodes.
* :func:`rectangle_voronoi` -- centroidal Voronoi mesh with exactly ``n`` cells.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from .generate import rectangle_squares
from .polymesh import Mesh
from .refine import refine_cells
from .voronoi import rectangle_domain, voronoi_from_seeds, voronoi_mesh

__all__ = [
    "distorted_quads",
    "hexagons",
    "nonconvex_mesh",
    "perturb_vertices",
    "rectangle_voronoi",
    "squares_with_hanging_nodes",
]


def _size_div(size: Sequence[float], divisions: Sequence[int]) -> tuple[float, float, int, int]:
    lx, ly = (float(s) for s in size)
    nx, ny = (int(d) for d in divisions)
    if lx <= 0 or ly <= 0:
        raise ValueError(f"size must be positive, got {tuple(size)}")
    if nx < 1 or ny < 1:
        raise ValueError(f"divisions must be positive integers, got {tuple(divisions)}")
    return lx, ly, nx, ny


def perturb_vertices(
    mesh: Mesh,
    amplitude: ArrayLike,
    seed: int | None = 0,
    *,
    slide_boundary: bool = False,
) -> Mesh:
    """Move the interior vertices of a mesh of a rectangle by uniform random offsets.

    Parameters
    ----------
    mesh : Mesh
        Mesh of an axis-aligned rectangle (its bounding box).
    amplitude : float or (2,) array_like
        Maximal displacement in x and y (absolute lengths).
    seed : int or None
        Seed of :func:`numpy.random.default_rng`.
    slide_boundary : bool
        Also move the vertices on the sides (not the corners) along their side.

    Returns
    -------
    Mesh
        Same cells and tags, moved points. Validity is the caller's business
        (see :func:`distorted_quads` for a safe amplitude).
    """
    amp = np.broadcast_to(np.asarray(amplitude, dtype=float), (2,))
    rng = np.random.default_rng(seed)
    P = mesh.points.copy()
    lo, hi = P.min(axis=0), P.max(axis=0)
    tol = 1e-9 * float(np.max(hi - lo))
    on_x = (np.abs(P[:, 0] - lo[0]) <= tol) | (np.abs(P[:, 0] - hi[0]) <= tol)
    on_y = (np.abs(P[:, 1] - lo[1]) <= tol) | (np.abs(P[:, 1] - hi[1]) <= tol)
    d = rng.uniform(-1.0, 1.0, size=P.shape) * amp
    interior = ~on_x & ~on_y
    P[interior] += d[interior]
    if slide_boundary:
        sx = on_y & ~on_x  # bottom/top sides: slide in x
        sy = on_x & ~on_y
        P[sx, 0] += d[sx, 0]
        P[sy, 1] += d[sy, 1]
    return Mesh(P, mesh.cell_offsets, mesh.cell_vertices, mesh.boundary_tags, mesh.part_names)


def distorted_quads(
    size: Sequence[float] = (2.0, 1.0),
    divisions: Sequence[int] = (16, 8),
    amplitude: float = 0.2,
    seed: int | None = 0,
    origin: Sequence[float] = (0.0, 0.0),
    *,
    slide_boundary: bool = False,
) -> Mesh:
    """Structured quadrilaterals with randomly perturbed interior vertices.

    Parameters
    ----------
    size : (lx, ly)
    divisions : (nx, ny)
        Number of cells in each direction.
    amplitude : float
        Every interior vertex moves by up to ``amplitude * (lx / nx, ly / ny)``,
        uniformly at random; ``0 <= amplitude < 0.25`` keeps every cell convex.
    seed : int or None
        Random seed.
    origin : (x0, y0)
    slide_boundary : bool
        Also move side vertices along their side (corners stay).

    Returns
    -------
    Mesh
        ``nx * ny`` convex quadrilaterals.
    """
    lx, ly, nx, ny = _size_div(size, divisions)
    if not 0.0 <= amplitude < 0.25:
        raise ValueError(f"amplitude must lie in [0, 0.25) to keep cells convex, got {amplitude}")
    base = rectangle_squares((lx, ly), (nx, ny), (float(origin[0]), float(origin[1])))
    return perturb_vertices(
        base, (amplitude * lx / nx, amplitude * ly / ny), seed, slide_boundary=slide_boundary
    )


def hexagons(
    size: Sequence[float] = (2.0, 1.0),
    divisions: Sequence[int] | int = 16,
    origin: Sequence[float] = (0.0, 0.0),
) -> Mesh:
    """Hexagon-dominant mesh: Voronoi cells of a triangular lattice, clipped at the rectangle.

    Seeds lie in ``ny`` rows at heights ``(j + 1/2) * ly / ny``; even rows have
    ``nx`` seeds at ``(i + 1/2) * lx / nx``, odd rows ``nx + 1`` seeds at
    ``i * lx / nx`` (the first and last on the sides, giving half hexagons).
    Interior cells are hexagons; the cells along the bottom and top sides are
    heptagons or pentagons (cut hexagons), those on the left and right sides half
    hexagons or cut hexagons.

    Parameters
    ----------
    size : (lx, ly)
    divisions : int or (nx, ny)
        Hexagons per row, and optionally the number of rows; by default ``ny``
        makes the hexagons as regular as possible (row spacing close to
        ``sqrt(3) / 2`` times the seed spacing).
    origin : (x0, y0)

    Returns
    -------
    Mesh
        ``nx * ceil(ny / 2) + (nx + 1) * floor(ny / 2)`` cells.
    """
    if np.ndim(divisions) == 0:
        nx = int(divisions)  # type: ignore[arg-type]
        lx, ly = (float(s) for s in size)
        ny = max(1, round(ly / (np.sqrt(3.0) / 2.0 * lx / max(nx, 1))))
    else:
        nx, ny = (int(d) for d in divisions)  # type: ignore[union-attr]
    lx, ly, nx, ny = _size_div(size, (nx, ny))
    dx, dy = lx / nx, ly / ny
    rows = []
    for j in range(ny):
        y = (j + 0.5) * dy
        x = (np.arange(nx) + 0.5) * dx if j % 2 == 0 else np.arange(nx + 1) * dx
        rows.append(np.column_stack([x, np.full(len(x), y)]))
    o = np.asarray(origin, dtype=float)
    seeds = np.vstack(rows) + o
    domain = rectangle_domain((lx, ly), (float(o[0]), float(o[1])))
    return voronoi_from_seeds(domain, seeds, collapse_tol=1e-6)


def nonconvex_mesh(
    size: Sequence[float] = (2.0, 1.0),
    divisions: Sequence[int] = (8, 4),
    depth: float = 0.5,
    origin: Sequence[float] = (0.0, 0.0),
) -> Mesh:
    """Chevron-shaped (non-convex) cells tiling a rectangle.

    Every interior horizontal grid line is replaced by a zigzag whose vertex above
    the middle of each cell is raised by ``depth * ly / ny``. A cell of an interior
    row is then the hexagon ``(x_i, y_j), (x_{i+1/2}, y_j + d), (x_{i+1}, y_j),
    (x_{i+1}, y_{j+1}), (x_{i+1/2}, y_{j+1} + d), (x_i, y_{j+1})``, an arrow pointing
    up with a re-entrant corner at the bottom; the bottom row has a straight bottom
    (convex pentagons) and the top row a straight top (non-convex pentagons).

    Parameters
    ----------
    size : (lx, ly)
    divisions : (nx, ny)
    depth : float
        Height of the chevrons as a fraction of the row height, ``0 < depth < 1``.
    origin : (x0, y0)

    Returns
    -------
    Mesh
        ``nx * ny`` cells, all star-shaped; non-convex if ``ny >= 2``.
    """
    lx, ly, nx, ny = _size_div(size, divisions)
    if not 0.0 < depth < 1.0:
        raise ValueError(f"depth must lie in (0, 1), got {depth}")
    x = np.linspace(0.0, lx, nx + 1)
    y = np.linspace(0.0, ly, ny + 1)
    X, Y = np.meshgrid(x, y)  # (ny + 1, nx + 1)
    grid = np.column_stack([X.ravel(), Y.ravel()])
    xm = 0.5 * (x[:-1] + x[1:])
    ya = y[1:-1] + depth * ly / ny
    AX, AY = np.meshgrid(xm, ya)  # apex (i, line j) for lines j = 1..ny-1
    apex = np.column_stack([AX.ravel(), AY.ravel()])
    points = np.vstack([grid, apex]) + np.asarray(origin, dtype=float)

    def g(i: int, j: int) -> int:
        return j * (nx + 1) + i

    def a(i: int, j: int) -> int:
        return len(grid) + (j - 1) * nx + i

    cells: list[list[int]] = []
    for j in range(ny):
        for i in range(nx):
            bottom = [g(i, j), g(i + 1, j)] if j == 0 else [g(i, j), a(i, j), g(i + 1, j)]
            top = (
                [g(i + 1, j + 1), g(i, j + 1)]
                if j == ny - 1
                else [
                    g(i + 1, j + 1),
                    a(i, j + 1),
                    g(i, j + 1),
                ]
            )
            cells.append(bottom + top)
    return Mesh.from_cells(points, cells)


def squares_with_hanging_nodes(
    size: Sequence[float] = (2.0, 1.0),
    divisions: Sequence[int] = (8, 4),
    pattern: str = "checkerboard",
    seed: int | None = 0,
    origin: Sequence[float] = (0.0, 0.0),
) -> Mesh:
    """Squares of which some are split in four, leaving hanging nodes in their neighbours.

    Parameters
    ----------
    size : (lx, ly)
    divisions : (nx, ny)
        The coarse grid.
    pattern : {"checkerboard", "random", "bottom", "corner"}
        Which coarse cells are split: every other one (all unsplit cells then have
        four hanging nodes), a random half (``seed``), the bottom row, or the
        lower-left quarter of the grid.
    seed : int or None
        For ``pattern="random"``.
    origin : (x0, y0)

    Returns
    -------
    Mesh
        Quadrilaterals (split cells) and polygons with 5 to 8 vertices, collinear
        ones being hanging nodes.
    """
    lx, ly, nx, ny = _size_div(size, divisions)
    base = rectangle_squares((lx, ly), (nx, ny), (float(origin[0]), float(origin[1])))
    i = np.arange(nx * ny) % nx
    j = np.arange(nx * ny) // nx
    if pattern == "checkerboard":
        sel = np.flatnonzero((i + j) % 2 == 0)
    elif pattern == "random":
        rng = np.random.default_rng(seed)
        sel = np.sort(rng.choice(nx * ny, size=(nx * ny) // 2, replace=False))
    elif pattern == "bottom":
        sel = np.flatnonzero(j == 0)
    elif pattern == "corner":
        sel = np.flatnonzero((i < max(1, nx // 2)) & (j < max(1, ny // 2)))
    else:
        raise ValueError(
            f"pattern must be 'checkerboard', 'random', 'bottom' or 'corner', got {pattern!r}"
        )
    return refine_cells(base, sel)  # type: ignore[return-value]


def rectangle_voronoi(
    size: Sequence[float] = (2.0, 1.0),
    n_cells: int = 256,
    seed: int | None = 0,
    origin: Sequence[float] = (0.0, 0.0),
    **kwargs: object,
) -> Mesh:
    """Centroidal Voronoi mesh of a rectangle with exactly ``n_cells`` cells (untagged).

    A shortcut for ``voronoi_mesh(rectangle_domain(size, origin), n_cells, seed,
    **kwargs)``; see :func:`~vemwear.mesh.voronoi.voronoi_mesh`. The paper's Example 5.4
    uses 2048 cells of (0, 2) x (0, 1) with seed 0.

    Parameters
    ----------
    size : (float, float)
        Side lengths ``(lx, ly)``.
    n_cells : int
        The number of cells.
    seed : int or None
        Seed of the initial points (None: not reproducible).
    origin : (float, float)
        The lower-left corner.
    **kwargs
        Further options of :func:`~vemwear.mesh.voronoi.voronoi_mesh` (Lloyd iterations
        and tolerances).

    Returns
    -------
    Mesh

    Examples
    --------
    >>> from vemwear.mesh import rectangle_voronoi
    >>> mesh = rectangle_voronoi((2.0, 1.0), n_cells=32, seed=0)
    >>> mesh.n_cells, round(float(mesh.cell_areas.sum()), 12)
    (32, 2.0)
    """
    return voronoi_mesh(rectangle_domain(size, origin), n_cells, seed, **kwargs)  # type: ignore[arg-type,return-value]
