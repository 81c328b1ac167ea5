"""Rigid parts: a holder that presses a pad with a force resultant (docs/method.md 1d)."""

from __future__ import annotations

import copy
import json
import textwrap
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from vemwear import LinearCompliance, Material, Problem, TimeGrid, simulate
from vemwear.config import ConfigError, parse_config
from vemwear.mesh import MeshError, rectangle_squares, select_parts, tag_rectangle
from vemwear.mesh.generate3d import box_hexahedra, tag_box
from vemwear.simulate import Prescribed, RigidPart

P = 0.06

CONFIG: dict[str, Any] = {
    "mesh": {"generator": "squares", "size": [1.0, 0.5], "divisions": [16, 8]},
    "boundary": {
        "contact": "bottom",
        "displacement": [{"name": "rollers", "on": ["left", "right"], "ux": 0.0}],
        "rigid": [{"name": "holder", "on": "top", "fy": f"-{P}*min(t/0.25, 1)"}],
    },
    "material": {"lam": 4.0, "eta": 4.0},
    "contact": {
        "p": {"type": "linear", "c": 1.0},
        "g": 0.1,
        "mu": 0.0,
        "kappa": 0.5,
        "v_star": [1.0, 0.0],
    },
    "time": {"T": 1.0, "steps": 8},
    "output": {"figures": False, "vtk": False},
}


def parse(d: dict[str, Any]) -> Any:
    return parse_config(d, source="c.toml")


@pytest.mark.parametrize("order", [1, 2])
def test_holder_presses_the_pad_with_its_resultant(order: int) -> None:
    d = copy.deepcopy(CONFIG)
    d["vem"] = {"order": order}
    pr = parse(d).problem
    assert pr.discrete.force_parts[-1] == ("holder", "rigid")
    res = simulate(pr, "newton")
    load = P * np.minimum(res.t / 0.25, 1.0)
    # rollers and a rigid top: uniaxial strain, the pressure is the load over the width
    assert np.abs(res.p_soft - load[:, None]).max() <= 1e-10 * P
    holder = res.forces[:, -1]
    assert np.abs(holder[:, 1] + load).max() <= 1e-14
    assert np.abs(res.forces[:, 0, 1] - load).max() <= 1e-12 * P  # contact balances it
    top = np.abs(pr.mesh.points[:, 1] - 0.5) < 1e-12
    assert np.ptp(res.u[:, top], axis=1).max() <= 1e-14  # the top moves as one body
    full = simulate(pr, "newton-full")
    assert np.abs(full.u - res.u).max() <= 1e-9 * np.abs(res.u).max()


def test_holder_with_a_prescribed_translation_and_friction() -> None:
    """Free sides: the holder is held in x (ux = 0) and loaded in y; friction's force
    is the holder's reaction in x."""
    mesh = tag_rectangle(
        rectangle_squares((1.0, 0.5), (16, 8)),
        {"holder": "top", "free": ["left", "right"], "contact": "bottom"},
    )
    pr = Problem(
        mesh,
        Material(4.0, 4.0),
        TimeGrid.uniform(1.0, 4),
        p=LinearCompliance(1.0),
        g=0.1,
        mu=0.2,
        kappa=0.5,
        v_star=(1.0, 0.0),
        clamped=(),
        rigid=(RigidPart("holder", force=(None, -P), translation=(0.0, None)),),
    )
    res = simulate(pr, "newton")
    assert np.abs(res.forces[:, 1] - [[-0.2 * P, -P]]).max() <= 1e-12 * P
    assert np.abs(res.forces.sum(axis=1)).max() <= 1e-12 * P
    full = simulate(pr, "newton-full")
    assert np.abs(full.wear - res.wear).max() <= 1e-9 * res.wear.max()


