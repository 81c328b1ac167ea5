"""What ``vemwear check`` and ``vemwear run`` say about a problem and a finished run.

Each function returns rows ``(label, text)``; the clients lay them out.
"""

from __future__ import annotations

import math
import warnings
from typing import TYPE_CHECKING

import numpy as np

from ..util.arrays import unique as _unique

if TYPE_CHECKING:
    from numpy.typing import NDArray

    from ..config import Config
    from ..simulate import Problem, Result, SolverOptions

__all__ = ["check_rows", "format_k", "part_wear_rows", "result_rows", "smallness_report"]

Rows = list[tuple[str, str]]


def format_k(k_min: float, k_max: float) -> str:
    """``k = 0.125 = 1/8`` or ``k in [a, b]``."""
    if math.isclose(k_min, k_max, rel_tol=1e-9):
        inv = 1.0 / k_min
        frac = f" = 1/{round(inv)}" if math.isclose(inv, round(inv), rel_tol=1e-9) else ""
        return f"k = {k_min:.6g}{frac}"
    return f"k in [{k_min:.6g}, {k_max:.6g}]"


def smallness_report(
    problem: Problem, solver: SolverOptions | None = None, max_dofs: int = 200_000
) -> tuple[str, str | None]:
    """The smallness condition of Theorem 3.4, estimated for ``vemwear check`` and ``run``.

    Parameters
    ----------
    problem : Problem
        A validated problem (its discretization is assembled here).
    solver : SolverOptions, optional
        The run's solver: its step solver is built here (the run's set-up, which the
        run then reuses) and the estimate takes the block of ``K^{-1}`` on the contact
        dofs from its factorization (:meth:`~vemwear.simulate.Discretization.
        smallness_estimate`).
    max_dofs : int
        Without ``solver``, skip the estimate (a factorization of its own) above this
        number of dofs.

    Returns
    -------
    row : str
        A one-line summary of the estimate ``L_p ||mu|| c_0^2 / C_1``.
    warning : str or None
        A warning when the condition is doubtful (estimate >= 1), else None.
    """
    if len(problem.rigid_basis):  # Theorem 3.4 takes a coercive a_h (clamped Gamma_D)
        return "not applicable (load control: contact holds the body)", None
    if solver is None and problem.dim * problem.mesh.n_points > max_dofs:
        return f"not estimated (more than {max_dofs} dofs)", None
    d = problem.discrete
    step_solver = None if solver is None else d.step_solver(solver)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        est = d.smallness_estimate(step_solver)
    r = float(est.get("ratio", float("nan")))
    if not math.isfinite(r):
        return "not estimated", None
    if r < 1:
        return f"L_p ||mu|| c0^2/C1 ~= {r:.3g} < 1: holds", None
    row = (
        f"L_p ||mu|| c0^2/C1 ~= {r:.3g} >= 1: MAY FAIL (step problems may not be uniquely solvable)"
    )
    warning = (
        f"the smallness condition of Theorem 3.4 is doubtful: L_p ||mu|| c0^2/C1 "
        f"~= {r:.3g} >= 1 (L_p = {est.get('L_p', float('nan')):g}, max mu = "
        f"{est.get('mu_max', float('nan')):g}, c0^2/C1 ~= "
        f"{est.get('c0_sq_over_C1', float('nan')):.3g}); the step problems may not be "
        "uniquely solvable and the solver may fail; reduce mu or the stiffness of p"
    )
    return row, warning


def check_rows(cfg: Config) -> Rows:
    """The description of a validated configuration that ``vemwear check`` prints."""
    pr = cfg.problem
    if pr.dim == 3:
        return _check_rows3d(cfg)
    m = pr.mesh
    cb = pr.contact
    counts = ", ".join(f"{n}-gons: {len(i)}" for n, (i, _) in sorted(m.groups.items()))
    parts = ", ".join(f"{p} {n}" for p, n in m.part_counts().items() if n)
    mesh_from = _mesh_from(cfg)
    edges, lengths = 0, 0.0
    for pc in pr.parts:
        ce = m.part_edges(pc.part)
        edges += len(ce)
        lengths += float(np.linalg.norm(m.points[ce[:, 1]] - m.points[ce[:, 0]], axis=1).sum())
    contact_rows = _contact_rows(pr)
    return [
        (
            "mesh",
            f"{mesh_from}: {m.n_points} vertices, {m.n_cells} cells ({counts}), h = {m.h:.4g}",
        ),
        ("boundary edges", parts),
        ("held by", "; ".join(_held(pr))),
        ("contact nodes", f"{cb.m} on {edges} contact edges (Gamma_C length {lengths:.6g})"),
        *_common_rows(cfg, contact_rows),
        *_adapt_rows(cfg),
    ]


