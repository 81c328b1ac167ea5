"""Running the runs of a study on Dask distributed, one output directory per run.

The layout of a study's output directory ``OUTDIR``:

``runs/<id>/``
    The output directory of run ``<id>`` as ``vemwear run`` writes it
    (:mod:`vemwear.runner`: marker, lock, streamed levels, checkpoints, resume).
``configs/<id>.toml``
    The run's whole configuration: ``vemwear run OUTDIR/configs/<id>.toml -o
    OUTDIR/runs/<id>`` repeats it by hand.
``log/<id>.json``
    The record of the run's last attempt: parameters, ``status`` (``done`` or
    ``failed``), ``error``, ``wall_time``, the worker.

The runs go to Dask in chunks: one task (:func:`run_chunk`) runs a few runs one after
the other (:func:`run_task` each) on a worker with one thread, its BLAS limited to one
thread (the runs are the parallelism). Chunks keep the scheduler's work per run small
when runs take milliseconds (Dask's overhead is about a millisecond of CPU per task on
each side, taken from the cores that run the runs), and there are still several chunks
per worker to balance the load. A run that raises is tried again once, then recorded
as failed with its error; it never stops the others. The tasks of a worker that dies
are rescheduled by Dask onto the others. A run whose directory holds a complete result
is skipped, so a study stopped and started again only computes what is missing (also
within a rescheduled chunk); a run stopped half-way resumes from its checkpoint. The
output directory must be on a file system every worker sees.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import socket
import sys
import threading
import time
import weakref
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from ..util.atomic import write_atomic
from .design import RunSpec, StudyError, params_text

__all__ = [
    "CONFIGS_DIR",
    "LOG_DIR",
    "PROGRESS_TOPIC",
    "RUNS_DIR",
    "Execution",
    "RunFailed",
    "chunk_size",
    "is_complete",
    "open_study_dir",
    "read_record",
    "run_all",
    "run_chunk",
    "run_task",
    "study_client",
]

RUNS_DIR = "runs"
CONFIGS_DIR = "configs"
LOG_DIR = "log"


class RunFailed(RuntimeError):
    """A run raised on a worker (the message names the exception and its text)."""


# ---------------------------------------------------------------------------- the client
#: Dask settings of the embedded cluster's workers. Dask's nannies start workers with
#: MALLOC_TRIM_THRESHOLD_=65536, which returns freed memory to the system at once; a run
#: allocates and frees large arrays at every step, and with that setting each one becomes
#: an mmap, page faults and an munmap (measured on 2 cores: a run on 128 x 64 cells took
#: 2.1 times as long in a worker as in a plain process). Dask's statistical profiler
#: samples every task's stack each 10 ms, holding the GIL: off (a run on 128 x 64 cells
#: took 122-127 ms in a worker without it, 244-261 ms with it, on the loaded machine).
#: BLAS and OpenMP stay at one thread per worker (one worker per core).
LOCAL_WORKERS: dict[str, Any] = {
    "distributed.nanny.pre-spawn-environ": {
        "OMP_NUM_THREADS": 1,
        "MKL_NUM_THREADS": 1,
        "OPENBLAS_NUM_THREADS": 1,
    },
    "distributed.worker.profile.enabled": False,
}


@contextlib.contextmanager
def study_client(
    client: Any = None,
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    say: Callable[[str], None] | None = None,
) -> Iterator[Any]:
    """A Dask client for a study: ``client`` as it is, one connected to ``scheduler``,
    or an embedded ``LocalCluster`` of ``workers`` (default ``os.cpu_count()``) processes
    with one thread each, on 127.0.0.1. Clients and clusters made here are closed at the
    end; the dashboard address is passed to ``say``."""
    if client is not None:
        yield client
        return
    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            own = Client(scheduler, timeout=20)
        except (OSError, TimeoutError, ValueError) as exc:
            raise StudyError(f"--scheduler {scheduler}: cannot connect: {exc}") from None
        try:
            _prepare_workers(own)
            _tell_dashboard(own, say)
            yield own
        finally:
            own.close()
        return
    import dask

    n = workers or os.cpu_count() or 1
    with contextlib.ExitStack() as stack:
        stack.enter_context(dask.config.set(LOCAL_WORKERS))
        cluster = stack.enter_context(
            LocalCluster(
                n_workers=n,
                threads_per_worker=1,
                processes=True,
                host="127.0.0.1",
                dashboard_address="127.0.0.1:8787",
                silence_logs=logging.CRITICAL,  # a closing worker's heartbeat error is noise
            )
        )
        own = stack.enter_context(Client(cluster))
        # the workers import the library now, as part of the cluster's start
        _prepare_workers(own)
        _tell_dashboard(own, say)
        yield own


def _tell_dashboard(client: Any, say: Callable[[str], None] | None) -> None:
    if say is None:
        return
    try:
        import bokeh  # noqa: F401

        note = ""
    except ImportError:
        note = " (install bokeh to serve it)"
    n = len(client.scheduler_info().get("workers", {}))
    say(f"vemwear: Dask: {n} workers; dashboard {client.dashboard_link}{note}")


#: Clients whose workers have the plugin already (a client of study_client, or one that
#: ran a study): registering it again costs a round trip to every worker per call.
_PREPARED: weakref.WeakSet[Any] = weakref.WeakSet()


def _prepare_workers(client: Any) -> None:
    """Register the worker plugin on ``client``'s cluster once."""
    if client not in _PREPARED:
        client.register_plugin(_worker_plugin(), name="vemwear")
        _PREPARED.add(client)


