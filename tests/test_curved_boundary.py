"""Refinement on curved boundaries: new boundary vertices go onto the curve through the
initial mesh's boundary vertices (vemwear.mesh.curves), straight parts keep the chord
midpoints to the bit, coarsening gives the chords back, the wear moves to the snapped
nodes, and the adaptive punch gets the geometry's accuracy."""

from __future__ import annotations

import signal
import subprocess
import sys
from importlib.resources import files
from pathlib import Path

import h5py
import numpy as np
import pytest

from conftest import run_until_segments
from vemwear.config import load_config
from vemwear.contact.transfer import transfer_along_contact
from vemwear.examples.punch_mesh import punch_mesh
from vemwear.mesh import (
    BoundaryCurve,
    MeshError,
    check_mesh,
    rectangle_squares,
    refine_cells,
    write_mesh,
)
from vemwear.mesh.adapt import CellTree, refine_tree
from vemwear.mesh.coarsen import coarsen_tree
from vemwear.mesh.curves import OFF_CHORD
from vemwear.simulate import Result, simulate, simulate_adaptive
from vemwear.simulate.adapt import adapt
from vemwear.simulate.problem import Problem


def _off_circle(P: np.ndarray) -> np.ndarray:
    """The distance of points to the punch's circle (centre (0, 1), R = 1)."""
    return np.abs(np.hypot(P[:, 0], P[:, 1] - 1.0) - 1.0)


def test_refinement_puts_new_arc_vertices_on_the_circle_and_keeps_straight_parts() -> None:
    mesh = punch_mesh(24, 8)
    curve = BoundaryCurve.of(mesh)
    E = mesh.part_edges("arc")
    h0 = np.linalg.norm(mesh.points[E[:, 1]] - mesh.points[E[:, 0]], axis=1).max()
    # only the arc's edges are curved: the top and the sides are straight
    arc = mesh.part_code("arc")
    assert np.all(curve.curved == (np.asarray(mesh.boundary_tags) == arc))
    for level in range(3):
        cells = np.unique(mesh.boundary_edge_cells)
        snapped = refine_cells(mesh, cells, curve=curve)
        chord = refine_cells(mesh, cells)
        check_mesh(snapped, require=())
        on_arc = snapped.part_vertices("arc")
        new = on_arc[on_arc >= mesh.n_points]
        E = mesh.part_edges("arc")
        h = np.linalg.norm(mesh.points[E[:, 1]] - mesh.points[E[:, 0]], axis=1).min()
        sagitta = h * h / 8.0  # of the shortest chord the new vertices were on before
        # the curve is the initial mesh's cubic, O(h0^4) off a circle: far below the
        # initial chords' sagitta, and below the current ones' down to h ~ h0^2
        assert _off_circle(snapped.points[new]).max() < 1e-3 * h0 * h0 / 8.0, level
        assert _off_circle(snapped.points[new]).max() < 1e-2 * sagitta, level
        assert _off_circle(chord.points[new]).max() > 0.5 * sagitta
        # every other point, the sides' and the top's midpoints included: the same bits
        rest = np.setdiff1d(np.arange(snapped.n_points), new)
        np.testing.assert_array_equal(snapped.points[rest], chord.points[rest])
        np.testing.assert_array_equal(snapped.cell_vertices, chord.cell_vertices)
        mesh = snapped


def test_straight_meshes_have_no_curve() -> None:
    mesh = rectangle_squares((2.0, 1.0), (4, 2))
    curve = BoundaryCurve.of(mesh)
    assert not curve.any
    X = mesh.points[mesh.boundary_edges[:, 0]] + 0.25 * np.array([1.0, 0.0])
    np.testing.assert_array_equal(curve.snap(X, np.asarray(mesh.boundary_tags)), X)


def test_coarsening_gives_the_chords_back() -> None:
    mesh0 = punch_mesh(12, 4)
    curve = BoundaryCurve.of(mesh0)
    mesh, tree = mesh0, CellTree.initial(mesh0.n_cells)
    for _ in range(2):
        mesh, tree, _ = refine_tree(mesh, tree, np.unique(mesh.boundary_edge_cells), 1, curve)
    assert _off_circle(mesh.points[mesh.part_vertices("arc")]).max() < 1e-6
    for _ in range(2):
        mesh, tree, _ = coarsen_tree(mesh, tree, np.arange(mesh.n_cells), 1, curve)
        check_mesh(mesh, require=())
    # back to the initial mesh: its points (renumbered) and cells
    assert mesh.n_cells == mesh0.n_cells and mesh.n_points == mesh0.n_points
    order0 = np.lexsort(mesh0.points.T)
    order = np.lexsort(mesh.points.T)
    np.testing.assert_array_equal(mesh.points[order], mesh0.points[order0])


def test_the_wear_moves_to_snapped_nodes_by_the_projection() -> None:
    mesh = punch_mesh(12, 4)
    curve = BoundaryCurve.of(mesh)
    fine = refine_cells(mesh, np.unique(mesh.boundary_edge_cells), curve=curve)
    nodes = mesh.part_vertices("arc")
    x = mesh.points[nodes, 0]
    values = 1.0 + x + 2.0 * x * x
    points = fine.points[fine.part_vertices("arc")]
    with pytest.raises(MeshError, match="lies on no contact edge"):
        transfer_along_contact(mesh, nodes, values, points, ("arc",))
    got = transfer_along_contact(mesh, nodes, values, points, ("arc",), OFF_CHORD)
    # kept nodes: the old values, bitwise
    kept = np.flatnonzero(fine.part_vertices("arc") < mesh.n_points)
    old = fine.part_vertices("arc")[kept]
    np.testing.assert_array_equal(got[kept], values[np.searchsorted(nodes, old)])
    # new nodes: the linear interpolant at the projection, here the middle of the edge,
    # as for the chord midpoints of the refinement without the curve
    chord = refine_cells(mesh, np.unique(mesh.boundary_edge_cells))
    at_mid = chord.points[chord.part_vertices("arc")]
    expect = transfer_along_contact(mesh, nodes, values, at_mid, ("arc",))
    assert np.abs(got - expect).max() <= 1e-14
    assert np.abs(points - at_mid).max() > 1e-4  # the nodes did move off the chords


