"""Figures of a run: contact profiles (paper Figs 3-6, 9), displacement maps (Figs 7-8),
the deformed mesh and time histories.

Every function builds a :class:`matplotlib.figure.Figure` directly (no ``pyplot``, so
no global backend or figure registry is touched and nothing needs a display), returns
it, and saves it when ``path`` is given (format from the suffix, PNG by default, at
150 dpi). Titles state the data: ``mu``, ``kappa`` and ``v*`` of each contact part; the
penetration is labelled ``u_nu - gap - w`` where a gap exists.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib import colormaps
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator
from numpy.typing import NDArray

from .layout import place_grid

if TYPE_CHECKING:
    from ..simulate.loop import Result

__all__ = [
    "QUANTITIES",
    "compare_profiles",
    "plot_contact_profiles",
    "plot_time_history",
]

DPI = 150

#: Quantities along Gamma_C that :func:`compare_profiles` plots, with their labels.
QUANTITIES: dict[str, str] = {
    "wear": r"wear $w$",
    "u_nu": r"normal displacement $u_\nu$",
    "penetration": r"penetration $u_\nu - w$",
    "p_rigid": r"rigid-layer pressure $\lambda$",
    "p_soft": r"soft-layer pressure $p(u_\nu - w)$",
}

_ABSCISSA_LABEL = {
    "x": r"$x_1$",
    "y": r"$x_2$",
    "s": r"arc length $s$ along $\Gamma_C$",
}

# ---------------------------------------------------------------------------- helpers


def _cap(text: str) -> str:
    return text[:1].upper() + text[1:]


def _fmt_num(v: float) -> str:
    return f"{v:.3g}"


def _fmt_nodal(v: NDArray[np.float64]) -> str:
    v = np.asarray(v, dtype=float)
    if v.size == 0:
        return "-"
    lo, hi = float(v.min()), float(v.max())
    if hi - lo <= 1e-12 * max(abs(hi), 1.0):
        return _fmt_num(hi)
    return f"{_fmt_num(lo)}..{_fmt_num(hi)}"


def _fmt_vstar(velocity: Any) -> str | None:
    desc = velocity.describe()
    if isinstance(desc, list) and len(desc) in (2, 3) and all(isinstance(c, float) for c in desc):
        return "(" + ", ".join(f"{c:g}" for c in desc) + ")"
    return None


def _params(result: Result, vstar: bool = True) -> str:
    """``mu = .., kappa = .., v* = ..`` in mathtext, for titles and legends; with
    several contact parts, one line ``part: mu = .., ...`` per part, each with its own
    data."""
    pr = result.problem
    nodal, part = pr.nodal, np.asarray(pr.contact.part)
    lines = []
    for i, pc in enumerate(pr.parts):
        sel = part == i
        items = [
            rf"$\mu$ = {_fmt_nodal(nodal['mu'][sel])}",
            rf"$\kappa$ = {_fmt_nodal(nodal['kappa'][sel])}",
        ]
        vs = _fmt_vstar(pc.velocity) if vstar else None
        if vs is not None:
            items.append(rf"$\mathbf{{v}}^*$ = {vs}")
        lines.append(", ".join(items) if len(pr.parts) == 1 else f"{pc.part}: {', '.join(items)}")
    return "\n".join(lines)


def _with_gap(result: Result, label: str) -> str:
    """``label`` with the penetration written ``u_nu - gap - w`` where a gap exists."""
    if np.any(np.asarray(result.problem.nodal["gap"]) != 0):
        return label.replace(r"u_\nu - w", r"u_\nu - \mathrm{gap} - w")
    return label


def _finish(fig: Figure, path: str | os.PathLike[str] | None) -> Figure:
    if path is not None:
        p = Path(path)
        p.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(p, dpi=DPI)
    return fig


def _abscissa(
    result: Result, abscissa: str = "auto", sel: NDArray[np.bool_] | None = None
) -> tuple[NDArray[np.float64], str]:
    """Coordinate along Gamma_C (the nodes ``sel``): ``x`` (``x_1``) on a horizontal
    straight contact part, ``y`` on a vertical one, the arc length ``s`` otherwise (or
    as asked)."""
    sel = np.ones(len(result.contact_s), dtype=bool) if sel is None else sel
    pts = np.asarray(result.contact_points, dtype=float)[sel]
    if abscissa == "auto":
        size = float(np.ptp(np.asarray(result.points), axis=0).max()) or 1.0
        tol = 1e-9 * size
        if np.ptp(pts[:, 1]) <= tol:
            abscissa = "x"
        elif np.ptp(pts[:, 0]) <= tol:
            abscissa = "y"
        else:
            abscissa = "s"
    if abscissa == "x":
        return pts[:, 0], abscissa
    if abscissa == "y":
        return pts[:, 1], abscissa
    if abscissa == "s":
        return np.asarray(result.contact_s, dtype=float)[sel], abscissa
    raise ValueError(f"abscissa must be 'auto', 'x', 'y' or 's', got {abscissa!r}")


def _extent(result: Result, which: str, part: str = "contact") -> tuple[float, float]:
    """Range of the abscissa over the whole contact part (including endpoints on Gamma_D,
    where there is no contact node), with a small margin."""
    mesh = result.problem.mesh
    if which == "s":
        lo, hi = 0.0, float(np.max(result.contact_s, initial=0.0))
        ce = mesh.part_edges(part)
        if len(ce):  # a chain may end on Gamma_D, beyond its last contact node
            lengths = np.linalg.norm(mesh.points[ce[:, 1]] - mesh.points[ce[:, 0]], axis=1)
            hi = max(hi, *(float(lengths[ch].sum()) for ch in _edge_chains(ce)))
    else:
        k = 0 if which == "x" else 1
        v = mesh.points[np.unique(mesh.part_edges(part)), k]
        if v.size == 0:
            v = np.asarray(result.contact_points)[:, k]
        lo, hi = float(v.min()), float(v.max())
    pad = 0.01 * (hi - lo if hi > lo else 1.0)
    return lo - pad, hi + pad


def _chain_breaks(result: Result) -> NDArray[np.int64]:
    """Indices where a new chain of contact edges starts (arc length restarts)."""
    s = np.asarray(result.contact_s, dtype=float)
    return np.flatnonzero(np.diff(s) <= 0) + 1


def _broken(
    x: NDArray[np.float64], y: NDArray[np.float64], breaks: NDArray[np.int64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Insert NaN between chains so that lines do not join separate pieces of Gamma_C."""
    if breaks.size == 0:
        return x, y
    return np.insert(x.astype(float), breaks, np.nan), np.insert(y.astype(float), breaks, np.nan)


