"""The 3D set-up of the condensed solver against a plain factorization of the same K.

For each case of ``benchmarks/bench_3d.py`` asked for (hexahedra, Voronoi polyhedra;
``tet`` adds tetrahedra of the same box), the stiffness ``K`` on the free dofs and the
contact dofs are built once; then, interleaved ``--repeat`` times:

* ``floor``: a plain Cholesky factorization of ``K`` by PARDISO (analysis and
  numerical factorization, no Schur block) with the settings of the Schur
  factorization, parallel nested dissection and the two-level factorization
  (``iparm[1] = 3, iparm[23] = 1``: on hexahedra 64 x 32 x 32, 75 s against 99 s
  for serial METIS, ``iparm[1] = 2``, on the loaded machine);
* ``setup``: :func:`vemwear.solvers.backends.schur_factorize` with PARDISO, the
  set-up of the condensed Newton solver (ordering, factorization, the dense Schur
  block and its inverse ``S_inv``), with its three stages.

Printed: min / median / max seconds of each, and the ratio setup / floor of each
repeat (min / median / max). PARDISO's flop count of each factorization (``iparm[18]``
with ``iparm[23] = 10``, which reports it) is printed once per case: the Schur
factorization orders the contact dofs last, which no option of PARDISO avoids (its
partial solve with sparse right-hand sides, ``iparm[30]``, orders the marked dofs
last as well), and that ordering costs more flops than the fill-minimizing one.

Usage::

    python benchmarks/bench_schur3d.py --cases hex32 hex64 --repeat 3
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from typing import Any

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from bench_3d import CASES

CASES_HERE = {**CASES, "tet": ("tetrahedra", (24, 12, 12), 64)}


def build(name: str) -> tuple[sp.csr_matrix, np.ndarray, np.ndarray]:
    """K on the free dofs, the contact dofs (as the condensed solver orders them), the
    dof points."""
    from vemwear.mesh.generate3d import box_hexahedra, box_tetrahedra
    from vemwear.mesh.voronoi3d import box_voronoi
    from vemwear.paper.ex3d import problem3d

    family, cells, _ = CASES_HERE[name]
    if family == "hexahedra":
        mesh = box_hexahedra((2.0, 1.0, 1.0), cells)
    elif family == "tetrahedra":
        mesh = box_tetrahedra((2.0, 1.0, 1.0), cells)
    else:
        mesh = box_voronoi((2.0, 1.0, 1.0), cells[0], seed=0)
    s = problem3d(mesh, 4).discrete.system
    cd = s.contact_dofs.ravel()
    return sp.csr_matrix(s.K), cd[cd >= 0], s.dof_points


def plain(K: sp.csr_matrix, settings: dict[int, int], flops: bool = False) -> tuple[float, int]:
    """Seconds of a plain PARDISO Cholesky (phases 11 and 22, the upper triangle taken
    in the timed part as the Schur factorization does), and the MFLOP when asked."""
    from vemwear.solvers.backends.pardiso import _Handle, _upper
    from vemwear.solvers.threads import solver_threads

    dummy = np.zeros(1)
    tick = time.perf_counter()
    h = _Handle(_upper(K), 2, {**settings, **({23: 10, 18: -1} if flops else {})})
    with solver_threads():
        h(11, dummy, dummy)
        h(22, dummy, dummy)
    seconds = time.perf_counter() - tick
    mflop = int(h.iparm[18])
    h.release()
    return seconds, mflop


def schur_flops(K: sp.csr_matrix, last: np.ndarray) -> int:
    """PARDISO's MFLOP of the factorization with the Schur block on ``last``."""
    from vemwear.solvers.backends.pardiso import _Handle, _upper
    from vemwear.solvers.threads import solver_threads

    n, c = K.shape[0], len(last)
    perm = np.zeros(n, dtype=np.int32)
    perm[last] = 1
    h = _Handle(_upper(K), 2, {1: 3, 23: 10, 35: 2, 18: -1}, perm)
    out = np.zeros(max(n, c * c))
    with solver_threads():
        h(11, out[:1], out)
        h(22, out[:1], out)
    mflop = int(h.iparm[18])
    h.release()
    return mflop


def _s(v: list[float]) -> str:
    return f"{min(v):8.2f} {statistics.median(v):8.2f} {max(v):8.2f}"


def main() -> None:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--cases", nargs="+", choices=list(CASES_HERE), default=["hex32", "hex64"])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    from vemwear.solvers.backends import schur_factorize

    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    print(f"machine: {os.cpu_count()} cores, load average {load}")
    data = {n: build(n) for n in args.cases}
    rows: dict[str, dict[str, list[float]]] = {n: {} for n in args.cases}
    info: dict[str, Any] = {}
    for name, (K, last, _) in data.items():
        info[name] = (K.shape[0], len(last), plain(K, {1: 3}, True)[1], schur_flops(K, last))
    for _ in range(args.repeat):
        for name, (K, last, points) in data.items():  # interleaved
            r = rows[name]
            floor = plain(K, {1: 3, 23: 1})[0]
            tick = time.perf_counter()
            f = schur_factorize(K, last, points, "pardiso")
            setup = time.perf_counter() - tick
            stages = [(k, f.timings[k]) for k in ("ordering", "factorization", "schur")]
            del f
            for key, v in [("floor", floor), ("setup", setup), ("ratio", setup / floor), *stages]:
                r.setdefault(key, []).append(v)
            print(f"  {name}: floor {floor:.2f} s, setup {setup:.2f} s", file=sys.stderr)
    print(f"set-up of the condensed solver against a plain PARDISO Cholesky, {args.repeat} repeats")
    print(
        f"{'case':>6} {'dofs':>7} {'contact':>7} {'GFLOP plain':>11} {'GFLOP schur':>11} | "
        f"{'floor s (min med max)':>26} | {'setup s (min med max)':>26} | "
        f"{'setup/floor (min med max)':>26}"
    )
    for name in args.cases:
        n, c, fp, fs = info[name]
        r = rows[name]
        print(
            f"{name:>6} {n:>7} {c:>7} {fp / 1e3:>11.1f} {fs / 1e3:>11.1f} | "
            f"{_s(r['floor']):>26} | {_s(r['setup']):>26} | {_s(r['ratio']):>26}"
        )
    print("setup stages, s (min med max)")
    print(
        f"{'case':>6} | " + " | ".join(f"{k:>26}" for k in ("ordering", "factorization", "schur"))
    )
    for name in args.cases:
        r = rows[name]
        print(
            f"{name:>6} | "
            + " | ".join(f"{_s(r[k]):>26}" for k in ("ordering", "factorization", "schur"))
        )
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    print(f"load average after: {load}")


if __name__ == "__main__":
    main()
