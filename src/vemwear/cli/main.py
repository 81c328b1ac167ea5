"""The ``vemwear`` command: ``run``, ``check``, ``schema``, ``example``, ``paper``, ...

This module parses arguments, calls the library (:mod:`vemwear.runner` for runs,
:mod:`vemwear.paper` for the examples), prints, and maps exceptions to exit codes
(also in ``vemwear --help`` and ``docs/config.md``): 0 success, 1 unexpected internal
error, 2 invalid input (configuration, mesh, data, output directory, command line),
3 a solver did not converge, 130 interrupted.

Only the parser of the chosen subcommand is filled in, and the library is imported
when a command runs, so that ``vemwear --help`` and ``--version`` start fast.
Its length (about 700 lines) is the arguments and help texts of every
subcommand: one job, kept in one place so that the command table reads at a glance.
"""

from __future__ import annotations

import argparse
import errno
import os
import sys
import time
import traceback
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .. import __version__
from . import mesh_cmd, outdir_cmd, study_cmd
from .common import (
    EXIT_CONVERGENCE,
    EXIT_INPUT,
    EXIT_INTERNAL,
    EXIT_INTERRUPTED,
    EXIT_OK,
    PROG,
    UsageError,
    add_debug_option,
    add_subcommand,
    positive_int,
    rows_text,
    say,
    top_parser,
)

if TYPE_CHECKING:
    from ..simulate import SolverOptions

__all__ = [
    "EXIT_CONVERGENCE",
    "EXIT_INPUT",
    "EXIT_INTERNAL",
    "EXIT_INTERRUPTED",
    "EXIT_OK",
    "build_parser",
    "main",
]

Setup = Callable[[argparse.ArgumentParser], None]


# ---------------------------------------------------------------------------- parser
def _solver_methods() -> tuple[str, ...]:
    from ..solvers import SOLVERS

    return tuple(SOLVERS)


def _common(p: argparse.ArgumentParser, *, solve: bool, outdir_required: bool = True) -> None:
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


def _setup_run(p: argparse.ArgumentParser) -> None:
    p.add_argument("config", metavar="CONFIG.toml", help="configuration file (docs/config.md)")
    _common(p, solve=True)
    _force_size(p)
    p.add_argument(
        "--resume",
        action="store_true",
        help="continue a stopped or killed run from its last checkpoint in OUTDIR "
        "(refused if the physics, the discretization or the kept levels changed; the "
        "solver options may change); the result is the one of an uninterrupted run",
    )
    p.set_defaults(func=cmd_run)


def _force_size(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--force-size",
        action="store_true",
        help="run even if the estimated memory or disk exceeds what is available",
    )


def _setup_check(p: argparse.ArgumentParser) -> None:
    p.add_argument("config", metavar="CONFIG.toml", help="configuration file (docs/config.md)")
    _force_size(p)
    _common(p, solve=False)
    p.set_defaults(func=cmd_check)


def _setup_schema(p: argparse.ArgumentParser) -> None:
    p.add_argument("--indent", type=int, default=2, metavar="N", help="indentation (default 2)")
    p.set_defaults(func=cmd_schema)


def _example_listing() -> str:
    from ..paper import available_examples

    return "\n".join(f"  {name:<5}{text}" for name, text in available_examples().items())


