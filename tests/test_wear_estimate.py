"""Adaptive runs for the wear (docs/method.md section 11): the indicator of the wear
profile's interpolation error, the monotone cubic transfer of the wear, and runs marked
by the wear that refine along Gamma_C only and start again bitwise."""

from __future__ import annotations

import dataclasses
import tomllib

import numpy as np
import pytest

from conftest import small_config
from vemwear.config import parse_config
from vemwear.config.errors import ConfigError
from vemwear.contact.transfer import transfer_along_contact
from vemwear.mesh import rectangle_squares, tag_rectangle
from vemwear.mesh.refine import refine_cells
from vemwear.paper import ex52
from vemwear.simulate.adaptive_time import simulate_adaptive
from vemwear.simulate.wear_estimate import wear_indicators


def _strip(n: int = 8):
    """n x 2 squares of (0, 1) x (0, 0.25), contact at the bottom (x from 0 to 1)."""
    mesh = rectangle_squares((1.0, 0.25), (n, 2))
    return tag_rectangle(mesh, {"clamped": "top", "free": ["left", "right"], "contact": "bottom"})


def _bottom(mesh):
    nodes = np.unique(mesh.part_edges("contact"))
    return nodes, mesh.points[nodes, 0]


def test_the_indicator_is_the_interpolation_error_of_a_smooth_profile() -> None:
    mesh = _strip(8)
    nodes, x = _bottom(mesh)
    eta2 = wear_indicators(mesh, nodes, 3.0 * x * x, ("contact",))
    L = 1 / 8
    # the 6 inner pieces: L^5 (w'')^2 / 120 with w'' = 6; the two end pieces see one
    # end without a second difference and carry nothing
    rows = mesh.boundary_edge_cells[mesh.boundary_tags == mesh.part_code("contact")]
    got = np.sort(eta2[rows])
    assert np.allclose(got[2:], L**5 * 36 / 120, rtol=1e-12) and np.all(got[:2] == 0)
    assert np.all(np.delete(eta2, rows) == 0)
    # a kink (where a contact zone ends) weighs nothing by itself: linear on both sides
    assert np.abs(wear_indicators(mesh, nodes, np.abs(x - 0.5), ("contact",))).max() < 1e-30


def test_the_cubic_transfer_keeps_nodes_is_monotone_and_beats_the_linear_one() -> None:
    mesh = _strip(8)
    nodes, x = _bottom(mesh)
    new = refine_cells(mesh, np.arange(mesh.n_cells))
    new_nodes, xn = _bottom(new)
    P = new.points[new_nodes]

    def move(v, cubic):
        return transfer_along_contact(mesh, nodes, v, P, ("contact",), cubic=cubic)

    smooth = np.exp(2 * x)
    old = dict(zip(x.tolist(), smooth, strict=True))
    got = move(smooth, True)
    kept = [i for i, xi in enumerate(xn.tolist()) if xi in old]
    assert len(kept) == len(nodes) and all(got[i] == old[xn[i]] for i in kept)
    inner = (xn > 1 / 8) & (xn < 7 / 8)  # the end pieces have one-sided slopes
    err_cubic = np.abs(got - np.exp(2 * xn))[inner].max()
    err_linear = np.abs(move(smooth, False) - np.exp(2 * xn))[inner].max()
    assert err_cubic < err_linear / 4, (err_cubic, err_linear)
    assert np.allclose(move(2 * x - 1, True), 2 * xn - 1, rtol=0, atol=1e-15)  # linear: exact
    # monotone data stay within the values of their old edge (no overshoot at a kink)
    ramp = np.clip((x - 0.4) * 5, 0, 1)
    out = move(ramp, True)
    assert out.min() >= 0 and out.max() <= 1 and np.all(np.diff(out[np.argsort(xn)]) >= 0)


