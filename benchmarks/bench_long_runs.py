"""Long runs: peak memory against the number of steps, and the cost of checkpoints.

Part 1, memory: ``vemwear run`` on 32 x 16 squares (the paper's data) with
``[output] store_u = "final"``, no figures and no ParaView output, for each number of
steps in ``--steps``; each run is a separate process and its peak resident memory
(``VmHWM`` of the child) is reported when the time loop ends and at the end of the
run (which writes ``result.npz`` and the summary from ``result.h5`` in memory), with the
size of ``result.h5``. The floor is
the same process importing vemwear and building the problem without solving (steps =
1), measured in the same run. Runs are repeated ``--repeat`` times, interleaved.

Part 2, checkpoints: the reference run of Example 5.5 (h = k = 1/256, 257 levels,
displacements at the 65 levels of the coarse grids) through ``vemwear run``, with
``[output] checkpoint = 0`` (only on signals) and with ``--checkpoint`` seconds,
interleaved; wall time min / median / max.

Usage::

    python benchmarks/bench_long_runs.py --steps 1000 10000 100000 --repeat 3
    python benchmarks/bench_long_runs.py --checkpoints-only --checkpoint 1 --repeat 3
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

PAPER = """\
title = "{title}"
[mesh]
generator = "squares"
size = [2.0, 1.0]
divisions = [{nx}, {ny}]
[boundary]
clamped = "left"
traction = ["top", "right"]
contact = "bottom"
[material]
lam = 4.0
eta = 4.0
[loads]
f1 = [0.0, -0.06]
f2 = [0.0, 0.0]
[contact]
p = {{ type = "linear", c = 0.4 }}
g = 0.1
mu = 0.2
kappa = 2.0
v_star = [1.0, 0.0]
[time]
T = 1.0
steps = {steps}
[output]
figures = false
vtk = {vtk}
store_u = {store_u}
checkpoint = {checkpoint}
"""


def _run(config: str, tmp: Path) -> tuple[float, float, float, int]:
    """Wall seconds, peak RSS (MB) of the child during the time loop and in all, and the
    size of result.h5 (bytes)."""
    cfg = tmp / "case.toml"
    cfg.write_text(config)
    out = tmp / f"out-{time.monotonic_ns()}"
    cmd = [sys.executable, "-c", _CHILD, str(cfg), str(out)]
    t = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t
    if proc.returncode != 0:
        raise SystemExit(f"run failed ({proc.returncode}): {proc.stderr.strip()}")
    loop_kb, total_kb = proc.stdout.strip().splitlines()[-1].split()
    h5 = out / "result.h5"
    return (
        wall,
        float(loop_kb) / 1024,
        float(total_kb) / 1024,
        h5.stat().st_size if h5.exists() else 0,
    )


# The child reports its own peak RSS (kB), so that earlier children do not count: once
# when the time loop has ended (before result.npz and the summary are written from
# result.h5) and once at the end.
_CHILD = """
import sys
from vemwear.util.system import peak_memory
import vemwear.runner.run as run
from vemwear.cli.main import main
peak = []
finish = run._finish
def _finish(*args, **kwargs):
    peak.append((peak_memory() // 1024))
    return finish(*args, **kwargs)
run._finish = _finish
code = main(["run", sys.argv[1], "-o", sys.argv[2], "--no-progress"])
print(peak[0], (peak_memory() // 1024))
sys.exit(code)
"""


def _stats(v: list[float]) -> str:
    return f"{min(v):9.2f} {statistics.median(v):9.2f} {max(v):9.2f}"


def memory_table(steps: list[int], repeat: int) -> None:
    print("peak memory against the number of steps (32 x 16 squares, store_u = 'final')")
    print(
        f"{'steps':>9} | {'time loop: peak RSS MB':>29} | {'whole run: peak RSS MB':>29} | "
        f"{'wall s (min med max)':>29} | {'result.h5 MB':>12}"
    )
    cases = [1, *steps]
    loop: dict[int, list[float]] = {n: [] for n in cases}
    rss: dict[int, list[float]] = {n: [] for n in cases}
    wall: dict[int, list[float]] = {n: [] for n in cases}
    size: dict[int, int] = {}
    with tempfile.TemporaryDirectory() as d:
        for _ in range(repeat):
            for n in cases:  # interleaved
                cfg = PAPER.format(
                    title=f"n{n}",
                    nx=32,
                    ny=16,
                    steps=n,
                    vtk="false",
                    store_u='"final"',
                    checkpoint=60,
                )
                w, lp, r, s = _run(cfg, Path(d))
                loop[n].append(lp)
                rss[n].append(r)
                wall[n].append(w)
                size[n] = s
    for n in cases:
        label = "1 (floor)" if n == 1 else str(n)
        print(
            f"{label:>9} | {_stats(loop[n]):>29} | {_stats(rss[n]):>29} | "
            f"{_stats(wall[n]):>29} | {size[n] / 1e6:12.2f}"
        )


def checkpoint_table(every: float, repeat: int) -> None:
    print("\nExample 5.5's reference run (1/256, 257 levels, u at 65 levels) through vemwear run")
    print(f"{'checkpoint':>12} | {'wall s (min med max)':>29}")
    store = "[" + ", ".join(f"{i / 64!r}" for i in range(65)) + "]"
    cases = {"0 (signals)": 0.0, f"{every:g} s": every}
    wall: dict[str, list[float]] = {k: [] for k in cases}
    with tempfile.TemporaryDirectory() as d:
        for _ in range(repeat):
            for label, cp in cases.items():
                cfg = PAPER.format(
                    title="ref",
                    nx=512,
                    ny=256,
                    steps=256,
                    vtk="false",
                    store_u=store,
                    checkpoint=cp,
                )
                w, _, _, _ = _run(cfg, Path(d))
                wall[label].append(w)
    for label in cases:
        print(f"{label:>12} | {_stats(wall[label]):>29}")


def main() -> None:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--steps", type=int, nargs="+", default=[1000, 10000, 100000])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--checkpoint", type=float, default=1.0)
    ap.add_argument("--checkpoints-only", action="store_true")
    ap.add_argument("--memory-only", action="store_true")
    args = ap.parse_args()
    print(f"machine: {os.cpu_count()} cores; python {sys.version.split()[0]}")
    if not args.checkpoints_only:
        memory_table(args.steps, args.repeat)
    if not args.memory_only:
        checkpoint_table(args.checkpoint, args.repeat)


if __name__ == "__main__":
    main()
