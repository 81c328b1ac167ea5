"""TOML configuration: every key form, every kind of error, and the paper's example files."""

from __future__ import annotations

import copy
import re
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from conftest import small_config
from vemwear.config import ConfigError, load_config, parse_config
from vemwear.contact import LinearCompliance, TableCompliance
from vemwear.mesh import PARTS, part_code, write_mesh
from vemwear.paper import ex52

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "src" / "vemwear" / "examples"

BASE = small_config(
    "small",
    mesh={"origin": [0.0, 0.0]},
    boundary={"traction": ["top", "right"]},
    vem={"stabilization": "paper"},
    loads={"f2": [0.0, 0.0]},
    solver={"tol": 1e-10, "max_iter": 50},
    output={"times": [0.25, 0.5, 1.0]},
)


def base() -> dict[str, Any]:
    return tomllib.loads(BASE)


def parse(data: dict[str, Any], base_dir: Path | str = ".") -> Any:
    return parse_config(data, source="config.toml", base_dir=base_dir)


def tags(mesh) -> dict[str, int]:
    return {p: int(np.sum(mesh.boundary_tags == part_code(p))) for p in PARTS}


# ---------------------------------------------------------------------------- key forms
def test_base_config() -> None:
    cfg = parse(base())
    pr = cfg.problem
    assert cfg.title == "small"
    assert pr.mesh.n_cells == 32 and pr.mesh.n_points == 45
    assert tags(pr.mesh) == {"clamped": 4, "traction": 12, "contact": 8}
    assert pr.contact.m == 8  # the corner (0, 0) is on Gamma_D
    assert pr.material.lam == 4.0 and pr.material.eta == 4.0
    assert pr.p == LinearCompliance(0.4)
    np.testing.assert_allclose(pr.time.t, np.linspace(0, 1, 9))
    assert cfg.solver.method == "newton" and cfg.solver.max_iter == 50
    assert cfg.solver.backend == "scipy" and cfg.solver.tol == 1e-10
    assert cfg.output.times == (0.25, 0.5, 1.0)
    assert not cfg.output.figures and not cfg.output.vtk


def test_defaults_of_optional_sections() -> None:
    d = base()
    for sec in ("vem", "loads", "solver", "output", "title"):
        del d[sec]
    cfg = parse(d)
    assert cfg.problem.stabilization == "paper"
    assert tuple(cfg.problem.f1) == (0.0, 0.0) and tuple(cfg.problem.f2) == (0.0, 0.0)
    assert cfg.solver.method == "newton" and cfg.solver.max_iter is None
    assert cfg.output.times == (0.25, 0.5, 0.75, 1.0)  # levels nearest T/4, ..., T
    assert cfg.output.figures and cfg.output.vtk
    assert cfg.title == "config"  # the file stem


def test_boundary_segments_and_rest_give_the_same_tags() -> None:
    ref = parse(base()).problem.mesh
    d = base()
    d["boundary"] = {
        "clamped": {"from": [0.0, 0.0], "to": [0.0, 1.0]},
        "contact": [{"from": [0.0, 0.0], "to": [1.0, 0.0]}, {"from": [1.0, 0.0], "to": [2.0, 0.0]}],
        "traction": "rest",
    }
    np.testing.assert_array_equal(parse(d).problem.mesh.boundary_tags, ref.boundary_tags)
    d["boundary"] = {"traction": "rest", "clamped": ["left"], "contact": "bottom"}
    np.testing.assert_array_equal(parse(d).problem.mesh.boundary_tags, ref.boundary_tags)


def test_boundary_mixed_list_and_order() -> None:
    d = base()
    # a part of the bottom is clamped, the rest of it is in contact
    d["boundary"] = {
        "contact": {"from": [0.5, 0.0], "to": [2.0, 0.0]},
        "traction": ["top", "right"],
        "clamped": ["left", {"from": [0.0, 0.0], "to": [0.5, 0.0]}],
    }
    m = parse(d).problem.mesh
    assert tags(m) == {"clamped": 6, "traction": 12, "contact": 6}
    # overlapping selectors are an error naming both parts and an edge
    d["boundary"]["contact"] = "bottom"
    with pytest.raises(
        ConfigError,
        match=r"\[boundary\] parts 'contact' and 'clamped' "
        r"overlap: both select the boundary edge \(0, 1\)",
    ):
        parse(d)


