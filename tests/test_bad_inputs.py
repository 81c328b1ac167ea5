"""A corpus of malformed configurations and meshes: every one is rejected before computing.

Each ``tests/data/bad/*.toml`` holds one defect and says, in its second line
``# expect: REGEX``, which message must name it. Both ``vemwear check`` and
``vemwear run`` must exit with code 2, print one line ``vemwear: error: ...`` matching
the regex (no traceback), and leave nothing behind: no output directory, no
``OUTDIR.partial``, no temporary directory.

The bad mesh files ``tests/data/bad/*.vtu`` are written by :func:`write_bad_meshes`
(``python tests/test_bad_inputs.py`` regenerates them); a test checks that the
committed files match it.
"""

from __future__ import annotations

import re
import shutil
import sys
from pathlib import Path

import meshio
import numpy as np
import pytest

from vemwear.cli.main import main
from vemwear.config import load_config
from vemwear.mesh import squares_with_hanging_nodes, write_mesh

DATA = Path(__file__).resolve().parent / "data" / "bad"
CORPUS = sorted(DATA.glob("*.toml"))
_EXPECT = re.compile(r"^# expect: (.+)$", re.MULTILINE)


def expectation(path: Path) -> str:
    m = _EXPECT.search(path.read_text(encoding="utf-8"))
    assert m, f"{path.name} has no '# expect: REGEX' line"
    return m.group(1).strip()


# ---------------------------------------------------------------------------- bad meshes
# two unit squares side by side: 0 (0,0), 1 (1,0), 2 (2,0), 3 (0,1), 4 (1,1), 5 (2,1)
_P = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [0.0, 1.0], [1.0, 1.0], [2.0, 1.0]]


def bad_meshes() -> dict[str, tuple[list[list[float]], list[list[int]]]]:
    """``{name: (points, cells)}`` of the bad mesh files, one defect each."""
    return {
        # the second cell is listed clockwise
        "clockwise": (_P, [[0, 1, 4, 3], [1, 4, 5, 2]]),
        # a pentagon whose boundary crosses itself (positive area, not simple)
        "self_intersecting": ([[0, 0], [1, 0], [1, 1], [0, 1], [2, -0.5]], [[0, 1, 2, 4, 3]]),
        # a triangle with three collinear vertices on the top side
        "degenerate": ([*_P, [0.5, 1.0]], [[0, 1, 4, 3], [1, 2, 5, 4], [3, 6, 4]]),
        # the right square has its own copies of the shared vertices 1 and 4
        "duplicate_vertex": ([*_P, [1.0, 0.0], [1.0, 1.0]], [[0, 1, 4, 3], [6, 2, 5, 7]]),
        # vertex 6 is used by no cell
        "dangling_vertex": ([*_P, [3.0, 3.0]], [[0, 1, 4, 3], [1, 2, 5, 4]]),
        # vertex 6 = (1, 1) lies on the right edge of cell 0 but is not one of its vertices
        "non_conforming": (
            [[0, 0], [1, 0], [2, 0], [0, 2], [1, 2], [2, 2], [1, 1], [2, 1]],
            [[0, 1, 4, 3], [1, 2, 7, 6], [6, 7, 5, 4]],
        ),
        # cell 1 lists vertex 2 twice
        "repeated_vertex": (_P, [[0, 1, 4, 3], [1, 2, 5, 4, 2]]),
        # the same square twice
        "overlapping_cells": ([[0, 0], [1, 0], [1, 1], [0, 1]], [[0, 1, 2, 3], [0, 1, 2, 3]]),
        # a valid mesh without boundary tags (for 'boundary from the file')
        "untagged": (_P, [[0, 1, 4, 3], [1, 2, 5, 4]]),
        # every boundary edge tagged, and the edge (1, 0) tagged again as clamped
        "conflicting_tags": (_P, [[0, 1, 4, 3], [1, 2, 5, 4]]),
    }


#: Tagged boundary lines ``(edges, part codes)`` of some bad meshes.
BAD_TAGS = {
    "conflicting_tags": (
        [[3, 0], [0, 1], [1, 2], [2, 5], [5, 4], [4, 3], [1, 0]],
        [1, 3, 3, 2, 2, 2, 1],
    ),
}