def test_a_run_marked_by_the_wear_refines_along_gamma_c_and_starts_again_bitwise() -> None:
    pr = ex52.problem(0.2, 2.0, divisions=(16, 8), steps=8)
    kw = {"every": 2, "max_cells": 600, "estimator": "wear", "transfer": "cubic"}
    states = []
    segs = simulate_adaptive(pr, on_segment=lambda s, st: states.append(st), **kw)
    last = segs[-1]
    mesh, level = last.problem.mesh, last.tree.level
    assert mesh.n_cells > pr.mesh.n_cells and level.max() >= 2
    # the cells refined twice or more are on Gamma_C, or its graded neighbours (y < 0.25)
    centres = np.array([mesh.points[c].mean(axis=0) for c in mesh.cells])
    assert np.all(centres[level >= 2, 1] < 0.25)
    # more than one refinement round per mesh change: the second mesh is already graded
    assert segs[1].tree.level.max() >= 2
    again = simulate_adaptive(pr, start=states[1], **kw)
    for a, b in zip(again, segs[2:], strict=True):
        assert np.array_equal(a.result.wear, b.result.wear)
        assert np.array_equal(a.problem.mesh.points, b.problem.mesh.points)


@pytest.mark.parametrize(
    ("adapt", "message"),
    [
        ('estimator = "wear"', "estimator = 'wear' is implemented for k = 1"),
        ('transfer = "cubic"', "transfer = 'cubic' is implemented for k = 1"),
    ],
)
def test_the_wear_settings_are_refused_for_k_2(adapt: str, message: str) -> None:
    text = small_config("k2", vem={"order": 2}) + f"[adapt]\nevery = 2\nmax_cells = 99\n{adapt}\n"
    with pytest.raises(ConfigError, match=message):
        parse_config(tomllib.loads(text), source="case.toml")


def test_the_shipped_punch_adapts_along_the_arc_and_beats_the_uniform_mesh(tmp_path) -> None:
    """``punch_adaptive.toml``: the CLI runs it; the refined cells lie along the arc; its
    wear at T is closer to that of the punch on 96 x 32 cells (16 times the shipped mesh's
    24 x 8) than the shipped mesh's own, with fewer dofs than the 96 x 32 mesh."""
    import subprocess
    import sys

    import h5py

    from vemwear.config import load_config
    from vemwear.examples import config_path
    from vemwear.examples.punch_mesh import punch_mesh
    from vemwear.mesh import write_mesh
    from vemwear.simulate import simulate

    config = config_path("punch_adaptive")
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "vemwear", "run", str(config), "-o", str(out), "--no-progress"]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    with h5py.File(out / "result.h5", "r") as f:
        last = f[sorted(n for n in f if n.startswith("mesh_"))[-1]]
        points, level = last["points"][()], last["tree_level"][()]
        offsets, verts = last["cells_offsets"][()], last["cells_vertices"][()]
        xc, wear = last["contact_points"][()][:, 0], last["wear"][()][-1]
    centres = np.add.reduceat(points[verts], offsets[:-1]) / np.diff(offsets)[:, None]
    assert level.max() >= 2 and np.all(centres[level >= 1, 1] < 0.15)  # along the arc

    cfg = load_config(config)
    coarse = simulate(cfg.problem, cfg.solver)
    write_mesh(punch_mesh(96, 32), tmp_path / "punch.msh")  # the same parts, 16 times the cells
    (tmp_path / "punch.toml").write_text(config_path("punch").read_text())
    fine_problem = load_config(tmp_path / "punch.toml").problem
    fine = simulate(fine_problem, cfg.solver)

    def error(x, w) -> float:
        xf, wf = fine.contact_points[:, 0], fine.wear[-1]
        o, of = np.argsort(x), np.argsort(xf)
        return float(np.abs(np.interp(xf[of], x[o], w[o]) - wf[of]).max())

    e_adaptive = error(xc, wear)
    e_coarse = error(coarse.contact_points[:, 0], coarse.wear[-1])
    assert e_adaptive < e_coarse / 3, (e_adaptive, e_coarse)
    assert 2 * len(points) < fine_problem.space.n_dofs


