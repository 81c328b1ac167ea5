"""The shipped example configurations: in the package, run at a small size, overrides."""

from __future__ import annotations

import tomllib
from importlib.resources import files
from pathlib import Path

import numpy as np
import pytest

from vemwear.config import ConfigError, apply_overrides, parse_config
from vemwear.examples import config_path, configs
from vemwear.simulate import SolverOptions, simulate

ROOT = Path(__file__).resolve().parents[1]

#: Overrides that make each mesh family of the shipped files small.
SMALL: dict[str, dict[str, object]] = {
    "squares": {"mesh.divisions": [8, 4], "time.steps": 4},
    "voronoi": {"mesh.n_cells": 32, "time.steps": 4},
    "hexahedra": {"mesh.divisions": [4, 4, 2], "time.steps": 4},
}


def _data(name: str) -> dict[str, object]:
    return tomllib.loads(config_path(name).read_text(encoding="utf-8"))


# ----------------------------------------------------------------------------- shipped
def test_the_configs_are_package_data() -> None:
    """Found through importlib.resources: in CI the tests import the installed wheel."""
    names = list(configs())
    assert names == sorted(names) and {
        "example_5_2_set1",
        "example_5_2_set2",
        "example_5_2_set3",
        "example_5_4_voronoi",
    } <= set(names)
    for name, f in configs().items():
        assert f.is_file() and tomllib.loads(f.read_text(encoding="utf-8"))["title"], name
        assert config_path(name + ".toml") == config_path(name)
    assert (files("vemwear") / "py.typed").is_file()
    assert (files("vemwear") / "__init__.pyi").is_file()
    with pytest.raises(
        KeyError, match="available: ball_on_flat, block_displacement, example_3d, example_5_2"
    ):
        config_path("example_9")


def test_pyproject_ships_every_config_and_the_marker() -> None:
    """The package-data globs of pyproject.toml cover every shipped file (the wheel's)."""
    with (ROOT / "pyproject.toml").open("rb") as fh:
        globs = tomllib.load(fh)["tool"]["setuptools"]["package-data"]["vemwear"]
    pkg = ROOT / "src" / "vemwear"
    shipped = {p.relative_to(pkg) for g in globs for p in pkg.glob(g)}
    wanted = {p.relative_to(pkg) for g in ("*.toml", "*.msh") for p in (pkg / "examples").glob(g)}
    assert wanted and wanted <= shipped
    assert Path("py.typed") in shipped and Path("__init__.pyi") in shipped
    assert not list((ROOT / "examples").glob("*.toml"))  # one copy of each file


PAPER = [n for n in configs() if n.startswith("example_")]


@pytest.mark.parametrize("name", PAPER)
def test_every_config_runs_at_a_small_size(name: str) -> None:
    data = _data(name)
    generator = data["mesh"]["generator"]  # type: ignore[index]
    assert generator in SMALL, f"{name}: add a small size for generator {generator!r}"
    small = apply_overrides(data, {**SMALL[generator], "solver.backend": "scipy"})
    cfg = parse_config(small, source=name)
    mesh = cfg.problem.mesh
    assert mesh.n_cells == 32 and len(cfg.problem.time.t) == 5
    res = simulate(cfg.problem, cfg.solver, store="final")
    assert res.residuals.max() <= cfg.solver.tol
    assert np.all(res.wear[-1] >= 0) and res.wear[-1].max() > 0
    assert cfg.output.times == (0.25, 0.5, 0.75, 1.0)


