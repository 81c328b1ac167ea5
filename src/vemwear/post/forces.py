"""Force resultants per boundary part over time: a figure and the summary's table.

The rows of :attr:`vemwear.simulate.Result.forces` are the force of the layer of each
contact part on the body and the reaction of each clamped or prescribed part
(:attr:`~vemwear.simulate.Result.force_parts`). For a contact part the normal force is
the resultant's component against the mean outward normal of the part, the
tangential force the rest (the friction the sliding foundation exerts).
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..simulate.loop import Result

__all__ = ["force_table", "part_directions", "plot_forces"]


def part_directions(result: Result) -> dict[str, NDArray[np.float64]]:
    """The mean outward unit normal of every contact part (weighted by the nodal weights)."""
    cb = result.problem.contact
    out = {}
    for i, name in enumerate(cb.part_names):
        sel = cb.part == i
        n = (cb.weights[sel, None] * cb.normals[sel]).sum(axis=0)
        out[name] = n / max(float(np.linalg.norm(n)), 1e-300)
    return out


def _tangent(result: Result, name: str, n: NDArray[np.float64]) -> NDArray[np.float64] | None:
    """The direction of the tangential force of a contact part: in 2D the normal turned
    by 90 degrees; in 3D the mean (weighted) nodal tangent, the direction of the
    foundation's tangential velocity, when the part's friction rows keep one direction;
    None where they do not (a v* that turns or differs from node to node, as a disc
    turning under the part): the tangential force is then given by its magnitude."""
    if len(n) == 2:
        return np.array([-n[1], n[0]])
    cb = result.problem.contact
    sel = cb.part == cb.part_names.index(name)
    if cb.tangents2 is not None:
        return None
    tau = (cb.weights[sel, None] * cb.tangents[sel]).sum(axis=0)
    length = float(np.linalg.norm(tau))
    if length < (1.0 - 1e-9) * float(cb.weights[sel].sum()):  # the tangents differ
        return None
    return np.asarray(tau / max(length, 1e-300))


def _tangential(F: NDArray[np.float64], n: NDArray[np.float64], tau: Any) -> Any:
    """The tangential force of resultants ``F`` (..., d): along ``tau``, or the length
    of the part normal to ``n`` where ``tau`` is None."""
    if tau is not None:
        return F @ tau
    return np.linalg.norm(F - np.multiply.outer(F @ n, n), axis=-1)


def force_table(result: Result) -> list[dict[str, Any]]:
    """Per part, at the last kept level: the resultant, and for contact parts its
    normal (compressive positive) and tangential components; for all parts the largest
    magnitude over time."""
    F = result.forces
    if F is None:
        return []
    normals = part_directions(result)
    rows = []
    for j, (name, kind) in enumerate(result.force_parts):
        last = F[-1, j]
        row: dict[str, Any] = {
            "part": name,
            "kind": kind,
            "force": last.tolist(),
            "max_magnitude": float(np.linalg.norm(F[:, j], axis=1).max(initial=0.0)),
        }
        if kind == "contact":
            n = normals[name]
            row["normal"] = float(-last @ n)
            row["tangential"] = float(_tangential(last, n, _tangent(result, name, n)))
        rows.append(row)
    return rows


def plot_forces(result: Result, path: str | os.PathLike[str] | None = None) -> Figure:
    """Force resultants against time: per contact part the normal and tangential force of
    its layer, per clamped or prescribed part the two components of its reaction."""
    from .layout import place_grid
    from .plots import DPI

    d = result.problem.dim
    F = np.asarray(result.forces) if result.forces is not None else np.zeros((len(result.t), 0, d))
    t = np.asarray(result.t)
    normals = part_directions(result)
    from matplotlib.figure import Figure  # here: the table of forces needs no matplotlib

    fig = Figure(figsize=(10.0, 4.0), dpi=DPI)
    ax_c, ax_r = fig.subplots(1, 2)
    for j, (name, kind) in enumerate(result.force_parts):
        if kind == "contact":
            n = normals[name]
            ax_c.plot(t, -F[:, j] @ n, lw=1.8, label=f"{name}: normal")
            ax_c.plot(
                t,
                _tangential(F[:, j], n, _tangent(result, name, n)),
                lw=1.4,
                ls="--",
                label=f"{name}: tangential",
            )
        else:
            ax_r.plot(t, F[:, j, 0], lw=1.6, label=f"{name}: $R_x$")
            ax_r.plot(t, F[:, j, 1], lw=1.6, ls="--", label=f"{name}: $R_y$")
            if d == 3:
                ax_r.plot(t, F[:, j, 2], lw=1.6, ls=":", label=f"{name}: $R_z$")
    # titles at a fixed height: no search for tick labels above the panels
    ax_c.set_title("contact parts: force of the layer on the body", y=1.0)
    ax_r.set_title("clamped and prescribed parts: reactions", y=1.0)
    for ax in (ax_c, ax_r):
        ax.set_xlabel(r"time $t$")
        ax.set_ylabel("force per unit depth" if d == 2 else "force")
        ax.grid(True, lw=0.4, alpha=0.5)
        if ax.lines:
            ax.legend(loc="best", frameon=False, fontsize=8)
    place_grid(fig, [[ax_c, ax_r]], (4.2, 3.1))
    if path is not None:
        fig.savefig(path, dpi=DPI)
    return fig
