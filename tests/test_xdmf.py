"""The ParaView series as XDMF + HDF5, read back; ``vemwear export`` from result.h5."""

from __future__ import annotations

import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import h5py
import meshio
import numpy as np
import pytest

from conftest import small_config
from vemwear.mesh import rectangle_voronoi, tag_rectangle
from vemwear.paper import ex52
from vemwear.post.vtk import cell_strain_stress
from vemwear.post.xdmf import mixed_topology, write_xdmf_series
from vemwear.simulate import Problem, simulate


def _decode(topo: np.ndarray) -> list[list[int]]:
    """Cells of an XDMF Mixed topology (triangles 4, quads 5, polygons 3 with a count)."""
    cells, i = [], 0
    while i < len(topo):
        kind = int(topo[i])
        n = {4: 3, 5: 4}.get(kind)
        if n is None:
            assert kind == 3
            n, i = int(topo[i + 1]), i + 1
        cells.append(topo[i + 1 : i + 1 + n].tolist())
        i += 1 + n
    return cells


def test_quad_series_reads_back_with_meshio(tmp_path: Path) -> None:
    pr = ex52.problem(0.2, 2.0, divisions=(8, 4), steps=8)
    r = simulate(pr, store=[0.5, 1.0])
    x = write_xdmf_series(r, tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["solution.h5", "solution.xdmf"]
    with meshio.xdmf.TimeSeriesReader(x) as rd:
        pts, cells = rd.read_points_cells()
        assert np.array_equal(pts, pr.mesh.points)
        assert [c.type for c in cells] == ["quad"] and len(cells[0].data) == pr.mesh.n_cells
        assert rd.num_steps == 2
        for k in range(2):
            t, pdata, cdata = rd.read_data(k)
            assert t == r.t[r.u_levels[k]]
            assert np.array_equal(pdata["displacement"][:, :2], r.displacement(r.u_levels[k]))
            nodes = r.contact_nodes
            assert np.array_equal(pdata["wear"][nodes], r.wear[r.u_levels[k]])
            assert set(cdata) == {"strain", "stress", "von_mises", "cell_id"}


def test_polygon_series_is_a_mixed_topology(tmp_path: Path) -> None:
    mesh = tag_rectangle(rectangle_voronoi(n_cells=40, seed=1))
    pr = Problem(
        mesh=mesh,
        material=ex52.problem(0.2, 2.0, divisions=(4, 2), steps=2).material,
        time=ex52.problem(0.2, 2.0, divisions=(4, 2), steps=4).time,
        f1=(0.0, -0.06),
        g=0.1,
        mu=0.2,
        kappa=2.0,
    )
    r = simulate(pr, store="final")
    x = write_xdmf_series(r, tmp_path)
    root = ET.parse(x).getroot()
    grids = root.findall(".//Grid[@GridType='Uniform']")
    assert len(grids) == 1
    topo_item = grids[0].find("Topology")
    assert topo_item is not None and topo_item.get("TopologyType") == "Mixed"
    assert int(topo_item.get("NumberOfElements", "0")) == mesh.n_cells
    with h5py.File(tmp_path / "solution.h5", "r") as f:
        topo = f["mesh/topology"][()]
        cells = _decode(topo)
        assert len(cells) == mesh.n_cells
        for k, c in enumerate(cells):
            assert c == mesh.cell_vertices[mesh.cell_offsets[k] : mesh.cell_offsets[k + 1]].tolist()
        assert np.array_equal(f["levels/0/displacement"][:, :2], r.displacement(-1))
        _, _, vm = cell_strain_stress(mesh, r.displacement(-1), pr.material)
        assert np.allclose(f["levels/0/von_mises"][()], vm, rtol=1e-14, atol=0)
    assert np.array_equal(mixed_topology(mesh), topo)


def test_export_writes_result_npz_from_the_stream(tmp_path: Path) -> None:
    cfg = tmp_path / "case.toml"
    cfg.write_text(small_config("export", output={"every": 3, "figures": False, "vtk": False}))
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "vemwear"]
    assert subprocess.run([*cmd, "run", str(cfg), "-o", str(out), "--no-progress"]).returncode == 0
    with np.load(out / "result.npz") as z:
        want = {k: z[k] for k in z.files}
    again = subprocess.run([*cmd, "export", str(out)], capture_output=True, text=True)
    assert again.returncode == 2 and "exists; use --force" in again.stderr
    (out / "result.npz").unlink()
    done = subprocess.run([*cmd, "export", str(out)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    with np.load(out / "result.npz") as z:
        got = {k: z[k] for k in z.files}
    assert {0, 3, 6, 8} <= set(want["levels"].tolist()) and len(want["levels"]) < 9
    for k, v in want.items():
        assert np.array_equal(got[k], v), k
    none = subprocess.run([*cmd, "export", str(tmp_path)], capture_output=True, text=True)
    assert none.returncode == 2 and "no streamed result" in none.stderr


@pytest.mark.parametrize("paraview", ["xdmf", "pvd"])
def test_run_writes_the_chosen_paraview_series(tmp_path: Path, paraview: str) -> None:
    cfg = tmp_path / "case.toml"
    cfg.write_text(
        small_config(
            "pv", output={"figures": False, "vtk": True, "paraview": paraview, "store_u": 2}
        )
    )
    out = tmp_path / "out"
    done = subprocess.run(
        [sys.executable, "-m", "vemwear", "run", str(cfg), "-o", str(out), "--no-progress"]
    )
    assert done.returncode == 0
    if paraview == "xdmf":
        assert (out / "solution.xdmf").read_text().count("<Time ") == 5  # levels 0,2,4,6,8
        assert not (out / "solution.pvd").exists()
    else:
        assert len(list((out / "solution").glob("*.vtu"))) == 5
        assert not (out / "solution.xdmf").exists()
