"""The ``vemwear`` command: the table of subcommands, the parser and the exit codes.

The subcommands are in their modules (:mod:`.run_cmd`: ``run``, ``check``, ``schema``;
:mod:`.paper_cmd`: ``example``, ``paper``, ``manufactured``; :mod:`.mesh_cmd`: ``mesh``;
:mod:`.outdir_cmd`: ``clean``, ``export``; :mod:`.study_cmd`: ``sweep``, ``fit``), each
with its parser set-up, its summary and its command. This module builds the parser,
runs the chosen command and maps exceptions to exit codes (also in ``vemwear --help``
and ``docs/config.md``): 0 success, 1 unexpected internal error, 2 invalid input
(configuration, mesh, data, output directory, command line), 3 a solver did not
converge, 130 interrupted.

Only the parser of the chosen subcommand is filled in, and the library is imported
when a command runs, so that ``vemwear --help`` and ``--version`` start fast.
"""

from __future__ import annotations

import argparse
import errno
import logging
import os
import sys
import traceback
import warnings
from collections.abc import Callable, Sequence
from contextlib import suppress
from typing import NoReturn

from .. import __version__
from . import mesh_cmd, outdir_cmd, paper_cmd, run_cmd, study_cmd
from .common import (
    EXIT_CONVERGENCE,
    EXIT_INPUT,
    EXIT_INTERNAL,
    EXIT_INTERRUPTED,
    EXIT_OK,
    PROG,
    UsageError,
    add_subcommand,
    say,
    top_parser,
)

__all__ = [
    "EXIT_CONVERGENCE",
    "EXIT_INPUT",
    "EXIT_INTERNAL",
    "EXIT_INTERRUPTED",
    "EXIT_OK",
    "build_parser",
    "command_environment",
    "main",
]

Setup = Callable[[argparse.ArgumentParser], None]


# ---------------------------------------------------------------------------- parser
#: The subcommands: name -> (summary, description or None, setup).
COMMANDS: dict[str, tuple[str, str | None, Setup]] = {
    "run": (run_cmd.RUN_SUMMARY, None, run_cmd.setup_run),
    "check": (run_cmd.CHECK_SUMMARY, None, run_cmd.setup_check),
    "schema": (run_cmd.SCHEMA_SUMMARY, None, run_cmd.setup_schema),
    "example": (paper_cmd.EXAMPLE_SUMMARY, None, paper_cmd.setup_example),
    "paper": (paper_cmd.PAPER_SUMMARY, None, paper_cmd.setup_paper),
    "manufactured": (paper_cmd.MANUFACTURED_SUMMARY, None, paper_cmd.setup_manufactured),
    "mesh": (mesh_cmd.SUMMARY, None, mesh_cmd.setup),
    "clean": (outdir_cmd.CLEAN_SUMMARY, None, outdir_cmd.setup_clean),
    "export": (outdir_cmd.EXPORT_SUMMARY, None, outdir_cmd.setup_export),
    "sweep": (study_cmd.SWEEP_SUMMARY, None, study_cmd.setup_sweep),
    "fit": (study_cmd.FIT_SUMMARY, None, study_cmd.setup_fit),
}