def _worker_plugin() -> Any:
    """A Dask worker plugin: BLAS at one thread and the library imported when a worker
    starts (also on workers that join later), so that runs do not pay the imports."""
    from distributed.diagnostics.plugin import WorkerPlugin

    class VemwearWorker(WorkerPlugin):  # type: ignore[misc]
        name = "vemwear"

        def setup(self, worker: Any) -> None:
            prepare_worker()

    return VemwearWorker()


def prepare_worker() -> None:
    """Limit the BLAS pools of this process to one thread; keep freed memory in the
    allocator (:func:`vemwear.util.heap.keep_freed_memory`); import what a run needs; keep
    the last factorization of the stiffness, so that runs that change only contact data,
    loads or the time grid (the usual sweep axes) reuse it
    (:func:`vemwear.solvers.backends.keep_factorizations`). The limit holds for the
    worker's life: tasks do not set it again (threadpoolctl's scan of the loaded
    libraries takes 1.5 ms, a tenth of a small run)."""
    from importlib import import_module

    from threadpoolctl import threadpool_limits

    from ..solvers.backends import keep_factorizations, resolve_backend
    from ..util.heap import keep_freed_memory

    keep_freed_memory()
    keep_factorizations(1)
    resolve_backend("auto")  # loads MKL where PARDISO is installed, so that it is limited too

    for mod in (
        "vemwear.config.build",
        "vemwear.config.overrides",
        "vemwear.runner.run",
        "vemwear.runner.checkpoint",
        "vemwear.simulate.levels",
        "vemwear.post.outputs",
        "vemwear.post.forces",
        "vemwear.post.stream",
        "scipy.spatial",
    ):
        import_module(mod)
    threadpool_limits(limits=1)


