"""Step solvers and the time loop: agreement, KKT residuals, the inequality (3.21), wear."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from vemwear.contact import LinearCompliance, TableCompliance
from vemwear.contact.phi import phi_h
from vemwear.mesh import rectangle_squares, tag_rectangle
from vemwear.simulate import Problem, SolverOptions, TimeGrid, simulate
from vemwear.solvers import ConvergenceError
from vemwear.vem import Material


def paper_problem(divisions=(16, 8), steps=16, mu=0.2, kappa=2.0, time=None, **kw) -> Problem:
    """Section 5 data on a coarser mesh."""
    mesh = tag_rectangle(rectangle_squares((2.0, 1.0), divisions))
    return Problem(
        mesh,
        Material(4.0, 4.0),
        time or TimeGrid.uniform(1.0, steps),
        f1=(0.0, -0.06),
        p=kw.pop("p", LinearCompliance(0.4)),
        g=kw.pop("g", 0.1),
        mu=mu,
        kappa=kappa,
        v_star=kw.pop("v_star", (1.0, 0.0)),
        **kw,
    )


def rel(a, b):
    return float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))


@pytest.fixture(scope="module")
def small():
    pr = paper_problem()
    return pr, simulate(pr, "newton")


def test_problem_exercises_both_contact_regimes(small):
    """The data must activate the rigid layer somewhere and leave it inactive elsewhere."""
    _, r = small
    g = 0.1
    assert np.any(np.isclose(r.u_nu, g, rtol=0, atol=1e-12)), "rigid layer never reached"
    assert np.any(r.p_rigid > 1e-6) and np.any(r.p_soft > 1e-6)
    assert np.any((r.u_nu > 0) & (r.u_nu < g - 1e-6)), "no node in the soft layer only"
    assert r.wear[-1].max() > 0.01


def test_condensed_newton_equals_full_newton(small):
    pr, r = small
    rf = simulate(pr, "newton-full")
    assert rel(rf.u, r.u) < 1e-10
    assert rel(rf.wear, r.wear) < 1e-10
    assert rel(rf.p_rigid, r.p_rigid) < 1e-10
    assert rel(rf.p_soft, r.p_soft) < 1e-10


def test_released_solvers_are_built_again_with_the_same_numbers():
    """A problem keeps its step solver (one factorization for every run) until
    release_solvers drops it (the command line does before writing the outputs)."""
    pr = paper_problem(divisions=(8, 4), steps=4)
    opts = SolverOptions("newton")
    first = simulate(pr, opts)
    solver = pr.discrete.step_solver(opts)
    assert pr.discrete.step_solver(opts) is solver
    pr.discrete.release_solvers()
    assert pr.discrete.step_solver(opts) is not solver
    again = simulate(pr, opts)
    np.testing.assert_array_equal(again.u, first.u)
    np.testing.assert_array_equal(again.wear, first.wear)


@pytest.mark.parametrize("mu,kappa", [(0.2, 2.0), (0.6, 10.0)])
def test_uzawa_agrees_with_newton(mu, kappa):
    pr = paper_problem(divisions=(8, 4), steps=8, mu=mu, kappa=kappa)
    rn = simulate(pr, SolverOptions("newton", tol=1e-12))
    ru = simulate(pr, SolverOptions("uzawa", tol=1e-12))
    assert rel(ru.u, rn.u) < 1e-8
    assert rel(ru.wear, rn.wear) < 1e-8
    assert rel(ru.p_rigid, rn.p_rigid) < 1e-8
    assert ru.iterations.min() > rn.iterations.max()  # Uzawa is the slow reference


@pytest.mark.slow
def test_example_5_2_newton_and_uzawa_agree():
    """Example 5.2 at full size (h = 1/16, k = 1/64): u, w and lam to 1e-8, max norm
    (data sets 1 and 3; set 2 is set 3 with a smaller mu)."""
    for mu, kappa in [(0.2, 2.0), (0.6, 10.0)]:
        pr = paper_problem(divisions=(32, 16), steps=64, mu=mu, kappa=kappa)
        rn = simulate(pr, SolverOptions("newton"))
        ru = simulate(pr, SolverOptions("uzawa", tol=1e-11))
        for a, b in [(ru.u, rn.u), (ru.wear, rn.wear), (ru.p_rigid, rn.p_rigid)]:
            assert rel(a, b) < 1e-8, (mu, kappa)


@pytest.mark.parametrize("method", ["newton", "newton-full", "uzawa"])
def test_every_step_meets_the_kkt_tolerance(method):
    pr = paper_problem(divisions=(8, 4), steps=8)
    r = simulate(pr, SolverOptions(method, tol=1e-10))
    assert r.residuals.shape == (9, 3)
    assert np.all(r.residuals <= 1e-10)
    # and independently of the solver's own bookkeeping:
    d = pr.discrete
    for n in range(len(r.t)):
        u = r.u[n].ravel()[d.free]
        lam = r.p_rigid[n]
        y = d.system.N @ u
        assert np.all(y <= d.g * (1 + 1e-10))
        assert np.all(lam >= 0)
        assert np.all(np.abs(lam * (y - d.g)) <= 1e-10 * max(lam.max(), 1e-300) * d.g.max())


def test_solution_satisfies_the_variational_inequality(small):
    """(3.21): a_h(u, v - u) + phi(u, v) - phi(u, u) >= f_h(v - u) for v in U_h."""
    pr, r = small
    d = pr.discrete
    K, F = d.K_full, d.load(0.0)
    rng = np.random.default_rng(1)
    n = len(r.t) - 1
    u = r.u[n].ravel()
    w = r.wear[n]
    n_star = pr.v_star.n_star(r.t[n])
    fh = np.zeros(d.n_dof)
    fh[d.free] = F
    cb = d.contact
    for _ in range(20):
        v = u.copy()
        v[d.free] += 0.01 * rng.normal(size=len(d.free))
        y = cb.N @ v
        v_nodes = v.reshape(-1, 2)
        over = np.maximum(y - d.g, 0.0)  # project onto U_h: v_nu <= g
        v_nodes[cb.nodes] -= over[:, None] * cb.normals
        v = v_nodes.ravel()
        assert np.all(cb.N @ v <= d.g + 1e-14)
        lhs = (
            (K @ u) @ (v - u)
            + phi_h(cb, pr.p, d.mu, n_star, w, u, v)
            - phi_h(cb, pr.p, d.mu, n_star, w, u, u)
        )
        assert lhs - fh @ (v - u) >= -1e-12 * np.abs(fh).sum()


def test_wear_is_left_rectangle_rule_on_nonuniform_grid():
    """w^{n+1} = w^n + k_n kappa |v*| p(u_nu^n - w^n) with k_n alternating 1/128, 3/128."""
    tg = TimeGrid.pattern(1.0, [1 / 128, 3 / 128])
    assert len(tg.t) == 65 and np.isclose(tg.t[-1], 1.0)
    pr = paper_problem(divisions=(16, 8), time=tg, kappa=2.0, v_star=(2.0, 0.0))
    r = simulate(pr)
    p = 0.4 * np.maximum(r.u_nu - r.wear, 0.0)
    assert np.allclose(r.p_soft, p, rtol=0, atol=1e-14)
    k = np.diff(r.t)
    expected = np.cumsum(
        np.vstack([np.zeros(r.wear.shape[1]), k[:, None] * 2.0 * 2.0 * p[:-1]]), axis=0
    )
    assert np.allclose(r.wear, expected, rtol=1e-13, atol=1e-15)


def test_wear_nonnegative_and_nondecreasing(small):
    _, r = small
    assert np.all(r.wear >= 0)
    assert np.all(np.diff(r.wear, axis=0) >= -1e-15)
    assert np.all(r.wear[0] == 0)


def test_paper_findings_example_5_2():
    """Fig 3-5: more wear with larger kappa, less wear with larger mu (Example 5.2)."""
    wmax = {}
    for mu, kappa in [(0.2, 2.0), (0.2, 10.0), (0.6, 10.0)]:
        r = simulate(paper_problem(divisions=(32, 16), steps=64, mu=mu, kappa=kappa))
        wmax[mu, kappa] = r.wear[-1]
    assert (
        np.all(wmax[0.2, 10.0] >= wmax[0.2, 2.0])
        and wmax[0.2, 10.0].max() > 1.5 * wmax[0.2, 2.0].max()
    )
    assert wmax[0.6, 10.0].sum() < wmax[0.2, 10.0].sum()


def test_time_dependent_velocity_and_table_law():
    """v*(t) reversing direction and a piecewise-linear law run and keep the KKT tolerance."""
    vs = {"t": [0.0, 0.5, 1.0], "values": [[1.0, 0.0], [1.0, 0.0], [-2.0, 0.0]]}
    law = TableCompliance((0.0, 0.05, 0.5), (0.0, 0.01, 0.5))
    pr = paper_problem(
        divisions=(8, 4),
        steps=10,
        p=law,
        v_star=vs,
        g={"along": "x", "at": [0.0, 2.0], "values": [0.12, 0.08]},
    )
    r = simulate(pr)
    assert np.all(r.residuals <= 1e-10)
    assert np.all(np.diff(r.wear, axis=0) >= -1e-15)


def test_nonconvergence_raises_with_level():
    pr = paper_problem(divisions=(8, 4), steps=4)
    with pytest.raises(ConvergenceError, match=r"time level \d+ \(t = ") as err:
        simulate(pr, SolverOptions("uzawa", max_iter=3))
    assert "contracts" not in str(err.value)  # the paper's layer: no note
    # a layer 1e6 times as stiff: Uzawa's fixed point contracts too slowly, and says so
    stiff = paper_problem(divisions=(8, 4), steps=4, p=LinearCompliance(4e5))
    with pytest.raises(ConvergenceError, match=r"contracts by 1 - 1/[0-9.e+]+ per iter"):
        simulate(stiff, SolverOptions("uzawa", max_iter=100))


def test_time_grids():
    assert np.allclose(TimeGrid.uniform(1.0, 4).t, [0, 0.25, 0.5, 0.75, 1.0])
    assert np.allclose(TimeGrid.from_steps([0.1, 0.2]).t, [0, 0.1, 0.3])
    tg = TimeGrid.pattern(1.0, [0.3])
    assert np.allclose(tg.t, [0, 0.3, 0.6, 0.9, 1.0])
    for bad in ([0.0, 0.0, 1.0], [0.1, 0.5], [0.0, 0.5, 0.4]):
        with pytest.raises(ValueError, match="time grid"):
            TimeGrid(np.array(bad))


def test_condensed_certificate_matches_its_definition(small):
    """The iteration's cheap certificate gives the residuals of ``condensed_residuals``."""
    from vemwear.solvers.newton import _condensed_errors
    from vemwear.solvers.system import RESIDUAL_NAMES, condensed_residuals

    pr, _ = small
    s = pr.discrete.system
    rng = np.random.default_rng(5)
    for _ in range(20):
        y = s.g + rng.normal(scale=0.05, size=s.m)
        p_rigid = rng.normal(size=s.m)
        R = rng.normal(scale=1e-3, size=s.m)
        inv_g = 1.0 / np.abs(s.g).max()
        fast = _condensed_errors(y, p_rigid, R, s.g, inv_g, np.empty(2 * s.m))
        ref = condensed_residuals(s, y, p_rigid, R)
        assert np.allclose(fast, [ref[k] for k in RESIDUAL_NAMES], rtol=1e-14, atol=0)
        assert ref["feasibility"] <= ref["complementarity"]


