"""Runs of levels on one piece of the step problem (vemwear.solvers.pieces).

A predicted level is the one Newton's first step from the level before gives on the
piece it sees, certified by Newton's exit test; the runs are compared with runs whose
law is the same function given as a callable, which Newton solves at every level.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from vemwear.contact import CallableCompliance, LinearCompliance, TableCompliance
from vemwear.mesh import rectangle_squares, tag_rectangle
from vemwear.simulate import Problem, TimeGrid, simulate
from vemwear.solvers.newton import CondensedNewton
from vemwear.solvers.pieces import MIN_WIDTH, block_width
from vemwear.vem import Material

FIELDS = ("wear", "u_nu", "p_rigid", "p_soft", "u", "forces")


def problem(law, *, T: float = 1.0, steps: int = 64, **kw) -> Problem:
    mesh = tag_rectangle(rectangle_squares((2.0, 1.0), (16, 8)))
    return Problem(
        mesh,
        Material(4.0, 4.0),
        TimeGrid.uniform(T, steps),
        f1=(0.0, -0.06),
        p=law,
        g=0.1,
        mu=0.2,
        kappa=2.0,
        v_star=(1.0, 0.0),
        **kw,
    )


def as_callable(law) -> CallableCompliance:
    """The same law, unknown to be piecewise linear: Newton at every level."""
    return CallableCompliance(law, law.derivative)


def newton_levels(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """The levels that Newton solves from now on (appended to the list returned)."""
    levels: list[int] = []
    solve = CondensedNewton.solve

    def counted(self, step, guess=None, recover=True):
        levels.append(step.level)
        return solve(self, step, guess, recover)

    monkeypatch.setattr(CondensedNewton, "solve", counted)
    return levels


TABLE = TableCompliance(r=(0.0, 0.02, 0.05, 0.2), p=(0.0, 0.004, 0.02, 0.1))


@pytest.mark.parametrize(
    ("law", "kw"),
    [
        (LinearCompliance(0.4), {}),  # the paper's Example 5.2
        (LinearCompliance(0.4), {"T": 10.0, "steps": 200}),  # wear reaches the layer
        (TABLE, {}),  # three segments
        (LinearCompliance(0.4), {"gap": 0.01}),  # an initial gap: a shifted wear
    ],
    ids=["paper", "rigid-layer", "table", "gap"],
)
def test_predicted_runs_are_newtons_levels(monkeypatch, law, kw) -> None:
    pr = problem(law, **kw)
    ref = simulate(dataclasses.replace(pr, p=as_callable(law)))
    solved = newton_levels(monkeypatch)
    got = simulate(pr)
    L = len(pr.time.t)
    # Newton solves the first level and those where the piece changes, no others
    assert 1 <= len(solved) <= L // 8, solved
    assert solved[0] == 0
    np.testing.assert_array_equal(got.iterations, ref.iterations)
    for k in FIELDS:
        a, b = getattr(got, k), getattr(ref, k)
        scale = max(float(np.abs(b).max()), 1e-300)
        assert np.abs(a - b).max() <= 1e-12 * scale, k
    assert got.residuals.max() <= 1e-10
    if kw.get("T"):
        assert got.p_rigid.max() > 0.0  # the rigid layer carries load at the end


def test_a_change_of_piece_is_left_to_newton(monkeypatch) -> None:
    """The levels where Newton needs two iterations (its first step lands on another
    piece) are exactly those solved by Newton after the first."""
    pr = problem(LinearCompliance(0.4), T=10.0, steps=200)
    solved = newton_levels(monkeypatch)
    got = simulate(pr)
    changes = np.flatnonzero(got.iterations >= 2).tolist()
    assert changes and solved[1:] == changes


def first_levels(pr: Problem):
    """A new condensed Newton (its predictor's first run tries 8 levels), the solution
    of level 0, and ``advance(w)``: the wear update (3.22) as the loop writes it, from
    the wear ``w`` of a level on."""
    d = pr.discrete
    newton = CondensedNewton(d.system)
    sol0 = newton.solve(d.step_data(0, np.zeros(d.system.m)), recover=False)
    rate = (pr.time.t[1] - pr.time.t[0]) * d.alpha(0.0)

    def advance(w):
        ws = [w]

        def next_w(p_soft):
            ws.append(ws[-1] + rate * p_soft)
            return ws[-1]

        return next_w

    return d, newton, sol0, rate * sol0.p_soft, advance


def test_a_guess_on_another_piece_is_not_accepted() -> None:
    """A run is accepted only where Newton's exit test holds: from a guess with the
    rigid layer active everywhere (a piece that holds y = g at every node) nothing is
    accepted, from the true previous level the whole run is."""
    pr = problem(LinearCompliance(0.4))
    d, newton, sol0, w1, advance = first_levels(pr)
    first = d.step_data(1, w1)
    m = d.system.m
    wrong = dataclasses.replace(sol0, p_rigid=np.ones(m), u_nu=np.full(m, 0.1))
    assert newton.predict(wrong, first, advance(w1), 8, pr.time.t) == []
    run = newton.predict(sol0, first, advance(w1), 8, pr.time.t)
    assert len(run) == 8
    for _, sol in run:
        assert max(sol.residuals.values()) <= 1e-11
        assert sol.iterations == 1 and sol.u is None


def test_a_level_has_the_same_bits_in_every_run() -> None:
    """Level n's numbers do not depend on the run it was computed in (the residual
    products are taken with level n in column n % width): runs started at level 1 and
    at level 5 give bitwise the same levels 5 to 8."""
    pr = problem(LinearCompliance(0.4))
    d, newton, sol0, w1, advance = first_levels(pr)
    assert block_width(d.system.m) == 64
    a = newton.predict(sol0, d.step_data(1, w1), advance(w1), 8, pr.time.t)
    assert len(a) == 8
    step4, guess = a[3]
    w5 = advance(step4.w)(guess.p_soft)
    _, other, *_ = first_levels(pr)
    b = other.predict(guess, d.step_data(5, w5), advance(w5), 8, pr.time.t)
    assert len(b) == 8
    for (sa, la), (sb, lb) in zip(a[4:], b, strict=False):
        assert sa.level == sb.level and np.array_equal(sa.w, sb.w)
        for k in ("u_nu", "p_rigid", "p_soft"):
            assert np.array_equal(getattr(la, k), getattr(lb, k)), k
        assert la.residuals == lb.residuals
    # the bits above hold whatever the BLAS (this OpenBLAS gives a column the same bits
    # in any position): the residual block holds level n in column n % width
    m = d.system.m
    X = other.predictor._X  # the work block of run b (levels 5 to 12)
    for step, sol in b:
        x_n = d.system.weights * (sol.p_soft + sol.p_rigid)  # no rigid-layer pressure
        assert np.array_equal(X[:m, step.level % 64], x_n)


def test_segments_of_the_laws() -> None:
    r = np.linspace(-0.1, 0.3, 4001)
    for law in (LinearCompliance(0.4), TABLE):
        s, q = law.segments(r)
        np.testing.assert_allclose(s * r + q, law(r), rtol=1e-14, atol=1e-16)
        np.testing.assert_array_equal(s, law.derivative(r))
    # one segment, one (s, q): the same numbers for every r of it
    s, q = TABLE.segments(np.array([0.021, 0.03, 0.049]))
    assert len(set(s.tolist())) == 1 and len(set(q.tolist())) == 1
    assert not as_callable(TABLE).piecewise_linear and TABLE.piecewise_linear


def test_reciprocating_sliding_runs_while_the_friction_stays(monkeypatch) -> None:
    """v*(t) = (cos 2 pi t, 0): the friction turns at t = 1/4 and 3/4, the wear rate
    changes at every level; runs go on while the friction stays the same."""

    def v_star(t: float) -> tuple[float, float]:
        return (float(np.cos(2 * np.pi * t)), 0.0)

    pr = dataclasses.replace(problem(LinearCompliance(0.4), steps=128), v_star=v_star)
    ref = simulate(dataclasses.replace(pr, p=as_callable(pr.p)))
    solved = newton_levels(monkeypatch)
    got = simulate(pr)
    assert 2 <= len(solved) <= 16, solved
    np.testing.assert_array_equal(got.iterations, ref.iterations)
    for k in FIELDS:
        a, b = getattr(got, k), getattr(ref, k)
        assert np.abs(a - b).max() <= 1e-12 * np.abs(b).max(), k


def test_many_contact_nodes_are_left_to_newton(monkeypatch) -> None:
    """Above 362 contact nodes a residual block would hold fewer than MIN_WIDTH levels:
    Newton solves every level, whose products cost as much as a run's."""
    assert block_width(362) >= MIN_WIDTH > block_width(363)
    mesh = tag_rectangle(rectangle_squares((2.0, 1.0), (400, 50)))
    pr = dataclasses.replace(problem(LinearCompliance(0.4), steps=8), mesh=mesh)
    assert not CondensedNewton(pr.discrete.system).predicts
    solved = newton_levels(monkeypatch)
    simulate(pr)
    assert solved == list(range(9))


