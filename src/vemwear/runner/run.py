"""A run of a validated configuration: plan, solve while streaming, checkpoint, write.

``vemwear run CONFIG -o OUTDIR`` writes into OUTDIR itself (an existing empty directory
or a mount point included; :mod:`vemwear.runner.outdir` says which directories it may
use and how ``--force`` treats them), holding a lock on it from :func:`prepare_run`,
before any assembly or solving, to the end of the run (:func:`execute_run`) or until
the run is given up (:func:`abandon_run`):

``result.h5``
    The finished levels, streamed as they come (:mod:`vemwear.post.stream`); memory
    does not grow with the number of levels.
``checkpoint.npz``
    Every ``[output] checkpoint`` seconds and when the run stops: the state to go on
    from (:mod:`vemwear.runner.checkpoint`), durable together with ``result.h5``.
``PARTIAL.txt``, ``summary.json``
    While the run is unfinished (stopped by Ctrl-C, SIGTERM, SIGHUP, an error, or
    killed): what happened and the command that continues it. ``summary.json`` says
    ``"partial": true``.

When the run completes, the standard files are written (``result.npz`` when its arrays
fit in memory, ``summary.json``, figures, the ParaView series;
:func:`vemwear.post.outputs.write_outputs`) and the checkpoint and ``PARTIAL.txt`` are
removed. ``--resume`` checks that the physics and the discretization are unchanged
(the problem's fingerprint) and that the run keeps the same levels; the solver options
may change. The resumed run gives the same arrays, bitwise, as an uninterrupted run
with the same solver.
"""

from __future__ import annotations

import dataclasses
import shlex
import time
from contextlib import ExitStack
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..post.outputs import write_outputs
from ..util.hashing import sha256_file, sha256_json
from .checkpoint import (
    CHECKPOINT_NAME,
    differences,
    read_adaptive_checkpoint,
    read_checkpoint,
    write_checkpoint,
)
from .outdir import (
    PARTIAL_NAME,
    OutputDirError,
    completed_leftovers,
    killed_before_checkpoint,
    output_lock,
    prepare_output_dir,
    read_marker,
    refuse_locked,
    write_marker,
)
from .partial import (
    WearGuard,
    WornThroughError,
    discard,
    keep_stopped,
    output_names,
    outputs_failed,
)
from .signals import check_stop

if TYPE_CHECKING:
    from ..config import Config
    from ..simulate import Result, SolverOptions
    from ..simulate.adaptive_time import AdaptiveState
    from ..simulate.stream import LoopState, StoragePlan

__all__ = [
    "PARTIAL_NAME",
    "ResumeError",
    "RunComplete",
    "RunPlan",
    "WornThroughError",
    "abandon_run",
    "execute_run",
    "hold_lock",
    "prepare_run",
    "storage_plan",
]


class ResumeError(OutputDirError):
    """``--resume`` is not possible (no checkpoint, other inputs, damaged files)."""


class RunComplete(Exception):
    """``--resume`` of a run that is complete: nothing to do (the message says so)."""


def storage_plan(cfg: Config) -> StoragePlan:
    """The levels a run of ``cfg`` keeps (``[output] store_u``, ``every``, ``times``)."""
    from ..simulate.stream import StoragePlan

    out = cfg.output
    return StoragePlan.make(len(cfg.problem.time.t), out.u_levels, out.every)


@dataclass
class RunPlan:
    """A validated ``vemwear run``: where it writes, what it keeps, what it resumes.

    Attributes
    ----------
    cfg : Config
        The configuration.
    config_path : Path
        Its file.
    out : Path
        The output directory (absolute).
    solver : SolverOptions
        The effective solver options.
    storage : StoragePlan
        The levels the run keeps.
    state : LoopState or AdaptiveState or None
        The checkpoint to resume from (an :class:`AdaptiveState` for ``[adapt]``).
    previous_solver : dict
        The solver options of the stopped run (recorded in ``summary.json``).
    meta : dict
        What every checkpoint stores: fingerprint, its hash, the kept levels, solver.
    command : str
        The command that resumes this run if it stops.
    created : bool
        Whether the run made the output directory.
    lock : ExitStack
        Holds the lock of the output directory (:func:`hold_lock`) until it is closed.
    locked : bool
        Whether ``lock`` holds it.
    note : str
        A line to show before the run (e.g. a resume that starts from level 0).
    """

    cfg: Config
    config_path: Path
    out: Path
    solver: SolverOptions
    storage: StoragePlan
    state: LoopState | AdaptiveState | None = None
    previous_solver: dict[str, Any] = field(default_factory=dict)
    meta: dict[str, Any] = field(default_factory=dict)
    command: str = ""
    created: bool = False
    lock: ExitStack = field(default_factory=ExitStack)
    locked: bool = False
    note: str = ""


