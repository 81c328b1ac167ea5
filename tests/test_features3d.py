"""The configuration features that have a meaning in 3D, on 4 x 2 x 2 hexahedra with 8
steps, through the Python API (`parse_config` + `simulate`) and `vemwear run`: initial
gaps, several contact parts, prescribed displacements without a clamped part, traction
tables, a reciprocating foundation with cycle jumps, `[output] store_u` and `every`
with `--resume`."""

from __future__ import annotations

import copy
import dataclasses
import tomllib
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from conftest import CONFIG_3D, npz_arrays
from vemwear.cli.main import main
from vemwear.config import ConfigError, parse_config
from vemwear.simulate import TimeGrid, simulate
from vemwear.simulate.cycles import CycleJump, simulate_cycles
from vemwear.vem.space import has_part

BASE = CONFIG_3D + "figures = false\nvtk = false\n"


def base() -> dict[str, Any]:
    return tomllib.loads(BASE)


def run(data: dict[str, Any]) -> Any:
    cfg = parse_config(copy.deepcopy(data))
    return cfg, simulate(cfg.problem, cfg.solver)


# ----------------------------------------------------------------------------- 1. gap
@pytest.mark.parametrize("gap", [0.002, "0.001*(1 + x) + 0.002*y"], ids=["number", "expr"])
def test_initial_gap(gap: float | str) -> None:
    d = base()
    d["contact"]["gap"] = gap
    cfg, res = run(d)
    cb = cfg.problem.contact
    x, y = cb.points[:, 0], cb.points[:, 1]
    want = 0.002 if isinstance(gap, float) else 0.001 * (1 + x) + 0.002 * y
    assert np.allclose(cfg.problem.nodal["gap"], want, rtol=0, atol=1e-15)
    assert np.array_equal(res.penetration, res.u_nu - cfg.problem.nodal["gap"] - res.wear)
    # the gap delays the contact: less wear than without
    _, ref = run(base())
    assert 0 < res.wear[-1].max() < ref.wear[-1].max()


def test_gap_zero_is_bitwise_the_default() -> None:
    _, ref = run(base())
    d = base()
    d["contact"]["gap"] = 0.0
    _, res = run(d)
    for k in ("u", "wear", "u_nu", "p_soft", "p_rigid", "penetration"):
        assert np.array_equal(getattr(res, k), getattr(ref, k)), k


# ----------------------------------------------------------------------------- 2. parts
def test_two_contact_parts_and_normal_motion_does_not_wear() -> None:
    """Contact on zmin (sliding along x) and on xmax, which the same foundation velocity
    (1, 0, 0) meets normally: no friction and no wear on xmax, though it is pressed."""
    d = base()
    d["boundary"] = {"clamped": "xmin", "free": "rest"}
    d["loads"]["f1"] = [0.06, 0.0, -0.06]
    common = {"p": {"type": "linear", "c": 0.4}, "g": 0.1, "v_star": [1.0, 0.0, 0.0]}
    d["contact"] = [
        {"name": "bottom", "on": "zmin", "mu": 0.2, "kappa": 2.0, **common},
        {"name": "end", "on": "xmax", "mu": 0.3, "kappa": 5.0, **common},
    ]
    cfg, res = run(d)
    pr = cfg.problem
    assert [pc.part for pc in pr.parts] == ["bottom", "end"]
    cb = pr.contact
    end = np.asarray(cb.part == 1)
    bottom = np.asarray(cb.part == 0)
    assert end.any() and bottom.any()
    assert np.allclose(cb.points[end, 0], 2.0) and np.allclose(cb.points[bottom, 2], 0.0)
    assert np.allclose(pr.nodal["mu"][end], 0.3) and np.allclose(pr.nodal["kappa"][end], 5.0)
    assert res.p_soft[-1][end].max() > 0  # pressed against xmax
    assert np.all(res.wear[:, end] == 0.0)  # v* normal to xmax: no wear at all
    assert res.wear[-1][bottom].max() > 0
    # the force of the xmax layer is normal: no friction along y or z
    rows = [i for i, (name, _) in enumerate(res.force_parts) if name == "end"]
    assert rows and res.forces is not None
    F = res.forces[:, rows[0]]
    assert np.abs(F[:, 0]).max() > 0 and np.abs(F[:, 1:]).max() < 1e-14


