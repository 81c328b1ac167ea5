"""Example 5.5's error computation against one factorization of its reference's matrix.

In one process, interleaved repeats (every part once, then again) of:

* **floor**: ``scipy.sparse.linalg.splu`` of the stiffness matrix of the reference mesh
  (h = 1/256, 512 x 256 squares, 263,682 unknowns) and one solve: the unit of the
  reference run, which factorizes such a matrix;
* **Comparison(reference)**: the projection Pi and the moments of the reference mesh;
* **errors, 5 runs**: :meth:`~vemwear.post.compare.Comparison.errors_many` of the five
  coarse runs h = k = 1/4, ..., 1/64 (129 common levels in all; the secondary
  displacement variants at t = T), as ``vemwear example 5.5`` computes them;

printed as min / median / max and the median over the floor's median. The reference
comes from the user's cache (computed and cached by the first use, about 12 s); the
coarse runs are computed once before the repeats.

Usage::

    python benchmarks/bench_ex55_errors.py --repeat 5
"""

from __future__ import annotations

import argparse
import statistics
import time


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args(argv)

    import numpy as np
    import scipy.sparse.linalg as spla

    from vemwear.paper import ex55
    from vemwear.post.compare import Comparison, Solution
    from vemwear.simulate import simulate
    from vemwear.util.cache import user_cache_dir

    ref, _info = ex55.reference_solution(
        ex55.REFERENCE, ex55.common_times(ex55.LEVELS), cache_dir=user_cache_dir()
    )
    coarse = [
        Solution.from_result(simulate(pr, "newton", store="all"))
        for pr in ex55.problems(levels=ex55.LEVELS).values()
    ]
    K = ex55.problem(ex55.REFERENCE, steps=1).discrete.system.K.tocsc()

    def floor() -> None:
        spla.splu(K).solve(np.ones(K.shape[0]))

    state: dict[str, Comparison] = {}

    def comparison() -> None:
        state["c"] = Comparison(ref)

    def errors() -> None:
        state["c"].errors_many(coarse, secondary="final")

    parts = {"floor": floor, "Comparison(reference)": comparison, "errors, 5 runs": errors}
    times: dict[str, list[float]] = {k: [] for k in parts}
    for r in range(a.repeat + 1):
        for name, f in parts.items():
            t = time.perf_counter()
            f()
            if r:  # the first round warms the caches
                times[name].append(time.perf_counter() - t)
    base = statistics.median(times["floor"])
    for name, x in times.items():
        med = statistics.median(x)
        print(f"{name:>21} | {min(x):6.3f} {med:6.3f} {max(x):6.3f} s | {med / base:5.2f} x floor")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
