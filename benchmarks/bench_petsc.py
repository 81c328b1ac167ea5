"""The petsc backend (MUMPS through PETSc over N MPI ranks) against the serial default.

For each case (2D: Example 5.2's data on 2n x n squares; 3D: the 3D example's block on
2n x n x n hexahedra) and each way of factorizing:

* ``petsc N=1``, ``petsc N=2``, ...: ``mpirun -n N`` runs of this script with the
  petsc backend as a run uses it: the ranks assemble the distributed matrix from their
  own cells and keep it, rank 0 holds K's operator and assembles only the cells along
  the contact and the constrained dofs (``Problem.discretize(distributed=True)``);
  MUMPS factorizes the ranks' matrix with the Schur complement on the contact dofs;
* with ``--cells``, also ``petsc cells N=1``, ...: rank 0 assembles the whole K as
  well (the path before the operator: the ranks' cells, and K on rank 0);
* with ``--rows``, also ``petsc rows N=1``, ...: the distributed matrix made as at
  first, rank 0 sending each rank its block of the rows of the K it assembled;
* ``pardiso`` (or ``scipy``): the serial default path, :func:`schur_factorize` with
  ``"auto"``, in one process;

the time of each phase: ``assembly`` (mesh, stiffness or its rows at the contact and
the constrained dofs, contact operators: rank 0's own), ``distribute`` (the making of
the distributed matrix, the slowest rank: the recipe and the partition sent, each
rank's cells' matrices, the interface rows exchanged; or the rows sent),
``factor`` (MUMPS's analysis and factorization; PARDISO's ordering and
factorization), ``schur inv`` (the inverse of the dense Schur complement on rank 0),
``set-up`` (all of them, from the configuration to the inverse), and the
``solve/rhs`` of a block of ``--rhs`` right-hand sides (the recovery of u). Every
process is a fresh one; the cases run interleaved (one of each per round) ``--repeat``
times and are reported as min / median / max. The floor, measured in the same rounds,
is ``pardiso plain``: a plain PARDISO Cholesky factorization of the same matrix (no
Schur block) and its block solve.

Per rank, min / median / max over the rounds: the seconds of each rank's cells'
matrices (``cells``) and of its whole part of ``distribute``, and its peak resident
memory (the process whole: interpreter, mesh, matrix, factors); from the last round,
the cells and rows of each rank and MUMPS's own count of its factorization's memory
on that rank (INFO(22)), which is the share that falls with N.

Usage::

    python benchmarks/bench_petsc.py --case 2d:128 3d:24 --ranks 1 2 --repeat 3
    python benchmarks/bench_petsc.py --case 2d:128 3d:16 --ranks 1 2 --cells --rows --no-serial
    python benchmarks/bench_petsc.py --mpirun "mpirun --allow-run-as-root --oversubscribe"

The script must run with a Python in which petsc4py and mpi4py import (docs/mpi.md).
Timings on a loaded machine are only indicative.
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import statistics
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

PHASES = ("assembly", "distribute", "factor", "schur inv", "set-up", "solve/rhs ms")
#: per rank, over the rounds
PER_RANK = ("cells s", "distribute s", "peak MB")

CONFIG_2D = """\
title = "bench 2d"
[mesh]
generator = "squares"
size = [2.0, 1.0]
divisions = [{a}, {b}]
[boundary]
clamped = "left"
traction = ["top", "right"]
contact = "bottom"
[material]
lam = 4.0
eta = 4.0
[loads]
f1 = [0.0, -0.06]
[contact]
p = {{ type = "linear", c = 0.4 }}
g = 0.1
mu = 0.2
kappa = 2.0
v_star = [1.0, 0.0]
[time]
T = 1.0
steps = 1
"""

CONFIG_3D = """\
title = "bench 3d"
[mesh]
generator = "hexahedra"
size = [2.0, 1.0, 1.0]
divisions = [{a}, {b}, {b}]
[boundary]
clamped = "xmin"
contact = "zmin"
free = "rest"
[material]
lam = 4.0
eta = 4.0
[loads]
f1 = [0.0, 0.0, -0.06]
[contact]
p = {{ type = "linear", c = 0.4 }}
g = 0.1
mu = 0.2
kappa = 2.0
v_star = [1.0, 0.0, 0.0]
[time]
T = 1.0
steps = 1
"""


def _peak_mb() -> float:
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _system(case: str, distributed: bool = False):
    """K (a SciPy matrix, or with ``distributed`` the operator of the matrix the ranks
    keep), the contact dofs, the dof points and the recipe of K."""
    from vemwear.config import load_config

    dim, n = case.split(":")
    text = (CONFIG_2D if dim == "2d" else CONFIG_3D).format(a=2 * int(n), b=int(n))
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "case.toml"
        path.write_text(text)
        cfg = load_config(path)
        s = cfg.problem.discretize(distributed=distributed).system
        cd = s.contact_dofs.ravel()
        return s.K, cd[cd >= 0], s.dof_points, s.assembly


def worker(case: str, method: str, rhs: int, partition: str = "rows") -> None:
    """One measurement (this process, or rank 0 of an MPI job): prints a JSON line."""
    import numpy as np

    row: dict = {}
    if method.startswith("petsc"):
        from vemwear.solvers.backends.petsc import PetscSchur, _rank, serve, session

        by_cells = method == "petsc-cells"
        st = _rank()
        with session() as root:
            if root:
                row = _measure(
                    case,
                    rhs,
                    lambda K, c, p, a: PetscSchur(K, c, p, a if by_cells else None, partition),
                    distributed=method == "petsc",
                )
            else:
                serve()
        peaks = st.comm.gather(_peak_mb(), root=0)
        if st.rank != 0:
            return
        row["peak MB"] = peaks
    else:
        from vemwear.solvers.backends import schur_factorize
        from vemwear.solvers.backends.pardiso import PardisoFactor

        if method == "pardiso plain":

            def make(K, c, p, a):
                return PardisoFactor(K, spd=True)
        else:

            def make(K, c, p, a):
                return schur_factorize(K, c, p, "auto")

        row = _measure(case, rhs, make)
        row["peak MB"] = [_peak_mb()]
    del np
    print("RESULT " + json.dumps(row), flush=True)


def _measure(case: str, rhs: int, make, distributed: bool = False) -> dict:
    import numpy as np

    t = time.perf_counter()
    K, contact, points, assembly = _system(case, distributed)
    made = time.perf_counter() - t
    t = time.perf_counter()
    f = make(K, contact, points, assembly)
    total = time.perf_counter() - t
    # the distributed matrix: made with the discretization (distributed), or by the
    # factorization (from the cells, or the rows sent by rank 0)
    report = getattr(K if distributed else f, "assembly_report", {})
    row: dict = {"n": K.shape[0], "c": len(contact)}
    row["distribute"] = max(report.get("seconds", [0.0]))
    row["assembly"] = made - row["distribute"] if distributed else made
    schur = getattr(f, "timings", {}).get("schur", 0.0)
    row["factor"] = total - schur - (0.0 if distributed else row["distribute"])
    row["schur inv"] = schur
    row["set-up"] = made + total
    row["distribute s"] = report.get("seconds", [0.0])
    row["cells s"] = report.get("cell_seconds", [])
    row["cells"] = report.get("cells", [])
    row["rows"] = report.get("rows", [])
    row["partitioner"] = report.get("partitioner", "-")
    B = np.random.default_rng(0).normal(size=(K.shape[0], rhs))
    t = time.perf_counter()
    X = f.solve(B)
    row["solve/rhs ms"] = 1e3 * (time.perf_counter() - t) / rhs
    row["residual"] = float(np.abs(K @ X - B).max() / np.abs(B).max())
    row["MUMPS MB"] = list(getattr(f, "megabytes", []))
    row["backend"] = getattr(f, "name", "pardiso")
    return row


def _stats(v: list[float]) -> str:
    return f"{min(v):8.3f} {statistics.median(v):8.3f} {max(v):8.3f}"


def _per_rank(times: dict, name: str) -> str:
    """``min/median/max`` of each rank's values of ``name`` over the rounds."""
    rounds = times.get(name, [])
    if not rounds or not rounds[0]:
        return "-"
    ranks = zip(*rounds, strict=True)
    fmt = ".0f" if name == "peak MB" else ".3f"
    return " | ".join(
        "/".join(format(x, fmt) for x in (min(v), statistics.median(v), max(v))) for v in ranks
    )


