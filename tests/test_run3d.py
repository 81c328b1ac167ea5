"""The front ends in 3D: a 3D configuration through `vemwear check`
and `vemwear run`, its files read back, a stopped run resumed bitwise, one-line errors
for bad 3D inputs, the 2D side aliases, and `vemwear example 3d --quick`."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from conftest import CONFIG_3D, npz_arrays
from vemwear.cli.main import main
from vemwear.config import ConfigError, load_config, parse_config
from vemwear.mesh.io3d import write_mesh3d
from vemwear.mesh.polyhedra import Mesh3D
from vemwear.post import load_result
from vemwear.post.results import mesh_from_arrays, result_from_arrays
from vemwear.simulate import simulate

CONFIG = CONFIG_3D + "times = [0.5, 1.0]\n"


@pytest.fixture
def config(tmp_path: Path) -> Path:
    p = tmp_path / "c3d.toml"
    p.write_text(CONFIG)
    return p


def _write(tmp_path: Path, text: str, name: str = "bad.toml") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


# ----------------------------------------------------------------------------- check, run
def test_check_and_run_a_3d_config(config: Path, tmp_path: Path, capsys) -> None:
    assert main(["check", str(config)]) == 0
    text = capsys.readouterr().out
    assert "3D, 45 vertices, 16 cells" in text and "contact 8" in text
    assert "12 on 8 contact faces" in text
    out = tmp_path / "out"
    assert main(["run", str(config), "-o", str(out), "--no-progress"]) == 0
    names = {p.name for p in out.iterdir()}
    assert {"result.npz", "summary.json", "solution.pvd", "contact_maps.png"} <= names
    assert {"contact_line.png", "time_history.png", "forces.png"} <= names
    vtus = sorted((out / "solution").glob("*.vtu"))
    assert [v.name for v in vtus] == ["solution_0004.vtu", "solution_0008.vtu"]
    import meshio

    m = meshio.read(vtus[-1])
    assert m.point_data["displacement"].shape == (45, 3) and "von_mises" in m.cell_data
    # the arrays read back
    a = load_result(out)
    assert a["u"].shape == (2, 45, 3) and a["contact_points"].shape == (12, 3)
    assert np.array_equal(a["contact_s"], a["contact_points"][:, 0])
    assert a["forces"].shape == (9, 2, 3)
    mesh = mesh_from_arrays(a)
    assert isinstance(mesh, Mesh3D) and mesh.parts == ("clamped", "contact", "free")
    cfg = load_config(config)
    res = result_from_arrays(cfg.problem, a)
    ref = simulate(cfg.problem, cfg.solver)
    assert np.array_equal(res.wear, ref.wear) and np.allclose(res.u[-1], ref.u[-1], atol=1e-14)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["inputs"]["problem"]["mesh"]["dim"] == 3
    assert summary["outputs"]["wear_max_final"] == pytest.approx(float(ref.wear[-1].max()))
    assert len(summary["outputs"]["forces_final"][0]["force"]) == 3


def test_stopped_3d_run_resumes_bitwise(
    config: Path, tmp_path: Path, stop_at: Callable[..., None], capsys
) -> None:
    ref = tmp_path / "ref"
    assert main(["run", str(config), "-o", str(ref), "--no-progress"]) == 0
    out = tmp_path / "out"
    stop_at(5)
    assert main(["run", str(config), "-o", str(out), "--no-progress"]) == 3
    stop_at(None)
    capsys.readouterr()
    assert main(["run", str(config), "-o", str(out), "--no-progress", "--resume"]) == 0
    assert "resumed from level 5" in capsys.readouterr().out
    a, b = npz_arrays(ref), npz_arrays(out)
    for k in ("u", "wear", "u_nu", "p_rigid", "p_soft", "iterations", "residuals", "forces"):
        assert np.array_equal(a[k], b[k]), k


# ----------------------------------------------------------------------------- inputs
@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (
            ("f1 = [0.0, 0.0, -0.06]", "f1 = [0.0, -0.06]"),
            "[loads] f1 = [0, -0.06] has 2 components; a 3D mesh ('hexahedra') needs 3",
        ),
        (
            ('contact = "zmin"', 'contact = "zmn"'),
            "[boundary] contact = 'zmn' is neither a side (xmin, xmax, ymin, ymax, zmin, "
            "zmax), 'rest' nor a part of the mesh",
        ),
        (
            ('contact = "zmin"', 'contact = "bottom"'),
            "[boundary] contact = 'bottom' is neither a side",
        ),
        (
            ("v_star = [1.0, 0.0, 0.0]", "v_star = [1.0, 0.0]"),
            "[contact] v_star = [1, 0] has 2 components; a 3D mesh ('hexahedra') needs 3",
        ),
        (
            ('generator = "hexahedra"', 'generator = "hexahedr"'),
            "did you mean 'hexahedra'?",
        ),
    ],
)
def test_bad_3d_inputs_give_one_line_errors(
    tmp_path: Path, edit: tuple[str, str], message: str
) -> None:
    p = _write(tmp_path, CONFIG.replace(*edit))
    with pytest.raises(ConfigError) as exc:
        load_config(p)
    text = str(exc.value)
    assert "\n" not in text and message in text, text
    assert text.startswith(str(p))


def test_3d_extras_prescribed_uz_expressions_and_a_mesh_file(tmp_path: Path) -> None:
    """uz, loads in x, y, z, g in x, y; a 3D mesh file read as such."""
    text = CONFIG.replace('clamped = "xmin"\n', "").replace(
        'free = "rest"',
        'free = "rest"\n[[boundary.displacement]]\non = "xmin"\nux = 0.0\nuy = 0.0\n'
        'uz = "-0.001 * t"',
    )
    text = text.replace("f1 = [0.0, 0.0, -0.06]", 'f1 = [0.0, 0.0, "-0.06 * (1 + 0.1 * z)"]')
    text = text.replace("g = 0.1", 'g = "0.1 + 0.01 * y"')
    cfg = load_config(_write(tmp_path, text, "uz.toml"))
    pr = cfg.problem
    assert pr.dim == 3 and pr.displacement[0].uz is not None
    assert np.allclose(pr.nodal["g"], 0.1 + 0.01 * pr.contact.points[:, 1])
    res = simulate(pr, cfg.solver, store="final")
    xmin = pr.mesh.points[:, 0] == 0
    assert np.allclose(res.u[-1][xmin, 2], -0.001)
    # a mesh file with volume cells is a 3D mesh
    mesh = load_config(_write(tmp_path, CONFIG)).problem.mesh
    write_mesh3d(mesh, tmp_path / "box.vtu")
    text = CONFIG.replace(
        'generator = "hexahedra"\nsize = [2.0, 1.0, 1.0]\ndivisions = [4, 2, 2]',
        'file = "box.vtu"',
    )
    cfg = load_config(_write(tmp_path, text, "file.toml"))
    assert isinstance(cfg.problem.mesh, Mesh3D) and cfg.problem.contact.m == 12


def test_2d_accepts_the_3d_side_names(tmp_path: Path) -> None:
    from vemwear.examples import config_path

    base = config_path("example_5_2_set1").read_text()
    data = {"mesh": {"generator": "squares", "size": [2.0, 1.0], "divisions": [8, 4]}}
    import tomllib

    d = tomllib.loads(base) | data
    d["time"] = {"T": 1.0, "steps": 4}
    a = parse_config(d)
    d["boundary"] = {"clamped": "xmin", "traction": ["ymax", "xmax"], "contact": "ymin"}
    b = parse_config(d)
    assert np.array_equal(a.problem.mesh.boundary_tags, b.problem.mesh.boundary_tags)
    d["loads"] = {"f1": [0.0, -0.06, 0.0]}
    with pytest.raises(ConfigError, match=r"\[loads\] f1 = \[0, -0.06, 0\] has 3 components"):
        parse_config(d)


# ----------------------------------------------------------------------------- example
def test_example_3d_quick(tmp_path: Path, capsys) -> None:
    out = tmp_path / "ex"
    assert main(["example", "3d", "--quick", "-o", str(out), "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "hexahedra against Voronoi polyhedra (16 cells each)" in text
    report = (out / "example_3d.md").read_text()
    assert "Convergence in h = k" in report and "| 1/2 |" in report
    assert (out / "hex" / "contact_maps.png").is_file()
    assert main(["example", "5.2", "--quick", "-o", str(tmp_path / "x"), "--no-progress"]) == 2
