"""The ``vemwear mesh`` commands: generate, inspect, plot, convert, and their errors."""

from __future__ import annotations

import json
import subprocess
import sys
import tomllib
from pathlib import Path

import meshio
import numpy as np
import pytest

from vemwear.cli.main import main
from vemwear.mesh import (
    PARTS,
    Mesh,
    check_mesh,
    contact_nodes,
    part_code,
    read_mesh,
    rectangle_squares,
    squares_with_hanging_nodes,
    tag_rectangle,
    write_mesh,
)
from vemwear.mesh.quality import hanging_nodes
from vemwear.mesh.registry import FAMILIES, generate_mesh

ROOT = Path(__file__).resolve().parents[1]

#: Small sizes per family for the command line.
ARGS: dict[str, list[str]] = {
    "squares": ["--divisions", "4", "2"],
    "triangles": ["--cells", "16"],
    "voronoi": ["--cells", "30", "--seed", "2"],
    "distorted": ["--divisions", "4", "2", "--seed", "1", "--param", "amplitude=0.1"],
    "hexagons": ["--divisions", "4", "3"],
    "nonconvex": ["--cells", "8"],
    "hanging": ["--divisions", "4", "2", "--param", "pattern=random", "--seed", "3"],
}


def tags(mesh: Mesh) -> dict[str, int]:
    return {p: int(np.sum(mesh.boundary_tags == part_code(p))) for p in PARTS}