# ----------------------------------------------------------------------------- overrides
def test_overrides_set_keys_on_a_copy() -> None:
    data = _data("example_5_2_set1")
    out = apply_overrides(
        data,
        {
            "time.steps": 8,
            "mesh.divisions": (8, 4),
            "contact.p.c": 0.5,
            "solver.max_iter": 20,
            "output.vtk": False,
        },
    )
    assert out["time"] == {"T": 1.0, "steps": 8} and out["mesh"]["divisions"] == [8, 4]
    assert out["contact"]["p"] == {"type": "linear", "c": 0.5}
    assert out["solver"]["max_iter"] == 20 and out["output"]["vtk"] is False
    assert data["time"]["steps"] == 64 and data["mesh"]["divisions"] == [32, 16]  # untouched
    cfg = parse_config(out, source="o")
    assert cfg.problem.mesh.n_cells == 32 and cfg.solver == SolverOptions(max_iter=20)
    # a missing section is created; a later key sees an earlier change of form
    bare = {k: v for k, v in data.items() if k != "solver"}
    assert apply_overrides(bare, {"solver.tol": 1e-8})["solver"] == {"tol": 1e-8}
    vor = apply_overrides(data, {"mesh.generator": "voronoi", "mesh.n_cells": 64})
    assert vor["mesh"]["n_cells"] == 64


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (
            {"time.stesp": 3},
            r"'time.stesp': \[time\] in its 'steps' form has no key 'stesp'; "
            r"did you mean 'steps'\?",
        ),
        ({"materal.lam": 1.0}, "the configuration has no key 'materal'; did you mean 'material'"),
        ({"mesh.n_cells": 32}, r"\[mesh\] in its 'squares' form has no key 'n_cells'; valid"),
        ({"contact.p.r": [0.0]}, r"\[contact\] p in its 'linear' form has no key 'r'"),
        ({"contact.mu.at": [0.0]}, r"\[contact\] mu is a value, not a table"),
        ({"time..steps": 3}, "is not a dotted key path"),
    ],
)
def test_overrides_name_paths_the_schema_does_not_have(
    overrides: dict[str, object], message: str
) -> None:
    with pytest.raises(ConfigError, match=message):
        apply_overrides(_data("example_5_2_set1"), overrides)


def test_overrides_of_a_voronoi_config_follow_its_generator() -> None:
    data = _data("example_5_4_voronoi")
    with pytest.raises(ConfigError, match=r"'voronoi' form has no key 'divisions'"):
        apply_overrides(data, {"mesh.divisions": [8, 4]})
    assert apply_overrides(data, {"mesh.seed": 3})["mesh"]["seed"] == 3


# ----------------------------------------------------------------------------- beyond the paper
def _beyond(name: str, **overrides: object):
    """A shipped example beyond the paper, validated with overrides."""
    data = apply_overrides(_data(name), {"time.steps": 8, **overrides})
    return parse_config(data, source=name, base_dir=config_path(name).parent)


def test_displacement_controlled_block_follows_its_closed_form() -> None:
    """The shipped block: contact starts at t0 = gap / rate; the discrete wear is the
    left-rectangle recursion of the uniaxial field, to round-off."""
    cfg = _beyond("block_displacement")
    res = simulate(cfg.problem, cfg.solver, store="final")
    c, lam, eta, H, kappa, gap, rate = 0.4, 4.0, 4.0, 1.0, 2.0, 0.02, 0.08
    M = lam + 2 * eta
    ks = c * M / (M + c * H)
    t = res.t
    w = np.zeros(len(t))
    for n in range(len(t) - 1):
        w[n + 1] = w[n] + (t[n + 1] - t[n]) * kappa * ks * max(rate * t[n] - gap - w[n], 0.0)
    assert np.abs(res.wear - w[:, None]).max() < 1e-14
    assert res.forces is not None and np.abs(res.forces[-1].sum(axis=0)).max() < 1e-12


def test_punch_from_a_gmsh_file_wears_under_its_lowest_point() -> None:
    from vemwear.mesh import read_mesh

    assert read_mesh(config_path("punch").parent / "punch.msh").parts == ("arc", "sides", "top")
    cfg = _beyond("punch")  # the file's groups become the config's parts, by name
    assert cfg.problem.mesh.parts == ("contact", "free", "press")
    res = simulate(cfg.problem, cfg.solver, store="final")
    assert res.residuals.max() <= cfg.solver.tol
    assert np.allclose(res.contact_points[np.argmax(res.wear[-1])], [0.0, 0.0])
    assert res.wear[-1][np.abs(res.contact_points[:, 0]) > 0.4].max() == 0.0  # no contact
    assert res.forces is not None and np.abs(res.forces[-1].sum(axis=0)).max() < 1e-12


