"""Output directories: checked before any computation, never a trap for the user's files.

Every output directory vemwear writes holds a marker file ``.vemwear`` (JSON: format,
version, command, ``state`` — ``running``, ``partial`` or ``complete`` —, ``files``,
the top-level names vemwear wrote there, and ``manifest``, the size and modification
time of each of them when the marker was written). The rules:

* a missing directory is created; an existing **empty** directory, a mount point (a
  Docker volume) included, is written into as it is, never renamed or removed;
* a non-empty directory with the marker is refused unless ``--force``, which removes
  only the entries the marker lists (and vemwear's stale temporaries); anything else in
  it is kept. A user's file that the new output would overwrite (a ``forces.png`` put
  there after a run without figures), or one of the listed files changed since vemwear
  wrote it, makes ``--force`` refuse, naming it;
* a directory left by a run killed before its first checkpoint (only vemwear's lock,
  its marker and its stream, no live run holding the lock) is taken as empty by
  ``run``, and emptied by ``clean``;
* a non-empty directory without the marker is refused even with ``--force``: vemwear
  never deletes what it did not write;
* the place is checked for being writable (a probe file, removed at once) and for free
  space, before any computation;
* a run holds an exclusive lock on ``OUTDIR/.vemwear.lock`` (``flock``; the system
  releases it when the process dies, even by SIGKILL) from the moment the directory is
  ready, before any assembly: a second run into the same directory is refused at once
  (:func:`refuse_locked`, before it reads its configuration) and leaves nothing behind.

Temporaries of atomic writes (:mod:`vemwear.util.atomic`) left by a killed process are
found by :func:`stale_temporaries`, reported by ``vemwear run`` and removed by
``--force`` or ``vemwear clean``.
"""

from __future__ import annotations

import errno
import fcntl
import json
import os
import shutil
import tempfile
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from .. import __version__
from ..util.atomic import atomic_dir, is_temporary, write_atomic
from .checkpoint import CHECKPOINT_NAME

__all__ = [
    "LOCK_NAME",
    "MARKER_NAME",
    "PARTIAL_NAME",
    "OutputDirError",
    "add_to_marker",
    "atomic_output_dir",
    "changed_entries",
    "check_output_dir",
    "clean_output_dir",
    "completed_leftovers",
    "foreign_entries",
    "killed_before_checkpoint",
    "locked_by",
    "output_lock",
    "prepare_output_dir",
    "read_marker",
    "refuse_locked",
    "stale_temporaries",
    "write_marker",
]

#: The marker of a directory that vemwear wrote.
MARKER_NAME = ".vemwear"
#: The lock file of a running run.
LOCK_NAME = ".vemwear.lock"
_FORMAT = "vemwear-outdir/1"
#: Explanation written into the output directory of an unfinished run.
PARTIAL_NAME = "PARTIAL.txt"


class OutputDirError(ValueError):
    """The output directory cannot be used (a file, not empty, not vemwear's, locked, ...)."""


# ---------------------------------------------------------------------------- marker
def read_marker(outdir: str | os.PathLike[str]) -> dict[str, Any] | None:
    """The marker of ``outdir``, or None if it has none (or an unreadable one)."""
    try:
        data = json.loads((Path(outdir) / MARKER_NAME).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) and data.get("format") == _FORMAT else None


def write_marker(
    outdir: str | os.PathLike[str], state: str, files: Sequence[str], command: str = "run"
) -> None:
    """Write the marker of ``outdir`` atomically; ``files`` are the names vemwear wrote."""
    out = Path(outdir)
    old = read_marker(out) or {}
    names = sorted({*files, MARKER_NAME, LOCK_NAME} - {""})
    manifest = {n: _stamp(out / n) for n in names if n not in (MARKER_NAME, LOCK_NAME)}
    data = {
        "format": _FORMAT,
        "vemwear_version": __version__,
        "command": command,
        "state": state,
        "created": old.get("created") or datetime.now(UTC).isoformat(timespec="seconds"),
        "updated": datetime.now(UTC).isoformat(timespec="seconds"),
        "files": names,
        "manifest": {n: v for n, v in manifest.items() if v is not None},
    }
    write_atomic(out / MARKER_NAME, json.dumps(data, indent=2) + "\n")


def _stamp(p: Path) -> dict[str, int] | None:
    """Size (bytes, summed over a directory's files) and modification time of ``p``."""
    try:
        st = p.lstat()
    except OSError:
        return None
    size = st.st_size
    if p.is_dir() and not p.is_symlink():
        size = sum(f.lstat().st_size for f in p.rglob("*") if not f.is_dir())
    return {"size": int(size), "mtime_ns": int(st.st_mtime_ns)}


