"""``vemwear clean OUTDIR`` and ``vemwear export OUTDIR``: output directories of runs.

``clean`` removes the temporaries that killed runs left in or next to OUTDIR (and, with
``--all``, the files OUTDIR's marker says vemwear wrote); nothing else. ``clean
--cache`` shows where the user's cache of vemwear is and its size, and empties it. ``export`` writes
``result.npz`` from the streamed ``result.h5`` of a run whose arrays were too large to
be written in memory at the end of the run (on a machine with more memory).
"""

from __future__ import annotations

import argparse

from .common import EXIT_OK, PROG, UsageError, add_debug_option

__all__ = ["CLEAN_SUMMARY", "EXPORT_SUMMARY", "setup_clean", "setup_export"]

CLEAN_SUMMARY = "Remove what killed runs left in or next to an output directory."
EXPORT_SUMMARY = "Write result.npz of an output directory from its streamed result.h5."


def setup_clean(p: argparse.ArgumentParser) -> None:
    p.add_argument("outdir", metavar="OUTDIR", nargs="?", help="output directory of a run")
    p.add_argument(
        "--cache",
        action="store_true",
        help="show the size of vemwear's cache of reference solutions (in the user's cache "
        "directory, or VEMWEAR_CACHE_DIR) and empty it",
    )
    p.add_argument(
        "--all",
        action="store_true",
        help="also remove every file the directory's .vemwear marker lists (vemwear's own "
        "output); files vemwear did not write are never removed",
    )
    add_debug_option(p)
    p.set_defaults(func=cmd_clean)


def setup_export(p: argparse.ArgumentParser) -> None:
    p.add_argument("outdir", metavar="OUTDIR", help="output directory of a finished run")
    p.add_argument("--force", action="store_true", help="write result.npz again if it exists")
    add_debug_option(p)
    p.set_defaults(func=cmd_export)


def cmd_clean(args: argparse.Namespace) -> int:
    """``vemwear clean OUTDIR [--all]``, ``vemwear clean --cache``."""
    from ..runner.outdir import clean_output_dir

    if args.outdir is None and not args.cache:
        raise UsageError("clean: give OUTDIR, or --cache")
    if args.cache:
        from ..util.cache import clear_cache, user_cache_dir

        size, files = clear_cache()
        print(f"{PROG}: cache {user_cache_dir()}: {size / 1e6:.1f} MB in {files} file(s) removed")
        if args.outdir is None:
            return EXIT_OK
    removed = clean_output_dir(args.outdir, everything=args.all)
    if not removed:
        print(f"{PROG}: {args.outdir}: nothing to remove")
    for p in removed:
        print(f"{PROG}: removed {p}")
    return EXIT_OK


def cmd_export(args: argparse.Namespace) -> int:
    """``vemwear export OUTDIR``."""
    import contextlib

    from ..post.stream import export_npz
    from ..runner.outdir import add_to_marker, output_lock, read_marker

    ours = read_marker(args.outdir) is not None  # lock only what vemwear wrote
    try:
        with output_lock(args.outdir) if ours else contextlib.nullcontext():
            path = export_npz(args.outdir, force=args.force)
            add_to_marker(args.outdir, [path.name])
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    print(f"{PROG}: wrote {path}")
    return EXIT_OK
