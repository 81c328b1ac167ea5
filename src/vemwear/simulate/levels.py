"""The time loop of the fully discrete scheme (paper 3.21-3.23), streaming its levels.

:func:`run_levels` solves the step problem (3.21) of each level with ``w^n`` fixed,
hands the level to a :class:`~vemwear.simulate.stream.LevelSink`, and updates the
wear by the left rectangle rule (3.22). With the condensed Newton solver, a
piecewise-linear law and a constant load, levels come in runs on one piece of the
step problem, certified together (:mod:`vemwear.solvers.pieces`). It keeps only the
state of the last level (:class:`~vemwear.simulate.stream.LoopState`), so its memory
does not depend on the number of levels. Every ``checkpoint`` seconds it asks the
sink to make the levels so far durable together with that state; a run started again
from the state gives the same numbers, bitwise, as one that never stopped.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from numpy.typing import NDArray

from ..solvers import StepSolution
from ..solvers.protocol import BatchStepSolver, StepSolver
from ..solvers.system import ConvergenceError, StepData, check_converged, kkt_residuals_block
from ..solvers.threads import solver_threads
from .stream import LevelSink, LoopState, Pending, StoragePlan

if TYPE_CHECKING:
    from .options import SolverOptions
    from .problem import Problem

__all__ = [
    "RECOVER_ENTRIES",
    "RESIDUAL_NAMES",
    "WearOverflowError",
    "recover_block_size",
    "run_levels",
]

#: The KKT residuals of every step, in the order of the result arrays.
RESIDUAL_NAMES = ("equilibrium", "feasibility", "complementarity")

#: Entries of one block of recovered displacements (2^20 doubles, 8 MB): small problems
#: recover all their stored levels in one block solve, large ones 32 levels at a time.
RECOVER_ENTRIES = 2**20


def recover_block_size(n_free: int, n_stored: int) -> int:
    """Stored levels whose displacements one block solve recovers: as many as fit in
    :data:`RECOVER_ENTRIES` (all of them for small problems), at least 32. One call
    instead of several saves the solver's fixed cost per call (PARDISO: 0.1-0.2 ms at
    1k unknowns, as much as a dozen more columns)."""
    return max(32, min(n_stored, RECOVER_ENTRIES // max(n_free, 1)))


# OpenBLAS's pools stay at one thread for the whole run, not only around the solver's
# kernels: a pool woken by any NumPy product spins against MKL's threads (PARDISO) on
# a small machine and slows them down (benchmarks/bench_threads.py shows the stalls).
@solver_threads()
def run_levels(
    problem: Problem,
    opts: SolverOptions,
    sink: LevelSink,
    plan: StoragePlan,
    *,
    start: LoopState | None = None,
    progress: bool = False,
    recover_block: int | None = None,
    checkpoint: float = 0.0,
    callback: Callable[[int, StepSolution], None] | None = None,
    timings: dict[str, float] | None = None,
) -> LoopState:
    """Solve the levels ``start.completed, ..., L - 1`` and hand each to ``sink``.

    Parameters
    ----------
    problem : Problem
        The problem.
    opts : SolverOptions
        The step solver.
    sink : LevelSink
        Receives every level, the recovered displacements and the checkpoints.
    plan : StoragePlan
        The levels whose displacement is recovered (``plan.u_levels``).
    start : LoopState, optional
        Go on from this state (a checkpoint) instead of level 0.
    progress : bool
        Show a progress bar.
    recover_block : int, optional
        The condensed solver recovers displacements in blocks of this many stored
        levels, at fixed positions among them, so that a resumed run recovers the same
        blocks (and gets bitwise the same numbers). Default:
        :func:`recover_block_size` of the problem and the plan.
    checkpoint : float
        Seconds between calls of ``sink.checkpoint`` (0: never during the loop).
    callback : callable, optional
        ``callback(n, solution)`` after each level.
    timings : dict, optional
        Filled with the wall times of assembly, setup (the step solver's
        factorization), the smallness estimate when one was made, and the loop, as they
        were spent on the problem's discretization (a diagnostic may have asked for
        the first two before the run); ``total`` is assembly + setup + loop.

    Returns
    -------
    LoopState
        The state after the last level.

    Raises
    ------
    ConvergenceError
        If a step does not reach the tolerance (the message names the level).
    WearOverflowError
        If the wear update gives non-finite values (a ConvergenceError naming the level).
    BaseException
        Any error or interruption carries the state of the finished levels as
        ``exc.loop_state`` before it propagates.
    """
    timings = {} if timings is None else timings
    d = problem.discrete
    sysm = d.system
    step_solver: StepSolver = d.step_solver(opts)
    # the phases this run spent, also when a diagnostic asked for them before it; none
    # when an earlier run in this process did (its factorization reused)
    timings.update({"assembly": 0.0, "setup": 0.0})
    timings.update(d.take_timings())
    for k, v in step_solver.setup_timings.items():
        timings[f"setup_{k}"] = v

    tgrid = problem.time.t
    L = len(tgrid)
    slot = plan.slots()[1].tolist()  # Python ints: read at every level
    if recover_block is None:
        recover_block = recover_block_size(sysm.n_free, len(plan.u_levels))
    state = start if start is not None else LoopState(0, np.zeros(sysm.m))
    # (completed, w of the next level, warm start): replaced as one tuple, so that a
    # signal arriving between two statements never sees a half-updated state
    now: tuple[int, Any, StepSolution | None] = (state.completed, state.w, state.guess)
    batch = step_solver.batch
    # the block recovery and the prediction of the condensed Newton (batch solvers only)
    batched = cast(BatchStepSolver, step_solver)
    # (level, its w, its step data, its solution) awaiting a block of back-substitutions
    pending: list[tuple[int, Any, StepData, StepSolution]] = [
        (p.level, p.w, d.step_data(p.level, p.w), p.solution) for p in state.pending
    ]
    # the displacements of a block, read before the next block overwrites them
    block = np.empty((sysm.n_free, 0), order="F")

    # sinks with a ``dofs`` method also get every dof of a higher-order space (k = 2:
    # the edge and cell means besides the vertex values), e.g. for the ParaView output
    put_dofs = getattr(sink, "dofs", None) if d.space.order > 1 else None
    # sinks that keep the displacements in memory take a block's rows in place
    sink_rows = getattr(sink, "displacement_rows", None)

    def give(n_: int, full: Any, res: Any) -> None:
        sink.displacement(n_, d.space.vertex_values(full), res)
        if put_dofs is not None:
            put_dofs(n_, full)

    def flush() -> None:
        nonlocal block
        if not pending:
            return
        if not batch:  # a resumed run whose pending levels another solver left
            for n_, _, st, so in pending:
                full_sol = step_solver.solve(st, so, recover=True)
                assert full_sol.u is not None  # recovered
                res = np.array([full_sol.residuals[k] for k in RESIDUAL_NAMES])
                give(n_, d.full_dofs(full_sol.u, st.t), res)
            pending.clear()
            return
        if block.shape[1] < len(pending):
            block = np.empty((sysm.n_free, max(recover_block, len(pending))), order="F")
        steps = [st for _, _, st, _ in pending]
        p_rigids = [so.p_rigid for *_, so in pending]
        p_softs = [so.p_soft for *_, so in pending]
        ys = [so.u_nu for *_, so in pending]
        X = batched.recover_many(steps, p_rigids, p_softs, out=block[:, : len(pending)], ys=ys)
        # feasibility and complementarity over the scale of the normal displacements
        y_refs = batched.displacement_scales(steps, ys, p_rigids, p_softs)
        fulls = kkt_residuals_block(sysm, steps, X, p_rigids, y_refs, opts.tol)
        rows = sink_rows([n_ for n_, *_ in pending]) if sink_rows is not None else None
        U = d.full_dofs_block(X, [st.t for _, _, st, _ in pending], out=rows)
        for j, (n_, _, st, so) in enumerate(pending):
            full = fulls[j]
            check_converged(full, opts.tol, st, "recovery of the displacement", so.iterations)
            res = np.array([full[k] for k in RESIDUAL_NAMES])
            give(n_, U[j], res)
        pending.clear()

    def current() -> LoopState:
        c, w_, g_ = now
        return LoopState(c, w_, g_, [Pending(n_, wn, so) for n_, wn, _, so in pending if n_ < c])

    # A constant load and a solver that predicts (a piecewise-linear law): runs of
    # levels on one piece of the step problem, certified together (solvers/pieces.py),
    # as long as the friction stays the same; each level has the same numbers as in
    # any other run, so a resumed run stays bitwise the same
    # (not with wear on the whole pressure: a run's wear update takes p_soft alone)
    runs = d.constant_load and d.wear_total is None and step_solver.predicts
    predict: Any = batched.predict if runs else None
    # (step data, solution, w^{n+1} or None) of the predicted levels not yet handed on
    ahead: deque[tuple[StepData, StepSolution, Any]] = deque()

    def predicted(n_: int, w_: Any, guess_: StepSolution) -> None:
        first = d.step_data(n_, w_)
        if (
            d.system.rows > 1
            and n_ + 1 < L
            and not np.array_equal(d.friction(float(tgrid[n_ + 1])), first.fric)
        ):
            return  # a turning v*: the friction changes at the next level, no run to make
        ws = [w_]

        def advance(p_soft: Any) -> Any:
            n_next = n_ + len(ws)
            # v* at t_{n_next - 1}; runs are made only when p_soft alone wears
            ws.append(d.next_wear(n_next - 1, ws[-1], p_soft, None))
            if not d.steady_sliding and not np.array_equal(
                d.friction(float(tgrid[n_next])), first.fric
            ):
                return None  # the friction changes: the run ends here
            return d.step_wear(ws[-1])

        run = predict(guess_, first, advance, L - n_, tgrid)
        if run:
            steps, sols = zip(*run, strict=True)
            forces = d.resultants_run(steps, sols, step_solver)
            for sol_, f in zip(sols, forces, strict=True):
                sol_.forces = f
            # w^{n+1} of every level but the run's last (ws holds those of levels tried)
            ahead.extend(zip(steps, sols, [*ws[1:], None], strict=False))

    t2 = time.perf_counter()
    last_checkpoint = time.monotonic()
    try:
        levels: Iterable[int] = range(now[0], L)
        if progress:  # a disabled bar still costs 0.1 ms to make
            from tqdm.auto import tqdm  # here: tqdm.auto imports asyncio (30 ms)

            levels = tqdm(levels, desc="time levels", unit="lvl", leave=False)
        for n in levels:
            _, w, guess = now
            store_here = slot[n] >= 0
            if predict is not None and guess is not None and not ahead:
                predicted(n, w, guess)
            if ahead:  # forces set already
                step, sol, w_after = ahead.popleft()
                sink.level(n, w, d.physical(sol))
            else:
                w_after = None
                step = d.step_data(n, w)
                sol = step_solver.solve(step, guess, recover=store_here and not batch)
                sink.level(n, w, d.physical(sol, step, step_solver))
            if store_here:
                if sol.u is not None:
                    give(n, d.full_dofs(sol.u, step.t), None)
                else:
                    pending.append((n, w, step, sol))
            if callback is not None:
                callback(n, sol)
            w_next = w
            if n + 1 < L:  # wear update (3.22)
                w_next = d.next_wear(n, w, sol.p_soft, sol.p_rigid) if w_after is None else w_after
                if not _finite(w_next):
                    raise _wear_overflow(problem, n, w_next)
            now = (n + 1, w_next, sol)
            # blocks at fixed positions among the stored levels: a resumed run recovers
            # the same blocks, so its results are bitwise the same
            if pending and slot[n] >= 0 and slot[n] % recover_block == recover_block - 1:
                flush()
            if checkpoint > 0 and time.monotonic() - last_checkpoint >= checkpoint:
                sink.checkpoint(current())
                last_checkpoint = time.monotonic()
        flush()
    except BaseException as exc:
        timings["time_loop"] = time.perf_counter() - t2
        exc.loop_state = current()  # type: ignore[attr-defined]
        raise
    timings["time_loop"] = time.perf_counter() - t2
    timings["total"] = timings["assembly"] + timings["setup"] + timings["time_loop"]
    return LoopState(now[0], now[1], now[2], [])


def _finite(w: NDArray[np.float64]) -> bool:
    """Whether every entry of ``w`` is finite: its sum is (one reduction to a scalar,
    cheaper at every level than the array of ``np.isfinite``), or, when the sum of
    finite entries overflows, each entry."""
    return math.isfinite(w.sum()) or bool(np.isfinite(w).all())


class WearOverflowError(ConvergenceError):
    """The wear update gave non-finite values (kappa |v*| p(u_nu - w) overflows)."""


def _wear_overflow(problem: Problem, n: int, w: NDArray[np.float64]) -> WearOverflowError:
    """The error of a wear ``w^{n+1}`` that is not finite, naming the level and a node."""
    t = problem.time.t
    a = int(np.flatnonzero(~np.isfinite(w))[0])
    x = ", ".join(f"{c:.4g}" for c in problem.contact.points[a])
    return WearOverflowError(
        f"the wear is not finite at time level {n + 1} (t = {t[n + 1]:g}): {w[a]:g} at "
        f"contact node {a} (x = ({x})) after the update of level {n}; the data overflow "
        "(check the scale of [contact] kappa, v_star and the compliance law)"
    )
