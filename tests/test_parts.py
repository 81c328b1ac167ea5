"""A user's own problem in a config file: named parts, prescribed displacements, several
traction and contact parts, initial gap, sliding that follows the geometry, a
foundation velocity that vanishes."""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from conftest import small_config
from vemwear.config import ConfigError, parse_config
from vemwear.simulate import simulate

BASE = tomllib.loads(small_config("parts", steps=8))


def parse(data: dict[str, Any]) -> Any:
    return parse_config(data, source="c.toml", base_dir=Path("."))


def variant(**sections: Any) -> dict[str, Any]:
    d = copy.deepcopy(BASE)
    for name, keys in sections.items():
        if keys is None:
            d.pop(name, None)
        else:
            d[name] = keys
    return d


def test_gap_zero_and_tangent_v_star_are_bitwise_the_paper_scheme() -> None:
    ref = simulate(parse(BASE).problem, "newton")
    d = copy.deepcopy(BASE)
    d["contact"]["gap"] = 0.0
    d["contact"]["on"] = d["boundary"].pop("contact")
    got = simulate(parse(d).problem, "newton")
    for name in ("wear", "u_nu", "p_soft", "p_rigid", "u"):
        assert np.array_equal(getattr(got, name), getattr(ref, name)), name


def test_load_on_top_right_side_free_and_rollers() -> None:
    """'load on top, right side free': each edge in one part, several traction tables."""
    d = variant(
        boundary={
            "clamped": "left",
            "free": "right",
            "contact": "bottom",
            "traction": [
                {"name": "load", "on": "top", "f2": [0.0, "-0.01*x"]},
            ],
        },
        loads={"f1": [0.0, -0.06]},
    )
    pr = parse(d).problem
    assert pr.mesh.parts == ("clamped", "contact", "free", "load")
    assert set(pr.tractions) == {"load"}
    r = simulate(pr, "newton")
    assert r.wear[-1].max() > 0


def test_traction_component_as_a_table_along_the_part() -> None:
    """f2 = [0, table]: along x as the expression -0.01 x, along s (the top runs from
    x = 2 to x = 0) as the same load; the same load vector, the same run."""

    def load(f2: list[Any]) -> Any:
        d = variant(
            boundary={
                "clamped": "left",
                "free": "right",
                "contact": "bottom",
                "traction": [{"name": "load", "on": "top", "f2": f2}],
            },
            loads={"f1": [0.0, -0.06]},
        )
        return parse(d).problem

    ref = load([0.0, "-0.01*x"])
    along_x = load([0.0, {"along": "x", "at": [0.0, 2.0], "values": [0.0, -0.02]}])
    along_s = load([0.0, {"along": "s", "at": [0.0, 2.0], "values": [-0.02, 0.0]}])
    F = ref.external_load(0.0)
    assert np.abs(F).max() > 0
    for pr in (along_x, along_s):
        assert np.abs(pr.external_load(0.0) - F).max() < 1e-17
    a, b = simulate(ref, "newton"), simulate(along_s, "newton")
    assert np.abs(a.wear - b.wear).max() < 1e-15 and a.wear[-1].max() > 0


def test_rollers_and_displacement_control_without_a_clamped_part() -> None:
    d = variant(
        boundary={
            "contact": "bottom",
            "displacement": [
                {"name": "rollers", "on": ["left", "right"], "ux": 0.0},
                {"name": "top", "on": "top", "uy": "-0.05*t"},
            ],
        }
    )
    d["contact"]["gap"] = 0.01
    d["contact"]["mu"] = 0.0
    pr = parse(d).problem
    assert pr.clamped == () and [p.part for p in pr.displacement] == ["rollers", "top"]
    r = simulate(pr, "newton")
    u = r.displacement(-1)
    assert np.abs(u[:, 0]).max() < 1e-14  # uniaxial
    top = np.abs(pr.mesh.points[:, 1] - 1.0) < 1e-12
    assert np.allclose(u[top, 1], -0.05, rtol=0, atol=1e-15)
    assert np.all(r.penetration[0] < 0)  # the gap is open at t = 0


