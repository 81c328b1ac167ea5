"""``vemwear run CONFIG -o OUTDIR``, ``vemwear check CONFIG`` and ``vemwear schema``.

``run`` validates a configuration file (``docs/config.md``), solves the problem and
writes the results to OUTDIR (``--resume`` continues a stopped run from its last
checkpoint); ``check`` validates and summarizes the problem without solving;
``schema`` prints the JSON Schema of configuration files. The work is in
:mod:`vemwear.runner` and :mod:`vemwear.config`, imported only when a command runs.
"""

from __future__ import annotations

import argparse
import time
from typing import TYPE_CHECKING, Any

from .common import EXIT_OK, PROG, add_common_options, rows_text, say

if TYPE_CHECKING:
    pass

__all__ = [
    "CHECK_SUMMARY",
    "RUN_SUMMARY",
    "SCHEMA_SUMMARY",
    "setup_check",
    "setup_run",
    "setup_schema",
]

RUN_SUMMARY = "Validate a configuration file, solve the problem and write the results."
CHECK_SUMMARY = "Validate a configuration file and summarize the problem, without solving."
SCHEMA_SUMMARY = (
    "Print the JSON Schema of configuration files (for editors' completion and checks)."
)


# ---------------------------------------------------------------------------- parser
def setup_run(p: argparse.ArgumentParser) -> None:
    p.add_argument("config", metavar="CONFIG.toml", help="configuration file (docs/config.md)")
    add_common_options(p, solve=True)
    _force_size(p)
    p.add_argument(
        "--backend",
        choices=_backends(),
        metavar="NAME",
        help="sparse direct solver, overriding the configuration: "
        + " | ".join(_backends())
        + " (petsc: MUMPS over the ranks of `mpirun -n N vemwear run ...`, docs/mpi.md)",
    )
    p.add_argument(
        "--resume",
        action="store_true",
        help="continue a stopped or killed run from its last checkpoint in OUTDIR "
        "(refused if the physics, the discretization or the kept levels changed; the "
        "solver options may change); the result is the one of an uninterrupted run",
    )
    p.set_defaults(func=cmd_run)


def _backends() -> tuple[str, ...]:
    from ..solvers import BACKENDS

    return tuple(BACKENDS)


def _force_size(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--force-size",
        action="store_true",
        help="run even if the estimated memory or disk exceeds what is available",
    )


def setup_check(p: argparse.ArgumentParser) -> None:
    p.add_argument("config", metavar="CONFIG.toml", help="configuration file (docs/config.md)")
    _force_size(p)
    add_common_options(p, solve=False)
    p.set_defaults(func=cmd_check)


def setup_schema(p: argparse.ArgumentParser) -> None:
    p.add_argument("--indent", type=int, default=2, metavar="N", help="indentation (default 2)")
    p.set_defaults(func=cmd_schema)


