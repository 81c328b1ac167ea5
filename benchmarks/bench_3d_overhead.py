"""What a 3D run costs besides its set-up and levels, family by family.

Each case is ``src/vemwear/examples/example_3d.toml`` with another mesh, run as a user
runs it: ``python -m vemwear run CONFIG -o OUT --no-progress --force`` in a new process,
timed from the outside (``process``). From its ``summary.json``: the set-up and levels
(``assembly + setup + smallness + time_loop``: the floor, the work the run is for), the
phases around them (``config``: the modules, reading the file, the mesh and its checks,
the problem; ``plan``: estimates, output directory, the report; ``outputs``: reading the
levels back, ``result.npz``, summary, figures, ParaView files, of which ``figures`` and
``paraview`` where the summary names them) and the rest of the process (``process -
run``: the interpreter, the command line, the first imports). ``cpu`` is the CPU time
(user + system, all threads) of the process: unlike the wall times it hardly grows when
other work shares the cores.
Every case runs with the outputs of the example (figures and ParaView files) and with
both off (``--outputs off``, ``[output] figures = false, vtk = false``: result.h5,
result.npz and summary.json only). Repeats are interleaved (every case once, then
again); times are given as min / median / max, the ratio process / (set-up + levels)
as the median of the runs' ratios. The children write and reuse compiled modules
(``PYTHONPYCACHEPREFIX`` in a temporary directory, ``PYTHONDONTWRITEBYTECODE`` unset),
as an installed package has them, after one untimed run of every case. ``--src`` runs
every case with each of several source trees (``PYTHONPATH``), interleaved too, to
compare a change with the code before it under the same load.

Usage::

    python benchmarks/bench_3d_overhead.py                        # the four families
    python benchmarks/bench_3d_overhead.py --families voronoi3d --repeat 5
    python benchmarks/bench_3d_overhead.py --outputs off
    python benchmarks/bench_3d_overhead.py --families voronoi3d-3000   # 3000 cells, 32 steps
    python benchmarks/bench_3d_overhead.py --src before=/path/to/old/src after=src
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

#: case -> the [mesh] lines replacing ``divisions = [16, 8, 8]`` and the time steps: runs
#: of a few seconds, and a larger one (3000 Voronoi polyhedra, 32 steps)
CASES: dict[str, tuple[str, int]] = {
    "hexahedra": ('generator = "hexahedra"\ndivisions = [32, 16, 16]', 8),
    "tetrahedra": ('generator = "tetrahedra"\ndivisions = [16, 8, 8]', 8),
    "prisms": ('generator = "prisms"\nn_cells = 200\nlayers = 8', 8),
    "voronoi3d": ('generator = "voronoi3d"\nn_cells = 500', 8),
    "voronoi3d-3000": ('generator = "voronoi3d"\nn_cells = 3000', 32),
}
DEFAULT = ("hexahedra", "tetrahedra", "prisms", "voronoi3d")
SETUP_AND_LEVELS = ("assembly", "setup", "smallness", "time_loop")


def config_text(family: str, outputs: bool) -> str:
    """The example's configuration on the case's mesh and steps, with or without outputs."""
    from vemwear.examples import config_path

    mesh, steps = CASES[family]
    text = config_path("example_3d").read_text(encoding="utf-8")
    text = re.sub(r'generator = "hexahedra"\n', "", text)
    text = text.replace("divisions = [16, 8, 8]      # h = 1/8", mesh)
    text = re.sub(r"(?m)^steps = 8 ", f"steps = {steps} ", text)
    if not outputs:
        text = text.replace("[output]\n", "[output]\nfigures = false\nvtk = false\n")
    return text


def run_case(family: str, outputs: bool, tmp: Path, src: str | None = None) -> dict[str, Any]:
    """One ``vemwear run`` of the case in a new process (with ``src`` first on
    ``PYTHONPATH`` if given): its wall time and timings."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    tag = "" if src is None else f"-{abs(hash(src))}"
    env["PYTHONPYCACHEPREFIX"] = str(tmp / f"pycache{tag}")
    if src is not None:
        env["PYTHONPATH"] = str(Path(src).resolve())
    cfg = tmp / f"{family}-{outputs}.toml"
    cfg.write_text(config_text(family, outputs), encoding="utf-8")
    out = tmp / f"out-{family}-{outputs}{tag}"
    cmd = [sys.executable, "-m", "vemwear", "run", str(cfg), "-o", str(out)]
    t, cpu = time.perf_counter(), _children_cpu()
    proc = subprocess.run(
        [*cmd, "--no-progress", "--force"], capture_output=True, text=True, env=env
    )
    wall, cpu = time.perf_counter() - t, _children_cpu() - cpu
    if proc.returncode != 0:
        raise SystemExit(f"{family} failed:\n{proc.stderr.strip()[-2000:]}")
    tm = json.loads((out / "summary.json").read_text())["timings"]
    floor = sum(tm[k] for k in SETUP_AND_LEVELS)
    return {
        "process": wall,
        "cpu": cpu,
        "floor": floor,
        "config": tm["config"],
        "plan": tm["plan"],
        "outputs": tm["outputs"],
        "figures": tm.get("outputs_figures", float("nan")),
        "paraview": tm.get("outputs_vtk", float("nan")),
        "rest": wall - tm["run"],
        "ratio": wall / floor,
    }


def _children_cpu() -> float:
    """CPU seconds (user + system) of the finished children so far."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _mmm(v: list[float]) -> str:
    if any(x != x for x in v):  # not in the summary of this source tree
        return f"{'-':^20}"
    return f"{min(v):6.2f} {statistics.median(v):6.2f} {max(v):6.2f}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--families", nargs="+", choices=list(CASES), default=list(DEFAULT))
    ap.add_argument("--outputs", choices=["on", "off", "both"], default="both")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument(
        "--src", nargs="+", metavar="NAME=DIR", help="source trees to compare (PYTHONPATH)"
    )
    a = ap.parse_args(argv)
    modes = {"on": [True], "off": [False], "both": [True, False]}[a.outputs]
    srcs: dict[str, str | None] = dict(s.split("=", 1) for s in a.src) if a.src else {"": None}
    runs: dict[tuple[str, str, bool], list[dict[str, Any]]] = {
        (f, n, o): [] for f in a.families for n in srcs for o in modes
    }
    with tempfile.TemporaryDirectory() as d:
        for f, n, o in runs:  # compiles the modules once
            run_case(f, o, Path(d), srcs[n])
        for _ in range(a.repeat):  # interleaved over the cases
            for f, n, o in runs:
                runs[(f, n, o)].append(run_case(f, o, Path(d), srcs[n]))
    print(f"vemwear run of example_3d.toml per family; min / median / max of {a.repeat} runs [s]")
    cols = ("process", "cpu", "floor", "config", "plan", "outputs", "figures", "paraview", "rest")
    head = " | ".join(f"{c:^20}" for c in ("process", "cpu", "set-up + levels", *cols[3:]))
    w = max(len(f) for f in a.families) + (max(len(n) for n in srcs) + 1 if a.src else 0)
    print(f"{'family':<{w}} {'outputs':<7} | {head} | ratio")
    for (f, n, o), rs in runs.items():
        row = " | ".join(_mmm([r[c] for r in rs]) for c in cols)
        ratio = statistics.median(r["ratio"] for r in rs)
        name = f"{f} {n}" if a.src else f
        print(f"{name:<{w}} {'on' if o else 'off':<7} | {row} | {ratio:5.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
