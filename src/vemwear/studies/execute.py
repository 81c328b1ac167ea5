"""Running the runs of a study on Dask distributed: what the client does.

The client (:func:`study_client`: given, connected to a scheduler, or an embedded
``LocalCluster``) has its workers prepared once (:func:`prepare_worker`);
:func:`run_all` submits the runs not yet complete, gathers their records and counts them
on a progress bar. What a task does on a worker is in :mod:`~vemwear.studies.tasks`; the
layout of the output directory and the records of the runs in
:mod:`~vemwear.studies.layout`.

The runs go to Dask in chunks: one task (:func:`~vemwear.studies.tasks.run_chunk`) runs
a few runs one after the other on a worker with one thread, its BLAS limited to one
thread (the runs are the parallelism). Chunks keep the scheduler's work per run small
when runs take milliseconds (Dask's overhead is about a millisecond of CPU per task on
each side, taken from the cores that run the runs), and there are still several chunks
per worker to balance the load (:func:`chunk_size`). The tasks of a worker that dies
are rescheduled by Dask onto the others.
"""

from __future__ import annotations

import contextlib
import logging
import os
import sys
import threading
import time
import weakref
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .design import RunSpec, StudyError, params_text
from .layout import RUNS_DIR, complete_record, is_complete, record_failure
from .tasks import PROGRESS_TOPIC, Extract, run_chunk

__all__ = [
    "Execution",
    "chunk_size",
    "run_all",
    "study_client",
]


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


def _active_client(say: Callable[[str], None] | None) -> Any:
    """The user's active ``distributed.Client`` in this process (``default_client()``),
    or None: a study then runs on it instead of starting a cluster of its own."""
    import sys

    if "distributed" not in sys.modules:  # no client can be active without it
        return None
    from distributed import default_client

    try:
        client = default_client()
    except ValueError:  # no client
        return None
    if client.status != "running":
        return None
    if say is not None:
        say(f"vemwear: using the active Dask client (scheduler {client.scheduler.address})")
    return client


@contextlib.contextmanager
def study_client(
    client: Any = None,
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    say: Callable[[str], None] | None = None,
) -> Iterator[Any]:
    """A Dask client for a study: ``client`` as it is, one connected to ``scheduler``,
    the user's active client in this process (``distributed.default_client()``, said to
    ``say``), or an embedded ``LocalCluster`` of ``workers`` (default ``os.cpu_count()``) processes
    with one thread each, on 127.0.0.1. Clients and clusters made here are closed at the
    end; the dashboard address is passed to ``say``."""
    if client is None and scheduler is None:
        client = _active_client(say)
    if client is not None:
        yield client
        return
    from distributed import Client

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
    # the settings stay for the cluster's life: a worker that dies is started again
    with dask.config.set(LOCAL_WORKERS):
        before = set(_clusters())
        cluster = _start_local_cluster(n)
        local: Any = None  # the client, once made
        try:
            local = Client(cluster)
            # the workers import the library now, as part of the cluster's start; a
            # worker that dies meanwhile is replaced by its nanny: register again
            for attempt in range(_STARTS):
                try:
                    _prepare_workers(local)
                    break
                except OSError:
                    if attempt + 1 == _STARTS:
                        raise
            _tell_dashboard(local, say)
            yield local
            local.close()
            cluster.close()
        except BaseException:  # a stop or an error, also during the graceful close
            # every cluster made here (Dask's exit hook would close one that is left
            # with a graceful wait for a worker being started again: 10 s)
            _forget({cluster} | (set(_clusters()) - before))
            _close_at_once(local, cluster)
            _kill_children()
            raise


def _close_at_once(own: Any, cluster: Any) -> None:
    """Close a stopped study's client and embedded cluster within about a second each.

    A graceful close waits for a nanny that is starting a worker again (one killed with
    the client), and stopping the cluster's event loop joins its thread for up to 10 s
    while the loop's tasks are cancelled; Dask has no public bound on that join."""
    from distributed.deploy.cluster import Cluster

    if own is not None:
        with contextlib.suppress(Exception):
            own.close(timeout=1)
    with contextlib.suppress(Exception):
        Cluster.close(cluster, timeout=1)  # the base class's: no unbounded join
    for runner in (getattr(own, "_loop_runner", None), getattr(cluster, "_loop_runner", None)):
        if runner is not None:  # the loop's thread is a daemon: left running past 1 s
            with contextlib.suppress(Exception):
                runner.stop(timeout=1)