def test_holder_in_3d() -> None:
    mesh = tag_box(
        box_hexahedra((1.0, 1.0, 0.5), (4, 4, 2)),
        {"contact": "zmin", "holder": "zmax", "sx": ["xmin", "xmax"], "sy": ["ymin", "ymax"]},
    )
    pr = Problem(
        mesh,
        Material(4.0, 4.0),
        TimeGrid.uniform(1.0, 4),
        p=LinearCompliance(1.0),
        g=0.1,
        mu=0.0,
        kappa=0.5,
        v_star=(1.0, 0.0, 0.0),
        clamped=(),
        displacement=(Prescribed("sx", ux=0.0), Prescribed("sy", uy=0.0)),
        rigid=(RigidPart("holder", force=(None, None, -P)),),
    )
    res = simulate(pr, "newton")
    assert np.abs(res.p_soft - P).max() <= 1e-10 * P
    assert np.abs(res.forces[:, -1, 2] + P).max() <= 1e-14


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            {"ux": 0.0, "fx": 0.1},
            r"\[\[boundary.rigid\]\] 1: component x has both a force and a prescribed "
            r"translation ux",
        ),
        ({"moment": 0.01}, r"moment is for rotation = 'free'"),
        ({"rotation": "free", "moment": [0.0, 0.01]}, r"moment is one number in 2D"),
        ({"fx": 0.1, "force": [0.0, -0.1]}, r"give the force as force = \[...\] or as fx"),
    ],
)
def test_bad_rigid_parts_are_one_line(change: dict[str, Any], message: str) -> None:
    d = copy.deepcopy(CONFIG)
    d["boundary"]["rigid"][0].update(change)
    with pytest.raises(ConfigError, match=message):
        parse(d)


def test_rigid_part_touching_a_clamped_part_is_refused() -> None:
    d = copy.deepcopy(CONFIG)
    d["boundary"]["clamped"] = "left"
    d["boundary"]["displacement"][0]["on"] = "right"
    with pytest.raises(ConfigError, match=r"rigid part 'holder' touches the clamped part"):
        parse(d)


def test_a_direction_held_by_nothing_is_named() -> None:
    d = copy.deepcopy(CONFIG)
    del d["boundary"]["displacement"]
    d["boundary"]["free"] = ["left", "right"]
    with pytest.raises(ConfigError, match=r"leave rigid motions free: the translation in x"):
        parse(d)


def test_summary_reports_the_holders_translation(tmp_path: Any) -> None:
    import json

    from vemwear.cli.main import main

    d = copy.deepcopy(CONFIG)
    lines = [
        "[mesh]",
        'generator = "squares"',
        "size = [1.0, 0.5]",
        "divisions = [8, 4]",
        "[boundary]",
        'contact = "bottom"',
        "[[boundary.displacement]]",
        'name = "rollers"',
        'on = ["left", "right"]',
        "ux = 0.0",
        "[[boundary.rigid]]",
        'name = "holder"',
        'on = "top"',
        f'fy = "{d["boundary"]["rigid"][0]["fy"]}"',
        "[material]",
        "lam = 4.0",
        "eta = 4.0",
        "[contact]",
        'p = { type = "linear", c = 1.0 }',
        "g = 0.1",
        "mu = 0.0",
        "kappa = 0.5",
        "v_star = [1.0, 0.0]",
        "[time]",
        "T = 1.0",
        "steps = 4",
        "[output]",
        "figures = false",
        "vtk = false",
    ]
    cfg = tmp_path / "holder.toml"
    cfg.write_text("\n".join(lines) + "\n")
    assert main(["run", str(cfg), "-o", str(tmp_path / "out"), "--no-progress"]) == 0
    out = json.loads((tmp_path / "out" / "summary.json").read_text())["outputs"]
    tx, ty = out["rigid_parts"]["holder"]["translation_final"]
    with np.load(tmp_path / "out" / "result.npz") as z:
        top = np.abs(z["points"][:, 1] - 0.5) < 1e-12
        assert np.allclose(z["u"][-1][top], [tx, ty], rtol=0, atol=1e-15)
        assert [str(n) for n in z["force_parts"]] == ["contact", "rollers", "holder"]
    assert ty < 0 and abs(tx) < 1e-15


