"""Closed-form solutions of the contact-and-wear scheme (docs/method.md, section 8).

A block ``(0, W) x (0, H)`` on rollers at both sides (``u_x = 0``), frictionless contact
at the bottom with a linear layer ``p(r) = c r_+`` of thickness g over an initial gap,
no body force, and the top pushed down by ``u_y = -delta``. The field is uniaxial,
``u = (0, u_y(y))`` with ``u_y`` linear, which the virtual elements represent exactly on
any mesh; with ``M = lam + 2 eta`` the soft-layer pressure is ``k_s (delta - gap - w)``,
``k_s = c M / (M + c H)``, while the body stays above the rigid layer, and the
left-rectangle wear (3.22) is exactly

    delta - gap - w^n = (delta - gap) (1 - k kappa |v*| k_s)^n.

Once the rigid layer is reached (``u_nu - gap = g``), the soft pressure is ``c (g - w)``
and ``g - w^n`` decays by ``(1 - k kappa |v*| c)`` per step. The continuous wear of the
constant push is ``(delta - gap) (1 - exp(-kappa |v*| k_s t))``, reached with order 1 in
k. A second case of our own:
the top pushed at a constant rate, ``u_y = -delta t``, so that contact starts at
``t_0 = gap / delta``; the continuous wear then is
``w(t) = delta (t - t_0) - delta / (a k_s) (1 - exp(-a k_s (t - t_0)))``,
``a = kappa |v*|``, and the scheme converges to it with order 1 in k.
"""

from __future__ import annotations

import numpy as np
import pytest

from vemwear.contact import LinearCompliance
from vemwear.mesh import rectangle_squares, rectangle_voronoi, select_parts
from vemwear.simulate import Prescribed, Problem, SolverOptions, TimeGrid, simulate
from vemwear.vem import Material

LAM, ETA, C, W, H, G, KAPPA = 4.0, 4.0, 0.4, 2.0, 1.0, 0.1, 2.0
M = LAM + 2 * ETA
K_S = C * M / (M + C * H)


def block(family: str, uy, gap: float, steps: int, T: float = 1.0, mu: float = 0.0) -> Problem:
    mesh = (
        rectangle_squares((W, H), (8, 4))
        if family == "squares"
        else rectangle_voronoi((W, H), 40, seed=3)
    )
    mesh = select_parts(mesh, {"rollers": ["left", "right"], "top": "top", "contact": "bottom"})
    return Problem(
        mesh,
        Material(LAM, ETA),
        TimeGrid.uniform(T, steps),
        p=LinearCompliance(C),
        g=G,
        mu=mu,
        kappa=KAPPA,
        v_star=(1.0, 0.0),
        gap=gap,
        clamped=(),
        displacement=(Prescribed("rollers", ux=0.0), Prescribed("top", uy=uy)),
    )


def discrete_wear(delta_t, gap: float, k: float, n: int) -> np.ndarray:
    """The left-rectangle recursion of the uniaxial block, with the rigid layer."""
    w = np.zeros(n + 1)
    for i in range(n):
        d = delta_t(i)
        soft = min(K_S * max(d - gap - w[i], 0.0), C * (G - w[i]))  # rigid layer caps it
        w[i + 1] = w[i] + k * KAPPA * soft
    return w


@pytest.mark.parametrize("family", ["squares", "voronoi"])
@pytest.mark.parametrize("gap", [0.0, 0.01])
def test_pushed_block_wears_as_the_closed_form(family: str, gap: float) -> None:
    delta, n = 0.05, 20
    r = simulate(block(family, -delta, gap, n), SolverOptions("newton"))
    k = 1.0 / n
    e = (delta - gap) * (1 - k * KAPPA * K_S) ** np.arange(n + 1)
    assert np.abs(r.wear - (delta - gap - e)[:, None]).max() < 1e-14
    assert np.abs(r.p_soft - K_S * e[:, None]).max() < 1e-14
    assert np.abs(r.p_rigid).max() == 0.0
    assert np.abs(r.penetration - (r.u_nu - gap - r.wear)).max() == 0.0
    # force resultants: the layer pushes up by k_s e W, the top holds it, the rollers'
    # two sides cancel; no body force, so they balance
    assert r.force_parts == (("contact", "contact"), ("rollers", "reaction"), ("top", "reaction"))
    F = r.forces
    assert F is not None
    assert np.abs(F[:, 0, 1] - K_S * e * W).max() < 1e-13
    assert np.abs(F[:, 2, 1] + K_S * e * W).max() < 1e-13
    assert np.abs(F.sum(axis=1)).max() < 1e-13
    # the field is uniaxial: u_x = 0 everywhere, u_y linear in y
    u = r.displacement(-1)
    P = r.problem.mesh.points
    assert np.abs(u[:, 0]).max() < 1e-14
    d = r.u_nu[-1, 0]  # u_nu = -u_y(0)
    assert np.abs(u[:, 1] - (-d + (d - delta) * P[:, 1] / H)).max() < 1e-14


