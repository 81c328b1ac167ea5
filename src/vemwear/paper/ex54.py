"""Example 5.4 of the paper: the same problem on squares and on general polygons.

Data (paper Section 5): as Example 5.2, data set 1:
Omega = (0, 2) x (0, 1), Gamma_D = left side, Gamma_N = top and right sides,
Gamma_C = bottom side; lam = eta = 4, T = 1, u^0 = 0, p(r) = 0.4 r_+,
f1 = (0, -0.06), f2 = 0, g = 0.1, v* = (1, 0), mu = 0.2, kappa = 2, k = 1/64.
The two meshes of the paper are

A. 2048 squares, 64 x 32, h = 1/32 (paper Fig. 7);
B. 2048 general polygons (paper Fig. 8): here the centroidal Voronoi mesh of
   :func:`vemwear.mesh.rectangle_voronoi` with exactly 2048 cells and seed 0.

The paper shows u_h1 and u_h2 at t = 1 on both meshes (Figs. 7 and 8, "almost the
same") and a scatter plot of u_nu and w along Gamma_C at t = 1 for both (Fig. 9,
"almost coincide"). This module makes those figures (Fig. 8 with the colour limits
of Fig. 7), and quantifies the agreement:

* wear and u_nu at t = 1: the Voronoi values interpolated (piecewise linearly in
  x_1, :func:`numpy.interp`) at the contact nodes of the square mesh; relative
  maximum and L2 differences (:func:`profile_difference`);
* displacement: at the vertices both meshes share (the domain corners and any
  boundary point present in both, matched by coordinates) and at probe points,
  where ``Pi u`` of the containing cell is evaluated on each mesh
  (:meth:`vemwear.vem.Projection.evaluate`);
* the shape regularity (assumption A1) of the Voronoi mesh;
* mesh convergence: :func:`voronoi_refinement_study` repeats the comparison for
  Voronoi meshes of 128, 512 and 2048 cells against the 2048 squares; the
  difference decreases as the Voronoi mesh is refined.

The Voronoi run is also described by ``examples/example_5_4_voronoi.toml``; a test
checks that it builds the same mesh.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from ..mesh import Mesh, quality_report, rectangle_voronoi, tag_rectangle
from ..post.norms import contact_l2_norm
from ..post.outputs import write_outputs
from ..post.results import jsonable
from ..simulate import Problem, Result, SolverOptions, simulate
from ..vem import Projection
from . import ExampleRun, ex52

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..mesh import QualityReport

__all__ = [
    "DESCRIPTION",
    "DIVISIONS",
    "KAPPA",
    "MU",
    "NAME",
    "N_CELLS",
    "SEED",
    "STEPS",
    "STUDY_CELLS",
    "TITLE",
    "RefinementStudy",
    "compare_runs",
    "displacement_difference",
    "polygon_mesh",
    "probe_points",
    "problem",
    "problems",
    "profile_difference",
    "report_markdown",
    "run",
    "shared_vertices",
    "square_mesh",
    "voronoi_refinement_study",
]

FloatArray = NDArray[np.float64]

NAME = "5.4"
TITLE = "Example 5.4"
DESCRIPTION = (
    "2048 squares against 2048 Voronoi polygons: u_1, u_2, u_nu and wear at t = 1 "
    "(paper Figs. 7-9), with a Voronoi refinement study"
)

MU, KAPPA = ex52.DATA_SETS["set1"]["mu"], ex52.DATA_SETS["set1"]["kappa"]
DIVISIONS: tuple[int, int] = (64, 32)  # mesh A: 2048 squares, h = 1/32
N_CELLS = 2048  # mesh B: 2048 Voronoi polygons
SEED = 0
STEPS = 64  # k = 1/64
STUDY_CELLS: tuple[int, ...] = (128, 512, 2048)
T = ex52.T
#: Labels of the two meshes (subdirectories of the output).
MESHES: dict[str, str] = {"squares": "squares", "voronoi": "Voronoi polygons"}
FIGURES: dict[str, str] = {"fig7": "fig7.png", "fig8": "fig8.png", "fig9": "fig9.png"}


# ---------------------------------------------------------------------------- problems
def square_mesh(divisions: tuple[int, int] = DIVISIONS) -> Mesh:
    """Mesh A: ``nx x ny`` squares of (0, 2) x (0, 1), tagged (paper: 64 x 32)."""
    return ex52.mesh(divisions)


def polygon_mesh(n_cells: int = N_CELLS, seed: int | None = SEED) -> Mesh:
    """Mesh B: centroidal Voronoi mesh of (0, 2) x (0, 1) with exactly ``n_cells`` cells, tagged.

    The same mesh as ``[mesh] generator = "voronoi"`` with ``n_cells`` and ``seed``
    in a configuration file (``examples/example_5_4_voronoi.toml``).
    """
    return tag_rectangle(rectangle_voronoi(ex52.SIZE, n_cells, seed), ex52.PARTS)


def problem(mesh: Mesh, steps: int = STEPS) -> Problem:
    """The problem of Example 5.4 (Example 5.2's data with mu = 0.2, kappa = 2) on ``mesh``."""
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


# ---------------------------------------------------------------------------- contact profiles
def _profile(result: Result, quantity: str, level: int) -> tuple[FloatArray, FloatArray]:
    """``(x_1, values)`` along Gamma_C sorted by x_1, with the clamped ends of Gamma_C
    (vertices of the contact part on Gamma_D, where u = 0 and w = 0) as zeros."""
    mesh = result.problem.mesh
    ends = np.setdiff1d(mesh.part_vertices("contact"), result.contact_nodes)
    x = np.concatenate([result.contact_points[:, 0], mesh.points[ends, 0]])
    v = np.concatenate([np.asarray(getattr(result, quantity))[level], np.zeros(len(ends))])
    order = np.argsort(x, kind="stable")
    return x[order], v[order]


def profile_difference(
    reference: Result, other: Result, quantity: str = "wear", time: float = T
) -> dict[str, float]:
    """Difference of a contact quantity between two runs, on the reference's contact nodes.

    The values of ``other`` are interpolated piecewise linearly in x_1 (Gamma_C is the
    bottom side) at the contact nodes of ``reference``, the clamped end of Gamma_C
    counting as 0 (u = 0 and w = 0 there).

    Parameters
    ----------
    reference, other : Result
        Runs on two meshes of the same domain.
    quantity : str
        ``wear``, ``u_nu``, ``penetration``, ``lam`` or ``p``.
    time : float
        A time level of both runs.

    Returns
    -------
    dict
        ``max_abs`` (max |a - I b|), ``rel_max`` (max |a - I b| / max |a|), ``rel_l2``
        (``||a - I b|| / ||a||`` in L2(Gamma_C), both piecewise linear on the
        reference's contact edges, integrated exactly:
        :func:`vemwear.post.norms.contact_l2_norm`), ``max_reference``, ``max_other``.
    """
    la, lb = reference.level(time), other.level(time)
    a = np.asarray(getattr(reference, quantity))[la]
    xb, b = _profile(other, quantity, lb)
    ib = np.interp(reference.contact_points[:, 0], xb, b)
    d = a - ib
    mesh, nodes = reference.problem.mesh, reference.contact_nodes
    scale_max = float(np.abs(a).max())
    scale_l2 = contact_l2_norm(mesh, nodes, a, "exact")
    return {
        "max_abs": float(np.abs(d).max()),
        "rel_max": float(np.abs(d).max()) / scale_max if scale_max > 0 else float("nan"),
        "rel_l2": contact_l2_norm(mesh, nodes, d, "exact") / scale_l2
        if scale_l2 > 0
        else float("nan"),
        "max_reference": scale_max,
        "max_other": float(np.abs(b).max()),
    }


# ---------------------------------------------------------------------------- probes
def probe_points(
    size: tuple[float, float] = ex52.SIZE, n: tuple[int, int] = (16, 8)
) -> NDArray[np.float64]:
    """Cell-centred ``n[0] x n[1]`` grid of probe points in ``(0, lx) x (0, ly)``."""
    x = (np.arange(n[0]) + 0.5) * size[0] / n[0]
    y = (np.arange(n[1]) + 0.5) * size[1] / n[1]
    X, Y = np.meshgrid(x, y)
    return np.column_stack([X.ravel(), Y.ravel()])


def shared_vertices(
    a: Mesh, b: Mesh, rtol: float = 1e-9, boundary_only: bool = True
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Vertex pairs of two meshes at the same coordinates (up to ``rtol`` of the extent).

    Parameters
    ----------
    a, b : Mesh
    rtol : float
    boundary_only : bool
        Only vertices on the boundary of both meshes (the domain corners and the
        boundary points the meshes share).

    Returns
    -------
    ia, ib : int arrays
        ``a.points[ia]`` coincides with ``b.points[ib]``; sorted by ``ia``.
    """
    va = np.unique(a.boundary_edges) if boundary_only else np.arange(a.n_points)
    vb = np.unique(b.boundary_edges) if boundary_only else np.arange(b.n_points)
    tol = rtol * float(np.ptp(a.points, axis=0).max())
    d, j = cKDTree(b.points[vb]).query(a.points[va], distance_upper_bound=tol)
    ok = np.isfinite(d)
    return va[ok], vb[j[ok]]


def displacement_difference(
    reference: Result,
    other: Result,
    time: float = T,
    probes: ArrayLike | None = None,
) -> dict[str, Any]:
    """Displacement differences between two runs at shared vertices and at probe points.

    Parameters
    ----------
    reference, other : Result
        Runs on two meshes of the same domain.
    time : float
        A time level whose displacement both runs stored.
    probes : (n, 2) array_like, optional
        Points where ``Pi u`` is compared (default: :func:`probe_points`).

    Returns
    -------
    dict
        ``shared``: list of ``{"x", "u_reference", "u_other", "diff"}`` at the shared
        boundary vertices; ``probes``: ``n``, ``max_abs`` and ``rel_max`` per component
        (``u1``, ``u2``; relative to the component's max over the probes of the
        reference) and for the vector (``vector``: max |d| / max |u|, ``vector_rms``:
        rms |d| / rms |u|).
    """
    ua = reference.displacement(reference.level(time))
    ub = other.displacement(other.level(time))
    ia, ib = shared_vertices(reference.problem.mesh, other.problem.mesh)
    shared = [
        {
            "x": reference.problem.mesh.points[i].tolist(),
            "u_reference": ua[i].tolist(),
            "u_other": ub[j].tolist(),
            "diff": float(np.linalg.norm(ua[i] - ub[j])),
        }
        for i, j in zip(ia, ib, strict=True)
    ]
    pts = probe_points() if probes is None else np.asarray(probes, dtype=float).reshape(-1, 2)
    pa = Projection(reference.problem.mesh).evaluate(ua, pts)
    pb = Projection(other.problem.mesh).evaluate(ub, pts)
    d = pa - pb
    comp = {}
    for c, name in enumerate(("u1", "u2")):
        scale = float(np.abs(pa[:, c]).max())
        m = float(np.abs(d[:, c]).max())
        comp[name] = {
            "max_abs": m,
            "max_reference": scale,
            "rel_max": m / scale if scale > 0 else float("nan"),
        }
    na, nd = np.linalg.norm(pa, axis=1), np.linalg.norm(d, axis=1)
    comp["vector"] = {
        "max_abs": float(nd.max()),
        "max_reference": float(na.max()),
        "rel_max": float(nd.max() / na.max()) if na.max() > 0 else float("nan"),
    }
    comp["vector_rms"] = (
        float(np.sqrt(np.mean(nd**2) / np.mean(na**2))) if na.max() > 0 else float("nan")
    )
    return {"shared": shared, "probes": {"n": len(pts), **comp}}


def compare_runs(
    reference: Result, other: Result, time: float = T, probes: ArrayLike | None = None
) -> dict[str, Any]:
    """Wear, u_nu and displacement differences of ``other`` against ``reference``.

    Returns
    -------
    dict
        ``wear`` and ``u_nu`` (:func:`profile_difference`) and ``displacement``
        (:func:`displacement_difference`, when both runs stored the displacement at
        ``time``; otherwise only the contact quantities); and the headline numbers as
        plain floats: ``wear_rel_max``, ``wear_rel_l2``, ``u_nu_rel_max``,
        ``u_nu_rel_l2``, ``u_probes_rel_max`` and ``u_probes_rel_rms`` (vector, at the
        probe points).
    """
    out: dict[str, Any] = {
        q: profile_difference(reference, other, q, time) for q in ("wear", "u_nu")
    }
    for q in ("wear", "u_nu"):
        out[f"{q}_rel_max"] = out[q]["rel_max"]
        out[f"{q}_rel_l2"] = out[q]["rel_l2"]
    try:
        out["displacement"] = displacement_difference(reference, other, time, probes)
    except KeyError:  # displacement not stored at that level
        return out
    pr = out["displacement"]["probes"]
    out["u_probes_rel_max"] = pr["vector"]["rel_max"]
    out["u_probes_rel_rms"] = pr["vector_rms"]
    return out


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


# ---------------------------------------------------------------------------- figures
def _displacement_figures(results: Mapping[str, Result], out: Path) -> dict[str, list[float]]:
    """Figs. 7 and 8: u_1, u_2 at t = T on both meshes with common colour limits."""
    from .. import post

    us = [r.displacement(-1) for r in results.values()]
    limits = {
        c: [float(min(u[:, c].min() for u in us)), float(max(u[:, c].max() for u in us))]
        for c in (0, 1)
    }
    for (name, res), fig_name in zip(results.items(), ("fig7", "fig8"), strict=True):
        fig = post.plot_displacement(res, -1)
        _set_limits(fig, limits)
        mesh = res.problem.mesh
        what = (
            f"{mesh.n_cells} squares, h = {mesh.h / np.sqrt(2):.4g}"
            if name == "squares"
            else f"{mesh.n_cells} Voronoi polygons, h = {mesh.h:.3g}"
        )
        fig.suptitle(
            f"{TITLE} (paper Fig. {fig_name[3:]}): displacement at $t$ = "
            f"{res.t[-1]:g} on {what}; $\\mu$ = {MU:g}, $\\kappa$ = {KAPPA:g}, "
            f"$k$ = 1/{len(res.t) - 1}"
        )
        fig.savefig(out / FIGURES[fig_name], dpi=150)
    return {"u1": limits[0], "u2": limits[1]}


def _set_limits(fig: Figure, limits: Mapping[int, Sequence[float]]) -> None:
    """Give the colour maps of ``plot_displacement``'s two panels the limits (u1, u2)."""
    mappables = [c for ax in fig.axes for c in ax.collections if c.get_array() is not None]
    if len(mappables) != 2:  # pragma: no cover - plot_displacement changed its layout
        raise RuntimeError(
            f"expected 2 colour maps in the displacement figure, found {len(mappables)}"
        )
    for c, m in enumerate(mappables):
        m.set_clim(*limits[c])


def _profiles_figure(results: Mapping[str, Result], out: Path) -> None:
    """Fig. 9: scatter of u_nu and w along Gamma_C at t = T for both meshes."""
    from .. import post

    labelled = {f"{r.problem.mesh.n_cells} {MESHES[k]}": r for k, r in results.items()}
    post.compare_profiles(
        labelled,
        T,
        ("u_nu", "wear"),
        out / FIGURES["fig9"],
        style="scatter",
        title=f"{TITLE} (paper Fig. 9): $u_\\nu$ and $w$ on $\\Gamma_C$ at $t$ = {T:g}; "
        f"$\\mu$ = {MU:g}, $\\kappa$ = {KAPPA:g}",
    )


# ---------------------------------------------------------------------------- report
def _cell(text: str) -> str:
    """Escape the pipes of a Markdown table cell."""
    return text.replace("|", "\\|")


def _q_table(rep: QualityReport) -> list[str]:
    lines = ["| quantity | min | mean | max |", "|---|---|---|---|"]
    for name, (lo, mean, hi) in rep.summary().items():
        lines.append(f"| {_cell(name)} | {lo:.4g} | {mean:.4g} | {hi:.4g} |")
    return lines


def report_markdown(details: Mapping[str, Any]) -> str:
    """The Markdown report ``example_5_4.md`` from the ``details`` of :func:`run`."""
    d = details
    m = d["meshes"]
    cmp = d["comparison"]
    lines = [
        "# Example 5.4: squares against general polygons",
        "",
        "Wu, Wang, Han, *The virtual element method for a contact problem with wear and "
        "unilateral constraint*, Section 5, Example 5.4.",
        "",
        f"Data of Example 5.2 with mu = {MU:g}, kappa = {KAPPA:g}, v* = (1, 0); "
        f"{d['steps']} uniform time steps (k = 1/{d['steps']}); solver `{d['solver']}`; "
        f"wall time {d['timings']['total']:.2f} s.",
        "",
        "| mesh | cells | vertices | cells by vertex count | h | contact nodes | max w(T) "
        "| max u_nu(T) | max iterations | max KKT residual | solve (s) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, s in m.items():
        counts = ", ".join(f"{n}: {c}" for n, c in s["cells_by_vertices"].items())
        lines.append(
            f"| {name} | {s['cells']} | {s['points']} | {counts} | {s['h']:.4g} "
            f"| {s['contact_nodes']} | {s['max_wear']:.6g} | {s['max_u_nu']:.6g} "
            f"| {s['max_iterations']} | {s['max_residual']:.2e} | {s['solve_seconds']:.2f} |"
        )
    w, un = cmp["wear"], cmp["u_nu"]
    lines += [
        "",
        "## Contact boundary at t = 1 (paper Fig. 9)",
        "",
        "Voronoi values interpolated linearly in x_1 at the contact nodes of the square mesh "
        "(the clamped end x_1 = 0 counts as 0); relative to the squares' values; L2: the "
        "exact L2(Gamma_C) norm of the piecewise linear functions on the squares' contact "
        "edges.",
        "",
        "| quantity | max (squares) | max (Voronoi) | max abs. diff | rel. max diff "
        "| rel. L2 diff |",
        "|---|---|---|---|---|---|",
    ]
    for q, v in (("wear w", w), ("u_nu", un)):
        lines.append(
            f"| {q} | {v['max_reference']:.6g} | {v['max_other']:.6g} "
            f"| {v['max_abs']:.3e} | {v['rel_max']:.3e} | {v['rel_l2']:.3e} |"
        )
    disp = cmp.get("displacement")
    if disp is not None:
        pr = disp["probes"]
        lines += [
            "",
            "## Displacement at t = 1 (paper Figs. 7 and 8)",
            "",
            f"Pi u of the containing cell at {pr['n']} probe points (a cell-centred "
            "16 x 8 grid), squares against Voronoi:",
            "",
            "| component | max abs. (squares) | max abs. diff | rel. max diff |",
            "|---|---|---|---|",
        ]
        for c in ("u1", "u2", "vector"):
            v = pr[c]
            lines.append(
                f"| {c if c != 'vector' else _cell('|u|')} | {v['max_reference']:.4e} "
                f"| {v['max_abs']:.3e} | {v['rel_max']:.3e} |"
            )
        lines += [
            "",
            f"Root-mean-square relative difference of the vector over the probes: "
            f"{pr['vector_rms']:.3e}.",
            "",
            "Vertices both meshes share (the domain corners and boundary points at the same "
            "coordinates):",
            "",
            "| x | u (squares) | u (Voronoi) | abs. diff |",
            "|---|---|---|---|",
        ]
        for s in disp["shared"]:
            fx = ", ".join(f"{c:.6g}" for c in s["x"])
            fa = ", ".join(f"{c:.6e}" for c in s["u_reference"])
            fb = ", ".join(f"{c:.6e}" for c in s["u_other"])
            lines.append(f"| ({fx}) | ({fa}) | ({fb}) | {s['diff']:.3e} |")
    q = d["quality"]
    lines += [
        "",
        "## Shape regularity of the Voronoi mesh (assumption A1)",
        "",
        *q["table"],
        "",
        f"gamma1 = min rho_K / h_K = {q['gamma1']:.4g}, gamma2 = min vertex distance / h_K = "
        f"{q['gamma2']:.4g}; {q['convex']} of {m['voronoi']['cells']} cells convex, "
        f"{q['not_star_shaped']} not star-shaped; "
        + ("no warnings." if not q["warnings"] else "warnings: " + "; ".join(q["warnings"])),
        "(For the squares, gamma1 = 1/(2 sqrt 2) = 0.3536.)",
    ]
    st = d.get("refinement_study")
    if st is not None:
        lines += [
            "",
            "## Mesh convergence: Voronoi refinement against the squares",
            "",
            f"Reference: {st['reference']}. Same data and time steps.",
            "",
            st["table"],
            "",
            f"Wear difference decreases with refinement: "
            f"{'yes' if st['decreasing'] else '**no**'} (rel. L2), "
            f"{'yes' if st['decreasing_max'] else '**no**'} (rel. max).",
        ]
    t = d["timings"]
    lines += [
        "",
        "## Timings (s)",
        "",
        "| step | seconds |",
        "|---|---|",
        *[f"| {k} | {v:.2f} |" for k, v in t.items()],
        "",
        "## Files",
        "",
        "- `fig7.png`: u_1 and u_2 at t = 1 on the squares (paper Fig. 7).",
        "- `fig8.png`: the same on the Voronoi mesh, with the colour limits of `fig7.png` "
        "(paper Fig. 8).",
        "- `fig9.png`: u_nu and w along Gamma_C at t = 1 on both meshes (paper Fig. 9).",
        "- `voronoi_mesh.png`: the Voronoi mesh coloured by rho_K / h_K.",
        "- `squares/`, `voronoi/`: the output of `vemwear run` for each mesh (result.npz, "
        "summary.json, figures, VTK series).",
        "- `example_5_4.json`: every number of this report.",
        "",
    ]
    return "\n".join(lines)


def _figure_times(pr: Problem) -> tuple[float, ...]:
    try:
        pr.time.index(ex52.TIMES)
        return ex52.TIMES
    except ValueError:
        return (float(pr.time.T),)


def run(
    outdir: str | Path,
    *,
    solver: SolverOptions | str = "newton",
    divisions: tuple[int, int] = DIVISIONS,
    n_cells: int = N_CELLS,
    seed: int | None = SEED,
    steps: int = STEPS,
    study_cells: Sequence[int] | None = STUDY_CELLS,
    progress: bool = False,
    figures: bool = True,
    vtk: bool = True,
    log: Callable[[str], None] | None = None,
) -> ExampleRun:
    """Solve on both meshes, compare, and write everything into the existing ``outdir``.

    Writes ``squares/`` and ``voronoi/`` (each the standard output of ``vemwear run``),
    ``fig7.png``, ``fig8.png``, ``fig9.png``, ``voronoi_mesh.png``, ``example_5_4.md``
    and ``example_5_4.json``.

    Parameters
    ----------
    outdir : path
        An existing directory.
    solver : SolverOptions or str
        Step solver (default: condensed Newton).
    divisions, n_cells, seed, steps : see :func:`problems`
        Smaller values make quick tests; the paper's are the defaults.
    study_cells : sequence of int or None
        Voronoi cell counts of the refinement study (None: no study). The run on
        ``n_cells`` and the squares are reused.
    progress : bool
        Show a progress bar per mesh.
    figures, vtk : bool
        Write figures / VTK series (reports and data are always written).
    log : callable, optional
        Receives one line of text per solve.

    Returns
    -------
    ExampleRun
        ``details`` holds the numbers of the report (also in ``example_5_4.json``).
    """
    t_start = time.perf_counter()
    out = Path(outdir)
    opts = SolverOptions(method=solver) if isinstance(solver, str) else solver
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    meshes = {"squares": square_mesh(divisions)}
    timings["mesh squares"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    meshes["voronoi"] = polygon_mesh(n_cells, seed)
    timings["mesh voronoi"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    rep = quality_report(meshes["voronoi"])
    timings["quality report"] = time.perf_counter() - t0
    results: dict[str, Result] = {}
    files: list[str] = []
    info: dict[str, dict[str, Any]] = {}
    for name, mesh in meshes.items():
        pr = problem(mesh, steps)
        if log is not None:
            log(f"{TITLE}, {MESHES[name]}: {mesh.n_cells} cells, {mesh.n_points} vertices")
        t0 = time.perf_counter()
        res = simulate(pr, opts, progress=progress)
        timings[f"solve {name}"] = time.perf_counter() - t0
        results[name] = res
        t0 = time.perf_counter()
        sub = out / name
        sub.mkdir(parents=True, exist_ok=True)
        extra = {
            "example": NAME,
            "mesh": name,
            "divisions": list(divisions),
            "n_cells": n_cells,
            "seed": seed,
            "steps": steps,
            "mu": MU,
            "kappa": KAPPA,
        }
        wr = write_outputs(res, sub, times=_figure_times(pr), figures=figures, vtk=vtk, extra=extra)
        files += [f"{name}/{f}" for group in wr.values() for f in group]
        timings[f"write {name}"] = time.perf_counter() - t0
        info[name] = {
            "cells": mesh.n_cells,
            "points": mesh.n_points,
            "h": float(mesh.h),
            "cells_by_vertices": {int(n): len(i) for n, (i, _v) in sorted(mesh.groups.items())},
            "contact_nodes": len(res.contact_nodes),
            "max_wear": float(res.wear[-1].max()),
            "max_u_nu": float(res.u_nu[-1].max()),
            "max_iterations": int(res.iterations.max()),
            "max_residual": float(res.residuals.max()),
            "solve_seconds": timings[f"solve {name}"],
        }
    t0 = time.perf_counter()
    comparison = compare_runs(results["squares"], results["voronoi"], T)
    timings["comparison"] = time.perf_counter() - t0
    details: dict[str, Any] = {
        "example": NAME,
        "steps": steps,
        "solver": opts.method,
        "mu": MU,
        "kappa": KAPPA,
        "divisions": list(divisions),
        "n_cells": n_cells,
        "seed": seed,
        "meshes": info,
        "comparison": comparison,
        "quality": {
            "summary": {k: list(v) for k, v in rep.summary().items()},
            "table": _q_table(rep),
            "gamma1": rep.gamma1,
            "gamma2": rep.gamma2,
            "convex": int(np.sum(rep.convex)),
            "not_star_shaped": int(np.sum(~rep.star_shaped)),
            "warnings": list(rep.warnings),
        },
    }
    if figures:
        from ..mesh.plot import plot_mesh

        t0 = time.perf_counter()
        details["colour_limits"] = _displacement_figures(results, out)
        _profiles_figure(results, out)
        plot_mesh(
            meshes["voronoi"],
            out / "voronoi_mesh.png",
            quality=rep,
            title=f"{TITLE}: {n_cells} Voronoi cells (seed {seed}), h = {meshes['voronoi'].h:.3g}",
        )
        files += [*FIGURES.values(), "voronoi_mesh.png"]
        timings["figures"] = time.perf_counter() - t0
    if study_cells:
        t0 = time.perf_counter()
        study = voronoi_refinement_study(
            study_cells,
            reference=results["squares"],
            steps=steps,
            seed=seed,
            solver=opts,
            results={n_cells: results["voronoi"]},
            log=log,
        )
        timings["refinement study"] = time.perf_counter() - t0
        details["refinement_study"] = {
            "reference": study.reference,
            "rows": study.rows,
            "table": study.markdown(),
            "decreasing": study.decreasing("wear_rel_l2"),
            "decreasing_max": study.decreasing("wear_rel_max"),
        }
    timings["total"] = time.perf_counter() - t_start
    details["timings"] = timings
    (out / "example_5_4.json").write_text(
        json.dumps(jsonable(details), indent=2) + "\n", encoding="utf-8"
    )
    report = out / "example_5_4.md"
    report.write_text(report_markdown(details), encoding="utf-8")
    files += ["example_5_4.json", report.name]
    return ExampleRun(
        name=NAME,
        outdir=out,
        results=results,
        files=files,
        report=report,
        details=details,
        elapsed=time.perf_counter() - t_start,
    )
