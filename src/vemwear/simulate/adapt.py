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

With ``estimator = "wear"`` (k = 1) the cells are marked by the error of the pass's
wear profile at the final time instead (:func:`~vemwear.simulate.wear_estimate.
wear_indicators`), refined round after round on that profile moved onto each new mesh
(:func:`~vemwear.simulate.mesh_change.change_mesh_for_wear`), and the whole run is
solved again on the mesh made for it: the mesh of the last pass is fixed in time and
resolves the wear where the contact zone has been at any time.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ..mesh.adapt import CellTree
from ..mesh.curves import OFF_CHORD, BoundaryCurve
from ..mesh.polymesh import Mesh
from .estimate import Estimate, estimate_last
from .loop import Result, simulate
from .options import SolverOptions
from .problem import Problem

if TYPE_CHECKING:
    from .mesh_change import AdaptSettings

__all__ = ["AdaptiveStep", "adapt", "adapt_passes"]


@dataclass(frozen=True)
class AdaptiveStep:
    """One pass of the adaptive loop.

    Attributes
    ----------
    problem : Problem
        The problem on this pass's mesh.
    result : Result
        Its solution.
    level : (n_cells,) int array
        The refinement level of every cell (0 on the initial mesh).
    marked : (m,) int array
        The cells Dörfler's criterion marked (before the graded closure; for the wear,
        in the first round); empty on the last pass.
    eta : float
        The estimate that decided the pass: the residual estimator's total, or the
        estimate of the wear profile's error (``estimator = "wear"``).
    known_estimate : Estimate, optional
        The residual estimator when it marked the cells (see :attr:`estimate`).
    """

    problem: Problem
    result: Result
    level: NDArray[np.int64]
    marked: NDArray[np.int64]
    eta: float
    known_estimate: Estimate | None = field(default=None, repr=False)

    @cached_property
    def estimate(self) -> Estimate:
        """The residual estimator of the last level: the one that marked the cells, or,
        when the wear marked them, computed when first asked for (a loop for the wear
        does not pay for it)."""
        if self.known_estimate is not None:
            return self.known_estimate
        return estimate_last(self.problem, self.result)

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
    estimator: str = "residual",
    transfer: str = "linear",
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
        Stop when the estimate is at most this (for the wear: refine, round after round,
        until the wear's estimate is at most this).
    max_passes : int
        Largest number of solves.
    max_difference : int
        Largest refinement level difference of neighbouring cells.
    max_level : int, optional
        Cells of this level are not refined further (their marks are dropped).
    curved : bool
        New boundary vertices of curved boundary parts go onto the curve through the
        initial mesh's boundary vertices (:class:`~vemwear.mesh.curves.BoundaryCurve`).
    estimator : {"residual", "wear"}
        What marks the cells: the residual estimator of the last level, or the error of
        the wear profile at the final time (k = 1; module docstring).
    transfer : {"linear", "cubic"}
        With ``estimator = "wear"``: how the profile moves onto the mesh of each round
        (:func:`~vemwear.contact.transfer.transfer_along_contact`).
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
    if max_passes < 1:
        raise ValueError(f"max_passes must be at least 1, got {max_passes}")
    from .mesh_change import AdaptSettings

    cfg = AdaptSettings(
        1, theta, 0.0, max_cells, target_error, max_level, max_difference, curved,
        estimator, transfer,
    )  # fmt: skip
    return adapt_passes(problem, cfg, max_passes, solver)[0]


def adapt_passes(
    problem: Problem,
    cfg: AdaptSettings,
    n: int,
    solver: SolverOptions | str = "newton",
    *,
    refine_last: bool = False,
    curve: BoundaryCurve | None = None,
) -> tuple[list[AdaptiveStep], Problem, CellTree]:
    """At most ``n`` passes of the loop of :func:`adapt` with the settings ``cfg`` (its
    ``every`` and ``coarsen`` are not used).

    Parameters
    ----------
    problem : Problem
        A 2D problem of order 1 or 2 (1 for ``cfg.estimator = "wear"``).
    cfg : AdaptSettings
        Marking, bounds, estimator and transfer.
    n : int
        Largest number of solves.
    solver : SolverOptions or str
        As for :func:`~vemwear.simulate.loop.simulate`.
    refine_last : bool
        Refine after the ``n``-th pass too (the mesh of a run that follows the passes).
    curve : BoundaryCurve, optional
        With ``cfg.curved``: the curve new boundary vertices go onto (default: the one
        through the boundary vertices of ``problem``'s mesh).

    Returns
    -------
    steps : list of AdaptiveStep
        One per solve, in order.
    next : Problem
        The problem on the mesh that the passes end with: the last pass's, or, with
        ``refine_last``, the one refined after it (the last pass's when nothing was
        refined, the target was reached or ``max_cells`` stopped it).
    tree : CellTree
        The levels and families of the cells of ``next``'s mesh.
    """
    # an adaptive run's modules only: a run on one mesh does not load them
    from .mesh_change import change_mesh, change_mesh_for_wear
    from .wear_estimate import wear_indicators

    if cfg.estimator == "wear" and problem.order != 1:
        raise ValueError("estimator = 'wear' is implemented for k = 1")
    mesh = problem.mesh
    assert isinstance(mesh, Mesh)
    tree = CellTree.initial(mesh.n_cells)
    if curve is None and cfg.curved:
        curve = BoundaryCurve.of(mesh)
    parts = tuple(pc.part for pc in problem.parts)
    move = (parts, OFF_CHORD if curve is not None and curve.any else 0.0, cfg.transfer == "cubic")
    steps: list[AdaptiveStep] = []
    pr = problem
    for k in range(n):
        res = simulate(pr, solver, store="final")
        est: Estimate | None = None
        if cfg.estimator == "wear":
            W = np.asarray(res.wear[-1], dtype=np.float64)
            eta2 = wear_indicators(mesh, pr.contact.nodes, W, parts)
        else:
            est = estimate_last(pr, res)
            eta2 = est.indicators
        eta = float(np.sqrt(eta2.sum()))
        new, new_tree, marked = mesh, tree, np.zeros(0, dtype=np.int64)
        if k < n - 1 or refine_last:
            if cfg.estimator == "wear":
                new, new_tree, marked = change_mesh_for_wear(
                    mesh, tree, pr.contact.nodes, W, cfg, curve, move
                )
            else:
                new, new_tree, marked = change_mesh(mesh, tree, eta2, eta, cfg, curve)
        steps.append(AdaptiveStep(pr, res, tree.level, marked, eta, est))
        if new is mesh:
            break
        mesh, tree = new, new_tree
        pr = dataclasses.replace(problem, mesh=mesh)
    return steps, pr, tree
