"""The adaptive loop SOLVE -> ESTIMATE -> MARK -> REFINE on one problem (docs/method.md,
section 11).

Every pass solves the problem on the current mesh (:func:`~vemwear.simulate.loop.
simulate`), computes the residual estimator of its last level
(:func:`~vemwear.simulate.estimate.estimate`), marks cells by Dörfler's bulk criterion
(:func:`~vemwear.mesh.adapt.dorfler_marking`) and refines them with the cells needed to
keep the refinement levels of neighbours within ``max_difference``
(:func:`~vemwear.mesh.adapt.refine_graded`). The problem's data are mesh independent
(fields, part names), so the problem of the next pass is the same problem on the refined
mesh.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..mesh.adapt import dorfler_marking, refine_graded
from ..mesh.curves import BoundaryCurve
from ..mesh.polymesh import Mesh
from .estimate import Estimate, estimate
from .loop import Result, simulate
from .options import SolverOptions
from .problem import Problem

__all__ = ["AdaptiveStep", "adapt"]


@dataclass(frozen=True)
class AdaptiveStep:
    """One pass of the adaptive loop.

    Attributes
    ----------
    problem : Problem
        The problem on this pass's mesh.
    result : Result
        Its solution.
    estimate : Estimate
        The estimator of the last level.
    level : (n_cells,) int array
        The refinement level of every cell (0 on the initial mesh).
    marked : (m,) int array
        The cells Dörfler's criterion marked (before the graded closure); empty on the
        last pass.
    """

    problem: Problem
    result: Result
    estimate: Estimate
    level: NDArray[np.int64]
    marked: NDArray[np.int64]

    @property
    def n_dofs(self) -> int:
        """The number of dofs of the space (2 per vertex for k = 1)."""
        return int(self.problem.space.n_dofs)


def adapt(
    problem: Problem,
    *,
    theta: float = 0.5,
    max_cells: int | None = None,
    target_error: float | None = None,
    max_passes: int = 30,
    max_difference: int = 1,
    max_level: int | None = None,
    curved: bool = True,
    solver: SolverOptions | str = "newton",
) -> list[AdaptiveStep]:
    """Refine the mesh of ``problem`` adaptively.

    Parameters
    ----------
    problem : Problem
        A 2D problem of order 1 or 2; its last level is the step the estimator sees.
    theta : float
        Dörfler's bulk fraction in (0, 1].
    max_cells : int, optional
        Stop when the next mesh would have more cells.
    target_error : float, optional
        Stop when the estimate is at most this.
    max_passes : int
        Largest number of solves.
    max_difference : int
        Largest refinement level difference of neighbouring cells.
    max_level : int, optional
        Cells of this level are not refined further (their marks are dropped).
    curved : bool
        New boundary vertices of curved boundary parts go onto the curve through the
        initial mesh's boundary vertices (:class:`~vemwear.mesh.curves.BoundaryCurve`).
    solver : SolverOptions or str
        As for :func:`~vemwear.simulate.loop.simulate`.

    Returns
    -------
    list of AdaptiveStep
        One per solve, in order.
    """
    if not isinstance(problem.mesh, Mesh) or problem.order not in (1, 2):
        raise ValueError("adaptive refinement is implemented for k = 1 and 2 in 2D")
    if max_cells is not None and max_cells < problem.mesh.n_cells:
        raise ValueError(
            f"max_cells = {max_cells} is below the initial mesh's {problem.mesh.n_cells} cells"
        )
    if target_error is not None and not target_error > 0:
        raise ValueError(f"target_error must be positive, got {target_error}")
    if max_passes < 1:
        raise ValueError(f"max_passes must be at least 1, got {max_passes}")
    level = np.zeros(problem.mesh.n_cells, dtype=np.int64)
    curve = BoundaryCurve.of(problem.mesh) if curved else None
    steps: list[AdaptiveStep] = []
    pr = problem
    for k in range(max_passes):
        res = simulate(pr, solver, store="final")
        u_last = res.u[-1] if res.dofs is None else res.dofs[-1]  # k = 2: every dof
        est = estimate(pr, u_last, res.p_rigid[-1], res.wear[-1])
        done = k == max_passes - 1 or (target_error is not None and est.total <= target_error)
        marked = np.zeros(0, dtype=np.int64)
        nxt = None
        if not done:
            marked = dorfler_marking(est.indicators, theta)
            if max_level is not None:
                marked = marked[level[marked] < max_level]
            if marked.size:
                mesh = pr.mesh
                assert isinstance(mesh, Mesh)
                new, new_level, _ = refine_graded(mesh, level, marked, max_difference, curve)
                if max_cells is None or new.n_cells <= max_cells:
                    nxt = (new, new_level)
        steps.append(AdaptiveStep(pr, res, est, level, marked if nxt else marked[:0]))
        if nxt is None:
            break
        pr = dataclasses.replace(pr, mesh=nxt[0])
        level = nxt[1]
    return steps