# ---------------------------------------------------------------------------- commands
def cmd_run(args: argparse.Namespace) -> int:
    """``vemwear run CONFIG -o OUTDIR [--resume]``: :func:`vemwear.runner.run_config`
    (which owns the order of the checks), then its outcome printed."""
    from ..runner import result_rows, run_config

    t0 = time.perf_counter()
    outcome = run_config(
        args.config,
        args.outdir,
        resume=args.resume,
        force=args.force,
        progress=not args.no_progress,
        solver=args.solver,
        backend=args.backend,
        force_size=args.force_size,
        say=lambda line: print(f"{PROG}: {line}", flush=True),
        warn=lambda line: say(f"{PROG}: {line}"),
    )
    if outcome.rank != 0:  # an MPI rank that served rank 0's solves: rank 0 reports
        return EXIT_OK
    title, result, cres = outcome.title, outcome.result, outcome.cycles
    elapsed = ("time", f"{time.perf_counter() - t0:.2f} s")
    if outcome.segments is not None:
        text = f"{PROG}: {title}: done\n" + rows_text(_adaptive_rows(outcome, elapsed))
        if outcome.resumed_from is not None:
            text += f"\n  resumed from level {outcome.resumed_from}"
        print(text)
        return EXIT_OK
    if result is None and cres is None:  # complete already, or result.h5 alone
        if outcome.config is None or (
            outcome.resumed_from is None and "result.h5" not in (outcome.note)
        ):
            print(f"{PROG}: {outcome.note}")
        else:
            print(f"{PROG}: {title}: done; {outcome.note}")
        return EXIT_OK
    if result is None:  # a cycle-jump run
        assert cres is not None and outcome.config is not None
        print(f"{PROG}: {title}: done\n" + rows_text(_cycle_rows(outcome, elapsed)))
        return EXIT_OK
    rows = [*result_rows(result), elapsed, ("output", str(outcome.out))]
    text = f"{PROG}: {title}: done\n" + rows_text(rows)
    if outcome.resumed_from is not None:
        text += f"\n  resumed from level {outcome.resumed_from}"
    print(text)
    return EXIT_OK


def _adaptive_rows(outcome: Any, elapsed: tuple[str, str]) -> list[tuple[str, str]]:
    """The summary rows of an ``[adapt]`` run."""
    segs = outcome.segments
    last = segs[-1]
    cells = [s.problem.mesh.n_cells for s in segs]
    return [
        ("time levels", str(len(outcome.config.problem.time.t))),
        ("meshes", f"{len(segs)}, {min(cells)} to {max(cells)} cells"),
        ("final mesh", f"{cells[-1]} cells, {last.problem.space.n_dofs} dofs"),
        ("estimate", f"eta = {last.estimate.total:.4g} at the final level"),
        ("max wear", f"{float(last.result.wear[-1].max(initial=0.0)):.6g}"),
        elapsed,
        ("output", str(outcome.out)),
    ]


def _cycle_rows(outcome: Any, elapsed: tuple[str, str]) -> list[tuple[str, str]]:
    """The summary rows of a cycle-jump run."""
    from ..runner.describe import part_wear_rows

    cfg, cres = outcome.config, outcome.cycles
    return [
        (
            "cycles",
            f"{cfg.cycles.cycles}, {len(cres.computed)} computed (jump "
            f"{cfg.cycles.jump}, max increment {cfg.cycles.max_increment:g} g)",
        ),
        ("max wear", f"{float(cres.wear[-1].max(initial=0.0)):.6g}"),
        *part_wear_rows(cfg.problem, cres.wear[-1]),
        elapsed,
        ("output", str(outcome.out)),
    ]


def cmd_check(args: argparse.Namespace) -> int:
    """``vemwear check CONFIG``: validate and describe the problem, no solve."""
    from ..config import load_config
    from ..runner import check_rows, smallness_report
    from ..runner.entry import overshoot_lines
    from ..runner.plan import admit_sizes, check_estimate, estimate_config

    cfg = load_config(args.config, admit=admit_sizes(force_size=args.force_size))
    est = estimate_config(cfg)
    if not args.force_size:  # the memory of the real mesh, as ``vemwear run`` checks it
        check_estimate(est, None, str(args.config))
    rows = check_rows(cfg)
    row, warning = smallness_report(cfg.problem, cfg.solver)
    rows.append(("smallness (Thm 3.4)", row))
    rows += est.rows()
    print(f"{PROG}: {args.config}: {cfg.title}: valid\n" + rows_text(rows))
    for w in [warning, *overshoot_lines(cfg)]:
        if w:
            say(f"{PROG}: warning: {w}")
    return EXIT_OK


def cmd_schema(args: argparse.Namespace) -> int:
    """``vemwear schema``: the JSON Schema of configuration files."""
    import json

    from ..config import config_json_schema

    print(json.dumps(config_json_schema(), indent=args.indent))
    return EXIT_OK
