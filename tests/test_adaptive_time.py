"""Adaptive meshes in a time-dependent run (docs/method.md section 11): one segment is the
plain run, bitwise; the mesh follows a moving load, coarsening behind it; the wear moves
to the new contact nodes."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest

from vemwear import simulate
from vemwear.mesh.checks import check_mesh
from vemwear.mesh.locate import locate_cells
from vemwear.paper import ex52
from vemwear.simulate.adaptive_time import simulate_adaptive
from vemwear.simulate.options import SolverOptions


def test_one_segment_is_the_plain_run_bitwise() -> None:
    pr = ex52.problem(0.2, 2.0, divisions=(8, 4), steps=8)
    plain = simulate(pr, "newton")
    (seg,) = simulate_adaptive(pr, every=8)
    assert (seg.first, seg.last) == (0, 8)
    assert np.array_equal(seg.result.wear, plain.wear)
    assert np.array_equal(seg.result.p_soft, plain.p_soft)
    assert np.array_equal(seg.result.u, plain.u)


def _moving_load(t: float = 0.0):
    def f2(x: np.ndarray, t: float) -> np.ndarray:
        """A pressure on the top moving from x = 0.3 to x = 1.7."""
        out = np.zeros((len(x), 2))
        centre = 0.3 + 1.4 * t
        out[:, 1] = -0.3 * np.exp(-(((x[:, 0] - centre) / 0.15) ** 2)) * (x[:, 1] > 0.99)
        return out

    base = ex52.problem(0.2, 2.0, divisions=(8, 4), steps=16)
    return dataclasses.replace(base, f1=(0.0, 0.0), f2=f2)


@pytest.fixture(scope="module")
def runs():
    pr = _moving_load()
    kw = {"every": 2, "theta": 0.5, "max_level": 3}
    return simulate_adaptive(pr, coarsen=0.1, **kw), simulate_adaptive(pr, **kw)


def test_the_mesh_follows_a_moving_load_and_coarsens_behind_it(runs) -> None:
    segs, kept = runs
    assert [s.first for s in segs] == list(range(0, 16, 2))
    assert segs[-1].last == 16
    for s in segs:
        check_mesh(s.problem.mesh)
    start, end = np.array([[0.3, 0.99]]), np.array([[1.7, 0.99]])
    last, last_kept = segs[-1], kept[-1]
    m = last.problem.mesh
    assert last.tree.level[locate_cells(m, end)][0] >= 2
    # where the load started, the mesh was refined, then coarsened when the load left
    was = max(int(s.tree.level[locate_cells(s.problem.mesh, start)][0]) for s in segs)
    assert was >= 2
    assert last.tree.level[locate_cells(m, start)][0] < was
    # without coarsening it stays refined there, with more cells
    mk = last_kept.problem.mesh
    assert last_kept.tree.level[locate_cells(mk, start)][0] == was
    assert m.n_cells < mk.n_cells


def test_the_wear_moves_to_the_new_contact_nodes(runs) -> None:
    segs, _ = runs
    for a, b in itertools.pairwise(segs):
        wa = a.result.wear[b.first]  # the wear a reached at the level b starts from
        wb = b.result.wear[b.first]
        pa, pb = a.result.contact_points, b.result.contact_points
        # kept nodes: bitwise
        index = {tuple(p): i for i, p in enumerate(pa.tolist())}
        same = [(index[tuple(p)], j) for j, p in enumerate(pb.tolist()) if tuple(p) in index]
        assert len(same) >= min(len(pa), len(pb)) // 2
        assert all(wa[i] == wb[j] for i, j in same)
        # the worn volume (trapezoidal, piecewise linear wear) is kept to round-off
        # when nodes are only added
        if len(same) == len(pa):
            va = np.sum(a.problem.contact.weights * wa)
            vb = np.sum(b.problem.contact.weights * wb)
            assert vb == pytest.approx(va, rel=1e-12)
    assert segs[-1].result.wear[-1].max() > 0


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"every": 0}, "every"),
        ({"every": 2, "coarsen": 1.0}, "coarsen"),
        ({"every": 2, "theta": 0.0}, "theta"),
        ({"every": 2, "theta": 0.8, "coarsen": 0.3}, "overlap"),
    ],
)
def test_inconsistent_settings_are_refused(kw: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        simulate_adaptive(_moving_load(), **kw)


def test_the_paraview_series_carries_every_mesh(runs, tmp_path) -> None:
    import xml.etree.ElementTree as ET

    import meshio

    from vemwear.post.adaptive import write_adaptive_series

    segs, _ = runs
    pvd = write_adaptive_series(segs, tmp_path)
    files = [(float(d.get("timestep")), d.get("file")) for d in ET.parse(pvd).iter("DataSet")]
    assert len(files) == 17  # levels 0 .. 16, each once
    times = [t for t, _ in files]
    assert times == sorted(times) and times[-1] == 1.0
    for s in segs:
        for lv in (s.first, s.last - 1):
            m = meshio.read(tmp_path / files[lv][1])
            n_cells = sum(len(c.data) for c in m.cells)
            assert n_cells == s.problem.mesh.n_cells
            assert np.allclose(m.points[:, :2], s.problem.mesh.points)
            wear = m.point_data["wear"]
            assert np.allclose(wear[s.result.contact_nodes], s.result.wear[lv])
            levels = np.concatenate(m.cell_data["level"])
            assert levels.max() == s.tree.level.max()


def test_example_5_2_reaches_the_uniform_256_accuracy_with_a_tenth_of_the_dofs() -> None:
    """The wear at T along Gamma_C against a 512 x 256 reference (16 steps): the
    adaptive run from 64 x 32 squares, a mesh change every 4 levels, is closer than the
    uniform 256 x 128 mesh with at least 10 times fewer dofs (benchmarks/adaptive_ex52.py
    gives the 64-step table with wall times)."""
    steps = 16

    def wear(r):
        x = r.contact_points[:, 0]
        return x[x.argsort()], np.asarray(r.wear[-1])[x.argsort()]

    xr, wr = wear(simulate(ex52.problem(0.2, 2.0, divisions=(512, 256), steps=steps), "newton"))

    def error(r) -> float:
        x, w = wear(r)
        d = np.interp(xr, x, w) - wr
        return float(np.sqrt(np.trapezoid(d**2, xr) / np.trapezoid(wr**2, xr)))

    fine = ex52.problem(0.2, 2.0, divisions=(256, 128), steps=steps)
    uniform = error(simulate(fine, "newton"))
    pr = ex52.problem(0.2, 2.0, divisions=(64, 32), steps=steps)
    segs = simulate_adaptive(pr, every=4, theta=0.4, max_cells=5000)
    assert len(segs) == 4
    assert error(segs[-1].result) < uniform
    assert 10 * segs[-1].problem.space.n_dofs <= fine.space.n_dofs


def test_a_mesh_that_stays_keeps_its_factorization_with_the_same_levels(monkeypatch) -> None:
    from vemwear.solvers import backends
    from vemwear.solvers.backends import superlu

    made: list[int] = []

    class Counted(superlu.SuperLUSchur):  # the real factorization, counted
        def __init__(self, *args, **kwargs) -> None:
            made.append(1)
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(superlu, "SuperLUSchur", Counted)
    pr = ex52.problem(0.2, 2.0, divisions=(8, 4), steps=16)
    opts = SolverOptions(method="newton", backend="scipy")
    states = []
    segs = simulate_adaptive(
        pr, every=2, max_cells=60, solver=opts, on_segment=lambda s, st: states.append(st)
    )
    cells = [s.problem.mesh.n_cells for s in segs]
    assert len(segs) == 8 and len(set(cells)) < len(cells) - 2  # the mesh stopped changing
    assert len(made) == len(set(cells))  # one factorization per mesh
    assert backends._KEEP == 0 and not backends._KEPT  # nothing kept after the run
    # a run started on the last mesh factorizes afresh and gives the same levels, bitwise
    again = simulate_adaptive(pr, every=2, max_cells=60, solver=opts, start=states[-2])
    assert np.array_equal(again[-1].result.wear, segs[-1].result.wear)
    assert np.array_equal(again[-1].result.u, segs[-1].result.u)
