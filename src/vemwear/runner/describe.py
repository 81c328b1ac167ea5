"""What ``vemwear check`` and ``vemwear run`` say about a problem and a finished run.

Each function returns rows ``(label, text)``; the clients lay them out.
"""

from __future__ import annotations

import math
import warnings
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from ..config import Config
    from ..simulate import Problem, Result

__all__ = ["check_rows", "format_k", "result_rows", "smallness_report"]

Rows = list[tuple[str, str]]


def format_k(k_min: float, k_max: float) -> str:
    """``k = 0.125 = 1/8`` or ``k in [a, b]``."""
    if math.isclose(k_min, k_max, rel_tol=1e-9):
        inv = 1.0 / k_min
        frac = f" = 1/{round(inv)}" if math.isclose(inv, round(inv), rel_tol=1e-9) else ""
        return f"k = {k_min:.6g}{frac}"
    return f"k in [{k_min:.6g}, {k_max:.6g}]"


def smallness_report(problem: Problem, max_dofs: int = 200_000) -> tuple[str, str | None]:
    """The smallness condition of Theorem 3.4, estimated for ``vemwear check`` and ``run``.

    Parameters
    ----------
    problem : Problem
        A validated problem (its discretization is assembled here).
    max_dofs : int
        Skip the estimate (an eigenvalue problem) above this number of dofs.

    Returns
    -------
    row : str
        A one-line summary of the estimate ``L_p ||mu|| c_0^2 / C_1``.
    warning : str or None
        A warning when the condition is doubtful (estimate >= 1), else None.
    """
    if 2 * problem.mesh.n_points > max_dofs:
        return f"not estimated (more than {max_dofs} dofs)", None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        est = problem.discrete.smallness_estimate()
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
    from ..mesh import PARTS
    from ..solvers import resolve_backend

    pr = cfg.problem
    m = pr.mesh
    cb = pr.contact
    counts = ", ".join(f"{n}-gons: {len(i)}" for n, (i, _) in sorted(m.groups.items()))
    parts = ", ".join(f"{p} {n}" for p, n in m.part_counts().items() if n or p in PARTS)
    k = pr.time.k
    src = cfg.mesh_source
    mesh_from = (
        f"file {src['file']}"
        if "file" in src
        else f"generator {src.get('generator')} ({src.get('function')})"
    )
    nodal = pr.nodal

    def rng(name: str) -> str:
        v = nodal[name]
        lo, hi = float(v.min()), float(v.max())
        return f"{lo:g}" if lo == hi else f"{lo:g} .. {hi:g}"

    ce = m.part_edges("contact")
    length = float(np.linalg.norm(m.points[ce[:, 1]] - m.points[ce[:, 0]], axis=1).sum())
    law = pr.p.describe()
    if law.get("type") == "linear":
        p_text = f"p(r) = {law['c']:g} r_+"
    elif law.get("type") == "table":
        p_text = f"p: table of {len(law['r'])} points, r up to {law['r'][-1]:g}"
    else:
        p_text = f"p: {law}"
    s = cfg.solver
    return [
        (
            "mesh",
            f"{mesh_from}: {m.n_points} vertices, {m.n_cells} cells ({counts}), h = {m.h:.4g}",
        ),
        ("boundary edges", parts),
        ("contact nodes", f"{cb.m} on {len(ce)} contact edges (Gamma_C length {length:.6g})"),
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
        (
            "contact",
            f"{p_text}; g {rng('g')}; mu {rng('mu')}; "
            f"kappa {rng('kappa')}; v_star {pr.v_star.describe()}",  # type: ignore[union-attr]
        ),
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
    ]