def _start_local_cluster(n: int) -> Any:
    """An embedded ``LocalCluster`` of ``n`` single-threaded worker processes on
    127.0.0.1, started again if a worker dies while it starts."""
    from distributed import LocalCluster

    for attempt in range(_STARTS):
        before = set(_clusters())
        try:
            return LocalCluster(
                n_workers=n,
                threads_per_worker=1,
                processes=True,
                host="127.0.0.1",
                dashboard_address="127.0.0.1:8787",
                silence_logs=logging.CRITICAL,  # a closing worker's heartbeat error is noise
            )
        except BaseException as exc:  # interrupted, or a worker died, while starting
            _forget(set(_clusters()) - before)
            if not isinstance(exc, RuntimeError | OSError | TimeoutError):
                raise
            if attempt + 1 == _STARTS:
                raise StudyError(
                    f"the embedded Dask cluster did not start ({type(exc).__name__}: {exc}); "
                    "no run was started: start the sweep again"
                ) from None
    raise AssertionError("unreachable")  # pragma: no cover


#: Attempts to start the embedded cluster and prepare its workers (a worker may die).
_STARTS = 3


def _clusters() -> Any:
    """Dask's set of the clusters of this process (those its exit hook closes)."""
    from distributed.deploy.spec import SpecCluster

    return getattr(SpecCluster, "_instances", set())


def _forget(clusters: Any) -> None:
    """End the workers of clusters made here whose start or run was interrupted (Ctrl-C,
    SIGTERM); Dask's exit hook no longer closes them (closing a cluster with a worker
    that never started fails with a traceback after the command's last line)."""
    clusters = list(clusters)
    if clusters:
        logging.getLogger("asyncio").addFilter(_closed_comms)
    for cluster in clusters:
        _kill_workers(cluster)
        _clusters().discard(cluster)


def _closed_comms(record: logging.LogRecord) -> bool:
    """Drop asyncio's report of a message to a killed worker (``Future exception was
    never retrieved ... CommClosedError``): those workers were ended on purpose."""
    text = record.getMessage()
    return not ("never retrieved" in text and "CommClosedError" in text)


def _kill_workers(cluster: Any) -> None:
    """End the worker processes of an embedded cluster at once (SIGKILL), before it is
    closed after an error or a stop: a graceful close waits for the runs in progress
    (seconds, or the workers' start), and a run stopped anywhere resumes from its
    checkpoint."""
    import signal

    from distributed.core import Status

    for nanny in list(getattr(cluster, "workers", {}).values()):
        if getattr(nanny, "status", None) == Status.running:
            nanny.status = Status.closing_gracefully  # it closes, not starts a new worker
        process = getattr(getattr(nanny, "process", None), "process", None)
        pid = getattr(process, "pid", None)
        if isinstance(pid, int):
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)


def _kill_children() -> None:
    """SIGKILL this process's multiprocessing children left after a stop: a worker that
    a nanny was starting again when the stop came (unknown to the cluster) would hold
    the interpreter's exit, which joins its children, until it gives up (10 s)."""
    import multiprocessing

    for child in multiprocessing.active_children():
        with contextlib.suppress(Exception):
            child.kill()


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


# ---------------------------------------------------------------------------- the study
def chunk_size(n_runs: int, n_threads: int) -> int:
    """Runs per task: at least four tasks per worker thread (the load stays balanced
    when the runs take different times), at most 16 runs per task."""
    return max(1, min(16, n_runs // (4 * max(n_threads, 1))))


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
    their error; the others go on. The warnings of the runs computed now are said
    (``vemwear: run ID (params): warning: ...``) as their records come back. Ctrl-C
    cancels the tasks not yet started and re-raises.
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
            ex.records[r.id] = complete_record(out, r.id, r.params, executed=False)
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
                        recs.append(complete_record(out, r.id, r.params, executed=True))
                    else:
                        recs.append(record_failure(out, r.id, r.params, msg))
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
                if rec.get("executed"):  # runs of an earlier execution said theirs then
                    for line in rec.get("warnings", []):
                        said = f"vemwear: run {r.id} ({params_text(r.params)}): warning: {line}"
                        bar.write(said, file=sys.stderr)
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
