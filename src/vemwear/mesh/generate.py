"""Structured meshes of a rectangle: squares (quadrilaterals) and triangles."""

from __future__ import annotations

import numpy as np

from .checks import known_valid
from .polymesh import Mesh


def _grid(size: tuple[float, float], divisions: tuple[int, int], origin: tuple[float, float]):
    nx, ny = (int(d) for d in divisions)
    if nx < 1 or ny < 1:
        raise ValueError(f"divisions must be positive integers, got {divisions}")
    lx, ly = (float(s) for s in size)
    if lx <= 0 or ly <= 0:
        raise ValueError(f"size must be positive, got {size}")
    x = origin[0] + np.linspace(0.0, lx, nx + 1)
    y = origin[1] + np.linspace(0.0, ly, ny + 1)
    X, Y = np.meshgrid(x, y)  # row j = y_j
    points = np.column_stack([X.ravel(), Y.ravel()])
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    v00 = (j * (nx + 1) + i).ravel()
    # valid by construction when no spacing is near the checks' tolerances (1e-9 of the
    # extent and below): then its checks are recorded as passed instead of run
    h = min(np.diff(x).min(), np.diff(y).min())
    valid = bool(h > 1e-6 * max(lx, ly))
    return points, v00, v00 + 1, v00 + nx + 2, v00 + nx + 1, valid


def rectangle_squares(
    size: tuple[float, float] = (2.0, 1.0),
    divisions: tuple[int, int] = (32, 16),
    origin: tuple[float, float] = (0.0, 0.0),
) -> Mesh:
    """Rectangle split into ``nx * ny`` axis-aligned rectangles (counter-clockwise).

    The boundary is untagged; use :meth:`Mesh.with_boundary` or
    :func:`vemwear.mesh.boundary.tag_rectangle`.

    Parameters
    ----------
    size : (float, float)
        Side lengths ``(lx, ly)`` (default: the paper's (0, 2) x (0, 1)).
    divisions : (int, int)
        Cells ``(nx, ny)`` along x and y (default: the paper's 32 x 16).
    origin : (float, float)
        The lower-left corner.

    Returns
    -------
    Mesh

    Examples
    --------
    >>> from vemwear.mesh import rectangle_squares
    >>> mesh = rectangle_squares((2.0, 1.0), (4, 2))
    >>> mesh.n_cells, mesh.n_points
    (8, 15)
    >>> mesh.cell(0)  # vertex ids, counter-clockwise
    array([0, 1, 6, 5])
    """
    points, a, b, c, d, valid = _grid(size, divisions, origin)
    mesh = Mesh.from_cells(points, np.column_stack([a, b, c, d]))
    return known_valid(mesh) if valid else mesh


def rectangle_triangles(
    size: tuple[float, float] = (2.0, 1.0),
    divisions: tuple[int, int] = (32, 16),
    origin: tuple[float, float] = (0.0, 0.0),
    diagonal: str = "right",
) -> Mesh:
    """Rectangle split into ``2 * nx * ny`` triangles (untagged).

    Parameters
    ----------
    size : (float, float)
        Side lengths ``(lx, ly)``.
    divisions : (int, int)
        Grid rectangles ``(nx, ny)``, each cut into two triangles.
    origin : (float, float)
        The lower-left corner.
    diagonal : {"right", "left", "alternate"}
        ``"right"`` cuts every rectangle from lower-left to upper-right, ``"left"``
        from lower-right to upper-left, ``"alternate"`` mixes both in a checkerboard
        (the union-jack-like pattern).

    Returns
    -------
    Mesh

    Examples
    --------
    >>> from vemwear.mesh import rectangle_triangles
    >>> mesh = rectangle_triangles((1.0, 1.0), (2, 2), diagonal="alternate")
    >>> mesh.n_cells, float(mesh.cell_areas.sum())
    (8, 1.0)
    """
    points, a, b, c, d, valid = _grid(size, divisions, origin)
    right = np.column_stack([a, b, c]), np.column_stack([a, c, d])
    left = np.column_stack([a, b, d]), np.column_stack([b, c, d])
    if diagonal == "right":
        t1, t2 = right
    elif diagonal == "left":
        t1, t2 = left
    elif diagonal == "alternate":
        nx = int(divisions[0])
        i = np.arange(len(a)) % nx
        j = np.arange(len(a)) // nx
        use_left = ((i + j) % 2 == 1)[:, None]
        t1 = np.where(use_left, left[0], right[0])
        t2 = np.where(use_left, left[1], right[1])
    else:
        raise ValueError(f"diagonal must be 'right', 'left' or 'alternate', got {diagonal!r}")
    mesh = Mesh.from_cells(points, np.vstack([t1, t2]))
    return known_valid(mesh) if valid else mesh
