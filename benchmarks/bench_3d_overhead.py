"""What a 3D run costs besides its set-up and levels, family by family.

Each case is ``src/vemwear/examples/example_3d.toml`` with another mesh, run as a user
runs it: ``python -m vemwear run CONFIG -o OUT --no-progress --force`` in a new process,
timed from the outside (``process``). From its ``summary.json``: the set-up and levels
(``assembly + setup + smallness + time_loop``: the floor, the work the run is for), the
phases around them (``config``: the modules, reading the file, the mesh and its checks,
the problem; ``plan``: estimates, output directory, the report; ``outputs``: reading the
levels back, ``result.npz``, summary, figures, ParaView files) and the rest of the
process (``process - run``: the interpreter, the command line, the first imports).
Every case runs with the outputs of the example (figures and ParaView files) and with
both off (``--outputs off``, ``[output] figures = false, vtk = false``: result.h5,
result.npz and summary.json only). Repeats are interleaved (every case once, then
again); times are given as min / median / max, the ratio process / (set-up + levels)
as the median of the runs' ratios. The children write and reuse compiled modules
(``PYTHONPYCACHEPREFIX`` in a temporary directory, ``PYTHONDONTWRITEBYTECODE`` unset),
as an installed package has them, after one untimed run of every case.

Usage::

    python benchmarks/bench_3d_overhead.py                        # every family
    python benchmarks/bench_3d_overhead.py --families voronoi3d --repeat 5
    python benchmarks/bench_3d_overhead.py --outputs off
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

#: family -> the [mesh] lines replacing ``divisions = [16, 8, 8]``: runs of a few seconds
CASES: dict[str, str] = {
    "hexahedra": 'generator = "hexahedra"\ndivisions = [32, 16, 16]',
    "tetrahedra": 'generator = "tetrahedra"\ndivisions = [16, 8, 8]',
    "prisms": 'generator = "prisms"\nn_cells = 200\nlayers = 8',
    "voronoi3d": 'generator = "voronoi3d"\nn_cells = 500',
}
SETUP_AND_LEVELS = ("assembly", "setup", "smallness", "time_loop")


def config_text(family: str, outputs: bool) -> str:
    """The example's configuration on the family's mesh, with or without outputs."""
    from vemwear.examples import config_path

    text = config_path("example_3d").read_text(encoding="utf-8")
    text = re.sub(r'generator = "hexahedra"\n', "", text)
    text = text.replace("divisions = [16, 8, 8]      # h = 1/8", CASES[family])
    if not outputs:
        text = text.replace("[output]\n", "[output]\nfigures = false\nvtk = false\n")
    return text


def run_case(family: str, outputs: bool, tmp: Path) -> dict[str, Any]:
    """One ``vemwear run`` of the case in a new process: its wall time and timings."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPYCACHEPREFIX"] = str(tmp / "pycache")
    cfg = tmp / f"{family}-{outputs}.toml"
    cfg.write_text(config_text(family, outputs), encoding="utf-8")
    out = tmp / f"out-{family}-{outputs}"
    cmd = [sys.executable, "-m", "vemwear", "run", str(cfg), "-o", str(out)]
    t = time.perf_counter()
    proc = subprocess.run(
        [*cmd, "--no-progress", "--force"], capture_output=True, text=True, env=env
    )
    wall = time.perf_counter() - t
    if proc.returncode != 0:
        raise SystemExit(f"{family} failed:\n{proc.stderr.strip()[-2000:]}")
    tm = json.loads((out / "summary.json").read_text())["timings"]
    floor = sum(tm[k] for k in SETUP_AND_LEVELS)
    return {
        "process": wall,
        "floor": floor,
        "config": tm["config"],
        "plan": tm["plan"],
        "outputs": tm["outputs"],
        "rest": wall - tm["run"],
        "ratio": wall / floor,
    }


def _mmm(v: list[float]) -> str:
    return f"{min(v):6.2f} {statistics.median(v):6.2f} {max(v):6.2f}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--families", nargs="+", choices=list(CASES), default=list(CASES))
    ap.add_argument("--outputs", choices=["on", "off", "both"], default="both")
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args(argv)
    modes = {"on": [True], "off": [False], "both": [True, False]}[a.outputs]
    runs: dict[tuple[str, bool], list[dict[str, Any]]] = {
        (f, o): [] for f in a.families for o in modes
    }
    with tempfile.TemporaryDirectory() as d:
        for f, o in runs:  # compiles the modules once
            run_case(f, o, Path(d))
        for _ in range(a.repeat):  # interleaved over the cases
            for f, o in runs:
                runs[(f, o)].append(run_case(f, o, Path(d)))
    print(f"vemwear run of example_3d.toml per family; min / median / max of {a.repeat} runs [s]")
    cols = ("process", "floor", "config", "plan", "outputs", "rest")
    head = " | ".join(f"{c:^20}" for c in ("process", "set-up + levels", *cols[2:]))
    print(f"{'family':<11} {'outputs':<7} | {head} | ratio")
    for (f, o), rs in runs.items():
        row = " | ".join(_mmm([r[c] for r in rs]) for c in cols)
        ratio = statistics.median(r["ratio"] for r in rs)
        print(f"{f:<11} {'on' if o else 'off':<7} | {row} | {ratio:5.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
