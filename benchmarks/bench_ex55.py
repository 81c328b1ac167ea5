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

Otherwise the user's defaults (figures on, no study, the progress bar off as it is
without a terminal). Wall time from start to exit, printed as min / median / max and
the median over the floor's median. Each command runs once untimed first, with bytecode
written (``PYTHONDONTWRITEBYTECODE`` unset for the children), as an installed package
has it. The first runs print the size of the cache they wrote.

Usage::

    python benchmarks/bench_ex55.py --repeat 3
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
    a = ap.parse_args(argv)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    example = [sys.executable, "-m", "vemwear", "example", "5.5", "--no-progress"]
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        warm = tmp / "cache"
        warm.mkdir()
        times: dict[str, list[float]] = {
            k: [] for k in ("floor", "floor process", "first run", "second run")
        }
        sizes: list[int] = []
        for r in range(a.repeat + 1):
            t = time.perf_counter()
            out = subprocess.run(
                [sys.executable, "-c", FLOOR], env=env, check=True, capture_output=True, text=True
            )
            wall = time.perf_counter() - t
            splu = float(out.stdout.split("SPLU")[-1])
            cold = tmp / f"cold{r}"
            cold.mkdir()
            cache = cold if r else warm  # the untimed round fills the second runs' cache
            t = time.perf_counter()
            cmd = [*example, "-o", str(tmp / f"first{r}"), "--cache", str(cache)]
            subprocess.run(cmd, env=env, check=True, capture_output=True)
            first = time.perf_counter() - t
            sizes.append(_size(cache))
            t = time.perf_counter()
            cmd = [*example, "-o", str(tmp / f"second{r}"), "--cache", str(warm)]
            subprocess.run(cmd, env=env, check=True, capture_output=True)
            second = time.perf_counter() - t
            if r:
                for k, x in zip(times, (splu, wall, first, second), strict=True):
                    times[k].append(x)
        floor = statistics.median(times["floor"])
        for name, x in times.items():
            med = statistics.median(x)
            print(
                f"{name:>13} | {min(x):6.2f} {med:6.2f} {max(x):6.2f} s | "
                f"{med / floor:5.2f} x floor"
            )
        print(f"cache written by a first run: {max(sizes) / 1e6:.1f} MB")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