def _punch(tmp: Path, nx: int, ny: int) -> Problem:
    d = tmp / f"punch_{nx}x{ny}"
    d.mkdir()
    write_mesh(punch_mesh(nx, ny), d / "punch.msh")
    (d / "punch.toml").write_text((files("vemwear.examples") / "punch.toml").read_text())
    return load_config(str(d / "punch.toml")).problem


def _wear(r: Result) -> tuple[np.ndarray, np.ndarray]:
    x = r.contact_points[:, 0]
    order = x.argsort()
    return x[order], np.asarray(r.wear[-1])[order]


def test_adaptive_punch_is_more_accurate_on_the_curve(tmp_path: Path) -> None:
    xr, wr = _wear(simulate(_punch(tmp_path, 192, 64), "newton"))

    def error(r: Result) -> float:
        x, w = _wear(r)
        d = np.interp(xr, x, w) - wr
        return float(np.sqrt(np.trapezoid(d**2, xr) / np.trapezoid(wr**2, xr)))

    p = _punch(tmp_path, 24, 8)
    err = {}
    for curved in (False, True):
        segs = simulate_adaptive(p, every=8, theta=0.5, max_cells=3000, curved=curved)
        err[curved] = error(segs[-1].result)
    # measured: 9.7e-3 on the chords, 4.9e-3 on the curve
    assert err[True] < 0.6 * err[False], err


def test_adaptive_punch_goes_on_bitwise_from_a_state(tmp_path: Path) -> None:
    p = _punch(tmp_path, 12, 4)
    states = []
    full = simulate_adaptive(
        p,
        every=8,
        theta=0.5,
        max_cells=2000,
        coarsen=0.1,
        on_segment=lambda s, st: states.append(st),
    )
    again = simulate_adaptive(p, every=8, theta=0.5, max_cells=2000, coarsen=0.1, start=states[1])
    assert len(again) == len(full) - 2
    for a, b in zip(again, full[2:], strict=True):
        np.testing.assert_array_equal(a.problem.mesh.points, b.problem.mesh.points)
        np.testing.assert_array_equal(a.result.wear[a.first :], b.result.wear[b.first :])
    on_arc = full[-1].problem.contact.points
    assert len(on_arc) > len(p.contact.points)  # the arc was refined, onto the circle
    assert _off_circle(on_arc).max() < 1e-6


def test_the_adaptive_loop_refines_onto_the_arc_too(tmp_path: Path) -> None:
    p = _punch(tmp_path, 12, 4)
    steps = adapt(p, theta=0.5, max_passes=3)
    assert len(steps) == 3
    on_arc = steps[-1].problem.contact.points
    assert len(on_arc) > len(p.contact.points)
    assert _off_circle(on_arc).max() < 1e-6
    chords = adapt(p, theta=0.5, max_passes=3, curved=False)
    assert _off_circle(chords[-1].problem.contact.points).max() > 1e-4


def test_the_curve_converges_to_the_circle_at_fourth_order() -> None:
    off = []
    for nx in (12, 24, 48):
        mesh = punch_mesh(nx, nx // 3)
        fine = refine_cells(mesh, np.unique(mesh.boundary_edge_cells), curve=BoundaryCurve.of(mesh))
        arc = fine.part_vertices("arc")
        off.append(_off_circle(fine.points[arc[arc >= mesh.n_points]]).max())
    # circle tangents at the vertices and a cubic over the chord: O(h^4), 16 per halving
    assert off[0] / off[1] > 12 and off[1] / off[2] > 12, off


def test_a_killed_punch_run_resumes_bitwise_on_the_arc(tmp_path: Path) -> None:
    from vemwear.examples import config_path

    src = config_path("punch")
    (tmp_path / "punch.msh").write_bytes((src.parent / "punch.msh").read_bytes())
    config = tmp_path / "punch.toml"
    text = src.read_text() + "\n[adapt]\nevery = 4\nmax_cells = 600\ncoarsen = true\n"
    config.write_text(text.replace("[output]", "[output]\nfigures = false\nvtk = false", 1))
    # the reference in a process of its own too: the arrays of two fresh processes
    run = [sys.executable, "-m", "vemwear", "run", str(config), "--no-progress", "-o"]
    done = subprocess.run([*run, str(tmp_path / "ref")], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    out = tmp_path / "out"
    cmd = [*run, str(out)]
    proc = run_until_segments(cmd, out, 3)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    resumed = subprocess.run([*cmd, "--resume"], capture_output=True, text=True)
    assert resumed.returncode == 0, resumed.stderr
    with h5py.File(tmp_path / "ref" / "result.h5") as f, h5py.File(out / "result.h5") as g:
        names = sorted(n for n in f if n.startswith("mesh_"))
        assert names == sorted(n for n in g if n.startswith("mesh_")) and len(names) > 3
        for n in names:
            for k in f[n]:
                assert np.array_equal(f[n][k][()], g[n][k][()]), (n, k)
        last = f[names[-1]]
        assert len(last["contact_points"]) > 25  # the arc was refined, onto the circle
        assert _off_circle(last["contact_points"][()]).max() < 1e-6
