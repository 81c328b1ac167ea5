"""The 3D analogue of the paper's Section 5.

The block Omega = (0, 2) x (0, 1) x (0, 1), clamped at x = 0, in contact with the
foundation on z = 0, traction-free elsewhere; f1 = (0, 0, -0.06), v* = (1, 0, 0),
lam = eta = 4, p(r) = 0.4 r_+, g = 0.1, mu = 0.2, kappa = 2, T = 1 (the data of
Example 5.4 in three components; ``examples/example_3d.toml`` is the hexahedral run as
a configuration file). Two studies:

1. the Example 5.4 analogue: hexahedra (``hex``, 2n x n x n cells, h = 1/n) against
   centroidal Voronoi polyhedra of the same count (``voronoi``), k = 1/n; the maximal
   wear at T of each and the difference of the two wear fields on the contact face
   (the Voronoi wear interpolated linearly, on the Delaunay triangles of its contact
   face vertices, at the hexahedral contact nodes);
2. the Example 5.5 analogue: hexahedra with h = k = 1/n for n in ``levels`` against the
   reference h = k = 1/``reference``: the relative L2 error of w(T) on the contact face
   (the coarse wear interpolated bilinearly at the reference's contact nodes, the norm by
   the reference's nodal weights) and the observed orders.

Wear on the contact face: at the contact nodes, and 0 at the clamped vertices of the
contact face (x = 0, which are no contact nodes: there u = 0 and no wear grows).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..contact import LinearCompliance
from ..mesh.boundary3d import select_parts3d
from ..mesh.generate3d import box_hexahedra
from ..mesh.voronoi3d import box_voronoi
from ..simulate import Problem, Result, TimeGrid
from ..vem import Material
from . import ExampleRun
from .driver import run_example
from .markdown import num
from .spec import Column, Context, Example, text_output

__all__ = [
    "EXAMPLE",
    "NAME",
    "TITLE",
    "convergence",
    "face_wear",
    "problem3d",
    "problems",
    "run",
    "wear_difference",
]

NAME = "3d"
TITLE = "Example 3d"
SIZE = (2.0, 1.0, 1.0)
SIDES = {"clamped": "xmin", "contact": "zmin", "free": "rest"}
LAM = ETA = 4.0
F1 = (0.0, 0.0, -0.06)
C_P, G, MU, KAPPA = 0.4, 0.1, 0.2, 2.0
V_STAR = (1.0, 0.0, 0.0)


def problem3d(mesh: Any, steps: int) -> Problem:
    """The 3D problem on a mesh of the box, ``steps`` uniform steps on [0, 1]."""
    return Problem(
        select_parts3d(mesh, SIDES),
        Material(LAM, ETA),
        TimeGrid.uniform(1.0, int(steps)),
        f1=F1,
        p=LinearCompliance(C_P),
        g=G,
        mu=MU,
        kappa=KAPPA,
        v_star=V_STAR,
    )


def _hex(n: int) -> Problem:
    return problem3d(box_hexahedra(SIZE, (2 * n, n, n)), n)


def problems(n: int, levels: tuple[int, ...], reference: int, seed: int) -> dict[str, Problem]:
    """``hex`` and ``voronoi`` (2 n^3 cells each, k = 1/n), ``h<m>`` for m in ``levels``
    and ``ref`` (h = k = 1/reference) on hexahedra."""
    out = {
        "hex": _hex(n),
        "voronoi": problem3d(box_voronoi(SIZE, 2 * n**3, seed=seed), n),
    }
    for m in levels:
        if m != n:
            out[f"h{m}"] = _hex(m)
    out["ref"] = _hex(reference)
    return out


def _name(ctx: Context, m: int) -> str:
    return "hex" if m == ctx.params["n"] else f"h{m}"


def face_wear(result: Result, row: int = -1) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The (x, y) of every vertex of the contact faces and w there at a kept level: the
    contact nodes' wear, 0 at the clamped vertices."""
    pr = result.problem
    space: Any = pr.space
    verts = space.facet_vertices(pr.mesh.part_faces("contact"))
    w = np.zeros(len(verts))
    pos = np.searchsorted(verts, result.contact_nodes)
    w[pos] = np.asarray(result.wear[row])
    return np.asarray(pr.mesh.points[verts, :2]), w