@pytest.mark.parametrize(
    ("method", "level", "turning"),
    [
        *((m, n, False) for m in ("newton", "uzawa") for n in (0, 3, 6)),
        *(("newton", n, True) for n in (0, 3, 6)),
    ],
)
def test_a_holders_run_resumes_bitwise(method: str, level: int, turning: bool) -> None:
    """Load control with a holder and a ramped load, two contact parts with their own
    data and a gap: a run stopped at a level resumes to the same arrays, bitwise; also
    with the holder free to turn under a moment (the pad tilts onto the softer part)."""
    from vemwear.contact import ContactPart

    mesh = select_parts(
        rectangle_squares((1.0, 0.5), (12, 6)),
        {
            "holder": "top",
            "free": ["left", "right"],
            "c1": [((0.0, 0.0), (0.5, 0.0))],
            "c2": [((0.5, 0.0), (1.0, 0.0))],
        },
    )
    law = LinearCompliance(1.0)
    pr = Problem(
        mesh,
        Material(4.0, 4.0),
        TimeGrid.uniform(1.0, 8),
        clamped=(),
        contacts=(
            ContactPart("c1", law, 0.1, 0.2, 0.5, (1.0, 0.0), 0.002),
            ContactPart("c2", LinearCompliance(2.0), 0.1, 0.3, 1.0, (1.0, 0.0), 0.0),
        ),
        rigid=(
            RigidPart(
                "holder",
                force=(None, lambda t: -P * min(t / 0.25, 1.0)),
                translation=(0.0, None),
                # (a moment ramped with the force: a moment alone would lift the pad)
                **(
                    {"rotation": "free", "moment": (lambda t: 0.1 * P * min(t / 0.25, 1.0),)}
                    if turning
                    else {}
                ),
            ),
        ),
    )

    class Stop(Exception):
        pass

    def stop(n: int, _sol: Any) -> None:
        if n == level:
            raise Stop

    with pytest.raises(Stop) as info:
        simulate(pr, method, callback=stop)
    resumed = simulate(pr, method, resume=info.value.partial_result)  # type: ignore[attr-defined]
    ref = simulate(pr, method)
    assert ref.residuals.max() <= 1e-10
    for k in ("wear", "u_nu", "p_rigid", "p_soft", "u", "iterations", "forces"):
        assert np.array_equal(getattr(resumed, k), getattr(ref, k)), k


def tilted_pad(
    order: int = 1, moment: float = 0.004, stiff: float = 1e4, steps: int = 1, **kw: Any
) -> Problem:
    """A pad 1 x 0.25 on a Winkler layer (p = r, no rigid layer reached), pressed by a
    holder on its top with the force P, free to turn, loaded by ``moment``; held in x
    by the holder, in y and in rotation by contact alone."""
    mesh = tag_rectangle(
        rectangle_squares((1.0, 0.25), (16, 4)),
        {"holder": "top", "free": ["left", "right"], "contact": "bottom"},
    )
    holder = RigidPart(
        "holder", force=(None, -P), translation=(0.0, None), rotation="free", moment=(moment,)
    )
    return Problem(
        mesh,
        Material(stiff, stiff),
        TimeGrid.uniform(1.0, steps),
        p=LinearCompliance(1.0),
        g=1.0,
        mu=0.0,
        kappa=0.5,
        v_star=(1.0, 0.0),
        clamped=(),
        rigid=(holder,),
        order=order,
        **kw,
    )


def contact_moment(res: Any, n: int, centre: np.ndarray) -> tuple[float, float]:
    """The resultant in y and the moment about ``centre`` of the layer's pressure on
    the body at level n (no friction: normal forces only)."""
    s = res.problem.discrete.system
    cb = res.problem.contact
    f = s.weights * (res.p_soft[n] + res.p_rigid[n])  # along -nu = +y on the bottom
    return float(f.sum()), float(((cb.points[:, 0] - centre[0]) * f).sum())


