"""Output directories: checked before any computation, never a trap for the user's files.

Every output directory vemwear writes holds a marker file ``.vemwear`` (JSON: format,
version, command, ``state`` — ``running``, ``partial`` or ``complete`` — and ``files``,
the top-level names vemwear wrote there). The rules:

* a missing directory is created; an existing **empty** directory, a mount point (a
  Docker volume) included, is written into as it is, never renamed or removed;
* a non-empty directory with the marker is refused unless ``--force``, which removes
  only the entries the marker lists (and vemwear's stale temporaries); anything else in
  it is kept;
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

__all__ = [
    "LOCK_NAME",
    "MARKER_NAME",
    "OutputDirError",
    "add_to_marker",
    "atomic_output_dir",
    "check_output_dir",
    "clean_output_dir",
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
    data = {
        "format": _FORMAT,
        "vemwear_version": __version__,
        "command": command,
        "state": state,
        "created": old.get("created") or datetime.now(UTC).isoformat(timespec="seconds"),
        "updated": datetime.now(UTC).isoformat(timespec="seconds"),
        "files": names,
    }
    write_atomic(out / MARKER_NAME, json.dumps(data, indent=2) + "\n")


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
    if everything:
        marker = read_marker(out)
        if marker is None:
            raise OutputDirError(f"{out} has no vemwear marker ({MARKER_NAME}); not cleaning")
        names = [n for n in marker.get("files", []) if n and "/" not in n and n != MARKER_NAME]
        removed += [out / n for n in names if (out / n).exists() or (out / n).is_symlink()]
        removed.append(out / MARKER_NAME)
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
    if out.is_dir():
        if any(out.iterdir()):
            if read_marker(out) is None:
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


def _probe(out: Path) -> None:
    """Write and remove a file in ``out``: writable for real (also for root, read-only
    mounts and full disks)."""
    try:
        fd, name = tempfile.mkstemp(dir=out, prefix=".vemwear-probe-")
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
) -> Path:
    """Check ``outdir`` (:func:`check_output_dir`), create it if missing, remove the files
    of an earlier vemwear run there if ``force``, and check that it takes a file.

    A directory created here is removed again if a later check fails, so a refused run
    leaves nothing behind.
    """
    out = check_output_dir(outdir, force, protect, need_bytes)
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
            ours = set(old.get("files", []))
            for p in out.iterdir():
                if p.name not in ours and not is_temporary(p.name) and not (tmp / p.name).exists():
                    os.replace(p, tmp / p.name)