def _meshio_mesh(
    points: list[list[float]],
    cells: list[list[int]],
    tags: tuple[list[list[int]], list[int]] | None = None,
) -> meshio.Mesh:
    pts = np.column_stack([np.asarray(points, dtype=float), np.zeros(len(points))])
    blocks: list[tuple[str, np.ndarray]] = []
    for c in cells:  # one block per cell keeps the file's cell order
        kind = {3: "triangle", 4: "quad"}.get(len(c), "polygon")
        blocks.append((kind, np.asarray([c], dtype=np.int64)))
    if tags is None:
        return meshio.Mesh(pts, blocks)
    blocks.append(("line", np.asarray(tags[0], dtype=np.int64)))
    part = [np.zeros(1, np.int32) for _ in cells] + [np.asarray(tags[1], np.int32)]
    return meshio.Mesh(pts, blocks, cell_data={"part": part})


def write_bad_meshes(directory: Path) -> None:
    """Write the bad mesh files (ASCII ``.vtu``) and ``garbage.vtu`` into ``directory``."""
    for name, (points, cells) in bad_meshes().items():
        meshio.write(
            directory / f"{name}.vtu", _meshio_mesh(points, cells, BAD_TAGS.get(name)), binary=False
        )
    (directory / "garbage.vtu").write_text("this is not a mesh\n")


def test_corpus_is_large_and_complete() -> None:
    assert len(CORPUS) >= 30
    for p in CORPUS:
        expectation(p)
        for ref in re.findall(r'^file = "(.+)"$', p.read_text(), re.MULTILINE):
            assert (DATA / ref).exists() or "nowhere" in ref, (p.name, ref)


def test_committed_meshes_match_the_generator(tmp_path: Path) -> None:
    write_bad_meshes(tmp_path)
    for name in [*bad_meshes(), "garbage"]:
        new, old = tmp_path / f"{name}.vtu", DATA / f"{name}.vtu"
        assert old.exists(), f"run: python {Path(__file__).name} to write {old.name}"
        if name == "garbage":
            assert old.read_text() == new.read_text()
            continue
        a, b = meshio.read(old), meshio.read(new)
        np.testing.assert_array_equal(a.points, b.points)
        assert [(c.type, c.data.tolist()) for c in a.cells] == [
            (c.type, c.data.tolist()) for c in b.cells
        ]


# ---------------------------------------------------------------------------- the corpus
def _one_error_line(err: str, expected: str, name: str) -> None:
    assert err.count("\n") == 1, f"{name}: expected one line, got:\n{err}"
    assert err.startswith("vemwear: error: "), err
    assert "Traceback" not in err
    assert re.search(expected, err), f"{name}: /{expected}/ not in:\n{err}"


