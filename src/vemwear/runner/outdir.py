"""Output directories of runs: checked before any computation, written atomically.

A run writes into a temporary sibling of the output directory (``.NAME.tmp-XXXX``
next to ``NAME``, :func:`vemwear.util.atomic.atomic_dir`) that is renamed into place
only once everything is written. An existing non-empty output directory is refused
unless ``force=True``; it is then replaced only after the new run has completed. On
any error, ``Ctrl-C`` or ``SystemExit`` the temporary directory is removed, so a
failed run never leaves half-written output behind (and never destroys an older one).
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

from ..util.atomic import atomic_dir

__all__ = ["OutputDirError", "atomic_output_dir", "check_output_dir"]


class OutputDirError(ValueError):
    """The output directory cannot be used (exists and is not empty, is a file, ...)."""


def _is_empty_dir(p: Path) -> bool:
    return p.is_dir() and not any(p.iterdir())


def check_output_dir(
    outdir: str | os.PathLike[str],
    force: bool = False,
    protect: Sequence[str | os.PathLike[str]] = (),
) -> Path:
    """Check that ``outdir`` can receive a run's output, before any computation.

    Parameters
    ----------
    outdir : path
        The output directory.
    force : bool
        Allow replacing an existing non-empty directory.
    protect : sequence of paths
        Paths that must not lie inside ``outdir`` (even with ``force``), e.g. the
        configuration file; the current working directory is always protected.

    Returns
    -------
    Path
        The absolute output path.

    Raises
    ------
    OutputDirError
        If ``outdir`` exists and is not a directory, or is a non-empty directory and
        ``force`` is False, or its parent cannot hold the temporary directory.
    """
    out = Path(outdir).expanduser().absolute()
    resolved = out.resolve()
    for p in (Path.cwd(), *protect):
        q = Path(p).expanduser().resolve()
        if q == resolved or resolved in q.parents:
            raise OutputDirError(
                f"output directory {out} contains {q}; choose a new directory for the output"
            )
    if out.exists() or out.is_symlink():
        if not out.is_dir() or out.is_symlink():
            raise OutputDirError(f"output path {out} exists and is not a directory")
        if not force and not _is_empty_dir(out):
            raise OutputDirError(
                f"output directory {out} exists and is not empty; use --force to replace it"
            )
    parent = out.parent
    if parent.exists() and not parent.is_dir():
        raise OutputDirError(f"cannot create {out}: {parent} is not a directory")
    anc = parent
    while not anc.exists():
        anc = anc.parent
    if not os.access(anc, os.W_OK | os.X_OK):
        raise OutputDirError(f"cannot create {out}: {anc} is not writable")
    return out


@contextmanager
def atomic_output_dir(outdir: str | os.PathLike[str], force: bool = False) -> Iterator[Path]:
    """Context manager yielding a temporary directory that becomes ``outdir`` on success.

    Parameters
    ----------
    outdir : path
        Final output directory.
    force : bool
        Replace an existing non-empty ``outdir`` (only once the block has succeeded).

    Yields
    ------
    Path
        The temporary directory to write into.

    Raises
    ------
    OutputDirError
        As :func:`check_output_dir`, on entry and again just before the rename (in
        case another process created ``outdir`` meanwhile).
    """
    out = check_output_dir(outdir, force)
    with atomic_dir(out) as tmp:
        yield tmp
        if out.exists() or out.is_symlink():  # created by another process meanwhile?
            if not out.is_dir() or out.is_symlink():
                raise OutputDirError(f"output path {out} exists and is not a directory")
            if _is_empty_dir(out):
                out.rmdir()
            elif not force:
                raise OutputDirError(
                    f"output directory {out} appeared during the run and is not empty; "
                    "use --force to replace it"
                )
