"""Rigid parts: a holder that presses a pad with a force resultant (docs/method.md 1d)."""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
import pytest

from vemwear import LinearCompliance, Material, Problem, TimeGrid, simulate
from vemwear.config import ConfigError, parse_config
from vemwear.mesh import rectangle_squares, select_parts, tag_rectangle
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
        ({"rotation": "free"}, r"rotation = 'free' is not available"),
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


@pytest.mark.parametrize("method", ["newton", "uzawa"])
@pytest.mark.parametrize("level", [0, 3, 6])
def test_a_holders_run_resumes_bitwise(method: str, level: int) -> None:
    """Load control with a holder and a ramped load, two contact parts with their own
    data and a gap: a run stopped at a level resumes to the same arrays, bitwise."""
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
                "holder", force=(None, lambda t: -P * min(t / 0.25, 1.0)), translation=(0.0, None)
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
