"""Maps of a run over the mesh: the displacement (paper Figs 7-8) and the deformed mesh
with the contact boundary and the rigid layer.

As in :mod:`vemwear.post.plots`, every function builds a
:class:`matplotlib.figure.Figure` directly, returns it, and saves it when ``path`` is
given.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.tri import Triangulation
from numpy.typing import NDArray

from ..mesh.polymesh import Mesh
from .plots import _edge_chains, _finish, _params

if TYPE_CHECKING:
    from ..simulate.loop import Result

__all__ = ["plot_deformed", "plot_displacement"]


def _fan_triangulation(
    mesh: Mesh, xy: NDArray[np.float64] | None = None
) -> tuple[Triangulation, Callable[[NDArray[np.float64]], NDArray[np.float64]]]:
    """Triangulate every cell: triangles as they are, other polygons as a fan around the
    vertex average. Returns the Triangulation and a function extending vertex values
    to the added centre points (by the vertex average, the value of ``Pi u`` there)."""
    pts = mesh.points if xy is None else xy
    tris: list[NDArray[np.int64]] = []
    centre_cells: list[NDArray[np.int64]] = []  # (m, n) vertex ids of fanned cells
    next_id = mesh.n_points
    for n, (_ids, verts) in sorted(mesh.groups.items()):
        if n == 3:
            tris.append(verts)
            continue
        m = len(verts)
        centre = next_id + np.arange(m)
        next_id += m
        t = np.stack(
            [verts, np.roll(verts, -1, axis=1), np.broadcast_to(centre[:, None], (m, n))], axis=-1
        )
        tris.append(t.reshape(-1, 3))
        centre_cells.append(verts)

    def extend(values: NDArray[np.float64]) -> NDArray[np.float64]:
        extra = [values[v].mean(axis=1) for v in centre_cells]
        return np.concatenate([values, *extra]) if extra else values

    allpts = extend(pts)
    tri = Triangulation(allpts[:, 0], allpts[:, 1], np.concatenate(tris))
    return tri, extend


def _cell_outlines(ax: Axes, mesh: Mesh, xy: NDArray[np.float64], **kw: Any) -> None:
    """Draw the cell edges (each edge once) as one LineCollection."""
    e = mesh.edges
    segments = list(np.stack([xy[e[:, 0]], xy[e[:, 1]]], axis=1))
    ax.add_collection(LineCollection(segments, **kw))


def _edge_width(mesh: Mesh) -> float:
    return float(np.clip(12.0 / np.sqrt(max(mesh.n_cells, 1)), 0.08, 0.6))


def _mesh_of(result: Result) -> Mesh:
    return result.problem.mesh


def plot_displacement(
    result: Result,
    level: int = -1,
    path: str | os.PathLike[str] | None = None,
    component: int | str | None = None,
    *,
    cmap: str = "viridis",
    edges: bool | None = None,
) -> Figure:
    """Colour maps of the displacement components on the polygonal mesh (paper Figs 7-8).

    Values are the vertex values (the VEM degrees of freedom), shaded linearly
    (Gouraud) over a fan triangulation of every polygon around its vertex average,
    where the value is the vertex average (the projection ``Pi u`` there).

    Parameters
    ----------
    result : Result
        The run.
    level : int
        Time level index (negative counts from the end); use ``result.level(t)`` for a
        time.
    path : path, optional
        Save the figure there.
    component : {None, 0, 1, "magnitude"}
        Both components ``u_1``, ``u_2`` side by side (default), one of them, or
        ``|u|``.
    cmap : str
        Matplotlib colormap.
    edges : bool, optional
        Draw the cell edges; default for meshes of at most 4096 cells.

    Returns
    -------
    Figure
    """
    mesh = _mesh_of(result)
    lv = int(level) % len(result.t)
    u = np.asarray(result.displacement(lv))
    if component is None:
        comps: list[int | str] = [0, 1]
    elif component in (0, 1, "magnitude"):
        comps = [component]
    else:
        raise ValueError(f"component must be None, 0, 1 or 'magnitude', got {component!r}")
    tri, extend = _fan_triangulation(mesh)
    lo, hi = mesh.points.min(axis=0), mesh.points.max(axis=0)
    ext = np.maximum(hi - lo, 1e-300)
    aspect = float(ext[1] / ext[0])
    pw = 5.6 if len(comps) > 1 else 6.6  # inches per panel, of which ~1.5 go to labels/bar
    fig = Figure(
        figsize=(pw * len(comps), min((pw - 1.5) * aspect, 7.0) + 1.2), layout="constrained"
    )
    axes = np.atleast_1d(fig.subplots(1, len(comps)))
    show_edges = mesh.n_cells <= 4096 if edges is None else edges
    labels = {0: r"$u_{h,1}$", 1: r"$u_{h,2}$", "magnitude": r"$|\mathbf{u}_h|$"}
    for ax, c in zip(axes, comps, strict=True):
        vals = np.linalg.norm(u, axis=1) if c == "magnitude" else u[:, int(c)]
        tpc = ax.tripcolor(tri, extend(vals), shading="gouraud", cmap=cmap, rasterized=True)
        if show_edges:
            _cell_outlines(
                ax, mesh, mesh.points, colors="k", linewidths=_edge_width(mesh), alpha=0.35
            )
        ax.set_aspect("equal")
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_xlabel(r"$x_1$")
        ax.set_ylabel(r"$x_2$")
        ax.set_title(labels[c])
        cax = ax.inset_axes((1.03, 0.0, 0.035, 1.0))  # exactly as tall as the plot
        cb = fig.colorbar(tpc, cax=cax)
        cb.formatter.set_powerlimits((-2, 3))  # type: ignore[attr-defined]
        cb.update_ticks()
    counts = ", ".join(f"{len(i)} {_ngon(n)}" for n, (i, _v) in sorted(mesh.groups.items()))
    fig.suptitle(f"Displacement at $t$ = {result.t[lv]:g} ({counts}): {_params(result)}")
    return _finish(fig, path)


def _ngon(n: int) -> str:
    return {3: "triangles", 4: "quads", 5: "pentagons", 6: "hexagons"}.get(n, f"{n}-gons")


def _polyline(segments: NDArray[np.float64]) -> NDArray[np.float64]:
    """(k, 2, 2) consecutive segments -> (k + 1, 2) polyline."""
    return np.concatenate([segments[:, 0], segments[-1:, 1]])


def _rigid_layer(
    result: Result, edges: NDArray[np.int64], scale: float, band: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Segments ``x + scale g nu`` over the contact edges (the magnified constraint
    ``u_nu = g``) and the same segments moved ``band`` further out, shape (E, 2, 2).
    Contact nodes use their nodal normal and g; an endpoint on Gamma_D (not a contact
    node) takes the edge normal and the g of the other endpoint."""
    P = result.problem.mesh.points
    g = np.asarray(result.problem.nodal["g"])
    nu_nodes = np.asarray(result.problem.contact.normals)
    where = np.full(len(P), -1, dtype=np.int64)
    cn = np.asarray(result.contact_nodes)
    vert = cn < len(P)  # k = 2: the edge midpoints (ids >= n_points) are not vertices
    where[cn[vert]] = np.flatnonzero(vert)
    d = P[edges[:, 1]] - P[edges[:, 0]]
    nu_edge = np.column_stack([d[:, 1], -d[:, 0]]) / np.linalg.norm(d, axis=1)[:, None]
    idx = where[edges]  # (E, 2)
    other = idx[:, ::-1]
    gi = np.where(idx >= 0, g[np.maximum(idx, 0)], g[np.maximum(other, 0)])
    nui = np.where((idx >= 0)[..., None], nu_nodes[np.maximum(idx, 0)], nu_edge[:, None, :])
    rigid = P[edges] + scale * gi[..., None] * nui
    return rigid, rigid + band * nui