def wear_difference(a: Result, b: Result) -> dict[str, float]:
    """``b``'s wear at T interpolated linearly at ``a``'s contact face vertices against
    ``a``'s: the largest difference, absolute and relative to max w of ``a``, and the
    relative L2 difference by ``a``'s nodal weights."""
    from scipy.interpolate import LinearNDInterpolator

    xa, wa = face_wear(a)
    xb, wb = face_wear(b)
    wi = LinearNDInterpolator(xb, wb)(xa)
    d = np.nan_to_num(wi - wa)
    space: Any = a.problem.space
    verts = space.facet_vertices(a.problem.mesh.part_faces("contact"))
    on = np.searchsorted(verts, a.contact_nodes)
    om = np.asarray(a.problem.contact.weights)
    l2 = math.sqrt(float(om @ d[on] ** 2) / max(float(om @ wa[on] ** 2), 1e-300))
    return {
        "max_abs": float(np.abs(d).max()),
        "max_rel": float(np.abs(d).max() / max(wa.max(), 1e-300)),
        "l2_rel": l2,
    }


def convergence(ctx: Context) -> list[dict[str, float]]:
    """Rows ``{n, h, dofs, max_wear, error, order}``: the relative L2 wear error at T of
    h = k = 1/n against the reference (:func:`wear_difference` with the reference as
    ``a``: the coarse wear interpolated linearly on the Delaunay triangles of its contact
    face vertices)."""
    ref = ctx.results["ref"]
    rows: list[dict[str, float]] = []
    for m in ctx.params["levels"]:
        r = ctx.results[_name(ctx, m)]
        e = wear_difference(ref, r)["l2_rel"]
        order = math.log(rows[-1]["error"] / e, 2) if rows and e > 0 else float("nan")
        rows.append(
            {
                "n": m,
                "h": 1.0 / m,
                "dofs": 3 * r.problem.mesh.n_points,
                "max_wear": float(r.wear[-1].max()),
                "error": e,
                "order": order,
            }
        )
    return rows


def _analyse(ctx: Context) -> dict[str, Any]:
    hx, vo = ctx.results["hex"], ctx.results["voronoi"]
    diff = wear_difference(hx, vo)
    rows = convergence(ctx)
    return {
        "max_wear": {k: float(r.wear[-1].max()) for k, r in ctx.results.items()},
        "difference": diff,
        "convergence": rows,
        "summary": [
            f"hexahedra against Voronoi polyhedra ({hx.problem.mesh.n_cells} cells each): "
            f"max w(T) {hx.wear[-1].max():.6g} and {vo.wear[-1].max():.6g}, difference "
            f"{diff['max_abs']:.3g} ({100 * diff['max_rel']:.2f} % of max w), relative L2 "
            f"{100 * diff['l2_rel']:.2f} %",
            "wear L2 errors against h = 1/"
            + str(ctx.params["reference"])
            + ": "
            + ", ".join(f"h = 1/{int(r['n'])}: {r['error']:.3g}" for r in rows),
        ],
    }


def convergence_markdown(rows: list[dict[str, float]], reference: int) -> str:
    """The convergence table as Markdown."""
    lines = [
        f"| h = k | dofs | max w(T) | rel. L2 error of w(T) vs h = 1/{reference} | order |",
        "|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| 1/{int(r['n'])} | {int(r['dofs'])} | {r['max_wear']:.6g} | {r['error']:.4g} | "
            f"{num(r['order'], '.2f')} |"
        )
    return "\n".join(lines) + "\n"


def _setup(ctx: Context) -> str:
    p = ctx.params
    n = p["n"]
    return (
        "Omega = (0, 2) x (0, 1) x (0, 1) clamped at x = 0, contact on z = 0, traction-free "
        "elsewhere; f1 = (0, 0, -0.06), v* = (1, 0, 0), lam = eta = 4, p(r) = 0.4 r_+, "
        f"g = 0.1, mu = 0.2, kappa = 2, T = 1. Mesh comparison: {2 * n}x{n}x{n} hexahedra "
        f"against {2 * n**3} centroidal Voronoi polyhedra (seed {p['seed']}), k = 1/{n}. "
        f"Convergence: hexahedra with h = k = 1/m, m in {list(p['levels'])}, against "
        f"h = k = 1/{p['reference']}."
    )