# ----------------------------------------------------------------------------- 3. rollers
def rollers(top: bool) -> dict[str, Any]:
    d = base()
    disp: list[dict[str, Any]] = [
        {"name": "rx", "on": ["xmin", "xmax"], "ux": 0.0},
        {"name": "ry", "on": ["ymin", "ymax"], "uy": 0.0},
    ]
    if top:
        disp.append({"name": "top", "on": "zmax", "uz": "-0.01*t"})
    d["boundary"] = {"contact": "zmin", "displacement": disp}
    if not top:
        d["boundary"]["free"] = "zmax"
    d["contact"]["v_star"] = [0.0, 1.0, 0.0]
    return d


def test_displacement_controlled_top_with_rollers() -> None:
    cfg, res = run(rollers(top=True))
    pr = cfg.problem
    assert not has_part(pr.mesh, "clamped")
    P = pr.mesh.points
    top = P[:, 2] == 1.0
    t = res.t[res.u_levels]
    assert np.allclose(res.u[:, top, 2], -0.01 * t[:, None], atol=1e-15)
    assert np.all(res.u[:, P[:, 0] == 0.0, 0] == 0) and np.all(res.u[:, P[:, 1] == 1.0, 1] == 0)
    assert res.p_soft[-1].max() > 0 and res.wear[-1].max() > 0


def test_too_few_constraints_name_the_rigid_motion() -> None:
    # rollers on the sides and a free top: contact on zmin holds the body along z (load
    # control); without the rollers on the y sides nothing holds it along y
    assert parse_config(rollers(top=False)).problem.rigid_basis.shape == (1, 6)
    d = rollers(top=False)
    d["boundary"]["displacement"] = d["boundary"]["displacement"][:1]
    d["boundary"]["free"] = ["zmax", "ymin", "ymax"]
    with pytest.raises(ConfigError, match=r"translation along \(0, 1, 0\)"):
        parse_config(d)


# ----------------------------------------------------------------------------- 4. tractions
@pytest.mark.parametrize(
    "f2",
    [[0.0, 0.01, -0.02], ["0.01*x", "0", "-0.02*(1 + y + z)*t"]],
    ids=["numbers", "expressions"],
)
def test_traction_tables(f2: list[Any]) -> None:
    d = base()
    d["boundary"] = {
        "clamped": "xmin",
        "contact": "zmin",
        "free": "rest",
        "traction": [{"name": "top", "on": "zmax", "f2": f2}],
    }
    cfg, res = run(d)
    pr = cfg.problem
    assert set(pr.tractions) == {"top"}
    # the resultant of the traction on zmax (the face [0, 2] x [0, 1]) at t = 1
    face = 2.0 * 1.0
    t1 = 1.0
    if isinstance(f2[0], float):
        want = np.array(f2) * face
    else:  # integrals over [0, 2] x [0, 1] at z = 1: x -> 2, 1 + y + z -> 2 + 0.5 = 2.5
        want = np.array([0.01 * 2.0, 0.0, -0.02 * 2.5 * face * t1])
    F = res.forces
    assert F is not None
    # equilibrium at the final level: layer + clamp reactions + body force + traction = 0
    body = np.array([0.0, 0.0, -0.06]) * 2.0
    assert np.abs(F[-1].sum(axis=0) + body + want).max() < 1e-10
    _, ref = run(base())
    assert not np.array_equal(res.u[-1], ref.u[-1])


# ----------------------------------------------------------------------------- 5. cycles
def reciprocating() -> dict[str, Any]:
    d = base()
    d["contact"]["v_star"] = ["cos(2*pi*t)", 0.0, 0.0]
    return d


def test_reciprocating_foundation_zero_levels_no_wear() -> None:
    """v* = (cos 2 pi t, 0, 0) on 8 steps: levels 2 and 6 are zeros of v* (to round-off,
    |cos| ~ 1e-16); accepted, and the wear does not grow over those steps."""
    _, res = run(reciprocating())
    assert np.allclose(res.t[[2, 6]], [0.25, 0.75])
    dw = np.diff(res.wear, axis=0)
    assert np.abs(dw[[2, 6]]).max() < 1e-17
    assert np.all(dw[[0, 1, 3, 4, 5, 7]].max(axis=1) > 0)
    assert res.forces is not None and np.abs(res.forces[1, 0, 0]) > 0  # friction, v* != 0


