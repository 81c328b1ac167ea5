"""The rounded punch (``examples/punch.toml``) on uniform and on adaptive meshes: the
wear's accuracy against dofs and wall time, with the new boundary vertices on the arc
(the default) and on the initial chords.

The punch's mesh (:func:`vemwear.examples.punch_mesh.punch_mesh`, ``nx x ny``
quadrilaterals over the arc ``y = R - sqrt(R^2 - x^2)``) is written with the shipped
``punch.toml`` into a temporary directory and loaded from there; 32 steps. Every run's
wear at T, interpolated along the arc onto the contact nodes of a uniform reference
mesh (``--reference``, default 768 x 256) gives the relative L2 error along the arc;
the table lists the dofs at T, the wall time of the run (set-up included, in this
process) and that error, for uniform meshes 48 x 16 ... 256 x 128, for a mesh refined a
priori along the part of the arc that the contact zone reaches, for runs whose mesh
adapts in time (:func:`vemwear.simulate.simulate_adaptive`) of several settings, and for
the loop of whole runs marked by the wear at T (:func:`vemwear.simulate.adapt` with
``estimator = "wear"``). The runs are repeated ``--repeat`` times, interleaved (every
case once, then again), and the wall times are given as min / median / max; the last
columns compare each run's dofs and median wall time with those of the uniform
256 x 128 mesh, measured in the same invocation.

Usage::

    python benchmarks/adaptive_punch.py --repeat 5
    python benchmarks/adaptive_punch.py --reference 384 --quick
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
import time
from importlib.resources import files
from pathlib import Path

import numpy as np
from adaptive_table import Case, measure, table, wear_error

from vemwear.config import load_config
from vemwear.examples.punch_mesh import punch_mesh
from vemwear.mesh import write_mesh
from vemwear.mesh.curves import BoundaryCurve
from vemwear.mesh.refine import refine_cells
from vemwear.simulate import Result, adapt, simulate, simulate_adaptive
from vemwear.simulate.problem import Problem

#: Uniform meshes: divisions along the arc and through the height.
UNIFORM = ((48, 16), (96, 32), (192, 64), (256, 128))
#: Adaptive settings: initial divisions, every, theta, max_cells, curved, estimator,
#: transfer.
ADAPTIVE = [
    ((48, 16), 4, 0.5, 8000, True, "residual", "linear"),
    ((48, 16), 4, 0.5, 8000, False, "residual", "linear"),
    ((48, 16), 4, 0.5, 8000, True, "wear", "cubic"),
    ((48, 16), 4, 0.5, 8000, True, "residual", "cubic"),
    ((48, 16), 4, 0.5, 8000, True, "wear", "linear"),
    ((96, 32), 4, 0.5, 8000, True, "residual", "linear"),
]

#: Meshes refined a priori along the arc: initial divisions, rounds, half-width in x.
BAND = [((48, 16), 2, 0.3)]

#: Loops of whole runs marked by the wear at T: initial divisions, max_passes,
#: target_error.
PASSES = [((24, 8), 3, None), ((24, 8), 10, 3e-7), ((48, 16), 10, 3e-7)]


def punch_problem(nx: int, ny: int, where: Path) -> Problem:
    """The problem of ``punch.toml`` on ``punch_mesh(nx, ny)``."""
    d = where / f"punch_{nx}x{ny}"
    d.mkdir(exist_ok=True)
    write_mesh(punch_mesh(nx, ny), d / "punch.msh")
    (d / "punch.toml").write_text((files("vemwear.examples") / "punch.toml").read_text())
    return load_config(str(d / "punch.toml")).problem


def _uniform(div: tuple[int, int], where: Path) -> Case:
    def run() -> tuple[int, Result]:
        p = punch_problem(*div, where)
        return p.space.n_dofs, simulate(p, "newton")

    return run


def _passes(div: tuple[int, int], passes: int, target: float | None, where: Path) -> Case:
    """Whole runs, the mesh refined between them for the wear at T (cubic transfer of
    the profile between the rounds of a refinement)."""

    def run() -> tuple[int, Result]:
        p = punch_problem(*div, where)
        steps = adapt(
            p,
            estimator="wear",
            transfer="cubic",
            max_passes=passes,
            target_error=target,
            max_cells=20000,
        )
        return steps[-1].n_dofs, steps[-1].result

    return run


def _band(div: tuple[int, int], rounds: int, width: float, where: Path) -> Case:
    """The uniform mesh refined ``rounds`` times, a priori, in the cells along the arc
    with |x| <= ``width`` (new vertices on the arc): the mesh an engineer who knows where
    the contact zone will be would make."""

    def run() -> tuple[int, Result]:
        p = punch_problem(*div, where)
        mesh, curve = p.mesh, BoundaryCurve.of(p.mesh)
        for _ in range(rounds):
            rows = mesh.boundary_tags == mesh.part_code("contact")
            cells = np.unique(mesh.boundary_edge_cells[rows])
            x = np.array([mesh.points[mesh.cells[c]][:, 0].mean() for c in cells])
            mesh = refine_cells(mesh, cells[np.abs(x) <= width], curve=curve)
        p = dataclasses.replace(p, mesh=mesh)
        return p.space.n_dofs, simulate(p, "newton")

    return run


def _adaptive(
    div: tuple[int, int],
    every: int,
    theta: float,
    max_cells: int,
    curved: bool,
    estimator: str,
    transfer: str,
    where: Path,
) -> Case:
    def run() -> tuple[int, Result]:
        p = punch_problem(*div, where)
        segs = simulate_adaptive(
            p,
            every=every,
            theta=theta,
            max_cells=max_cells,
            curved=curved,
            estimator=estimator,
            transfer=transfer,
            keep=True,
        )
        return segs[-1].problem.space.n_dofs, segs[-1].result

    return run


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reference", type=int, default=768, help="x divisions of the reference")
    ap.add_argument("--repeat", type=int, default=3, help="interleaved repeats")
    ap.add_argument("--quick", action="store_true", help="the first three adaptive settings")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        where = Path(tmp)
        n = a.reference
        t0 = time.perf_counter()
        ref = simulate(punch_problem(n, n // 3, where), "newton")
        print(f"reference {n} x {n // 3}: {time.perf_counter() - t0:.1f} s")
        cases: dict[str, Case] = {f"uniform {d[0]} x {d[1]}": _uniform(d, where) for d in UNIFORM}
        for div, rounds, width in BAND:
            cases[f"{div[0]} x {div[1]} refined {rounds} times along the arc, |x| <= {width}"] = (
                _band(div, rounds, width, where)
            )
        for div, every, theta, max_cells, curved, est, tr in ADAPTIVE[: 3 if a.quick else None]:
            name = (
                f"adaptive from {div[0]} x {div[1]}, every {every}, theta {theta}, "
                f"max_cells {max_cells}, {'on the arc' if curved else 'on the chords'}, "
                f"{est}, {tr}"
            )
            cases[name] = _adaptive(div, every, theta, max_cells, curved, est, tr, where)
        for div, passes, target in PASSES:
            name = f"whole runs from {div[0]} x {div[1]}, wear at T, cubic, max_passes {passes}" + (
                f", target_error {target:g}" if target else ""
            )
            cases[name] = _passes(div, passes, target, where)
        times, found = measure(cases, a.repeat, wear_error(ref))
    base = UNIFORM[-1]
    print(table(times, found, f"uniform {base[0]} x {base[1]}"))


if __name__ == "__main__":
    main()
