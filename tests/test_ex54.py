"""Example 5.4 (squares against general polygons) and the VEM patch test on every mesh family.

The patch test is computed from the definition: a linear displacement prescribed at
every boundary vertex must be reproduced at every interior vertex to round-off by
the VEM stiffness (paper 3.11), on any polygonal mesh, hanging nodes included.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from vemwear.cli.main import main
from vemwear.config import load_config
from vemwear.mesh import (
    Mesh,
    check_mesh,
    l_shape_domain,
    locate_cells,
    refine_along,
    voronoi_mesh,
)
from vemwear.mesh.quality import hanging_nodes
from vemwear.mesh.registry import FAMILIES, generate_mesh
from vemwear.paper import EXAMPLES, ex54, load_example
from vemwear.simulate import SolverOptions, simulate
from vemwear.vem import STABILIZATIONS, Material, Projection, stiffness

ROOT = Path(__file__).resolve().parents[1]
SCIPY = SolverOptions(backend="scipy")

# ----------------------------------------------------------------------------- patch test
#: Small meshes of every family (arguments of generate_mesh).
SMALL: dict[str, dict[str, Any]] = {
    "squares": {"divisions": (4, 2)},
    "triangles": {"divisions": (4, 2)},
    "voronoi": {"cells": 40, "seed": 3},
    "distorted": {"divisions": (6, 3), "seed": 1},
    "hexagons": {"divisions": (4, 3)},
    "nonconvex": {"divisions": (4, 3)},
    "hanging": {"divisions": (4, 2)},
}


def _l_shape(levels: int) -> Mesh:
    mesh = voronoi_mesh(l_shape_domain((2.0, 2.0), (1.0, 1.0)), 60, seed=0)
    assert isinstance(mesh, Mesh)
    mesh = mesh.with_boundary(
        {
            "clamped": lambda m: np.abs(m[:, 0]) < 1e-12,
            "contact": lambda m: np.abs(m[:, 1]) < 1e-12,
            "traction": "rest",
        }
    )
    return refine_along(mesh, "contact", levels) if levels else mesh


def _patch_meshes() -> dict[str, Mesh]:
    out = {name: generate_mesh(name, **kw) for name, kw in SMALL.items()}
    for name in ("squares", "voronoi", "hexagons", "nonconvex", "hanging", "triangles"):
        for levels in (1, 2):
            out[f"{name}+refine{levels}"] = generate_mesh(
                name, **SMALL[name], refine_contact=levels
            )
    out["voronoi L-shape"] = _l_shape(0)
    out["voronoi L-shape+refine1"] = _l_shape(1)
    return out


PATCH_MESHES = _patch_meshes()


def test_every_family_of_vemwear_mesh_is_tested() -> None:
    """Every registered family (test_mesh_cli: every generator is registered) is tested."""
    assert set(SMALL) == set(FAMILIES)


def test_patch_meshes_are_valid_and_refined_ones_hang() -> None:
    for name, mesh in PATCH_MESHES.items():
        check_mesh(mesh, ("clamped", "contact"))
        if "refine" in name or name == "hanging":
            assert len(hanging_nodes(mesh)) > 0, name
        elif name in ("squares", "triangles", "voronoi", "distorted", "hexagons"):
            assert len(hanging_nodes(mesh)) == 0, name


def _solve_prescribed(K, fixed: np.ndarray, values: np.ndarray) -> np.ndarray:
    """u with u[fixed] = values and (K u)[free] = 0, by elimination of the fixed dofs."""
    n = K.shape[0]
    u = np.zeros(n)
    u[fixed] = values
    free = np.setdiff1d(np.arange(n), fixed)
    K = K.tocsr()
    u[free] = spla.spsolve(K[free][:, free].tocsc(), -(K[free][:, fixed] @ values))
    return u


@pytest.mark.parametrize("stab", STABILIZATIONS)
@pytest.mark.parametrize("name", list(PATCH_MESHES))
def test_patch_test_every_family(name: str, stab: str) -> None:
    mesh = PATCH_MESHES[name]
    rng = np.random.default_rng(7)
    A, b = rng.normal(size=(2, 2)), rng.normal(size=2)
    exact = mesh.points @ A.T + b
    K = stiffness(mesh, Material(lam=7.5, eta=1.3), stab)
    bnd = np.unique(mesh.boundary_edges)
    interior = np.setdiff1d(np.arange(mesh.n_points), bnd)
    assert interior.size > 0
    fixed = np.column_stack([2 * bnd, 2 * bnd + 1]).ravel()
    u = _solve_prescribed(K, fixed, exact[bnd].ravel()).reshape(-1, 2)
    err = np.abs(u - exact).max() / np.abs(exact).max()
    assert err < 1e-11, f"{name}/{stab}: patch test error {err:.2e}"


# ----------------------------------------------------------------------------- Pi u at points
@pytest.mark.parametrize("name", ["voronoi", "hanging+refine2", "nonconvex", "triangles"])
def test_projection_at_probe_points_reproduces_linear_fields(name: str) -> None:
    """The probes of Example 5.4 evaluate Pi u of the containing cell (the operator)."""
    mesh = PATCH_MESHES[name]
    rng = np.random.default_rng(1)
    A, b = rng.normal(size=(2, 2)), rng.normal(size=2)
    pts = rng.uniform([0, 0], [2, 1], size=(300, 2))
    pts = np.vstack([pts, mesh.points[:20], [[0.0, 0.0], [2.0, 1.0], [1.0, 0.0]]])
    cells = locate_cells(mesh, pts)
    assert np.all(cells >= 0)
    pi, u = Projection(mesh), mesh.points @ A.T + b
    np.testing.assert_allclose(pi.evaluate(u, pts, cells), pts @ A.T + b, atol=1e-12)
    np.testing.assert_allclose(pi.evaluate(u, pts), pts @ A.T + b, atol=1e-12)


def test_shared_vertices_are_the_corners_for_unrelated_meshes() -> None:
    a = ex54.square_mesh((8, 4))
    b = ex54.polygon_mesh(32, seed=0)
    ia, ib = ex54.shared_vertices(a, b)
    np.testing.assert_array_equal(a.points[ia], b.points[ib])
    corners = {(0.0, 0.0), (2.0, 0.0), (2.0, 1.0), (0.0, 1.0)}
    assert corners <= {tuple(p) for p in a.points[ia]}


# ----------------------------------------------------------------------------- Example 5.4
def test_paper_sizes_and_config_file_builds_the_same_mesh() -> None:
    cfg = load_config(ROOT / "src" / "vemwear" / "examples" / "example_5_4_voronoi.toml")
    a = cfg.problem
    b = ex54.problems()["voronoi"]
    for key in ("points", "cell_offsets", "cell_vertices", "boundary_tags"):
        np.testing.assert_array_equal(getattr(a.mesh, key), getattr(b.mesh, key))
    np.testing.assert_array_equal(a.contact.nodes, b.contact.nodes)
    for key in ("g", "mu", "kappa"):
        np.testing.assert_array_equal(a.nodal[key], b.nodal[key])
    np.testing.assert_array_equal(a.time.t, b.time.t)
    assert a.p.describe() == b.p.describe()
    assert (a.material.lam, a.material.eta) == (b.material.lam, b.material.eta) == (4.0, 4.0)
    np.testing.assert_array_equal(np.asarray(a.f1, float), [0.0, -0.06])
    np.testing.assert_array_equal(a.v_star(0.5), b.v_star(0.5))
    assert a.stabilization == b.stabilization == "paper"
    # the paper's numbers: 2048 polygons, 2048 squares of side 1/32, k = 1/64
    assert b.mesh.n_cells == 2048 and max(b.mesh.groups) > 4
    sq = ex54.problems(n_cells=8)["squares"].mesh
    assert sq.n_cells == 2048 and set(sq.groups) == {4}
    assert sq.h == pytest.approx(np.sqrt(2) / 32)
    assert len(b.time.t) == 65 and float(b.nodal["mu"][0]) == 0.2
    assert float(b.nodal["kappa"][0]) == 2.0


def test_profile_difference_of_a_run_with_itself_is_zero() -> None:
    res = simulate(ex54.problem(ex54.polygon_mesh(16), steps=4), SCIPY)
    d = ex54.profile_difference(res, res, "wear")
    assert d["max_abs"] == 0.0 and d["rel_l2"] == 0.0 and d["max_reference"] > 0
    disp = ex54.displacement_difference(res, res)
    assert disp["probes"]["vector"]["max_abs"] == 0.0 and len(disp["shared"]) >= 4


@pytest.fixture(scope="module")
def small_run(tmp_path_factory: pytest.TempPathFactory) -> ex54.ExampleRun:
    out = tmp_path_factory.mktemp("ex54")
    return ex54.run(
        out,
        divisions=(16, 8),
        n_cells=128,
        steps=8,
        study_cells=(8, 32, 128),
        vtk=False,
        solver=SCIPY,
    )


def test_example_54_small_writes_figures_and_report(small_run: ex54.ExampleRun) -> None:
    out = small_run.outdir
    names = {p.name for p in out.iterdir()}
    assert {
        "fig7.png",
        "fig8.png",
        "fig9.png",
        "voronoi_mesh.png",
        "example_5_4.md",
        "example_5_4.json",
        "squares",
        "voronoi",
    } <= names
    for sub in ("squares", "voronoi"):
        assert (out / sub / "result.npz").exists() and (out / sub / "summary.json").exists()
    for f in small_run.files:
        assert (out / f).exists(), f
    assert set(small_run.results) == {"squares", "voronoi"}
    assert small_run.results["voronoi"].problem.mesh.n_cells == 128
    d = json.loads((out / "example_5_4.json").read_text())
    w = d["comparison"]["wear"]
    assert 0 < w["rel_l2"] < 0.02 and 0 < w["rel_max"] < 0.02  # the meshes nearly agree
    assert d["comparison"]["wear_rel_l2"] == w["rel_l2"]  # the flat headline numbers
    assert d["comparison"]["u_probes_rel_max"] < 0.02
    assert d["comparison"]["displacement"]["probes"]["vector"]["rel_max"] < 0.02
    assert d["quality"]["gamma1"] > 0.2 and d["quality"]["not_star_shaped"] == 0
    lim = d["colour_limits"]
    for r in small_run.results.values():  # Figs. 7 and 8 share limits covering both
        u = r.displacement(-1)
        assert lim["u1"][0] <= u[:, 0].min() and u[:, 0].max() <= lim["u1"][1]
        assert lim["u2"][0] <= u[:, 1].min() and u[:, 1].max() <= lim["u2"][1]
    text = (out / "example_5_4.md").read_text()
    for phrase in (
        "rel. L2 diff",
        "probe points",
        "(2, 1)",
        "assumption A1",
        "gamma1",
        "Voronoi refinement",
        "| 128 |",
        "Timings",
    ):
        assert phrase in text, phrase


def test_refinement_study_in_run_decreases(small_run: ex54.ExampleRun) -> None:
    st = small_run.details["refinement_study"]
    assert [r["n_cells"] for r in st["rows"]] == [8, 32, 128]
    assert st["decreasing"] and st["decreasing_max"]
    # the 128-cell row reuses the run of the example
    assert st["rows"][-1]["wear_rel_l2"] == small_run.details["comparison"]["wear"]["rel_l2"]


def test_voronoi_refinement_study_standalone() -> None:
    study = ex54.voronoi_refinement_study((8, 32, 128), divisions=(16, 8), steps=4, solver=SCIPY)
    d = study.differences("wear_rel_l2")
    assert len(d) == 3 and study.decreasing() and study.decreasing("wear_rel_max")
    assert d[-1] < 0.5 * d[0]
    assert study.reference.startswith("128 squares")
    assert "| 32 |" in study.markdown()


def test_example_54_registered_and_cli(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    assert EXAMPLES["5.4"] == "ex54" and load_example("5.4") is ex54
    original = ex54.run

    def tiny(outdir: Path, *, solver: SolverOptions, **kw: Any) -> ex54.ExampleRun:
        return original(
            outdir,
            solver=SolverOptions(method=solver.method, backend="scipy"),
            divisions=(8, 4),
            n_cells=32,
            steps=4,
            study_cells=None,
            figures=False,
            vtk=False,
            **kw,
        )

    monkeypatch.setattr(ex54, "run", tiny)
    out = tmp_path / "ex"
    assert main(["example", "5.4", "-o", str(out), "--no-progress"]) == 0
    assert (out / "example_5_4.md").exists() and (out / "voronoi" / "result.npz").exists()
    text = capsys.readouterr().out
    assert "squares" in text and "voronoi" in text and "max wear at T" in text
