"""The fully discrete scheme (paper 3.21-3.23): step problems and the wear update."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..solvers import StepSolution
from ..util.heap import keep_freed_memory, small_zeros
from .levels import RESIDUAL_NAMES, run_levels
from .options import SolverOptions
from .problem import Problem
from .stream import LoopState, StoragePlan


@dataclass
class Result:
    """Solution at every time level.

    Parameters
    ----------
    problem : Problem
        The problem that was solved.
    t : (L,) ndarray
        The time levels.
    points : (n_points, 2) ndarray
        Vertex coordinates.
    u : (S, n_points, 2) ndarray
        Displacement at the stored levels ``u_levels``.
    contact_nodes : (m,) ndarray of int
        Vertex ids on Gamma_C, ordered along it.
    contact_s : (m,) ndarray
        Arc length along Gamma_C.
    contact_points : (m, 2) ndarray
        Coordinates of the contact nodes.
    wear : (L, m) ndarray
        Wear w at the contact nodes.
    u_nu : (L, m) ndarray
        Normal displacement at the contact nodes (``penetration = u_nu - gap - wear``).
    p_rigid : (L, m) ndarray
        Pressure of the rigid layer (the multiplier of u_nu - gap <= g).
    p_soft : (L, m) ndarray
        Pressure of the soft layer, p(u_nu - gap - w).
    iterations : (L,) ndarray of int
        Solver iterations per level.
    residuals : (L, 3) ndarray
        KKT residuals (equilibrium, feasibility, complementarity) per level.
    u_levels : (S,) ndarray of int
        Indices of the levels whose displacement is stored.
    completed : int
        Number of finished levels (``L`` unless the run was interrupted; -1 means L).
    levels : (K,) ndarray of int, optional
        The levels whose contact arrays are kept (rows of ``wear`` ...); default: all.
    solver : dict
        The solver options the levels were computed with.
    timings : dict
        Wall times of the stages, in seconds.
    forces : (K, P, 2) ndarray, optional
        Force resultants on the body per kept level: of every contact part's layer,
        then the reaction of every clamped or prescribed part (the rows of
        :attr:`force_parts`).
    dofs : (S, n_dofs) ndarray, optional
        Every dof of the displacement at the stored levels, for spaces of order k > 1
        (k = 2: vertex values, edge and cell means, :mod:`vemwear.vem.dofs2`) when the
        run kept them (:func:`simulate` does); ``u`` holds the vertex values only. None
        for k = 1 (``u`` is all the dofs).
    """

    problem: Problem
    t: NDArray[np.float64]
    points: NDArray[np.float64]
    u: NDArray[np.float64]
    contact_nodes: NDArray[np.int64]
    contact_s: NDArray[np.float64]
    contact_points: NDArray[np.float64]
    wear: NDArray[np.float64]
    u_nu: NDArray[np.float64]
    p_rigid: NDArray[np.float64]
    p_soft: NDArray[np.float64]
    iterations: NDArray[np.int64]
    residuals: NDArray[np.float64]
    u_levels: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, np.int64))
    completed: int = -1
    levels: NDArray[np.int64] | None = None
    solver: dict[str, Any] = field(default_factory=dict)
    timings: dict[str, float] = field(default_factory=dict)
    forces: NDArray[np.float64] | None = None
    dofs: NDArray[np.float64] | None = None

    RESIDUAL_NAMES = RESIDUAL_NAMES

    @property
    def force_parts(self) -> tuple[tuple[str, str], ...]:
        """``(part, kind)`` of the rows of :attr:`forces` (kind "contact" or "reaction")."""
        return self.problem.discrete.force_parts

    @property
    def penetration(self) -> NDArray[np.float64]:
        gap = self.problem.nodal["gap"]
        return self.u_nu - self.wear if not np.any(gap) else self.u_nu - gap - self.wear

    def __post_init__(self) -> None:
        if self.completed < 0:
            self.completed = len(self.t)
        if self.levels is None:
            self.levels = np.arange(len(self.wear), dtype=np.int64)

    @property
    def is_partial(self) -> bool:
        """True for the levels-so-far of an interrupted run."""
        return self.completed < len(self.t)

    def level(self, t: float) -> int:
        """Index of the kept level (the row of ``wear`` ...) at time t."""
        from .timegrid import TimeGrid

        return int(TimeGrid.index(self._grid, [t])[0])

    @property
    def _grid(self) -> Any:
        from .timegrid import TimeGrid

        if len(self.t) == len(self.problem.time.t):
            return self.problem.time
        return TimeGrid(np.asarray(self.t))

    def displacement(self, level: int) -> NDArray[np.float64]:
        """(n_points, 2) displacement at a level (negative counts from the end)."""
        lv = int(level) % len(self.t)
        where = np.flatnonzero(self.u_levels == lv)
        if where.size == 0:
            raise KeyError(
                f"the displacement at level {lv} (t = {self.t[lv]:g}) was not stored; "
                f"stored levels: {self.u_levels.tolist()[:10]}"
            )
        return self.u[where[0]]


def simulate(
    problem: Problem,
    solver: SolverOptions | str = "newton",
    *,
    progress: bool = False,
    store: str | ArrayLike = "all",
    every: int = 1,
    recover_block: int | None = None,
    resume: Result | None = None,
    callback: Callable[[int, StepSolution], None] | None = None,
    initial_wear: ArrayLike | None = None,
) -> Result:
    """Run the fully discrete scheme (Problem 3.3) on the problem's time grid.

    At each level ``n``: solve the step problem (3.21) with ``w^n`` fixed, warm-started
    from level ``n - 1``; then ``w^{n+1} = w^n + k_n alpha(t_n) p(u_nu^n - w^n)``
    (left rectangle rule, 3.22), with ``w^0 = 0`` (3.23).

    The contact quantities are kept at every level (or every ``every``-th). The full
    displacement costs a back-substitution per level with the condensed solver, so
    ``store`` chooses where it is recovered: ``"all"``, ``"final"``, or a list of times
    (levels). The result is kept in memory; the command line streams long runs to disk
    instead (:func:`vemwear.simulate.levels.run_levels` with a file sink).

    On Linux with glibc, the first call makes the allocator keep freed memory for the
    next arrays, process-wide (:func:`vemwear.util.heap.keep_freed_memory`): new
    arrays then reuse pages instead of page-faulting fresh ones.

    Parameters
    ----------
    problem : Problem
        The problem: mesh, material, loads, contact data and time grid.
    solver : SolverOptions or str
        The solver of the step problems, or just its method (``"newton"``,
        ``"newton-full"``, ``"uzawa"``).
    progress : bool
        Show a progress bar over the time levels.
    store : {"all", "final"} or array_like of float
        The levels whose full displacement is recovered and kept.
    every : int
        Keep the contact arrays of every ``every``-th level (and of the final level and
        the levels of ``store``); 1 keeps all.
    recover_block : int, optional
        Number of levels whose displacements the condensed solver recovers together
        (default: :func:`~vemwear.simulate.levels.recover_block_size`).
    resume : Result, optional
        A partial result of the same problem (``completed < len(t)``); the run goes on
        from its first unfinished level, warm-started as an uninterrupted run would
        be, so the result is the same.
    callback : callable, optional
        ``callback(n, step_solution)`` after each level ``n``.
    initial_wear : array_like, optional
        ``w^0`` at the contact nodes instead of 0 (3.23), e.g. the wear after earlier
        cycles (:func:`vemwear.simulate.cycles.simulate_cycles`).

    Returns
    -------
    Result

    Raises
    ------
    ConvergenceError
        If a step does not reach the tolerance (the message names the level).
    BaseException
        Any error or interruption (KeyboardInterrupt) during the time loop carries the
        levels finished so far as ``exc.partial_result`` (a :class:`Result` with
        ``completed`` set) before it propagates.

    Examples
    --------
    >>> import vemwear
    >>> mesh = vemwear.tag_rectangle(vemwear.rectangle_squares((2.0, 1.0), (8, 4)))
    >>> problem = vemwear.Problem(
    ...     mesh, vemwear.Material(lam=4.0, eta=4.0), vemwear.TimeGrid.uniform(1.0, 8),
    ...     f1=(0.0, -0.06), g=0.1, mu=0.2, kappa=2.0, v_star=(1.0, 0.0),
    ... )
    >>> result = vemwear.simulate(problem)  # condensed semismooth Newton
    >>> result.wear.shape  # (levels, contact nodes)
    (9, 8)
    >>> print(f"{result.wear[-1].max():.6f}")
    0.056086
    >>> bool(result.residuals.max() <= 1e-10)  # KKT residuals of every step
    True
    >>> uzawa = vemwear.simulate(problem, "uzawa")
    >>> bool(abs(uzawa.wear - result.wear).max() < 1e-8)
    True
    """
    keep_freed_memory()  # as the command line does: arrays reuse freed memory
    opts = SolverOptions(method=solver) if isinstance(solver, str) else solver
    L = len(problem.time.t)
    if isinstance(store, str):
        if store not in ("all", "final"):
            raise ValueError(f"store must be 'all', 'final' or a list of times, got {store!r}")
        u_levels = np.arange(L) if store == "all" else np.array([L - 1])
    else:
        u_levels = problem.time.index(store)
    plan = StoragePlan.make(L, u_levels, every)
    sink = MemorySink(problem, plan, opts)
    start = None
    if resume is not None:
        if every != 1 or resume.levels is None or len(resume.levels) != len(resume.t):
            raise ValueError("resume: needs results that keep every level (every = 1)")
        start = _restart(sink.result, resume, problem)
    elif initial_wear is not None:
        w0 = np.array(initial_wear, dtype=float)
        if w0.shape != (sink.result.contact_nodes.size,):
            raise ValueError(
                f"initial_wear must have one value per contact node "
                f"({sink.result.contact_nodes.size}), got shape {w0.shape}"
            )
        start = LoopState(0, w0)
    try:
        run_levels(
            problem,
            opts,
            sink,
            plan,
            start=start,
            progress=progress,
            recover_block=recover_block,
            callback=callback,
            timings=sink.result.timings,
        )
    except BaseException as exc:
        state: LoopState | None = getattr(exc, "loop_state", None)
        done = state.complete_upto if state is not None else sink.result.completed
        exc.partial_result = _truncate(sink.result, done)  # type: ignore[attr-defined]
        raise
    sink.result.completed = L
    return sink.result


class MemorySink:
    """A :class:`~vemwear.simulate.stream.LevelSink` that fills a :class:`Result`."""

    def __init__(self, problem: Problem, plan: StoragePlan, opts: SolverOptions) -> None:
        d = problem.discrete
        K, m, nv = len(plan.levels), d.system.m, problem.mesh.n_points
        self.row, self.slot = plan.slots()
        self._rows = self.row.tolist()  # Python ints: read at every level
        # the result's arrays are written once and handed back: 4 KB pages fault steadily
        self.result = Result(
            problem=problem,
            t=np.array(problem.time.t[plan.levels]),
            points=problem.mesh.points.copy(),
            u=small_zeros((len(plan.u_levels), nv, d.dim)),
            contact_nodes=d.contact.nodes.copy(),
            contact_s=d.contact.s.copy(),
            contact_points=d.contact.points.copy(),
            wear=small_zeros((K, m)),
            u_nu=small_zeros((K, m)),
            p_rigid=small_zeros((K, m)),
            p_soft=small_zeros((K, m)),
            iterations=small_zeros(K, dtype=np.int64),
            residuals=small_zeros((K, 3)),
            u_levels=np.searchsorted(plan.levels, plan.u_levels).astype(np.int64),
            solver={"method": opts.method, "tol": opts.tol, "backend": opts.backend},
            completed=0,
            levels=plan.levels.copy(),
            forces=small_zeros((K, len(d.force_parts), d.dim)),
            dofs=small_zeros((len(plan.u_levels), d.n_dof)) if problem.order > 1 else None,
        )

    def level(self, n: int, w: NDArray[np.float64], solution: StepSolution) -> None:
        r, out = self._rows[n], self.result
        if r < 0:
            return
        out.wear[r], out.u_nu[r] = w, solution.u_nu
        out.p_rigid[r], out.p_soft[r] = solution.p_rigid, solution.p_soft
        out.iterations[r] = solution.iterations
        out.residuals[r] = [solution.residuals[k] for k in RESIDUAL_NAMES]
        if solution.forces is not None and out.forces is not None:
            out.forces[r] = solution.forces

    def displacement(
        self, n: int, u: NDArray[np.float64], residuals: NDArray[np.float64] | None
    ) -> None:
        dest = self.result.u[self.slot[n]]
        if not np.may_share_memory(u, dest):  # not written in place already (a bounds test)
            dest[...] = u
        if residuals is not None and self.row[n] >= 0:
            self.result.residuals[self.row[n]] = residuals

    def displacement_rows(self, levels: list[int]) -> NDArray[np.float64] | None:
        """The rows of ``u`` of these stored levels as one (k, n_dofs) array, when they
        are consecutive and hold every dof (k = 1): the loop writes them in place."""
        out = self.result
        if out.dofs is not None or not levels:
            return None
        first = int(self.slot[levels[0]])
        if list(self.slot[levels]) != list(range(first, first + len(levels))):
            return None
        return out.u[first : first + len(levels)].reshape(len(levels), -1)

    def dofs(self, n: int, u: NDArray[np.float64]) -> None:
        """Every dof of the displacement at level n (spaces of order k > 1)."""
        if self.result.dofs is not None:
            self.result.dofs[self.slot[n]] = u

    def checkpoint(self, state: LoopState) -> None:
        self.result.completed = state.complete_upto


def _truncate(r: Result, c: int) -> Result:
    """The partial result: levels ``< c`` are kept, the later ones set to zero
    (a level whose displacement block was not recovered yet may hold values)."""
    levels = r.levels if r.levels is not None else np.arange(len(r.wear))
    keep = r.u_levels < c
    arrays = {
        k: getattr(r, k).copy()
        for k in ("wear", "u_nu", "p_rigid", "p_soft", "iterations", "residuals", "forces")
        if getattr(r, k) is not None
    }
    for a in arrays.values():
        a[levels >= c] = 0
    dofs = None if r.dofs is None else r.dofs[keep].copy()
    return replace(
        r,
        u=r.u[keep].copy(),
        u_levels=r.u_levels[keep].copy(),
        completed=c,
        dofs=dofs,
        **arrays,
    )


def _restart(out: Result, prev: Result, problem: Problem) -> LoopState:
    """Copy the finished levels of ``prev`` into ``out``; the state to go on from."""
    d = problem.discrete
    c = int(prev.completed)
    if len(prev.t) != len(out.t) or not np.array_equal(prev.t, out.t):
        raise ValueError("resume: the partial result has another time grid")
    if prev.wear.shape[1] != out.wear.shape[1] or not np.array_equal(
        prev.contact_nodes, out.contact_nodes
    ):
        raise ValueError("resume: the partial result has other contact nodes (another mesh?)")
    if c <= 0:
        return LoopState(0, np.zeros(out.wear.shape[1]))
    for name in ("wear", "u_nu", "p_rigid", "p_soft", "iterations", "residuals", "forces"):
        if getattr(prev, name) is not None and getattr(out, name) is not None:
            getattr(out, name)[:c] = getattr(prev, name)[:c]
    slot = -np.ones(len(out.t), dtype=np.int64)
    slot[out.u_levels] = np.arange(len(out.u_levels))
    if prev.dofs is None:  # the earlier levels' dofs are lost: keep the vertex values only
        out.dofs = None
    for j, lv in enumerate(prev.u_levels):
        if lv < c and slot[lv] >= 0:
            out.u[slot[lv]] = prev.u[j]
            if out.dofs is not None and prev.dofs is not None:
                out.dofs[slot[lv]] = prev.dofs[j]
    missing = [int(lv) for lv in out.u_levels if lv < c and lv not in set(prev.u_levels.tolist())]
    if missing:
        raise ValueError(
            f"resume: the partial result lacks the displacement at levels {missing[:5]}"
        )
    out.completed = c
    if c == len(out.t):
        return LoopState(c, out.wear[-1].copy())
    w = d.next_wear(c - 1, out.wear[c - 1], out.p_soft[c - 1], out.p_rigid[c - 1])
    u_last = None
    if slot[c - 1] >= 0 and out.u[slot[c - 1]].size == d.n_dof:
        # the stored vertex values are all the dofs for k = 1 only (k = 2: no guess of u)
        u_last = out.u[slot[c - 1]].ravel()[d.free]
    guess = StepSolution(
        u=u_last,
        u_nu=out.u_nu[c - 1] - d.offset,  # the solver's unknown y = N_f u_f
        p_rigid=out.p_rigid[c - 1].copy(),
        p_soft=out.p_soft[c - 1].copy(),
        iterations=0,
        residuals={},
    )
    return LoopState(c, w, guess)