def test_fretting_runs_its_cycles_through_the_command_line(tmp_path: Path) -> None:
    """vemwear run with [time] cycle_jump: cycles.npz read back, the scar grows."""
    from vemwear.cli.main import main

    text = config_path("fretting").read_text(encoding="utf-8")
    text = text.replace(
        'file = "punch.msh"', f'file = "{config_path("punch").parent / "punch.msh"}"'
    )
    text = text.replace("steps = 16", "steps = 8")
    text = text.replace("cycles = 100, jump = 10", "cycles = 6, jump = 2")
    cfg = tmp_path / "fretting.toml"
    cfg.write_text(text + "vtk = false\n")
    assert main(["run", str(cfg), "-o", str(tmp_path / "out"), "--no-progress"]) == 0
    with np.load(tmp_path / "out" / "cycles.npz") as z:
        assert z["cycle"][0] == 0 and z["cycle"][-1] == 6
        wear = z["wear"]
    assert np.all(np.diff(wear.max(axis=1)) > 0)
    assert (tmp_path / "out" / "wear_by_cycle.png").is_file()


# ----------------------------------------------------------------------------- tribometers
def test_ball_on_flat_wears_a_scar_under_its_holders_load() -> None:
    """The shipped ball on flat, small: the holder's force is the ramped dead load, the
    contact forces balance it, the scar is deepest under the ball's lowest point."""
    cfg = _beyond("ball_on_flat", **{"mesh.divisions": [8, 8, 4], "time.steps": 8})
    pr = cfg.problem
    assert pr.rigid_basis.shape == (1, 6)  # held along z by contact alone
    res = simulate(pr, cfg.solver, store="final")
    assert res.residuals.max() <= cfg.solver.tol
    load = 0.02 * np.minimum(res.t / 0.1, 1.0)
    assert np.abs(res.forces[:, -1, 2] + load).max() <= 1e-14
    assert np.abs(res.forces.sum(axis=1)).max() <= 1e-12 * 0.02
    assert np.allclose(res.contact_points[np.argmax(res.wear[-1])], [0.0, 0.0, 0.0])


def test_fretting_cylinder_runs_its_cycles_under_load_control(tmp_path: Path) -> None:
    from vemwear.cli.main import main

    text = config_path("fretting_cylinder").read_text(encoding="utf-8")
    text = text.replace("divisions = [64, 32]", "divisions = [16, 8]")
    text = text.replace("steps = 16", "steps = 8")
    text = text.replace("cycles = 200, jump = 20", "cycles = 6, jump = 2")
    cfg = tmp_path / "fretting_cylinder.toml"
    cfg.write_text(text + "vtk = false\nfigures = false\n")
    assert main(["run", str(cfg), "-o", str(tmp_path / "out"), "--no-progress"]) == 0
    with np.load(tmp_path / "out" / "cycles.npz") as z:
        wear = z["wear"]
    assert np.all(np.diff(wear.max(axis=1)) > 0)
    with np.load(tmp_path / "out" / "result.npz") as z:
        assert np.abs(z["forces"][:, -1, 1] + 0.05).max() <= 1e-14


def test_pin_on_disc_wears_faster_on_the_outer_side() -> None:
    """The shipped pin on a turning disc, a few levels: the holder carries the dead load
    and friction, the outer side (farther from the disc's axis) wears faster."""
    cfg = _beyond("pin_on_disc", **{"time.steps": 8})
    assert [r.part for r in cfg.problem.rigid] == ["holder"]
    res = simulate(cfg.problem, cfg.solver, store="final")
    assert res.residuals.max() <= cfg.solver.tol
    assert np.abs(res.forces.sum(axis=1)).max() <= 1e-12 * 0.02
    assert np.abs(res.forces[:, -1, 2] + 0.02 * np.minimum(res.t / 0.1, 1.0)).max() <= 1e-14
    x = res.contact_points[:, 0]
    w = res.wear[-1]
    assert w[x > 0.2].mean() > 1.1 * w[x < -0.2].mean()


