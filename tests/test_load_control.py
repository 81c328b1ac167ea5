"""Load control: bodies held in the normal direction by contact alone (docs/method.md 1c).

A pad pressed by a traction on a linear soft layer is the closed form of the flat pin:
the pressure is P/A at every contact node and the wear grows by k kappa |v*| P/A a
level. The condensed and the full-space Newton agree, the contact forces balance the
load, and a load that pulls the body off the foundation stops the run naming the level.
"""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import pytest

from vemwear import (
    LinearCompliance,
    Material,
    Problem,
    TimeGrid,
    rectangle_squares,
    simulate,
    tag_rectangle,
)
from vemwear.mesh.generate3d import box_hexahedra, tag_box
from vemwear.simulate.constraints import Prescribed
from vemwear.solvers.system import ConvergenceError

W, H, P = 1.0, 0.5, 0.06  # pad width and height, load per unit width
C, G, KAPPA = 1.0, 0.1, 0.5  # soft layer: P / C = 0.06 < g, the rigid layer not reached


def pad(mu: float = 0.0, order: int = 1, f2: Any = (0.0, -P), steps: int = 8) -> Problem:
    """A pad on rollers (u_x = 0 on its sides), the traction f2 on top, contact below."""
    mesh = tag_rectangle(
        rectangle_squares((W, H), (16, 8)),
        {"rollers": ["left", "right"], "traction": "top", "contact": "bottom"},
    )
    return Problem(
        mesh,
        Material(lam=4.0, eta=4.0),
        TimeGrid.uniform(T=1.0, steps=steps),
        f2=f2,
        p=LinearCompliance(C),
        g=G,
        mu=mu,
        kappa=KAPPA,
        v_star=(1.0, 0.0),
        clamped=(),
        displacement=(Prescribed("rollers", ux=0.0),),
        order=order,
    )


def tilting_pad(mu: float) -> Problem:
    """A pad held only in x along its top (u_x = 0 there): it may move down and turn
    about any point of its top, which contact resists; the load is off-centre."""
    mesh = tag_rectangle(
        rectangle_squares((W, H), (16, 8)),
        {"holder": "top", "free": ["left", "right"], "contact": "bottom"},
    )
    return Problem(
        mesh,
        Material(lam=4.0, eta=4.0),
        TimeGrid.uniform(T=1.0, steps=8),
        f1=lambda x, t: np.column_stack([np.zeros(len(x)), np.where(x[:, 0] > 0.6, -0.3, -0.02)]),
        p=LinearCompliance(C),
        g=G,
        mu=mu,
        kappa=KAPPA,
        v_star=(1.0, 0.0),
        clamped=(),
        displacement=(Prescribed("holder", ux=0.0),),
    )


def balance(res: Any) -> float:
    """The largest resultant of all forces on the body (contact, reactions, load) over
    the load, at every kept level."""
    pr = res.problem
    worst = 0.0
    for n in range(len(res.t)):
        F = pr.external_load(float(res.t[n]))
        load = F.reshape(-1, pr.dim)[: pr.mesh.n_points].sum(axis=0) if pr.order == 1 else None
        if load is None:  # k = 2: sum the components of all dofs
            load = np.array([F[c :: pr.dim].sum() for c in range(pr.dim)])
        total = res.forces[n].sum(axis=0) + load
        worst = max(worst, float(np.abs(total).max() / np.abs(load).max()))
    return worst


@pytest.mark.parametrize("order", [1, 2])
def test_flat_pad_pressure_and_wear_closed_form(order: int) -> None:
    pr = pad(order=order)
    assert pr.rigid_basis.shape == (1, 3)  # the translation in y, held by contact
    res = simulate(pr, "newton")
    k = 1.0 / 8
    assert np.abs(res.p_soft - P / W).max() <= 1e-10 * P
    n = np.arange(len(res.t))[:, None]
    assert np.abs(res.wear - n * k * KAPPA * 1.0 * P / W).max() <= 1e-13
    assert np.all(res.p_rigid == 0)
    assert balance(res) <= 1e-12
    full = simulate(pr, "newton-full")
    assert np.abs(full.u - res.u).max() <= 1e-9 * np.abs(res.u).max()
    assert np.abs(full.wear - res.wear).max() <= 1e-9 * res.wear.max()


@pytest.mark.parametrize("mu", [0.0, 0.3])
def test_tilting_pad_solvers_agree_and_forces_balance(mu: float) -> None:
    pr = tilting_pad(mu)
    assert pr.rigid_basis.shape == (2, 3)  # down and the rotation about the top
    res = simulate(pr, "newton")
    full = simulate(pr, "newton-full")
    assert res.residuals.max() <= 1e-10 and full.residuals.max() <= 1e-10
    assert np.abs(full.u - res.u).max() <= 1e-9 * np.abs(res.u).max()
    assert np.abs(full.wear - res.wear).max() <= 1e-9 * res.wear.max()
    assert balance(res) <= 1e-12 and balance(full) <= 1e-12
    # the off-centre load tilts the pad: the right end is pressed harder
    assert res.p_soft[0][res.contact_points[:, 0].argmax()] > 2 * res.p_soft[0].min()