def _contact_quantity(result: Result, name: str) -> NDArray[np.float64]:
    if name not in QUANTITIES:
        raise ValueError(f"unknown quantity {name!r}; expected one of {list(QUANTITIES)}")
    return np.asarray(getattr(result, name), dtype=float)


def _time_colors(k: int) -> list[Any]:
    cmap = colormaps["viridis"]
    return [cmap(v) for v in np.linspace(0.8, 0.0, k)] if k > 1 else [cmap(0.3)]


def _marker_kw(m: int) -> dict[str, Any]:
    return {"marker": "o", "markersize": 2.5} if m <= 80 else {}


def _default_times(result: Result) -> list[float]:
    """``T/4, T/2, 3T/4, T`` if they are levels, else four evenly spaced levels."""
    t = np.asarray(result.t)
    T = float(t[-1])
    want = [0.25 * T, 0.5 * T, 0.75 * T, T]
    try:
        [result.level(x) for x in want]
        return want
    except ValueError:
        idx = np.unique(np.linspace(0, len(t) - 1, 5).round().astype(int)[1:])
        return [float(t[i]) for i in idx]


# ---------------------------------------------------------------------------- profiles


def _edge_chains(edges: NDArray[np.int64]) -> list[NDArray[np.int64]]:
    """Split directed edges (a, b) into chains of consecutive edges; returns the edge
    indices of every chain in order (a closed loop gives one chain)."""
    nxt = {int(a): k for k, a in enumerate(edges[:, 0])}
    ends = {int(b) for b in edges[:, 1]}
    seen = np.zeros(len(edges), dtype=bool)
    starts = [k for k, a in enumerate(edges[:, 0]) if int(a) not in ends]
    chains: list[NDArray[np.int64]] = []
    for first in [*starts, *range(len(edges))]:
        if seen[first]:
            continue
        chain, k = [], first
        while k is not None and not seen[k]:
            seen[k] = True
            chain.append(k)
            k = nxt.get(int(edges[k, 1]))
        chains.append(np.asarray(chain, dtype=np.int64))
    return chains