def test_block_equilibrium_check_estimates_and_catches_a_wrong_column():
    """The randomized equilibrium check of a recovered block (Freivalds) against the exact
    backward errors level by level: on a correct block both are at rounding level and
    the estimate is within the documented factors; one column off by 1e-6 of u (a wrong
    back-substitution) is caught, whichever column it is."""
    from vemwear.solvers.system import kkt_residuals, kkt_residuals_block

    pr = paper_problem(steps=12)
    d = pr.discrete
    s = d.system
    solver = d.step_solver(SolverOptions("newton"))
    w = np.zeros(s.m)
    steps, sols = [], []
    guess = None
    for n in range(len(pr.time.t)):
        st = d.step_data(n, w)
        sol = solver.solve(st, guess, recover=False)
        steps.append(st)
        sols.append(sol)
        w = w + 1.0 / 12 * d.alpha(st.t) * sol.p_soft
        guess = sol
    X = solver.recover_many(steps, [x.p_rigid for x in sols], [x.p_soft for x in sols])
    rig = [x.p_rigid for x in sols]
    K_norm = float(abs(s.K).sum(axis=1).max())

    def backward_error(j: int, x: np.ndarray) -> float:
        force, _ = s.contact_force(x, rig[j], steps[j].fric, steps[j].w)
        r = s.K @ x - steps[j].F + force
        slopes = s.p.derivative(s.N @ x - steps[j].w)  # |J|: |K| and the soft layer's
        J = s.operator_norms(slopes[:, None], steps[j].fric[:, None])[0]
        assert K_norm <= J < 1.01 * K_norm  # the paper's soft layer: a small part of it
        scale = max(np.abs(steps[j].F).max(), np.abs(force).max(), J * np.abs(x).max())
        return float(np.abs(r).max() / scale)

    block = kkt_residuals_block(s, steps, X, rig)
    est = block[0]["equilibrium"]
    assert all(r["equilibrium"] == est for r in block)  # one estimate for the block
    exact = max(backward_error(j, X[:, j]) for j in range(len(steps)))
    assert exact < 1e-14 and est < 1e-13
    # with a tolerance below the estimate: each level's own residual, exactly
    each = kkt_residuals_block(s, steps, X, rig, tol=est / 2)
    for j in range(len(steps)):
        assert each[j]["equilibrium"] == pytest.approx(backward_error(j, X[:, j]), rel=1e-9)
    for j in range(len(steps)):  # feasibility and complementarity are exact
        full = kkt_residuals(s, steps[j], X[:, j], rig[j])
        for key in ("feasibility", "complementarity"):
            assert block[j][key] == pytest.approx(full[key], abs=1e-15)
    for bad in (0, 5, len(steps) - 1):  # a wrong column is caught
        Y = X.copy()
        Y[:, bad] += 1e-6 * np.abs(X[:, bad]).max() * np.cos(np.arange(len(Y)))
        true = backward_error(bad, Y[:, bad])
        got = kkt_residuals_block(s, steps, Y, rig)[0]["equilibrium"]
        assert true > 1e-8 and true / 100 < got < true * len(steps), (bad, true, got)
        each = kkt_residuals_block(s, steps, Y, rig, tol=1e-10)  # the wrong one named
        assert [r["equilibrium"] > 1e-10 for r in each] == [j == bad for j in range(len(Y.T))]


