"""The ``vemwear`` command: ``run``, ``check``, ``schema``, ``example``, ``paper``, ...

Exit codes (also in ``vemwear --help`` and ``docs/config.md``): 0 success,
1 unexpected internal error, 2 invalid input (configuration, mesh, data, output
directory, command line), 3 a solver did not converge, 130 interrupted.
"""

from __future__ import annotations

import argparse
import math
import os
import signal
import sys
import time
import traceback
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .. import __version__
from ..config import ConfigError
from ..solvers import SOLVERS
from .output import OutputDirError, atomic_output_dir, check_output_dir

if TYPE_CHECKING:
    from ..simulate import Problem, Result, SolverOptions

__all__ = [
    "EXIT_CONVERGENCE",
    "EXIT_INPUT",
    "EXIT_INTERNAL",
    "EXIT_INTERRUPTED",
    "EXIT_OK",
    "build_parser",
    "main",
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
  3    a solver did not converge (no output directory is left behind)
  130  interrupted (Ctrl-C or SIGTERM; no output directory is left behind)

If `run` stops after finishing some time levels (codes 1, 3, 130), they are saved
in OUTDIR.partial/ (see its PARTIAL.txt); `vemwear run CONFIG -o OUTDIR --resume`
continues from there and gives the same result as an uninterrupted run.

The configuration file format is documented in docs/config.md.
"""
SOLVER_METHODS = tuple(SOLVERS)


class _Interrupted(KeyboardInterrupt):
    """SIGTERM, handled like Ctrl-C."""


# ---------------------------------------------------------------------------- parser
def _formatter(prog: str) -> argparse.HelpFormatter:
    return argparse.RawDescriptionHelpFormatter(prog, max_help_position=30)


def _subcommand(
    sub: argparse._SubParsersAction,  # type: ignore[type-arg]
    name: str,
    summary: str,
    description: str | None = None,
) -> argparse.ArgumentParser:
    """A subcommand parser with the common help layout (``summary`` is its ``--help`` line)."""
    return sub.add_parser(
        name,
        help=summary,
        description=summary if description is None else description,
        epilog=EPILOG,
        formatter_class=_formatter,
    )


def _debug_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--debug", action="store_true", help="print the full traceback on errors")


def _common(p: argparse.ArgumentParser, *, solve: bool) -> None:
    if solve:
        p.add_argument(
            "-o",
            "--outdir",
            required=True,
            metavar="OUTDIR",
            help="output directory (written atomically: it appears only when the run is complete)",
        )
        p.add_argument(
            "--force",
            action="store_true",
            help="replace an existing non-empty OUTDIR (only after the new run has completed)",
        )
        p.add_argument(
            "--solver",
            choices=SOLVER_METHODS,
            metavar="METHOD",
            help="step solver, overriding the configuration: " + " | ".join(SOLVER_METHODS),
        )
        p.add_argument(
            "--no-progress",
            action="store_true",
            help="do not show the progress bar of the time loop",
        )
    _debug_option(p)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``vemwear`` command."""
    from ..paper import available_examples

    parser = argparse.ArgumentParser(
        prog=PROG,
        description="Quasistatic frictional contact with wear on polygonal meshes by the "
        "virtual element method.",
        epilog=EPILOG,
        formatter_class=_formatter,
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", title="commands")
    sub.required = True

    d = "Validate a configuration file, solve the problem and write the results."
    p = _subcommand(sub, "run", d)
    p.add_argument("config", metavar="CONFIG.toml", help="configuration file (docs/config.md)")
    _common(p, solve=True)
    p.add_argument(
        "--resume",
        action="store_true",
        help="continue a stopped run from the finished levels in OUTDIR.partial "
        "(refused if the inputs changed); OUTDIR.partial is removed on success",
    )
    p.set_defaults(func=cmd_run)

    d = "Validate a configuration file and summarize the problem, without solving."
    p = _subcommand(sub, "check", d)
    p.add_argument("config", metavar="CONFIG.toml", help="configuration file (docs/config.md)")
    _common(p, solve=False)
    p.set_defaults(func=cmd_check)

    d = "Print the JSON Schema of configuration files (for editors' completion and checks)."
    p = _subcommand(sub, "schema", d)
    p.add_argument("--indent", type=int, default=2, metavar="N", help="indentation (default 2)")
    p.set_defaults(func=cmd_schema)

    d = "Run one of the paper's numerical examples and write its figures and report."
    examples = available_examples()
    listing = "available examples:\n" + "\n".join(
        f"  {name:<5}{text}" for name, text in examples.items()
    )
    p = _subcommand(sub, "example", d, d + "\n\n" + listing)
    p.add_argument(
        "name",
        metavar="NAME",
        choices=list(examples),
        help="example number: " + ", ".join(examples),
    )
    _common(p, solve=True)
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

    d = (
        "Run the paper's examples (5.2, 5.3, 5.4, 5.5) into subdirectories and write "
        "OUTDIR/report.md, our numbers beside the paper's."
    )
    p = _subcommand(sub, "paper", d)
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

    d = (
        "Convergence of the VEM for linear elasticity alone against a manufactured smooth "
        "solution on several mesh families; prints the table of errors and orders."
    )
    p = _subcommand(sub, "manufactured", d)
    p.add_argument(
        "--families",
        type=_families_list,
        metavar="LIST",
        help="comma-separated mesh families (default squares,triangles,voronoi,"
        "hanging; also distorted, hexagons, nonconvex)",
    )
    p.add_argument(
        "--levels",
        type=_positive_int,
        default=4,
        metavar="N",
        help="number of meshes per family, n = N0, 2 N0, ... (default 4)",
    )
    p.add_argument(
        "--n0",
        type=_positive_int,
        default=4,
        metavar="N0",
        help="cells per side of the coarsest mesh (default 4)",
    )
    p.add_argument("--markdown", action="store_true", help="print a Markdown table")
    p.add_argument("--csv", metavar="FILE", help="also write the table as CSV to FILE")
    _common(p, solve=False)
    p.set_defaults(func=cmd_manufactured)

    from . import mesh_cmd  # vemwear mesh generate | inspect | plot | convert

    mesh_cmd.add_parser(sub)
    return parser


# ---------------------------------------------------------------------------- helpers
def _positive_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return v


def _inverse_h(text: str) -> int:
    """``256`` or ``1/256`` -> 256."""
    t = text.strip()
    return _positive_int(t[2:] if t.startswith("1/") else t)


def _levels_list(text: str) -> list[int]:
    return [_inverse_h(x) for x in text.split(",") if x.strip()] or [_positive_int("")]


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


def _fmt_k(k_min: float, k_max: float) -> str:
    if math.isclose(k_min, k_max, rel_tol=1e-9):
        inv = 1.0 / k_min
        frac = f" = 1/{round(inv)}" if math.isclose(inv, round(inv), rel_tol=1e-9) else ""
        return f"k = {k_min:.6g}{frac}"
    return f"k in [{k_min:.6g}, {k_max:.6g}]"


def _rows(rows: Sequence[tuple[str, str]]) -> str:
    w = max(len(a) for a, _ in rows)
    return "\n".join(f"  {a:<{w}}  {b}" for a, b in rows)


def _run_summary(result: Result, title: str, outdir: Path, elapsed: float) -> str:
    import numpy as np

    it = np.asarray(result.iterations)
    res = np.asarray(result.residuals)
    worst = int(np.argmax(res.max(axis=0))) if res.size else 0
    wT = np.asarray(result.wear[-1])
    a = int(np.argmax(wT)) if wT.size else 0
    at = np.asarray(result.contact_points[a]).tolist() if wT.size else []
    k = np.diff(result.t)
    rows = [
        (
            "levels",
            f"{len(result.t)} (T = {result.t[-1]:g}, {_fmt_k(float(k.min()), float(k.max()))})"
            if k.size
            else "1",
        ),
        (
            "solver",
            f"{result.solver.get('method', '?')}, iterations max {int(it.max())} per "
            f"step, total {int(it.sum())}",
        ),
        (
            "max KKT residual",
            f"{float(res.max()):.2e} ({result.RESIDUAL_NAMES[worst]}; "
            f"tol {result.solver.get('tol', float('nan')):g})",
        ),
        (
            "max wear at T",
            f"{float(wT.max()):.6g} at x = ({', '.join(f'{c:.4g}' for c in at)})"
            if wT.size
            else "-",
        ),
        ("time", f"{elapsed:.2f} s"),
        ("output", str(outdir)),
    ]
    return f"{PROG}: {title}: done\n" + _rows(rows)


@contextmanager
def _sigterm_as_interrupt() -> Iterator[None]:
    """Turn SIGTERM into an interrupt (so temporary output is cleaned up), main thread only."""

    def handler(signum: int, frame: Any) -> None:
        raise _Interrupted()

    try:
        old = signal.signal(signal.SIGTERM, handler)
    except (ValueError, OSError, AttributeError):  # not the main thread / no SIGTERM
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


def _say(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def smallness_report(problem: Problem, max_dofs: int = 200_000) -> tuple[str, str | None]:
    """The smallness condition of Theorem 3.4, estimated for ``vemwear check`` and ``run``.

    Parameters
    ----------
    problem : Problem
        A validated problem (its discretization is assembled here).
    max_dofs : int
        Skip the estimate (an eigenvalue problem) above this number of dofs.

    Returns
    -------
    row : str
        A one-line summary of the estimate ``L_p ||mu|| c_0^2 / C_1``, for the
        ``check`` table.
    warning : str or None
        A warning when the condition is doubtful (estimate >= 1), else None.
    """
    import warnings

    if 2 * problem.mesh.n_points > max_dofs:
        return f"not estimated (more than {max_dofs} dofs)", None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        est = problem.discrete.smallness_estimate()
    r = float(est.get("ratio", float("nan")))
    if not math.isfinite(r):
        return "not estimated", None
    if r < 1:
        return f"L_p ||mu|| c0^2/C1 ~= {r:.3g} < 1: holds", None
    row = (
        f"L_p ||mu|| c0^2/C1 ~= {r:.3g} >= 1: MAY FAIL (step problems may not be uniquely solvable)"
    )
    warning = (
        f"the smallness condition of Theorem 3.4 is doubtful: L_p ||mu|| c0^2/C1 "
        f"~= {r:.3g} >= 1 (L_p = {est.get('L_p', float('nan')):g}, max mu = "
        f"{est.get('mu_max', float('nan')):g}, c0^2/C1 ~= "
        f"{est.get('c0_sq_over_C1', float('nan')):.3g}); the step problems may not be "
        "uniquely solvable and the solver may fail; reduce mu or the stiffness of p"
    )
    return row, warning


# ---------------------------------------------------------------------------- commands
def cmd_run(args: argparse.Namespace) -> int:
    """``vemwear run CONFIG -o OUTDIR [--resume]``: validate, solve, write, summarize.

    A run that stops after finishing some levels keeps them in ``OUTDIR.partial``;
    ``--resume`` continues from there (:mod:`vemwear.cli.resume`).
    """
    from ..config import load_config
    from .resume import execute_run, prepare_run

    t0 = time.perf_counter()
    cfg = load_config(args.config)
    out = check_output_dir(args.outdir, args.force, protect=[args.config])  # before solving
    solver = _solver_options(cfg.solver, args.solver)
    plan = prepare_run(
        cfg,
        args.config,
        out,
        solver,
        force=args.force,
        resume=args.resume,
        solver_flag=args.solver,
    )
    _, warning = smallness_report(cfg.problem)
    if warning:
        _say(f"{PROG}: warning: {warning}")
    result = execute_run(plan, progress=not args.no_progress)
    text = _run_summary(result, cfg.title, out, time.perf_counter() - t0)
    if plan.previous is not None:
        text += f"\n  resumed from level {plan.previous.completed} ({plan.part} removed)"
    print(text)
    return EXIT_OK


def cmd_check(args: argparse.Namespace) -> int:
    """``vemwear check CONFIG``: validate and describe the problem, no solve."""
    import numpy as np

    from ..config import load_config
    from ..mesh import PARTS, part_code
    from ..solvers import resolve_backend

    cfg = load_config(args.config)
    pr = cfg.problem
    m = pr.mesh
    cb = pr.contact
    counts = ", ".join(f"{n}-gons: {len(i)}" for n, (i, _) in sorted(m.groups.items()))
    parts = ", ".join(f"{p} {int(np.sum(m.boundary_tags == part_code(p)))}" for p in PARTS)
    k = pr.time.k
    src = cfg.mesh_source
    mesh_from = (
        f"file {src['file']}"
        if "file" in src
        else f"generator {src.get('generator')} ({src.get('function')})"
    )
    nodal = pr.nodal

    def rng(name: str) -> str:
        v = nodal[name]
        lo, hi = float(v.min()), float(v.max())
        return f"{lo:g}" if lo == hi else f"{lo:g} .. {hi:g}"

    ce = m.part_edges("contact")
    length = float(np.linalg.norm(m.points[ce[:, 1]] - m.points[ce[:, 0]], axis=1).sum())
    law = pr.p.describe()
    if law.get("type") == "linear":
        p_text = f"p(r) = {law['c']:g} r_+"
    elif law.get("type") == "table":
        p_text = f"p: table of {len(law['r'])} points, r up to {law['r'][-1]:g}"
    else:
        p_text = f"p: {law}"
    s = cfg.solver
    rows = [
        (
            "mesh",
            f"{mesh_from}: {m.n_points} vertices, {m.n_cells} cells ({counts}), h = {m.h:.4g}",
        ),
        ("boundary edges", parts),
        ("contact nodes", f"{cb.m} on {len(ce)} contact edges (Gamma_C length {length:.6g})"),
        (
            "time levels",
            f"{len(pr.time.t)} on [0, {pr.time.T:g}], "
            f"{_fmt_k(float(k.min()), float(k.max())) if k.size else 'no steps'}",
        ),
        (
            "material",
            f"lam = {pr.material.lam:g}, eta = {pr.material.eta:g}; "
            f"stabilization {pr.stabilization}",
        ),
        (
            "contact",
            f"{p_text}; g {rng('g')}; mu {rng('mu')}; "
            f"kappa {rng('kappa')}; v_star {pr.v_star.describe()}",
        ),  # type: ignore[union-attr]
        (
            "solver",
            f"{s.method}, tol {s.tol:g}, max_iter "
            f"{s.max_iter if s.max_iter is not None else 'default'}, backend "
            f"{s.backend} ({resolve_backend(s.backend)})",
        ),
        (
            "output",
            f"profiles at t = {', '.join(f'{t:g}' for t in cfg.output.times)}; "
            f"figures {'yes' if cfg.output.figures else 'no'}; "
            f"vtk {'yes' if cfg.output.vtk else 'no'}",
        ),
    ]
    row, warning = smallness_report(pr)
    rows.append(("smallness (Thm 3.4)", row))
    print(f"{PROG}: {args.config}: {cfg.title}: valid\n" + _rows(rows))
    if warning:
        _say(f"{PROG}: warning: {warning}")
    return EXIT_OK


def cmd_schema(args: argparse.Namespace) -> int:
    """``vemwear schema``: the JSON Schema of configuration files."""
    import json

    from ..config import config_json_schema

    print(json.dumps(config_json_schema(), indent=args.indent))
    return EXIT_OK


def cmd_example(args: argparse.Namespace) -> int:
    """``vemwear example NAME -o OUTDIR``: run one of the paper's examples."""
    from ..paper import load_example
    from ..simulate import SolverOptions

    mod = load_example(args.name)
    extra = _example_extra(args)
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
            log=None if args.no_progress else _say,
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
    print(f"{PROG}: {mod.TITLE}: done\n" + _rows(rows))
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
            raise ConfigError(f"{', '.join(given)}: only for example 5.5")
        return {}
    from ..paper.ex55 import LEVELS, REFERENCE, check_sizes

    ref = args.reference_h or REFERENCE
    try:  # without --levels: the default levels coarser than the reference
        levels, ref = check_sizes(args.levels or [n for n in LEVELS if n < ref] or LEVELS, ref)
    except ValueError as exc:
        raise ConfigError(str(exc)) from None
    return {"levels": levels, "reference": ref}


def cmd_paper(args: argparse.Namespace) -> int:
    """``vemwear paper -o OUTDIR [--quick]``: every example and ``report.md``."""
    from ..paper.report import run_paper
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
            log=None if args.no_progress else _say,
        )
    rows = [(f"Example {n}", f"{r.elapsed:.1f} s") for n, r in pr.runs.items()]
    rows += [("skipped", ", ".join(pr.skipped))] if pr.skipped else []
    rows += [
        ("time", f"{pr.elapsed:.1f} s"),
        ("output", str(out)),
        ("report", str(out / pr.report.name)),
    ]
    print(f"{PROG}: paper: done\n" + _rows(rows))
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
    rows = convergence_study(fams, levels=args.levels, n0=args.n0)
    print(table_text(rows, markdown=args.markdown), end="")
    if args.csv:
        Path(args.csv).write_text(table_csv(rows), encoding="utf-8")
    sys.stdout.flush()
    print(
        f"{PROG}: manufactured: {len(fams)} families x {args.levels} levels in "
        f"{time.perf_counter() - t0:.1f} s; H1 = ||grad(Pi u_h) - grad u||, "
        "L2 = ||Pi u_h - u||, nodal = cell-weighted nodal L2 error",
        file=sys.stderr,
    )
    return EXIT_OK


# ---------------------------------------------------------------------------- entry point
def _fail(msg: str, exc: BaseException, debug: bool) -> None:
    if debug:
        traceback.print_exception(exc)
    note = getattr(exc, "vemwear_note", "")  # where the finished levels were saved
    print(f"{PROG}: error: {msg}{note}", file=sys.stderr, flush=True)


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
    from ..mesh import MeshError
    from ..solvers import ConvergenceError

    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, usage errors
        code = exc.code
        return code if isinstance(code, int) else (EXIT_OK if code is None else EXIT_INPUT)
    debug = bool(getattr(args, "debug", False))
    func: Callable[[argparse.Namespace], int] = args.func
    try:
        with _sigterm_as_interrupt():
            return func(args)
    except BrokenPipeError:  # stdout closed early (``vemwear check ... | head``): not an error
        try:  # no second error when Python flushes stdout at exit
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        except (OSError, ValueError):
            pass
        return EXIT_OK
    except (ConfigError, OutputDirError, MeshError) as exc:
        _fail(str(exc), exc, debug)
        return EXIT_INPUT
    except ConvergenceError as exc:
        _fail(f"the solver did not converge: {exc}", exc, debug)
        return EXIT_CONVERGENCE
    except KeyboardInterrupt as exc:
        if debug:
            traceback.print_exception(exc)
        print(f"{PROG}: interrupted{getattr(exc, 'vemwear_note', '')}", file=sys.stderr, flush=True)
        return EXIT_INTERRUPTED
    except Exception as exc:  # the last line of defence, reported as such
        _fail(
            f"internal error: {type(exc).__name__}: {exc}"
            + ("" if debug else " (rerun with --debug for the traceback)"),
            exc,
            debug,
        )
        return EXIT_INTERNAL


if __name__ == "__main__":  # pragma: no cover
    # ``python -m vemwear.cli.main``: run the imported module, not this copy named
    # __main__, so that its classes (e.g. _Interrupted, checked by resume._reason) are
    # the ones the other modules import
    from vemwear.cli.main import main as _main

    sys.exit(_main())