def test_free_rigid_motion_is_named_at_the_boundary_key() -> None:
    d = variant(
        boundary={
            "contact": "bottom",
            "free": "rest",
            "displacement": [{"name": "rollers", "on": "left", "uy": 0.0}],
        }
    )
    # contact holds the body along its normal (y) and the rotation; not along x
    with pytest.raises(
        ConfigError,
        match=r"^c.toml: \[boundary\] the boundary conditions "
        r"leave rigid motions free: the translation in x; clamp a part",
    ):
        parse(d)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            {
                "boundary": {
                    "clamped": "left",
                    "contact": "bottom",
                    "traction": [{"on": "top", "f2": [0.0, -0.01]}],
                    "free": "right",
                }
            },
            r"\[loads\] f2 is the traction of \[boundary\] traction",
        ),
        (
            {
                "boundary": {
                    "clamped": "left",
                    "contact": "bottom",
                    "traction": "rest",
                    "displacement": [{"name": "clamped", "on": "top", "uy": 0.0}],
                }
            },
            r"\[\[boundary.displacement\]\] 1: the part name 'clamped' is taken by "
            r"\[boundary\] clamped",
        ),
        (
            {
                "boundary": {
                    "clamped": "left",
                    "contact": "bottom",
                    "traction": "rest",
                    "displacement": [{"on": "top"}],
                }
            },
            r"\[\[boundary.displacement\]\] 1: give ux, uy or both",
        ),
    ],
)
def test_part_errors(change: dict[str, Any], message: str) -> None:
    d = variant(**change)
    if "traction" in d["boundary"] and isinstance(d["boundary"]["traction"], list):
        d["loads"]["f2"] = [0.0, 0.0]
    with pytest.raises(ConfigError, match=message):
        parse(d)


def test_contact_on_and_boundary_contact_both_refused() -> None:
    d = copy.deepcopy(BASE)
    d["contact"]["on"] = "bottom"
    with pytest.raises(ConfigError, match=r"\[contact\] on and \[boundary\] contact both"):
        parse(d)


def test_a_face_the_foundation_moves_against_does_not_wear() -> None:
    """Contact on the bottom and the right side as one part, v* = (1, 0): the right
    face (normal (1, 0)) has v*_tau = 0: no wear and no friction there."""
    d = variant(boundary={"clamped": "left", "traction": "top", "contact": ["bottom", "right"]})
    d["contact"]["g"] = 0.3
    d["loads"]["f1"] = [-0.06, -0.06]
    pr = parse(d).problem
    r = simulate(pr, "newton")
    pts = r.contact_points
    right = (np.abs(pts[:, 0] - 2.0) < 1e-12) & (pts[:, 1] > 1e-12)
    assert right.sum() == 4 and r.p_soft[:, right].max() > 0  # pressed, yet
    assert r.wear[-1, right].max() == 0.0  # no wear where the foundation moves normally
    assert r.wear[-1, ~right].max() > 0


def test_reciprocating_foundation_with_levels_on_its_zeros() -> None:
    """v* = (cos 2 pi t, 0) on 8 steps: levels 2 and 6 are zeros of v*; accepted, and
    the wear does not grow over those steps."""
    d = copy.deepcopy(BASE)
    d["contact"]["v_star"] = ["cos(2*pi*t)", "0"]
    pr = parse(d).problem
    r = simulate(pr, "newton")
    dw = np.diff(r.wear, axis=0)
    assert np.abs(dw[2]).max() < 1e-17 and np.abs(dw[6]).max() < 1e-17  # |cos| ~ 1e-16
    assert dw[0].max() > 0 and dw[4].max() > 0