def held_by_contact(law, *, T: float = 1.0, steps: int = 64) -> Problem:
    """A pad on rollers pressed by a traction on its top: contact alone holds it in y
    (load control, docs/method.md section 1c)."""
    from vemwear.simulate import Prescribed

    mesh = tag_rectangle(
        rectangle_squares((2.0, 1.0), (16, 8)),
        {"rollers": ["left", "right"], "traction": "top", "contact": "bottom"},
    )
    return Problem(
        mesh,
        Material(4.0, 4.0),
        TimeGrid.uniform(T, steps),
        f2=(0.0, -0.06),
        p=law,
        g=0.1,
        mu=0.2,
        kappa=2.0,
        v_star=(1.0, 0.0),
        clamped=(),
        displacement=(Prescribed("rollers", ux=0.0),),
    )


@pytest.mark.parametrize(
    ("law", "kw"),
    [(LinearCompliance(0.4), {}), (LinearCompliance(0.4), {"T": 10.0, "steps": 200}), (TABLE, {})],
    ids=["paper", "rigid-layer", "table"],
)
def test_load_controlled_runs_are_newtons_levels(monkeypatch, law, kw) -> None:
    """Under load control the runs solve the bordered piece (with the rigid motion's
    amplitude and the force balance): the same levels as Newton's, few Newton solves,
    and the contact forces balance the load at every level."""
    pr = held_by_contact(law, **kw)
    ref = simulate(dataclasses.replace(pr, p=as_callable(law)))
    solved = newton_levels(monkeypatch)
    got = simulate(pr)
    L = len(pr.time.t)
    assert 1 <= len(solved) <= L // 8, solved
    np.testing.assert_array_equal(got.iterations, ref.iterations)
    for k in FIELDS:
        a, b = getattr(got, k), getattr(ref, k)
        scale = max(float(np.abs(b).max()), 1e-300)
        assert np.abs(a - b).max() <= 1e-11 * scale, k
    assert got.residuals.max() <= 1e-10
    load = 0.06 * 2.0  # the traction on the top side, of length 2
    resultant = got.forces[:, :, 1].sum(axis=1)  # in y, of the contact and the rollers
    assert np.abs(resultant - load).max() <= 1e-12 * load, resultant
    if kw.get("T"):
        assert got.p_rigid.max() > 0.0