def _setup_example(p: argparse.ArgumentParser) -> None:
    from ..paper import available_examples

    examples = available_examples()
    p.description = f"{p.description}\n\navailable examples:\n{_example_listing()}"
    p.add_argument(
        "name",
        metavar="NAME",
        nargs="?",
        choices=[*examples, "orders"],
        help="example number: " + ", ".join(examples) + "; or orders (k = 1 against k = 2)",
    )
    p.add_argument("--list", action="store_true", help="list the examples and exit")
    p.add_argument(
        "--order",
        type=int,
        choices=(1, 2),
        default=1,
        help="order k of the virtual element space (default 1, the paper's; 2 for "
        "examples 5.2, 5.3, 5.4)",
    )
    _common(p, solve=True, outdir_required=False)
    p.add_argument(
        "--quick",
        action="store_true",
        help="example 3d only: small sizes (8 + 16 cells, h = 1, 1/2 against 1/4), seconds",
    )
    g = p.add_argument_group("Example 5.5 only")
    g.add_argument(
        "--reference-h",
        type=_inverse_h,
        metavar="N",
        help="reference h = k = 1/N (default 256; 128 or 64 for quick runs); N or 1/N",
    )
    g.add_argument(
        "--levels",
        type=_levels_list,
        metavar="LIST",
        help="coarse h = k = 1/n for n in LIST (default: those of 4,8,16,32,64 "
        "below the reference)",
    )
    g.add_argument(
        "--cache",
        metavar="DIR",
        help="cache directory of the reference solution (default OUTDIR/../.vemwear-cache)",
    )
    p.set_defaults(func=cmd_example)


def _setup_paper(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--quick",
        action="store_true",
        help="Example 5.5 against the reference h = k = 1/64 instead of 1/256 "
        "(levels 1/4 ... 1/32)",
    )
    p.add_argument(
        "--cache",
        metavar="DIR",
        help="cache directory of the Example 5.5 reference (default OUTDIR/../.vemwear-cache)",
    )
    _common(p, solve=True)
    p.set_defaults(func=cmd_paper)


def _setup_manufactured(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--families",
        type=_families_list,
        metavar="LIST",
        help="comma-separated mesh families (default squares,triangles,voronoi,"
        "hanging; also distorted, hexagons, nonconvex)",
    )
    p.add_argument(
        "--levels",
        type=positive_int,
        default=4,
        metavar="N",
        help="number of meshes per family, n = N0, 2 N0, ... (default 4)",
    )
    p.add_argument(
        "--n0",
        type=positive_int,
        default=4,
        metavar="N0",
        help="cells per side of the coarsest mesh (default 4)",
    )
    p.add_argument("--markdown", action="store_true", help="print a Markdown table")
    p.add_argument("--csv", metavar="FILE", help="also write the table as CSV to FILE")
    p.add_argument(
        "--order",
        type=int,
        choices=(1, 2),
        default=1,
        help="order k of the virtual element space (default 1; 2: expected orders H1 2, L2 3)",
    )
    _common(p, solve=False)
    p.set_defaults(func=cmd_manufactured)