def test_a_slender_bar_is_certified_over_the_scale_of_its_normal_displacements():
    """An 8 x 1 bar clamped at one end and pressed onto the rigid layer by its weight:
    the load alone would move its free end by 42 (|d|, 424 times g), and N u = g on the
    layer is the small difference of d and the contact forces' displacement. The
    recovered u is as accurate as a direct solve gives it (it agrees with the full-space
    Newton), yet measured over g alone its contact constraint is violated by about
    1e-10 of g, the tolerance: the certificate measures it over max(g, |d|), and the
    run is certified and agrees with the full-space Newton (k = 1 and 2, in 3D, and a
    strip four times as thin)."""
    from vemwear.mesh.generate3d import box_hexahedra, tag_box
    from vemwear.solvers.system import kkt_residuals, kkt_residuals_block

    mesh = tag_rectangle(rectangle_squares((8.0, 1.0), (16, 2)))
    pr = Problem(
        mesh, Material(4.0, 4.0), TimeGrid.uniform(1.0, 4), f1=(0.0, -0.06),
        p=LinearCompliance(0.4), g=0.1, mu=0.2, kappa=2.0, v_star=(1.0, 0.0),
    )  # fmt: skip
    d, s = pr.discrete, pr.discrete.system
    solver = d.step_solver(SolverOptions("newton"))
    step = d.step_data(0, np.zeros(s.m))
    load = np.abs(solver.normal_displacement(step.F)).max()
    assert load > 400 * s.g.max()
    sol = solver.solve(step, None, recover=False)
    X = solver.recover_many([step], [sol.p_rigid], [sol.p_soft])
    over_g = kkt_residuals(s, step, X[:, 0], sol.p_rigid)
    assert over_g["complementarity"] > 1e-10  # what a certificate over g alone sees
    scale = solver.displacement_scales([step], [sol.u_nu], [sol.p_rigid], [sol.p_soft])[0]
    assert scale == pytest.approx(load, rel=1e-9)
    certified = kkt_residuals_block(s, [step], X, [sol.p_rigid], np.array([scale]))[0]
    assert max(certified.values()) < 1e-11
    assert solver.solve(step, None, recover=True).residuals == certified

    # nodal contact dofs, the trace operator of k = 2, and the bar in 3D
    box = tag_box(
        box_hexahedra((8.0, 1.0, 1.0), (16, 2, 2)),
        {"clamped": "xmin", "contact": "zmin", "traction": ["xmax", "ymin", "ymax", "zmax"]},
    )
    bar3d = dataclasses.replace(pr, mesh=box, f1=(0.0, 0.0, -0.06), v_star=(1.0, 0.0, 0.0))
    # a strip 32 times as long as it is thick: |d| = 6.7e3 g, whose rounding is also in
    # the soft layer's forces (the equilibrium residual is over |J| max(|u|, |d|)); the
    # two solvers' u differ by about |d| / |u| times their backward errors
    strip = dataclasses.replace(pr, mesh=tag_rectangle(rectangle_squares((8.0, 0.25), (64, 2))))
    sd = strip.discrete
    strip_step = sd.step_data(0, np.zeros(sd.system.m))
    strip_d = sd.step_solver(SolverOptions("newton")).normal_displacement(strip_step.F)
    assert np.abs(strip_d).max() > 6e3 * s.g.max()
    for case, u_tol in ((pr, 1e-9), (dataclasses.replace(pr, order=2), 1e-9), (bar3d, 1e-9),
                        (strip, 1e-6)):  # fmt: skip
        r = simulate(case, "newton")  # u recovered and certified at every level
        full = simulate(case, "newton-full")
        assert r.residuals.max() < 1e-10
        assert rel(r.u, full.u) < u_tol and rel(r.wear, full.wear) < 1e-9