def _tables(times: dict, last: dict) -> None:
    print("Time per phase [s] (solve: ms per right-hand side), min / median / max")
    head = "".join(f" {p + ': min median max':>29}" for p in PHASES)
    print(f"{'case':<8} {'unknowns':>9} {'contact':>7} {'path':<15}{head}")
    for (case, name), ph in times.items():
        row = last[(case, name)]
        cells = "".join(f" {_stats(ph[p]):>29}" for p in PHASES)
        print(f"{case:<8} {row['n']:9d} {row['c']:7d} {name:<15}{cells}")
    print("Per rank (rank 0 | rank 1 | ...), min/median/max over the rounds:")
    for (case, name), ph in times.items():
        row = last[(case, name)]
        print(f"{case:<8} {name:<15} partitioner {row['partitioner']}")
        for p in PER_RANK:
            print(f"{'':<24} {p:<13} {_per_rank(ph, p)}")
        mumps = " | ".join(str(m) for m in row["MUMPS MB"]) or "-"
        print(f"{'':<24} {'cells':<13} {' | '.join(map(str, row['cells'])) or '-'}")
        print(f"{'':<24} {'rows':<13} {' | '.join(map(str, row['rows'])) or '-'}")
        print(f"{'':<24} {'MUMPS MB':<13} {mumps}  (residual {row['residual']:.1e})")
    sys.stdout.flush()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--case", nargs="+", default=["2d:128", "3d:24"], help="2d:n or 3d:n")
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--rhs", type=int, default=8, help="columns of the block solve")
    ap.add_argument("--mpirun", default="mpirun --allow-run-as-root --oversubscribe")
    ap.add_argument(
        "--rows", action="store_true", help="also the rows sent by rank 0 (the first path)"
    )
    ap.add_argument(
        "--cells",
        action="store_true",
        help="also the whole K on rank 0 beside the ranks' cells (the second path)",
    )
    ap.add_argument(
        "--no-serial", action="store_true", help="leave out the serial default and its floor"
    )
    ap.add_argument(
        "--partition",
        default="rows",
        choices=("rows", "metis", "slabs"),
        help="the split of the cells over the ranks (PetscSchur's partition)",
    )
    ap.add_argument("--worker", nargs=2, metavar=("CASE", "METHOD"), help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.worker:
        worker(a.worker[0], a.worker[1], a.rhs, a.partition)
        return 0
    me = [sys.executable, os.path.abspath(__file__), "--rhs", str(a.rhs)]
    me += ["--partition", a.partition, "--worker"]
    runs: dict[str, list[str]] = {}
    if not a.no_serial:
        runs.update({"default (auto)": [], "pardiso plain": []})
    for n in a.ranks:
        runs[f"petsc N={n}"] = [*shlex.split(a.mpirun), "-n", str(n)]
        if a.cells:
            runs[f"petsc cells N={n}"] = runs[f"petsc N={n}"]
        if a.rows:
            runs[f"petsc rows N={n}"] = runs[f"petsc N={n}"]
    times: dict[tuple[str, str], dict[str, list[float]]] = defaultdict(lambda: defaultdict(list))
    last: dict[tuple[str, str], dict] = {}
    for r in range(a.repeat):
        for case in a.case:
            for name, prefix in runs.items():
                method = {"default (auto)": "auto"}.get(name, name)
                if name.startswith("petsc"):
                    way = name.split()[1]  # "N=2", or the path: "cells", "rows"
                    method = "petsc" if way.startswith("N=") else f"petsc-{way}"
                done = subprocess.run(
                    [*prefix, *me, case, method], capture_output=True, text=True, check=False
                )
                lines = [ln for ln in done.stdout.splitlines() if ln.startswith("RESULT ")]
                if done.returncode != 0 or not lines:
                    print(f"{case} {name}: failed\n{done.stdout}\n{done.stderr}", file=sys.stderr)
                    return 1
                row = json.loads(lines[-1][7:])
                for p in PHASES + PER_RANK:
                    times[(case, name)][p].append(row[p])
                last[(case, name)] = row
        print(f"\n== after round {r + 1} of {a.repeat}", flush=True)
        _tables(times, last)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
