"""The plan's memory estimate against the peak memory of real runs (vemwear.runner.plan).

For each size and backend, a child process runs ``vemwear run`` twice: first on 8 x 4
squares with 2 steps (so that the libraries are loaded and have run once), then on
``nx x nx/2`` squares of (0, 2) x (0, 1) with the paper's data, 16 steps, u kept at
t = T only, no figures and no ParaView output. It prints the memory the child held
before the second run (the plan's base, :func:`vemwear.runner.plan.base_memory`), the
estimate the run makes of itself (:func:`vemwear.runner.plan.estimate_config`), the
peak resident memory of the child (``VmHWM``), the estimate over the peak, and the
peak over the base per ``N log2 N`` (N unknowns): the constant of the 2D factorization
in the plan's model.

Usage::

    python benchmarks/bench_estimate.py --sizes 128 256 512 1024 --backends pardiso
    python benchmarks/bench_estimate.py --sizes 128 256 512 --backends scipy
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path

from bench_long_runs import PAPER  # the paper's data on squares of (0, 2) x (0, 1)

CHILD = """
import json, sys
from vemwear.cli.main import main
from vemwear.config import load_config
from vemwear.runner.plan import base_memory, estimate_config
from vemwear.util.system import peak_memory
assert main(["run", sys.argv[1], "-o", sys.argv[2], "--no-progress", "--force"]) == 0
base = base_memory()
est = estimate_config(load_config(sys.argv[3])).memory
code = main(["run", sys.argv[3], "-o", sys.argv[4], "--no-progress", "--force"])
print(json.dumps({"base": base, "estimate": est, "peak": peak_memory(), "code": code}))
"""


def measure(nx: int, backend: str, tmp: Path) -> dict[str, float]:
    """Base, estimate and peak (bytes) of a child's run at ``nx x nx/2``."""
    warm, cfg = tmp / "warm.toml", tmp / f"c{nx}.toml"
    solver = f'[solver]\nbackend = "{backend}"\n'
    case = dict(vtk="false", store_u='"final"', checkpoint=0)
    warm.write_text(PAPER.format(title="warm", nx=8, ny=4, steps=2, **case) + solver)
    cfg.write_text(
        PAPER.format(title=f"estimate {nx}", nx=nx, ny=nx // 2, steps=16, **case) + solver
    )
    cmd = [sys.executable, "-c", CHILD, str(warm), str(tmp / "w"), str(cfg), str(tmp / "o")]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"{backend} {nx}: {done.stderr.strip()[-400:]}")
    out = json.loads(done.stdout.splitlines()[-1])
    if out["code"] != 0:
        raise SystemExit(f"{backend} {nx}: the run ended with {out['code']}")
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--sizes", type=int, nargs="+", default=[128, 256, 512])
    ap.add_argument("--backends", nargs="+", default=["pardiso", "scipy"])
    a = ap.parse_args(argv)
    print(
        f"{'backend':>8} {'size':>10} {'N':>9} | {'base MB':>8} {'peak MB':>8} "
        f"{'est. MB':>8} {'est/peak':>8} | (peak - base) / (N log2 N)"
    )
    with tempfile.TemporaryDirectory() as d:
        for backend in a.backends:
            for nx in a.sizes:
                m = measure(nx, backend, Path(d))
                n = 2 * (nx + 1) * (nx // 2 + 1)
                per = (m["peak"] - m["base"]) / (n * math.log2(n))
                print(
                    f"{backend:>8} {f'{nx}x{nx // 2}':>10} {n:9d} | {m['base'] / 1e6:8.0f} "
                    f"{m['peak'] / 1e6:8.0f} {m['estimate'] / 1e6:8.0f} "
                    f"{m['estimate'] / m['peak']:8.2f} | {per:6.1f}",
                    flush=True,
                )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