@pytest.mark.parametrize("order", [1, 2])
def test_a_turning_holder_balances_force_and_moment_and_tilts_the_pad(order: int) -> None:
    """The holder's rotation is free and loaded by M: the layer's pressure balances P
    and M exactly, the holder moves as one rigid body (translation of its centre and
    rotation), and on a pad much stiffer than the layer the pressure is the rigid
    punch's on a Winkler foundation, linear: p(x) = P / L - 12 M (x - x_0) / L^3."""
    M = 0.004
    pr = tilted_pad(order, M)
    res = simulate(pr, "newton")
    ties = pr.constraints.ties
    centre = ties.centres[0]
    assert np.allclose(centre, [0.5, 0.25])
    F, Mc = contact_moment(res, -1, centre)
    assert abs(F - P) <= 1e-12 * P
    assert abs(Mc + M) <= 1e-10 * P  # the pressure's moment about x_0 balances M
    # the holder is rigid: u = t + theta e_z x (x - x_0) at its vertices, exactly
    trans, theta = ties.motions(res.u[-1])
    top = np.abs(pr.mesh.points[:, 1] - 0.25) < 1e-12
    X = pr.mesh.points[top] - centre
    rigid = trans[0] + theta[0, 0] * np.column_stack([-X[:, 1], X[:, 0]])
    assert np.abs(res.u[-1][top] - rigid).max() <= 1e-12 * np.abs(res.u[-1]).max()
    assert abs(trans[0, 0]) <= 1e-15  # ux = 0 prescribed
    # before wear, with the layer's nodal quadrature w_i: p_i = P / sum(w) - M (x_i -
    # x_0) / I, I = sum(w (x - x_0)^2) (12 M / L^3 in the limit); a layer of stiffness
    # 1 tilts the punch by theta = M / I
    x = pr.contact.points[:, 0] - centre[0]
    w = pr.discrete.system.weights
    inertia = float((w * x**2).sum())
    winkler = P / w.sum() - M * x / inertia
    assert np.abs(res.p_soft[0] - winkler).max() <= 1e-3 * P
    theta0 = ties.motions(res.u[0])[1][0, 0]
    assert abs(theta0 - M / inertia) <= 1e-3 * M / inertia
    assert theta[0, 0] > theta0  # the worn side sinks further
    assert abs(inertia - 1 / 12) <= 0.01 / 12
    # the three solvers agree (on a pad as stiff as the layer: well conditioned)
    soft = tilted_pad(order, M, stiff=4.0, steps=2)
    ref = simulate(soft, "newton")
    for method in ("newton-full", "uzawa"):
        other = simulate(soft, method)
        assert np.abs(other.u - ref.u).max() <= 1e-9 * np.abs(ref.u).max(), method


def test_a_turning_holder_without_moment_on_a_symmetric_pad_does_not_turn() -> None:
    """With M = 0 and a symmetric pad the free rotation stays zero: the same solution
    as a holder whose rotation is fixed."""
    free = simulate(tilted_pad(moment=0.0, stiff=4.0), "newton")
    fixed_pr = tilted_pad(moment=0.0, stiff=4.0)
    holder = RigidPart("holder", force=(None, -P), translation=(0.0, None))
    fixed = simulate(replace(fixed_pr, rigid=(holder,)), "newton")
    assert np.abs(free.u - fixed.u).max() <= 1e-10 * np.abs(fixed.u).max()
    _, theta = free.problem.constraints.ties.motions(free.u[-1])
    assert abs(theta[0, 0]) <= 1e-12 * np.abs(free.u).max()