def foreign_entries(out: Path, marker: dict[str, Any]) -> list[str]:
    """The entries of ``out`` that its marker does not list (a user's files)."""
    ours = {*marker.get("files", []), MARKER_NAME, LOCK_NAME}
    return sorted(p.name for p in out.iterdir() if p.name not in ours and not is_temporary(p.name))


def changed_entries(out: Path, marker: dict[str, Any]) -> list[str]:
    """The listed entries of a complete output changed since vemwear wrote them."""
    if marker.get("state") != "complete":  # a stopped run's stream changes by design
        return []
    recorded = marker.get("manifest") or {}
    return sorted(n for n, v in recorded.items() if _stamp(out / n) not in (None, v))


def killed_before_checkpoint(outdir: str | os.PathLike[str]) -> bool:
    """Whether ``outdir`` holds only what a run killed before its first checkpoint left:
    its lock, a marker of a running run and that marker's files, no checkpoint, and no
    live run holding the lock (nothing in it can be continued)."""
    out = Path(outdir)
    if not out.is_dir() or locked_by(out) is not None or (out / CHECKPOINT_NAME).exists():
        return False
    names = {p.name for p in out.iterdir() if not is_temporary(p.name)}
    if not names:
        return False
    marker = read_marker(out)
    if marker is None:
        return names <= {LOCK_NAME, MARKER_NAME}  # an unreadable marker is not vemwear's
    return marker.get("state") == "running" and names <= {*marker["files"], LOCK_NAME}


def completed_leftovers(out: Path) -> list[Path]:
    """The checkpoint and ``PARTIAL.txt`` of a complete run killed just after its marker
    said so (they are removed after it is written)."""
    marker = read_marker(out)
    if marker is None or marker.get("state") != "complete":
        return []
    return [
        out / n
        for n in (CHECKPOINT_NAME, PARTIAL_NAME)
        if n not in marker.get("files", []) and (out / n).exists()
    ]


def add_to_marker(outdir: str | os.PathLike[str], names: Sequence[str]) -> None:
    """Record more files vemwear wrote in ``outdir`` (if it has a marker)."""
    old = read_marker(outdir)
    if old is not None:
        write_marker(outdir, old["state"], [*old["files"], *names], old.get("command", "run"))


# ---------------------------------------------------------------------------- lock
def locked_by(outdir: str | os.PathLike[str]) -> int | None:
    """The pid of the vemwear process holding the lock of ``outdir`` (0 if unknown), or
    None if no run holds it. Creates nothing."""
    path = Path(outdir) / LOCK_NAME
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        try:
            return int(os.read(fd, 32).decode() or 0)
        except ValueError:
            return 0
    else:
        fcntl.flock(fd, fcntl.LOCK_UN)
        return None
    finally:
        os.close(fd)


@contextmanager
def output_lock(outdir: str | os.PathLike[str]) -> Iterator[None]:
    """Hold the lock of ``outdir`` (which must exist) for the duration of the block.

    Raises
    ------
    OutputDirError
        If another process holds it.
    """
    out = Path(outdir)
    fd = os.open(out / LOCK_NAME, os.O_RDWR | os.O_CREAT, 0o666)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            pid = os.read(fd, 32).decode().strip() or "?"
            raise OutputDirError(
                f"another vemwear run (pid {pid}) is writing into {out}; wait for it to end "
                "or choose another output directory"
            ) from None
        os.ftruncate(fd, 0)
        os.write(fd, str(os.getpid()).encode())
        yield
    finally:
        os.close(fd)  # releases the lock


def refuse_locked(outdir: str | os.PathLike[str]) -> None:
    """Raise :class:`OutputDirError` if a run holds the lock of ``outdir`` (a cheap check,
    made before any work; creates nothing)."""
    out = Path(outdir).expanduser().absolute()
    pid = locked_by(out) if out.is_dir() else None
    if pid is not None:
        raise OutputDirError(
            f"another vemwear run (pid {pid or '?'}) is writing into {out}; wait for it to "
            "end or choose another output directory"
        )


# ---------------------------------------------------------------------------- checks
def stale_temporaries(outdir: str | os.PathLike[str]) -> list[Path]:
    """vemwear's temporaries left by killed processes: inside ``outdir`` and its
    ``.NAME.tmp-XXXXXXXX`` siblings. Empty while a run holds the directory's lock."""
    out = Path(outdir).expanduser().absolute()
    found: list[Path] = []
    if out.is_dir() and locked_by(out) is None:
        found += [p for p in out.iterdir() if is_temporary(p.name)]
    if out.parent.is_dir():
        prefix = f".{out.name}.tmp-"
        found += [p for p in out.parent.iterdir() if p.name.startswith(prefix)]
    return sorted(found)


