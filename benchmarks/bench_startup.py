"""Whole processes of small runs against the import of NumPy and SciPy's sparse solvers.

Interleaved repeats (every command once, then again) of three child processes, wall
time from start to exit:

* **floor**: ``python -c "import numpy, scipy.sparse.linalg"``;
* **import vemwear**: ``python -c "import vemwear"``;
* **run 32 x 16**: ``vemwear run`` of Example 5.2's data set 1 (32 x 16 squares, 64
  steps) with figures and ParaView output off, as ``python -m vemwear``;

printed as min / median / max, the median over the floor's median and the minimum
over the floor's minimum (less moved by other work on the machine). Each command runs
once untimed first, with bytecode written (``PYTHONDONTWRITEBYTECODE`` unset for the
children), as an installed package has it. Then the libraries that the run's process
imported, of those it needs only for some runs (figures, mesh files, studies).

``--phases`` splits the run above the floor, in fresh processes (``--repeat`` of them)
that import the pieces one after the other and then run the configuration twice: the
library's modules (mesh to simulate, with the solvers), pydantic, the configuration
models, the configuration's builder and the runner, the first validation (the deferred
validators built), h5py, threadpoolctl, the first run (with its first-call set-up:
MKL's first PARDISO call, the BLAS controller's scan, the output directory) and a
second run in the same process.

Usage::

    python benchmarks/bench_startup.py --repeat 11
    python benchmarks/bench_startup.py --repeat 11 --phases
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

#: Libraries a run imports only when it uses them.
OPTIONAL = (
    *("matplotlib", "certifi", "meshio", "xarray", "dask", "pandas", "pyamg", "scipy.spatial"),
    *("vemwear.simulate.adaptive_time", "vemwear.simulate.cycles", "vemwear.studies"),
)

MODULES = """
import sys
from vemwear.cli.main import main
assert main(sys.argv[1:]) == 0
print("MODULES:", *sorted(m for m in {opt} if m in sys.modules))
"""


PHASES = """
import sys, time
marks = [("start", time.perf_counter())]
def mark(name):
    marks.append((name, time.perf_counter()))
import numpy, scipy.sparse.linalg; mark("floor imports")
import vemwear.cli.main; mark("vemwear.cli")
vemwear.cli.main.command_environment()  # as the command's process has it
import vemwear.simulate, vemwear.solvers; mark("library modules")
import pydantic, pydantic.fields, pydantic.functional_validators, pydantic.main
mark("pydantic")
import vemwear.config.schema; mark("configuration models")
import vemwear.config.build, vemwear.runner.entry, vemwear.runner.run; mark("builder, runner")
import tomllib
with open(sys.argv[1], "rb") as f:
    data = tomllib.load(f)
vemwear.config.schema.ConfigFile.model_validate(data); mark("first validation")
import h5py; mark("h5py")
import threadpoolctl; mark("threadpoolctl")
import contextlib, io
from vemwear.cli.main import main
with contextlib.redirect_stdout(io.StringIO()):
    assert main(sys.argv[2:]) == 0; mark("first run")
    assert main(sys.argv[2:]) == 0; mark("second run")
print("PHASES:", *(f"{b}={t1 - t0}" for (a, t0), (b, t1) in zip(marks, marks[1:])), sep="|")
"""


def phases(cfg: Path, run: list[str], env: dict[str, str], repeat: int) -> None:
    """Print the split of a run's process into its phases, min / median / max in ms."""
    rows: list[dict[str, float]] = []
    for r in range(repeat + 1):
        out = subprocess.run(
            [sys.executable, "-c", PHASES, str(cfg), *run],
            env=env,
            check=True,
            capture_output=True,
            text=True,
        )
        line = out.stdout.strip().splitlines()[-1].split("|")[1:]
        if r:  # the first process writes the bytecode
            rows.append({k: float(v) for k, v in (kv.split("=") for kv in line)})
    for name in rows[0]:
        x = [1e3 * row[name] for row in rows]
        print(f"{name:>20} | {min(x):7.1f} {statistics.median(x):7.1f} {max(x):7.1f} ms")


def config(tmp: Path) -> Path:
    """Example 5.2, data set 1, with figures and ParaView output off."""
    from vemwear.examples import config_path

    text = config_path("example_5_2_set1").read_text(encoding="utf-8")
    text = text.replace("figures = true", "figures = false").replace("vtk = true", "vtk = false")
    path = tmp / "ex52.toml"
    path.write_text(text, encoding="utf-8")
    return path


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--phases", action="store_true", help="the split of the run's process")
    a = ap.parse_args(argv)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    with tempfile.TemporaryDirectory() as d:
        cfg = config(Path(d))
        run = ["run", str(cfg), "-o", str(Path(d) / "out"), "--force", "--no-progress"]
        if a.phases:
            phases(cfg, run, env, a.repeat)
            return 0
        cmds = {
            "floor": [sys.executable, "-c", "import numpy, scipy.sparse.linalg"],
            "import vemwear": [sys.executable, "-c", "import vemwear"],
            "run 32 x 16": [sys.executable, "-m", "vemwear", *run],
        }
        times: dict[str, list[float]] = {k: [] for k in cmds}
        for r in range(a.repeat + 1):
            for name, cmd in cmds.items():
                t = time.perf_counter()
                subprocess.run(cmd, env=env, check=True, capture_output=True)
                if r:  # the first round writes the bytecode
                    times[name].append(time.perf_counter() - t)
        floor = statistics.median(times["floor"])
        least = min(times["floor"])
        for name, x in times.items():
            med = statistics.median(x)
            print(
                f"{name:>15} | {min(x):6.3f} {med:6.3f} {max(x):6.3f} s | "
                f"{med / floor:5.2f} x floor (min: {min(x) / least:4.2f})"
            )
        code = MODULES.format(opt=repr(OPTIONAL))
        out = subprocess.run(
            [sys.executable, "-c", code, *run], env=env, check=True, capture_output=True, text=True
        )
        held = out.stdout.strip().splitlines()[-1].split()[1:]
        print(f"optional libraries the run imported: {' '.join(held) or 'none'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