def plot_deformed(
    result: Result,
    level: int = -1,
    path: str | os.PathLike[str] | None = None,
    scale: float | None = None,
    *,
    show_rigid: bool | None = None,
) -> Figure:
    """The mesh before (light grey) and after deformation, with Gamma_C marked.

    Parameters
    ----------
    result : Result
        The run.
    level : int
        Time level index (negative counts from the end).
    path : path, optional
        Save the figure there.
    scale : float, optional
        Displacement magnification; default: the largest displacement drawn as 10% of
        the domain size (1 if the displacement vanishes).
    show_rigid : bool, optional
        Draw where the constraint ``u_nu = g`` (the rigid part of the foundation) lies
        in the magnified picture, i.e. at ``x + scale * g * nu`` along Gamma_C. Default:
        if that line lies within 30% of the domain size.

    Returns
    -------
    Figure
    """
    mesh = _mesh_of(result)
    lv = int(level) % len(result.t)
    u = np.asarray(result.displacement(lv))
    P = mesh.points
    size = float(np.ptp(P, axis=0).max()) or 1.0
    umax = float(np.linalg.norm(u, axis=1).max(initial=0.0))
    if scale is None:
        scale = 0.1 * size / umax if umax > 0 else 1.0
    Q = P + scale * u
    lo = np.minimum(P.min(axis=0), Q.min(axis=0))
    hi = np.maximum(P.max(axis=0), Q.max(axis=0))
    aspect = float((hi - lo)[1] / max((hi - lo)[0], 1e-300))
    fig = Figure(figsize=(8.0, min(8.0 * aspect, 8.0) + 1.2), layout="constrained")
    ax = fig.subplots()
    lw = _edge_width(mesh) * 1.6
    if mesh.n_cells <= 5000:  # finer meshes: outlines only, inner edges would fill the area
        _cell_outlines(ax, mesh, P, colors="0.72", linewidths=lw)
        _cell_outlines(ax, mesh, Q, colors="#1f4e79", linewidths=lw)
    be = mesh.boundary_edges
    for X, color in ((P, "0.6"), (Q, "#1f4e79")):
        ax.add_collection(LineCollection(list(X[be]), colors=color, linewidths=1.2))
    ce = mesh.part_edges("contact")
    chains = _edge_chains(ce)
    styles: tuple[tuple[NDArray[np.float64], dict[str, Any]], ...] = (
        (P, {"color": "#f4a582", "lw": 2.0, "ls": "--"}),
        (Q, {"color": "#b2182b", "lw": 2.2}),
    )
    for X, kw in styles:
        for ch in chains:
            line = _polyline(X[ce[ch]])
            ax.plot(line[:, 0], line[:, 1], solid_capstyle="butt", **kw)
    handles = [
        Line2D([], [], color="0.6", lw=1.2, label="reference"),
        Line2D([], [], color="#1f4e79", lw=1.2, label="deformed"),
        Line2D([], [], color="#b2182b", lw=2.2, label=r"$\Gamma_C$ deformed"),
        Line2D([], [], color="#f4a582", lw=2.0, ls="--", label=r"$\Gamma_C$ reference"),
    ]
    g = np.asarray(result.problem.nodal["g"])
    if show_rigid is None:
        show_rigid = bool(scale * g.max(initial=0.0) <= 0.3 * size)
    if show_rigid and len(ce):
        rigid, outer = _rigid_layer(result, ce, scale, 0.025 * size)
        for ch in chains:
            r, o = _polyline(rigid[ch]), _polyline(outer[ch])
            ax.plot(r[:, 0], r[:, 1], color="k", lw=1.0, ls=(0, (4, 2)))
            ax.add_collection(
                PolyCollection(
                    [np.concatenate([r, o[::-1]])], facecolors="0.55", alpha=0.35, linewidths=0
                )
            )
        handles.append(
            Line2D(
                [],
                [],
                color="k",
                lw=1.0,
                ls=(0, (4, 2)),
                label=r"rigid layer $u_\nu = g$ (magnified)",
            )
        )
        lo = np.minimum(lo, outer.reshape(-1, 2).min(axis=0))
        hi = np.maximum(hi, outer.reshape(-1, 2).max(axis=0))
    pad = 0.03 * size
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel(r"$x_1$")
    ax.set_ylabel(r"$x_2$")
    fig.legend(
        handles=handles, loc="outside lower center", ncols=3, fontsize="small", frameon=False
    )
    ax.set_title(
        f"Deformed mesh at $t$ = {result.t[lv]:g}: {_params(result)}\n"
        f"displacement magnified × {scale:.3g} (max $|\\mathbf{{u}}_h|$ = {umax:.3g})",
        fontsize="medium",
    )
    return _finish(fig, path)
