"""Atomic writes of files and directories: the one helper every writer uses.

A file is written under a temporary name in its own directory (``.NAME.tmp-XXXXXXXX``
plus the target's suffix, so that writers choosing a format by suffix still work)
and renamed onto the target only once it is complete; a directory likewise. An
error, ``Ctrl-C`` or ``SystemExit`` inside the block removes the temporary, so a
reader sees the old file or the new one, never half of one. With ``durable=True``
the data and the rename are also flushed to the disk (``fsync`` of the file and of
its directory), as checkpoints need.

Temporary names are recognised by :func:`is_temporary`, so that what a killed
process left behind can be found and removed.
"""

from __future__ import annotations

import os
import re
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

__all__ = [
    "atomic_dir",
    "atomic_file",
    "fsync_dir",
    "is_temporary",
    "umask",
    "write_atomic",
]

_TMP = ".tmp-"
_TEMP_NAME = re.compile(r"\..+\.tmp-[A-Za-z0-9_]{8}(\.[^.]*)?")


def umask() -> int:
    """The process's file mode creation mask."""
    mask = os.umask(0)
    os.umask(mask)
    return mask


def is_temporary(name: str) -> bool:
    """True for the name of a temporary made by :func:`atomic_file` or :func:`atomic_dir`."""
    return bool(_TEMP_NAME.fullmatch(name))


def fsync_dir(path: str | os.PathLike[str]) -> None:
    """Flush a directory's entries (a rename in it) to the disk; a no-op where unsupported."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _fsync_file(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


@contextmanager
def atomic_file(path: str | os.PathLike[str], *, durable: bool = False) -> Iterator[Path]:
    """A temporary file next to ``path`` (same suffix) that replaces ``path`` on success.

    Parameters
    ----------
    path : path
        The target; its directory is created if missing.
    durable : bool
        ``fsync`` the file before and its directory after the rename.

    Yields
    ------
    Path
        The temporary file (it exists, empty); write it by name.

    Examples
    --------
    >>> with atomic_file("out/result.txt") as tmp:     # doctest: +SKIP
    ...     tmp.write_text("done")
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(
        dir=target.parent, prefix=f".{target.stem or target.name}{_TMP}", suffix=target.suffix
    )
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~umask())  # mkstemp makes 0600: give the usual mode
        if durable:
            _fsync_file(tmp)
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    if durable:
        fsync_dir(target.parent)


def write_atomic(path: str | os.PathLike[str], data: bytes | str, *, durable: bool = False) -> Path:
    """Write ``data`` (text as UTF-8) to ``path`` atomically (:func:`atomic_file`)."""
    raw = data.encode("utf-8") if isinstance(data, str) else data
    with atomic_file(path, durable=durable) as tmp:
        tmp.write_bytes(raw)
    return Path(path)


@contextmanager
def atomic_dir(path: str | os.PathLike[str]) -> Iterator[Path]:
    """A temporary directory next to ``path`` that becomes ``path`` on success.

    An existing ``path`` is replaced only once the block has succeeded (moved aside,
    the new one renamed into place, the old one removed). The caller decides whether
    ``path`` may be replaced.

    Yields
    ------
    Path
        The temporary directory to write into.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(dir=target.parent, prefix=f".{target.name}{_TMP}"))
    try:
        yield tmp
        os.chmod(tmp, 0o777 & ~umask())  # mkdtemp makes 0700
        if target.is_dir() and not target.is_symlink():
            old = Path(tempfile.mkdtemp(dir=target.parent, prefix=f".{target.name}{_TMP}"))
            os.rmdir(old)
            os.replace(target, old)  # move the old one aside ...
            try:
                os.replace(tmp, target)  # ... put the new one in place ...
            except BaseException:
                os.replace(old, target)  # ... or restore the old one
                raise
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(tmp, target)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
