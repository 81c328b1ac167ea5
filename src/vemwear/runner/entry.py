"""One run of a configuration file, from the cheap refusals to the outcome.

:func:`run_config` is the library's entry point for a run: ``vemwear run`` calls it
(parse, call, print) and so do the workers of a study. It owns the order in which a
run is checked, so that every refusal is as cheap as it can be:

1. a run holding OUTDIR's lock refuses before the configuration is even read;
2. the rough plan (sizes read from the file alone) refuses before the mesh is built,
   and again with the built mesh's sizes before the time grid is made
   (:func:`vemwear.runner.plan.admit_sizes`);
3. the configuration is validated and built (mesh, time grid, data);
4. the plan of the real mesh refuses before anything is assembled;
5. the output directory is checked and locked, the checkpoint read on ``resume``
   (:func:`vemwear.runner.run.prepare_run`);
6. the warnings (stale temporaries, smallness of Theorem 3.4, overshooting wear steps)
   and the plan's line are said;
7. the levels are solved (or the cycles jumped: ``[time] cycle_jump``; or the mesh
   adapted every few levels: ``[adapt]``, :mod:`vemwear.runner.adaptive`) and the
   outputs written.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ..config import Config
    from ..simulate import Result, SolverOptions
    from ..simulate.adaptive_time import Segment
    from ..simulate.cycles import CycleResult

__all__ = ["LaunchError", "RunOutcome", "overshoot_lines", "run_config"]


class LaunchError(ValueError):
    """A run started in a way that cannot work (several MPI ranks without the petsc
    backend, an option that does not go with the configuration): invalid input."""


@dataclass
class RunOutcome:
    """What :func:`run_config` did.

    Attributes
    ----------
    title : str
        The configuration's title.
    out : Path
        The output directory.
    result : Result or None
        The result (None for a cycle-jump or an adaptive run, a run that was complete
        already, or one whose arrays did not fit in memory).
    cycles : CycleResult or None
        The cycles of a ``[time] cycle_jump`` run.
    segments : list of Segment or None
        The meshes of an ``[adapt]`` run, each with its levels (read back from
        ``result.h5``).
    note : str
        A line about the outcome (complete already; ``result.h5`` only).
    resumed_from : int or None
        The level a resumed run went on from.
    warnings : list of str
        The warnings said before the run.
    seconds : float
        Wall time.
    config : Config or None
        The validated configuration.
    rank : int
        This process's rank in an MPI job (0 outside one); on the other ranks, which
        only took part in rank 0's linear algebra, nothing else is set.
    """

    title: str
    out: Path
    result: Result | None = None
    cycles: CycleResult | None = None
    segments: list[Segment] | None = None
    note: str = ""
    resumed_from: int | None = None
    warnings: list[str] = field(default_factory=list)
    seconds: float = 0.0
    config: Config | None = None
    rank: int = 0


def _solver_options(
    base: SolverOptions, method: str | None, backend: str | None = None
) -> SolverOptions:
    from ..simulate import SolverOptions
    from ..solvers import resolve_backend

    chosen = base.backend if backend is None else backend
    try:
        resolve_backend(chosen)
        if method is None or method == base.method:
            if chosen == base.backend:
                return base
            return SolverOptions(base.method, base.tol, base.max_iter, chosen)
        # keep tol; iteration limits of different methods are not comparable
        return SolverOptions(method=method, tol=base.tol, max_iter=None, backend=chosen)
    except ValueError as exc:
        raise LaunchError(str(exc)) from None


def _config_backend(config: str | os.PathLike[str]) -> str | None:
    """``[solver] backend`` of a configuration file read as plain TOML ("auto" when
    absent), None when the file cannot be read (its run reports why)."""
    import tomllib

    try:
        with open(config, "rb") as f:
            solver = tomllib.load(f).get("solver", {})
    except (OSError, ValueError):
        return None
    backend = solver.get("backend", "auto") if isinstance(solver, dict) else None
    return backend if isinstance(backend, str) else None


def _resumed_bytes(outdir: Path) -> int:
    """The disk that the ``result.h5`` a resumed run goes on writing occupies already."""
    from ..post.stream import STREAM_NAME

    try:
        st = (outdir / STREAM_NAME).stat()
    except OSError:
        return 0
    return min(st.st_size, 512 * st.st_blocks)


def run_config(
    config: str | os.PathLike[str],
    outdir: str | os.PathLike[str],
    *,
    resume: bool = False,
    force: bool = False,
    progress: bool = True,
    solver: str | None = None,
    backend: str | None = None,
    force_size: bool = False,
    say: Callable[[str], None] | None = None,
    warn: Callable[[str], None] | None = None,
) -> RunOutcome:
    """Validate the configuration file ``config``, solve it and write into ``outdir``.

    Parameters
    ----------
    config : path
        The TOML configuration (docs/config.md).
    outdir : path
        The output directory (:mod:`vemwear.runner.outdir` says which it may use).
    resume : bool
        Go on from the checkpoint of a stopped run in ``outdir``.
    force : bool
        Replace the output of an earlier vemwear run in ``outdir``.
    progress : bool
        Show a progress bar.
    solver : str, optional
        Another solver method than the configuration's.
    backend : str, optional
        Another sparse backend than the configuration's. Under an MPI launcher
        (``mpirun -n N``, N > 1) the backend must be ``"petsc"``: every rank calls
        ``run_config``, rank 0 runs the simulation and writes ``outdir``, the other
        ranks take part in its factorization and solves and return an outcome with
        only ``rank`` set (docs/mpi.md).
    force_size : bool
        Run even if the estimated memory or disk exceeds what is available.
    say : callable, optional
        Receives the plan's line (``"TITLE: memory (estimate) ..."``) before the levels
        are solved.
    warn : callable, optional
        Receives the warnings (``"warning: ..."``) and notes as they come.

    Returns
    -------
    RunOutcome

    Raises
    ------
    ConfigError, PlanError, OutputDirError, ResumeError
        A refused run (invalid input), before any solving.
    LaunchError
        Several MPI ranks without the petsc backend, or a backend that is not installed
        or does not go with the solver method.
    ConvergenceError, WornThroughError, KeyboardInterrupt
        A run that stopped; its finished levels are saved (``exc.vemwear_note``).

    Examples
    --------
    A shipped configuration at a small size, run into a fresh directory:

    >>> import tempfile
    >>> from pathlib import Path
    >>> from vemwear import run_config
    >>> from vemwear.examples import config_path
    >>> tmp = Path(tempfile.mkdtemp())
    >>> text = config_path("example_5_2_set1").read_text(encoding="utf-8")
    >>> text = text.replace("divisions = [32, 16]", "divisions = [8, 4]")
    >>> text = text.replace("steps = 64", "steps = 4").replace("= true", "= false")
    >>> _ = (tmp / "small.toml").write_text(text)
    >>> outcome = run_config(tmp / "small.toml", tmp / "out", progress=False)
    >>> len(outcome.result.t), sorted(p.name for p in outcome.out.glob("*.npz"))
    (5, ['result.npz'])
    """
    from ..util.mpi import launched

    job = launched()
    kw: dict[str, Any] = dict(resume=resume, force=force, progress=progress, solver=solver)
    kw.update(backend=backend, force_size=force_size, say=say, warn=warn)
    if job.size == 1:
        return _run_config(config, outdir, **kw)
    requested = backend or _config_backend(config)
    if requested not in (None, "petsc"):
        raise LaunchError(
            f"started as {job.size} MPI ranks, but the solver backend is {requested!r}: "
            "only the petsc backend runs one simulation on several ranks (--backend petsc "
            'or [solver] backend = "petsc"); without it, run vemwear without mpirun'
        )
    from ..solvers.backends.petsc import HINT, available, serve, session

    if not available():
        raise LaunchError(f"backend petsc: {HINT}")
    with session() as root:
        if not root:
            serve()
            return RunOutcome("", Path(outdir).expanduser().absolute(), rank=job.rank)
        return _run_config(config, outdir, **kw)
    raise AssertionError("unreachable")  # pragma: no cover


def _run_config(
    config: str | os.PathLike[str],
    outdir: str | os.PathLike[str],
    *,
    resume: bool,
    force: bool,
    progress: bool,
    solver: str | None,
    backend: str | None,
    force_size: bool,
    say: Callable[[str], None] | None,
    warn: Callable[[str], None] | None,
) -> RunOutcome:
    """:func:`run_config` on one process (rank 0 of an MPI job)."""
    t0 = time.perf_counter()  # the modules of a run are imported in its config phase
    from ..config import load_config
    from .describe import smallness_report
    from .outdir import refuse_locked, stale_temporaries
    from .plan import admit_sizes, check_estimate, estimate_config
    from .run import ResumeError, RunComplete, abandon_run, execute_run, prepare_run
    from .signals import check_stop

    tell = say or (lambda line: None)
    caution = warn or (lambda line: None)
    out = Path(outdir).expanduser()
    refuse_locked(out)
    # on --resume, the disk that result.h5 takes already is not asked for again
    have = _resumed_bytes(out) if resume else 0
    cfg = load_config(config, admit=admit_sizes(out, force_size=force_size, have=have))
    # the phases before the levels, for summary.json: reading and building the
    # configuration (mesh, checks, problem), then the plan and the set-up
    phases = {"config": time.perf_counter() - t0}
    options = _solver_options(cfg.solver, solver, backend)
    if cfg.adapt is not None:
        from ..util.mpi import launched

        if launched().size > 1:
            raise LaunchError(
                f"{config}: [adapt] runs are not split over MPI ranks (each mesh change "
                "would rebuild the distributed factorization); run vemwear without mpirun"
            )
    if cfg.cycles is not None and resume:
        raise ResumeError(
            "--resume: a run with [time] cycle_jump is not checkpointed; run it again"
        )
    outcome = RunOutcome(cfg.title, out.absolute(), config=cfg)
    stale = [] if force else stale_temporaries(out)
    if stale:
        outcome.warnings.append(
            f"{len(stale)} temporary file(s) of killed runs in or next to {outdir} (e.g. "
            f"{stale[0].name}); remove them with: vemwear clean {outdir}"
        )
        caution(f"warning: {outcome.warnings[-1]}")
    check_stop()  # safe points between the phases of the set-up
    t1, before = time.perf_counter(), _phases_done(cfg)
    est = estimate_config(cfg)
    if not force_size:
        check_estimate(est, out, str(config), have=have)
    try:
        plan = prepare_run(
            cfg,
            Path(config),
            out,
            options,
            force=force,
            resume=resume,
            solver_flag=solver,
            backend_flag=backend,
        )
    except RunComplete as done:
        outcome.note = str(done)
        outcome.seconds = time.perf_counter() - t0
        return outcome
    outcome.out = plan.out
    try:  # assembles and factorizes (the run's set-up): may fail before any level
        check_stop()
        if plan.note:
            caution(plan.note)
        if plan.solver.backend == "petsc" and cfg.adapt is None:
            # K kept by the ranks, not on rank 0 (docs/mpi.md); an adaptive run reuses
            # factorizations by a digest of the whole K, and holds it
            cfg.problem.discretize(distributed=True)
        _, small = smallness_report(cfg.problem, plan.solver)
        for w in [small, *overshoot_lines(cfg)]:
            if w:
                outcome.warnings.append(w)
                caution(f"warning: {w}")
        tell(f"{cfg.title}: " + ", ".join(f"{k} {v}" for k, v in est.rows()))
        # the plan: this block but the assembly, set-up and estimate (their own phases)
        spent = _phases_done(cfg) - before
        phases["plan"] = max(time.perf_counter() - t1 - spent, 0.0)
        check_stop()
    except BaseException:
        abandon_run(plan)
        raise
    if cfg.cycles is not None:
        from .cycles import execute_cycles

        _, outcome.cycles = execute_cycles(plan, progress=progress)
    elif cfg.adapt is not None:
        from .adaptive import execute_adaptive

        outcome.segments = execute_adaptive(plan, progress=progress)
        if plan.state is not None:
            outcome.resumed_from = int(plan.state.completed)
    else:
        result = execute_run(plan, progress=progress, phases=phases, start=t0)
        if isinstance(result, str):  # the arrays do not fit in memory: result.h5 only
            outcome.note = result
        else:
            outcome.result = result
        if plan.state is not None:
            outcome.resumed_from = int(plan.state.completed)
    outcome.seconds = time.perf_counter() - t0
    return outcome


def _phases_done(cfg: Any) -> float:
    """Seconds of the phases that the discretization timed itself (assembly, set-up,
    estimate) and not yet handed to a run; 0 before it exists."""
    d = cfg.problem.__dict__.get("discrete")
    return float(sum(d.timings.values())) if d is not None else 0.0


def overshoot_lines(cfg: Any) -> list[str]:
    """The warning of the explicit wear rule's overshoot, if any."""
    from ..simulate.explicit import overshoot_warning

    w = overshoot_warning(cfg.problem)
    return [w] if w else []
