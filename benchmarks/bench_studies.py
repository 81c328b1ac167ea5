"""Studies on Dask against a serial loop: overhead per run, speed-up, start-up cost.

N runs of Example 5.2's size (data set 1, h = 1/16: 32 x 16 squares, 64 steps, kappa
from 1 to 10; no figures or ParaView output), each through vemwear.runner into its own
directory:

- serial: one process, one run after the other (load_config, prepare_run, execute_run);
- study: ``vemwear.studies.sweep`` on the LocalCluster a sweep makes (W single-threaded
  workers; the cluster's start is timed apart from the sweep).

Reported: wall times, the study's overhead per run (W x study wall / N minus the serial
time per run), the speed-up (with and without the cluster's start), and the start-up
cost of a run: a worker's one-time preparation (imports, BLAS limits) and, within each
run, what comes before the time loop (configuration, output directory; assembly and
factorization from ``summary.json``), which a sweep axis that changes neither the mesh
nor the material could share between runs. Not a test: no time is asserted.

    python benchmarks/bench_studies.py [--runs 64] [--workers 2] [--steps 64] [--n 16]
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np


def _base(args: argparse.Namespace) -> dict:
    from vemwear.config import apply_overrides
    from vemwear.examples import config_path

    data = tomllib.loads(config_path("example_5_2_set1").read_text())
    return apply_overrides(
        data,
        {
            "mesh.divisions": [2 * args.n, args.n],
            "time.steps": args.steps,
            "output.figures": False,
            "output.vtk": False,
            "solver.backend": "scipy",
        },
    )


def serial(study, root: Path) -> tuple[float, list[dict[str, float]]]:
    """The runs one after the other in this process; the wall time and per-run parts."""
    from vemwear.config import load_config
    from vemwear.runner import execute_run, prepare_run

    parts = []
    t0 = time.perf_counter()
    for r in study.runs:
        cfgfile = root / "configs" / f"{r.id}.toml"
        cfgfile.parent.mkdir(parents=True, exist_ok=True)
        cfgfile.write_text(r.toml())
        a = time.perf_counter()
        cfg = load_config(cfgfile)
        b = time.perf_counter()
        plan = prepare_run(cfg, cfgfile, root / "runs" / r.id, cfg.solver)
        c = time.perf_counter()
        execute_run(plan, progress=False)
        d = time.perf_counter()
        s = json.loads((root / "runs" / r.id / "summary.json").read_text())["timings"]
        parts.append(
            {
                "config": b - a,
                "outdir": c - b,
                "run": d - c,
                "setup": float(s.get("setup", 0.0)),
                "loop": float(s.get("time_loop", 0.0)),
                "total": d - a,
            }
        )
    return time.perf_counter() - t0, parts


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=64)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--steps", type=int, default=64)
    ap.add_argument("--n", type=int, default=16, help="squares per unit length (1/h)")
    args = ap.parse_args()

    from vemwear.studies import load_study, sweep
    from vemwear.studies.execute import prepare_worker, study_client

    tmp = Path(tempfile.mkdtemp(prefix="bench-studies-"))
    try:
        from vemwear.studies import _toml

        (tmp / "case.toml").write_text(_toml.dumps(_base(args)))
        (tmp / "study.toml").write_text(
            'base = "case.toml"\ntitle = "bench"\n[axes]\n'
            f'"contact.kappa" = {{ start = 1.0, stop = 10.0, num = {args.runs} }}\n'
        )
        t = time.perf_counter()
        prepare_worker()  # the serial loop gets the same imports, outside its timing
        prep = time.perf_counter() - t
        study = load_study(tmp / "study.toml")
        S, parts = serial(study, tmp / "serial")

        t = time.perf_counter()
        with study_client(workers=args.workers, say=None) as client:  # what sweep makes
            C = time.perf_counter() - t
            t = time.perf_counter()
            ds = sweep(study, tmp / "study", client=client, progress=False, figures=False)
            W = time.perf_counter() - t
        assert int(ds.attrs["runs_computed"]) == args.runs and int(ds.attrs["runs_failed"]) == 0
        wt = np.asarray(ds["wall_time"].values, dtype=float)
        s = S / args.runs
        med = {k: statistics.median(p[k] for p in parts) for k in parts[0]}
        rows = [
            ("runs", f"{args.runs} (h = 1/{args.n}, {args.steps} steps, {args.workers} workers)"),
            ("serial: wall", f"{S:8.2f} s  ({1e3 * s:.1f} ms per run)"),
            ("study: cluster start", f"{C:8.2f} s"),
            ("study: sweep wall", f"{W:8.2f} s  (validation, tasks, study.nc)"),
            (
                "study: task time per run",
                f"{1e3 * float(np.median(wt)):8.1f} ms (median on the workers)",
            ),
            (
                "overhead per run",
                f"{1e3 * (args.workers * W / args.runs - s):8.1f} ms  (W x wall / N - serial per run)",
            ),
            ("speed-up", f"{S / W:8.2f} x   (with the cluster start {S / (W + C):.2f} x)"),
            ("worker preparation", f"{1e3 * prep:8.1f} ms once per worker (imports, BLAS limit)"),
            ("per run: config", f"{1e3 * med['config']:8.1f} ms (load_config: mesh, problem)"),
            ("per run: outdir", f"{1e3 * med['outdir']:8.1f} ms (prepare_run)"),
            ("per run: setup", f"{1e3 * med['setup']:8.1f} ms (assembly, ordering, factorization)"),
            ("per run: time loop", f"{1e3 * med['loop']:8.1f} ms"),
            ("per run: run", f"{1e3 * med['run']:8.1f} ms (execute_run: loop + outputs)"),
        ]
        w = max(len(a) for a, _ in rows)
        print("\n".join(f"{a:<{w}}  {b}" for a, b in rows))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