def test_coefficient_tables_and_velocity_table() -> None:
    d = base()
    d["contact"]["g"] = {"along": "x", "at": [0.0, 2.0], "values": [0.1, 0.05]}
    d["contact"]["mu"] = {"at": [0.0, 1.0], "values": [0.0, 0.3]}  # along defaults to x
    d["contact"]["kappa"] = {"along": "s", "at": [0.0, 10.0], "values": [1.0, 1.0]}
    d["contact"]["v_star"] = {"t": [0.0, 1.0], "values": [[1.0, 0.0], [3.0, 0.0]]}
    pr = parse(d).problem
    x = pr.contact.points[:, 0]
    np.testing.assert_allclose(pr.nodal["g"], 0.1 - 0.025 * x)
    np.testing.assert_allclose(pr.nodal["mu"], np.minimum(x, 1.0) * 0.3)
    np.testing.assert_allclose(pr.nodal["kappa"], 1.0)
    np.testing.assert_allclose(pr.v_star(0.5), [2.0, 0.0])
    np.testing.assert_allclose(pr.v_star.n_star(0.5), [-1.0, 0.0])


def test_table_compliance() -> None:
    d = base()
    d["contact"]["p"] = {"type": "table", "r": [0.0, 0.01, 0.1], "p": [0.0, 0.001, 0.1]}
    pr = parse(d).problem
    assert isinstance(pr.p, TableCompliance)
    np.testing.assert_allclose(pr.p(np.array([-1.0, 0.005, 0.2])), [0.0, 0.0005, 0.21])


def test_time_dt_list() -> None:
    d = base()
    d["time"] = {"dt": [0.25, 0.25, 0.5]}
    cfg = parse(d)
    np.testing.assert_allclose(cfg.problem.time.t, [0.0, 0.25, 0.5, 1.0])
    d["time"] = {"T": 1.0, "dt": [0.25, 0.25, 0.5]}
    assert parse(d).problem.time.T == 1.0


def test_time_pattern() -> None:
    d = base()
    d["time"] = {"T": 1.0, "pattern": [1 / 128, 3 / 128]}
    d["output"]["times"] = [0.25, 0.5, 1.0]
    t = parse(d).problem.time.t
    assert len(t) == 65 and t[-1] == 1.0
    np.testing.assert_allclose(np.diff(t)[:4], [1 / 128, 3 / 128, 1 / 128, 3 / 128])


def test_triangles_generator() -> None:
    d = base()
    d["mesh"] = {
        "generator": "triangles",
        "size": [2.0, 1.0],
        "divisions": [4, 2],
        "diagonal": "alternate",
    }
    m = parse(d).problem.mesh
    assert m.n_cells == 16 and set(m.groups) == {3}


def test_mesh_file_with_and_without_boundary(tmp_path: Path) -> None:
    ref = parse(base()).problem.mesh
    write_mesh(ref, tmp_path / "mesh.vtu")
    d = base()
    d["mesh"] = {"file": "mesh.vtu"}
    del d["boundary"]  # keep the file's tags
    m1 = parse(d, base_dir=tmp_path).problem.mesh
    np.testing.assert_allclose(m1.points, ref.points)
    assert tags(m1) == tags(ref)
    d["boundary"] = "file"
    assert tags(parse(d, base_dir=tmp_path).problem.mesh) == tags(ref)
    d["boundary"] = {"clamped": "left", "contact": "bottom", "traction": "rest"}
    assert tags(parse(d, base_dir=tmp_path).problem.mesh) == tags(ref)


def test_load_config_relative_mesh_file(tmp_path: Path) -> None:
    sub = tmp_path / "case"
    sub.mkdir()
    write_mesh(parse(base()).problem.mesh, sub / "m.vtu")
    text = BASE.replace(
        'generator = "squares"\nsize = [2.0, 1.0]\norigin = [0.0, 0.0]\ndivisions = [8, 4]',
        'file = "m.vtu"',
    )
    (sub / "c.toml").write_text(text)
    cfg = load_config(sub / "c.toml")
    assert cfg.mesh_source == {"file": str((sub / "m.vtu").resolve())}
    assert cfg.path == sub / "c.toml"


