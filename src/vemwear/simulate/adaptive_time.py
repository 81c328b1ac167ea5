"""Adaptive meshes in a time-dependent run (docs/method.md, section 11): the mesh changes
every few levels and follows the contact zone.

The time grid is split into segments of ``every`` levels. A segment runs the scheme
(:func:`~vemwear.simulate.levels.run_levels`) on its mesh from its first level to its
last, starting from the wear of its first level; at its last level the estimator
(:func:`~vemwear.simulate.estimate.estimate`) marks cells for refinement (Dörfler's
criterion) and, with a coarsening fraction, for coarsening
(:func:`~vemwear.mesh.coarsen.coarsening_marking`); the mesh changes once (one level of
refinement of the marked cells with the graded closure, one level of coarsening of the
families all marked), the wear moves to the new contact nodes
(:func:`~vemwear.contact.transfer.transfer_along_contact`: bitwise on kept nodes), the
discretization and its factorization are built for the new mesh, and the next segment
solves that level again on it. A segment owns its levels up to, not including, its
last (the next segment's first); the last segment owns the final level too.

The state between two segments (:class:`AdaptiveState`: the next segment's first level,
mesh, cell tree and wear) is all the run carries over, so a run started again from it
(``start``) gives the same levels, bitwise, as one that went on; ``on_segment``
receives every finished segment with that state (the runner streams the one and
checkpoints the other there).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from ..contact.transfer import transfer_along_contact
from ..mesh.adapt import CellTree
from ..mesh.curves import OFF_CHORD, BoundaryCurve
from ..mesh.polymesh import Mesh
from ..solvers.backends import reusing_factorizations
from .adapt import AdaptiveStep, adapt_passes
from .estimate import Estimate, estimate_last
from .levels import run_levels
from .loop import MemorySink, Result
from .mesh_change import AdaptSettings, change_mesh, change_mesh_for_wear
from .options import SolverOptions
from .problem import Problem
from .stream import LoopState, StoragePlan
from .timegrid import TimeGrid
from .wear_estimate import predicted_wear

__all__ = ["AdaptSettings", "AdaptiveState", "Segment", "simulate_adaptive"]


@dataclass(frozen=True)
class Segment:
    """The levels of an adaptive run computed on one mesh.

    Attributes
    ----------
    problem : Problem
        The problem on this segment's mesh, its time grid cut after :attr:`last`.
    first, last : int
        The levels it computed; it owns ``first .. last - 1`` (``.. last`` for the final
        segment).
    result : Result
        Its arrays; the rows of the levels before ``first`` are not computed (zero).
    tree : CellTree
        The levels and families of its cells.
    known_estimate : Estimate, optional
        The residual estimate at ``last`` when it is known already (read back from a
        results file); see :attr:`estimate`.
    """

    problem: Problem
    first: int
    last: int
    result: Result
    tree: CellTree
    known_estimate: Estimate | None = field(default=None, repr=False)

    @cached_property
    def estimate(self) -> Estimate:
        """The residual estimator at :attr:`last`, computed from the segment's last level
        when first asked for: at once when it marks the cells, only on request when the
        wear marks them (a run for the wear does not pay for it)."""
        if self.known_estimate is not None:
            return self.known_estimate
        return estimate_last(self.problem, self.result, level=self.last)


@dataclass(frozen=True)
class AdaptiveState:
    """What an adaptive run carries from one segment to the next.

    Attributes
    ----------
    segment : int
        The number of finished segments.
    first : int
        The next segment's first level.
    mesh : Mesh
        Its mesh.
    tree : CellTree
        The levels and families of its cells.
    wear : (m,) array
        The wear of level ``first`` at the mesh's contact nodes.
    """

    segment: int
    first: int
    mesh: Mesh
    tree: CellTree
    wear: NDArray[np.float64]

    @property
    def completed(self) -> int:
        """The number of finished levels (those before :attr:`first`)."""
        return self.first


def simulate_adaptive(
    problem: Problem,
    *,
    every: int,
    theta: float = 0.5,
    coarsen: float = 0.0,
    max_cells: int | None = None,
    target_error: float | None = None,
    max_level: int | None = None,
    max_difference: int = 1,
    curved: bool = True,
    estimator: str = "residual",
    transfer: str = "linear",
    passes: int = 1,
    solver: SolverOptions | str = "newton",
    start: AdaptiveState | None = None,
    on_segment: Callable[[Segment, AdaptiveState | None], None] | None = None,
    on_pass: Callable[[AdaptiveStep], None] | None = None,
    keep: bool = True,
) -> list[Segment]:
    """Run the scheme on a mesh that adapts every ``every`` levels (module docstring).

    Parameters
    ----------
    problem : Problem
        A 2D problem of order 1 or 2 on its initial mesh.
    every : int
        Levels between mesh changes (>= 1).
    theta : float
        Dörfler's bulk fraction of the refinement, in (0, 1].
    coarsen : float
        The fraction of eta^2 the coarsened cells may carry, in [0, 1); 0: no coarsening.
    max_cells : int, optional
        No refinement that would give more cells (coarsening still applies).
    target_error : float, optional
        No refinement at a mesh change whose estimate is at most this.
    max_level : int, optional
        Cells of this level are not refined further.
    max_difference : int
        Largest level difference of neighbours.
    curved : bool
        New boundary vertices of curved boundary parts go onto the curve through the
        initial mesh's boundary vertices (:class:`~vemwear.mesh.curves.BoundaryCurve`).
    estimator, transfer, passes : str, str, int
        As in :class:`AdaptSettings`: with ``passes > 1`` the run starts on the mesh
        refined after ``passes - 1`` whole runs (not when it goes on from ``start``).
    solver : SolverOptions or str
        As for :func:`~vemwear.simulate.loop.simulate`.
    start : AdaptiveState, optional
        Go on from this state (given to ``on_segment`` by an earlier run of the same
        problem and settings) instead of level 0.
    on_segment : callable, optional
        Called with every finished segment and the state the run goes on from (None
        after the last segment).
    on_pass : callable, optional
        Called with every whole run before the run (``passes > 1``).
    keep : bool
        Return the segments (False: an empty list; ``on_segment`` has them).

    Returns
    -------
    list of Segment
        From ``start`` on.
    """
    if not isinstance(problem.mesh, Mesh) or problem.order not in (1, 2):
        raise ValueError("adaptive runs are implemented for k = 1 and 2 in 2D")
    cfg = AdaptSettings(
        every,
        theta,
        coarsen,
        max_cells,
        target_error,
        max_level,
        max_difference,
        curved,
        estimator,
        transfer,
        passes,
    )
    if problem.order != 1 and (estimator, transfer) != ("residual", "linear"):
        raise ValueError("estimator = 'wear' and transfer = 'cubic' are implemented for k = 1")
    opts = SolverOptions(method=solver) if isinstance(solver, str) else solver
    mesh: Mesh = problem.mesh
    tree = CellTree.initial(mesh.n_cells)
    # the curve of the initial mesh, the same for a run started again from a state
    curve = BoundaryCurve.of(mesh) if cfg.curved else None
    w: NDArray[np.float64] | None = None
    n0, k = 0, 0
    if start is not None:
        n0, k, mesh, tree, w = start.first, start.segment, start.mesh, start.tree, start.wear
    elif cfg.passes > 1:  # whole runs first, each refining the mesh for the next
        steps, pr, tree = adapt_passes(
            problem, cfg, cfg.passes - 1, opts, refine_last=True, curve=curve
        )
        mesh = pr.mesh
        for step in steps:
            if on_pass is not None:
                on_pass(step)
    # a mesh that stays (max_cells reached, nothing marked) keeps its factorization for the
    # next segment: the same matrix, so the same factors and bitwise the same levels
    with reusing_factorizations() as forget:
        return _segments(problem, cfg, opts, mesh, tree, curve, w, n0, k, forget, on_segment, keep)


def _segments(
    problem: Problem,
    cfg: AdaptSettings,
    opts: SolverOptions,
    mesh: Mesh,
    tree: CellTree,
    curve: BoundaryCurve | None,
    w: NDArray[np.float64] | None,
    n0: int,
    k: int,
    forget: Callable[[], None],
    on_segment: Callable[[Segment, AdaptiveState | None], None] | None,
    keep: bool,
) -> list[Segment]:
    """The segments of :func:`simulate_adaptive` from level ``n0`` (segment ``k``) on."""
    t = problem.time.t
    N = len(t) - 1
    off_chord = OFF_CHORD if curve is not None and curve.any else 0.0
    parts = tuple(pc.part for pc in problem.parts)
    segments: list[Segment] = []
    while True:
        n1 = min(n0 + cfg.every, N)
        pr = dataclasses.replace(problem, mesh=mesh, time=TimeGrid(t[: n1 + 1]))
        plan = StoragePlan.make(n1 + 1, np.arange(n0, n1 + 1))
        sink = MemorySink(pr, plan, opts)
        state = None if w is None else LoopState(n0, w)
        run_levels(pr, opts, sink, plan, start=state, timings=sink.result.timings)
        res = sink.result
        res.completed = n1 + 1
        seg = Segment(pr, n0, n1, res, tree)
        if keep:
            segments.append(seg)
        if n1 == N:
            if on_segment is not None:
                on_segment(seg, None)
            return segments
        cubic = cfg.transfer == "cubic"
        if cfg.estimator == "wear":
            W = predicted_wear(
                pr.discrete, res.wear[-1], res.p_soft[-1], res.p_rigid[-1], t[n1], t[N]
            )
            move = (parts, off_chord, cubic)
            new, tree, _ = change_mesh_for_wear(mesh, tree, pr.contact.nodes, W, cfg, curve, move)
        else:
            est = seg.estimate
            new, tree, _ = change_mesh(mesh, tree, est.indicators, est.total, cfg, curve)
        w = res.wear[-1]
        if new is not mesh:
            nxt = dataclasses.replace(problem, mesh=new)
            w = transfer_along_contact(
                mesh, pr.contact.nodes, w, nxt.contact.points, parts, off_chord, cubic
            )
            forget()  # the old mesh's factorization, before the new one is made
        pr.discrete.release_solvers()
        mesh, n0, k = new, n1, k + 1
        if on_segment is not None:
            on_segment(seg, AdaptiveState(k, n0, mesh, tree, w))