def test_a_turning_holder_in_3d_balances_force_and_both_moments() -> None:
    """3D: a block pressed by a holder that tilts (free about x and y, not about z)
    with moments about x and y; the layer's pressure balances the force and the two
    moments about the holder's centre. Free about z too, nothing would hold it."""
    mesh = tag_box(
        box_hexahedra((1.0, 1.0, 0.25), (6, 6, 2)),
        {"contact": "zmin", "holder": "zmax", "free": ["xmin", "xmax", "ymin", "ymax"]},
    )
    Mx, My = 0.002, -0.003
    holder = RigidPart(
        "holder",
        force=(None, None, -P),
        translation=(0.0, 0.0, None),
        rotation=("free", "free", "fixed"),
        moment=(Mx, My, None),
    )
    pr = Problem(
        mesh,
        Material(100.0, 100.0),
        TimeGrid.uniform(1.0, 1),
        p=LinearCompliance(1.0),
        g=1.0,
        mu=0.0,
        kappa=0.5,
        v_star=(1.0, 0.0, 0.0),
        clamped=(),
        rigid=(holder,),
    )
    res = simulate(pr, "newton")
    s = pr.discrete.system
    c = pr.constraints.ties.centres[0]
    f = s.weights * (res.p_soft[-1] + res.p_rigid[-1])  # along +z on the bottom face
    X = pr.contact.points - c
    assert abs(f.sum() - P) <= 1e-12 * P
    # moments of the forces f e_z at X about the centre: (X_y f, -X_x f, 0)
    assert abs((X[:, 1] * f).sum() + Mx) <= 1e-10 * P
    assert abs(-(X[:, 0] * f).sum() + My) <= 1e-10 * P
    _, theta = pr.constraints.ties.motions(res.u[-1])
    assert theta[0, 0] * Mx > 0 and theta[0, 1] * My > 0  # it turns with the moments
    assert theta[0, 2] == 0.0
    with pytest.raises(MeshError, match=r"leave rigid motions free: the rotation about the axis"):
        replace(pr, rigid=(replace(holder, rotation="free"),))


def test_a_turning_holder_from_a_config_reports_its_rotation(tmp_path: Path) -> None:
    """``rotation = "free"`` and ``moment`` in ``[[boundary.rigid]]``: the run's summary
    gives the holder's centre, its translation and its rotation, which the vertex
    displacements of result.npz reproduce."""
    from vemwear.cli.main import main

    text = """
    [mesh]
    generator = "squares"
    size = [1.0, 0.5]
    divisions = [16, 8]
    [boundary]
    contact = "bottom"
    free = ["left", "right"]
    [[boundary.rigid]]
    name = "holder"
    on = "top"
    ux = 0.0
    fy = -0.06
    rotation = "free"
    moment = "0.004*t"
    [material]
    lam = 4.0
    eta = 4.0
    [contact]
    p = { type = "linear", c = 1.0 }
    g = 0.1
    mu = 0.0
    kappa = 0.5
    v_star = [1.0, 0.0]
    [time]
    T = 1.0
    steps = 4
    [output]
    figures = false
    vtk = false
    """
    cfg = tmp_path / "turning.toml"
    cfg.write_text(textwrap.dedent(text))
    out = tmp_path / "out"
    assert main(["run", str(cfg), "-o", str(out), "--no-progress"]) == 0
    holder = json.loads((out / "summary.json").read_text())["outputs"]["rigid_parts"]["holder"]
    assert holder["centre"] == [0.5, 0.5]
    (theta,) = holder["rotation_final"]
    tx, ty = holder["translation_final"]
    with np.load(out / "result.npz") as z:
        pts, u = z["points"], z["u"][-1]
    top = np.abs(pts[:, 1] - 0.5) < 1e-12
    X = pts[top] - [0.5, 0.5]
    rigid = np.array([tx, ty]) + theta * np.column_stack([-X[:, 1], X[:, 0]])
    assert np.abs(u[top] - rigid).max() <= 1e-12 * np.abs(u).max()
    assert theta > 0 and abs(tx) <= 1e-15  # a counter-clockwise moment turns it so
    # every kept level (t > 0: the moment 0.004 t turns the holder counter-clockwise)
    assert holder["t"][-1] == 1.0 and len(holder["t"]) >= 3
    assert holder["rotation"][-1] == [theta] and holder["translation"][-1] == [tx, ty]
    assert len(holder["rotation"]) == len(holder["t"]) and min(holder["rotation"])[0] > 0
    bad = cfg.read_text().replace('rotation = "free"', 'rotation = ["free", "free", "fixed"]')
    cfg.write_text(bad)
    assert main(["check", str(cfg)]) == 2
