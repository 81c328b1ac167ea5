"""Example 5.4 of the paper: the same problem on squares and on general polygons.

Data (paper Section 5): as Example 5.2, data set 1:
Omega = (0, 2) x (0, 1), Gamma_D = left side, Gamma_N = top and right sides,
Gamma_C = bottom side; lam = eta = 4, T = 1, u^0 = 0, p(r) = 0.4 r_+,
f1 = (0, -0.06), f2 = 0, g = 0.1, v* = (1, 0), mu = 0.2, kappa = 2, k = 1/64.
The two meshes of the paper are

A. 2048 squares, 64 x 32: 32 squares per unit length (the paper's h = 1/32; Fig. 7);
B. 2048 general polygons (paper Fig. 8): here the centroidal Voronoi mesh of
   :func:`vemwear.mesh.rectangle_voronoi` with exactly 2048 cells and seed 0.

The paper shows u_h1 and u_h2 at t = 1 on both meshes (Figs. 7 and 8, "almost the
same") and a scatter plot of u_nu and w along Gamma_C at t = 1 for both (Fig. 9,
"almost coincide"). This module makes those figures (Fig. 8 with the colour limits
of Fig. 7), and quantifies the agreement (:mod:`vemwear.paper.ex54_compare`):

* wear and u_nu at t = 1: the Voronoi values interpolated piecewise linearly in x_1
  at the contact nodes of the square mesh; relative maximum and L2 differences (the
  headline numbers);
* displacement: at the vertices both meshes share and at probe points, where
  ``Pi u`` (3.8)-(3.10) of the containing cell is evaluated on each mesh;
* the shape regularity (assumption A1) of the Voronoi mesh;
* mesh convergence: :func:`voronoi_refinement_study` repeats the comparison for
  Voronoi meshes of 128, 512 and 2048 cells against the 2048 squares; the
  difference decreases as the Voronoi mesh is refined.

The Voronoi run is also described by ``vemwear/examples/example_5_4_voronoi.toml``; a
test checks that it builds the same mesh.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..mesh import Mesh, quality_report, rectangle_voronoi, tag_rectangle
from ..simulate import Problem, Result, SolverOptions, simulate
from . import DESCRIPTIONS, ExampleRun, ex52
from . import ex54_report as R
from .driver import run_example
from .ex54_compare import (
    compare_runs,
    displacement_difference,
    probe_points,
    profile_difference,
    shared_vertices,
)
from .ex54_report import MESHES
from .markdown import cell, table
from .spec import Column, Context, Example, OutputFile

__all__ = [
    "DESCRIPTION",
    "DIVISIONS",
    "EXAMPLE",
    "KAPPA",
    "MESHES",
    "MU",
    "NAME",
    "N_CELLS",
    "SEED",
    "STEPS",
    "STUDY_CELLS",
    "TITLE",
    "ExampleRun",
    "RefinementStudy",
    "compare_runs",
    "displacement_difference",
    "polygon_mesh",
    "probe_points",
    "problem",
    "problems",
    "profile_difference",
    "run",
    "shared_vertices",
    "square_mesh",
    "voronoi_refinement_study",
]

NAME = "5.4"
TITLE = f"Example {NAME}"
DESCRIPTION = DESCRIPTIONS[NAME]

MU, KAPPA = ex52.DATA_SETS["set1"]["mu"], ex52.DATA_SETS["set1"]["kappa"]
DIVISIONS: tuple[int, int] = (64, 32)  # mesh A: 2048 squares, side 1/32 (the paper's h)
N_CELLS = 2048  # mesh B: 2048 Voronoi polygons
SEED = 0
STEPS = 64  # k = 1/64
STUDY_CELLS: tuple[int, ...] = (128, 512, 2048)
T = ex52.T


# ---------------------------------------------------------------------------- problems
def square_mesh(divisions: tuple[int, int] = DIVISIONS) -> Mesh:
    """Mesh A: ``nx x ny`` squares of (0, 2) x (0, 1), tagged (paper: 64 x 32).

    Parameters
    ----------
    divisions : (int, int)
        Squares in x and y.
    """
    return ex52.mesh(divisions)


def polygon_mesh(n_cells: int = N_CELLS, seed: int | None = SEED) -> Mesh:
    """Mesh B: centroidal Voronoi mesh of (0, 2) x (0, 1) with exactly ``n_cells`` cells, tagged.

    The same mesh as ``[mesh] generator = "voronoi"`` with ``n_cells`` and ``seed``
    in a configuration file (``vemwear/examples/example_5_4_voronoi.toml``).

    Parameters
    ----------
    n_cells : int
        Number of cells (paper: 2048).
    seed : int or None
        Seed of the Voronoi generator.
    """
    return tag_rectangle(rectangle_voronoi(ex52.SIZE, n_cells, seed), ex52.PARTS)


def problem(mesh: Mesh, steps: int = STEPS) -> Problem:
    """The problem of Example 5.4 (Example 5.2's data with mu = 0.2, kappa = 2) on ``mesh``.

    Parameters
    ----------
    mesh : Mesh
        A tagged mesh of (0, 2) x (0, 1).
    steps : int
        Uniform time steps on [0, 1] (paper: 64).
    """
    return ex52.problem(MU, KAPPA, tagged_mesh=mesh, steps=steps)


def problems(
    *,
    divisions: tuple[int, int] = DIVISIONS,
    n_cells: int = N_CELLS,
    seed: int | None = SEED,
    steps: int = STEPS,
) -> dict[str, Problem]:
    """The two problems, ``squares`` (mesh A) and ``voronoi`` (mesh B).

    Parameters
    ----------
    divisions : (int, int)
        Squares in x and y (paper: 64 x 32).
    n_cells : int
        Voronoi cells (paper: 2048).
    seed : int or None
        Seed of the Voronoi mesh.
    steps : int
        Uniform time steps on [0, 1] (paper: 64).
    """
    return {
        "squares": problem(square_mesh(divisions), steps),
        "voronoi": problem(polygon_mesh(n_cells, seed), steps),
    }


# ---------------------------------------------------------------------------- refinement study
@dataclass
class RefinementStudy:
    """Voronoi meshes of increasing size against one reference run (mesh convergence).

    Attributes
    ----------
    reference : str
        Description of the reference run (e.g. ``"2048 squares (64 x 32)"``).
    rows : list of dict
        One per Voronoi mesh, by increasing cell count: ``n_cells``, ``h``,
        ``contact_nodes``, ``wear_rel_max``, ``wear_rel_l2``, ``u_nu_rel_max``,
        ``u_rel_max`` (Pi u at the probe points, vector), ``max_wear`` and ``seconds``
        (the wall time of the Voronoi run's ``simulate``).
    """

    reference: str
    rows: list[dict[str, Any]] = field(default_factory=list)

    def differences(self, key: str = "wear_rel_l2") -> NDArray[np.float64]:
        """One column of the table, by increasing cell count."""
        return np.array([r[key] for r in self.rows], dtype=float)

    def decreasing(self, key: str = "wear_rel_l2") -> bool:
        """Whether the difference to the reference decreases strictly with refinement."""
        return bool(np.all(np.diff(self.differences(key)) < 0))

    def markdown(self) -> str:
        """The study as a Markdown table."""
        lines = [
            "| Voronoi cells | h | contact nodes | max w(T) | wear rel. max diff "
            "| wear rel. L2 diff | u_nu rel. max diff | Pi u rel. max diff (probes) "
            "| solve (s) |",
            "|---|---|---|---|---|---|---|---|---|",
        ]
        for r in self.rows:
            lines.append(
                f"| {r['n_cells']} | {r['h']:.4g} | {r['contact_nodes']} | {r['max_wear']:.6g} "
                f"| {r['wear_rel_max']:.3e} | {r['wear_rel_l2']:.3e} | {r['u_nu_rel_max']:.3e} "
                f"| {r['u_rel_max']:.3e} | {r['seconds']:.2f} |"
            )
        return "\n".join(lines)


def voronoi_refinement_study(
    n_cells: Sequence[int] = STUDY_CELLS,
    *,
    reference: Result | None = None,
    divisions: tuple[int, int] = DIVISIONS,
    steps: int = STEPS,
    seed: int | None = SEED,
    solver: SolverOptions | str = "newton",
    results: Mapping[int, Result] | None = None,
    probes: ArrayLike | None = None,
    log: Callable[[str], None] | None = None,
) -> RefinementStudy:
    """Refine the Voronoi mesh and measure how its wear at t = 1 approaches the squares'.

    Parameters
    ----------
    n_cells : sequence of int
        Voronoi cell counts (default 128, 512, 2048).
    reference : Result, optional
        The reference run; default: solved here on ``divisions`` squares.
    divisions : (int, int)
        Squares of the reference (paper: 64 x 32), if it is solved here.
    steps : int
        Uniform time steps (paper: 64).
    seed : int or None
        Seed of the Voronoi meshes.
    solver : SolverOptions or str
        Step solver.
    results : mapping of int to Result, optional
        Voronoi runs already computed, by cell count (they are reused, not re-solved).
    probes : (n, 2) array_like, optional
        Points of the displacement comparison (default: :func:`probe_points`).
    log : callable, optional
        Receives one line per solve.

    Returns
    -------
    RefinementStudy
        Use ``study.decreasing()`` to check that the wear difference decreases.
    """
    opts = SolverOptions(method=solver) if isinstance(solver, str) else solver
    if reference is None:
        if log is not None:
            log(f"{TITLE}, refinement study: reference, {divisions[0]} x {divisions[1]} squares")
        reference = simulate(problem(square_mesh(divisions), steps), opts, store="final")
    ref_mesh = reference.problem.mesh
    ref_name = (
        f"{ref_mesh.n_cells} cells"
        if set(ref_mesh.groups) != {4}
        else f"{ref_mesh.n_cells} squares"
    )
    study = RefinementStudy(reference=f"{ref_name}, h = {ref_mesh.h:.4g}")
    known = dict(results or {})
    for n in sorted(int(c) for c in n_cells):
        res = known.get(n)
        if res is None:
            if log is not None:
                log(f"{TITLE}, refinement study: {n} Voronoi cells")
            res = simulate(problem(polygon_mesh(n, seed), steps), opts, store="final")
        cmp = compare_runs(reference, res, T, probes)
        study.rows.append(
            {
                "n_cells": n,
                "h": float(res.problem.mesh.h),
                "contact_nodes": len(res.contact_nodes),
                "max_wear": float(res.wear[-1].max()),
                "wear_rel_max": cmp["wear"]["rel_max"],
                "wear_rel_l2": cmp["wear"]["rel_l2"],
                "u_nu_rel_max": cmp["u_nu"]["rel_max"],
                "u_rel_max": cmp["displacement"]["probes"]["vector"]["rel_max"]
                if "displacement" in cmp
                else float("nan"),
                "seconds": float(res.timings.get("total", float("nan"))),
            }
        )
    return study


# ---------------------------------------------------------------------------- analysis
def _prepare(ctx: Context) -> None:
    t0 = time.perf_counter()
    ctx.state["quality"] = quality_report(ctx.problems["voronoi"].mesh)
    ctx.timings["quality report"] = time.perf_counter() - t0


def _mesh_info(ctx: Context, name: str, res: Result) -> dict[str, Any]:
    mesh = res.problem.mesh
    return {
        "cells": mesh.n_cells,
        "points": mesh.n_points,
        "h": float(mesh.h),
        "cells_by_vertices": {int(n): len(i) for n, (i, _v) in sorted(mesh.groups.items())},
        "contact_nodes": len(res.contact_nodes),
        "max_wear": float(res.wear[-1].max()),
        "max_u_nu": float(res.u_nu[-1].max()),
        "max_iterations": int(res.iterations.max()),
        "max_residual": float(res.residuals.max()),
        "solve_seconds": ctx.timings[f"solve {name}"],
    }


def _analyse(ctx: Context) -> dict[str, Any]:
    p = ctx.params
    rep = ctx.state["quality"]
    details: dict[str, Any] = {
        "example": NAME,
        "steps": p["steps"],
        "solver": ctx.solver.method,
        "mu": MU,
        "kappa": KAPPA,
        "divisions": list(p["divisions"]),
        "n_cells": p["n_cells"],
        "seed": p["seed"],
        "meshes": {n: _mesh_info(ctx, n, r) for n, r in ctx.results.items()},
        "comparison": compare_runs(ctx.results["squares"], ctx.results["voronoi"], T),
        "quality": {
            "summary": {k: list(v) for k, v in rep.summary().items()},
            "table": table(
                ["quantity", "min", "mean", "max"],
                [
                    [cell(k), f"{lo:.4g}", f"{mean:.4g}", f"{hi:.4g}"]
                    for k, (lo, mean, hi) in rep.summary().items()
                ],
            ),
            "gamma1": rep.gamma1,
            "gamma2": rep.gamma2,
            "convex": int(np.sum(rep.convex)),
            "not_star_shaped": int(np.sum(~rep.star_shaped)),
            "warnings": list(rep.warnings),
        },
    }
    if p["study_cells"]:
        study = voronoi_refinement_study(
            p["study_cells"],
            reference=ctx.results["squares"],
            steps=p["steps"],
            seed=p["seed"],
            solver=ctx.solver,
            results={p["n_cells"]: ctx.results["voronoi"]},
            log=ctx.log,
        )
        details["refinement_study"] = {
            "reference": study.reference,
            "rows": study.rows,
            "table": study.markdown(),
            "decreasing": study.decreasing("wear_rel_l2"),
            "decreasing_max": study.decreasing("wear_rel_max"),
        }
    details["timings"] = ctx.timings
    return details


def _figure_times(pr: Problem) -> tuple[float, ...]:
    try:
        pr.time.index(ex52.TIMES)
        return ex52.TIMES
    except ValueError:
        return (float(pr.time.T),)


EXAMPLE = Example(
    name=NAME,
    heading="squares against general polygons",
    parameters={
        "divisions": DIVISIONS,
        "n_cells": N_CELLS,
        "seed": SEED,
        "steps": STEPS,
        "study_cells": STUDY_CELLS,
    },
    problems=problems,
    prepare=_prepare,
    setup=R.setup,
    runs_description="the output of `vemwear run` for each mesh (result.npz, summary.json, "
    "figures, VTK series).",
    run_label=lambda ctx, name, pr: (
        f"{MESHES[name]}: {pr.mesh.n_cells} cells, {pr.mesh.n_points} vertices"
    ),
    run_extra=lambda ctx, name, pr: {
        "mesh": name,
        **{k: ctx.params[k] for k in ("divisions", "n_cells", "seed", "steps")},
        "mu": MU,
        "kappa": KAPPA,
    },
    figure_times=_figure_times,
    analyse=_analyse,
    columns=(
        Column("mesh", lambda ctx, n, r: n),
        R.info_column("cells", "cells"),
        R.info_column("points", "vertices"),
        Column(
            "cells by vertex count",
            lambda ctx, n, r: ", ".join(
                f"{k}: {c}" for k, c in ctx.details["meshes"][n]["cells_by_vertices"].items()
            ),
        ),
        R.info_column("h", "h", ".4g"),
        R.info_column("contact_nodes", "contact nodes"),
        R.info_column("max_wear", "max w(T)", ".6g"),
        R.info_column("max_u_nu", "max u_nu(T)", ".6g"),
        R.info_column("max_iterations", "max iterations"),
        R.info_column("max_residual", "max KKT residual", ".2e"),
        R.info_column("solve_seconds", "solve (s)", ".2f"),
    ),
    sections=(
        R.contact_section,
        R.displacement_section,
        R.quality_section,
        R.study_section,
        R.timings_section,
    ),
    outputs=(
        OutputFile(
            "fig7.png",
            "u_1 and u_2 at t = 1 on the squares (paper Fig. 7).",
            R.displacement_figure("squares", 7),
            True,
        ),
        OutputFile(
            "fig8.png",
            "the same on the Voronoi mesh, with the colour limits of `fig7.png` (paper Fig. 8).",
            R.displacement_figure("voronoi", 8),
            True,
        ),
        OutputFile(
            "fig9.png",
            "u_nu and w along Gamma_C at t = 1 on both meshes (paper Fig. 9).",
            R.fig9,
            True,
        ),
        OutputFile(
            "voronoi_mesh.png",
            "the Voronoi mesh coloured by rho_K / h_K.",
            R.voronoi_mesh_figure,
            True,
        ),
        OutputFile("example_5_4.json", "every number of this report.", R.write_json),
    ),
    headlines={
        "wear_rel_max": lambda ctx: ctx.details["comparison"]["wear_rel_max"],
        "wear_rel_l2": lambda ctx: ctx.details["comparison"]["wear_rel_l2"],
        "u_probes_rel_max": lambda ctx: ctx.details["comparison"]["u_probes_rel_max"],
    },
    paper_section=R.paper_section,
)


def run(outdir: str | Path, **options: Any) -> ExampleRun:
    """Solve on both meshes, compare, and write everything into the existing ``outdir``.

    Writes ``squares/`` and ``voronoi/`` (each the standard output of ``vemwear run``),
    ``fig7.png``, ``fig8.png``, ``fig9.png``, ``voronoi_mesh.png``, ``example_5_4.md``
    and ``example_5_4.json``.

    Parameters
    ----------
    outdir : path
        An existing directory.
    **options
        ``divisions``, ``n_cells``, ``seed``, ``steps`` (see :func:`problems`; the
        paper's by default), ``study_cells`` (Voronoi cell counts of the refinement
        study, None for none; the runs on ``n_cells`` and the squares are reused), and
        the driver's ``solver``, ``progress``, ``figures``, ``vtk``, ``log``
        (:func:`vemwear.paper.driver.run_example`).

    Returns
    -------
    ExampleRun
        ``details`` holds the numbers of the report (also in ``example_5_4.json``).
    """
    return run_example(EXAMPLE, outdir, **options)