@pytest.mark.parametrize("c, mu", [(1e4, 0.0), (1e6, 0.2)])
def test_a_stiff_coating_is_certified_by_the_backward_error_of_its_operator(c, mu):
    """A soft layer 2.5e4 to 2.5e6 times as stiff as the paper's (p = c r) with a wear
    coefficient that keeps kappa c at the paper's 0.8: Newton converges in one or two
    iterations, but its forces carry the rounding of y times the slope. The recovered u
    is certified by the backward error of the operator u -> K u + force(u), whose norm
    |K| + |J_soft| (J_soft the soft layer's tangent) is then far above |K|; over |K|
    alone the same u fails the tolerance. The run is certified and agrees with the
    full-space Newton, for k = 1, k = 2 and in 3D."""
    from vemwear.mesh.generate3d import box_hexahedra, tag_box
    from vemwear.solvers.system import kkt_residuals_block

    pr = paper_problem(steps=8, p=LinearCompliance(c), mu=mu, kappa=0.8 / c)
    d, s = pr.discrete, pr.discrete.system
    solver = d.step_solver(SolverOptions("newton"))
    step = d.step_data(0, np.zeros(s.m))
    sol = solver.solve(step, None, recover=False)
    X = solver.recover_many([step], [sol.p_rigid], [sol.p_soft])
    x = X[:, 0]
    # the operator's norm against its dense form: max row sum of |K| + |J_soft|
    slopes = s.p.derivative(s.N @ x - step.w)
    dp = slopes * s.weights
    N, Tau = s.N.toarray(), s.Tau.toarray()
    J_soft = np.abs(N.T * dp) @ np.abs(N) + np.abs(Tau.T * (dp * step.fric)) @ np.abs(N)
    dense = (np.abs(s.K.toarray()) + J_soft).sum(axis=1).max()
    norm = s.operator_norms(slopes[:, None], step.fric[:, None])[0]
    assert norm == pytest.approx(dense, rel=1e-12) and norm > 20 * s.K_norm
    # the backward error over |K| |u| alone (as if the soft layer were not part of the
    # operator) fails; over the operator's norm it is at rounding level
    force, _ = s.contact_force(x, sol.p_rigid, step.fric, step.w)
    res = np.abs(s.K @ x - step.F + force).max()
    over_K = res / max(np.abs(step.F).max(), np.abs(force).max(), s.K_norm * np.abs(x).max())
    assert over_K > 1e-10
    scales = solver.displacement_scales([step], [sol.u_nu], [sol.p_rigid], [sol.p_soft])
    certified = kkt_residuals_block(s, [step], X, [sol.p_rigid], scales)[0]
    assert max(certified.values()) < 1e-11
    assert solver.solve(step, None, recover=True).residuals == certified

    sides = {"clamped": "xmin", "contact": "zmin", "traction": ["xmax", "ymin", "ymax", "zmax"]}
    box = tag_box(box_hexahedra((2.0, 1.0, 1.0), (8, 4, 2)), sides)
    in3d = dataclasses.replace(pr, mesh=box, f1=(0.0, 0.0, -0.06), v_star=(1.0, 0.0, 0.0))
    for case in (pr, dataclasses.replace(pr, order=2), in3d):
        run = simulate(case, "newton")  # u recovered and certified at every level
        full = simulate(case, "newton-full")
        assert run.residuals.max() < 1e-10
        assert rel(run.u, full.u) < 1e-9 and rel(run.wear, full.wear) < 1e-9