def test_data_is_jsonable() -> None:
    import json

    cfg = parse(base())
    json.dumps(cfg.data)
    assert cfg.data["contact"]["mu"] == 0.2


# ---------------------------------------------------------------------------- errors
def _set(d: dict[str, Any], path: str, value: Any) -> None:
    *head, last = path.split(".")
    for k in head:
        d = d[k]
    if value is _DELETE:
        del d[last]
    else:
        d[last] = value


_DELETE = object()

ERRORS = [
    # (key path, new value, expected message; the file name is prepended)
    ("contact.muu", 0.2, "[contact] unknown key 'muu'; did you mean 'mu'?"),
    ("contac", {"mu": 0.2}, "unknown section or key 'contac'; did you mean [contact]?"),
    ("titel", "x", "unknown section or key 'titel'; did you mean 'title'?"),
    ("solver.metod", "uzawa", "[solver] unknown key 'metod'; did you mean 'method'?"),
    (
        "mesh.divisons",
        [2, 2],
        "[mesh] unknown key 'divisons' for generator 'squares'; did you mean 'divisions'?",
    ),
    (
        "contact.mu",
        [0.2],
        "[contact] mu must be a number, an expression string in x, y, z or a "
        "table { along, at, values }, got an array ([0.2])",
    ),
    ("contact.mu", -0.2, "[contact] mu must be >= 0 on the contact part; it is -0.2 at contact"),
    ("contact.kappa", -1, "[contact] kappa must be >= 0 on the contact part; it is -1 at"),
    ("contact.g", 0.0, "[contact] g must be > 0 on the contact part; it is 0 at contact node 0"),
    (
        "contact.g",
        {"at": [0, 2], "values": [0.1, -0.1]},
        "[contact] g = {'at': [0, 2], 'values': [0.1, -0.1]} must be > 0 on the contact part; it",
    ),
    (
        "contact.g",
        {"at": [0, 2], "values": [0.1]},
        "[contact] g = {'at': [0, 2], 'values': [0.1]}: 'at' must",
    ),
    ("contact.g", {"at": [0, 2], "values": ["0.1", 1]}, "[contact] g.values[0] must be a number"),
    ("contact.g", {"along": "z", "at": [0], "values": [0.1]}, "[contact] g.along must be one of"),
    (
        "contact.g",
        {"at": [2, 0], "values": [0.1, 0.1]},
        "'values': [0.1, 0.1]}: 'at' must increase",
    ),
    ("material.lam", 0, "[material] Lamé coefficient lam must be positive, got 0"),
    ("material.eta", True, "[material] eta must be a number, got a boolean (True)"),
    ("material.lam", _DELETE, "[material] missing required key 'lam'"),
    ("material", _DELETE, "missing required section [material]"),
    ("contact", _DELETE, "missing required section [contact]"),
    ("boundary", _DELETE, "missing required section [boundary]"),
    ("contact.v_star", _DELETE, "[contact] missing required key 'v_star'"),
    ("contact.v_star", [1.0], "[contact] v_star must have at least 2 entries, got 1 ([1.0])"),
    ("contact.v_star", {"t": [0, 1], "values": [[1, 0]]}, "[contact] v_star: 't' and 'values'"),
    (
        "contact.p",
        {"type": "cubic"},
        "[contact] p.type must be one of 'linear', 'table', got 'cubic'",
    ),
    ("contact.p", {"type": "linear"}, "[contact] p missing required key 'c'"),
    ("contact.p", {"type": "linear", "c": -1}, "[contact] p: stiffness c must be >= 0, got -1"),
    (
        "contact.p",
        {"type": "table", "r": [0, 1], "p": [0, 1, 2]},
        "[contact] p: compliance table: r and p must be lists of equal length",
    ),
    (
        "contact.p",
        {"type": "table", "r": [0, 1, 2], "p": [0, 2, 1]},
        "[contact] p: compliance table: p must be non-decreasing (p[1] = 2.0 > p[2] = 1.0)",
    ),
    ("contact.p", 0.4, "[contact] p must be a table, got a float (0.4)"),
    ("time.T", -1.0, "[time] T must be positive, got -1.0"),
    ("time.T", _DELETE, "[time] missing required key 'T' (needed with 'steps')"),
    ("time.steps", 8.0, "[time] steps must be an integer, got a float (8.0)"),
    ("time.steps", 0, "[time] steps must be a positive integer, got 0"),
    ("time.dt", [0.5, 0.5], "[time] needs exactly one of 'steps' (uniform), 'dt'"),
    ("time.steps", _DELETE, "[time] needs exactly one of"),
    ("time.tmax", 1, "[time] unknown key 'tmax'"),
    ("solver.tol", 0.0, "[solver] tol must be positive, got 0.0"),
    ("solver.tol", -1e-8, "[solver] tol must be positive, got -1e-08"),
    (
        "solver.method",
        "newtn",
        "[solver] method must be one of 'newton', 'newton-full', "
        "'uzawa', got 'newtn'; did you mean 'newton'?",
    ),
    ("solver.max_iter", 0, "[solver] max_iter must be >= 1, got 0"),
    ("solver.backend", "mkl", "[solver] backend must be one of"),
    ("vem.stabilization", "dofi", "[vem] stabilization must be one of 'paper', 'eta', 'trace'"),
    (
        "loads.f1",
        [0, True],
        "[loads] f1[1] must be a number or an expression string in x, y, z, t, got a boolean "
        "(True)",
    ),
    (
        "output.times",
        [0.25, 0.3],
        "[output] times[1] = 0.3 is not a time level of the grid "
        "(T = 1, 8 steps; nearest level 0.25)",
    ),
    ("output.times", 0.25, "[output] times must be an array, got a float (0.25)"),
    ("output.vtk", "yes", "[output] vtk must be true or false, got a string ('yes')"),
    ("mesh.generator", "voronio", "[mesh] generator = 'voronio' is not a known mesh family"),
    ("mesh.generator", _DELETE, "[mesh] needs exactly one of 'generator' or 'file'"),
    ("mesh.file", "m.vtu", "[mesh] needs exactly one of 'generator' or 'file', not both"),
    ("mesh.divisions", [8, 0], "[mesh] divisions must be positive integers, got [8, 0]"),
    ("mesh.divisions", [8, 4.0], "[mesh] divisions[1] must be an integer, got a float (4.0)"),
    ("mesh.divisions", [8], "[mesh] divisions must have at least 2 entries, got 1 ([8])"),
    ("mesh.size", [2.0, -1.0], "[mesh] size must be positive, got [2.0, -1.0]"),
    (
        "boundary.contact",
        "bottm",
        "[boundary] contact = 'bottm' is neither a side (left, right, bottom, top), 'rest' "
        "nor a part of the mesh; did you mean 'bottom'?",
    ),
    ("boundary.contact", [{"from": [0, 0]}], "[boundary] contact[0] missing required key 'to'"),
    ("boundary.contact", 3, "[boundary] contact must be a side ('left', 'right', 'bottom'"),
    ("boundary.contakt", "bottom", "[boundary] unknown key 'contakt'; did you mean 'contact'?"),
    ("boundary.clamped", "rest", "[boundary] only one part can be 'rest'"),
    ("boundary.traction", _DELETE, "[boundary] 12 boundary edges have no boundary part, e.g."),
    ("boundary", "file", "boundary = 'file' needs [mesh] file"),
]


