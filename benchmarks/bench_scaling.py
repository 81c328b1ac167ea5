"""Scaling of a whole simulation against the floor of one sparse factorization.

For h = 1/16 ... 1/256 (k = h, the paper's data of Example 5.5 with mu = 0.2,
kappa = 2, squares), every case runs in a fresh subprocess, so that its peak memory
is its own, and reports:

* unknowns, contact nodes, time levels;
* assembly (stiffness and loads), ordering, factorization, Schur complement;
* Newton time per step and recovery of the displacement at the stored levels;
* total wall time and peak resident memory;
* the floor: one plain SuperLU factorization (SciPy's default ordering) of the
  same stiffness plus one solve;
* the paper's Uzawa iteration on the same problem where it finishes in reasonable
  time (``--uzawa-max-h``).

Usage::

    python benchmarks/bench_scaling.py                 # h = 1/16 ... 1/256
    python benchmarks/bench_scaling.py --n 16 32 64    # a quicker table
    python benchmarks/bench_scaling.py --example-5-2   # Example 5.2: Newton vs Uzawa
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time


def _case(n: int, store: str, uzawa: bool, backend: str) -> dict:
    """Run one case in this process and return its figures."""
    import numpy as np
    import scipy.sparse.linalg as spla

    from vemwear.paper import ex52
    from vemwear.simulate import SolverOptions, simulate
    from vemwear.util.system import peak_memory

    out: dict = {"n": n}
    t0 = time.perf_counter()
    problem = ex52.problem(0.2, 2.0, divisions=(2 * n, n), steps=n)
    out["mesh_s"] = time.perf_counter() - t0
    levels = np.arange(0, 65) / 64 if n >= 64 and store == "paper" else None
    t1 = time.perf_counter()
    res = simulate(
        problem,
        SolverOptions("newton", backend=backend),
        store=levels if levels is not None else "all",
    )
    out["wall_s"] = time.perf_counter() - t1 + out["mesh_s"]
    tm = res.timings
    out.update(
        {
            "unknowns": int(problem.discrete.system.n_free),
            "contact_nodes": int(problem.discrete.system.m),
            "levels": len(res.t),
            "stored_levels": len(res.u_levels),
            "assembly_s": tm["assembly"],
            "ordering_s": tm.get("setup_ordering", float("nan")),
            "factorization_s": tm.get("setup_factorization", float("nan")),
            "schur_s": tm.get("setup_schur", float("nan")),
            "time_loop_s": tm["time_loop"],
            "per_step_ms": 1e3 * tm["time_loop"] / len(res.t),
            "newton_iterations": int(res.iterations.sum()),
            "max_residual": float(res.residuals.max()),
            "max_wear_T": float(res.wear[-1].max()),
        }
    )
    out["peak_MB"] = peak_memory() / 2**20
    # the floor: one plain factorization and one solve of the same matrix
    K = problem.discrete.system.K.tocsc()
    t2 = time.perf_counter()
    lu = spla.splu(K)
    lu.solve(np.ones(K.shape[0]))
    out["floor_s"] = time.perf_counter() - t2
    if uzawa:
        t3 = time.perf_counter()
        ru = simulate(problem, SolverOptions("uzawa", backend=backend), store="final")
        out["uzawa_s"] = time.perf_counter() - t3
        out["uzawa_iterations"] = int(ru.iterations.sum())
        out["uzawa_vs_newton_wear"] = float(np.abs(ru.wear - res.wear).max() / res.wear.max())
    return out


def _example_5_2() -> dict:
    """Example 5.2's three data sets: solve time of Newton and of the paper's Uzawa."""
    import numpy as np

    from vemwear.paper import ex52
    from vemwear.simulate import SolverOptions, simulate

    rows = []
    for mu, kappa in [(0.2, 2.0), (0.2, 10.0), (0.6, 10.0)]:
        pr = ex52.problem(mu, kappa)
        _ = pr.discrete  # assembly is not part of the solve
        t = time.perf_counter()
        rn = simulate(pr, SolverOptions("newton"))
        tn = time.perf_counter() - t
        t = time.perf_counter()
        ru = simulate(pr, SolverOptions("uzawa"))
        tu = time.perf_counter() - t
        rows.append(
            {
                "mu": mu,
                "kappa": kappa,
                "newton_s": tn,
                "uzawa_s": tu,
                "speedup": tu / tn,
                "newton_iterations": int(rn.iterations.sum()),
                "uzawa_iterations": int(ru.iterations.sum()),
                "max_rel_diff_u": float(np.abs(ru.u - rn.u).max() / np.abs(rn.u).max()),
            }
        )
    return {"rows": rows}


def _assembly() -> dict:
    """Stiffness assembly of 131k squares and of 100k Voronoi cells (best of 3)."""
    from vemwear.mesh import rectangle_squares, rectangle_voronoi
    from vemwear.vem import Material, stiffness

    mat = Material(4.0, 4.0)
    out = {}
    t = time.perf_counter()
    vor = rectangle_voronoi((2.0, 1.0), 100_000, seed=0, lloyd_iterations=0)
    out["voronoi_mesh_s"] = time.perf_counter() - t
    for name, mesh in (
        ("squares_131k", rectangle_squares((2.0, 1.0), (512, 256))),
        ("voronoi_100k", vor),
    ):
        best = float("inf")
        for _ in range(3):
            t = time.perf_counter()
            stiffness(mesh, mat)
            best = min(best, time.perf_counter() - t)
        out[name] = {"cells": mesh.n_cells, "unknowns": 2 * mesh.n_points, "assembly_s": best}
    return out


def _machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}"


def _run_child(args: list[str]) -> dict:
    cmd = [sys.executable, __file__, "--child", *args]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise RuntimeError(f"benchmark case {args} failed:\n{proc.stderr}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument(
        "--n",
        type=int,
        nargs="+",
        default=[16, 32, 64, 128, 256],
        help="1/h values (k = h); default 16 32 64 128 256",
    )
    ap.add_argument("--uzawa-max-n", type=int, default=32, help="run Uzawa up to this 1/h")
    ap.add_argument(
        "--store",
        choices=["all", "paper"],
        default="paper",
        help="levels whose displacement is recovered: all, or Example 5.5's (multiples of 1/64)",
    )
    ap.add_argument("--backend", default="auto")
    ap.add_argument("--example-5-2", action="store_true", help="Example 5.2: Newton against Uzawa")
    ap.add_argument(
        "--assembly",
        action="store_true",
        help="stiffness assembly of 131k squares and 100k Voronoi cells",
    )
    ap.add_argument("--json", help="also write the rows to this JSON file")
    ap.add_argument("--child", nargs="*", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.child is not None:
        if a.child[0] == "ex52":
            print(json.dumps(_example_5_2()))
        elif a.child[0] == "assembly":
            print(json.dumps(_assembly()))
        else:
            n, store, uz, backend = a.child
            print(json.dumps(_case(int(n), store, uz == "1", backend)))
        return 0
    print(f"machine: {_machine()}")
    if a.assembly:
        out = _run_child(["assembly"])
        print("\nstiffness assembly (best of 3)")
        for name in ("squares_131k", "voronoi_100k"):
            r = out[name]
            print(
                f"{name:14s} {r['cells']:7d} cells {r['unknowns']:7d} unknowns {r['assembly_s']:6.3f} s"
            )
        rows = [out]
    elif a.example_5_2:
        out = _run_child(["ex52"])
        print("\nExample 5.2 (h = 1/16, k = 1/64): solve time, same tolerance 1e-10")
        print(
            f"{'mu':>5} {'kappa':>6} {'newton s':>9} {'uzawa s':>9} {'speedup':>8} {'rel diff u':>11}"
        )
        for r in out["rows"]:
            print(
                f"{r['mu']:5.1f} {r['kappa']:6.1f} {r['newton_s']:9.3f} {r['uzawa_s']:9.2f} "
                f"{r['speedup']:8.0f} {r['max_rel_diff_u']:11.1e}"
            )
        tot = sum(r["newton_s"] for r in out["rows"])
        print(f"Newton, three data sets: {tot:.3f} s")
        rows = out["rows"]
    else:
        rows = [
            _run_child([str(n), a.store, "1" if n <= a.uzawa_max_n else "0", a.backend])
            for n in a.n
        ]
        hdr = (
            f"{'1/h':>5} {'unknowns':>9} {'levels':>6} {'assembly':>8} {'ordering':>8} {'factor':>7} "
            f"{'schur':>6} {'step ms':>8} {'loop':>6} {'total':>6} {'peak MB':>8} {'floor':>6} {'uzawa':>7}"
        )
        print("\ntimes in seconds; total = mesh + assembly + setup + time loop (with recovery)")
        print(hdr)
        for r in rows:
            uz = f"{r['uzawa_s']:7.1f}" if "uzawa_s" in r else f"{'-':>7}"
            print(
                f"{r['n']:5d} {r['unknowns']:9d} {r['levels']:6d} {r['assembly_s']:8.2f} {r['ordering_s']:8.2f} "
                f"{r['factorization_s']:7.2f} {r['schur_s']:6.2f} {r['per_step_ms']:8.1f} "
                f"{r['time_loop_s']:6.2f} {r['wall_s']:6.2f} {r['peak_MB']:8.0f} {r['floor_s']:6.2f} {uz}"
            )
    if a.json:
        with open(a.json, "w") as f:
            json.dump(rows, f, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