#: The subcommands: name -> (summary, description or None, setup).
COMMANDS: dict[str, tuple[str, str | None, Setup]] = {
    "run": (
        "Validate a configuration file, solve the problem and write the results.",
        None,
        _setup_run,
    ),
    "check": (
        "Validate a configuration file and summarize the problem, without solving.",
        None,
        _setup_check,
    ),
    "schema": (
        "Print the JSON Schema of configuration files (for editors' completion and checks).",
        None,
        _setup_schema,
    ),
    "example": (
        "Run one of the paper's numerical examples and write its figures and report.",
        None,
        _setup_example,
    ),
    "paper": (
        "Run the paper's examples (5.2, 5.3, 5.4, 5.5) into subdirectories and write "
        "OUTDIR/report.md, our numbers beside the paper's.",
        None,
        _setup_paper,
    ),
    "manufactured": (
        "Convergence of the VEM for linear elasticity alone against a manufactured smooth "
        "solution on several mesh families; prints the table of errors and orders.",
        None,
        _setup_manufactured,
    ),
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


# ---------------------------------------------------------------------------- argument types
def _inverse_h(text: str) -> int:
    """``256`` or ``1/256`` -> 256."""
    t = text.strip()
    return positive_int(t[2:] if t.startswith("1/") else t)


def _levels_list(text: str) -> list[int]:
    return [_inverse_h(x) for x in text.split(",") if x.strip()] or [positive_int("")]


def _families_list(text: str) -> list[str]:
    from ..paper.manufactured import available_families

    names = [x.strip() for x in text.split(",") if x.strip()]
    known = available_families()
    bad = [n for n in names if n not in known]
    if bad or not names:
        raise argparse.ArgumentTypeError(
            f"unknown mesh families {bad or [text]}; available: {', '.join(known)}"
        )
    return names


def _solver_options(base: SolverOptions, method: str | None) -> SolverOptions:
    from ..simulate import SolverOptions

    if method is None or method == base.method:
        return base
    # keep tol and backend; iteration limits of different methods are not comparable
    return SolverOptions(method=method, tol=base.tol, max_iter=None, backend=base.backend)


# ---------------------------------------------------------------------------- commands
def cmd_run(args: argparse.Namespace) -> int:
    """``vemwear run CONFIG -o OUTDIR [--resume]``: validate, solve, write, summarize.

    The order keeps every refusal cheap: a locked OUTDIR before the file is read, the
    rough plan before the mesh is built, the plan of the real mesh and the output
    directory (taking its lock) before the stiffness is assembled."""
    from ..config import load_config
    from ..runner import abandon_run, execute_run, prepare_run, result_rows, smallness_report
    from ..runner.outdir import refuse_locked, stale_temporaries
    from ..runner.plan import admit_sizes, check_estimate, estimate_config

    t0 = time.perf_counter()
    refuse_locked(args.outdir)
    # on --resume, the disk that result.h5 takes already is not asked for again
    have = _resumed_bytes(args.outdir) if args.resume else 0
    admit = admit_sizes(args.outdir, force_size=args.force_size, have=have)
    cfg = load_config(args.config, admit=admit)
    solver = _solver_options(cfg.solver, args.solver)
    if cfg.cycles is not None and args.resume:
        raise UsageError("--resume: a run with [time] cycle_jump is not checkpointed; run it again")
    stale = [] if args.force else stale_temporaries(args.outdir)
    if stale:
        say(
            f"{PROG}: warning: {len(stale)} temporary file(s) of killed runs in or next to "
            f"{args.outdir} (e.g. {stale[0].name}); remove them with: vemwear clean {args.outdir}"
        )
    est = estimate_config(cfg)
    if not args.force_size:
        check_estimate(est, args.outdir, str(args.config), have=have)
    plan = prepare_run(  # the output directory, its lock and the checkpoint, before solving
        cfg,
        args.config,
        args.outdir,
        solver,
        force=args.force,
        resume=args.resume,
        solver_flag=args.solver,
    )
    try:  # assembles the stiffness: may fail before any level, like the run
        _, warning = smallness_report(cfg.problem)
        for w in [warning, *_overshoot(cfg)]:
            if w:
                say(f"{PROG}: warning: {w}")
        print(f"{PROG}: {cfg.title}: " + ", ".join(f"{k} {v}" for k, v in est.rows()), flush=True)
    except BaseException:
        abandon_run(plan)
        raise
    if cfg.cycles is not None:
        from ..runner.cycles import execute_cycles
        from ..runner.describe import part_wear_rows

        _last, cres = execute_cycles(plan, progress=not args.no_progress)
        print(
            f"{PROG}: {cfg.title}: done\n"
            + rows_text(
                [
                    (
                        "cycles",
                        f"{cfg.cycles.cycles}, {len(cres.computed)} computed (jump "
                        f"{cfg.cycles.jump}, max increment {cfg.cycles.max_increment:g} g)",
                    ),
                    ("max wear", f"{float(cres.wear[-1].max(initial=0.0)):.6g}"),
                    *part_wear_rows(cfg.problem, cres.wear[-1]),
                    ("time", f"{time.perf_counter() - t0:.2f} s"),
                    ("output", str(plan.out)),
                ]
            )
        )
        return EXIT_OK
    result = execute_run(plan, progress=not args.no_progress)
    if isinstance(result, str):  # the arrays do not fit in memory: result.h5 only
        print(f"{PROG}: {cfg.title}: done; {result}")
        return EXIT_OK
    rows = [
        *result_rows(result),
        ("time", f"{time.perf_counter() - t0:.2f} s"),
        ("output", str(plan.out)),
    ]
    text = f"{PROG}: {cfg.title}: done\n" + rows_text(rows)
    if plan.state is not None:
        text += f"\n  resumed from level {plan.state.completed}"
    print(text)
    return EXIT_OK


def _resumed_bytes(outdir: str | Path) -> int:
    """The disk that the ``result.h5`` a resumed run goes on writing occupies already (its
    allocated blocks; 0 if there is none)."""
    from ..post.stream import STREAM_NAME

    try:
        st = (Path(outdir).expanduser() / STREAM_NAME).stat()
    except OSError:
        return 0
    return min(st.st_size, 512 * st.st_blocks)


def cmd_check(args: argparse.Namespace) -> int:
    """``vemwear check CONFIG``: validate and describe the problem, no solve."""
    from ..config import load_config
    from ..runner import check_rows, smallness_report
    from ..runner.plan import admit_sizes, check_estimate, estimate_config

    cfg = load_config(args.config, admit=admit_sizes(force_size=args.force_size))
    est = estimate_config(cfg)
    if not args.force_size:  # the memory of the real mesh, as ``vemwear run`` checks it
        check_estimate(est, None, str(args.config))
    rows = check_rows(cfg)
    row, warning = smallness_report(cfg.problem)
    rows.append(("smallness (Thm 3.4)", row))
    rows += est.rows()
    print(f"{PROG}: {args.config}: {cfg.title}: valid\n" + rows_text(rows))
    for w in [warning, *_overshoot(cfg)]:
        if w:
            say(f"{PROG}: warning: {w}")
    return EXIT_OK


def _overshoot(cfg: Any) -> list[str]:
    """The warning of the explicit wear rule's overshoot, if any."""
    from ..simulate.explicit import overshoot_warning

    w = overshoot_warning(cfg.problem)
    return [w] if w else []


def cmd_schema(args: argparse.Namespace) -> int:
    """``vemwear schema``: the JSON Schema of configuration files."""
    import json

    from ..config import config_json_schema

    print(json.dumps(config_json_schema(), indent=args.indent))
    return EXIT_OK


def cmd_example(args: argparse.Namespace) -> int:
    """``vemwear example NAME -o OUTDIR``: run one of the paper's examples."""
    if args.list:
        print(_example_listing())
        return EXIT_OK
    if args.name is None or args.outdir is None:
        raise UsageError("example: give NAME and -o OUTDIR (or --list)")
    if args.name == "orders":  # not a paper example: vemwear.paper.orders
        from ..paper.orders import cmd_example as orders_example

        return orders_example(args)
    from ..paper import load_example
    from ..runner import atomic_output_dir, check_output_dir
    from ..simulate import SolverOptions

    mod = load_example(args.name)
    extra = _example_extra(args)
    if args.quick:
        if args.name != "3d":
            raise UsageError("--quick: only for example 3d (vemwear paper --quick for the others)")
        extra["quick"] = True
    if args.order != 1:
        if args.name == "5.5":
            raise UsageError("--order 2: for examples 5.2, 5.3 and 5.4 (not 5.5 yet)")
        extra["order"] = args.order
    out = check_output_dir(args.outdir, args.force)
    if args.name == "5.5":
        extra["cache"] = (
            Path(args.cache) if args.cache is not None else out.parent / ".vemwear-cache"
        )
    solver = SolverOptions(method=args.solver or "newton")
    t0 = time.perf_counter()
    with atomic_output_dir(out, args.force) as tmp:
        ex = mod.run(
            tmp,
            solver=solver,
            progress=not args.no_progress,
            log=None if args.no_progress else say,
            **extra,
        )
    rows = [
        (
            name,
            f"max wear at T {float(r.wear[-1].max()):.6g}, iterations max "
            f"{int(r.iterations.max())}, max KKT residual {float(r.residuals.max()):.2e}",
        )
        for name, r in ex.results.items()
    ]
    rows += [
        ("time", f"{time.perf_counter() - t0:.2f} s"),
        ("output", str(out)),
        ("report", str(out / ex.report.name) if ex.report is not None else "-"),
    ]
    print(f"{PROG}: {mod.TITLE}: done\n" + rows_text(rows))
    summary = ex.details.get("summary") if isinstance(ex.details, dict) else None
    if summary:
        print("\n".join(summary))
    return EXIT_OK


def _example_extra(args: argparse.Namespace) -> dict[str, Any]:
    """The Example 5.5 options of ``vemwear example`` (an input error for other examples)."""
    given = {
        k: v
        for k, v in (
            ("--reference-h", args.reference_h),
            ("--levels", args.levels),
            ("--cache", args.cache),
        )
        if v is not None
    }
    if args.name != "5.5":
        if given:
            raise UsageError(f"{', '.join(given)}: only for example 5.5")
        return {}
    from ..paper.ex55 import LEVELS, REFERENCE, check_sizes

    ref = args.reference_h or REFERENCE
    try:  # without --levels: the default levels coarser than the reference
        levels, ref = check_sizes(args.levels or [n for n in LEVELS if n < ref] or LEVELS, ref)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    return {"levels": levels, "reference": ref}


def cmd_paper(args: argparse.Namespace) -> int:
    """``vemwear paper -o OUTDIR [--quick]``: every example and ``report.md``."""
    from ..paper.report import run_paper
    from ..runner import atomic_output_dir, check_output_dir
    from ..simulate import SolverOptions

    out = check_output_dir(args.outdir, args.force)
    cache = Path(args.cache) if args.cache is not None else out.parent / ".vemwear-cache"
    solver = SolverOptions(method=args.solver or "newton")
    with atomic_output_dir(out, args.force) as tmp:
        pr = run_paper(
            tmp,
            quick=args.quick,
            solver=solver,
            cache=cache,
            progress=not args.no_progress,
            log=None if args.no_progress else say,
        )
    rows = [(f"Example {n}", f"{r.elapsed:.1f} s") for n, r in pr.runs.items()]
    rows += [("skipped", ", ".join(pr.skipped))] if pr.skipped else []
    rows += [
        ("time", f"{pr.elapsed:.1f} s"),
        ("output", str(out)),
        ("report", str(out / pr.report.name)),
    ]
    print(f"{PROG}: paper: done\n" + rows_text(rows))
    return EXIT_OK


def cmd_manufactured(args: argparse.Namespace) -> int:
    """``vemwear manufactured``: convergence table against a manufactured solution."""
    from ..paper.manufactured import (
        DEFAULT_FAMILIES,
        available_families,
        convergence_study,
        table_csv,
        table_text,
    )

    fams = args.families or [f for f in DEFAULT_FAMILIES if f in available_families()]
    t0 = time.perf_counter()
    rows = convergence_study(fams, levels=args.levels, n0=args.n0, order=args.order)
    print(table_text(rows, markdown=args.markdown), end="")
    if args.csv:
        from ..util.atomic import write_atomic

        write_atomic(args.csv, table_csv(rows))
    sys.stdout.flush()
    say(
        f"{PROG}: manufactured: {len(fams)} families x {args.levels} levels in "
        f"{time.perf_counter() - t0:.1f} s (k = {args.order}); H1 = ||grad(Pi u_h) - grad u||, "
        "L2 = ||Pi u_h - u||, nodal = cell-weighted nodal L2 error"
    )
    return EXIT_OK


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
            ("vemwear.mesh.polymesh", "MeshError"),
            ("vemwear.simulate.discrete", "DataError"),
        )
    ):
        return EXIT_INPUT, str(exc)
    if _is(exc, "vemwear.simulate.levels", "WearOverflowError"):
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
        if debug:
            traceback.print_exception(exc)
        say(f"{PROG}: interrupted{getattr(exc, 'vemwear_note', '')}")
        return EXIT_INTERRUPTED
    except Exception as exc:  # every error ends as one line with its exit code
        code, msg = _exit_code(exc)
        if debug:
            traceback.print_exception(exc)
        elif code == EXIT_INTERNAL:
            msg += " (rerun with --debug for the traceback)"
        say(f"{PROG}: error: {msg}{getattr(exc, 'vemwear_note', '')}")
        return code


if __name__ == "__main__":  # pragma: no cover
    # ``python -m vemwear.cli.main``: run the imported module, not this copy named __main__
    from vemwear.cli.main import main as _main

    sys.exit(_main())
