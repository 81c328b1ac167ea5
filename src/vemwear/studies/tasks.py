"""The Dask tasks of a study: what a worker runs, one output directory per run.

One task (:func:`run_chunk`) runs a few runs one after the other (:func:`run_task`
each) through :mod:`vemwear.runner`, each from ``OUTDIR/configs/<id>.toml`` into
``OUTDIR/runs/<id>`` (:mod:`~vemwear.studies.layout`), and hands back their records. A
run that raises is tried again once, then recorded as failed with its error; it never
stops the others. A run whose directory holds a complete result is skipped, so a study
stopped and started again only computes what is missing (also within a rescheduled
chunk); a run stopped half-way resumes from its checkpoint. Each finished run is
published on :data:`PROGRESS_TOPIC`, for the client's progress bar. The warnings of a
run (those ``vemwear run`` says, and Python warnings raised while it runs) are in its
record, ``warnings``, and the client says them.
"""

from __future__ import annotations

import contextlib
import os
import socket
import time
import warnings
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from ..util.atomic import write_atomic
from .layout import (
    CONFIGS_DIR,
    RUNS_DIR,
    complete_record,
    is_complete,
    record_failure,
    remove_temporaries,
    write_record,
)

__all__ = [
    "PROGRESS_TOPIC",
    "RunFailed",
    "run_chunk",
    "run_task",
]


class RunFailed(RuntimeError):
    """A run raised on a worker (the message names the exception and its text)."""


def _wait_unlocked(rundir: Path) -> None:
    """Wait while another process writes into ``rundir`` (e.g. a task of a stopped study
    that still runs on a worker); the lock is released when it ends, in any way."""
    from ..runner.outdir import locked_by

    while rundir.is_dir() and locked_by(rundir) is not None:
        time.sleep(0.2)


def _execute(config_path: Path, rundir: Path) -> tuple[Any, list[str]]:
    """One run of ``config_path`` into ``rundir`` by :func:`vemwear.runner.run_config`
    (the plan's refusals and the warnings as for ``vemwear run``): resumed from its
    checkpoint if a stopped attempt left one, else from the start. Returns the result
    (None for a cycle-jump run, whose result is in its files; for an ``[adapt]`` run the
    contact arrays of :func:`~vemwear.post.adaptive_stream.contact_arrays`) and the
    run's warnings:
    those ``vemwear run`` says, then the Python warnings raised meanwhile (each once)."""
    from ..runner import ResumeError, run_config
    from ..runner.checkpoint import CHECKPOINT_NAME

    outcome = None
    # a worker runs one task at a time (one thread): the warnings caught are the run's
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("default")
        if (rundir / CHECKPOINT_NAME).is_file():
            with contextlib.suppress(ResumeError):
                outcome = run_config(config_path, rundir, resume=True, progress=False)
        if outcome is None:
            outcome = run_config(config_path, rundir, force=True, progress=False)
    said = [*outcome.warnings, *(f"{w.category.__name__}: {w.message}" for w in caught)]
    if outcome.segments is not None:  # [adapt]: the arrays of every mesh on one set of points
        from ..post.adaptive_stream import contact_arrays, read_groups
        from ..post.stream import STREAM_NAME

        arrays = contact_arrays(read_groups(rundir / STREAM_NAME))
        return arrays, list(dict.fromkeys(said))
    if outcome.result is None and outcome.cycles is None:  # result.h5 only
        raise RunFailed(outcome.note)
    return outcome.result, list(dict.fromkeys(said))


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
    ``executed`` False if the directory already held a complete result, ``warnings``
    the run's warnings (a list of lines) and, with ``extract``, ``arrays =
    extract(result)`` (not logged).

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
        return complete_record(out, rid, params, executed=False)
    remove_temporaries(rundir)  # of a killed attempt: its lock is free
    try:
        if not config_path.is_file() or config_path.read_text(encoding="utf-8") != config_text:
            write_atomic(config_path, config_text)
        result, said = _execute(config_path, rundir)
    except Exception as exc:
        note = getattr(exc, "vemwear_note", "")
        raise RunFailed(f"{type(exc).__name__}: {exc}{note}") from None
    rec.update(wall_time=time.perf_counter() - t0, executed=True, warnings=said)
    write_record(out, rec)
    if extract is not None and result is not None:
        rec["arrays"] = extract(result)
    return rec


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
                    rec = record_failure(Path(outdir), rid, params, str(exc))
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