def _adapt_rows(cfg: Config) -> Rows:
    """The ``[adapt]`` settings, if any."""
    a = cfg.adapt
    if a is None:
        return []
    bound = [f"max_cells {a.max_cells}"] if a.max_cells is not None else []
    bound += [f"target_error {a.target_error:g}"] if a.target_error is not None else []
    bound += [f"max_level {a.max_level}"] if a.max_level is not None else []
    coarsen = f"coarsen {a.coarsen:g} of eta^2" if a.coarsen > 0 else "no coarsening"
    first = f"{a.passes - 1} whole runs make the mesh, " if a.passes > 1 else ""
    steps = len(cfg.problem.time.t) - 1
    when = f"mesh change every {a.every} levels" if a.every < steps else "no mesh change in time"
    return [
        (
            "adapt",
            f"{a.estimator} estimator, {first}{when}, theta {a.theta:g}, "
            f"{', '.join(bound)}, {coarsen}",
        )
    ]


def _mesh_from(cfg: Config) -> str:
    src = cfg.mesh_source
    if "file" in src:
        return f"file {src['file']}"
    return f"generator {src.get('generator')} ({src.get('function')})"


def _held(pr: Problem) -> list[str]:
    con = pr.constraints
    return [f"{n} (u = 0)" for n in con.parts[: con.n_clamped]] + [
        f"{d.part} ("
        + ", ".join(f"{c} = {v}" for c, v in d.describe().items() if c != "part" and v is not None)
        + ")"
        for d in pr.displacement
    ]


def _contact_rows(pr: Problem) -> Rows:
    cb, nodal = pr.contact, pr.nodal

    def rng(name: str, sel: np.ndarray) -> str:
        v = nodal[name][sel]
        if not v.size:
            return "-"
        lo, hi = float(v.min()), float(v.max())
        return f"{lo:g}" if lo == hi else f"{lo:g} .. {hi:g}"

    def law_text(law: dict) -> str:
        if law.get("type") == "linear":
            return f"p(r) = {law['c']:g} r_+"
        if law.get("type") == "table":
            return f"p: table of {len(law['r'])} points, r up to {law['r'][-1]:g}"
        return f"p: {law}"

    rows = []
    for i, pc in enumerate(pr.parts):
        sel = np.asarray(cb.part == i)
        gap = f"; gap {rng('gap', sel)}" if np.any(nodal["gap"][sel]) else ""
        gap += "".join(
            f"; {key} total" for key in ("friction_on", "wear_on") if getattr(pc, key) != "soft"
        )
        rows.append(
            (
                "contact" if len(pr.parts) == 1 else f"contact {pc.part}",
                f"{law_text(pc.p.describe())}; g {rng('g', sel)}; mu {rng('mu', sel)}; "
                f"kappa {rng('kappa', sel)}{gap}; v_star {pc.velocity.describe()}",
            )
        )
    return rows


def _check_rows3d(cfg: Config) -> Rows:
    """:func:`check_rows` of a 3D problem: faces instead of edges."""
    pr = cfg.problem
    m = pr.mesh
    nf = np.diff(m.cell_offsets)
    counts = ", ".join(f"{n} faces: {int(np.sum(nf == n))}" for n in _unique(nf))
    h = float(m.cell_diameters.max())
    parts = ", ".join(f"{p} {len(m.part_faces(p))}" for p in m.part_names if len(m.part_faces(p)))
    faces = np.concatenate([m.part_faces(pc.part) for pc in pr.parts])
    area = float(m.face_areas[faces].sum())
    return [
        (
            "mesh",
            f"{_mesh_from(cfg)}: 3D, {m.n_points} vertices, {m.n_cells} cells ({counts}), "
            f"h = {h:.4g}",
        ),
        ("boundary faces", parts),
        ("held by", "; ".join(_held(pr))),
        (
            "contact nodes",
            f"{pr.contact.m} on {len(faces)} contact faces (Gamma_C area {area:.6g})",
        ),
        *_common_rows(cfg, _contact_rows(pr)),
    ]


