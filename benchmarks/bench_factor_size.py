"""PARDISO's own prediction of a 3D run's factorization, and the plan's estimate.

For the box of ``example_3d.toml`` on hexahedra n x n/2 x n/2, the stiffness on the free
dofs is assembled and PARDISO's analysis (phase 11) is run, nothing factorized, with the
Schur block on the contact dofs as a run has it and without (a plain Cholesky, the floor).
Printed: PARDISO's counts of the factors' entries (``iparm[17]``), of the factorization's
GFLOP (``iparm[18]``) and of its peak memory (``iparm[16]``), and the plan's estimate of the
whole run (:func:`vemwear.runner.plan.estimate_config`, 64 steps), all in GB of 10^9 bytes.
The analysis of 112 x 56 x 56 (a million unknowns) takes about a minute and 5 GB.

Usage::

    python benchmarks/bench_factor_size.py --sizes 64 80 96 112
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp


def analyse(K: sp.csr_matrix, last: np.ndarray | None) -> tuple[float, float, float]:
    """(entries of the factors, GFLOP, peak bytes) that PARDISO's analysis predicts."""
    from vemwear.solvers.backends.pardiso import _Handle, _upper
    from vemwear.solvers.threads import solver_threads

    settings = {1: 3, 23: 10, 17: -1, 18: -1}
    perm = None
    if last is not None:
        settings[35] = 2
        perm = np.zeros(K.shape[0], dtype=np.int32)
        perm[last] = 1
    h = _Handle(_upper(K), 2, settings, perm)
    dummy = np.zeros(1)
    with solver_threads():
        h(11, dummy, dummy)
    entries = int(h.iparm[17]) % 2**32  # a 32-bit count: above 2^31 it wraps
    out = (float(entries), int(h.iparm[18]) / 1e3, int(h.iparm[16]) * 1024.0)
    h.release()
    return out


def main() -> None:
    from vemwear.config import load_config
    from vemwear.examples import config_path
    from vemwear.runner.plan import estimate_config

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[32, 48, 64])
    ap.add_argument("--steps", type=int, default=64)
    args = ap.parse_args()
    text = config_path("example_3d").read_text(encoding="utf-8")
    print(
        f"{'hexahedra':>14} {'unknowns':>9} {'contact':>8} | {'entries':>9} {'GFLOP':>7} "
        f"{'peak GB':>8} | {'plain':>9} {'GFLOP':>7} {'peak GB':>8} | {'plan GB':>7} {'s':>5}"
    )
    for n in args.sizes:
        tick = time.perf_counter()
        path = Path(f"factor_size_{n}.toml")
        path.write_text(
            text.replace(
                "divisions = [16, 8, 8]", f"divisions = [{n}, {n // 2}, {n // 2}]"
            ).replace("steps = 8 ", f"steps = {args.steps} "),
            encoding="utf-8",
        )
        try:
            cfg = load_config(path)
        finally:
            path.unlink()
        plan = estimate_config(cfg).memory / 1e9
        s = cfg.problem.discrete.system
        K = sp.csr_matrix(s.K)
        cd = s.contact_dofs.ravel()
        last = cd[cd >= 0]
        schur = analyse(K, last)
        plain = analyse(K, None)
        print(
            f"{f'{n}x{n // 2}x{n // 2}':>14} {K.shape[0]:9d} {len(last):8d} | "
            f"{schur[0] / 1e6:8.0f}M {schur[1]:7.0f} {schur[2] / 1e9:8.2f} | "
            f"{plain[0] / 1e6:8.0f}M {plain[1]:7.0f} {plain[2] / 1e9:8.2f} | "
            f"{plan:7.2f} {time.perf_counter() - tick:5.0f}",
            flush=True,
        )
        del s, K, cfg


if __name__ == "__main__":
    main()
