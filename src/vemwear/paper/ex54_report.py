"""Example 5.4's figures (paper Figs. 7-9, the Voronoi mesh) and report sections.

Figs. 7 and 8 show u_1 and u_2 at t = 1 on the squares and on the Voronoi mesh with
common colour limits; Fig. 9 the contact profiles u_nu and w of both meshes. The
report sections read the numbers of :func:`vemwear.paper.ex54` 's analysis from the
run's ``details``.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..post.results import jsonable
from ..simulate import Result
from . import ExampleRun
from .markdown import cell, links, num, table
from .spec import Column, Context

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "MESHES",
    "contact_section",
    "displacement_figure",
    "displacement_section",
    "fig9",
    "info_column",
    "paper_section",
    "quality_section",
    "setup",
    "study_section",
    "timings_section",
    "voronoi_mesh_figure",
    "write_json",
]

#: Labels of the two meshes (subdirectories of the output).
MESHES: dict[str, str] = {"squares": "squares", "voronoi": "Voronoi polygons"}


# ---------------------------------------------------------------------------- figures
def _colour_limits(results: Mapping[str, Result]) -> dict[int, list[float]]:
    us = [r.displacement(-1) for r in results.values()]
    return {
        c: [float(min(u[:, c].min() for u in us)), float(max(u[:, c].max() for u in us))]
        for c in (0, 1)
    }


def _set_limits(fig: Figure, limits: Mapping[int, Sequence[float]]) -> None:
    """Give the colour maps of ``plot_displacement``'s two panels the limits (u1, u2)."""
    mappables = [c for ax in fig.axes for c in ax.collections if c.get_array() is not None]
    if len(mappables) != 2:  # pragma: no cover - plot_displacement changed its layout
        raise RuntimeError(
            f"expected 2 colour maps in the displacement figure, found {len(mappables)}"
        )
    for c, m in enumerate(mappables):
        m.set_clim(*limits[c])


def displacement_figure(name: str, number: int) -> Callable[[Context, Path], None]:
    """Fig. 7 (squares) or 8 (Voronoi): u_1, u_2 at t = T, colour limits of both runs."""

    def write(ctx: Context, path: Path) -> None:
        from ..post import plot_displacement

        limits = _colour_limits(ctx.results)
        ctx.details["colour_limits"] = {"u1": limits[0], "u2": limits[1]}
        res = ctx.results[name]
        fig = plot_displacement(res, -1)
        _set_limits(fig, limits)
        mesh = res.problem.mesh
        what = (
            f"{mesh.n_cells} squares, h = {mesh.h / np.sqrt(2):.4g}"
            if name == "squares"
            else f"{mesh.n_cells} Voronoi polygons, h = {mesh.h:.3g}"
        )
        d = ctx.details
        fig.suptitle(
            f"{ctx.example.title} (paper Fig. {number}): displacement at $t$ = "
            f"{res.t[-1]:g} on {what}; $\\mu$ = {d['mu']:g}, $\\kappa$ = {d['kappa']:g}, "
            f"$k$ = 1/{len(res.t) - 1}"
        )
        fig.savefig(path, dpi=150)

    return write


def fig9(ctx: Context, path: Path) -> None:
    """Fig. 9: scatter of u_nu and w along Gamma_C at t = T for both meshes."""
    from ..post import compare_profiles

    labelled = {f"{r.problem.mesh.n_cells} {MESHES[k]}": r for k, r in ctx.results.items()}
    T = float(ctx.results["squares"].t[-1])
    compare_profiles(
        labelled,
        T,
        ("u_nu", "wear"),
        path,
        style="scatter",
        title=f"{ctx.example.title} (paper Fig. 9): $u_\\nu$ and $w$ on $\\Gamma_C$ at "
        f"$t$ = {T:g}; "
        f"$\\mu$ = {ctx.details['mu']:g}, $\\kappa$ = {ctx.details['kappa']:g}",
    )


def voronoi_mesh_figure(ctx: Context, path: Path) -> None:
    from ..mesh.plot import plot_mesh

    mesh, p = ctx.problems["voronoi"].mesh, ctx.params
    plot_mesh(
        mesh,
        path,
        quality=ctx.state["quality"],
        title=f"{ctx.example.title}: {p['n_cells']} Voronoi cells (seed {p['seed']}), "
        f"h = {mesh.h:.3g}",
    )


def write_json(ctx: Context, path: Path) -> None:
    ctx.timings["total"] = ctx.elapsed()
    path.write_text(json.dumps(jsonable(ctx.details), indent=2) + "\n", encoding="utf-8")


# ---------------------------------------------------------------------------- report
def setup(ctx: Context) -> str:
    steps = ctx.params["steps"]
    return (
        f"Data of Example 5.2 with mu = {ctx.details['mu']:g}, "
        f"kappa = {ctx.details['kappa']:g}, v* = (1, 0); "
        f"{steps} uniform time steps (k = 1/{steps}); solver `{ctx.solver.method}`; "
        f"wall time {ctx.elapsed():.2f} s."
    )


def info_column(key: str, header: str, fmt: str = "") -> Column:
    """A column of the table of meshes: ``details["meshes"][name][key]`` formatted."""
    return Column(header, lambda ctx, n, r: format(ctx.details["meshes"][n][key], fmt))