def test_newton_stops_at_the_rounding_floor_of_its_residual():
    """A strip 64 times as long as it is thick, clamped at one end: the load alone would
    move it 1.1e5 times g, so the condensed residual's rounding (about 1e-16 of that)
    stays above 0.1 tol, the iteration's own target. Newton stops once two steps in a
    row were on one piece and the residual is within tol (it took the 100 iterations
    of max_iter at every level before); the run is certified and agrees with the
    full-space Newton in the wear to 1e-8 (the displacements to 2e-4: u is the small
    difference of terms 7e4 times as large, and the solvers' forward errors differ)."""
    pr = paper_problem(divisions=(128, 2), steps=4)
    pr = dataclasses.replace(pr, mesh=tag_rectangle(rectangle_squares((16.0, 0.25), (128, 2))))
    solver = pr.discrete.step_solver(SolverOptions("newton"))
    step = pr.discrete.step_data(0, np.zeros(pr.discrete.system.m))
    assert np.abs(solver.normal_displacement(step.F)).max() > 1e5 * 0.1
    r = simulate(pr, "newton")
    full = simulate(pr, "newton-full")
    assert r.iterations.max() <= 4 and r.residuals.max() < 1e-10
    assert rel(r.wear, full.wear) < 1e-7 and rel(r.u, full.u) < 1e-3
    # a tolerance below rounding: Newton stops after four steps on one piece and says so
    # (not after max_iter)
    with pytest.raises(ConvergenceError, match=r"level 0 .* after [1-6] iterations"):
        simulate(paper_problem(steps=2), SolverOptions("newton", tol=1e-18))