def test_block_in_3d_on_rollers_is_pressed_uniformly() -> None:
    mesh = tag_box(
        box_hexahedra((1.0, 1.0, 0.5), (4, 4, 2)),
        {"contact": "zmin", "top": "zmax", "sx": ["xmin", "xmax"], "sy": ["ymin", "ymax"]},
    )
    pr = Problem(
        mesh,
        Material(lam=4.0, eta=4.0),
        TimeGrid.uniform(T=1.0, steps=4),
        f2={"top": (0.0, 0.0, -P)},
        p=LinearCompliance(C),
        g=G,
        mu=0.0,
        kappa=KAPPA,
        v_star=(1.0, 0.0, 0.0),
        clamped=(),
        displacement=(Prescribed("sx", ux=0.0), Prescribed("sy", uy=0.0)),
    )
    assert pr.rigid_basis.shape == (1, 6)
    res = simulate(pr, "newton")
    assert np.abs(res.p_soft - P).max() <= 1e-10 * P
    full = simulate(pr, "newton-full")
    assert np.abs(full.u - res.u).max() <= 1e-9 * np.abs(res.u).max()


def test_a_load_that_pulls_off_stops_the_run_naming_the_level() -> None:
    pr = pad(f2=lambda x, t: np.column_stack([0 * x[:, 0], -P * np.cos(np.pi * t) + 0 * x[:, 0]]))
    for method in ("newton", "newton-full", "uzawa"):
        with pytest.raises(
            ConvergenceError,
            match=r"pulls the body off the foundation at time "
            r"level 5 .*'contact'.*translation in y",
        ):
            simulate(pr, method)


@pytest.mark.parametrize("mu", [0.0, 0.3])
def test_uzawa_agrees_under_load_control(mu: float) -> None:
    """Uzawa with the outer iteration on the rigid amplitudes (docs/method.md 1c)."""
    pr = dataclasses.replace(tilting_pad(mu), time=TimeGrid.uniform(T=1.0, steps=3))
    ref, uz = simulate(pr, "newton"), simulate(pr, "uzawa")
    assert uz.residuals.max() <= 1e-10
    assert np.abs(uz.u - ref.u).max() <= 1e-9 * np.abs(ref.u).max()
    assert np.abs(uz.wear - ref.wear).max() <= 1e-9 * ref.wear.max()
    flat = simulate(pad(steps=3), "uzawa")
    assert np.abs(flat.p_soft - P / W).max() <= 1e-9 * P


def test_cli_keeps_the_levels_before_the_load_pulls_off(tmp_path: Path) -> None:
    cfg = tmp_path / "pad.toml"
    cfg.write_text(
        """
[mesh]
generator = "squares"
size = [1.0, 0.5]
divisions = [8, 4]

[boundary]
contact = "bottom"
traction = "top"

[[boundary.displacement]]
name = "rollers"
on = ["left", "right"]
ux = 0.0

[material]
lam = 4.0
eta = 4.0

[loads]
f2 = [0.0, "-0.06*cos(pi*t)"]

[contact]
p = { type = "linear", c = 1.0 }
g = 0.1
mu = 0.0
kappa = 0.5
v_star = [1.0, 0.0]

[time]
T = 1.0
steps = 8

[output]
figures = false
vtk = false
"""
    )
    out = tmp_path / "out"
    run = subprocess.run(
        [sys.executable, "-m", "vemwear", "run", str(cfg), "-o", str(out)],
        capture_output=True,
        text=True,
    )
    assert run.returncode == 3, run.stderr
    assert "pulls the body off the foundation at time level 5" in run.stderr
    assert "the 5 finished time levels (of 9) are saved" in run.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["partial"] is True and summary["completed"] == 5
    with h5py.File(out / "result.h5") as f:
        wear = np.asarray(f["wear"])
    # the wear of the finished levels: the pressure P cos(pi t_n) / A, level by level
    t = np.arange(5) / 8
    expected = np.concatenate([[0.0], np.cumsum(0.5 * 0.06 * np.cos(np.pi * t[:4]) / 8)])
    assert np.abs(wear[:5] - expected[:, None]).max() < 1e-12


def test_signorini_pad_rests_on_the_rigid_layer() -> None:
    """No soft layer (p = 0, a thin g): the rigid layer alone carries P / A; Newton
    starts with every node on it (docs/method.md section 1c)."""
    pr = dataclasses.replace(pad(), p=LinearCompliance(0.0), g=1e-3, kappa=0.0)
    for method in ("newton", "newton-full"):
        res = simulate(pr, method)
        assert np.abs(res.p_rigid - P / W).max() <= 1e-10 * P
        assert np.all(res.p_soft == 0) and balance(res) <= 1e-12