def _remove(p: Path) -> None:
    if p.is_dir() and not p.is_symlink():
        shutil.rmtree(p)
    else:
        p.unlink(missing_ok=True)


def clean_output_dir(outdir: str | os.PathLike[str], *, everything: bool = False) -> list[Path]:
    """Remove vemwear's stale temporaries of ``outdir`` (and, with ``everything``, the
    files its marker lists); return what was removed. Nothing else is touched."""
    out = Path(outdir).expanduser().absolute()
    pid = locked_by(out) if out.is_dir() else None
    if pid is not None:
        raise OutputDirError(f"a vemwear run (pid {pid}) is writing into {out}; not cleaning")
    removed = stale_temporaries(out)
    if killed_before_checkpoint(out):  # a run killed in its set-up: nothing to keep
        removed += [p for p in out.iterdir() if not is_temporary(p.name)]
    elif everything:
        marker = read_marker(out)
        if marker is None:
            raise OutputDirError(f"{out} has no vemwear marker ({MARKER_NAME}); not cleaning")
        names = [n for n in marker.get("files", []) if n and "/" not in n and n != MARKER_NAME]
        removed += [out / n for n in names if (out / n).exists() or (out / n).is_symlink()]
        removed.append(out / MARKER_NAME)
    elif out.is_dir():
        removed += completed_leftovers(out)
    for p in removed:
        _remove(p)
    return removed


def _check_place(out: Path, protect: Sequence[str | os.PathLike[str]]) -> None:
    resolved = out.resolve()
    for p in (Path.cwd(), *protect):
        q = Path(p).expanduser().resolve()
        if q == resolved or resolved in q.parents:
            raise OutputDirError(
                f"output directory {out} contains {q}; choose a new directory for the output"
            )
    if out.is_symlink() or (out.exists() and not out.is_dir()):
        raise OutputDirError(f"output path {out} exists and is not a directory")
    if out.parent.exists() and not out.parent.is_dir():
        raise OutputDirError(f"cannot create {out}: {out.parent} is not a directory")


def _refuse_users_files(out: Path, marker: dict[str, Any], reserved: Sequence[str]) -> None:
    """--force: refuse if the new output would overwrite a file vemwear did not write."""
    changed = changed_entries(out, marker)
    if changed:
        raise OutputDirError(
            f"--force refused: {out / changed[0]} changed since vemwear wrote it (a user's "
            "file?); move it away or choose another output directory"
        )
    clash = [n for n in foreign_entries(out, marker) if n in set(reserved)]
    if clash:
        raise OutputDirError(
            f"--force refused: {out / clash[0]} was not written by vemwear and the new "
            "output has a file of that name; move it away or choose another output directory"
        )


def _existing_ancestor(p: Path) -> Path:
    while not p.exists():
        p = p.parent
    return p


def _size(n: float) -> str:
    return f"{n / 1e9:.2f} GB" if n >= 1e9 else f"{n / 1e6:.1f} MB"


def check_output_dir(
    outdir: str | os.PathLike[str],
    force: bool = False,
    protect: Sequence[str | os.PathLike[str]] = (),
    need_bytes: int = 0,
    reserved: Sequence[str] = (),
) -> Path:
    """Check that ``outdir`` may receive vemwear's output, creating nothing.

    Parameters
    ----------
    outdir : path
        The output directory.
    force : bool
        Allow replacing the output of an earlier vemwear run there (its marker's files).
    protect : sequence of paths
        Paths that must not lie inside ``outdir`` (the configuration file; the current
        working directory always).
    need_bytes : int
        Free space the output needs.
    reserved : sequence of str
        The names the output may have: a user's entry of one of these names refuses
        ``force`` (it would be overwritten).

    Returns
    -------
    Path
        The absolute output path.

    Raises
    ------
    OutputDirError
        Naming the directory and the problem.
    """
    out = Path(outdir).expanduser().absolute()
    _check_place(out, protect)
    refuse_locked(out)
    if out.is_dir() and not killed_before_checkpoint(out):
        if any(not is_temporary(p.name) for p in out.iterdir()):  # stale ones: a warning
            marker = read_marker(out)
            if marker is None:
                raise OutputDirError(
                    f"output directory {out} is not empty and was not written by vemwear (no "
                    f"{MARKER_NAME} marker); --force replaces only vemwear's own output "
                    "directories: choose another directory"
                )
            if not force:
                raise OutputDirError(
                    f"output directory {out} holds the output of an earlier vemwear run; "
                    "use --force to replace it"
                )
            _refuse_users_files(out, marker, reserved)
    anc = _existing_ancestor(out)
    if not os.access(anc, os.W_OK | os.X_OK):
        raise OutputDirError(f"cannot write into {out}: {anc} is not writable")
    if need_bytes > 0:
        free = shutil.disk_usage(anc).free
        if free < need_bytes:
            raise OutputDirError(
                f"not enough free disk for {out}: the output needs about {_size(need_bytes)}, "
                f"{_size(free)} are free there; store fewer levels ([output] store_u, every) "
                "or use --force-size to run anyway"
            )
    return out


