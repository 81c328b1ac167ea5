"""Polygonal domains of the Voronoi mesher: constructors, validation, point tests.

A domain is the ``(k, 2)`` array of the counter-clockwise corners of a simple
polygon, convex or not.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .checks import crossing_sides

__all__ = ["as_domain", "l_shape_domain", "point_in_domain", "rectangle_domain"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def rectangle_domain(
    size: Sequence[float] = (2.0, 1.0), origin: Sequence[float] = (0.0, 0.0)
) -> FloatArray:
    """Counter-clockwise corners of the rectangle ``origin + [0, lx] x [0, ly]``.

    Parameters
    ----------
    size : (lx, ly)
        Side lengths, positive.
    origin : (x0, y0)
        Lower-left corner.

    Returns
    -------
    (4, 2) float array
    """
    lx, ly = (float(s) for s in size)
    if lx <= 0 or ly <= 0:
        raise ValueError(f"size must be positive, got {tuple(size)}")
    x0, y0 = (float(o) for o in origin)
    return np.array([[x0, y0], [x0 + lx, y0], [x0 + lx, y0 + ly], [x0, y0 + ly]])


def l_shape_domain(
    size: Sequence[float] = (2.0, 2.0),
    notch: Sequence[float] = (1.0, 1.0),
    origin: Sequence[float] = (0.0, 0.0),
) -> FloatArray:
    """Counter-clockwise corners of an L-shaped domain.

    The domain is the rectangle ``origin + [0, lx] x [0, ly]`` without its
    upper-right part ``[lx - nx, lx] x [ly - ny, ly]``; the re-entrant corner is
    ``origin + (lx - nx, ly - ny)``.

    Parameters
    ----------
    size : (lx, ly)
        Bounding box of the L.
    notch : (nx, ny)
        Size of the removed upper-right rectangle, ``0 < nx < lx``, ``0 < ny < ly``.
    origin : (x0, y0)
        Lower-left corner.

    Returns
    -------
    (6, 2) float array
    """
    lx, ly = (float(s) for s in size)
    nx, ny = (float(s) for s in notch)
    if not (0 < nx < lx and 0 < ny < ly):
        raise ValueError(f"notch {tuple(notch)} must be smaller than size {tuple(size)}")
    x0, y0 = (float(o) for o in origin)
    pts = np.array(
        [[0, 0], [lx, 0], [lx, ly - ny], [lx - nx, ly - ny], [lx - nx, ly], [0, ly]], dtype=float
    )
    return pts + np.array([x0, y0])


def _polygon_area(p: FloatArray) -> float:
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def as_domain(domain: ArrayLike) -> FloatArray:
    """Validate a domain polygon and return it as a ``(k, 2)`` float array.

    Parameters
    ----------
    domain : (k, 2) array_like
        Corners of a simple polygon, counter-clockwise, without repetition of the
        first corner at the end.

    Raises
    ------
    ValueError
        If the polygon has fewer than three corners, repeated or non-finite
        corners, crossing sides, or is clockwise.
    """
    d = np.array(domain, dtype=float)
    if d.ndim != 2 or d.shape[1] != 2 or len(d) < 3:
        raise ValueError(f"domain must be a (k, 2) array with k >= 3, got shape {d.shape}")
    if not np.all(np.isfinite(d)):
        raise ValueError("domain corners must be finite")
    if len(d) > 3 and np.allclose(d[0], d[-1]):
        raise ValueError("do not repeat the first domain corner at the end")
    scale = float(np.max(np.ptp(d, axis=0)))
    nxt = np.roll(d, -1, axis=0)
    if np.any(np.linalg.norm(nxt - d, axis=1) <= 1e-12 * scale):
        raise ValueError("domain has repeated consecutive corners")
    hit, i, j = crossing_sides(d[None], eps=0.0)
    if np.any(hit):
        a, b = i[hit[0]][0], j[hit[0]][0]
        raise ValueError(f"domain sides {a} and {b} cross; use a simple polygon")
    if _polygon_area(d) <= 0:
        raise ValueError("domain corners must be listed counter-clockwise (positive area)")
    return d


def point_in_domain(points: ArrayLike, domain: ArrayLike) -> NDArray[np.bool_]:
    """Even-odd test: which points lie inside the polygon ``domain``.

    Points on the boundary may be reported either way.
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    dom = np.asarray(domain, dtype=float)
    a, b = dom, np.roll(dom, -1, axis=0)
    out = np.zeros(len(pts), dtype=bool)
    chunk = max(1, 2_000_000 // len(dom))
    for s in range(0, len(pts), chunk):
        x = pts[s : s + chunk, 0:1]
        y = pts[s : s + chunk, 1:2]
        straddle = (a[None, :, 1] > y) != (b[None, :, 1] > y)
        with np.errstate(divide="ignore", invalid="ignore"):
            xc = a[None, :, 0] + (y - a[None, :, 1]) * (b[None, :, 0] - a[None, :, 0]) / (
                b[None, :, 1] - a[None, :, 1]
            )
        out[s : s + chunk] = (np.sum(straddle & (x < xc), axis=1) % 2) == 1
    return out


def _nearest_sides(points: FloatArray, dom: FloatArray) -> tuple[IntArray, FloatArray, FloatArray]:
    """The side of the polygon nearest to every point (the first of equally near ones),
    the parameter in [0, 1] of the nearest point on it, and the distance."""
    a, b = dom, np.roll(dom, -1, axis=0)
    ab = b - a
    L2 = np.sum(ab * ab, axis=1)
    side = np.zeros(len(points), dtype=np.int64)
    par = np.zeros(len(points))
    dist = np.full(len(points), np.inf)
    chunk = max(1, 2_000_000 // len(dom))
    for s in range(0, len(points), chunk):
        p = points[s : s + chunk, None, :]
        t = np.clip(np.sum((p - a) * ab, axis=2) / L2, 0.0, 1.0)
        d = p - (a + t[..., None] * ab)
        dd = np.sqrt(np.sum(d * d, axis=2))
        k = np.argmin(dd, axis=1)
        rows = np.arange(len(k))
        side[s : s + chunk], par[s : s + chunk], dist[s : s + chunk] = k, t[rows, k], dd[rows, k]
    return side, par, dist
