"""Figures of a 3D run: maps over the contact face, profiles along a line on it.

The contact nodes of a 3D run lie on planar faces (docs/method.md, section 10); the maps
show a nodal quantity over the contact surface seen along its mean normal (for the box
of ``vemwear example 3d`` the plane ``z = 0`` seen from below, coordinates ``(x, y)``),
on the Delaunay triangulation of the nodes' two in-plane coordinates, linear on every
triangle. A profile samples these linear interpolants along a straight line in that
plane (by default the middle line in the second coordinate, ``y = Ly / 2`` on the box).
Every function builds a :class:`matplotlib.figure.Figure` directly, returns it, and
saves it when ``path`` is given (as :mod:`vemwear.post.plots`).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.tri import LinearTriInterpolator, Triangulation
from numpy.typing import NDArray

from .layout import place_grid
from .plots import DPI, _finish, _params, _time_colors, _with_gap

if TYPE_CHECKING:
    from ..simulate.loop import Result

__all__ = ["contact_plane", "line_profile", "plot_contact_line", "plot_contact_maps"]

#: Nodal quantities of the maps: attribute of the result and label.
MAP_QUANTITIES = {
    "wear": r"wear $w$",
    "penetration": r"$u_\nu - w$",
    "u_nu": r"$u_\nu$",
    "p_soft": r"soft-layer pressure $p$",
    "p_rigid": r"rigid-layer pressure $\lambda$",
}
_AXES = ("x", "y", "z")


def contact_plane(result: Result) -> tuple[NDArray[np.float64], tuple[int, int]]:
    """The contact nodes' two in-plane coordinates (m, 2) and which axes they are: the
    two axes least aligned with the mean outward normal of the contact nodes."""
    cb = result.problem.contact
    n = np.abs((np.asarray(cb.weights)[:, None] * np.asarray(cb.normals)).sum(axis=0))
    a, b = sorted(int(i) for i in np.argsort(n)[:2])
    P = np.asarray(result.contact_points, dtype=float)
    return P[:, [a, b]], (a, b)


def _triangulation(result: Result) -> tuple[Triangulation, tuple[int, int]]:
    """The Delaunay triangulation of the contact nodes in their plane, without its
    slivers: nodes on a circle (a pin's face) give triangles of zero area at the
    boundary, which matplotlib's interpolators refuse."""
    xy, axes = contact_plane(result)
    tri = Triangulation(xy[:, 0], xy[:, 1])
    a, b, c = (xy[tri.triangles[:, k]] for k in range(3))
    area = 0.5 * np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    sliver = area <= 1e-9 * float(area.max(initial=0.0))
    if np.any(sliver):
        tri = Triangulation(xy[:, 0], xy[:, 1], tri.triangles[~sliver])
    return tri, axes


def _rows(result: Result, times: Sequence[float]) -> list[int]:
    t = np.asarray(result.t)
    return [int(np.abs(t - float(s)).argmin()) for s in times]


def _values(result: Result, name: str) -> NDArray[np.float64]:
    if name not in MAP_QUANTITIES:
        raise ValueError(f"quantity must be one of {', '.join(MAP_QUANTITIES)}, got {name!r}")
    return np.asarray(getattr(result, name), dtype=float)


def plot_contact_maps(
    result: Result,
    times: Sequence[float],
    path: str | os.PathLike[str] | None = None,
    quantities: Sequence[str] = ("wear", "penetration"),
) -> Figure:
    """Maps of nodal quantities over the contact face at chosen times.

    Parameters
    ----------
    result : Result
        A 3D run.
    times : sequence of float
        The times (the nearest kept levels are shown), one column each.
    path : path, optional
        Save the figure there.
    quantities : sequence of str
        Rows: ``wear``, ``penetration`` (``u_nu - w``), ``u_nu``, ``p_soft``, ``p_rigid``.

    Returns
    -------
    Figure
        One row per quantity with a shared colour scale (over the times shown), the
        contact nodes' in-plane coordinates as axes.
    """
    tri, (a, b) = _triangulation(result)
    rows = _rows(result, times)
    nq, nt = len(quantities), len(rows)
    xy = np.column_stack([tri.x, tri.y])
    aspect = float(np.ptp(xy[:, 1]) / max(np.ptp(xy[:, 0]), 1e-300))
    # panels 3.2 inches wide at the face's aspect; a tall face is narrower
    pw = min(3.2, 4.8 / max(aspect, 1e-300))
    panel = (pw, float(np.clip(pw * aspect, 0.5, 4.8)))
    fig = Figure(figsize=(3.2 * nt + 1.2, (panel[1] + 0.9) * nq + 0.6), dpi=DPI)
    # one scale per row and shared coordinates: tick labels on the outer panels only
    axes = np.atleast_2d(fig.subplots(nq, nt, squeeze=False, sharex=True, sharey=True))
    caxes = [fig.add_axes((0.0, 0.0, 0.1, 0.1), label="<colorbar>") for _ in range(nq)]
    for i, name in enumerate(quantities):
        V = _values(result, name)[rows]
        lo, hi = float(V.min()), float(V.max())
        if hi <= lo:
            hi = lo + 1e-12 * max(abs(lo), 1.0)
        levels = np.linspace(lo, hi, 15)
        im: Any = None
        for j, r in enumerate(rows):
            ax = axes[i, j]
            im = ax.tricontourf(tri, V[j], levels=levels, cmap="viridis", extend="neither")
            ax.set_aspect("equal")
            # a title at a fixed height: no search for tick labels above the panel
            ax.set_title(rf"$t$ = {float(result.t[r]):.3g}", fontsize=9, y=1.0)
            if i == nq - 1:
                ax.set_xlabel(f"${_AXES[a]}$")
            if j == 0:
                ax.set_ylabel(f"${_AXES[b]}$")
        fig.colorbar(im, cax=caxes[i], label=_with_gap(result, MAP_QUANTITIES[name]))
    title = fig.suptitle(f"Contact face: {_params(result)}", fontsize=10)
    place_grid(fig, axes.tolist(), panel, colorbars=caxes, suptitle=title)
    return _finish(fig, path)


def line_profile(
    result: Result,
    name: str,
    row: int,
    *,
    at: float | None = None,
    samples: int = 201,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A nodal quantity of a kept level along the line ``second coordinate = at`` of the
    contact plane (linear interpolation on the nodes' triangulation).

    Parameters
    ----------
    result : Result
    name : str
        As in :func:`plot_contact_maps`.
    row : int
        The kept level.
    at : float, optional
        The line's second in-plane coordinate (default: the middle of the contact face).
    samples : int
        Points along the line.

    Returns
    -------
    s, values : (samples,) arrays
        The first in-plane coordinate and the values there (NaN outside the nodes'
        convex hull).
    """
    tri, _ = _triangulation(result)
    y = float(0.5 * (tri.y.min() + tri.y.max())) if at is None else float(at)
    return _profile(tri, _values(result, name)[row], y, samples)


def _profile(
    tri: Triangulation, values: NDArray[np.float64], y: float, samples: int = 201
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """:func:`line_profile` on a given triangulation (its point locator, built on the
    first call, serves every later one)."""
    s = np.linspace(float(tri.x.min()), float(tri.x.max()), samples)
    f = LinearTriInterpolator(tri, values)
    return s, np.ma.filled(f(s, np.full_like(s, y)).astype(float), np.nan)


def plot_contact_line(
    result: Result,
    times: Sequence[float],
    path: str | os.PathLike[str] | None = None,
    *,
    at: float | None = None,
    quantities: Sequence[str] = ("wear", "penetration"),
) -> Figure:
    """Profiles of nodal quantities along a line of the contact face at chosen times (the
    3D analogue of :func:`~vemwear.post.plots.plot_contact_profiles`).

    Parameters
    ----------
    result : Result
        A 3D run.
    times : sequence of float
        The times (nearest kept levels), one curve each.
    path : path, optional
        Save the figure there.
    at : float, optional
        As in :func:`line_profile` (default: the middle line, ``y = Ly / 2`` on the box).
    quantities : sequence of str
        One panel each.

    Returns
    -------
    Figure
    """
    tri, (a, b) = _triangulation(result)
    y = float(0.5 * (tri.y.min() + tri.y.max())) if at is None else float(at)
    rows = _rows(result, times)
    colors = _time_colors(len(rows))
    fig = Figure(figsize=(5.0 * len(quantities), 4.0), dpi=DPI)
    axes = np.atleast_1d(fig.subplots(1, len(quantities)))
    for ax, name in zip(axes, quantities, strict=True):
        V = _values(result, name)
        for c, r in zip(colors, rows, strict=True):
            s, v = _profile(tri, V[r], y)
            ax.plot(s, v, color=c, lw=1.6, label=rf"$t$ = {float(result.t[r]):.3g}")
        ax.set_xlabel(f"${_AXES[a]}$ (on ${_AXES[b]}$ = {y:.3g})")
        ax.set_ylabel(_with_gap(result, MAP_QUANTITIES[name]))
        ax.grid(True, lw=0.4, alpha=0.5)
        ax.legend(frameon=False, fontsize=8)
    title = fig.suptitle(f"Along the contact face: {_params(result)}", fontsize=10)
    place_grid(fig, [list(axes)], (4.1, 3.0), suptitle=title)
    return _finish(fig, path)