def test_two_contact_parts_with_their_own_data() -> None:
    """A body squeezed between two moving foundations: the left side clamped, the right
    side pushed in (u_x = -0.2 t), so that the block bulges onto the layers at the bottom
    and the top; each part its own law, mu, kappa, v* and gap. Both parts touch and
    wear; the foundations slide, so the tangential force of each part is its own mu
    times its normal force, in the direction of its own v*."""
    d = variant(
        boundary={
            "clamped": "left",
            "displacement": [{"name": "squeeze", "on": "right", "ux": "-0.2*t"}],
        },
        contact=[
            {
                "name": "lower",
                "on": "bottom",
                "p": {"type": "linear", "c": 0.4},
                "g": 0.1,
                "mu": 0.2,
                "kappa": 2.0,
                "v_star": [1.0, 0.0],
            },
            {
                "name": "upper",
                "on": "top",
                "p": {"type": "table", "r": [0.0, 0.1], "p": [0.0, 0.08]},
                "g": 0.1,
                "mu": 0.1,
                "kappa": 1.0,
                "v_star": [-1.0, 0.0],
                "gap": 0.001,
            },
        ],
        loads={"f1": [0.0, 0.0]},
    )
    pr = parse(d).problem
    cb = pr.contact
    assert cb.part_names == ("lower", "upper")
    assert set(np.unique(pr.nodal["kappa"][cb.part == 1])) == {1.0}
    assert set(np.unique(pr.nodal["gap"][cb.part == 1])) == {0.001}
    assert set(np.unique(pr.nodal["gap"][cb.part == 0])) == {0.0}
    r = simulate(pr, "newton")
    assert r.force_parts == (
        ("lower", "contact"),
        ("upper", "contact"),
        ("clamped", "reaction"),
        ("squeeze", "reaction"),
    )
    F = r.forces
    assert F is not None
    for i, (mu, vx, ny) in enumerate([(0.2, 1.0, 1.0), (0.1, -1.0, -1.0)]):
        assert r.wear[-1, cb.part == i].max() > 0
        normal = F[1:, i, 1] * ny  # the layer pushes the body away from it
        assert np.all(normal > 0)
        assert np.abs(F[1:, i, 0] - mu * vx * normal).max() < 1e-14 * np.abs(normal).max()


def test_reactions_are_the_residual_of_the_recovered_displacement() -> None:
    """The reactions of the clamped and the prescribed part, computed from the condensed
    data, are ``K u - f_h`` plus the layer forces summed over each part's constrained
    dofs with the recovered u; the corner contact nodes have constrained components, so
    the layer forces on constrained dofs are part of it."""
    d = variant(
        boundary={
            "clamped": "left",
            "contact": "bottom",
            "free": "top",
            "displacement": [{"name": "squeeze", "on": "right", "ux": "-0.2*t"}],
        },
    )
    pr = parse(d).problem
    r = simulate(pr, "newton")
    disc, con, cb = pr.discrete, pr.constraints, pr.contact
    assert r.force_parts[-2:] == (("clamped", "reaction"), ("squeeze", "reaction"))
    on_constrained = np.isin(np.concatenate([cb.N.indices, cb.Tau.indices]), con.dofs)
    assert on_constrained.any()  # the corners: contact nodes with constrained components
    for j, level in enumerate(r.u_levels):
        t = float(r.t[level])
        u = r.u[j].ravel()
        fric = disc.tangential_velocity(t)  # v* . tau: the friction is -mu sign of it
        w = cb.weights
        p_soft, p_rigid = r.p_soft[level], r.p_rigid[level]
        layer = cb.N.T @ (w * (p_soft + p_rigid)) + cb.Tau.T @ (
            w * pr.nodal["mu"] * -np.sign(fric) * p_soft
        )
        residual = disc.K_full @ u - pr.external_load(t) + layer
        want = np.zeros((len(con.parts), 2))
        np.add.at(want, (con.owner, con.dofs % 2), residual[con.dofs])
        got = r.forces[level, -2:]
        assert np.abs(got - want).max() <= 1e-10 * np.abs(want).max()
