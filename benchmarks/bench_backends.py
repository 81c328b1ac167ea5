"""Sparse direct solvers on the stiffness of Example 5.5's meshes (k = h, squares).

For each 1/h: unknowns, factorization time and time of one back-substitution for

* SuperLU with SciPy's default ordering (the plain factorization),
* SuperLU with nested dissection and the contact dofs last (the condensed path,
  including the Schur complement it gives),
* PARDISO through pypardiso (the ``fast`` extra), if installed.

Usage::

    python benchmarks/bench_backends.py --n 32 64 128 256
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla


def _timed(f, *args, repeat: int = 1):
    """(result of the last call, mean wall time of a call)."""
    t = time.perf_counter()
    for _ in range(repeat):
        out = f(*args)
    return out, (time.perf_counter() - t) / repeat


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--n", type=int, nargs="+", default=[32, 64, 128, 256])
    a = ap.parse_args(argv)
    from vemwear.paper import ex52
    from vemwear.solvers.linalg import PardisoFactor, SchurFactor, _have_pardiso

    print(
        f"{'1/h':>5} {'unknowns':>9} | {'superlu factor':>14} {'solve':>7} | "
        f"{'ND+Schur factor':>15} {'solve':>7} | {'pardiso factor':>14} {'solve':>7}"
    )
    for n in a.n:
        pr = ex52.problem(0.2, 2.0, divisions=(2 * n, n), steps=1)
        s = pr.discrete.system
        K = s.K.tocsc()
        b = np.ones(K.shape[0])
        lu, t_lu = _timed(spla.splu, K)
        _, s_lu = _timed(lu.solve, b, repeat=3)
        nd, t_nd = _timed(SchurFactor, s.K, s.contact_dofs.ravel(), s.dof_points)
        _, s_nd = _timed(nd.solve, b, repeat=3)
        if _have_pardiso():
            pa_f, t_pa = _timed(PardisoFactor, sp.csr_matrix(K))
            _, s_pa = _timed(pa_f.solve, b, repeat=3)
            pa = f"{t_pa:14.2f} {s_pa:7.3f}"
        else:
            pa = f"{'not installed':>14} {'':>7}"
        print(
            f"{n:5d} {K.shape[0]:9d} | {t_lu:14.2f} {s_lu:7.3f} | {t_nd:15.2f} {s_nd:7.3f} | {pa}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
