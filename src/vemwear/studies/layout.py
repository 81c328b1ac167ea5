"""The layout of a study's output directory and the records of its runs.

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

The client (:mod:`~vemwear.studies.execute`) and the tasks on the workers
(:mod:`~vemwear.studies.tasks`) both read and write it: the output directory must be on
a file system every worker sees. Temporaries of killed writes (``.NAME.tmp-XXXXXXXX``)
are removed by the next execution: those of OUTDIR, ``configs`` and ``log`` when it
takes OUTDIR's lock, those of a run's directory before the run is computed again
(:func:`remove_temporaries`).
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from ..util.atomic import is_temporary, write_atomic

__all__ = [
    "CONFIGS_DIR",
    "LOG_DIR",
    "RUNS_DIR",
    "complete_record",
    "is_complete",
    "open_study_dir",
    "read_record",
    "record_failure",
    "remove_temporaries",
    "write_record",
]

RUNS_DIR = "runs"
CONFIGS_DIR = "configs"
LOG_DIR = "log"


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


def remove_temporaries(out: Path, *subdirs: str) -> list[Path]:
    """Remove the temporaries of killed writes in ``out`` and its ``subdirs`` (their
    writer is gone: the caller holds the directory's lock or found it free); return
    them."""
    found = [
        p
        for d in (out, *(out / s for s in subdirs))
        if d.is_dir()
        for p in d.iterdir()
        if is_temporary(p.name) and p.is_file()
    ]
    for p in found:
        p.unlink(missing_ok=True)
    return found


def is_complete(rundir: Path) -> bool:
    """Whether ``rundir`` holds the complete result of a run."""
    from ..post.adaptive_stream import is_adaptive
    from ..runner.outdir import read_marker

    m = read_marker(rundir) if rundir.is_dir() else None
    if not (m and m.get("state") == "complete"):
        return False
    return (rundir / "result.npz").is_file() or is_adaptive(rundir / "result.h5")


def read_record(out: Path, rid: str) -> dict[str, Any] | None:
    """The logged record of run ``rid``, or None."""
    try:
        rec = json.loads((out / LOG_DIR / f"{rid}.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return rec if isinstance(rec, dict) else None


def complete_record(out: Path, rid: str, params: dict[str, Any], executed: bool) -> dict:
    """The record of a run whose directory holds a complete result (its wall time and
    warnings from the logged record, if that is there). A run killed after its result
    was complete but before its record was logged is logged now."""
    old = read_record(out, rid) or {}
    rec = {
        "id": rid,
        "params": params,
        "status": "done",
        "error": "",
        "wall_time": old.get("wall_time", float("nan")),
        "executed": executed,
        "warnings": list(old.get("warnings", [])),
    }
    if old.get("status") != "done":
        write_record(out, rec)
    return rec


def write_record(out: Path, rec: dict[str, Any]) -> None:
    """Log ``rec`` as the record of its run (``OUTDIR/log/<id>.json``)."""
    write_atomic(out / LOG_DIR / f"{rec['id']}.json", json.dumps(rec, indent=2) + "\n")


def record_failure(out: Path, rid: str, params: dict[str, Any], msg: str) -> dict[str, Any]:
    """Log run ``rid`` as failed with the error ``msg``; returns its record."""
    rec = {
        "id": rid,
        "params": params,
        "status": "failed",
        "error": msg,
        "wall_time": float("nan"),
        "executed": True,
        "finished": datetime.now(UTC).isoformat(timespec="seconds"),
    }
    write_record(out, rec)
    return rec
