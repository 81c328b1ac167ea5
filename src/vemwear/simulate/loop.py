"""The fully discrete scheme (paper 3.21-3.23): step problems and the wear update."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from tqdm.auto import tqdm

from ..solvers import SOLVERS, NewtonOptions, StepSolution, UzawaOptions, kkt_residuals
from ..solvers.system import check_converged
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
            raise ValueError(f"solver: unknown method {self.method!r}; expected one of {list(SOLVERS)}")
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

    Attributes
    ----------
    t : (L,) time levels
    points : (n_points, 2) vertex coordinates
    u : (S, n_points, 2) displacement at the stored levels ``u_levels`` (all by default)
    u_levels : (S,) indices of the levels whose displacement is stored
    contact_nodes : (m,) vertex ids on Gamma_C, ordered along it
    contact_s : (m,) arc length along Gamma_C; contact_points : (m, 2)
    wear, u_nu, penetration, lam, p : (L, m) at contact nodes; penetration = u_nu - wear,
        lam and p are the pressures of the rigid and the soft layer
    iterations : (L,) solver iterations per level
    residuals : (L, 3) KKT residuals (equilibrium, feasibility, complementarity)
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
    lam: NDArray[np.float64]
    p: NDArray[np.float64]
    iterations: NDArray[np.int64]
    residuals: NDArray[np.float64]
    u_levels: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, np.int64))
    solver: dict[str, Any] = field(default_factory=dict)
    timings: dict[str, float] = field(default_factory=dict)

    RESIDUAL_NAMES = ("equilibrium", "feasibility", "complementarity")

    @property
    def penetration(self) -> NDArray[np.float64]:
        return self.u_nu - self.wear

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
    callback: Callable[[int, StepSolution], None] | None = None,
) -> Result:
    """Run the fully discrete scheme (Problem 3.3) on the problem's time grid.

    At each level ``n``: solve the step problem (3.21) with ``w^n`` fixed, warm-started
    from level ``n - 1``; then ``w^{n+1} = w^n + k_n alpha(t_n) p(u_nu^n - w^n)``
    (left rectangle rule, 3.22), with ``w^0 = 0`` (3.23).

    The contact quantities are kept at every level. The full displacement costs a
    back-substitution per level with the condensed solver, so ``store`` chooses
    where it is recovered: ``"all"``, ``"final"``, or a list of times (levels).

    Raises
    ------
    ConvergenceError
        If a step does not reach the tolerance (the message names the level).
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
    slot = -np.ones(L, dtype=np.int64)
    slot[u_levels] = np.arange(len(u_levels))
    U = np.zeros((len(u_levels), nv, 2))
    W, Y, LAM, P = (np.zeros((L, m)) for _ in range(4))
    iters = np.zeros(L, dtype=np.int64)
    res = np.zeros((L, 3))
    w = np.zeros(m)
    guess: StepSolution | None = None
    t2 = time.perf_counter()
    # with the condensed solver, full displacements are recovered in blocks of levels
    batch = hasattr(step_solver, "recover_many")
    pending: list[tuple[int, object, StepSolution]] = []

    def flush() -> None:
        if not pending:
            return
        X = step_solver.recover_many([st for _, st, _ in pending], [so.lam for _, _, so in pending],
                                     [so.p for _, _, so in pending])
        for j, (n_, st, so) in enumerate(pending):
            u_free = X[:, j]
            U[slot[n_]] = d.full_displacement(u_free)
            full = kkt_residuals(sysm, st, u_free, so.lam)  # type: ignore[arg-type]
            check_converged(full, opts.tol, st, "recovery of the displacement", so.iterations)  # type: ignore[arg-type]
            res[n_] = [full[k] for k in Result.RESIDUAL_NAMES]
        pending.clear()

    bar = tqdm(range(L), desc="time levels", unit="lvl", disable=not progress, leave=False)
    for n in bar:
        step = d.step_data(n, w)
        store_here = bool(slot[n] >= 0)
        sol = step_solver.solve(step, guess, recover=store_here and not batch)
        W[n], Y[n], LAM[n], P[n] = w, sol.u_nu, sol.lam, sol.p
        iters[n] = sol.iterations
        res[n] = [sol.residuals[k] for k in Result.RESIDUAL_NAMES]
        if store_here:
            if sol.u is not None:
                U[slot[n]] = d.full_displacement(sol.u)
            else:
                pending.append((n, step, sol))
                if len(pending) == recover_block:
                    flush()
        if callback is not None:
            callback(n, sol)
        if n + 1 < L:  # wear update (3.22), left rectangle rule
            k_n = tgrid[n + 1] - tgrid[n]
            w = w + k_n * d.alpha(step.t) * sol.p
        guess = sol
    flush()
    timings["time_loop"] = time.perf_counter() - t2
    timings["total"] = time.perf_counter() - t0
    return Result(
        problem=problem, t=np.array(tgrid), points=problem.mesh.points.copy(), u=U,
        contact_nodes=d.contact.nodes.copy(), contact_s=d.contact.s.copy(),
        contact_points=d.contact.points.copy(), wear=W, u_nu=Y, lam=LAM, p=P,
        iterations=iters, residuals=res, u_levels=u_levels,
        solver={"method": opts.method, "tol": opts.tol, "backend": opts.backend},
        timings=timings,
    )