def hold_lock(plan: RunPlan) -> None:
    """Take the lock of ``plan.out`` (which must exist) until ``plan.lock`` is closed;
    nothing if it is held already.

    Raises
    ------
    OutputDirError
        If another run holds it.
    """
    if not plan.locked:
        plan.lock.enter_context(output_lock(plan.out))
        plan.locked = True


def _release_lock(plan: RunPlan) -> None:
    plan.lock.close()
    plan.locked = False


def _resume_command(
    config_path: str | Path, out: Path, solver_flag: str | None, backend_flag: str | None = None
) -> str:
    """The command that resumes the run (under ``mpirun -n N`` for a run of N ranks)."""
    from ..util.mpi import launched

    ranks = launched().size
    cmd = ["mpirun", "-n", str(ranks)] if ranks > 1 else []
    cmd += ["vemwear", "run", str(Path(config_path).resolve()), "-o", str(out), "--resume"]
    if solver_flag:
        cmd += ["--solver", solver_flag]
    if backend_flag:
        cmd += ["--backend", backend_flag]
    return " ".join(shlex.quote(c) for c in cmd)


def _storage_hash(storage: StoragePlan) -> str:
    return sha256_json({"levels": storage.levels.tolist(), "u_levels": storage.u_levels.tolist()})


def prepare_run(
    cfg: Config,
    config_path: str | Path,
    out: str | Path,
    solver: SolverOptions,
    *,
    force: bool = False,
    resume: bool = False,
    solver_flag: str | None = None,
    backend_flag: str | None = None,
    need_bytes: int = 0,
) -> RunPlan:
    """Everything a run checks before solving: the output directory and the checkpoint.

    Without ``resume`` the output directory must be new, empty, or (with ``force``)
    one that vemwear wrote; with ``resume`` it must hold the checkpoint of a stopped
    run of the same problem keeping the same levels. The returned plan holds the lock
    of the output directory (``plan.lock``): :func:`execute_run` releases it at its
    end, :func:`abandon_run` when the run is given up before.

    Raises
    ------
    OutputDirError, ResumeError
        Naming the directory and the problem.
    """
    from ..simulate import Problem

    storage = storage_plan(cfg)
    fp = Problem.fingerprint(cfg.problem)
    meta = {
        "inputs_sha256": sha256_json(fp),
        "config_sha256": sha256_file(config_path),
        "fingerprint": fp,
        "storage_sha256": _storage_hash(storage),
        "solver": {"method": solver.method, "tol": solver.tol, "max_iter": solver.max_iter},
    }
    if cfg.adapt is not None:
        meta["adapt"] = dataclasses.asdict(cfg.adapt)
    outdir = Path(out).expanduser().absolute()
    plan = RunPlan(
        cfg=cfg,
        config_path=Path(config_path),
        out=outdir,
        solver=solver,
        storage=storage,
        meta=meta,
        command=_resume_command(config_path, outdir, solver_flag, backend_flag),
    )
    refuse_locked(outdir)
    marker = read_marker(outdir) if outdir.is_dir() else None
    if resume and marker is not None and marker.get("state") == "complete":
        for p in completed_leftovers(outdir):  # a run killed just after it completed
            p.unlink(missing_ok=True)
        raise RunComplete(f"{outdir} holds a complete run; there is nothing to resume")
    if resume and killed_before_checkpoint(outdir):
        resume = False  # killed before its first checkpoint: nothing to go on from
        plan.note = f"{outdir}: the stopped run saved no level; starting from level 0"
    if resume:  # a refused resume leaves the directory as it was, lock file included
        plan.state, plan.previous_solver = _load_checkpoint(outdir, meta)
        hold_lock(plan)
        return plan
    if (
        marker is not None
        and marker.get("state") in ("partial", "running")
        and not force
        and not killed_before_checkpoint(outdir)
    ):
        raise ResumeError(
            f"{outdir} holds a stopped run ({marker.get('state')}); continue it with --resume, "
            "or start over with --force"
        )
    plan.created = not outdir.exists()
    prepare_output_dir(
        outdir,
        force=force,
        protect=[config_path],
        need_bytes=need_bytes,
        command="run",
        reserved=output_names(),
    )
    hold_lock(plan)  # before any assembly: a second run is refused at once
    return plan


