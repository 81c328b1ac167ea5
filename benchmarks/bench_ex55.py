"""``vemwear example 5.5`` as a whole process against one factorization of its reference.

Interleaved repeats (every part once, then again) of three child processes:

* **floor**: a child that builds the stiffness matrix K of the reference mesh (h = 1/256,
  512 x 256 squares, 263,682 unknowns) and times, in itself, ``scipy.sparse.linalg.splu``
  of K and one solve; the floor is that in-child time (the child's wall time, with its
  imports and the assembly, is printed beside it);
* **first run**: ``python -m vemwear example 5.5 -o DIR --cache EMPTY`` with an empty
  cache directory: the reference is computed (and cached), as on a user's first run;
* **second run**: the same with the cache that a first run wrote, as on every later run
  (the user's default ``--cache`` is their cache directory; here a private one, so that
  the benchmark neither reads nor replaces the user's).

With ``--baseline SRC``, the first and second runs also with the package at ``SRC`` (put
first on ``PYTHONPATH``; e.g. ``git archive COMMIT src | tar -x -C DIR`` of an earlier
commit, then ``--baseline DIR/src``), interleaved with the others, each with its own
cache (the caches of two versions differ in their hash).

Otherwise the user's defaults (figures on, no study, the progress bar off as it is
without a terminal). Wall time from start to exit, printed as min / median / max and
the median over the floor's median. Each command runs once untimed first, with bytecode
written (``PYTHONDONTWRITEBYTECODE`` unset for the children), as an installed package
has it. The first runs print the size of the cache they wrote.

Usage::

    python benchmarks/bench_ex55.py --repeat 3
    python benchmarks/bench_ex55.py --repeat 3 --baseline /tmp/before/src
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

FLOOR = """
import time
import numpy as np
import scipy.sparse.linalg as spla
from vemwear.paper import ex55
K = ex55.problem(ex55.REFERENCE, steps=1).discrete.system.K.tocsc()
t = time.perf_counter()
spla.splu(K).solve(np.ones(K.shape[0]))
print("SPLU", time.perf_counter() - t)
"""


def _size(d: Path) -> int:
    return sum(p.stat().st_size for p in d.iterdir() if p.is_file())


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--baseline", type=Path, default=None, help="src directory of a baseline")
    a = ap.parse_args(argv)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    versions = {"": env}
    if a.baseline is not None:
        path = os.pathsep.join([str(a.baseline.resolve()), env.get("PYTHONPATH", "")])
        versions["baseline "] = {**env, "PYTHONPATH": path}
    example = [sys.executable, "-m", "vemwear", "example", "5.5", "--no-progress"]
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        times: dict[str, list[float]] = {"floor": [], "floor process": []}
        for v in versions:
            times[f"{v}first run"], times[f"{v}second run"] = [], []
            (tmp / f"{v}cache").mkdir()
        sizes: list[int] = []
        for r in range(a.repeat + 1):
            t = time.perf_counter()
            out = subprocess.run(
                [sys.executable, "-c", FLOOR], env=env, check=True, capture_output=True, text=True
            )
            wall = time.perf_counter() - t
            if r:  # the first round writes the bytecode and fills the second runs' caches
                times["floor"].append(float(out.stdout.split("SPLU")[-1]))
                times["floor process"].append(wall)
            for v, venv in versions.items():
                warm = tmp / f"{v}cache"
                cache = tmp / f"{v}cold{r}" if r else warm
                cache.mkdir(exist_ok=True)
                for kind, c in (("first", cache), ("second", warm)):
                    cmd = [*example, "-o", str(tmp / f"{v}{kind}{r}"), "--cache", str(c)]
                    t = time.perf_counter()
                    subprocess.run(cmd, env=venv, check=True, capture_output=True)
                    if r:
                        times[f"{v}{kind} run"].append(time.perf_counter() - t)
                if not v:
                    sizes.append(_size(cache))
        floor = statistics.median(times["floor"])
        for name, x in times.items():
            med = statistics.median(x)
            print(
                f"{name:>19} | {min(x):6.2f} {med:6.2f} {max(x):6.2f} s | "
                f"{med / floor:5.2f} x floor"
            )
        print(f"cache written by a first run: {max(sizes) / 1e6:.1f} MB")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
