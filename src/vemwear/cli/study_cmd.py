"""``vemwear sweep STUDY -o OUTDIR`` and ``vemwear fit CONFIG --data CSV``: studies on Dask.

``sweep`` runs a parameter study (a base configuration, axes over its dotted keys, a
grid, zip, Latin hypercube or Sobol design; docs/studies.md) on Dask distributed, one
output directory per run, and writes ``OUTDIR/study.nc`` (an xarray Dataset), figures
and ``OUTDIR/report.md``. ``fit`` calibrates kappa (and mu, c, g) against measured wear
profiles by bounded least squares, the Jacobian's runs in parallel. Both use an
embedded ``LocalCluster`` (one worker per core) unless ``--scheduler ADDRESS`` names a
running Dask scheduler. The work is in :mod:`vemwear.studies`; Dask and xarray are
imported only when a command runs.
"""

from __future__ import annotations

import argparse
import json
import time

from .common import EXIT_CONVERGENCE, EXIT_OK, PROG, add_debug_option, positive_int, rows_text, say

__all__ = ["FIT_SUMMARY", "SWEEP_SUMMARY", "setup_fit", "setup_sweep"]

SWEEP_SUMMARY = (
    "Run a parameter study (a study file: base configuration, axes, design) on Dask and "
    "write OUTDIR/study.nc, figures and a report."
)
FIT_SUMMARY = (
    "Calibrate kappa (and mu, c, g) against measured wear profiles by least squares, "
    "the sensitivities' runs in parallel on Dask."
)


def _cluster(p: argparse.ArgumentParser, workers: bool) -> None:
    p.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="address of a running Dask scheduler (e.g. tcp://10.0.0.1:8786); default: an "
        "embedded LocalCluster, one single-threaded worker per core",
    )
    if workers:
        p.add_argument(
            "--workers",
            type=positive_int,
            metavar="N",
            help="workers of the embedded LocalCluster (default: the number of cores)",
        )


def setup_sweep(p: argparse.ArgumentParser) -> None:
    p.add_argument("study", metavar="STUDY.toml", help="study file (docs/studies.md)")
    p.add_argument(
        "-o",
        "--outdir",
        required=True,
        metavar="OUTDIR",
        help="output directory: new, empty, or one of an earlier sweep of which the "
        "finished runs are kept (a stopped study continues)",
    )
    _cluster(p, workers=True)
    p.add_argument(
        "--chunk",
        type=positive_int,
        metavar="N",
        help="runs per Dask task (default: four or more tasks per worker, at most 16 runs "
        "each); chunks save the scheduler's work when runs take milliseconds",
    )
    p.add_argument(
        "--max-runs",
        type=positive_int,
        default=100_000,
        metavar="N",
        help="refuse a design of more runs (counted before any is built; default 100000)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_debug_option(p)
    p.set_defaults(func=cmd_sweep)


def setup_fit(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "config", metavar="CONFIG.toml", help="configuration file; its values start the fit"
    )
    p.add_argument(
        "--data",
        required=True,
        metavar="CSV",
        help="measured wear: a CSV with the columns x or s, w and t (one or several times)",
    )
    p.add_argument(
        "-o",
        "--outdir",
        metavar="OUTDIR",
        help="write fit.json, fit.md, fit.png and the runs there (default: runs in a "
        "temporary directory, only the report printed)",
    )
    p.add_argument(
        "--params",
        nargs="+",
        default=["kappa"],
        choices=["kappa", "mu", "c", "g"],
        metavar="NAME",
        help="parameters to calibrate: kappa, mu, c (linear compliance), g (default: kappa)",
    )
    _cluster(p, workers=True)
    add_debug_option(p)
    p.set_defaults(func=cmd_fit)


def cmd_sweep(args: argparse.Namespace) -> int:
    """``vemwear sweep STUDY -o OUTDIR``."""
    from ..studies import load_study, sweep

    t0 = time.perf_counter()
    # counted, then every run validated, before the cluster starts
    st = load_study(args.study, max_runs=args.max_runs, say=say)
    say(f"{PROG}: {args.study}: {len(st.runs)} runs ({st.kind}), all valid")
    ds = sweep(
        st,
        args.outdir,
        scheduler=args.scheduler,
        workers=args.workers,
        progress=not args.no_progress,
        chunk=args.chunk,
        say=say,
    )
    a = ds.attrs
    rows = [
        (
            "runs",
            f"{a['runs']}: {a['runs_computed']} computed, {a['runs_skipped']} finished earlier, "
            f"{a['runs_failed']} failed",
        ),
        ("axes", ", ".join(json.loads(a["axes"]))),
        ("max wear", f"{float(ds['max_wear'].min()):.6g} .. {float(ds['max_wear'].max()):.6g}"),
        ("time", f"{time.perf_counter() - t0:.2f} s"),
        ("output", f"{args.outdir}/study.nc, report.md"),
    ]
    print(f"{PROG}: {a['title']}: done\n" + rows_text(rows))
    if a["runs_failed"]:
        say(
            f"{PROG}: error: {a['runs_failed']} of {a['runs']} runs failed (their errors are in "
            f"{args.outdir}/report.md); sweep again into the same OUTDIR to retry them"
        )
        return EXIT_CONVERGENCE
    return EXIT_OK


def cmd_fit(args: argparse.Namespace) -> int:
    """``vemwear fit CONFIG --data CSV``."""
    from ..studies import fit

    res = fit(
        args.config,
        args.data,
        params=args.params,
        out=args.outdir,
        scheduler=args.scheduler,
        workers=args.workers,
        say=say,
    )
    rows = [*res.rows(), ("time", f"{res.seconds:.2f} s")]
    if args.outdir:
        rows.append(("output", f"{args.outdir}/fit.json, fit.md, fit.png"))
    print(f"{PROG}: fit of {', '.join(res.params)}: done\n" + rows_text(rows))
    return EXIT_OK