def test_newton_restarts_cold_when_its_warm_start_cycles():
    """p = 1e5 r with the paper's kappa = 2 on 8 steps: the explicit wear overshoots
    (k kappa p' = 2.5e4), so level 7's solution lies far from level 6's, and Newton
    started there cycles between pieces (period 6). It starts again from the cold start
    y = min(d, g) and converges; the run is certified, and every level's solution is
    the one a cold start gives."""
    pr = paper_problem(divisions=(32, 16), steps=8, p=LinearCompliance(1e5))
    r = simulate(pr, "newton")
    assert r.residuals.max() < 1e-10 and r.iterations.max() <= 20
    d = pr.discrete
    solver = d.step_solver(SolverOptions("newton"))
    guess = None
    for n in range(len(r.t)):
        step = d.step_data(n, r.wear[n])
        cold = solver.solve(step, None, recover=True)
        assert np.abs(d.space.vertex_values(d.full_dofs(cold.u, step.t)) - r.u[n]).max() < 1e-12
        if n == 7:  # the warm start from level 6 cycles: a piece comes back
            start = (guess.u_nu.copy(), guess.p_rigid.copy())
            assert solver._newton(step, solver.normal_displacement(step.F), start, 0)[5]
        guess = solver.solve(step, guess, recover=False)


