"""The plan's memory estimate against the peak of whole 3D runs, every mesh family.

For each family and size a child process runs ``vemwear run`` twice: first on 16 3D
hexahedra with 2 steps (so that the libraries are loaded and have run once), then on
the 3D example's data (Omega = (0, 2) x (0, 1) x (0, 1), clamped at x = 0, contact on
z = 0) meshed by the family, 16 steps, u kept at t = T only, no figures and no
ParaView output. Printed per run: the unknowns, the memory the child held before the
second run (the plan's base), the estimate the run makes of itself
(:func:`vemwear.runner.plan.estimate_config` with that base), the peak resident memory of the child (``VmHWM``) and the estimate over the
peak; then the wall time of the run and its phases from ``summary.json`` (mesh
generation and problem set-up, assembly, set-up, smallness estimate, levels) and the
whole run over set-up + levels.

Usage::

    python benchmarks/bench_estimate3d.py
    python benchmarks/bench_estimate3d.py --families voronoi3d --sizes 1000 3000 8000
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

CONFIG = """
title = "estimate {family} {size}"
[mesh]
generator = "{family}"
size = [2.0, 1.0, 1.0]
{cells}
[boundary]
clamped = "xmin"
contact = "zmin"
free = "rest"
[material]
lam = 4.0
eta = 4.0
[loads]
f1 = [0.0, 0.0, -0.06]
[contact]
p = {{ type = "linear", c = 0.4 }}
g = 0.1
mu = 0.2
kappa = 2.0
v_star = [1.0, 0.0, 0.0]
[time]
T = 1.0
steps = {steps}
[output]
times = [1.0]
store_u = "final"
figures = false
vtk = false
checkpoint = 0
"""

CHILD = """
import json, sys, time
from vemwear.cli.main import main
from vemwear.config import load_config
from vemwear.runner.plan import base_memory, estimate_config
from vemwear.util.system import peak_memory
assert main(["run", sys.argv[1], "-o", sys.argv[2], "--no-progress", "--force"]) == 0
base = base_memory()
t = time.perf_counter()
code = main(["run", sys.argv[3], "-o", sys.argv[4], "--no-progress", "--force"])
wall = time.perf_counter() - t
peak = peak_memory()
if code != 0:  # refused or failed: no summary, and the mesh is not to be made again
    raise SystemExit(code)
tm = json.load(open(sys.argv[4] + "/summary.json"))["timings"]
est = estimate_config(load_config(sys.argv[3]), base=base).memory  # the run's own base
print(json.dumps({"base": base, "estimate": est, "peak": peak, "code": code, "wall": wall,
                  "timings": tm}))
"""

#: family -> the three default sizes (cells, or the grid's x divisions)
SIZES = {
    "hexahedra": [16, 32, 40],
    "tetrahedra": [16, 24, 32],
    "prisms": [250, 500, 1000],
    "voronoi3d": [300, 1000, 2000],
}


def cells_line(family: str, size: int) -> str:
    if family in ("hexahedra", "tetrahedra"):
        return f"divisions = [{size}, {size // 2}, {size // 2}]"
    return f"n_cells = {size}\nseed = 0"


def measure(family: str, size: int, tmp: Path) -> dict:
    warm, cfg = tmp / "warm.toml", tmp / f"{family}{size}.toml"
    warm.write_text(
        CONFIG.format(family="hexahedra", size=4, cells=cells_line("hexahedra", 4), steps=2)
    )
    cfg.write_text(
        CONFIG.format(family=family, size=size, cells=cells_line(family, size), steps=16)
    )
    cmd = [sys.executable, "-c", CHILD, str(warm), str(tmp / "w"), str(cfg), str(tmp / "o")]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"{family} {size}: {done.stderr.strip()[-600:]}")
    return json.loads(done.stdout.splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--families", nargs="+", default=list(SIZES))
    ap.add_argument("--sizes", type=int, nargs="+", help="the sizes of every family given")
    a = ap.parse_args(argv)
    print(
        f"{'family':>10} {'size':>5} | {'base MB':>7} {'peak MB':>7} {'est. MB':>7} "
        f"{'est/peak':>8} | {'wall s':>6} {'before':>6} {'asm':>6} {'setup':>6} "
        f"{'small':>6} {'levels':>6} | whole/(setup+levels)"
    )
    with tempfile.TemporaryDirectory() as d:
        for family in a.families:
            for size in a.sizes or SIZES[family]:
                m = measure(family, size, Path(d))
                tm = m["timings"]
                core = tm["setup"] + tm["time_loop"]
                before = m["wall"] - tm["assembly"] - core - tm.get("smallness", 0.0)
                print(
                    f"{family:>10} {size:>5} | {m['base'] / 1e6:7.0f} {m['peak'] / 1e6:7.0f} "
                    f"{m['estimate'] / 1e6:7.0f} {m['estimate'] / m['peak']:8.2f} | "
                    f"{m['wall']:6.2f} {before:6.2f} {tm['assembly']:6.2f} {tm['setup']:6.2f} "
                    f"{tm.get('smallness', 0.0):6.2f} {tm['time_loop']:6.2f} | "
                    f"{m['wall'] / core:5.2f}",
                    flush=True,
                )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