#: ``[adapt]`` settings added after checkpoints of adaptive runs were first written, with
#: the value that does what a run made before they existed did
_ADAPT_SINCE = {"estimator": "residual", "transfer": "linear", "passes": 1}


def _adapt_settings(stored: dict[str, Any] | None) -> dict[str, Any] | None:
    """The ``[adapt]`` settings of a checkpoint, with those it predates at their value."""
    return None if stored is None else {**_ADAPT_SINCE, **stored}


def _load_checkpoint(
    outdir: Path, meta: dict[str, Any]
) -> tuple[LoopState | AdaptiveState, dict[str, Any]]:
    if not (outdir / CHECKPOINT_NAME).is_file():
        raise ResumeError(
            f"--resume: {outdir} holds no checkpoint to resume from (it is written every "
            "[output] checkpoint seconds and when a run stops); start over with --force"
        )
    state: LoopState | AdaptiveState
    try:
        if "adapt" in meta:
            state, stored = read_adaptive_checkpoint(outdir)
        else:
            state, stored = read_checkpoint(outdir)
    except ValueError as exc:
        raise ResumeError(f"--resume: {exc}") from None
    if _adapt_settings(stored.get("adapt")) != meta.get("adapt"):
        raise ResumeError(
            f"--resume refused: {outdir} was computed with other [adapt] settings (or without "
            "[adapt]); restore them, or start over with --force"
        )
    if stored.get("inputs_sha256") != meta["inputs_sha256"]:
        diffs = differences(stored.get("fingerprint", {}), meta["fingerprint"])
        what = "; ".join(diffs) if diffs else "the stored fingerprint does not match"
        raise ResumeError(
            f"--resume refused: {outdir} was computed from another problem ({what}); restore "
            "the inputs of the stopped run, or start over with --force"
        )
    if stored.get("storage_sha256") != meta["storage_sha256"]:
        raise ResumeError(
            f"--resume refused: {outdir} keeps other levels ([output] store_u, every or "
            "times changed); restore them, or start over with --force"
        )
    return state, dict(stored.get("solver") or {})


def execute_run(
    plan: RunPlan,
    *,
    progress: bool = True,
    phases: dict[str, float] | None = None,
    start: float | None = None,
) -> Result | str:
    """Solve, streaming the levels into ``OUTDIR/result.h5`` with checkpoints; write
    the standard files when done.

    ``phases`` (seconds of the phases before this call, e.g. ``config`` and ``plan``)
    go into the timings of ``summary.json`` with the run's own; ``start``, the
    :func:`time.perf_counter` at which the run began, makes ``run`` there the wall
    time of the whole run, up to its last output file.

    Returns the result, or, when its arrays do not fit in memory, a line saying that the
    run ends with ``result.h5`` alone.

    On any error or interruption after at least one finished level, the levels and the
    state are made durable (a last checkpoint) and the exception propagates with an
    attribute ``vemwear_note`` saying how to resume.
    """
    from ..post.stream import STREAM_NAME, H5Sink
    from ..simulate.levels import run_levels
    from ..simulate.stream import LoopState

    out, cfg = plan.out, plan.cfg
    hold_lock(plan)
    with plan.lock:
        # every name the run may write: a kill in its last writes leaves only listed files
        write_marker(out, "running", output_names(), command="run")
        meta = {**plan.meta, "written": ""}

        def on_checkpoint(state: LoopState) -> None:
            meta["written"] = datetime.now(UTC).isoformat(timespec="seconds")
            write_checkpoint(out, state, meta)

        h5 = H5Sink(
            out / STREAM_NAME,
            cfg.problem,
            plan.storage,
            resume=plan.state is not None,
            on_checkpoint=on_checkpoint,
        )
        sink = WearGuard(h5, cfg.problem)
        timings: dict[str, float] = dict(phases or {})
        try:
            final = run_levels(
                cfg.problem,
                plan.solver,
                sink,
                plan.storage,
                start=plan.state if isinstance(plan.state, LoopState) else None,
                progress=progress,
                checkpoint=cfg.output.checkpoint,
                timings=timings,
            )
            sink.checkpoint(final)  # every level durable: a failure below loses no solve
            sink.close(completed=plan.storage.n_levels)
            # the outputs read the kept arrays back: without the factors, in less memory
            cfg.problem.discrete.release_solvers()
        except BaseException as exc:
            _stop(plan, sink, exc)
            raise
        try:
            result = _finish(plan, timings, start)
        except BaseException as exc:
            outputs_failed(plan, exc)
            raise
    return result


