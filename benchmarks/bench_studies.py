"""Studies on Dask against a serial loop: overhead per run, speed-up, start-up cost.

N runs of Example 5.2's size (data set 1, h = 1/16: 32 x 16 squares, 64 steps, kappa
from 1 to 10; no figures or ParaView output), each through vemwear.runner into its own
directory:

- serial: one process, one run after the other (load_config, prepare_run, execute_run);
- floor: W plain processes (no Dask), each running its share of the runs like the
  serial loop, started together after their imports: what W busy cores can give;
- study: ``vemwear.studies.sweep`` on the LocalCluster a sweep makes (W single-threaded
  workers; the cluster's start is timed apart from the sweep).

The two run ``--repeat`` times, interleaved, on one cluster. Reported: min / median /
max wall times, the study's overhead per run (W x study wall / N minus the serial
time per run), the speed-up (with and without the cluster's start), and the start-up
cost of a run: a worker's one-time preparation (imports, BLAS limits) and, within each
run, what comes before the time loop (configuration, output directory; assembly and
factorization from ``summary.json``), which a sweep axis that changes neither the mesh
nor the material could share between runs. Not a test: no time is asserted.

    python benchmarks/bench_studies.py [--runs 64] [--workers 2] [--steps 64] [--n 16]
        [--repeat 3] [--chunk N]
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


def _floor_worker(study_file: str, root: str, share: list[int], barrier, queue) -> None:
    """One plain process of the floor: imports, then its share of the runs in a loop."""
    from vemwear.studies import load_study
    from vemwear.studies.execute import prepare_worker

    prepare_worker()
    study = load_study(study_file)
    study.runs = [study.runs[i] for i in share]
    barrier.wait()
    t = time.perf_counter()
    serial(study, Path(root))
    queue.put(time.perf_counter() - t)


def floor(study_file: Path, n_runs: int, root: Path, workers: int) -> float:
    """The floor of a study on ``workers`` cores: as many plain processes, each running
    its share of the runs in a loop (no Dask), started together once imported; the wall
    time until the last one ends. What two busy cores cost each other (shared caches,
    memory bandwidth, the machine's other work) is in it."""
    import multiprocessing as mp

    ctx = mp.get_context("spawn")
    barrier, queue = ctx.Barrier(workers + 1), ctx.Queue()
    procs = [
        ctx.Process(
            target=_floor_worker,
            args=(
                str(study_file),
                str(root / f"w{i}"),
                list(range(i, n_runs, workers)),
                barrier,
                queue,
            ),
        )
        for i in range(workers)
    ]
    for pr in procs:
        pr.start()
    barrier.wait()
    t = time.perf_counter()
    for _ in procs:
        queue.get()
    wall = time.perf_counter() - t
    for pr in procs:
        pr.join()
    return wall


def _stats(v: list[float], scale: float = 1.0) -> str:
    return " ".join(f"{scale * x:7.3f}" for x in (min(v), statistics.median(v), max(v)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=64)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--steps", type=int, default=64)
    ap.add_argument("--n", type=int, default=16, help="squares per unit length (1/h)")
    ap.add_argument("--repeat", type=int, default=3, help="interleaved repeats")
    ap.add_argument("--chunk", type=int, default=None, help="runs per task (default: auto)")
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
        import h5netcdf  # noqa: F401  the study's writer: imports are not timed either
        import xarray  # noqa: F401

        study = load_study(tmp / "study.toml")
        t = time.perf_counter()
        with study_client(workers=args.workers, say=None) as client:  # what sweep makes
            C = time.perf_counter() - t
            serial_wall, study_wall, floor_wall, parts, wt = [], [], [], [], []
            for k in range(args.repeat):  # interleaved: serial, floor, study, serial, ...
                S, p = serial(study, tmp / f"serial{k}")
                serial_wall.append(S)
                parts += p
                floor_wall.append(
                    floor(tmp / "study.toml", args.runs, tmp / f"floor{k}", args.workers)
                )
                t = time.perf_counter()
                ds = sweep(
                    study,
                    tmp / f"study{k}",
                    client=client,
                    progress=False,
                    figures=False,
                    chunk=args.chunk,
                )
                study_wall.append(time.perf_counter() - t)
                assert int(ds.attrs["runs_computed"]) == args.runs
                assert int(ds.attrs["runs_failed"]) == 0
                wt += [float(x) for x in np.ravel(ds["wall_time"].values)]
        S, W = statistics.median(serial_wall), statistics.median(study_wall)
        s = S / args.runs
        med = {k: statistics.median(p[k] for p in parts) for k in parts[0]}
        rows = [
            (
                "runs",
                f"{args.runs} (h = 1/{args.n}, {args.steps} steps, {args.workers} workers, "
                f"x {args.repeat} interleaved)",
            ),
            ("", "    min     med     max"),
            ("serial: wall [s]", _stats(serial_wall)),
            (
                "floor: wall [s]",
                _stats(floor_wall) + f"  ({args.workers} plain processes, no Dask)",
            ),
            ("study: sweep wall [s]", _stats(study_wall) + "  (tasks, study.nc)"),
            ("study: cluster start [s]", f"{C:7.3f}  (once: workers, their imports)"),
            ("serial: per run [ms]", _stats(serial_wall, 1e3 / args.runs)),
            ("study: task time per run [ms]", _stats(wt, 1e3) + "  (on the workers)"),
            (
                "overhead per run",
                f"{1e3 * (args.workers * W / args.runs - s):7.1f} ms  "
                "(W x wall / N - serial per run, medians)",
            ),
            (
                "speed-up",
                f"{S / W:7.2f} x  (medians; min/min {min(serial_wall) / min(study_wall):.2f} x; "
                f"with the cluster start {S / (W + C):.2f} x)",
            ),
            (
                "floor speed-up",
                f"{S / statistics.median(floor_wall):7.2f} x  (serial / floor, medians: what "
                f"{args.workers} busy cores give; study / floor {W / statistics.median(floor_wall):.2f})",
            ),
            ("worker preparation", f"{1e3 * prep:7.1f} ms once per worker (imports, BLAS limit)"),
            ("per run: config", f"{1e3 * med['config']:7.1f} ms (load_config: mesh, problem)"),
            ("per run: outdir", f"{1e3 * med['outdir']:7.1f} ms (prepare_run)"),
            ("per run: setup", f"{1e3 * med['setup']:7.1f} ms (assembly, ordering, factorization)"),
            ("per run: time loop", f"{1e3 * med['loop']:7.1f} ms"),
            ("per run: run", f"{1e3 * med['run']:7.1f} ms (execute_run: loop + outputs)"),
        ]
        w = max(len(a) for a, _ in rows)
        print("\n".join(f"{a:<{w}}  {b}" for a, b in rows))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