def error_line(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("vemwear: error: ")
    return lines[0]


# ----------------------------------------------------------------------------- help
def test_help_everywhere(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--help"]) == 0
    assert "mesh" in capsys.readouterr().out
    assert main(["mesh", "--help"]) == 0
    out = capsys.readouterr().out
    for cmd in ("generate", "inspect", "plot", "convert"):
        assert cmd in out
    for cmd in ("generate", "inspect", "plot", "convert"):
        assert main(["mesh", cmd, "--help"]) == 0
        text = capsys.readouterr().out
        assert f"usage: vemwear mesh {cmd}" in text and "exit codes" in text
    main(["mesh", "generate", "--help"])
    text = capsys.readouterr().out
    for name in FAMILIES:
        assert name in text


def test_usage_errors_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["mesh"]) == 2
    assert main(["mesh", "generate", "pentagons", "-o", "x.vtu"]) == 2
    assert "invalid choice" in capsys.readouterr().err
    assert (
        main(
            ["mesh", "generate", "squares", "-o", "x.vtu", "--cells", "8", "--divisions", "2", "2"]
        )
        == 2
    )
    assert "not allowed with" in capsys.readouterr().err


# ----------------------------------------------------------------------------- generate
@pytest.mark.parametrize("family", list(FAMILIES))
def test_generate_every_family(
    family: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / f"{family}.vtu"
    assert main(["mesh", "generate", family, "-o", str(out), *ARGS[family]]) == 0
    assert f"wrote {out}" in capsys.readouterr().out
    mesh = read_mesh(out)
    check_mesh(mesh, ("clamped", "contact"))
    t = tags(mesh)
    assert all(t[p] > 0 for p in PARTS)  # the paper's parts, every edge tagged
    assert np.all(mesh.boundary_tags > 0)
    P = mesh.points
    mid = 0.5 * (P[mesh.part_edges("contact")[:, 0]] + P[mesh.part_edges("contact")[:, 1]])
    assert np.all(np.abs(mid[:, 1]) < 1e-12)  # contact = bottom
    mid = 0.5 * (P[mesh.part_edges("clamped")[:, 0]] + P[mesh.part_edges("clamped")[:, 1]])
    assert np.all(np.abs(mid[:, 0]) < 1e-12)  # clamped = left
    assert np.sum(mesh.cell_areas) == pytest.approx(2.0, rel=1e-12)
    expected = generate_mesh(family, **_kwargs(ARGS[family]))
    np.testing.assert_array_equal(mesh.points, expected.points)
    np.testing.assert_array_equal(mesh.cell_vertices, expected.cell_vertices)


def _kwargs(argv: list[str]) -> dict[str, object]:
    """generate_mesh arguments of the ARGS lists above."""
    kw: dict[str, object] = {}
    params: dict[str, object] = {}
    it = iter(argv)
    for a in it:
        if a == "--divisions":
            kw["divisions"] = (int(next(it)), int(next(it)))
        elif a == "--cells":
            kw["cells"] = int(next(it))
        elif a == "--seed":
            kw["seed"] = int(next(it))
        elif a == "--param":
            k, v = next(it).split("=")
            params[k] = float(v) if k == "amplitude" else v
    return {**kw, "params": params}


def test_generate_counts_and_options(tmp_path: Path) -> None:
    m = generate_mesh("voronoi", cells=77, seed=0)
    assert m.n_cells == 77
    m = generate_mesh("squares", cells=2048)  # 64 x 32: the paper's mesh A
    assert m.n_cells == 2048 and m.h == pytest.approx(np.sqrt(2) / 32)
    assert generate_mesh("triangles", cells=64).n_cells == 64
    m = generate_mesh("squares", divisions=(3, 2), size=(3.0, 2.0))
    assert m.n_cells == 6 and np.allclose(m.points.max(axis=0), [3.0, 2.0])
    assert not np.any(generate_mesh("squares", divisions=(2, 1), boundary="none").boundary_tags)
    base = generate_mesh("squares", divisions=(4, 2))
    r1 = generate_mesh("squares", divisions=(4, 2), refine_contact=1)
    r2 = generate_mesh("squares", divisions=(4, 2), refine_contact=2)
    assert (base.n_cells, r1.n_cells, r2.n_cells) == (8, 20, 44)
    assert (tags(base)["contact"], tags(r1)["contact"], tags(r2)["contact"]) == (4, 8, 16)
    assert len(hanging_nodes(base)) == 0
    assert len(hanging_nodes(r1)) == 4  # top-side midpoints of the 4 refined cells
    check_mesh(r2)
    assert (
        main(
            [
                "mesh",
                "generate",
                "squares",
                "-o",
                str(tmp_path / "r.vtu"),
                "--divisions",
                "4",
                "2",
                "--refine-contact",
                "2",
            ]
        )
        == 0
    )
    back = read_mesh(tmp_path / "r.vtu")
    np.testing.assert_array_equal(back.boundary_tags, r2.boundary_tags)


@pytest.mark.parametrize("family", ["squares", "triangles", "distorted"])
def test_generate_gmsh_roundtrip(family: str, tmp_path: Path) -> None:
    out = tmp_path / "m.msh"
    assert main(["mesh", "generate", family, "-o", str(out), "--divisions", "4", "2"]) == 0
    a, b = generate_mesh(family, divisions=(4, 2)), read_mesh(out)
    np.testing.assert_allclose(b.points, a.points, atol=1e-15)
    np.testing.assert_array_equal(b.cell_vertices, a.cell_vertices)
    np.testing.assert_array_equal(b.boundary_tags, a.boundary_tags)


def test_generate_refuses_to_overwrite_unless_forced(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "m.vtu"
    assert main(["mesh", "generate", "squares", "-o", str(out)]) == 0
    before = out.read_bytes()
    assert main(["mesh", "generate", "squares", "-o", str(out), "--divisions", "2", "1"]) == 2
    assert "exists; use --force" in error_line(capsys)
    assert out.read_bytes() == before
    assert (
        main(["mesh", "generate", "squares", "-o", str(out), "--divisions", "2", "1", "--force"])
        == 0
    )
    assert read_mesh(out).n_cells == 2
    assert [p.name for p in tmp_path.iterdir()] == ["m.vtu"]  # no temporary files left


# ----------------------------------------------------------------------------- inspect
def test_inspect_counts_validity_quality(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    mesh = tag_rectangle(squares_with_hanging_nodes((2.0, 1.0), (4, 2)))
    write_mesh(mesh, tmp_path / "h.vtu")
    assert main(["mesh", "inspect", str(tmp_path / "h.vtu")]) == 0
    out = capsys.readouterr().out
    n_hang = len(hanging_nodes(mesh))
    assert n_hang == 10  # 4 split cells: 4 x 4 side midpoints, 6 of them on the boundary
    for phrase in (
        f"points          {mesh.n_points}",
        f"cells           {mesh.n_cells}",
        "4-gons 16",
        f"hanging nodes   {n_hang}",
        "contact nodes   6",
        "clamped 3, traction 9, contact 6, untagged 0",
        "valid (vertices",
        "boundary parts  complete",
        "Mesh quality (assumption A1)",
        "gamma1 =",
        "no warnings",
    ):
        assert phrase in out, phrase
    assert main(["mesh", "inspect", str(tmp_path / "h.vtu"), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["cells"] == mesh.n_cells and d["hanging_nodes"] == n_hang
    assert d["boundary_edges"] == {"clamped": 3, "traction": 9, "contact": 6, "untagged": 0}
    assert d["contact_nodes"] == len(contact_nodes(mesh)) == 6
    assert d["valid"] and d["boundary_error"] is None
    assert d["quality"]["gamma1"] == pytest.approx(0.5 / np.sqrt(2))
    assert d["cells_by_vertices"] == {"4": 16, "6": 2, "7": 2}  # 2 or 3 split neighbours


def test_inspect_config_and_untagged(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert (
        main(
            [
                "mesh",
                "inspect",
                str(ROOT / "src" / "vemwear" / "examples" / "example_5_2_set1.toml"),
                "--json",
            ]
        )
        == 0
    )
    d = json.loads(capsys.readouterr().out)
    assert d["cells"] == 512 and d["contact_nodes"] == 32 and d["hanging_nodes"] == 0
    write_mesh(rectangle_squares((2.0, 1.0), (2, 1)), tmp_path / "u.vtu")
    assert main(["mesh", "inspect", str(tmp_path / "u.vtu")]) == 0  # valid, parts missing
    out = capsys.readouterr().out
    assert "untagged 6" in out and "boundary parts  incomplete" in out


def test_inspect_invalid_mesh_is_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pts = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
    meshio.write(tmp_path / "cw.vtu", meshio.Mesh(pts, [("quad", np.array([[0, 3, 2, 1]]))]))
    assert main(["mesh", "inspect", str(tmp_path / "cw.vtu")]) == 2
    cap = capsys.readouterr()
    assert "INVALID" in cap.out and "clockwise" in cap.out
    assert cap.err.strip() == (
        f"vemwear: error: {tmp_path / 'cw.vtu'}: invalid mesh: cells [0] "
        "are clockwise; cells must be counter-clockwise"
    )


# ----------------------------------------------------------------------------- plot
def test_plot_mesh_and_quality(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    src = tmp_path / "v.vtu"
    assert (
        main(
            [
                "mesh",
                "generate",
                "voronoi",
                "-o",
                str(src),
                "--cells",
                "40",
                "--refine-contact",
                "1",
            ]
        )
        == 0
    )
    for extra, name in (([], "m.png"), (["--quality"], "q.png")):
        out = tmp_path / name
        assert main(["mesh", "plot", str(src), "-o", str(out), *extra]) == 0
        assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 10_000
    assert (
        main(
            [
                "mesh",
                "plot",
                str(ROOT / "src" / "vemwear" / "examples" / "example_5_2_set1.toml"),
                "-o",
                str(tmp_path / "c.pdf"),
            ]
        )
        == 0
    )
    assert (tmp_path / "c.pdf").read_bytes()[:4] == b"%PDF"
    capsys.readouterr()
    assert main(["mesh", "plot", str(src), "-o", str(tmp_path / "m.png")]) == 2
    assert "exists; use --force" in error_line(capsys)
    assert main(["mesh", "plot", str(src), "-o", str(tmp_path / "m.xyz")]) == 2
    assert "unknown file type '.xyz'" in error_line(capsys)


# ----------------------------------------------------------------------------- convert
def test_convert_roundtrips(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    a = tmp_path / "a.vtu"
    assert main(["mesh", "generate", "triangles", "-o", str(a), "--divisions", "4", "2"]) == 0
    assert main(["mesh", "convert", str(a), str(tmp_path / "b.msh")]) == 0
    assert main(["mesh", "convert", str(tmp_path / "b.msh"), str(tmp_path / "c.vtu")]) == 0
    ma, mc = read_mesh(a), read_mesh(tmp_path / "c.vtu")
    np.testing.assert_array_equal(ma.points, mc.points)
    np.testing.assert_array_equal(ma.cell_vertices, mc.cell_vertices)
    np.testing.assert_array_equal(ma.boundary_tags, mc.boundary_tags)
    cfg = ROOT / "src" / "vemwear" / "examples" / "example_5_2_set1.toml"
    assert main(["mesh", "convert", str(cfg), str(tmp_path / "cfg.msh")]) == 0
    m = read_mesh(tmp_path / "cfg.msh")
    assert m.n_cells == 512 and tags(m) == {"clamped": 16, "traction": 48, "contact": 32}
    assert "wrote" in capsys.readouterr().out


# ----------------------------------------------------------------------------- errors
@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["generate", "voronoi", "-o", "{d}/v.msh", "--cells", "20"],
            "gmsh files hold triangles and quadrilaterals only, but the mesh has",
        ),
        (["generate", "hanging", "-o", "{d}/h.msh"], "write .vtu instead"),
        (["generate", "squares", "-o", "{d}/s.obj"], "unknown file type '.obj'"),
        (
            ["generate", "voronoi", "-o", "{d}/v.vtu", "--divisions", "2", "2"],
            "family 'voronoi' does not take --divisions; give --cells N",
        ),
        (
            ["generate", "hexagons", "-o", "{d}/v.vtu", "--cells", "20"],
            "family 'hexagons' does not take --cells",
        ),
        (["generate", "squares", "-o", "{d}/v.vtu", "--cells", "7"], "aspect ratio 3.5 > 2"),
        (
            ["generate", "squares", "-o", "{d}/v.vtu", "--seed", "1"],
            "family 'squares' is deterministic: --seed does not apply",
        ),
        (
            ["generate", "distorted", "-o", "{d}/v.vtu", "--param", "amplitude=0.4"],
            "amplitude must lie in [0, 0.25)",
        ),
        (
            ["generate", "distorted", "-o", "{d}/v.vtu", "--param", "amplitde=0.1"],
            "--param amplitde: family 'distorted' has no such option; did you mean 'amplitude'?",
        ),
        (
            ["generate", "distorted", "-o", "{d}/v.vtu", "--param", "seed=2"],
            "--param seed: use the option --seed instead",
        ),
        (["generate", "squares", "-o", "{d}/v.vtu", "--param", "nonsense"], "expected NAME=VALUE"),
        (
            ["generate", "squares", "-o", "{d}/v.vtu", "--size", "0", "1"],
            "--size must be two positive numbers",
        ),
        (["generate", "voronoi", "-o", "{d}/v.vtu", "--cells", "0"], "--cells must be >= 1"),
        (
            [
                "generate",
                "squares",
                "-o",
                "{d}/v.vtu",
                "--refine-contact",
                "1",
                "--boundary",
                "none",
            ],
            "--refine-contact needs the boundary parts",
        ),
        (
            ["generate", "squares", "-o", "{d}/v.vtu", "--refine-contact", "-1"],
            "--refine-contact must be >= 0",
        ),
        (["inspect", "{d}/missing.vtu"], "missing.vtu: no such file"),
        (["inspect", "{d}"], ": not a file"),
        (["inspect", "{d}/garbage.vtu"], "garbage.vtu: cannot read mesh"),
        (["inspect", "{d}/garbage.msh"], "garbage.msh: cannot read mesh"),
        (["inspect", "{d}/bad.toml"], "[contact] mu must be >= 0"),
        (["plot", "{d}/missing.vtu", "-o", "{d}/x.png"], "missing.vtu: no such file"),
        (["convert", "{d}/missing.vtu", "{d}/x.vtu"], "missing.vtu: no such file"),
        (["convert", "{d}/garbage.vtu", "{d}/garbage.vtu"], "input and output are the same file"),
        (["convert", "{d}/garbage.vtu", "{d}/x.txt"], "unknown file type '.txt'"),
    ],
)
def test_bad_input_is_one_line_exit_2(
    argv: list[str], message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "garbage.vtu").write_text("not a mesh\n")
    (tmp_path / "garbage.msh").write_text("not a mesh\n")
    cfg = (ROOT / "src" / "vemwear" / "examples" / "example_5_2_set1.toml").read_text()
    (tmp_path / "bad.toml").write_text(cfg.replace("mu = 0.2", "mu = -0.2"))
    args = [a.replace("{d}", str(tmp_path)) for a in argv]
    assert main(["mesh", *args]) == 2
    line = error_line(capsys)
    assert message in line, line
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temporaries


def test_subprocess_exit_codes(tmp_path: Path) -> None:
    cmd = [sys.executable, "-m", "vemwear.cli.main", "mesh"]
    ok = subprocess.run(
        [*cmd, "generate", "voronoi", "-o", str(tmp_path / "v.vtu"), "--cells", "12"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert ok.returncode == 0, ok.stderr
    bad = subprocess.run(
        [*cmd, "convert", str(tmp_path / "v.vtu"), str(tmp_path / "v.msh")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert bad.returncode == 2
    assert bad.stderr.startswith("vemwear: error: ") and bad.stderr.count("\n") == 1


# ----------------------------------------------------------------------------- helpers
def test_hanging_and_contact_nodes() -> None:
    sq = tag_rectangle(rectangle_squares((2.0, 1.0), (4, 2)))
    assert len(hanging_nodes(sq)) == 0
    np.testing.assert_array_equal(contact_nodes(sq), [1, 2, 3, 4])  # bottom row minus (0, 0)
    m = generate_mesh("hanging", divisions=(4, 2))  # checkerboard
    P = m.points
    h = hanging_nodes(m)
    # every hanging node is a side midpoint of a split cell, inside the domain
    assert np.all((P[h, 0] > 0) & (P[h, 0] < 2) & (P[h, 1] > 0) & (P[h, 1] < 1))
    assert len(h) == 10  # 16 side midpoints of the 4 split cells, 6 on the boundary


def test_config_and_cli_share_the_registry(tmp_path: Path) -> None:
    """Every family and alias of the registry works in a config and gives the command's mesh."""
    from vemwear.config import parse_config
    from vemwear.config.mesh_forms import MESH_FORMS
    from vemwear.mesh.registry3d import FAMILIES_3D

    assert set(MESH_FORMS) == {*FAMILIES, *FAMILIES_3D, "file"}
    cfg = tomllib.loads(
        (ROOT / "src" / "vemwear" / "examples" / "example_5_2_set1.toml").read_text()
    )
    for name, fam in FAMILIES.items():
        seed = 3 if fam.option("seed") else None
        if fam.option("n_cells"):
            expected = generate_mesh(name, cells=20, seed=seed)
            keys: dict[str, object] = {"n_cells": 20}
        else:
            expected = generate_mesh(name, divisions=(4, 2), seed=seed)
            keys = {"divisions": [4, 2]}
        keys.update({"seed": seed} if seed is not None else {})
        for alias in (name, *fam.aliases):
            cfg["mesh"] = {"generator": alias, **keys}
            mesh = parse_config(cfg, source="c.toml").problem.mesh
            np.testing.assert_array_equal(mesh.points, expected.points)
            np.testing.assert_array_equal(mesh.cell_vertices, expected.cell_vertices)


def test_registry_options_are_generator_parameters() -> None:
    """Each option is a parameter of its generator, with the generator's default."""
    import inspect

    from vemwear.mesh import voronoi_mesh

    for fam in FAMILIES.values():
        params = dict(inspect.signature(fam.function).parameters)
        if any(p.kind is p.VAR_KEYWORD for p in params.values()):
            params = {**inspect.signature(voronoi_mesh).parameters, **params}
        for opt in fam.options:
            assert opt.name in params, (fam.name, opt.name)
            default = params[opt.name].default
            assert opt.default == (None if default is inspect.Parameter.empty else default)
    with pytest.raises(ValueError, match=r"'hexagon' is not a known mesh family; did you mean"):
        from vemwear.mesh.registry import family

        family("hexagon")


def test_every_generator_of_vemwear_mesh_is_registered() -> None:
    """A public function of vemwear.mesh that makes a Mesh from scratch is a family (or an
    alias of one), so that configs and ``vemwear mesh generate`` know it."""
    import inspect

    import vemwear.mesh as vm

    names = {n for f in FAMILIES.values() for n in (f.name, f.function.__name__, *f.aliases)}
    generators = [
        n
        for n in vm.__all__
        if inspect.isfunction(getattr(vm, n))
        and "Mesh" in str(inspect.signature(getattr(vm, n)).return_annotation)
        and "mesh" not in inspect.signature(getattr(vm, n)).parameters
        and n not in ("read_mesh", "check_mesh", "tag_rectangle")
    ]
    assert len(generators) >= 9
    assert not [n for n in generators if n not in names]


# ----------------------------------------------------------------------------- 3D meshes
def test_generate_inspect_plot_convert_3d(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from vemwear.mesh.io3d import read_mesh3d
    from vemwear.mesh.registry3d import generate_mesh3d

    box = tmp_path / "box.vtu"
    argv = ["--divisions", "4", "2", "2", "--size", "2", "1", "1"]
    assert main(["mesh", "generate", "hexahedra", "-o", str(box), *argv]) == 0
    out = capsys.readouterr().out
    assert f"wrote {box}" in out and "16 cells (6 faces 16)" in out
    m = read_mesh3d(box)
    assert m.n_cells == 16 and m.part_counts()["zmin"] == 8
    expected = generate_mesh3d("hexahedra", divisions=(4, 2, 2))
    np.testing.assert_array_equal(m.points, expected.points)

    vor = tmp_path / "v.vtu"
    argv = ["--cells", "12", "--seed", "1", "--param", "lloyd_iterations=2"]
    assert main(["mesh", "generate", "voronoi3d", "-o", str(vor), *argv]) == 0
    assert read_mesh3d(vor).n_cells == 12
    capsys.readouterr()

    assert main(["mesh", "inspect", str(box)]) == 0
    out = capsys.readouterr().out
    for phrase in (
        "valid 3D mesh",
        "cells           16 (6 faces 16)",
        "boundary faces  40: xmin 4, xmax 4, ymin 8, ymax 8, zmin 8, zmax 8, untagged 0",
        "valid (vertices, faces, cells, conformity)",
        "boundary parts  complete",
        "Mesh quality (3D)",
    ):
        assert phrase in out, phrase
    assert main(["mesh", "inspect", str(vor), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["dim"] == 3 and d["cells"] == 12 and d["valid"]
    assert d["volume"] == pytest.approx(2.0) and d["boundary_faces"]["untagged"] == 0

    assert main(["mesh", "convert", str(vor), str(tmp_path / "w.vtu")]) == 0
    a, b = read_mesh3d(vor), read_mesh3d(tmp_path / "w.vtu")
    np.testing.assert_array_equal(a.points, b.points)
    np.testing.assert_array_equal(a.boundary_tags, b.boundary_tags)
    assert main(["mesh", "plot", str(box), "-o", str(tmp_path / "b.png")]) == 0
    assert (tmp_path / "b.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "wrote" in capsys.readouterr().out


def test_3d_config_inspect_and_convert(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cfg = tmp_path / "c.toml"
    text = (ROOT / "src" / "vemwear" / "examples" / "example_3d.toml").read_text()
    cfg.write_text(text.replace("divisions = [16, 8, 8]", "divisions = [4, 2, 2]"))
    assert main(["mesh", "inspect", str(cfg)]) == 0
    out = capsys.readouterr().out
    assert "cells           16" in out and "boundary faces" in out and "contact 8" in out
    assert main(["mesh", "convert", str(cfg), str(tmp_path / "c.vtu")]) == 0
    assert "16 cells" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["generate", "hexahedra", "-o", "{d}/b.vtu", "--size", "2", "1"],
            "--size takes 3 numbers (LX LY LZ) for the 3D family 'hexahedra', got 2",
        ),
        (
            ["generate", "squares", "-o", "{d}/b.vtu", "--size", "2", "1", "1"],
            "--size takes 2 numbers (LX LY) for the 2D family 'squares', got 3",
        ),
        (
            ["generate", "voronoi3d", "-o", "{d}/b.vtu", "--divisions", "2", "2", "2"],
            "family 'voronoi3d' does not take --divisions; give --cells N",
        ),
        (
            ["generate", "hexahedra", "-o", "{d}/b.msh", "--divisions", "2", "1", "1"],
            "writing polyhedral (3D) meshes as .msh is not supported; write .vtu instead",
        ),
        (
            ["generate", "hexahedra", "-o", "{d}/b.vtu", "--refine-contact", "1"],
            "--refine-contact applies to 2D families only",
        ),
        (["convert", "{d}/box.vtu", "{d}/box.msh"], "write .vtu instead"),
        (["plot", "{d}/box.vtu", "-o", "{d}/q.png", "--quality"], "--quality is for 2D meshes"),
    ],
)
def test_3d_errors_are_one_line_exit_2(
    argv: list[str], message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from vemwear.mesh.io3d import write_mesh3d
    from vemwear.mesh.registry3d import generate_mesh3d

    write_mesh3d(generate_mesh3d("hexahedra", divisions=(2, 1, 1)), tmp_path / "box.vtu")
    args = [a.replace("{d}", str(tmp_path)) for a in argv]
    assert main(["mesh", *args]) == 2
    line = error_line(capsys)
    assert message in line, line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["box.vtu"]  # nothing written
