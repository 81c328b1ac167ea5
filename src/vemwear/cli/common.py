"""What every ``vemwear`` subcommand shares: exit codes, the help layout, the options of
the solving commands, printing rows.

Nothing here imports NumPy or the library when the module is imported: ``vemwear --help``
and ``--version`` stay fast.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

__all__ = [
    "EPILOG",
    "EXIT_CONVERGENCE",
    "EXIT_INPUT",
    "EXIT_INTERNAL",
    "EXIT_INTERRUPTED",
    "EXIT_OK",
    "PROG",
    "UsageError",
    "add_common_options",
    "add_debug_option",
    "add_subcommand",
    "positive_int",
    "rows_text",
    "say",
]

EXIT_OK = 0
EXIT_INTERNAL = 1
EXIT_INPUT = 2
EXIT_CONVERGENCE = 3
EXIT_INTERRUPTED = 130

PROG = "vemwear"
EPILOG = """\
exit codes:
  0    success
  1    unexpected internal error (rerun with --debug for a traceback)
  2    invalid input: configuration file, mesh, data, output directory or arguments
       (also a refused --resume)
  3    a solver did not converge
  130  interrupted (Ctrl-C, SIGTERM or SIGHUP)

`run` streams the finished time levels into OUTDIR/result.h5 and makes them durable
with a checkpoint every [output] checkpoint seconds and whenever it stops (codes 1, 3,
130; see OUTDIR/PARTIAL.txt). Even after a kill -9 or a power loss,
`vemwear run CONFIG -o OUTDIR --resume` continues from the last checkpoint and gives
the same result as an uninterrupted run. --force replaces only an output directory
that vemwear wrote (it holds a .vemwear marker); `vemwear clean OUTDIR` removes what
killed runs left behind.

The configuration file format is documented in docs/config.md.
"""


class UsageError(ValueError):
    """Arguments that do not go together (exit code 2)."""


def _formatter(prog: str) -> argparse.HelpFormatter:
    return argparse.RawDescriptionHelpFormatter(prog, max_help_position=30)


def add_subcommand(
    sub: argparse._SubParsersAction,  # type: ignore[type-arg]
    name: str,
    summary: str,
    description: str | None = None,
) -> argparse.ArgumentParser:
    """A subcommand parser with the common help layout (``summary`` is its ``--help`` line)."""
    return sub.add_parser(  # type: ignore[no-any-return]
        name,
        help=summary,
        description=summary if description is None else description,
        epilog=EPILOG,
        formatter_class=_formatter,
    )


def top_parser(description: str) -> argparse.ArgumentParser:
    """The ``vemwear`` parser itself (same layout as the subcommands)."""
    return argparse.ArgumentParser(
        prog=PROG, description=description, epilog=EPILOG, formatter_class=_formatter
    )


def add_debug_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--debug", action="store_true", help="print the full traceback on errors")


def _solver_methods() -> tuple[str, ...]:
    from ..solvers import SOLVERS

    return tuple(SOLVERS)


def add_common_options(
    p: argparse.ArgumentParser, *, solve: bool, outdir_required: bool = True
) -> None:
    """The options of the commands that solve (``solve``: OUTDIR, ``--force``, ``--solver``,
    ``--no-progress``) and ``--debug``; the solver methods are imported only here."""
    if solve:
        methods = _solver_methods()
        p.add_argument(
            "-o",
            "--outdir",
            required=outdir_required,
            metavar="OUTDIR",
            help="output directory: new, empty, or one vemwear wrote (with --force)",
        )
        p.add_argument(
            "--force",
            action="store_true",
            help="replace the output of an earlier vemwear run in OUTDIR (only the files "
            "vemwear wrote there; a directory vemwear did not write is never replaced)",
        )
        p.add_argument(
            "--solver",
            choices=methods,
            metavar="METHOD",
            help="step solver, overriding the configuration: " + " | ".join(methods),
        )
        p.add_argument(
            "--no-progress",
            action="store_true",
            help="do not show the progress bar of the time loop",
        )
    add_debug_option(p)


def positive_int(text: str) -> int:
    """An argparse type: a positive integer."""
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return v


def rows_text(rows: Sequence[tuple[str, str]]) -> str:
    """Two aligned columns, indented by two spaces."""
    if not rows:
        return ""
    w = max(len(a) for a, _ in rows)
    return "\n".join(f"  {a:<{w}}  {b}" for a, b in rows)


def say(msg: str) -> None:
    """A line on standard error."""
    print(msg, file=sys.stderr, flush=True)