@pytest.mark.parametrize("path", CORPUS, ids=[p.stem for p in CORPUS])
def test_bad_input_is_rejected_by_check_and_run(
    path: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    expected = expectation(path)
    assert main(["check", str(path)]) == 2
    cap = capsys.readouterr()
    assert cap.out == ""
    _one_error_line(cap.err, expected, path.name)
    assert str(path) in cap.err  # the message names the file

    work = tmp_path / "work"
    work.mkdir()
    out = work / "out"
    assert main(["run", str(path), "-o", str(out), "--no-progress"]) == 2
    cap = capsys.readouterr()
    _one_error_line(cap.err, expected, path.name)
    assert list(work.iterdir()) == []  # no OUTDIR, OUTDIR.partial or .OUTDIR.tmp-*
    assert sorted(p.name for p in tmp_path.iterdir()) == ["work"]


# ---------------------------------------------------------------------------- not errors
GOOD = (DATA / "negative_mu.toml").read_text().replace("mu = -0.2", "mu = 0.2")


def test_corpus_base_is_valid(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The files differ from a valid configuration only by their defect."""
    good = tmp_path / "good.toml"
    good.write_text(GOOD)
    assert main(["check", str(good)]) == 0
    assert ": valid" in capsys.readouterr().out


def test_contact_vertex_that_is_clamped_is_not_a_contact_node(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A vertex on both Gamma_D and Gamma_C is clamped and simply not a contact node."""
    cfg = tmp_path / "c.toml"
    cfg.write_text(
        GOOD.replace(
            'clamped = "left"\ntraction = ["top", "right"]\ncontact = "bottom"',
            'clamped = ["left", { from = [1.0, 0.0], to = [1.5, 0.0] }]\n'
            'traction = ["top", "right"]\n'
            "contact = [{ from = [0.0, 0.0], to = [1.0, 0.0] },\n"
            "           { from = [1.5, 0.0], to = [2.0, 0.0] }]",
        )
    )
    pr = load_config(cfg).problem
    clamped = set(pr.mesh.part_vertices("clamped").tolist())
    on_contact = set(pr.mesh.part_vertices("contact").tolist())
    both = clamped & on_contact
    x = pr.mesh.points[sorted(both), 0]
    assert np.allclose(sorted(x), [0.0, 1.0, 1.5])  # the corner and both ends of the clamp
    nodes = set(pr.contact.nodes.tolist())
    assert nodes == on_contact - clamped and not nodes & clamped
    assert main(["check", str(cfg)]) == 0
    assert "contact nodes        2 on 3 contact edges" in capsys.readouterr().out
    out = tmp_path / "out"
    assert main(["run", str(cfg), "-o", str(out), "--no-progress"]) == 0
    with np.load(out / "result.npz") as z:
        assert sorted(z["contact_nodes"].tolist()) == sorted(nodes)
        u = z["u"][:, sorted(both)]
        assert np.all(u == 0)  # clamped vertices do not move


def test_proper_hanging_nodes_are_accepted(tmp_path: Path) -> None:
    mesh = squares_with_hanging_nodes(size=(2.0, 1.0), divisions=(4, 2))
    write_mesh(mesh, tmp_path / "hanging.vtu")
    cfg = tmp_path / "h.toml"
    cfg.write_text(
        GOOD.replace(
            'generator = "squares"\nsize = [2.0, 1.0]\ndivisions = [4, 2]', 'file = "hanging.vtu"'
        )
    )
    pr = load_config(cfg).problem
    assert max(pr.mesh.groups) > 4  # cells with hanging nodes are polygons


def test_smallness_warning_in_check_and_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Doubtful smallness (Theorem 3.4) is a warning with the estimate, not an error."""
    cfg = tmp_path / "s.toml"
    cfg.write_text(
        GOOD.replace("mu = 0.2", "mu = 1.0").replace(
            'p = { type = "linear", c = 0.4 }', 'p = { type = "linear", c = 4.0 }'
        )
    )
    assert main(["check", str(cfg)]) == 0
    cap = capsys.readouterr()
    row = re.search(
        r"smallness \(Thm 3\.4\)\s+L_p \|\|mu\|\| c0\^2/C1 ~= ([0-9.]+) >= 1: "
        r"MAY FAIL",
        cap.out,
    )
    assert row, cap.out
    warn = re.search(
        r"^vemwear: warning: the smallness condition of Theorem 3\.4 is doubtful: "
        r"L_p \|\|mu\|\| c0\^2/C1 ~= ([0-9.]+) >= 1 \(L_p = 4, max mu = 1,",
        cap.err,
        re.MULTILINE,
    )
    assert warn and warn.group(1) == row.group(1), cap.err
    out = tmp_path / "out"
    code = main(["run", str(cfg), "-o", str(out), "--no-progress"])
    cap = capsys.readouterr()
    assert "vemwear: warning: the smallness condition of Theorem 3.4 is doubtful" in cap.err
    assert code in (0, 3)  # it may still converge
    # a small mu: no warning
    cfg.write_text(GOOD)
    assert main(["check", str(cfg)]) == 0
    cap = capsys.readouterr()
    assert "warning" not in cap.err and "< 1: holds" in cap.out


def test_expressions_give_the_same_problem_as_python_callables(tmp_path: Path) -> None:
    from vemwear.vem import body_force_vector, traction_vector

    cfg = tmp_path / "e.toml"
    cfg.write_text(
        GOOD.replace("g = 0.1", 'g = "0.1 + 0.01*x"')
        .replace("mu = 0.2", 'mu = "0.2*(1 + 0.5*sin(pi*x))"')
        .replace("v_star = [1.0, 0.0]", 'v_star = ["1 + 0.5*sin(2*pi*t)", 0.25]')
        .replace("f1 = [0.0, -0.06]", 'f1 = ["0", "-0.06*(1 + x)*(1 + t)"]\nf2 = [0, "-0.01*t*y"]')
    )
    pr = load_config(cfg).problem
    x = pr.contact.points[:, 0]
    np.testing.assert_allclose(pr.nodal["g"], 0.1 + 0.01 * x, rtol=1e-15)
    np.testing.assert_allclose(pr.nodal["mu"], 0.2 * (1 + 0.5 * np.sin(np.pi * x)), rtol=1e-15)
    for t in (0.0, 0.3, 1.0):
        np.testing.assert_allclose(pr.v_star(t), [1 + 0.5 * np.sin(2 * np.pi * t), 0.25])
        f1 = body_force_vector(
            pr.mesh, lambda p, t: np.column_stack([0 * p[:, 0], -0.06 * (1 + p[:, 0]) * (1 + t)]), t
        )
        np.testing.assert_allclose(body_force_vector(pr.mesh, pr.f1, t), f1, rtol=1e-14)
        f2 = traction_vector(
            pr.mesh, lambda p, t: np.column_stack([0 * p[:, 0], -0.01 * t * p[:, 1]]), t
        )
        np.testing.assert_allclose(traction_vector(pr.mesh, pr.f2, t), f2, rtol=1e-14)


EXPRESSION_ERRORS = [
    ("x.real", "attribute access is not allowed"),
    ("().__class__.__bases__", "attribute access is not allowed"),
    ("x[0]", "a subscript is not allowed"),
    ("lambda: 1", "a lambda function is not allowed"),
    ("[x for x in (1, 2)]", "a comprehension is not allowed"),
    ("'abc'", "a string is not allowed"),
    ("x if x else 1", "a conditional expression is not allowed"),
    ("x < 1", "a comparison is not allowed"),
    ("x and y", "'and' / 'or' is not allowed"),
    ("(x, y)", "a tuple is not allowed"),
    ("(z := 1)", "an assignment is not allowed"),
    ("open('f')", "unknown function 'open'"),
    ("eval('1')", "unknown function 'eval'"),
    ("x.conjugate()", "only the functions sin cos tan exp log sqrt abs min max can be called"),
    ("sin(x=1)", "keyword arguments are not allowed"),
    ("sin(x, y)", "sin takes exactly 1 argument, got 2"),
    ("max(x)", "max takes 2 or more arguments, got 1"),
    ("sin", "the function 'sin' must be called"),
    ("x % 2", "'%' is not allowed"),
    ("x // 2", "'//' is not allowed"),
    ("x ^ 2", "'^' is not a power; write '**'"),
    ("~x", "the operator Invert is not allowed"),
    ("1j", "the constant 1j is not allowed"),
    ("True", "the constant True is not allowed"),
    ("z + 1", "unknown name 'z'"),
    ("t + 1", "the variable 't' cannot be used here"),
    ("", "is an empty expression"),
    ("1 +", "is not a valid expression"),
    ("0.1 mm", "units are not accepted"),
    ("9" * 400, "is too large"),
    ("1e999", "is not a finite number"),
    ("log(0)", "is not a finite number"),
    ("-" * 200 + "x", "nested too deeply"),
    ("max(" + ",".join(["x"] * 450) + ")", "too complex"),
    ("x" * 1001, "longer than 1000 characters"),
]


@pytest.mark.parametrize(
    ("text", "message"), EXPRESSION_ERRORS, ids=[t[:20] for t, _ in EXPRESSION_ERRORS]
)
def test_expression_language_is_a_whitelist(text: str, message: str) -> None:
    from vemwear.config.expr import ExpressionError, parse_expression

    with pytest.raises(ExpressionError) as info:
        parse_expression(text, ("x", "y"), where="[contact] g")
    msg = str(info.value)
    assert msg.startswith("[contact] g") and message in msg and "\n" not in msg, msg


def test_mesh_file_errors_name_the_file_not_a_copy(tmp_path: Path) -> None:
    """Relative mesh files are found next to the configuration (copies work the same)."""
    shutil.copy(DATA / "mesh_clockwise.toml", tmp_path / "c.toml")
    shutil.copy(DATA / "clockwise.vtu", tmp_path / "clockwise.vtu")
    assert main(["check", str(tmp_path / "c.toml")]) == 2


if __name__ == "__main__":  # pragma: no cover - regenerate the committed mesh files
    write_bad_meshes(DATA)
    print(f"wrote the bad meshes into {DATA}", file=sys.stderr)
