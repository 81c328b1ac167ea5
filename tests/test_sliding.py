"""Sliding fields v*(x, t) in 2D and 3D, and friction on the whole contact pressure
(docs/method.md, sections 3b, 4b and 10): a disc turning under a pin, a circular fretting
path, the Coulomb law on the total pressure, and the bad inputs of both."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from vemwear.config import ConfigError, parse_config
from vemwear.contact import ContactPart, FoundationVelocity, LinearCompliance, RotatingFoundation
from vemwear.mesh import rectangle_squares, tag_rectangle
from vemwear.mesh.generate3d import box_hexahedra, tag_box
from vemwear.post.forces import force_table
from vemwear.simulate import Prescribed, Problem, SolverOptions, TimeGrid, simulate
from vemwear.vem import Material

SOLVERS = {
    "newton-full": SolverOptions("newton-full"),
    "uzawa": SolverOptions("uzawa", tol=1e-11, max_iter=100_000),
}


def rel(a, b) -> float:
    return float(np.abs(np.asarray(a) - b).max() / max(np.abs(b).max(), 1e-300))


def agree(pr: Problem, tol: float = 1e-9):
    """The run of the condensed Newton, after checking that newton-full and Uzawa agree
    with it (u, wear, pressures, forces)."""
    ref = simulate(pr, "newton")
    assert ref.residuals.max() < 1e-9
    for name, opts in SOLVERS.items():
        other = simulate(pr, opts)
        for key in ("u", "wear", "p_soft", "p_rigid", "forces"):
            assert rel(getattr(other, key), getattr(ref, key)) < tol, (name, key)
    return ref


def pin(v_star, steps: int = 6, divisions=(4, 4, 2), **contact) -> Problem:
    """A square pin [-0.5, 0.5]^2 x [0, 0.5] pressed into the layer on z = 0 by its top face
    (u = (0, 0, -0.05) there), the foundation sliding with ``v_star``."""
    mesh = tag_box(
        box_hexahedra((1.0, 1.0, 0.5), divisions, origin=(-0.5, -0.5, 0.0)),
        {"top": "zmax", "contact": "zmin", "free": ["xmin", "xmax", "ymin", "ymax"]},
    )
    part = ContactPart(
        "contact",
        LinearCompliance(contact.pop("c", 0.4)),
        g=contact.pop("g", 0.1),
        mu=0.3,
        kappa=2.0,
        v_star=v_star,
        **contact,
    )
    return Problem(
        mesh,
        Material(4.0, 4.0),
        TimeGrid.uniform(1.0, steps),
        clamped=(),
        displacement=(Prescribed("top", ux=0.0, uy=0.0, uz=-0.05),),
        contacts=(part,),
    )


# --------------------------------------------------------------------- a turning disc (3D)
def test_disc_turning_under_a_pin() -> None:
    """The axis of the disc passes through the pin's face at c = (0.2, 0, 0): v* changes
    its direction across the axis, friction drags every node along its own v*_tau (so in
    opposite directions on the two sides), and the wear rate is kappa |omega| r."""
    omega, c = 2.0, np.array([0.2, 0.0, 0.0])
    pr = pin(RotatingFoundation(center=c, axis=(0, 0, 1), omega=omega))
    d = pr.discrete
    cb = pr.contact
    assert d.system.rows == 1  # a constant omega keeps one line at every node
    r_vec = cb.points - c
    r = np.linalg.norm(r_vec[:, :2], axis=1)
    v = omega * np.column_stack([-r_vec[:, 1], r_vec[:, 0], np.zeros(cb.m)])
    off = r > 1e-12
    # each node's friction row is along its own v*, the tangent of its circle
    assert np.abs(np.sum(cb.tangents[off] * r_vec[off], axis=1)).max() < 1e-14
    assert np.allclose(d.alpha(0.5), 2.0 * abs(omega) * r, rtol=1e-14, atol=1e-15)
    res = agree(pr)
    # the friction force of the layer on node a: omega_a mu p_a v*_tau / |v*_tau|
    fric, p = d.friction(0.0), res.p_soft[-1]
    force = -(cb.weights * fric * p)[:, None] * cb.tangents
    unit = v[off] / np.linalg.norm(v[off], axis=1)[:, None]
    expect = (cb.weights * 0.3 * p)[off, None] * unit
    assert np.abs(force[off] - expect).max() < 1e-15
    assert np.all(fric[~off] == 0.0) and np.all(res.wear[:, ~off] == 0.0)  # on the axis
    # opposite sides of the axis (y > 0 and y < 0 at the same x) are dragged opposite ways
    up, down = cb.points[:, 1] > 1e-9, cb.points[:, 1] < -1e-9
    assert np.all(force[up, 0] < 0) and np.all(force[down, 0] > 0)
    # the wear of the first step: k kappa |omega| r p(u_nu - w)
    assert rel(res.wear[1], (1 / 6) * 2.0 * omega * r * res.p_soft[0]) < 1e-13
    # the force table gives the magnitude of the tangential force (no one direction)
    row = force_table(res)[0]
    F = res.forces[-1, 0]
    assert row["tangential"] == pytest.approx(np.hypot(F[0], F[1]), rel=1e-12)


def test_disc_in_2d_equals_its_tangential_velocity() -> None:
    """In 2D a rotation about the out-of-plane axis through c gives the flat contact face
    y = 0 the tangential velocity -omega (0 - c_y): the same run, bitwise, as that constant v*."""
    mesh = tag_rectangle(
        rectangle_squares((2.0, 1.0), (8, 4)),
        {"clamped": "left", "traction": ["top", "right"], "contact": "bottom"},
    )

    def problem(v):
        return Problem(
            mesh=mesh,
            material=Material(4.0, 4.0),
            time=TimeGrid.uniform(1.0, 8),
            f1=(0.0, -0.06),
            p=LinearCompliance(0.4),
            g=0.1,
            mu=0.2,
            kappa=2.0,
            v_star=v,
        )

    a = simulate(problem(RotatingFoundation(center=(0.7, -0.5), omega=-2.0)))
    b = simulate(problem((1.0, 0.0)))  # -omega (0 - c_y) = 1
    for key in ("u", "wear", "p_soft", "forces"):
        assert np.array_equal(getattr(a, key), getattr(b, key)), key


# --------------------------------------------------------------- circular fretting (3D)
def test_circular_fretting_path() -> None:
    """v* = (cos 2 pi t, sin 2 pi t, 0): the friction rows are two fixed tangents per node
    (one factorization), and at every level the friction force of every pressed node is mu
    p omega_a along v*(t), so the resultant turns with v*."""
    v = lambda t: (np.cos(2 * np.pi * t), np.sin(2 * np.pi * t), 0.0)  # noqa: E731
    pr = pin(v, steps=8)
    d = pr.discrete
    assert d.system.rows == 2 and d.system.Tau.shape[0] == 2 * pr.contact.m
    res = agree(pr)
    cb = pr.contact
    for n, t in enumerate(res.t):
        fric = d.friction(float(t)).reshape(2, -1)
        direction = fric[0][:, None] * cb.tangents + fric[1][:, None] * cb.tangents2
        unit = np.array(v(t))
        assert np.abs(direction + 0.3 * unit).max() < 1e-15  # mu n*, n* = -v*/|v*|
        F = res.forces[n, 0]  # the layer's resultant on the pin
        normal = F[2]  # nu = -e_z: the layer pushes the pin up
        tangential = F[:2]
        assert normal > 0
        assert np.abs(tangential - 0.3 * normal * unit[:2]).max() < 1e-13 * normal
    assert np.all(np.diff(res.wear, axis=0) >= 0)


def test_field_of_one_line_keeps_one_row_and_numbers() -> None:
    """A field that is one constant vector gives the same run, bitwise, as that vector:
    the per-node lines reduce to the one line."""
    field = FoundationVelocity(lambda x, t: np.array([0.6, 0.8, 0.0]), spatial=True)
    a = simulate(pin(field))
    b = simulate(pin((0.6, 0.8, 0.0)))
    for key in ("u", "wear", "p_soft", "forces"):
        assert np.array_equal(getattr(a, key), getattr(b, key)), key


# ------------------------------------------------------ friction on the whole pressure
@pytest.mark.parametrize("wear_on", ["soft", "total"])
def test_friction_on_the_total_pressure(wear_on) -> None:
    """friction_on = "total": the tangential force of every sliding node is mu times its
    normal force (the soft and the rigid layer's) to 1e-12, with all three solvers; the
    wear takes p_soft, or the whole pressure with wear_on = "total"."""
    pr = pin((1.0, 0.0, 0.0), g=0.02, friction_on="total", wear_on=wear_on)
    res = agree(pr)
    cb, d = pr.contact, pr.discrete
    p_total = res.p_soft + res.p_rigid
    assert res.p_rigid.max() > 0.1 * p_total.max()  # the rigid layer carries load
    fric = d.friction(0.0)
    assert np.all(np.abs(fric) == 0.3)
    for n in range(len(res.t)):
        normal = cb.weights * p_total[n]  # the nodal normal forces
        tangential = np.abs(cb.weights * fric * p_total[n])
        assert np.abs(tangential - 0.3 * normal).max() <= 1e-12 * normal.max()
        F = res.forces[n, 0]
        assert abs(F[0] - 0.3 * F[2]) <= 1e-12 * abs(F[2])
    k, alpha = 1 / 6, 2.0
    pressure = res.p_soft[0] if wear_on == "soft" else p_total[0]
    assert rel(res.wear[1], k * alpha * pressure) < 1e-13


@pytest.mark.parametrize("order", [1, 2])
def test_field_and_total_friction_in_2d(order) -> None:
    """A 2D field v*(x, t) = ((1 + x) cos 2 pi t, 0) with friction and wear on the whole
    pressure, k = 1 and k = 2 (the trace operator): the three solvers agree, and the wear
    rate of each node is kappa (1 + x) |cos 2 pi t|."""
    mesh = tag_rectangle(
        rectangle_squares((2.0, 1.0), (8, 4)),
        {"clamped": "left", "traction": ["top", "right"], "contact": "bottom"},
    )
    v = FoundationVelocity(
        lambda x, t: np.column_stack([(1 + x[:, 0]) * np.cos(2 * np.pi * t), 0 * x[:, 0]]),
        spatial=True,
    )
    part = ContactPart(
        "contact", LinearCompliance(0.4), 0.05, 0.2, 2.0, v, friction_on="total", wear_on="total"
    )
    pr = Problem(
        mesh=mesh,
        material=Material(4.0, 4.0),
        time=TimeGrid.uniform(1.0, 8),
        f1=(0.0, -0.6),
        contacts=(part,),
        order=order,
    )
    res = agree(pr)
    assert res.p_rigid.max() > 0
    x = pr.contact.points[:, 0]
    assert np.allclose(pr.discrete.alpha(0.125), 2.0 * (1 + x) * np.cos(np.pi / 4), rtol=1e-14)


def test_friction_on_soft_is_the_paper() -> None:
    """The default, friction_on = "soft": the rigid layer's pressure has no friction."""
    pr = pin((1.0, 0.0, 0.0), g=0.02)
    res = simulate(pr)
    F = res.forces[-1, 0]
    soft = float((pr.contact.weights * res.p_soft[-1]).sum())
    assert res.p_rigid.max() > 0 and abs(F[0] - 0.3 * soft) < 1e-12 * soft


# ------------------------------------------------------------------------ configuration
CONFIG = """
[mesh]
generator = "rectangle_squares"
size = [2.0, 1.0]
divisions = [8, 4]
[boundary]
clamped = "left"
traction = ["top", "right"]
contact = "bottom"
[material]
lam = 4.0
eta = 4.0
[loads]
f1 = [0.0, -0.06]
[contact]
p = {{ type = "linear", c = 0.4 }}
g = 0.1
mu = 0.2
kappa = 2.0
v_star = {v}
{extra}
[time]
T = 1.0
steps = 8
"""


def config(v: str, extra: str = ""):
    return parse_config(tomllib.loads(CONFIG.format(v=v, extra=extra)), source="c.toml")


def test_config_fields_and_rotation() -> None:
    """v_star expressions in x and t, and a rotation, run from a configuration file; the
    rotation equals its library form."""
    pr = config('["(1 + x)*cos(2*pi*t)", "0"]').problem
    d = pr.discrete
    x = pr.contact.points[:, 0]
    assert np.allclose(d.tangential_velocity(0.25), 0.0, atol=1e-15)
    assert np.allclose(d.tangential_velocity(0.5), -(1 + x), rtol=1e-15)
    rot = config('{ rotation = { center = [1.0, -1.0], omega = "2*min(t/0.5, 1)" } }').problem
    # -omega(t) (0 - c_y) with omega(0.25) = 1
    assert np.allclose(rot.discrete.tangential_velocity(0.25), -1.0, rtol=1e-15)
    assert simulate(rot).wear[-1].max() > 0
    total = config("[1.0, 0.0]", 'friction_on = "total"\nwear_on = "total"').problem
    assert total.parts[0].friction_on == "total" and total.parts[0].wear_on == "total"


def test_bad_sliding_fields() -> None:
    """One line before any work: a v* field not finite at a node and level names both; a
    2D rotation about an axis in the plane is refused."""
    with pytest.raises(ConfigError) as e:
        config('["1/(x - 1)", "0"]')
    msg = str(e.value)
    assert "\n" not in msg
    assert "not finite at contact node" in msg and "x = (1, 0)" in msg and "level 0" in msg
    with pytest.raises(ConfigError) as e:
        config('["x/(t - 0.5)", "0"]')
    assert "t = 0.5 (level 4)" in str(e.value)
    with pytest.raises(ConfigError) as e:
        config("{ rotation = { center = [1.0, -1.0], axis = [1.0, 0.0, 0.0], omega = 1.0 } }")
    msg = str(e.value)
    assert msg.startswith("c.toml: [contact] v_star.rotation.axis = [1, 0, 0]: on a 2D mesh")
    assert "needs a 3D mesh" in msg
    with pytest.raises(ConfigError, match="friction_on"):
        config("[1.0, 0.0]", 'friction_on = "rigid"')
    with pytest.raises(ValueError, match="in 2D the axis"):
        RotatingFoundation(center=(0.0, 0.0), axis=(0.0, 1.0, 0.0))


# ------------------------------------------------------ every earlier v* form, bitwise
def _p2(v, f1=(0.0, -0.06)) -> Problem:
    mesh = tag_rectangle(
        rectangle_squares((2.0, 1.0), (8, 4)),
        {"clamped": "left", "traction": ["top", "right"], "contact": "bottom"},
    )
    return Problem(
        mesh=mesh,
        material=Material(4.0, 4.0),
        time=TimeGrid.uniform(1.0, 16),
        f1=f1,
        p=LinearCompliance(0.4),
        g=0.1,
        mu=0.2,
        kappa=2.0,
        v_star=v,
    )


def _p3(v, f1=(0.0, 0.0, -0.06)) -> Problem:
    mesh = tag_box(
        box_hexahedra((2.0, 1.0, 1.0), (4, 2, 2)),
        {"clamped": "xmin", "contact": "zmin", "traction": ["xmax", "ymin", "ymax", "zmax"]},
    )
    return Problem(
        mesh,
        Material(4.0, 4.0),
        TimeGrid.uniform(1.0, 16),
        f1=f1,
        p=LinearCompliance(0.4),
        g=0.1,
        mu=0.2,
        kappa=2.0,
        v_star=v,
    )


def _cfg(v: str) -> Problem:
    text = CONFIG.format(v=v, extra="").replace("steps = 8", "steps = 32")
    return parse_config(tomllib.loads(text)).problem


#: sha256 (first 32 hex digits) of wear, u, p_soft, p_rigid and forces of the condensed
#: Newton's run of each v* form, computed before sliding fields and two friction rows
#: were added: those forms take the same arithmetic as before, bitwise
BEFORE = {
    "const2": ("456aa440f7ef0679d123f5b05a647075", lambda: _p2((1.0, 0.0))),
    "const2_rigid": (
        "29875b89cd29ad21f45d59a8654c017a",
        lambda: _p2((1.0, 0.0), f1=(0.0, -0.6)),
    ),
    "oblique2": ("456aa440f7ef0679d123f5b05a647075", lambda: _p2((1.0, 0.3))),
    "table2": (
        "1fd3983bb49a513f6b1b1e8f266fbc9a",
        lambda: _p2({"t": [0.0, 0.5, 1.0], "values": [[1.0, 0.0], [-1.0, 0.2], [0.5, 0.0]]}),
    ),
    "callable2": (
        "053c309bb3727ddc3311790f66f2192b",
        lambda: _p2(lambda t: (np.cos(2 * np.pi * t), 0.0)),
    ),
    "const3": ("ed63ef07790ed771c0424f82b5999630", lambda: _p3((1.0, 0.0, 0.0))),
    "line3": (
        "c0321cf92002d3960b4b12b6bc398a2c",
        lambda: _p3(lambda t: (1 - 1.5 * t) * np.array([1.0, 0.5, 0.3])),
    ),
    "line3_rigid": (
        "0f2b11fb1667c7f96ebdc829b3078dbb",
        lambda: _p3((0.6, 0.8, 0.0), f1=(0.0, 0.0, -0.6)),
    ),
    "expr_cfg": ("7a852dcf131529e1f76fcab2a59f5174", lambda: _cfg('["cos(2*pi*t)", 0.0]')),
    "table_cfg": (
        "c970ab4e7767a65f4540aa99c48f7dca",
        lambda: _cfg("{ t = [0.0, 1.0], values = [[1.0, 0.0], [-1.0, 0.0]] }"),
    ),
}


@pytest.mark.parametrize("case", list(BEFORE))
def test_earlier_velocity_forms_bitwise(case) -> None:
    import hashlib

    digest, make = BEFORE[case]
    # PARDISO with MKL's own thread count, as when the digests were computed ("auto" runs
    # small Schur factorizations on one thread, whose round-off differs)
    r = simulate(make(), SolverOptions(method="newton", backend="pardiso"))
    h = hashlib.sha256()
    for key in ("wear", "u", "p_soft", "p_rigid", "forces"):
        h.update(np.ascontiguousarray(getattr(r, key)).tobytes())
    assert h.hexdigest()[:32] == digest


class _Stop(Exception):
    pass


@pytest.mark.parametrize("level", [3, 6])
def test_resume_of_a_turning_path_with_total_pressure(level) -> None:
    """A circular path with friction and wear on the whole pressure, stopped at a level
    and resumed: the same arrays as the uninterrupted run, bitwise (the resumed wear
    update takes the same pressure)."""
    v = lambda t: (np.cos(2 * np.pi * t), np.sin(2 * np.pi * t), 0.0)  # noqa: E731
    pr = pin(v, steps=8, g=0.02, friction_on="total", wear_on="total")

    def stop(n, _sol):
        if n == level:
            raise _Stop

    with pytest.raises(_Stop) as info:
        simulate(pr, store="all", recover_block=4, callback=stop)
    part = info.value.partial_result  # type: ignore[attr-defined]
    assert part.is_partial and part.completed <= level
    resumed = simulate(pr, store="all", recover_block=4, resume=part)
    ref = simulate(pr, store="all", recover_block=4)
    assert ref.p_rigid.max() > 0
    for key in ("wear", "u", "u_nu", "p_rigid", "p_soft", "forces", "residuals"):
        assert np.array_equal(getattr(resumed, key), getattr(ref, key)), key


# ------------------------------------------------------------- the wear law, one place
@pytest.mark.parametrize("wear_on", ["soft", "total"])
def test_wear_update_and_rate_are_the_loops_and_the_warnings(wear_on) -> None:
    """On a turning path, every level's wear is ``wear_update`` of the level before with
    the discretization's ``alpha(t_n)`` (bitwise), and the overshoot measure of the
    warning is ``max_n k_n max_a alpha(t_n) L_p`` with the same alpha."""
    from vemwear.simulate.explicit import overshoot
    from vemwear.simulate.wear import wear_update

    v = lambda t: (np.cos(2 * np.pi * t), np.sin(2 * np.pi * t), 0.0)  # noqa: E731
    pr = pin(v, steps=8, g=0.02, friction_on="total", wear_on=wear_on)
    res = simulate(pr)
    d, t = pr.discrete, pr.time.t
    assert res.wear[-1].max() > 0
    for n in range(len(t) - 1):
        pressure = res.p_soft[n] + (res.p_rigid[n] if wear_on == "total" else 0.0)
        w = wear_update(res.wear[n], t[n + 1] - t[n], d.alpha(float(t[n])), pressure)
        assert np.array_equal(res.wear[n + 1], w), n
    rates = [float(np.max(d.alpha(float(x)))) * 0.4 for x in t[:-1]]  # L_p = c = 0.4
    expected = max(k * r for k, r in zip(np.diff(t), rates, strict=True))
    value, _, safe = overshoot(pr)
    assert rel(value, expected) < 1e-14 and rel(safe, 1 / max(rates)) < 1e-14