@pytest.mark.parametrize(
    ("path", "value", "expected"), ERRORS, ids=[f"{p}={v!r}"[:40] for p, v, _ in ERRORS]
)
def test_error_messages(path: str, value: Any, expected: str) -> None:
    d = base()
    if path == "boundary.clamped":  # a second 'rest'
        d["boundary"]["traction"] = "rest"
    _set(d, path, value)
    with pytest.raises(ConfigError) as info:
        parse(d)
    msg = str(info.value)
    assert msg.startswith("config.toml: "), msg
    assert expected in msg, msg
    assert "\n" not in msg


def test_negative_mu_message_exactly() -> None:
    d = base()
    d["contact"]["mu"] = -0.2
    with pytest.raises(ConfigError) as info:
        parse(d)
    assert str(info.value) == (
        "config.toml: [contact] mu must be >= 0 on the contact part; it is -0.2 at contact "
        "node 0 (vertex 1, x = [0.25, 0.0])"
    )


def test_missing_mesh_file(tmp_path: Path) -> None:
    d = base()
    d["mesh"] = {"file": "nowhere.vtu"}
    with pytest.raises(ConfigError) as info:
        parse(d, base_dir=tmp_path)
    assert f"config.toml: [mesh] file not found: {tmp_path / 'nowhere.vtu'}" == str(info.value)


