"""Dörfler marking, graded refinement and the adaptive loop (docs/method.md section 11)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from vemwear import simulate
from vemwear.mesh import rectangle_squares, tag_rectangle
from vemwear.mesh.adapt import dorfler_marking, graded_closure, neighbour_pairs, refine_graded
from vemwear.mesh.checks import check_mesh
from vemwear.mesh.locate import locate_cells
from vemwear.paper import ex52
from vemwear.post.energy import energy_error_reference
from vemwear.simulate.adapt import adapt


def test_dorfler_marks_the_fewest_cells_that_carry_theta() -> None:
    rng = np.random.default_rng(3)
    eta2 = rng.random(200) ** 4
    for theta in (0.1, 0.5, 0.9, 1.0):
        m = dorfler_marking(eta2, theta)
        assert eta2[m].sum() >= theta * eta2.sum() * (1 - 1e-12)
        # one cell fewer (the smallest marked) is not enough, and the marked are the largest
        assert eta2[m[:-1]].sum() < theta * eta2.sum()
        assert eta2[m].min() >= np.delete(eta2, m).max(initial=0.0)
    assert dorfler_marking(np.zeros(5), 0.5).size == 0


@pytest.mark.parametrize("bad", [0.0, -0.1, 1.5])
def test_dorfler_refuses_a_theta_outside_0_1(bad: float) -> None:
    with pytest.raises(ValueError, match="theta"):
        dorfler_marking(np.ones(3), bad)


def test_dorfler_names_a_negative_indicator() -> None:
    with pytest.raises(ValueError, match="cell 2"):
        dorfler_marking([1.0, 2.0, -1.0], 0.5)


def _corner_refinement(max_difference: int, times: int = 5):
    mesh = tag_rectangle(rectangle_squares((2.0, 1.0), (8, 4)))
    level = np.zeros(mesh.n_cells, dtype=np.int64)
    for _ in range(times):
        # the cell holding a point next to the side x = 1/4 of its initial cell
        cell = locate_cells(mesh, np.array([[0.25 - 1e-3, 0.1]]))
        mesh, level, parent = refine_graded(mesh, level, cell, max_difference)
        assert len(parent) == mesh.n_cells
    return mesh, level


def test_graded_refinement_keeps_neighbours_within_one_level() -> None:
    mesh, level = _corner_refinement(1)
    check_mesh(mesh)
    pairs = neighbour_pairs(mesh)
    assert np.abs(level[pairs[:, 0]] - level[pairs[:, 1]]).max() == 1
    assert level.max() == 5
    # without the bound the corner's neighbours fall several levels behind
    loose, loose_level = _corner_refinement(10)
    lp = neighbour_pairs(loose)
    assert np.abs(loose_level[lp[:, 0]] - loose_level[lp[:, 1]]).max() > 1
    assert loose.n_cells < mesh.n_cells
    # the boundary parts carry over to the refined edges
    assert mesh.part_counts()["contact"] > 8


def test_graded_closure_adds_nothing_to_a_uniform_marking() -> None:
    mesh = rectangle_squares((1.0, 1.0), (4, 4))
    level = np.zeros(mesh.n_cells, dtype=np.int64)
    assert graded_closure(mesh, level, [5]).tolist() == [5]
    with pytest.raises(ValueError, match="one entry per cell"):
        graded_closure(mesh, level[:3], [5])


def _step(n: int):
    """Example 5.2's data, one step, no wear: the clamped corners are singular."""
    return ex52.problem(0.2, 0.0, divisions=(2 * n, n), steps=1)


@pytest.fixture(scope="module")
def reference():
    pr = _step(64)
    return pr, simulate(pr, "newton", store="final").u[-1]


def _error(problem, u, reference) -> float:
    ref, u_ref = reference
    e2 = energy_error_reference(problem.mesh, problem.material, u, ref.mesh, u_ref)
    return float(np.sqrt(e2.sum()))


def test_the_adaptive_loop_refines_the_clamped_corners(reference) -> None:
    steps = adapt(_step(4), theta=0.5, max_level=3, max_passes=8)
    assert len(steps) == 8
    eff, err = [], []
    for s in steps:
        check_mesh(s.problem.mesh)
        err.append(_error(s.problem, s.result.u[-1], reference))
        eff.append(s.estimate.total / err[-1])
    assert all(0.3 < x < 3.0 for x in eff), eff
    assert all(b < a for a, b in itertools.pairwise(err)), err
    est = [s.estimate.total for s in steps]
    assert est[-1] < 0.5 * est[0]
    # the finest cells are at the corners of the clamped side, the far end is coarse
    last = steps[-1]
    mesh = last.problem.mesh
    corners = locate_cells(mesh, np.array([[1e-3, 1e-3], [1e-3, 1 - 1e-3]]))
    assert np.all(last.level[corners] == 3)
    far = locate_cells(mesh, np.array([[1.9, 0.9], [1.5, 0.6]]))
    assert np.all(last.level[far] <= 1)
    # a smaller error than the uniform mesh of h = 1/16 with fewer dofs
    uniform = _step(16)
    e_uni = _error(uniform, simulate(uniform, "newton", store="final").u[-1], reference)
    k = max(i for i, s in enumerate(steps) if s.n_dofs <= uniform.space.n_dofs)
    assert err[k] < 0.85 * e_uni, (steps[k].n_dofs, err[k], e_uni)


def test_the_loop_stops_at_max_cells_and_target_error() -> None:
    steps = adapt(_step(4), theta=0.5, max_cells=80)
    assert all(s.problem.mesh.n_cells <= 80 for s in steps)
    assert steps[-1].marked.size == 0
    first = steps[0].estimate.total
    steps = adapt(_step(4), target_error=0.7 * first)
    assert steps[-1].estimate.total <= 0.7 * first
    assert all(s.estimate.total > 0.7 * first for s in steps[:-1])


def test_the_loop_refuses_inconsistent_settings() -> None:
    with pytest.raises(ValueError, match="max_cells"):
        adapt(_step(4), max_cells=10)
    with pytest.raises(ValueError, match="target_error"):
        adapt(_step(4), target_error=0.0)
    with pytest.raises(ValueError, match="theta"):
        adapt(_step(4), theta=2.0, max_passes=2)


def test_the_adaptive_loop_resolves_a_hertz_contact_from_a_coarse_mesh() -> None:
    """The 2D Hertz line contact (a = 0.2) from 16 x 8 squares of side 0.5 = 2.5 a: the
    loop refines at the contact zone and reaches the closed form's half-width and peak
    within 1 % and its profile within 1 % (L2) with about a thousand cells."""
    from vemwear.paper.hertz import line_contact, measure

    a = 0.2
    steps = adapt(line_contact(a, 0, n=16), theta=0.5, max_passes=8)
    first, last = measure(steps[0].result, a), measure(steps[-1].result, a)
    assert first["a_err"] == -1.0  # one contact node: the coarse mesh sees no width
    assert abs(last["a_err"]) < 0.01 and abs(last["p0_err"]) < 0.01 and last["l2_err"] < 0.01
    mesh, level = steps[-1].problem.mesh, steps[-1].level
    assert mesh.n_cells < 1100
    finest = np.flatnonzero(level == level.max())
    centres = np.array([mesh.points[mesh.cell(c)].mean(axis=0) for c in finest])
    assert np.all(np.abs(centres[:, 0] - 4.0) < 1.5 * a) and np.all(centres[:, 1] < a)