def plot_contact_profiles(
    result: Result,
    times: Sequence[float] | None = None,
    path: str | os.PathLike[str] | None = None,
    title: str | None = None,
    *,
    abscissa: str = "auto",
) -> Figure:
    """Wear ``w`` and penetration ``u_nu - gap - w`` along Gamma_C at some times (paper
    Figs 3-5).

    Parameters
    ----------
    result : Result
        The run.
    times : sequence of float, optional
        Times to show; each must be a time level (``result.level(t)``). Default:
        ``T/4, T/2, 3T/4, T`` (or four evenly spaced levels if those are not levels).
    path : path, optional
        Save the figure there.
    title : str, optional
        Figure title; default names the data (``mu``, ``kappa``, ``v*`` of each part).
    abscissa : {"auto", "x", "y", "s"}
        Horizontal coordinate: ``x_1``, ``x_2`` or the arc length ``s`` along Gamma_C;
        ``auto`` takes ``x_1`` (``x_2``) on a horizontal (vertical) straight contact
        part and ``s`` otherwise.

    Returns
    -------
    Figure
        Two panels side by side, one line per time; one row of panels per contact part,
        each against its own coordinate.
    """
    times = _default_times(result) if times is None else list(times)
    levels = [result.level(t) for t in times]
    cb = result.problem.contact
    names = cb.part_names
    fig = Figure(figsize=(10.0, 3.9 * len(names)), layout="constrained")
    axes = np.asarray(fig.subplots(len(names), 2, squeeze=False))
    colors = _time_colors(len(levels))
    for i, part in enumerate(names):
        sel = np.asarray(cb.part == i)
        x, which = _abscissa(result, abscissa, sel)
        order = np.argsort(x, kind="stable") if which != "s" else np.arange(len(x))
        s_part = np.asarray(result.contact_s, dtype=float)[sel]
        breaks = np.flatnonzero(np.diff(s_part) <= 0) + 1 if which == "s" else np.zeros(0, int)
        mk = _marker_kw(len(x))
        where = r"$\Gamma_C$" if len(names) == 1 else f"{part}"
        for ax, name in zip(axes[i], ("wear", "penetration"), strict=True):
            data = _contact_quantity(result, name)[:, sel]
            for lv, c in zip(levels, colors, strict=True):
                xs, ys = _broken(x[order], data[lv][order], breaks)
                ax.plot(xs, ys, color=c, lw=1.6, label=f"$t$ = {result.t[lv]:g}", **mk)
            ax.set_xlabel(_ABSCISSA_LABEL[which])
            ax.set_ylabel(_with_gap(result, QUANTITIES[name]))
            ax.set_title(_cap(_with_gap(result, QUANTITIES[name])) + f" on {where}")
            ax.grid(True, lw=0.4, alpha=0.5)
            ax.set_xlim(*_extent(result, which, part))
    axes[0, 0].legend(loc="best", frameon=False)
    fig.suptitle(title if title is not None else f"Wear and penetration: {_params(result)}")
    return _finish(fig, path)


def compare_profiles(
    results: Mapping[str, Result],
    time: float,
    quantity: str | Sequence[str] = "wear",
    path: str | os.PathLike[str] | None = None,
    *,
    style: str = "line",
    abscissa: str = "auto",
    title: str | None = None,
) -> Figure:
    """Overlay quantities along Gamma_C at one time for several runs (paper Figs 6 and 9).

    Parameters
    ----------
    results : mapping of str to Result
        Runs by legend label.
    time : float
        A time level of every run.
    quantity : str or sequence of str
        One or more of ``wear``, ``u_nu``, ``penetration``, ``p_rigid``, ``p_soft``. With
        several, each run gets one colour and each quantity one marker/line style
        (Fig 9 shows ``("wear", "u_nu")`` for two meshes).
    path : path, optional
        Save the figure there.
    style : {"line", "scatter"}
        Lines with small markers, or markers only (Fig 9).
    abscissa : {"auto", "x", "y", "s"}
        As in :func:`plot_contact_profiles`; ``auto`` is decided on the first run.
    title : str, optional
        Default: the quantity, the time and the data shared by all runs.

    Returns
    -------
    Figure
    """
    if not results:
        raise ValueError("compare_profiles: no results given")
    if style not in ("line", "scatter"):
        raise ValueError(f"style must be 'line' or 'scatter', got {style!r}")
    quantities = [quantity] if isinstance(quantity, str) else list(quantity)
    for q in quantities:
        _contact_quantity(next(iter(results.values())), q)  # validates the names
    first = next(iter(results.values()))
    _x0, which = _abscissa(first, abscissa)
    params = {label: _params(r) for label, r in results.items()}
    common = len(set(params.values())) == 1
    fig = Figure(figsize=(7.0, 4.2), layout="constrained")
    ax = fig.subplots()
    markers = ["o", "s", "^", "D", "v"]
    linestyles = ["-", "--", ":", "-.", (0, (5, 1, 1, 1))]
    colors = colormaps["tab10"].colors  # type: ignore[attr-defined]
    for i, (label, res) in enumerate(results.items()):
        lv = res.level(time)
        x, _w = _abscissa(res, which)
        order = np.argsort(x, kind="stable") if which != "s" else np.arange(len(x))
        breaks = _chain_breaks(res) if which == "s" else np.zeros(0, np.int64)
        for j, q in enumerate(quantities):
            y = _contact_quantity(res, q)[lv]
            name = label if len(quantities) == 1 else f"{label}, {QUANTITIES[q]}"
            if not common:
                name += f" ({_params(res, vstar=False)})"
            # runs differ by colour, marker and (decreasing) size, so that coinciding
            # profiles stay visible; quantities by line style / marker fill
            c = colors[i % len(colors)]
            mk = markers[i % len(markers)]
            shrink = 0.72**i
            if style == "scatter":
                ax.scatter(
                    x,
                    y,
                    s=max(36.0 * shrink, 6.0),
                    marker=mk,
                    lw=1.0,
                    label=name,
                    edgecolors=c,
                    facecolors=c if j % 2 == 0 else "none",
                    zorder=2 + i,
                )
            else:
                xs, ys = _broken(x[order], y[order], breaks)
                kw: dict[str, Any] = {}
                if len(x) <= 80:
                    kw = {
                        "marker": mk,
                        "markersize": max(5.0 * shrink, 2.0),
                        "markerfacecolor": c if j % 2 == 0 else "white",
                    }
                ax.plot(
                    xs,
                    ys,
                    color=c,
                    lw=max(2.2 * shrink, 0.9),
                    ls=linestyles[j % len(linestyles)],
                    label=name,
                    zorder=2 + i,
                    **kw,
                )
    ax.set_xlabel(_ABSCISSA_LABEL[which])
    ax.set_ylabel(_with_gap(first, QUANTITIES[quantities[0]]) if len(quantities) == 1 else "value")
    ax.grid(True, lw=0.4, alpha=0.5)
    ax.set_xlim(*_extent(first, which))
    ax.legend(loc="best", frameon=False, fontsize="small")
    if title is None:
        what = (
            QUANTITIES[quantities[0]]
            if len(quantities) == 1
            else " and ".join(QUANTITIES[q] for q in quantities)
        )
        title = f"{_cap(_with_gap(first, what))} at $t$ = {time:g}"
        if common:
            title += f": {params[next(iter(results))]}"
    ax.set_title(title)
    return _finish(fig, path)