# ----------------------------------------------------------------------------- gallery
GALLERY = ROOT / "docs" / "gallery"

#: Each gallery script (docs/gallery, executed when the documentation site is built)
#: pins one number: script -> (global name, value, relative tolerance).
PINNED: dict[str, tuple[str, float, float]] = {
    "plot_example_5_2.py": ("max_wear_set2", 0.0989606172, 1e-6),
    "plot_example_5_3.py": ("max_difference", 0.00249676106, 1e-5),
    "plot_example_5_4.py": ("max_wear_voronoi", 0.0551279608, 1e-6),
    "plot_example_5_5.py": ("wear_order", 1.37837546, 1e-5),
    "plot_punch.py": ("max_wear", 0.00892077417, 1e-6),
    "plot_block_displacement.py": ("max_difference", 0.0, 1e-14),  # absolute
    "plot_fretting.py": ("max_wear", 0.00401160541, 1e-6),
    "plot_3d.py": ("max_wear", 0.0578112114, 1e-6),
    "plot_orders_k2.py": ("u_error_k2_h4", 0.0328152867, 1e-6),
    "plot_sweep.py": ("max_wear", 0.0985703257, 1e-6),
    "plot_fit.py": ("kappa", 4.96341836, 1e-4),  # least squares to its tolerance
    "plot_pin_on_disc.py": ("max_wear", 0.0942821890599, 1e-6),
    "plot_hertz.py": ("a_error", -0.00374499417180, 1e-4),
    "plot_ball_on_flat.py": ("scar_width", 0.887092314349, 1e-6),
    "plot_adaptive_moving.py": ("max_wear", 0.0356442832, 1e-6),
    "plot_punch_adaptive.py": ("max_wear", 0.00892143409, 1e-6),
}


def test_every_gallery_script_pins_a_number() -> None:
    scripts = sorted(p.name for p in GALLERY.glob("plot_*.py"))
    assert scripts == sorted(PINNED)
    for name in scripts:
        text = (GALLERY / name).read_text(encoding="utf-8")
        doc = text.split('"""')[1]
        title = doc.strip().splitlines()
        assert set(title[1]) == {"="} and len(title[1]) == len(title[0]), name
        assert "It shows" in doc and "Pinned" in doc, f"{name}: say what it shows and pins"


@pytest.mark.parametrize("name", sorted(PINNED))
def test_gallery_script_runs_and_gives_its_number(name: str) -> None:
    """The script as sphinx-gallery runs it (``__name__ == "__main__"``), figures on Agg."""
    import runpy

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    key, value, rtol = PINNED[name]
    try:
        found = runpy.run_path(str(GALLERY / name), run_name="__main__")
        assert plt.get_fignums(), f"{name}: no figure"
    finally:
        plt.close("all")
    if name == "plot_example_5_2.py":  # the paper's findings: more wear with kappa, mu slight
        w = found["max_wear"]
        assert w["set2"] > 1.5 * w["set1"] and abs(w["set3"] - w["set2"]) < 1e-3 * w["set2"]
        found["max_wear_set2"] = w["set2"]
    if name == "plot_pin_on_disc.py":  # Archard's line until the coating wears through
        V, A, rigid = found["volume"], found["archard"], found["on_rigid"]
        before = rigid == 0.0
        assert np.abs(V[before] - A[before]).max() <= 0.01 * A[before].max()
        assert rigid[-1] > 0.0 and V[-1] < A[-1]
    if name == "plot_ball_on_flat.py":  # the scar starts at the contact and widens
        w = found["width"]
        assert abs(w[2] - found["winkler"]) <= 0.05 * found["winkler"]
        assert np.all(np.diff(w) >= 0.0) and w[-1] > 1.2 * w[2]
    if name == "plot_fit.py":  # the true kappa is inside the 95 % interval
        assert found["lo"] < 5.0 < found["hi"] and found["result"].success
    got = float(found[key])
    if value == 0.0:
        assert abs(got) <= rtol, f"{name}: {key} = {got:.3e}"
    else:
        assert got == pytest.approx(value, rel=rtol), f"{name}: {key} = {got!r}"