def contact_section(ctx: Context) -> list[str]:
    cmp = ctx.details["comparison"]
    rows = [
        [
            q,
            f"{v['max_reference']:.6g}",
            f"{v['max_other']:.6g}",
            f"{v['max_abs']:.3e}",
            f"{v['rel_max']:.3e}",
            f"{v['rel_l2']:.3e}",
        ]
        for q, v in (("wear w", cmp["wear"]), ("u_nu", cmp["u_nu"]))
    ]
    return [
        "## Contact boundary at t = 1 (paper Fig. 9)",
        "",
        "Voronoi values interpolated linearly in x_1 at the contact nodes of the square mesh "
        "(the clamped end x_1 = 0 counts as 0); relative to the squares' values; L2: the "
        "exact L2(Gamma_C) norm of the piecewise linear functions on the squares' contact "
        "edges.",
        "",
        *table(
            [
                "quantity",
                "max (squares)",
                "max (Voronoi)",
                "max abs. diff",
                "rel. max diff",
                "rel. L2 diff",
            ],
            rows,
        ),
        "",
    ]


def displacement_section(ctx: Context) -> list[str]:
    disp = ctx.details["comparison"].get("displacement")
    if disp is None:
        return []
    pr = disp["probes"]
    comp = [
        [
            cell("|u|") if c == "vector" else c,
            f"{pr[c]['max_reference']:.4e}",
            f"{pr[c]['max_abs']:.3e}",
            f"{pr[c]['rel_max']:.3e}",
        ]
        for c in ("u1", "u2", "vector")
    ]

    def vec(v: Sequence[float], fmt: str) -> str:
        return "(" + ", ".join(format(c, fmt) for c in v) + ")"

    shared = [
        [
            vec(s["x"], ".6g"),
            vec(s["u_reference"], ".6e"),
            vec(s["u_other"], ".6e"),
            f"{s['diff']:.3e}",
        ]
        for s in disp["shared"]
    ]
    return [
        "## Displacement at t = 1 (paper Figs. 7 and 8)",
        "",
        f"Pi u of the containing cell at {pr['n']} probe points (a cell-centred 16 x 8 grid), "
        "squares against Voronoi:",
        "",
        *table(["component", "max abs. (squares)", "max abs. diff", "rel. max diff"], comp),
        "",
        "Root-mean-square relative difference of the vector over the probes: "
        f"{pr['vector_rms']:.3e}.",
        "",
        "Vertices both meshes share (the domain corners and boundary points at the same "
        "coordinates):",
        "",
        *table(["x", "u (squares)", "u (Voronoi)", "abs. diff"], shared),
        "",
    ]


def quality_section(ctx: Context) -> list[str]:
    q, cells = ctx.details["quality"], ctx.details["meshes"]["voronoi"]["cells"]
    return [
        "## Shape regularity of the Voronoi mesh (assumption A1)",
        "",
        *q["table"],
        "",
        f"gamma1 = min rho_K / h_K = {q['gamma1']:.4g}, gamma2 = min vertex distance / h_K = "
        f"{q['gamma2']:.4g}; {q['convex']} of {cells} cells convex, "
        f"{q['not_star_shaped']} not star-shaped; "
        + ("no warnings." if not q["warnings"] else "warnings: " + "; ".join(q["warnings"])),
        "(For the squares, gamma1 = 1/(2 sqrt 2) = 0.3536.)",
        "",
    ]


def study_section(ctx: Context) -> list[str]:
    st = ctx.details.get("refinement_study")
    if st is None:
        return []
    return [
        "## Mesh convergence: Voronoi refinement against the squares",
        "",
        f"Reference: {st['reference']}. Same data and time steps.",
        "",
        st["table"],
        "",
        "Wear difference decreases with refinement: "
        f"{'yes' if st['decreasing'] else '**no**'} (rel. L2), "
        f"{'yes' if st['decreasing_max'] else '**no**'} (rel. max).",
        "",
    ]


def timings_section(ctx: Context) -> list[str]:
    t = {k: v for k, v in ctx.timings.items() if k != "total"}
    t["total"] = ctx.elapsed()
    return [
        "## Timings (s)",
        "",
        *table(["step", "seconds"], [[k, f"{v:.2f}"] for k, v in t.items()]),
        "",
    ]


def paper_section(out: Path, sub: str, run: ExampleRun) -> list[str]:
    d = run.details
    meshes = d.get("meshes", {})
    rows = [
        [
            name,
            str(meshes.get(name, {}).get("cells", r.problem.mesh.n_cells)),
            num(r.wear[-1].max(), ".5g"),
            num(r.u_nu[-1].max(), ".5g"),
        ]
        for name, r in run.results.items()
    ]
    comp = d.get("comparison", {})
    flat = [(k, v) for k, v in comp.items() if isinstance(v, int | float)]
    return [
        "## Example 5.4: squares against general polygons (paper Figs. 7-9)",
        "",
        f"Report: [{sub}/example_5_4.md]({sub}/example_5_4.md). Wall time {run.elapsed:.1f} s.",
        "",
        *table(["mesh", "cells", "max w(T)", "max u_nu(T)"], rows),
        *(["", "Agreement of the two meshes (see the example's report):", ""] if flat else []),
        *(f"- {k}: {num(v, '.4g')}" for k, v in flat),
        "",
        'The paper shows the displacements and the contact profiles of both meshes "almost '
        'the same" (figures only, no numbers).',
        "",
        "Figures:",
        "",
        *links(out, sub),
        "",
    ]
