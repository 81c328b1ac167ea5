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
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .common import EXIT_OK, PROG, UsageError, add_common_options, rows_text, say

if TYPE_CHECKING:
    from ..simulate import SolverOptions

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


def setup_check(p: argparse.ArgumentParser) -> None:
    p.add_argument("config", metavar="CONFIG.toml", help="configuration file (docs/config.md)")
    _force_size(p)
    add_common_options(p, solve=False)
    p.set_defaults(func=cmd_check)


def setup_schema(p: argparse.ArgumentParser) -> None:
    p.add_argument("--indent", type=int, default=2, metavar="N", help="indentation (default 2)")
    p.set_defaults(func=cmd_schema)


# ---------------------------------------------------------------------------- commands
def _solver_options(base: SolverOptions, method: str | None) -> SolverOptions:
    from ..simulate import SolverOptions

    if method is None or method == base.method:
        return base
    # keep tol and backend; iteration limits of different methods are not comparable
    return SolverOptions(method=method, tol=base.tol, max_iter=None, backend=base.backend)


def cmd_run(args: argparse.Namespace) -> int:
    """``vemwear run CONFIG -o OUTDIR [--resume]``: validate, solve, write, summarize.

    The order keeps every refusal cheap: a locked OUTDIR before the file is read, the
    rough plan before the mesh is built, the plan of the real mesh and the output
    directory (taking its lock) before the stiffness is assembled."""
    from ..config import load_config
    from ..runner import abandon_run, execute_run, prepare_run, result_rows, smallness_report
    from ..runner.outdir import refuse_locked, stale_temporaries
    from ..runner.plan import admit_sizes, check_estimate, estimate_config
    from ..runner.run import RunComplete

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
    try:  # the output directory, its lock and the checkpoint, before solving
        plan = prepare_run(
            cfg,
            args.config,
            args.outdir,
            solver,
            force=args.force,
            resume=args.resume,
            solver_flag=args.solver,
        )
    except RunComplete as done:
        print(f"{PROG}: {done}")
        return EXIT_OK
    if plan.note:
        say(f"{PROG}: {plan.note}")
    try:  # assembles and factorizes (the run's set-up): may fail before any level
        _, warning = smallness_report(cfg.problem, plan.solver)
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
    row, warning = smallness_report(cfg.problem, cfg.solver)
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