# ---------------------------------------------------------------------------- mesh maps


def plot_time_history(
    result: Result,
    path: str | os.PathLike[str] | None = None,
) -> Figure:
    """Maximal wear and penetration along Gamma_C against time, and solver iterations.

    Parameters
    ----------
    result : Result
        The run.
    path : path, optional
        Save the figure there.

    Returns
    -------
    Figure
        Left axis: ``max w``, ``max (u_nu - gap - w)`` and ``max u_nu`` over the contact
        nodes; right axis: iterations per level (bars).
    """
    t = np.asarray(result.t)
    fig = Figure(figsize=(7.5, 4.2), dpi=DPI)
    ax = fig.subplots()
    ax2 = ax.twinx()
    it = np.asarray(result.iterations)
    width = np.diff(t).min(initial=1.0) * 0.8 if len(t) > 1 else 1.0
    # the bars as one collection: a Rectangle artist per level took seconds at 1500 levels
    x0, x1 = t - width / 2, t + width / 2
    zero = np.zeros_like(t)
    bars = np.stack([np.c_[x0, zero], np.c_[x0, it], np.c_[x1, it], np.c_[x1, zero]], axis=1)
    ax2.add_collection(
        PolyCollection(
            list(bars), facecolors="0.6", edgecolors="none", alpha=0.35, label="solver iterations"
        )
    )
    ax2.set_ylabel("solver iterations per level")
    ax2.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax2.set_ylim(0, max(int(it.max(initial=1)), 1) * 2.2)
    ax.set_zorder(ax2.get_zorder() + 1)
    ax.patch.set_visible(False)
    ax.plot(t, np.asarray(result.wear).max(axis=1), color="#b2182b", lw=1.8, label=r"max $w$")
    ax.plot(
        t,
        np.asarray(result.penetration).max(axis=1),
        color="#2166ac",
        lw=1.8,
        label=_with_gap(result, r"max $(u_\nu - w)$"),
    )
    ax.plot(
        t, np.asarray(result.u_nu).max(axis=1), color="0.2", lw=1.2, ls="--", label=r"max $u_\nu$"
    )
    ax.set_xlabel(r"time $t$")
    ax.set_ylabel(r"max over $\Gamma_C$")
    ax.grid(True, lw=0.4, alpha=0.5)
    ax.set_xlim(t[0] - 0.6 * width, t[-1] + 0.6 * width)
    ax.set_ylim(bottom=0)
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = ax2.get_legend_handles_labels()
    legend = fig.legend(h1 + h2, l1 + l2, loc="lower center", ncols=4, frameon=False)
    # a title at a fixed height: no search for tick labels above the panel
    ax.set_title(f"Time history: {_params(result)}", y=1.0)
    place_grid(fig, [[(ax, ax2)]], (6.2, 2.9), legend=legend)
    return _finish(fig, path)
