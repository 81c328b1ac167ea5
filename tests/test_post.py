"""Post-processing: result files, figures and ParaView output (vemwear.post)."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import meshio
import numpy as np
import pytest
from matplotlib.figure import Figure

import vemwear
from vemwear.contact import LinearCompliance
from vemwear.mesh import Mesh, rectangle_squares, tag_rectangle
from vemwear.post import (
    cell_strain_stress,
    compare_profiles,
    load_result,
    load_summary,
    mesh_from_arrays,
    plot_contact_profiles,
    plot_deformed,
    plot_displacement,
    plot_time_history,
    save_result,
    write_vtk_series,
)
from vemwear.simulate import Problem, Result, TimeGrid, simulate
from vemwear.vem import Material

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _problem(mesh: Mesh, steps: int = 8, **kw) -> Problem:
    data = dict(f1=(0, -0.06), p=LinearCompliance(0.4), g=0.1, mu=0.2, kappa=2, v_star=(1, 0))
    data.update(kw)
    return Problem(mesh, Material(4, 4), TimeGrid.uniform(1, steps), **data)


def _mixed_mesh(nx: int = 8, ny: int = 4) -> Mesh:
    """Triangles, quads and hexagons (pairs of squares) on (0, 2) x (0, 1)."""
    sq = rectangle_squares((2, 1), (nx, ny))
    cells: list[list[int]] = []
    for j in range(ny):
        row = [sq.cell(j * nx + i).tolist() for i in range(nx)]
        i = 0
        while i < nx:
            a, b, c, d = row[i]
            if j % 2 == 1 and i + 1 < nx:
                _a2, b2, c2, _d2 = row[i + 1]
                cells.append([a, b, b2, c2, c, d])
                i += 2
            elif j % 2 == 0 and i % 4 == 0:
                cells += [[a, b, c], [a, c, d]]
                i += 1
            else:
                cells.append([a, b, c, d])
                i += 1
    return Mesh.from_cells(sq.points, cells)


@pytest.fixture(scope="module")
def run() -> Result:
    return simulate(_problem(tag_rectangle(rectangle_squares((2, 1), (8, 4)))))


@pytest.fixture(scope="module")
def run_mixed() -> Result:
    """Polygons of 3, 4 and 6 vertices; Gamma_C bends round a corner (bottom and right)."""
    parts = {"clamped": "left", "traction": "top", "contact": ["bottom", "right"]}
    return simulate(_problem(tag_rectangle(_mixed_mesh(), parts), steps=4))


def _is_png(path: Path) -> bool:
    return path.is_file() and path.stat().st_size > 1000 and path.read_bytes()[:8] == PNG_MAGIC


# ---------------------------------------------------------------------------- result files


def test_save_and_load_arrays(run: Result, tmp_path: Path) -> None:
    paths = save_result(run, tmp_path / "out", extra={"config": {"mesh": [8, 4]}})
    assert [p.name for p in paths] == ["result.npz", "summary.json"]
    assert all(p.is_file() for p in paths)
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["result.npz", "summary.json"]

    data = load_result(paths[0])
    L, n, m = len(run.t), run.problem.mesh.n_points, len(run.contact_nodes)
    shapes = {
        "t": (L,),
        "points": (n, 2),
        "u": (L, n, 2),
        "contact_nodes": (m,),
        "contact_s": (m,),
        "contact_points": (m, 2),
        "wear": (L, m),
        "u_nu": (L, m),
        "penetration": (L, m),
        "p_rigid": (L, m),
        "p_soft": (L, m),
        "iterations": (L,),
        "residuals": (L, 3),
        "cells_offsets": (run.problem.mesh.n_cells + 1,),
    }
    for key, shape in shapes.items():
        assert data[key].shape == shape, key
    for key in ("t", "u", "wear", "u_nu", "p_rigid", "p_soft", "iterations", "residuals"):
        np.testing.assert_array_equal(data[key], getattr(run, key))  # one name in both
    np.testing.assert_array_equal(data["contact_nodes"], run.contact_nodes)
    assert data["format"].item() == "vemwear-result/2"
    np.testing.assert_array_equal(data["penetration"], data["u_nu"] - data["wear"])
    np.testing.assert_array_equal(data["cells_vertices"], run.problem.mesh.cell_vertices)
    assert data["residual_names"].tolist() == list(Result.RESIDUAL_NAMES)
    assert data["vemwear_version"].item() == vemwear.__version__
    # the directory works too, and the mesh (with its boundary parts) comes back
    again = load_result(tmp_path / "out")
    assert set(again) == set(data)
    mesh = mesh_from_arrays(data)
    ref = run.problem.mesh
    np.testing.assert_array_equal(mesh.part_edges("contact"), ref.part_edges("contact"))
    np.testing.assert_array_equal(mesh.boundary_tags, ref.boundary_tags)


def test_summary_contents(run: Result, tmp_path: Path) -> None:
    extra = {"config": {"steps": np.int64(8), "h": np.float64(0.25), "file": tmp_path / "c.toml"}}
    save_result(run, tmp_path, extra=extra)
    s = json.loads((tmp_path / "summary.json").read_text())
    assert s == load_summary(tmp_path)
    assert {"vemwear_version", "inputs", "solver", "statistics", "timings", "outputs"} <= set(s)
    assert s["vemwear_version"] == vemwear.__version__
    assert s["inputs"]["problem"]["material"] == {"lam": 4, "eta": 4}
    config = {"steps": 8, "h": 0.25, "file": str(tmp_path / "c.toml")}
    assert s["inputs"]["extra"]["config"] == config
    assert s["solver"]["method"] == run.solver["method"]
    st = s["statistics"]
    assert st["iterations_total"] == int(run.iterations.sum())
    assert st["iterations_max"] == int(run.iterations.max())
    assert set(st["max_residual"]) == set(Result.RESIDUAL_NAMES)
    assert st["max_residual"]["equilibrium"] == pytest.approx(run.residuals[:, 0].max())
    assert set(s["timings"]) == set(run.timings)
    out = s["outputs"]
    assert out["wear_max_final"] == pytest.approx(run.wear[-1].max())
    assert out["u_nu_max"] == pytest.approx(run.u_nu.max())
    assert out["penetration_max_final"] == pytest.approx(run.penetration[-1].max())
    assert out["wear_area_final"] == pytest.approx(run.problem.contact.weights @ run.wear[-1])
    lengths = np.linalg.norm(run.u, axis=-1)  # (S, n): |u| at every vertex and kept level
    assert out["displacement_max"] == pytest.approx(lengths.max(), rel=1e-15)
    assert out["displacement_max_final"] == pytest.approx(lengths[-1].max(), rel=1e-15)


def test_failed_save_keeps_old_files(run: Result, tmp_path: Path, monkeypatch) -> None:
    save_result(run, tmp_path, extra={"tag": "old"})
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}

    def boom(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr("vemwear.post.results.json.dumps", boom)
    with pytest.raises(OSError, match="disk full"):
        save_result(run, tmp_path, extra={"tag": "new"})
    after = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    assert after == before  # no temporary leftovers, old pair intact


def test_load_missing(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError):
        load_result(tmp_path)


# ---------------------------------------------------------------------------- figures


def test_plots_write_png(run: Result, tmp_path: Path) -> None:
    other = simulate(_problem(run.problem.mesh, steps=2))
    figs = {
        "profiles": lambda p: plot_contact_profiles(run, [0.25, 0.5, 0.75, 1.0], path=p),
        "displacement": lambda p: plot_displacement(run, path=p),
        "u2": lambda p: plot_displacement(run, level=4, path=p, component=1),
        "deformed": lambda p: plot_deformed(run, path=p),
        "history": lambda p: plot_time_history(run, path=p),
        "compare": lambda p: compare_profiles({"k=1/8": run, "k=1/2": other}, 1.0, path=p),
        "compare9": lambda p: compare_profiles(
            {"a": run, "b": other}, 0.5, quantity=("wear", "u_nu"), style="scatter", path=p
        ),
    }
    for name, make in figs.items():
        path = tmp_path / "figs" / f"{name}.png"
        fig = make(path)
        assert isinstance(fig, Figure), name
        assert _is_png(path), name


def test_profile_lines_and_titles(run: Result) -> None:
    times = [0.25, 0.5, 1.0]
    fig = plot_contact_profiles(run, times)
    axes = fig.get_axes()
    assert len(axes) == 2
    for ax in axes:
        assert len(ax.get_lines()) == len(times)
        assert ax.get_xlabel() and ax.get_ylabel()
    np.testing.assert_allclose(axes[0].get_lines()[-1].get_ydata(), run.wear[-1])
    np.testing.assert_allclose(axes[1].get_lines()[0].get_ydata(), run.penetration[run.level(0.25)])
    assert [t.get_text() for t in axes[0].get_legend().get_texts()] == [
        "$t$ = 0.25",
        "$t$ = 0.5",
        "$t$ = 1",
    ]
    title = fig.get_suptitle()
    assert "0.2" in title and "kappa" in title
    # default times are T/4, T/2, 3T/4, T
    assert len(plot_contact_profiles(run).get_axes()[0].get_lines()) == 4


def test_plot_argument_errors(run: Result) -> None:
    with pytest.raises(ValueError, match="not levels"):
        plot_contact_profiles(run, [0.3])
    with pytest.raises(ValueError, match="quantity"):
        compare_profiles({"a": run}, 1.0, quantity="stress")
    with pytest.raises(ValueError, match="component"):
        plot_displacement(run, component=2)
    with pytest.raises(ValueError, match="abscissa"):
        plot_contact_profiles(run, [1.0], abscissa="z")


def test_plots_on_polygons_and_bent_contact(run_mixed: Result, tmp_path: Path) -> None:
    assert set(run_mixed.problem.mesh.groups) == {3, 4, 6}
    fig = plot_contact_profiles(run_mixed, [0.5, 1.0], path=tmp_path / "p.png")
    assert "arc length" in fig.get_axes()[0].get_xlabel()
    # the contact chain turns the corner: the arc length increases along it
    assert np.all(np.diff(run_mixed.contact_s) > 0)
    plot_displacement(run_mixed, path=tmp_path / "d.png", component="magnitude")
    plot_deformed(run_mixed, level=2, path=tmp_path / "f.png", scale=3.0)
    for name in ("p", "d", "f"):
        assert _is_png(tmp_path / f"{name}.png")


# ---------------------------------------------------------------------------- VTK


def test_vtk_series(run: Result, tmp_path: Path) -> None:
    pvd = write_vtk_series(run, tmp_path)
    assert pvd == tmp_path / "solution.pvd"
    root = ET.parse(pvd).getroot()
    assert root.get("type") == "Collection"
    sets = root.findall("./Collection/DataSet")
    assert len(sets) == len(run.t)
    np.testing.assert_allclose([float(d.get("timestep")) for d in sets], run.t)
    mesh = run.problem.mesh
    nodes = run.contact_nodes
    for lv, ds in enumerate(sets):
        rel = ds.get("file")
        assert rel is not None and not Path(rel).is_absolute()
        m = meshio.read(pvd.parent / rel)
        assert len(m.points) == mesh.n_points
        np.testing.assert_allclose(m.points[:, :2], mesh.points)
        disp = m.point_data["displacement"]
        assert disp.shape == (mesh.n_points, 3)
        np.testing.assert_allclose(disp[:, :2], run.u[lv])
        assert np.all(disp[:, 2] == 0)
        for key in ("wear", "u_nu", "p_rigid", "p_soft"):  # the names of the API
            field = m.point_data[key]
            np.testing.assert_allclose(field[nodes], getattr(run, key)[lv])
            off = np.ones(mesh.n_points, bool)
            off[nodes] = False
            assert np.all(field[off] == 0)
        assert sum(len(b.data) for b in m.cells) == mesh.n_cells
        cell_id = np.concatenate(m.cell_data["cell_id"])
        strain = np.concatenate(m.cell_data["strain"])[np.argsort(cell_id)]
        ref, _stress, vm = cell_strain_stress(mesh, run.u[lv], run.problem.material)
        np.testing.assert_allclose(strain, ref.reshape(-1, 9), atol=1e-14)
        von_mises = np.concatenate(m.cell_data["von_mises"])[np.argsort(cell_id)]
        np.testing.assert_allclose(von_mises, vm)


def test_vtk_levels_subset_removes_stale(run: Result, run_mixed: Result, tmp_path: Path) -> None:
    write_vtk_series(run, tmp_path, name="s")
    pvd = write_vtk_series(run, tmp_path, levels=[0, -1], name="s")
    files = [d.get("file") for d in ET.parse(pvd).getroot().iter("DataSet")]
    assert files == ["s/s_0000.vtu", "s/s_0008.vtu"]
    assert sorted(p.name for p in (tmp_path / "s").iterdir()) == ["s_0000.vtu", "s_0008.vtu"]
    # general polygons read back
    pvd = write_vtk_series(run_mixed, tmp_path / "mixed", levels=[-1])
    m = meshio.read(tmp_path / "mixed" / "solution" / "solution_0004.vtu")
    assert sorted(len(b.data[0]) for b in m.cells) == [3, 4, 6]
    assert len(m.points) == run_mixed.problem.mesh.n_points
    with pytest.raises(IndexError):
        write_vtk_series(run, tmp_path, levels=[99])


def test_cell_strain_stress_linear_field() -> None:
    """The projection is exact on linear fields: eps = sym(A) on every polygon."""
    mesh = _mixed_mesh(6, 4)
    A = np.array([[0.01, 0.03], [-0.01, -0.02]])
    u = mesh.points @ A.T
    mat = Material(2.0, 3.0)
    strain, stress, vm = cell_strain_stress(mesh, u, mat)
    E = 0.5 * (A + A.T)
    shape = (mesh.n_cells, 2, 2)
    np.testing.assert_allclose(strain[:, :2, :2], np.broadcast_to(E, shape), atol=1e-14)
    assert np.all(strain[:, 2, :] == 0) and np.all(strain[:, :, 2] == 0)
    tr = np.trace(E)
    S = 2 * mat.eta * E + mat.lam * tr * np.eye(2)
    np.testing.assert_allclose(stress[:, :2, :2], np.broadcast_to(S, shape), atol=1e-13)
    np.testing.assert_allclose(stress[:, 2, 2], mat.lam * tr)
    szz = mat.lam * tr
    vm_ref = np.sqrt(
        0.5 * ((S[0, 0] - S[1, 1]) ** 2 + (S[1, 1] - szz) ** 2 + (szz - S[0, 0]) ** 2)
        + 3 * S[0, 1] ** 2
    )
    np.testing.assert_allclose(vm, vm_ref)


def test_jsonable_converts_numpy_paths_and_non_finite() -> None:
    from vemwear.post.results import jsonable

    data = {1: (np.float64(0.5), np.int64(3)), "a": np.array([1.0, np.nan]), "p": Path("x/y")}
    assert jsonable(data) == {"1": [0.5, 3], "a": [1.0, None], "p": "x/y"}
    json.dumps(jsonable({"inf": float("inf"), "f": np.sqrt}))  # no error