def _common_rows(cfg: Config, contact_rows: Rows) -> Rows:
    from ..solvers import resolve_backend

    pr = cfg.problem
    k = pr.time.k
    s = cfg.solver
    return [
        (
            "time levels",
            f"{len(pr.time.t)} on [0, {pr.time.T:g}], "
            f"{format_k(float(k.min()), float(k.max())) if k.size else 'no steps'}",
        ),
        (
            "material",
            f"lam = {pr.material.lam:g}, eta = {pr.material.eta:g}; "
            f"stabilization {pr.stabilization}",
        ),
        *contact_rows,
        (
            "solver",
            f"{s.method}, tol {s.tol:g}, max_iter "
            f"{s.max_iter if s.max_iter is not None else 'default'}, backend "
            f"{s.backend} ({resolve_backend(s.backend)})",
        ),
        (
            "output",
            f"profiles at t = {', '.join(f'{t:g}' for t in cfg.output.times)}; "
            f"figures {'yes' if cfg.output.figures else 'no'}; "
            f"vtk {'yes' if cfg.output.vtk else 'no'}",
        ),
    ]


def result_rows(result: Result) -> Rows:
    """Levels, solver statistics and the largest wear of a finished run."""
    it = np.asarray(result.iterations)
    res = np.asarray(result.residuals)
    worst = int(np.argmax(res.max(axis=0))) if res.size else 0
    wT = np.asarray(result.wear[-1])
    a = int(np.argmax(wT)) if wT.size else 0
    at = np.asarray(result.contact_points[a]).tolist() if wT.size else []
    t = result.problem.time.t
    k = np.diff(t)
    return [
        (
            "levels",
            f"{len(t)} (T = {t[-1]:g}, {format_k(float(k.min()), float(k.max()))})"
            + (f", {len(result.t)} kept" if len(result.t) < len(t) else "")
            if k.size
            else "1",
        ),
        (
            "solver",
            f"{result.solver.get('method', '?')}, iterations max {int(it.max())} per "
            f"step, total {int(it.sum())}",
        ),
        (
            "max KKT residual",
            f"{float(res.max()):.2e} ({result.RESIDUAL_NAMES[worst]}; "
            f"tol {result.solver.get('tol', float('nan')):g})",
        ),
        (
            "max wear at T",
            f"{float(wT.max()):.6g} at x = ({', '.join(f'{c:.4g}' for c in at)})"
            if wT.size
            else "-",
        ),
        *part_wear_rows(result.problem, wT),
        *_force_rows(result),
    ]


def part_wear_rows(problem: Problem, wear: NDArray[np.float64]) -> Rows:
    """The largest wear ``wear`` (at the contact nodes) of every contact part and where
    (a row each, when there are several)."""
    cb = problem.contact
    if len(cb.part_names) < 2:
        return []
    rows = []
    for i, name in enumerate(cb.part_names):
        sel = np.flatnonzero(np.asarray(cb.part) == i)
        a = int(sel[np.argmax(wear[sel])])
        x = ", ".join(f"{c:.4g}" for c in cb.points[a])
        rows.append((f"max wear at T: {name}", f"{float(wear[a]):.6g} at x = ({x})"))
    return rows


def _force_rows(result: Result) -> Rows:
    """The force resultant of every part at T (a row each, when there are several)."""
    F = result.forces
    if F is None or not len(F):
        return []
    return [
        (
            f"force at T: {name}",
            "("
            + ", ".join(f"{v:.4g}" for v in F[-1, j])
            + ")"
            + (" reaction" if kind == "reaction" else ""),
        )
        for j, (name, kind) in enumerate(result.force_parts)
    ]
