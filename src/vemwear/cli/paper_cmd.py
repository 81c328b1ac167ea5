"""``vemwear example NAME``, ``vemwear paper`` and ``vemwear manufactured``: the paper.

``example`` runs one of the paper's numerical examples (or ``orders``, k = 1 against
k = 2) and writes its figures and report; ``paper`` runs the examples 5.2 to 5.5 into
subdirectories of OUTDIR and writes ``OUTDIR/report.md``, our numbers beside the
paper's; ``manufactured`` prints the convergence table of the VEM for linear
elasticity against a manufactured smooth solution on several mesh families. The work
is in :mod:`vemwear.paper`, imported only when a command runs.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

from .common import (
    EXIT_OK,
    PROG,
    UsageError,
    add_common_options,
    positive_int,
    rows_text,
    say,
)

__all__ = [
    "EXAMPLE_SUMMARY",
    "MANUFACTURED_SUMMARY",
    "PAPER_SUMMARY",
    "setup_example",
    "setup_manufactured",
    "setup_paper",
]

EXAMPLE_SUMMARY = "Run one of the paper's numerical examples and write its figures and report."
PAPER_SUMMARY = (
    "Run the paper's examples (5.2, 5.3, 5.4, 5.5) into subdirectories and write "
    "OUTDIR/report.md, our numbers beside the paper's."
)
MANUFACTURED_SUMMARY = (
    "Convergence of the VEM for linear elasticity alone against a manufactured smooth "
    "solution on several mesh families; prints the table of errors and orders."
)


# ---------------------------------------------------------------------------- parser
def _example_listing() -> str:
    from ..paper import available_examples

    return "\n".join(f"  {name:<5}{text}" for name, text in available_examples().items())


def _order_option(p: argparse.ArgumentParser, help: str) -> None:
    """``--order``: the order k = 1 or 2 of the virtual element space."""
    p.add_argument("--order", type=int, choices=(1, 2), default=1, help=help)


def setup_example(p: argparse.ArgumentParser) -> None:
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
    _order_option(
        p,
        "order k of the virtual element space (default 1, the paper's; 2 for "
        "examples 5.2, 5.3, 5.4)",
    )
    add_common_options(p, solve=True, outdir_required=False)
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
        help="cache directory of the reference solution (default: the user's cache directory, "
        "shown by vemwear clean --cache)",
    )
    p.set_defaults(func=cmd_example)


def setup_paper(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--quick",
        action="store_true",
        help="Example 5.5 against the reference h = k = 1/64 instead of 1/256 "
        "(levels 1/4 ... 1/32)",
    )
    p.add_argument(
        "--cache",
        metavar="DIR",
        help="cache directory of the Example 5.5 reference (default: the user's cache "
        "directory, shown by vemwear clean --cache)",
    )
    add_common_options(p, solve=True)
    p.set_defaults(func=cmd_paper)


def setup_manufactured(p: argparse.ArgumentParser) -> None:
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
    _order_option(
        p, "order k of the virtual element space (default 1; 2: expected orders H1 2, L2 3)"
    )
    add_common_options(p, solve=False)
    p.set_defaults(func=cmd_manufactured)


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


# ---------------------------------------------------------------------------- commands
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
    from ..util.cache import user_cache_dir

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
        extra["cache"] = Path(args.cache) if args.cache is not None else user_cache_dir()
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
    from ..util.cache import user_cache_dir

    out = check_output_dir(args.outdir, args.force)
    cache = Path(args.cache) if args.cache is not None else user_cache_dir()
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