def test_a_soft_layer_much_stiffer_than_the_body_is_named_when_newton_fails():
    """p = 1e8 r (2e7 times as stiff as the body at the contact nodes) with the paper's
    kappa: Newton's residual does not get below tol (the slope times the rounding of y
    is above it); the error says so, with the stiffness ratio, instead of a bare
    residual. With the paper's law the ratio is small and the note is empty."""
    pr = paper_problem(steps=4, p=LinearCompliance(1e8))
    with pytest.raises(ConvergenceError, match=r"did not converge at time level \d+ .*the "
                       r"soft layer is [0-9.e+]+ times as stiff as the body"):  # fmt: skip
        simulate(pr, "newton")
    small = paper_problem(steps=2)
    d = small.discrete
    solver = d.step_solver(SolverOptions("newton"))
    step = d.step_data(0, np.zeros(d.system.m))
    assert solver.stiffness_note(solver.solve(step, None, recover=False).u_nu, step) == ""


def test_a_run_keeps_the_blocks_of_k_it_uses_and_not_the_whole_matrix(monkeypatch):
    """The stiffness on all dofs is not kept by a discretization (in 3D it is as large
    as the free block); asked for, it is assembled again, and the blocks the run uses
    are its blocks. The absolute row sums of the certificates are those of ``|K|``,
    bit for bit, taken in chunks of rows without a copy of K; the condensed Newton's
    dense blocks are views of one array, ``C_NN W`` and ``C_NT W Fric`` formed from
    them when asked for."""
    import scipy.sparse as sp

    import vemwear.solvers.stiffness as stiffness_module

    pr = paper_problem(divisions=(16, 8), steps=2)
    d = pr.discrete
    assert "K_full" not in vars(d)
    K_full = d.K_full
    free, fixed = d.free, d.constraints.dofs
    assert abs(K_full[free][:, free] - d.system.K).max() == 0.0
    assert abs(K_full[free][:, fixed] - d._K_fc).max() == 0.0
    assert d.K_full is K_full  # kept once asked for
    monkeypatch.setattr(stiffness_module, "ROW_CHUNK", 37)  # chunk ends inside rows' runs
    K = sp.csr_matrix(d.system.K)
    K = sp.vstack([K[:6], sp.csr_matrix((1, K.shape[1])), K[7:]], format="csr")  # empty row
    K.data[K.indptr[3] : K.indptr[4]] = 0.0  # stored zeros
    s = dataclasses.replace(d.system, K=K)
    assert np.array_equal(s.K_row_sums, np.asarray(abs(K).sum(axis=1)).ravel())
    newton = d.step_solver(SolverOptions("newton"))
    for block in (newton.C_NN, newton.C_NT):
        assert np.shares_memory(block, newton.H)
    w = d.system.weights
    active = np.arange(d.system.m) % 3 == 0
    assert np.array_equal(newton.norm_columns(active), (newton.C_NN * w[None, :])[:, active])
    fric = np.linspace(0.1, 0.3, d.system.m)
    assert np.array_equal(
        newton.friction_matrix(fric), newton.C_NN * w[None, :] + newton.C_NT * w * fric
    )