def test_reciprocating_foundation_zero_levels_no_friction() -> None:
    """cos(2 pi t) evaluates to about 1e-16 at t = 1/4 and 3/4: round-off of a zero
    gives no friction (not the full friction in the direction of its sign)."""
    _, res = run(reciprocating())
    F = res.forces
    assert F is not None
    # the tangential force of the layer at the zeros of v*
    assert np.abs(F[[2, 6], 0, :2]).max() < 1e-14, F[[2, 6], 0]


def test_cycle_jump_3d() -> None:
    d = reciprocating()
    d["time"]["cycle_jump"] = {"period": 1.0, "cycles": 10, "jump": 5}
    cfg = parse_config(copy.deepcopy(d))
    assert cfg.cycles is not None and cfg.cycles.jump == 5
    one = cfg.problem
    jumped = simulate_cycles(one, cfg.cycles, cfg.solver)
    assert sum(jumped.jumps) == 10
    whole = dataclasses.replace(one, time=TimeGrid.uniform(10.0, 80))
    ref = simulate(whole, cfg.solver, store="final").wear[-1]
    every = simulate_cycles(one, CycleJump(10, 1), cfg.solver)
    assert len(every.computed) == 10
    assert np.abs(every.wear[-1] - ref).max() <= 1e-14 * ref.max()
    # the extrapolation over 10 cycles with jumps of 5 (the layer is nearly worn through)
    assert np.all(jumped.wear[-1] > 0) and np.abs(jumped.wear[-1] - ref).max() < 0.2 * ref.max()
    d["time"]["cycle_jump"]["period"] = 2.0
    with pytest.raises(ConfigError, match="period"):
        parse_config(d)


def test_cycle_jump_3d_run(tmp_path: Path) -> None:
    text = BASE.replace("v_star = [1.0, 0.0, 0.0]", 'v_star = ["cos(2*pi*t)", 0.0, 0.0]')
    text = text.replace(
        "steps = 8", "steps = 8\ncycle_jump = { period = 1, cycles = 10, jump = 5 }"
    )
    out = tmp_path / "out"
    assert main(["run", str(write(tmp_path, text)), "-o", str(out), "--no-progress"]) == 0
    with np.load(out / "cycles.npz") as z:
        assert z["cycle"][-1] == 10 and z["wear"].shape[1] == 12
    assert npz_arrays(out)["u"].shape[-1] == 3


# ----------------------------------------------------------------------------- 6. output
def write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "c.toml"
    p.write_text(text)
    return p


@pytest.mark.parametrize(
    ("store", "levels"),
    [('"all"', list(range(9))), ('"final"', [8]), ("[0.25, 0.5]", [2, 4, 8]), ("3", [0, 3, 6, 8])],
)
def test_store_u_and_every(tmp_path: Path, store: str, levels: list[int]) -> None:
    text = BASE + f"store_u = {store}\nevery = 4\n"
    out = tmp_path / "out"
    assert main(["run", str(write(tmp_path, text)), "-o", str(out), "--no-progress"]) == 0
    a = npz_arrays(out)
    assert a["u"].shape == (len(levels), 45, 3)
    assert list(a["levels"][a["u_levels"]]) == levels
    kept = sorted({0, 4, 8} | set(levels))
    assert list(a["levels"]) == kept and a["wear"].shape == (len(kept), 12)


def test_resume_with_store_u_and_every(tmp_path: Path, stop_at: Callable[..., None]) -> None:
    cfg = write(tmp_path, BASE + "store_u = 2\nevery = 3\ncheckpoint = 0\n")
    ref = tmp_path / "ref"
    assert main(["run", str(cfg), "-o", str(ref), "--no-progress"]) == 0
    out = tmp_path / "out"
    stop_at(5)
    assert main(["run", str(cfg), "-o", str(out), "--no-progress"]) == 3
    stop_at(None)
    assert main(["run", str(cfg), "-o", str(out), "--no-progress", "--resume"]) == 0
    a, b = npz_arrays(ref), npz_arrays(out)
    assert list(a["levels"][a["u_levels"]]) == [0, 2, 4, 6, 8]
    for k in ("u", "u_levels", "levels", "wear", "u_nu", "p_soft", "iterations", "forces"):
        assert np.array_equal(a[k], b[k]), k