# ---------------------------------------------------------------------------- the output
def open_study_dir(
    outdir: str | os.PathLike[str], command: str, protect: Sequence[Any] = ()
) -> Path:
    """The study's output directory: a new or empty one, or (to continue a stopped
    study) one that an earlier ``vemwear {command}`` wrote. Anything else is refused
    with an :class:`~vemwear.runner.OutputDirError` (exit code 2)."""
    from ..runner.outdir import (
        OutputDirError,
        check_output_dir,
        prepare_output_dir,
        read_marker,
        write_marker,
    )

    out = Path(outdir).expanduser().absolute()
    marker = read_marker(out) if out.is_dir() else None
    keep = [p for p in protect if p is not None]
    if marker is not None and marker.get("command") == command:
        check_output_dir(out, force=True, protect=keep)  # place, lock, writable
    elif marker is not None:
        raise OutputDirError(
            f"{out} holds the output of `vemwear {marker.get('command', 'run')}`, not of "
            f"`vemwear {command}`; choose another output directory"
        )
    else:
        prepare_output_dir(out, protect=keep, command=command)
    for d in (RUNS_DIR, CONFIGS_DIR, LOG_DIR):
        (out / d).mkdir(exist_ok=True)
    old = read_marker(out) or {}
    names = {*old.get("files", []), RUNS_DIR, CONFIGS_DIR, LOG_DIR}
    write_marker(out, "running", sorted(names), command=command)
    return out


def is_complete(rundir: Path) -> bool:
    """Whether ``rundir`` holds the complete result of a run."""
    from ..runner.outdir import read_marker

    m = read_marker(rundir) if rundir.is_dir() else None
    return bool(m and m.get("state") == "complete" and (rundir / "result.npz").is_file())