def test_a_wear_mesh_change_refines_until_the_target_error() -> None:
    """With ``target_error`` the rounds of one mesh change go on until the estimate of
    the profile on the new mesh is at most the target (here reached within the rounds;
    the rounds see the profile moved by the cubic transfer, not the exact one)."""
    from vemwear.mesh.adapt import CellTree
    from vemwear.simulate.adaptive_time import AdaptSettings
    from vemwear.simulate.mesh_change import change_mesh_for_wear

    mesh = _strip(8)
    nodes, x = _bottom(mesh)
    tree = CellTree.initial(mesh.n_cells)
    eta0 = float(np.sqrt(wear_indicators(mesh, nodes, np.exp(2 * x), ("contact",)).sum()))
    for target in (eta0 / 3, eta0 / 8):
        cfg = AdaptSettings(1, target_error=target, estimator="wear", transfer="cubic")
        new, _, _ = change_mesh_for_wear(
            mesh, tree, nodes, np.exp(2 * x), cfg, None, (("contact",), 0.0, True)
        )
        on, xn = _bottom(new)
        eta = float(np.sqrt(wear_indicators(new, on, np.exp(2 * xn), ("contact",)).sum()))
        assert eta <= 1.2 * target < eta0, (eta, target, eta0)
        assert new.n_cells < 8 * mesh.n_cells  # not a uniform refinement of the strip


def test_whole_runs_marked_by_the_wear_refine_along_the_arc_to_the_target(tmp_path) -> None:
    """:func:`~vemwear.simulate.adapt` with ``estimator = "wear"`` on the shipped punch
    (24 x 8 cells): every pass solves the whole run, the cells along the arc are refined
    for its wear at T, the estimate falls by more than half from pass to pass, the loop
    stops at the first pass within ``target_error``, and the final wear is closer to that
    of the 96 x 32 mesh than the first pass's, with fewer dofs than that mesh."""
    from vemwear.config import load_config
    from vemwear.examples import config_path
    from vemwear.examples.punch_mesh import punch_mesh
    from vemwear.mesh import write_mesh
    from vemwear.simulate import adapt, simulate

    pr = load_config(config_path("punch")).problem
    steps = adapt(pr, estimator="wear", transfer="cubic", max_passes=3, max_cells=4000)
    assert len(steps) == 3
    eta = [s.eta for s in steps]
    assert eta[1] < eta[0] / 2 and eta[2] < eta[1] / 2, eta
    last = steps[-1]
    mesh, level = last.problem.mesh, last.level
    centres = np.array([mesh.points[c].mean(axis=0) for c in mesh.cells])
    assert level.max() >= 2 and np.all(centres[level >= 1, 1] < 0.15)  # along the arc
    assert steps[0].marked.size > 0 and last.marked.size == 0

    target = 0.5 * (eta[1] + eta[2])
    again = adapt(pr, estimator="wear", transfer="cubic", max_passes=10, target_error=target)
    assert again[-1].eta <= target and all(s.eta > target for s in again[:-1])

    write_mesh(punch_mesh(96, 32), tmp_path / "punch.msh")  # 16 times the cells
    (tmp_path / "punch.toml").write_text(config_path("punch").read_text())
    fine_problem = load_config(tmp_path / "punch.toml").problem
    fine = simulate(fine_problem, "newton")

    def error(r) -> float:
        x, w = r.contact_points[:, 0], r.wear[-1]
        xf, wf = fine.contact_points[:, 0], fine.wear[-1]
        o, of = np.argsort(x), np.argsort(xf)
        return float(np.abs(np.interp(xf[of], x[o], w[o]) - wf[of]).max())

    assert error(last.result) < error(steps[0].result) / 3
    assert last.n_dofs < fine_problem.space.n_dofs / 4
    # the residual estimator stays available: computed from the pass when asked for
    assert last.estimate.total > 0


def test_the_loop_refuses_an_unknown_estimator_and_the_wear_for_k_2() -> None:
    from vemwear.simulate import adapt

    pr = ex52.problem(0.2, 2.0, divisions=(8, 4), steps=2)
    with pytest.raises(ValueError, match="estimator must be 'residual' or 'wear'"):
        adapt(pr, estimator="energy", max_passes=1)
    with pytest.raises(ValueError, match="estimator = 'wear' is implemented for k = 1"):
        adapt(dataclasses.replace(pr, order=2), estimator="wear")


