"""Whole processes of small runs against the import of NumPy and SciPy's sparse solvers.

Interleaved repeats (every command once, then again) of three child processes, wall
time from start to exit:

* **floor**: ``python -c "import numpy, scipy.sparse.linalg"``;
* **import vemwear**: ``python -c "import vemwear"``;
* **run 32 x 16**: ``vemwear run`` of Example 5.2's data set 1 (32 x 16 squares, 64
  steps) with figures and ParaView output off, as ``python -m vemwear``;

printed as min / median / max and the median over the floor's median. Each command
runs once untimed first, with bytecode written (``PYTHONDONTWRITEBYTECODE`` unset for
the children), as an installed package has it. Then the libraries that the run's
process imported, of those it needs only for some runs (figures, mesh files, studies).

Usage::

    python benchmarks/bench_startup.py --repeat 11
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
    a = ap.parse_args(argv)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    with tempfile.TemporaryDirectory() as d:
        cfg = config(Path(d))
        run = ["run", str(cfg), "-o", str(Path(d) / "out"), "--force", "--no-progress"]
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
        for name, x in times.items():
            med = statistics.median(x)
            print(
                f"{name:>15} | {min(x):6.3f} {med:6.3f} {max(x):6.3f} s | "
                f"{med / floor:5.2f} x floor"
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