def read_record(out: Path, rid: str) -> dict[str, Any] | None:
    """The logged record of run ``rid``, or None."""
    try:
        rec = json.loads((out / LOG_DIR / f"{rid}.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return rec if isinstance(rec, dict) else None


def _complete_record(out: Path, rid: str, params: dict[str, Any], executed: bool) -> dict:
    """The record of a run whose directory holds a complete result (its wall time from
    the logged record, if that is there)."""
    old = read_record(out, rid) or {}
    return {
        "id": rid,
        "params": params,
        "status": "done",
        "error": "",
        "wall_time": old.get("wall_time", float("nan")),
        "executed": executed,
    }


def _write_record(out: Path, rec: dict[str, Any]) -> None:
    write_atomic(out / LOG_DIR / f"{rec['id']}.json", json.dumps(rec, indent=2) + "\n")


# ---------------------------------------------------------------------------- the task
def _wait_unlocked(rundir: Path) -> None:
    """Wait while another process writes into ``rundir`` (e.g. a task of a stopped study
    that still runs on a worker); the lock is released when it ends, in any way."""
    from ..runner.outdir import locked_by

    while rundir.is_dir() and locked_by(rundir) is not None:
        time.sleep(0.2)


def _execute(config_path: Path, rundir: Path) -> Any:
    """One run of ``config_path`` into ``rundir`` through :mod:`vemwear.runner`:
    resumed from its checkpoint if a stopped attempt left one, else from the start.
    Returns the result (None for a cycle-jump run, whose result is in its files)."""
    from ..config import load_config
    from ..runner import ResumeError, execute_run, prepare_run
    from ..runner.checkpoint import CHECKPOINT_NAME

    cfg = load_config(config_path)
    plan = None
    if cfg.cycles is None and (rundir / CHECKPOINT_NAME).is_file():
        with contextlib.suppress(ResumeError):
            plan = prepare_run(cfg, config_path, rundir, cfg.solver, resume=True)
    if plan is None:
        plan = prepare_run(cfg, config_path, rundir, cfg.solver, force=True)
    if cfg.cycles is not None:
        from ..runner.cycles import execute_cycles

        execute_cycles(plan, progress=False)
        return None
    result = execute_run(plan, progress=False)
    if isinstance(result, str):  # the arrays did not fit in memory: result.h5 only
        raise RunFailed(result)
    return result


#: What a task hands back besides the record: ``extract(result)``, e.g. the arrays the
#: study's Dataset needs, so that the client does not read them back from the files.
Extract = Callable[[Any], dict[str, Any]]


def run_task(
    rid: str,
    params: dict[str, Any],
    config_text: str,
    outdir: str,
    extract: Extract | None = None,
) -> dict[str, Any]:
    """Run one configuration into ``OUTDIR/runs/<rid>``.

    Returns the run's record (also written to ``OUTDIR/log/<rid>.json``), with
    ``executed`` False if the directory already held a complete result, and, with
    ``extract``, ``arrays = extract(result)`` (not logged).

    Raises
    ------
    RunFailed
        Naming the error of the run.
    """
    out = Path(outdir)
    rundir = out / RUNS_DIR / rid
    config_path = out / CONFIGS_DIR / f"{rid}.toml"
    t0 = time.perf_counter()
    started = datetime.now(UTC).isoformat(timespec="seconds")
    rec: dict[str, Any] = {
        "id": rid,
        "params": params,
        "status": "done",
        "error": "",
        "started": started,
        "worker": f"{socket.gethostname()}:{os.getpid()}",
    }
    _wait_unlocked(rundir)
    if is_complete(rundir):
        return _complete_record(out, rid, params, executed=False)
    try:
        if not config_path.is_file() or config_path.read_text(encoding="utf-8") != config_text:
            write_atomic(config_path, config_text)
        result = _execute(config_path, rundir)
    except Exception as exc:
        note = getattr(exc, "vemwear_note", "")
        raise RunFailed(f"{type(exc).__name__}: {exc}{note}") from None
    rec.update(wall_time=time.perf_counter() - t0, executed=True)
    _write_record(out, rec)
    if extract is not None and result is not None:
        rec["arrays"] = extract(result)
    return rec


def _failed(rid: str, params: dict[str, Any], msg: str) -> dict[str, Any]:
    return {
        "id": rid,
        "params": params,
        "status": "failed",
        "error": msg,
        "wall_time": float("nan"),
        "executed": True,
        "finished": datetime.now(UTC).isoformat(timespec="seconds"),
    }


def run_chunk(
    runs: list[tuple[str, dict[str, Any], str]],
    outdir: str,
    retries: int = 1,
    extract: Extract | None = None,
) -> list[dict[str, Any]]:
    """Run ``(id, params, config text)`` one after the other (a Dask task).

    A run that raises is tried ``retries`` more times, then recorded as failed (its
    record in ``OUTDIR/log``) and the chunk goes on: the task itself does not fail.

    Returns
    -------
    list of dict
        The records, in the order of ``runs``.
    """
    records = []
    for rid, params, text in runs:
        for attempt in range(retries + 1):
            try:
                rec = run_task(rid, params, text, outdir, extract)
                break
            except RunFailed as exc:
                if attempt == retries:
                    rec = _failed(rid, params, str(exc))
                    _write_record(Path(outdir), rec)
        records.append(rec)
        _tell_progress(rid)
    return records


#: The Dask event topic of finished runs (the client's progress bar counts them).
PROGRESS_TOPIC = "vemwear-run-finished"


def _tell_progress(rid: str) -> None:
    """Publish that run ``rid`` finished, when running on a Dask worker."""
    try:
        from distributed import get_worker

        get_worker().log_event(PROGRESS_TOPIC, rid)
    except (ImportError, ValueError):  # not on a worker: nobody to tell
        pass


def chunk_size(n_runs: int, n_threads: int) -> int:
    """Runs per task: at least four tasks per worker thread (the load stays balanced
    when the runs take different times), at most 16 runs per task."""
    return max(1, min(16, n_runs // (4 * max(n_threads, 1))))


# ---------------------------------------------------------------------------- the study
@dataclass
class Execution:
    """What one execution of a study did.

    Attributes
    ----------
    records : dict
        Run id -> its record (``status``, ``error``, ``wall_time``, ``executed``).
    computed, skipped, failed : int
        Runs computed now, found complete from an earlier execution, failed.
    seconds : float
        Wall time of the execution.
    arrays : dict
        Run id -> what the task's ``extract`` returned, for the runs computed now.
    """

    records: dict[str, dict[str, Any]] = field(default_factory=dict)
    computed: int = 0
    skipped: int = 0
    failed: int = 0
    seconds: float = 0.0
    arrays: dict[str, dict[str, Any]] = field(default_factory=dict)


def run_all(
    runs: Sequence[RunSpec],
    out: Path,
    client: Any,
    *,
    retries: int = 1,
    progress: bool = True,
    chunk: int | None = None,
    extract: Extract | None = None,
) -> Execution:
    """Run every run not yet complete in ``out`` on ``client``'s cluster.

    The runs go in tasks of ``chunk`` runs (default :func:`chunk_size` of the cluster's
    worker threads). Failed runs (after ``retries``) are recorded in ``out/log`` with
    their error; the others go on. Ctrl-C cancels the tasks not yet started and
    re-raises.
    """
    from distributed import as_completed
    from tqdm import tqdm

    t0 = time.perf_counter()
    ex = Execution()
    if runs:
        _prepare_workers(client)
    todo = []
    for r in runs:
        if is_complete(out / RUNS_DIR / r.id):
            ex.records[r.id] = _complete_record(out, r.id, r.params, executed=False)
            ex.skipped += 1
        else:
            todo.append(r)
    if chunk is None:
        threads = sum(w.get("nthreads", 1) for w in client.scheduler_info()["workers"].values())
        chunk = chunk_size(len(todo), threads)
    bar = tqdm(
        total=len(runs),
        initial=ex.skipped,
        unit="run",
        desc="vemwear: runs",
        disable=not progress,
        file=sys.stderr,
    )
    # the bar advances per run, as the workers report them, not per chunk
    counted: set[str] = set()
    lock = threading.Lock()
    ours = {r.id for r in todo}

    def advance(rids: Sequence[str]) -> None:
        with lock:
            new = [rid for rid in rids if rid in ours and rid not in counted]
            counted.update(new)
            if new:
                bar.update(len(new))

    if progress and todo:
        client.subscribe_topic(PROGRESS_TOPIC, lambda event: advance([event[1]]))
    futures = {}
    for i in range(0, len(todo), chunk):
        part = todo[i : i + chunk]
        fut = client.submit(
            run_chunk,
            [(r.id, r.params, r.toml()) for r in part],
            str(out),
            retries,
            extract,
            key=f"vemwear-runs-{part[0].id}-{len(part)}-{os.urandom(4).hex()}",
            retries=retries,  # a chunk fails only outside its runs (e.g. a lost result)
            pure=False,
        )
        futures[fut] = part
    try:
        for fut in as_completed(list(futures)):
            part = futures[fut]
            if fut.status == "finished":
                recs = fut.result()
            else:
                # e.g. its workers died too often: the runs it finished are kept
                err = fut.exception()
                msg = f"{type(err).__name__}: {err}"
                recs = []
                for r in part:
                    if is_complete(out / RUNS_DIR / r.id):
                        recs.append(_complete_record(out, r.id, r.params, executed=True))
                    else:
                        recs.append(_failed(r.id, r.params, msg))
                        _write_record(out, recs[-1])
            for r, rec in zip(part, recs, strict=True):
                arrays = rec.pop("arrays", None)
                if arrays is not None:
                    ex.arrays[r.id] = arrays
                if rec["status"] == "failed":
                    ex.failed += 1
                    bar.write(
                        f"vemwear: run {r.id} ({params_text(r.params)}) failed: {rec['error']}"
                    )
                else:
                    ex.computed += bool(rec.get("executed"))
                    ex.skipped += not rec.get("executed")
                ex.records[r.id] = rec
            fut.release()
            advance([r.id for r in part])
    except BaseException:
        client.cancel(list(futures))
        raise
    finally:
        if progress and todo:
            client.unsubscribe_topic(PROGRESS_TOPIC)
        bar.close()
    ex.seconds = time.perf_counter() - t0
    return ex