@pytest.mark.parametrize("family", ["squares", "voronoi"])
def test_pushed_into_the_rigid_layer(family: str) -> None:
    """delta large: the body reaches the rigid layer at once; the soft pressure is
    c (g - w), so g - w^n = g (1 - k kappa |v*| c)^n, and the rigid layer carries the
    rest."""
    delta, gap, n = 0.5, 0.02, 16
    r = simulate(block(family, -delta, gap, n), SolverOptions("newton"))
    w = discrete_wear(lambda i: delta, gap, 1.0 / n, n)
    assert np.abs(w - G * (1 - (1 - KAPPA * C / n) ** np.arange(n + 1))).max() < 1e-15
    assert np.abs(r.wear - w[:, None]).max() < 1e-14
    assert np.allclose(r.u_nu - gap, G, rtol=0, atol=1e-14)
    total = M * (delta - gap - G) / H  # the whole normal stress at the bottom
    assert np.abs(r.p_soft + r.p_rigid - total).max() < 1e-13
    assert np.abs(r.p_soft - C * (G - w)[:, None]).max() < 1e-14


@pytest.mark.parametrize("method", ["newton-full", "uzawa"])
def test_solvers_agree_on_the_pushed_block(method: str) -> None:
    pr = block("voronoi", -0.3, 0.01, 8)
    ref = simulate(pr, SolverOptions("newton"))
    other = simulate(pr, SolverOptions(method, tol=1e-11, max_iter=20000))
    assert np.abs(other.wear - ref.wear).max() < 1e-8
    assert np.abs(other.p_rigid - ref.p_rigid).max() < 1e-7


def test_pushed_block_converges_to_the_continuous_wear() -> None:
    """u_y = -delta from t = 0: the continuous wear is
    w(t) = (delta - gap) (1 - exp(-kappa |v*| k_s t)); the scheme converges to it with
    order 1 in k."""
    delta, gap = 0.05, 0.01
    errors = []
    for n in (16, 32, 64):
        r = simulate(block("squares", -delta, gap, n), SolverOptions("newton"))
        exact = (delta - gap) * (1 - np.exp(-KAPPA * 1.0 * K_S * r.t))
        errors.append(float(np.abs(r.wear - exact[:, None]).max()))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all((orders > 0.9) & (orders < 1.1)), (errors, orders)


def test_pushed_at_a_rate_converges_to_the_continuous_wear() -> None:
    """u_y = -delta t: contact starts at t_0 = gap / delta; discrete recursion to
    round-off, the continuous wear with order 1 in k."""
    delta, gap = 0.08, 0.02
    t0, a = gap / delta, KAPPA * 1.0

    def exact(t: np.ndarray) -> np.ndarray:
        s = np.maximum(t - t0, 0.0)
        return delta * s - delta / (a * K_S) * (1 - np.exp(-a * K_S * s))

    errors = []
    for n in (16, 32, 64):
        k = 1.0 / n
        r = simulate(block("squares", lambda x, t: -delta * t, gap, n), SolverOptions("newton"))
        w = discrete_wear(lambda i, k=k: delta * i * k, gap, k, n)
        assert np.abs(r.wear - w[:, None]).max() < 1e-14
        errors.append(float(np.abs(r.wear[:, 0] - exact(r.t)).max()))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all((orders > 0.9) & (orders < 1.1)), (errors, orders)


def test_free_rigid_motions_are_named() -> None:
    """Rollers u_y = 0 on the left side: contact on the bottom holds the translation in y
    and the rotation (load control), not the translation in x, which the message names."""
    mesh = select_parts(
        rectangle_squares((W, H), (4, 2)), {"rollers": "left", "contact": "bottom", "free": "rest"}
    )
    with pytest.raises(ValueError, match="leave rigid motions free: the translation in x; clamp"):
        Problem(
            mesh,
            Material(LAM, ETA),
            TimeGrid.uniform(1.0, 2),
            clamped=(),
            displacement=(Prescribed("rollers", uy=0.0),),
        )


def test_rigid_motions_held_by_contact_are_accepted() -> None:
    """u_x = 0 on the bottom only, contact on the top: the body may move up and turn
    about any point of the bottom, which the top's contact normals resist (load
    control); without any constraint the translation in x stays free."""
    mesh = select_parts(
        rectangle_squares((W, H), (4, 2)), {"rollers": "bottom", "contact": "top", "free": "rest"}
    )
    pr = Problem(
        mesh,
        Material(LAM, ETA),
        TimeGrid.uniform(1.0, 2),
        clamped=(),
        displacement=(Prescribed("rollers", ux=0.0),),
    )
    assert pr.rigid_basis.shape == (2, 3)
    assert pr.held_by_contact_check().shape == (0, 3)
    with pytest.raises(ValueError, match="leave rigid motions free: the translation in x; clamp"):
        Problem(mesh, Material(LAM, ETA), TimeGrid.uniform(1.0, 2), clamped=())