def _sections(ctx: Context) -> list[str]:
    d = ctx.details
    diff = d["difference"]
    return [
        "## Hexahedra against Voronoi polyhedra (the Example 5.4 analogue)",
        "",
        f"max w(T): hexahedra {num(d['max_wear']['hex'], '.6g')}, Voronoi polyhedra "
        f"{num(d['max_wear']['voronoi'], '.6g')}. Difference of w(T) on the contact face: "
        f"largest {num(diff['max_abs'], '.3g')} ({num(100 * diff['max_rel'], '.2f')} % of "
        f"max w), relative L2 {num(100 * diff['l2_rel'], '.2f')} %.",
        "",
        "## Convergence in h = k (the Example 5.5 analogue)",
        "",
        convergence_markdown(d["convergence"], ctx.params["reference"]),
        "The wear update is first order in k and the k = 1 elements first order in h in "
        "H1 (second in L2), so with h = k an order near 1 is expected.",
        "",
    ]


def _check(params: Mapping[str, Any]) -> None:
    levels, ref, n = tuple(params["levels"]), int(params["reference"]), int(params["n"])
    if not levels or any(m < 1 or ref % m for m in levels) or max(levels) >= ref or n < 1:
        raise ValueError(
            f"{TITLE}: levels {list(levels)} must divide the reference {ref} and be smaller; "
            f"n = {n} >= 1"
        )


EXAMPLE = Example(
    name=NAME,
    heading="the block in 3D: hexahedra against Voronoi polyhedra, convergence in h = k",
    parameters={"n": 8, "levels": (2, 4, 8), "reference": 16, "seed": 0},
    problems=problems,
    check=_check,
    setup=_setup,
    runs_description="the output of `vemwear run` for each mesh.",
    run_label=lambda ctx, name, pr: f"{name}: {pr.mesh.n_cells} cells, {pr.time.n_steps} steps",
    analyse=_analyse,
    columns=(
        Column("run", lambda ctx, n, r: n),
        Column("cells", lambda ctx, n, r: str(r.problem.mesh.n_cells)),
        Column("dofs", lambda ctx, n, r: str(3 * r.problem.mesh.n_points)),
        Column("levels", lambda ctx, n, r: str(len(r.t))),
        Column("max w(T)", lambda ctx, n, r: f"{r.wear[-1].max():.6g}"),
        Column("max iterations", lambda ctx, n, r: str(int(r.iterations.max()))),
        Column("max KKT residual", lambda ctx, n, r: f"{float(r.residuals.max()):.2e}"),
    ),
    sections=(_sections,),
    outputs=(
        text_output(
            "convergence.md",
            "the convergence table.",
            lambda ctx: convergence_markdown(ctx.details["convergence"], ctx.params["reference"]),
        ),
    ),
    figure_times=lambda pr: (0.25, 0.5, 0.75, 1.0),
    store="final",
    vtk=False,
    quick={"n": 2, "levels": (1, 2), "reference": 4},
    paper_section=lambda out, sub, run: [
        "## Example 3d: the block in 3D",
        "",
        f"Report: [{sub}/example_3d.md]({sub}/example_3d.md). Wall time {run.elapsed:.1f} s.",
        "",
        *run.details.get("summary", []),
        "",
    ],
    headlines={
        "max_wear_hex": lambda ctx: ctx.details["max_wear"]["hex"],
        "max_wear_voronoi": lambda ctx: ctx.details["max_wear"]["voronoi"],
        "wear_difference_rel": lambda ctx: ctx.details["difference"]["max_rel"],
    },
)


def run(outdir: str | Path, **options: Any) -> ExampleRun:
    """Run the 3D example and write everything into the existing directory ``outdir``.

    Writes ``hex/``, ``voronoi/``, ``h<m>/``, ``ref/`` (the standard output of
    ``vemwear run`` each), ``convergence.md`` and ``example_3d.md``.

    Parameters
    ----------
    outdir : path
        An existing directory.
    **options
        ``n`` (the comparison's h = k = 1/n; default 8: 16 x 8 x 8 = 1024 cells),
        ``levels`` (default 2, 4, 8), ``reference`` (default 16), ``seed`` (the Voronoi
        cells'), ``quick`` (the small sizes of :attr:`Example.quick`) and the driver's
        ``solver``, ``progress``, ``figures``, ``vtk``, ``log``.

    Returns
    -------
    ExampleRun
        ``details``: ``max_wear`` by run, ``difference`` (:func:`wear_difference` of the
        Voronoi run against the hexahedral one), ``convergence`` (rows of
        :func:`convergence`) and ``summary`` (lines).
    """
    if options.pop("quick", False):
        options = {**EXAMPLE.quick, **options}
    return run_example(EXAMPLE, outdir, **options)