#: The probe's name is a temporary's (``.NAME.tmp-XXXXXXXX``): one left by a process
#: killed while probing is found and removed like any stale temporary.
PROBE_PREFIX = ".vemwear-probe.tmp-"


def _probe(out: Path) -> None:
    """Write and remove a file in ``out``: writable for real (also for root, read-only
    mounts and full disks)."""
    try:
        fd, name = tempfile.mkstemp(dir=out, prefix=PROBE_PREFIX)
        try:
            os.write(fd, b"0" * 4096)
            os.fsync(fd)
        finally:
            os.close(fd)
            os.unlink(name)
    except OSError as exc:
        why = "the disk is full" if exc.errno in (errno.ENOSPC, errno.EDQUOT) else exc.strerror
        raise OutputDirError(f"cannot write into {out}: {why}") from None


def prepare_output_dir(
    outdir: str | os.PathLike[str],
    *,
    force: bool = False,
    protect: Sequence[str | os.PathLike[str]] = (),
    need_bytes: int = 0,
    command: str = "run",
    reserved: Sequence[str] = (),
) -> Path:
    """Check ``outdir`` (:func:`check_output_dir`), create it if missing, remove the files
    of an earlier vemwear run there if ``force``, and check that it takes a file.

    A directory created here is removed again if a later check fails, so a refused run
    leaves nothing behind. What a run killed before its first checkpoint left there is
    removed (:func:`killed_before_checkpoint`).
    """
    out = check_output_dir(outdir, force, protect, need_bytes, reserved)
    if killed_before_checkpoint(out):
        clean_output_dir(out)
    created = not out.exists()
    out.mkdir(parents=True, exist_ok=True)
    try:
        _probe(out)
    except OutputDirError:
        if created:
            shutil.rmtree(out, ignore_errors=True)
        raise
    if not created and force and any(out.iterdir()):
        clean_output_dir(out, everything=True)
    return out


@contextmanager
def atomic_output_dir(outdir: str | os.PathLike[str], force: bool = False) -> Iterator[Path]:
    """A directory to write a whole output into, which becomes ``outdir`` on success.

    A new ``outdir``, or (with ``force``) one holding an earlier vemwear output, is
    written as a temporary sibling that takes its place when the block succeeds: a
    failed block leaves the old output as it was, and the entries of the old directory
    that vemwear did not write are moved into the new one. An existing empty directory
    or a mount point is written into in place (never renamed); on failure what the block
    wrote there is removed. The marker is written last.

    Yields
    ------
    Path
        The directory to write into.

    Raises
    ------
    OutputDirError
        As :func:`check_output_dir`.
    """
    out = check_output_dir(outdir, force)
    empty = out.is_dir() and not any(out.iterdir())
    if out.is_dir() and (empty or os.path.ismount(out)):
        out = prepare_output_dir(out, force=force)
        before = {p.name for p in out.iterdir()}
        try:
            yield out
        except BaseException:
            for p in out.iterdir():
                if p.name not in before:
                    _remove(p)
            raise
        write_marker(out, "complete", [p.name for p in out.iterdir()], "example")
        return
    old = read_marker(out) if out.is_dir() else None
    with atomic_dir(out) as tmp:
        yield tmp
        write_marker(tmp, "complete", [p.name for p in tmp.iterdir()], "example")
        if old is not None:  # keep what the user put into the old output directory
            users = foreign_entries(out, old)
            clash = [n for n in users if (tmp / n).exists() or (tmp / n).is_symlink()]
            if clash:  # the old output stays as it was
                raise OutputDirError(
                    f"{out / clash[0]} was not written by vemwear and the new output has a "
                    "file of that name; move it away and run again"
                )
            for name in users:
                os.replace(out / name, tmp / name)