def test_a_config_with_passes_makes_the_mesh_by_whole_runs_and_resumes_bitwise(tmp_path) -> None:
    """``punch_passes.toml``: ``vemwear run`` solves the whole run on the shipped 24 x 8
    mesh and on the meshes refined for each run's wear at T until the target, then runs
    on the last mesh; its mesh and wear equal the API's loop bitwise and summary.json
    lists the passes. With mesh changes in time too (``every = 4``) a run killed after a
    mesh change resumes to the same arrays."""
    import dataclasses
    import json
    import signal
    import subprocess
    import sys

    import h5py

    from conftest import run_until_segments, segments_done
    from vemwear.config import load_config
    from vemwear.examples import config_path
    from vemwear.simulate.adapt import adapt_passes

    shipped = config_path("punch_passes")

    def cli(config, out, *extra):
        cmd = [sys.executable, "-m", "vemwear", "run", str(config), "-o", str(out)]
        return [*cmd, "--no-progress", *extra]

    def groups(path):
        with h5py.File(path, "r") as f:
            return {n: {k: f[n][k][()] for k in f[n]} for n in f if n.startswith("mesh_")}

    done = subprocess.run(cli(shipped, tmp_path / "ship"), capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    summary = json.loads((tmp_path / "ship" / "summary.json").read_text())
    passes = summary["adaptive"]["passes"]
    cfg = load_config(shipped)
    a = cfg.adapt
    assert a is not None and a.passes == 4 and a.target_error is not None
    steps, _, _ = adapt_passes(cfg.problem, a, a.passes)
    # the passes before the run are the loop's, and the run is its last pass
    assert [p["cells"] for p in passes] == [s.problem.mesh.n_cells for s in steps[:-1]]
    assert [p["eta"] for p in passes] == [s.eta for s in steps[:-1]]
    assert passes[0]["cells"] == 192 and passes[-1]["eta"] > a.target_error
    (g,) = groups(tmp_path / "ship" / "result.h5").values()
    assert np.array_equal(g["points"], steps[-1].problem.mesh.points)
    assert np.array_equal(g["wear"][-1], steps[-1].result.wear[-1])

    text = shipped.read_text() + "\n"
    (tmp_path / "punch.msh").write_bytes(shipped.with_name("punch.msh").read_bytes())
    config = tmp_path / "punch.toml"  # two passes, then mesh changes every 4 levels
    config.write_text(text.replace("passes = 4", "passes = 2\nevery = 4"))
    done = subprocess.run(cli(config, tmp_path / "ref"), capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    reference = groups(tmp_path / "ref" / "result.h5")
    cfg = load_config(config)
    assert cfg.adapt is not None and cfg.adapt.passes == 2
    segs = simulate_adaptive(cfg.problem, **dataclasses.asdict(cfg.adapt), solver=cfg.solver)
    assert segs[0].problem.mesh.n_cells > 192 and len(segs) == len(reference) == 8
    for k, (g, seg) in enumerate(zip(reference.values(), segs, strict=True)):
        rows = np.arange(seg.first, seg.last + (k == len(segs) - 1))  # the owned levels
        assert np.array_equal(g["points"], seg.problem.mesh.points)
        assert np.array_equal(g["wear"], seg.result.wear[rows])

    out = tmp_path / "out"
    proc = run_until_segments(cli(config, out), out, 3)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    assert 3 <= segments_done(out) < len(reference)
    again = subprocess.run(cli(config, out, "--resume"), capture_output=True, text=True)
    assert again.returncode == 0, again.stderr
    got = groups(out / "result.h5")
    assert got.keys() == reference.keys()
    for name, g in reference.items():
        for key, v in g.items():
            assert np.array_equal(got[name][key], v), (name, key)
    ref_summary = json.loads((tmp_path / "ref" / "summary.json").read_text())
    resumed = json.loads((out / "summary.json").read_text())
    assert resumed["adaptive"]["passes"] == ref_summary["adaptive"]["passes"]
