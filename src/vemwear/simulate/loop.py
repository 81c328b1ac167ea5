"""The fully discrete scheme (paper 3.21-3.23): step problems and the wear update."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from tqdm.auto import tqdm

from ..solvers import SOLVERS, NewtonOptions, StepSolution, UzawaOptions, kkt_residuals
from ..solvers.system import StepData, check_converged
from .problem import Problem


@dataclass(frozen=True)
class SolverOptions:
    """Which solver and how tightly.

    Parameters
    ----------
    method : {"newton", "newton-full", "uzawa"}
        ``newton``: semismooth Newton condensed on Gamma_C, one factorization of K
        for the whole run (default). ``newton-full``: Newton on all dofs, a new
        factorization per iteration (the plain path). ``uzawa``: the paper's
        Uzawa iteration with two multipliers.
    tol : float
        Bound on the scaled KKT residuals of every step.
    max_iter : int or None
        Iteration limit per step (default: 100 for Newton, 200000 for Uzawa).
    backend : {"auto", "scipy", "pardiso"}
        Sparse direct solver.
    """

    method: str = "newton"
    tol: float = 1e-10
    max_iter: int | None = None
    backend: str = "auto"

    def __post_init__(self) -> None:
        if self.method not in SOLVERS:
            raise ValueError(
                f"solver: unknown method {self.method!r}; expected one of {list(SOLVERS)}"
            )
        if not (self.tol > 0):
            raise ValueError(f"solver: tol must be positive, got {self.tol}")
        if self.max_iter is not None and self.max_iter < 1:
            raise ValueError(f"solver: max_iter must be >= 1, got {self.max_iter}")

    def build(self, system):
        cls = SOLVERS[self.method]
        kw: dict[str, Any] = {"tol": self.tol, "backend": self.backend}
        if self.max_iter is not None:
            kw["max_iter"] = self.max_iter
        if self.method == "uzawa":
            return cls(system, UzawaOptions(**kw))
        return cls(system, NewtonOptions(**kw))


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
        Normal displacement at the contact nodes (``penetration = u_nu - wear``).
    p_rigid : (L, m) ndarray
        Pressure of the rigid layer (the multiplier of u_nu <= g).
    p_soft : (L, m) ndarray
        Pressure of the soft layer, p(u_nu - w).
    iterations : (L,) ndarray of int
        Solver iterations per level.
    residuals : (L, 3) ndarray
        KKT residuals (equilibrium, feasibility, complementarity) per level.
    u_levels : (S,) ndarray of int
        Indices of the levels whose displacement is stored.
    completed : int
        Number of finished levels (``L`` unless the run was interrupted; -1 means L).
    solver : dict
        The solver options the levels were computed with.
    timings : dict
        Wall times of the stages, in seconds.
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
    solver: dict[str, Any] = field(default_factory=dict)
    timings: dict[str, float] = field(default_factory=dict)

    RESIDUAL_NAMES = ("equilibrium", "feasibility", "complementarity")

    @property
    def penetration(self) -> NDArray[np.float64]:
        return self.u_nu - self.wear

    def __post_init__(self) -> None:
        if self.completed < 0:
            self.completed = len(self.t)

    @property
    def is_partial(self) -> bool:
        """True for the levels-so-far of an interrupted run."""
        return self.completed < len(self.t)

    def level(self, t: float) -> int:
        """Index of the level at time t."""
        return int(self.problem.time.index([t])[0])

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
    recover_block: int = 32,
    resume: Result | None = None,
    callback: Callable[[int, StepSolution], None] | None = None,
) -> Result:
    """Run the fully discrete scheme (Problem 3.3) on the problem's time grid.

    At each level ``n``: solve the step problem (3.21) with ``w^n`` fixed, warm-started
    from level ``n - 1``; then ``w^{n+1} = w^n + k_n alpha(t_n) p(u_nu^n - w^n)``
    (left rectangle rule, 3.22), with ``w^0 = 0`` (3.23).

    The contact quantities are kept at every level. The full displacement costs a
    back-substitution per level with the condensed solver, so ``store`` chooses
    where it is recovered: ``"all"``, ``"final"``, or a list of times (levels).

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
    recover_block : int
        Number of levels whose displacements the condensed solver recovers together.
    callback : callable, optional
        ``callback(n, step_solution)`` after each level ``n``.
    resume : Result, optional
        A partial result of the same problem (``completed < len(t)``); the run goes on
        from its first unfinished level, warm-started as an uninterrupted run would
        be, so the result is the same.

    Raises
    ------
    ConvergenceError
        If a step does not reach the tolerance (the message names the level).
    BaseException
        Any error or interruption (KeyboardInterrupt) during the time loop carries the
        levels finished so far as ``exc.partial_result`` (a :class:`Result` with
        ``completed`` set) before it propagates.
    """
    opts = SolverOptions(method=solver) if isinstance(solver, str) else solver
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    d = problem.discrete
    sysm = d.system
    timings["assembly"] = time.perf_counter() - t0
    t1 = time.perf_counter()
    step_solver = opts.build(sysm)
    timings["setup"] = time.perf_counter() - t1
    for k, v in getattr(getattr(step_solver, "factor", None), "timings", {}).items():
        timings[f"setup_{k}"] = v

    tgrid = problem.time.t
    L, m = len(tgrid), sysm.m
    nv = problem.mesh.n_points
    if isinstance(store, str):
        if store not in ("all", "final"):
            raise ValueError(f"store must be 'all', 'final' or a list of times, got {store!r}")
        u_levels = np.arange(L) if store == "all" else np.array([L - 1])
    else:
        u_levels = np.unique(problem.time.index(store))
    out = Result(
        problem=problem,
        t=np.array(tgrid),
        points=problem.mesh.points.copy(),
        u=np.zeros((len(u_levels), nv, 2)),
        contact_nodes=d.contact.nodes.copy(),
        contact_s=d.contact.s.copy(),
        contact_points=d.contact.points.copy(),
        wear=np.zeros((L, m)),
        u_nu=np.zeros((L, m)),
        p_rigid=np.zeros((L, m)),
        p_soft=np.zeros((L, m)),
        iterations=np.zeros(L, dtype=np.int64),
        residuals=np.zeros((L, 3)),
        u_levels=u_levels,
        solver={"method": opts.method, "tol": opts.tol, "backend": opts.backend},
        timings=timings,
        completed=0,
    )
    slot = -np.ones(L, dtype=np.int64)
    slot[u_levels] = np.arange(len(u_levels))
    w = np.zeros(m)
    guess: StepSolution | None = None
    if resume is not None:
        w, guess = _restart(out, resume, slot, d)

    # with the condensed solver, full displacements are recovered in blocks of levels
    batch = hasattr(step_solver, "recover_many")
    pending: list[tuple[int, StepData, StepSolution]] = []

    def flush() -> None:
        if not pending:
            return
        X = step_solver.recover_many(
            [st for _, st, _ in pending],
            [so.p_rigid for _, _, so in pending],
            [so.p_soft for _, _, so in pending],
        )
        for j, (n_, st, so) in enumerate(pending):
            full = kkt_residuals(sysm, st, X[:, j], so.p_rigid)
            check_converged(full, opts.tol, st, "recovery of the displacement", so.iterations)
            out.u[slot[n_]] = d.full_displacement(X[:, j])
            out.residuals[n_] = [full[k] for k in Result.RESIDUAL_NAMES]
        pending.clear()

    t2 = time.perf_counter()
    try:
        bar = tqdm(
            range(out.completed, L),
            desc="time levels",
            unit="lvl",
            disable=not progress,
            leave=False,
        )
        for n in bar:
            step = d.step_data(n, w)
            store_here = bool(slot[n] >= 0)
            sol = step_solver.solve(step, guess, recover=store_here and not batch)
            out.wear[n], out.u_nu[n] = w, sol.u_nu
            out.p_rigid[n], out.p_soft[n] = sol.p_rigid, sol.p_soft
            out.iterations[n] = sol.iterations
            out.residuals[n] = [sol.residuals[k] for k in Result.RESIDUAL_NAMES]
            if store_here:
                if sol.u is not None:
                    out.u[slot[n]] = d.full_displacement(sol.u)
                else:
                    pending.append((n, step, sol))
                    # blocks at fixed positions among the stored levels: a resumed run
                    # recovers the same blocks, so its results are bitwise the same
                    if slot[n] % recover_block == recover_block - 1:
                        flush()
            if callback is not None:
                callback(n, sol)
            if n + 1 < L:  # wear update (3.22), left rectangle rule
                w = w + (tgrid[n + 1] - tgrid[n]) * d.alpha(step.t) * sol.p_soft
            guess = sol
            if not pending:  # every level so far is complete, displacements included
                out.completed = n + 1
        flush()
        out.completed = L
    except BaseException as exc:
        # levels whose displacement block is not recovered yet count as unfinished
        timings["time_loop"] = time.perf_counter() - t2
        exc.partial_result = _truncate(out)  # type: ignore[attr-defined]
        raise
    timings["time_loop"] = time.perf_counter() - t2
    timings["total"] = time.perf_counter() - t0
    return out


def _truncate(r: Result) -> Result:
    """The partial result: levels ``< completed`` are kept, the later ones set to zero
    (a level whose displacement block was not recovered yet may hold values)."""
    c = r.completed
    keep = r.u_levels < c
    arrays = {
        k: getattr(r, k).copy()
        for k in ("wear", "u_nu", "p_rigid", "p_soft", "iterations", "residuals")
    }
    for a in arrays.values():
        a[c:] = 0
    return replace(r, u=r.u[keep].copy(), u_levels=r.u_levels[keep].copy(), **arrays)


def _restart(
    out: Result, prev: Result, slot: NDArray[np.int64], d
) -> tuple[NDArray, StepSolution | None]:
    """Copy the finished levels of ``prev`` into ``out``; return w and the warm start."""
    c = int(prev.completed)
    if len(prev.t) != len(out.t) or not np.array_equal(prev.t, out.t):
        raise ValueError("resume: the partial result has another time grid")
    if prev.wear.shape[1] != out.wear.shape[1] or not np.array_equal(
        prev.contact_nodes, out.contact_nodes
    ):
        raise ValueError("resume: the partial result has other contact nodes (another mesh?)")
    if c <= 0:
        return np.zeros(out.wear.shape[1]), None
    for name in ("wear", "u_nu", "p_rigid", "p_soft", "iterations", "residuals"):
        getattr(out, name)[:c] = getattr(prev, name)[:c]
    for j, lv in enumerate(prev.u_levels):
        if lv < c and slot[lv] >= 0:
            out.u[slot[lv]] = prev.u[j]
    missing = [int(lv) for lv in out.u_levels if lv < c and lv not in set(prev.u_levels.tolist())]
    if missing:
        raise ValueError(
            f"resume: the partial result lacks the displacement at levels {missing[:5]}"
        )
    out.completed = c
    if c == len(out.t):
        return out.wear[-1].copy(), None
    w = (
        out.wear[c - 1]
        + (out.t[c] - out.t[c - 1]) * d.alpha(float(out.t[c - 1])) * out.p_soft[c - 1]
    )
    u_last = None
    if slot[c - 1] >= 0:
        u_last = out.u[slot[c - 1]].ravel()[d.free]
    guess = StepSolution(
        u=u_last,
        u_nu=out.u_nu[c - 1].copy(),
        p_rigid=out.p_rigid[c - 1].copy(),
        p_soft=out.p_soft[c - 1].copy(),
        iterations=0,
        residuals={},
    )
    return w, guess