def _stop(plan: RunPlan, sink: Any, exc: BaseException) -> None:
    """Keep the finished levels of a stopped run; attach a one-line note to ``exc``."""
    state: LoopState | None = getattr(exc, "loop_state", None)
    c = state.completed if state else 0
    if state is None or (c == 0 and plan.state is None):
        try:  # nothing finished: remove what this run wrote, even if closing fails
            sink.close()
        except BaseException:
            pass
        finally:
            discard(plan)
        return

    def save() -> None:
        sink.checkpoint(state)
        sink.close()

    keep_stopped(plan, c, exc, save)


def abandon_run(plan: RunPlan) -> None:
    """A prepared run that failed before its first level: remove what it wrote in its
    output directory, and the directory if it made it (nothing else); release its lock."""
    try:
        if plan.state is None:
            discard(plan)
    finally:
        _release_lock(plan)


def _add_timings(out: Path, result: Result, more: dict[str, float]) -> None:
    """Add the phases timed after ``summary.json`` was written to it and to the result
    (the file replaced as a whole: a kill leaves the old one or the new one)."""
    import json

    from ..post.results import SUMMARY_NAME
    from ..util.atomic import write_atomic

    result.timings.update(more)
    path = out / SUMMARY_NAME
    summary = json.loads(path.read_text(encoding="utf-8"))
    summary["timings"].update(more)
    write_atomic(path, json.dumps(summary, indent=2, allow_nan=False) + "\n", durable=True)


def _finish(plan: RunPlan, timings: dict[str, float], start: float | None) -> Result | str:
    """The standard files of a completed run; the checkpoint is no longer needed.

    ``result.npz``, the summary, the figures and the ParaView series need the kept arrays
    in memory (about three times their size: read, summarized, written). When they do not
    fit, the run ends with ``result.h5`` alone and a line saying so is returned instead
    of the result (``vemwear export`` writes ``result.npz`` on a larger machine).
    """
    from ..post.stream import STREAM_NAME, result_from_stream, stream_bytes
    from ..util.system import available_memory

    cfg, out = plan.cfg, plan.out
    tick = time.perf_counter()
    need, avail = stream_bytes(out / STREAM_NAME), available_memory()
    if avail and 3 * need > avail:
        write_marker(out, "complete", [STREAM_NAME], command="run")
        for name in (CHECKPOINT_NAME, PARTIAL_NAME):  # after the marker: see completed_leftovers
            (out / name).unlink(missing_ok=True)
        return (
            f"the kept arrays take {need / 1e9:.2f} GB, too much for the "
            f"{avail / 1e9:.2f} GB of memory available: {out / STREAM_NAME} holds the whole "
            "run; result.npz, summary.json, figures and ParaView output are not written "
            f"(write result.npz on a larger machine with: vemwear export {out})"
        )
    extra: dict[str, Any] = {
        "config": cfg.data,
        "config_path": str(plan.config_path.resolve()),
        "title": cfg.title,
        "inputs_sha256": plan.meta["inputs_sha256"],
    }
    if plan.state is not None:
        extra["resumed_from_level"] = int(plan.state.completed)
        extra["previous_solver"] = plan.previous_solver
    result = result_from_stream(cfg.problem, out / STREAM_NAME, solver=plan.meta["solver"])
    parts = {"outputs_read": time.perf_counter() - tick}
    result.timings.update(timings)
    written = write_outputs(
        result,
        out,
        times=cfg.output.times,
        figures=cfg.output.figures,
        vtk=cfg.output.vtk,
        extra=extra,
        between=check_stop,  # safe points between the files
        timings=parts,
        **({"paraview": cfg.output.paraview} if hasattr(cfg.output, "paraview") else {}),
    )
    now = time.perf_counter()
    # the outputs: reading the levels back, result.npz, summary, figures, ParaView files
    more = {"outputs": now - tick, **parts, **({"run": now - start} if start else {})}
    _add_timings(out, result, more)
    files = [STREAM_NAME, *(f.split("/")[0] for names in written.values() for f in names)]
    write_marker(out, "complete", sorted(set(files)), command="run")
    for name in (CHECKPOINT_NAME, PARTIAL_NAME):  # after the marker: see completed_leftovers
        (out / name).unlink(missing_ok=True)
    return result