def test_unreadable_mesh_file(tmp_path: Path) -> None:
    (tmp_path / "bad.vtu").write_text("not a mesh")
    d = base()
    d["mesh"] = {"file": "bad.vtu"}
    with pytest.raises(
        ConfigError, match=r"\[mesh\] file 'bad.vtu': cannot read mesh \(meshio could not parse"
    ):
        parse(d, base_dir=tmp_path)


def test_file_errors(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"missing\.toml: config file not found"):
        load_config(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[mesh\ngenerator = 1\n")
    with pytest.raises(ConfigError, match=r"bad.toml: not valid TOML: .*line 1"):
        load_config(bad)
    neg = tmp_path / "neg.toml"
    neg.write_text(BASE.replace("mu = 0.2", "mu = -0.2"))
    with pytest.raises(ConfigError) as info:
        load_config(neg)
    assert str(info.value).startswith(f"{neg}: [contact] mu must be >= 0 on the contact part")


def test_problem_errors_keep_the_file_name() -> None:
    d = base()  # g < 0 near x = 2: only the Problem sees it, at the contact nodes
    d["contact"]["g"] = {"along": "x", "at": [0.0, 2.0], "values": [0.1, -0.1]}
    with pytest.raises(
        ConfigError, match=r"^config.toml: \[contact\] g = .* must be > 0 on the contact part"
    ):
        parse(d)


def test_dt_must_sum_to_T() -> None:
    d = base()
    d["time"] = {"T": 2.0, "dt": [0.5, 0.5]}
    with pytest.raises(ConfigError, match=r"\[time\] dt sums to 1, but T = 2"):
        parse(d)


def test_input_dict_is_not_modified() -> None:
    d = base()
    before = copy.deepcopy(d)
    parse(d)
    assert d == before


# ---------------------------------------------------------------------------- paper files
@pytest.mark.parametrize("name", list(ex52.DATA_SETS))
def test_example_files_match_paper_module(name: str) -> None:
    cfg = load_config(EXAMPLES / f"example_5_2_{name}.toml")
    a = cfg.problem
    b = ex52.problems()[name]
    np.testing.assert_array_equal(a.mesh.points, b.mesh.points)
    np.testing.assert_array_equal(a.mesh.cell_offsets, b.mesh.cell_offsets)
    np.testing.assert_array_equal(a.mesh.cell_vertices, b.mesh.cell_vertices)
    np.testing.assert_array_equal(a.mesh.boundary_tags, b.mesh.boundary_tags)
    np.testing.assert_array_equal(a.contact.nodes, b.contact.nodes)
    for key in ("g", "mu", "kappa"):
        np.testing.assert_array_equal(a.nodal[key], b.nodal[key])
    np.testing.assert_array_equal(a.time.t, b.time.t)
    assert a.p.describe() == b.p.describe()
    assert (a.material.lam, a.material.eta) == (b.material.lam, b.material.eta)
    np.testing.assert_array_equal(np.asarray(a.f1, float), np.asarray(b.f1, float))
    np.testing.assert_array_equal(np.asarray(a.f2, float), np.asarray(b.f2, float))
    for t in (0.0, 0.5, 1.0):
        np.testing.assert_array_equal(a.v_star(t), b.v_star(t))
    assert a.stabilization == b.stabilization
    assert cfg.output.times == ex52.TIMES
    # and the paper's numbers themselves
    assert b.mesh.n_cells == 32 * 16 and len(b.time.t) == 65
    assert b.contact.m == 32
    assert (
        dict(
            zip(("mu", "kappa"), (float(b.nodal["mu"][0]), float(b.nodal["kappa"][0])), strict=True)
        )
        == ex52.DATA_SETS[name]
    )


# ---------------------------------------------------------------------------- mesh families
def test_other_mesh_families_are_looked_up() -> None:
    d = base()
    d["mesh"] = {"generator": "voronoi", "size": [2.0, 1.0], "n_cells": 24, "seed": 1}
    m = parse(d).problem.mesh
    assert m.n_cells == 24 and max(m.groups) > 4
    d["mesh"] = {"generator": "hexagons", "size": [2.0, 1.0], "divisions": 6}
    assert max(parse(d).problem.mesh.groups) == 6
    d["mesh"] = {"generator": "hexagons", "divisons": 6}
    with pytest.raises(
        ConfigError,
        match="unknown key 'divisons' for generator 'hexagons'; did you mean 'divisions'",
    ):
        parse(d)
    d["mesh"] = {"generator": "hexagon"}
    with pytest.raises(ConfigError, match=r"did you mean 'hexagons'\? available: .*voronoi"):
        parse(d)


def test_voronoi_aliases_take_a_domain_or_seeds() -> None:
    """The function names of the Voronoi family take a polygon (or seeds) instead of size."""
    d = base()
    d["mesh"] = {"generator": "voronoi_mesh", "n_cells": 16, "seed": 2}
    square = {"domain": [[0, 0], [2, 0], [2, 1], [0, 1]]}
    m0 = parse(d).problem.mesh  # the default rectangle [0, 2] x [0, 1]
    d["mesh"].update(square)
    cfg = parse(d)
    np.testing.assert_array_equal(cfg.problem.mesh.points, m0.points)
    assert cfg.mesh_source["domain"] == square["domain"]
    assert cfg.mesh_source["function"] == "voronoi"
    d["mesh"]["size"] = [2.0, 1.0]
    with pytest.raises(ConfigError, match=r"\[mesh\] give either 'domain' or 'size', not both"):
        parse(d)
    seeds = [[0.5, 0.5], [1.5, 0.5], [1.0, 0.2]]
    d["mesh"] = {"generator": "voronoi_from_seeds", "seeds": seeds, **square}
    assert parse(d).problem.mesh.n_cells == 3
    d["mesh"]["n_cells"] = 3
    with pytest.raises(ConfigError, match="give either 'seeds' or 'n_cells', not both"):
        parse(d)


# ---------------------------------------------------------------------------- schema and docs
def test_docs_key_tables_are_generated_from_the_schema() -> None:
    """docs/config.md holds every generated table, up to date (python -m
    vemwear.config.reference docs/config.md rewrites them)."""
    from vemwear.config import update_reference
    from vemwear.config.reference import reference_tables

    text = (ROOT / "docs" / "config.md").read_text(encoding="utf-8")
    names = re.findall(r"<!-- schema: ([\w.]+) -->", text)
    assert sorted(names) == sorted(reference_tables())
    assert update_reference(text) == text, "run: python -m vemwear.config.reference docs/config.md"
    assert "| `n_cells` | integer | `256` | number of cells |" in text
    assert (
        update_reference(text.replace("| `n_cells` | integer | `256`", "| `n_cells` | x | 1"))
        == text
    )


def test_schema_command_prints_the_json_schema(capsys: pytest.CaptureFixture[str]) -> None:
    """``vemwear schema`` is a JSON Schema that editors can check files with, made
    without warnings (defaults of the types the schema states: lists, not tuples)."""
    import json
    import warnings

    import jsonschema

    from vemwear.cli.main import main

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["schema"]) == 0
    schema = json.loads(capsys.readouterr().out)
    jsonschema.Draft202012Validator.check_schema(schema)
    check = jsonschema.Draft202012Validator(schema)
    files = [*EXAMPLES.glob("*.toml"), ROOT / "tests" / "data" / "bad" / "negative_mu.toml"]
    configs = [tomllib.loads(f.read_text()) for f in files]
    for f, data in zip(files, configs, strict=True):
        if "axes" in data:  # a study file (docs/studies.md), not a configuration
            continue
        # valid in form (the sign of mu is the Problem's business)
        assert not list(check.iter_errors(data)), f.name
    for path, value in [
        ("contact.muu", 0.2),
        ("contact.mu", [0.2]),
        ("mesh.generator", "voronio"),
        ("mesh.divisons", [2, 2]),
        ("time.steps", "8"),
        ("solver.method", "newtn"),
        ("boundary.contact", 3),
    ]:
        d = base()
        _set(d, path, value)
        assert list(check.iter_errors(d)), path
        with pytest.raises(ConfigError):
            parse(d)