def _chosen(argv: Sequence[str] | None) -> str | None:
    """The subcommand named in ``argv`` (the first word that is not an option)."""
    for a in argv or ():
        if not a.startswith("-"):
            return a if a in COMMANDS else None
    return None


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The argument parser of the ``vemwear`` command.

    Parameters
    ----------
    argv : sequence of str, optional
        The arguments to be parsed: only the subcommand they name is filled in (the
        others keep their one-line summary). Without them, every subcommand is.
    """
    parser = top_parser(
        "Quasistatic frictional contact with wear on polygonal meshes by the "
        "virtual element method."
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", title="commands")
    sub.required = True
    chosen = _chosen(argv) if argv is not None else None
    for name, (summary, description, setup) in COMMANDS.items():
        p = add_subcommand(sub, name, summary, description)
        if argv is None or name == chosen:
            setup(p)
    return parser


# ---------------------------------------------------------------------------- entry point
def _is(exc: BaseException, module: str, name: str) -> bool:
    """``isinstance(exc, module.name)`` without importing ``module`` (if it is not
    imported, ``exc`` cannot be one of its classes)."""
    mod = sys.modules.get(module)
    return mod is not None and isinstance(exc, getattr(mod, name))


def _exit_code(exc: BaseException) -> tuple[int, str]:
    """The exit code and the message of an exception that stopped a command."""
    if isinstance(exc, UsageError) or any(
        _is(exc, m, n)
        for m, n in (
            ("vemwear.config.errors", "ConfigError"),
            ("vemwear.runner.outdir", "OutputDirError"),
            ("vemwear.runner.plan", "PlanError"),
            ("vemwear.runner.entry", "LaunchError"),
            ("vemwear.mesh.polymesh", "MeshError"),
            ("vemwear.simulate.blocks", "DataError"),
        )
    ):
        return EXIT_INPUT, str(exc)
    if _is(exc, "vemwear.simulate.levels", "WearOverflowError") or _is(
        exc, "vemwear.runner.partial", "WornThroughError"
    ):
        return EXIT_CONVERGENCE, str(exc)
    if _is(exc, "vemwear.solvers.system", "FactorizationError"):
        return EXIT_CONVERGENCE, f"the solver failed: {exc}"
    if _is(exc, "vemwear.solvers.system", "ConvergenceError"):
        return EXIT_CONVERGENCE, f"the solver did not converge: {exc}"
    if isinstance(exc, MemoryError):
        return EXIT_INTERNAL, "out of memory; use a coarser mesh or keep fewer levels"
    if isinstance(exc, OSError) and exc.errno in (errno.ENOSPC, errno.EDQUOT):
        where = f" writing {exc.filename}" if exc.filename else ""
        return EXIT_INTERNAL, f"the disk is full{where}; free some space"
    return EXIT_INTERNAL, f"internal error: {type(exc).__name__}: {exc}"


def _refused_under_mpi(func: Callable[[argparse.Namespace], int]) -> int | None:
    """Exit code 2 for a command other than ``run`` started by an MPI launcher on
    several ranks (it would run once per rank), said by rank 0; None otherwise."""
    from ..util.mpi import launched

    job = launched()
    if job.size == 1 or func is run_cmd.cmd_run:
        return None
    if job.rank == 0:
        say(
            f"{PROG}: error: started as {job.size} MPI ranks: only `vemwear run` (with the "
            "petsc backend) runs on several ranks; run this command without mpirun"
        )
    return EXIT_INPUT


def _other_rank() -> bool:
    """Whether this process is a rank other than 0 of an MPI job."""
    from ..util.mpi import launched

    return launched().rank > 0


def _interrupted(exc: BaseException, debug: bool) -> int:
    """Ctrl-C, SIGTERM or SIGHUP (or an error raised while stopping for one): one line."""
    if debug:
        traceback.print_exception(exc)
    say(f"{PROG}: interrupted{getattr(exc, 'vemwear_note', '')}")
    return EXIT_INTERRUPTED


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``vemwear`` command line; returns the exit code.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments without the program name (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        0 success, 1 internal error, 2 invalid input, 3 no convergence, 130 interrupted.
    """
    args_list = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser(args_list)
    try:
        args = parser.parse_args(args_list)
    except SystemExit as exc:  # --help, --version, usage errors
        code = exc.code
        return code if isinstance(code, int) else (EXIT_OK if code is None else EXIT_INPUT)
    debug = bool(getattr(args, "debug", False))
    func: Callable[[argparse.Namespace], int] = args.func
    refused = _refused_under_mpi(func)
    if refused is not None:
        return refused
    from ..util.heap import keep_freed_memory

    keep_freed_memory()  # steady run times: no page faults for every new array
    try:
        from ..runner.signals import signals_as_interrupts

        with signals_as_interrupts(), warnings.catch_warnings():
            if not debug:  # overflows are reported by the checks of the library, in words
                warnings.simplefilter("ignore", RuntimeWarning)
            return func(args)
    except BrokenPipeError:  # stdout closed early (``vemwear check ... | head``): not an error
        try:  # no second error when Python flushes stdout at exit
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        except (OSError, ValueError):
            pass
        return EXIT_OK
    except KeyboardInterrupt as exc:
        return _interrupted(exc, debug)
    except Exception as exc:  # every error ends as one line with its exit code
        from ..runner.signals import stop_signal

        if stop_signal(exc) is not None:  # a library failing as it unwinds from the stop
            return _interrupted(exc, debug)
        code, msg = _exit_code(exc)
        if code == EXIT_INPUT and _other_rank():  # every rank meets it: rank 0 says it
            return code
        if debug:
            traceback.print_exception(exc)
        elif code == EXIT_INTERNAL:
            msg += " (rerun with --debug for the traceback)"
        say(f"{PROG}: error: {msg}{getattr(exc, 'vemwear_note', '')}")
        return code


def command_environment() -> None:
    """The environment of the command's process: pydantic's plugins off (unless
    ``PYDANTIC_DISABLE_PLUGINS`` is set).

    pydantic looks for plugins in the entry points of every installed distribution when
    it builds the first validator (10 to 20 ms with a hundred installed); no plugin
    observes the configuration models of a command.
    """
    os.environ.setdefault("PYDANTIC_DISABLE_PLUGINS", "__all__")


def entry() -> NoReturn:
    """The ``vemwear`` command (console script, ``python -m vemwear``): :func:`main`, exit.

    The process's environment is set first (:func:`command_environment`).

    A stopped command (130) leaves without the interpreter's teardown: its files are
    closed and its streams flushed by then, and the teardown only joins or destroys what
    the stop cut short (a Dask cluster's event loop and a worker being started again, or
    a library interrupted inside a write), which took seconds, and once aborted the
    process, turning the stop's exit code into SIGABRT's.
    """
    command_environment()
    code = main()
    if code == EXIT_INTERRUPTED:
        for stream in (sys.stdout, sys.stderr):
            with suppress(Exception):
                stream.flush()
        logging.shutdown()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":  # pragma: no cover
    # ``python -m vemwear.cli.main``: run the imported module, not this copy named __main__
    from vemwear.cli.main import entry as _entry

    _entry()
