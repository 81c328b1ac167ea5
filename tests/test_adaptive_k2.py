"""Adaptive runs with the second-order space (k = 2): the wear moves between meshes as a
piecewise quadratic along Gamma_C (exact on kept nodes and on old midpoints that
refinement makes vertices), one segment is the plain run, a run started again from a
segment's state gives the same levels, and ``vemwear run`` of an ``[adapt]`` config with
``order = 2`` writes every mesh with its levels."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np

from conftest import small_config
from vemwear.config import load_config
from vemwear.contact.transfer import transfer_along_contact
from vemwear.mesh.refine import refine_cells
from vemwear.paper import ex52
from vemwear.post.energy import energy_error_reference2
from vemwear.simulate import simulate
from vemwear.simulate.adapt import adapt
from vemwear.simulate.adaptive_time import simulate_adaptive


def _problem(steps: int = 8):
    return dataclasses.replace(ex52.problem(0.2, 2.0, divisions=(8, 4), steps=steps), order=2)


def test_the_wear_moves_as_a_quadratic_along_the_contact_edges() -> None:
    pr = _problem()
    cb = pr.contact
    assert np.any(cb.nodes >= pr.mesh.n_points)  # midpoints are contact nodes

    def q(x: np.ndarray) -> np.ndarray:
        return 0.3 + x - 0.7 * x * x

    w = q(cb.points[:, 0])
    # refine the cells along the middle of Gamma_C: new vertices at old midpoints
    centres = np.array([pr.mesh.points[c].mean(axis=0) for c in pr.mesh.cells])
    new = refine_cells(pr.mesh, np.flatnonzero((centres[:, 1] < 0.3) & (centres[:, 0] > 0.6)))
    nxt = dataclasses.replace(pr, mesh=new).contact
    out = transfer_along_contact(pr.mesh, cb.nodes, w, nxt.points)
    assert np.allclose(out, q(nxt.points[:, 0]), rtol=0, atol=1e-14)
    # an old node (a kept vertex, or a midpoint now a vertex) keeps its value, bitwise
    old = {tuple(p): v for p, v in zip(cb.points.tolist(), w, strict=True)}
    kept = [i for i, p in enumerate(nxt.points.tolist()) if tuple(p) in old]
    assert len(kept) > len(cb.nodes) // 2
    assert all(out[i] == old[tuple(nxt.points[i])] for i in kept)
    assert len(nxt.nodes) > len(cb.nodes)


def test_one_segment_is_the_plain_run_and_a_restart_gives_the_same_levels() -> None:
    pr = _problem(steps=8)
    plain = simulate(pr, "newton")
    (seg,) = simulate_adaptive(pr, every=8)
    assert np.array_equal(seg.result.wear, plain.wear)
    assert np.array_equal(seg.result.dofs, plain.dofs)
    states = []
    segs = simulate_adaptive(
        pr, every=2, theta=0.5, coarsen=0.05, on_segment=lambda s, st: states.append(st)
    )
    cells = [s.problem.mesh.n_cells for s in segs]
    assert cells[-1] > cells[0] and len(set(cells)) >= 3
    assert segs[-1].estimate.total < segs[0].estimate.total
    again = simulate_adaptive(pr, every=2, theta=0.5, coarsen=0.05, start=states[1])
    for a, b in zip(again, segs[2:], strict=True):
        assert np.array_equal(a.result.wear, b.result.wear)
        assert np.array_equal(a.result.dofs, b.result.dofs)


def test_the_cli_runs_an_adaptive_order_2_config(tmp_path: Path) -> None:
    out = {"times": [0.5, 1.0], "figures": False, "vtk": True, "paraview": "pvd"}
    config = tmp_path / "case.toml"
    config.write_text(
        small_config("adaptive k2", steps=8, output=out, vem={"order": 2})
        + "[adapt]\nevery = 2\nmax_cells = 200\ncoarsen = true\n"
    )
    cmd = [sys.executable, "-m", "vemwear", "run", str(config), "-o", str(tmp_path / "o")]
    done = subprocess.run([*cmd, "--no-progress"], capture_output=True, text=True, timeout=180)
    assert done.returncode == 0, done.stderr
    cfg = load_config(str(config))
    assert cfg.adapt is not None
    segs = simulate_adaptive(cfg.problem, **dataclasses.asdict(cfg.adapt), solver=cfg.solver)
    with h5py.File(tmp_path / "o" / "result.h5", "r") as f:
        groups = [f[n] for n in sorted(f) if n.startswith("mesh_")]
        assert len(groups) == len(segs) >= 3
        for g, s in zip(groups, segs, strict=True):
            levels = g["levels"][()]
            assert len(g["contact_nodes"][()]) == len(s.problem.contact.nodes)
            assert np.array_equal(g["wear"][()], s.result.wear[levels])


def test_the_adaptive_loop_of_k_2_refines_the_clamped_corners_at_the_optimal_rate() -> None:
    """Example 5.2's step with k = 2 (singular corners of the clamped side): the energy
    error against a uniform k = 2 reference of h = 1/32 falls as N^(-1) or faster on the
    adaptive meshes (cells down to h = 1/16), against about N^(-0.4) uniformly."""

    def step(n: int):
        return dataclasses.replace(ex52.problem(0.2, 0.0, divisions=(2 * n, n), steps=1), order=2)

    ref = step(32)
    u_ref = simulate(ref, "newton", store="final").dofs[-1]

    def error(pr, u) -> float:
        e2 = energy_error_reference2(pr.mesh, pr.material, u, ref.mesh, u_ref)
        return float(np.sqrt(e2.sum()))

    steps = adapt(step(4), theta=0.5, max_level=2, max_passes=4)
    N = [s.n_dofs for s in steps]
    err = [error(s.problem, s.result.dofs[-1]) for s in steps]
    eff = [s.estimate.total / e for s, e in zip(steps, err, strict=True)]
    assert all(0.3 < x < 3.0 for x in eff), eff
    adaptive = np.polyfit(np.log(N), np.log(err), 1)[0]
    uni = [step(n) for n in (4, 8)]
    uniform = np.polyfit(
        np.log([p.space.n_dofs for p in uni]),
        np.log([error(p, simulate(p, "newton", store="final").dofs[-1]) for p in uni]),
        1,
    )[0]
    assert adaptive < -0.9 and uniform > -0.6, (adaptive, uniform)
