"""``vemwear run`` and ``run_config`` of an ``[adapt]`` configuration: result.h5 with one
group per mesh (read back with h5py), the ParaView series on the hanging-node meshes
(read back with meshio), summary.json, and a run killed by SIGKILL that resumes to the
arrays of a run that never stopped, bitwise."""

from __future__ import annotations

import dataclasses
import itertools
import json
import re
import signal
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import h5py
import meshio
import numpy as np
import pytest

from conftest import run_until_segments, segments_done, small_config
from vemwear import run_config
from vemwear.config import load_config
from vemwear.runner import ResumeError
from vemwear.simulate.adaptive_time import simulate_adaptive

ADAPT = "[adapt]\nevery = 2\nmax_cells = 200\ncoarsen = true\n"
ROWS = ("wear", "u_nu", "p_rigid", "p_soft", "penetration", "iterations", "residuals", "u")


def _config(
    tmp_path: Path, steps: int = 8, figures: bool = False, adapt: str = ADAPT, paraview: str = "pvd"
) -> Path:
    out = {"times": [0.5, 1.0], "figures": figures, "vtk": figures, "paraview": paraview}
    p = tmp_path / "case.toml"
    p.write_text(small_config("adaptive", steps=steps, output=out) + adapt)
    return p


def _groups(path: Path) -> dict[str, dict[str, np.ndarray]]:
    with h5py.File(path, "r") as f:
        names = [n for n in sorted(f) if n.startswith("mesh_")]
        return {n: {k: np.asarray(f[n][k][()]) for k in f[n]} for n in names}


def test_the_cli_writes_every_mesh_with_its_levels(tmp_path: Path) -> None:
    config = _config(tmp_path, figures=True)
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "vemwear", "run", str(config), "-o", str(out), "--no-progress"]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "adaptive: done" in done.stdout and "meshes" in done.stdout
    groups = _groups(out / "result.h5")
    with h5py.File(out / "result.h5", "r") as f:
        t = f["t"][()]
        first, last = f["segment_first"][()], f["segment_last"][()]
        assert int(f["completed"][()]) == len(t) == 9
    # the meshes own the levels 0 .. 8 once each, in order
    owned = np.concatenate([g["levels"] for g in groups.values()])
    assert np.array_equal(owned, np.arange(9))
    assert np.array_equal(first, [g["first"] for g in groups.values()])
    assert np.array_equal(last, [g["last"] for g in groups.values()])
    summary = json.loads((out / "summary.json").read_text())
    meshes = summary["adaptive"]["meshes"]
    assert len(meshes) == len(groups) >= 3 and summary["partial"] is False
    assert meshes[-1]["cells"] > meshes[0]["cells"] == 32
    for m, (name, g) in zip(meshes, groups.items(), strict=True):
        assert m["group"] == name and m["cells"] == len(g["cells_offsets"]) - 1
        assert m["dofs"] == 2 * len(g["points"]) and m["contact_nodes"] == len(g["contact_nodes"])
        assert g["wear"].shape == (len(g["levels"]), len(g["contact_nodes"]))
        assert g["u"].shape == (len(g["levels"]), len(g["points"]), 2)
        assert np.array_equal(g["t"], t[g["levels"]])
        assert len(g["tree_level"]) == m["cells"] and g["eta_jump"].shape == (m["cells"],)
    # every level in ParaView, on the mesh that computed it; hanging nodes as polygon vertices
    pvd = out / "solution.pvd"
    files = [d.get("file") for d in ET.parse(pvd).iter("DataSet")]
    assert len(files) == 9
    for g in groups.values():
        for lv, row in ((g["levels"][0], 0), (g["levels"][-1], len(g["levels"]) - 1)):
            m = meshio.read(out / files[lv])
            assert np.array_equal(m.points[:, :2], g["points"])
            conn = np.concatenate([c.data.ravel() for c in m.cells])
            assert np.array_equal(np.sort(conn), np.sort(g["cells_vertices"]))
            wear = m.point_data["wear"]
            assert np.array_equal(wear[g["contact_nodes"]], g["wear"][row])
    last_vtu = meshio.read(out / files[-1])
    sizes = [c.data.shape[1] for c in last_vtu.cells if c.type == "polygon"]
    assert sizes and max(sizes) > 4  # squares with hanging nodes on their sides
    for name in ("contact_profiles.png", "meshes.png"):
        assert (out / name).stat().st_size > 10_000
    marker = json.loads((out / ".vemwear").read_text())
    assert marker["state"] == "complete" and not (out / "checkpoint.npz").exists()


def test_run_config_gives_the_arrays_of_simulate_adaptive(tmp_path: Path) -> None:
    config = _config(tmp_path)
    outcome = run_config(config, tmp_path / "out", progress=False)
    assert outcome.result is None and outcome.segments is not None
    cfg = load_config(config)
    assert cfg.adapt is not None
    ref = simulate_adaptive(cfg.problem, **dataclasses.asdict(cfg.adapt), solver=cfg.solver)
    groups = list(_groups(tmp_path / "out" / "result.h5").values())
    assert len(groups) == len(ref) == len(outcome.segments)
    for k, (g, seg, got) in enumerate(zip(groups, ref, outcome.segments, strict=True)):
        rows = np.arange(seg.first, seg.last + (k == len(ref) - 1))
        assert np.array_equal(g["points"], seg.problem.mesh.points)
        assert np.array_equal(g["tree_level"], seg.tree.level)
        for name in ROWS:
            if name == "u":
                mine = np.stack([seg.result.displacement(lv) for lv in rows])
            else:
                mine = getattr(seg.result, name)[rows]
            assert np.array_equal(g[name], mine), name
            assert np.array_equal(getattr(got.result, name), mine), name
        assert got.estimate.total == seg.estimate.total
    from vemwear.post.stream import export_npz

    with pytest.raises(ValueError, match=r"holds an \[adapt\] run, one group per mesh"):
        export_npz(tmp_path / "out")


def test_target_error_stops_the_refinement(tmp_path: Path) -> None:
    loose = _config(tmp_path, adapt="[adapt]\nevery = 2\ntarget_error = 1.0\n")
    outcome = run_config(loose, tmp_path / "out", progress=False)
    assert outcome.segments is not None
    assert {s.problem.mesh.n_cells for s in outcome.segments} == {32}  # eta < 1 already


# ---------------------------------------------------------------------------- resume
KILL_STEPS = 32  # 16 mesh changes, about 0.1 s each


def _cli(config: Path, out: Path, *extra: str) -> list[str]:
    cmd = [sys.executable, "-m", "vemwear", "run", str(config), "-o", str(out), "--no-progress"]
    return [*cmd, *extra]


def test_sigkill_after_a_mesh_change_resumes_bitwise(tmp_path: Path) -> None:
    config = _config(tmp_path, steps=KILL_STEPS, adapt=ADAPT.replace("200", "120"))
    ref_out = tmp_path / "ref"
    run_config(config, ref_out, progress=False)
    reference = _groups(ref_out / "result.h5")
    out = tmp_path / "out"
    proc = run_until_segments(
        _cli(config, out), out, 3
    )  # past the third mesh change, in the middle of the run
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    assert proc.returncode == -signal.SIGKILL
    done = segments_done(out)
    assert 3 <= done < len(reference)
    assert json.loads((out / ".vemwear").read_text())["state"] == "running"
    with pytest.raises(ResumeError, match=r"holds a stopped run .* --resume"):
        run_config(config, out, progress=False)
    resumed = subprocess.run(_cli(config, out, "--resume"), capture_output=True, text=True)
    assert resumed.returncode == 0, resumed.stderr
    assert "resumed from level" in resumed.stdout
    got = _groups(out / "result.h5")
    assert got.keys() == reference.keys()
    for name, g in reference.items():
        assert got[name].keys() == g.keys()
        for k, v in g.items():
            assert got[name][k].dtype == v.dtype and np.array_equal(got[name][k], v), (name, k)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["resumed_from_level"] == 2 * done
    assert not (out / "checkpoint.npz").exists()


def test_resume_refuses_other_adapt_settings(tmp_path: Path) -> None:
    config = _config(tmp_path, steps=KILL_STEPS)
    out = tmp_path / "out"
    proc = run_until_segments(_cli(config, out), out, 1)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    config.write_text(config.read_text().replace("max_cells = 200", "max_cells = 150"))
    with pytest.raises(ResumeError, match=r"--resume refused: .* other \[adapt\] settings"):
        run_config(config, out, resume=True, progress=False)


def test_the_shipped_example_refines_at_the_clamped_corners(tmp_path: Path) -> None:
    from vemwear.examples import config_path
    from vemwear.mesh.locate import locate_cells
    from vemwear.simulate import simulate

    config = config_path("example_5_2_adaptive")
    out = tmp_path / "out"
    done = subprocess.run(_cli(config, out), capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    summary = json.loads((out / "summary.json").read_text())
    meshes = summary["adaptive"]["meshes"]
    assert [m["first"] for m in meshes] == [0, 4, 8, 12] and meshes[-1]["last"] == 16
    assert meshes[0]["cells"] == 128 < meshes[-1]["cells"] <= 600
    groups = _groups(out / "result.h5")
    last = groups[meshes[-1]["group"]]
    from vemwear.post.results import mesh_from_arrays

    mesh = mesh_from_arrays(last)
    corner, middle = locate_cells(mesh, np.array([[0.01, 0.01], [1.5, 0.5]]))
    assert last["tree_level"][corner] == 3 and last["tree_level"][middle] == 0
    # the wear agrees with the run on the initial mesh to a few percent
    cfg = load_config(config)
    plain = simulate(cfg.problem, cfg.solver, store="final")
    w_plain, w_adapt = plain.wear[-1].max(), last["wear"][-1].max()
    assert abs(w_adapt - w_plain) < 0.03 * w_plain
    assert summary["outputs"]["wear_max_final"] == w_adapt
    # the XDMF series: every mesh once, every level's grid on its mesh
    root = ET.parse(out / "solution.xdmf").getroot()
    grids = list(root.iter("Grid"))[1:]
    assert len(grids) == 17
    with h5py.File(out / "solution.h5", "r") as f:
        assert sorted(n for n in f if n.startswith("mesh_")) == sorted(groups)
        for lv, grid in enumerate(grids):
            m = next(mm for mm in meshes if mm["owns_levels"][0] <= lv <= mm["owns_levels"][1])
            g = groups[m["group"]]
            assert float(grid.find("Time").get("Value")) == lv / 16
            topo_path = grid.find("Topology/DataItem").text.split(":")[1]
            assert topo_path == f"/{m['group']}/topology"
            cells = _decode(f[topo_path][()])
            off = g["cells_offsets"]
            assert cells == [g["cells_vertices"][a:b].tolist() for a, b in itertools.pairwise(off)]
            attrs = {
                a.get("Name"): a.find("DataItem").text.split(":")[1] for a in grid.iter("Attribute")
            }
            row = lv - m["owns_levels"][0]
            assert np.array_equal(f[attrs["wear"]][()][g["contact_nodes"]], g["wear"][row])
            assert np.array_equal(f[attrs["level"]][()], g["tree_level"])
        assert max(len(c) for c in cells) > 4  # hanging nodes


def _decode(topo: np.ndarray) -> list[list[int]]:
    """Cells of an XDMF Mixed topology (triangles 4, quads 5, polygons 3 with a count)."""
    cells, i = [], 0
    while i < len(topo):
        kind = int(topo[i])
        n = {4: 3, 5: 4}.get(kind)
        if n is None:
            n, i = int(topo[i + 1]), i + 1
        cells.append(topo[i + 1 : i + 1 + n].tolist())
        i += 1 + n
    return cells


def test_a_study_of_adaptive_runs(tmp_path: Path) -> None:
    xr = pytest.importorskip("xarray")
    pytest.importorskip("distributed")
    from vemwear.studies import sweep

    (tmp_path / "case.toml").write_text(_config(tmp_path).read_text())
    study = tmp_path / "study.toml"
    study.write_text(
        'base = "case.toml"\n[axes]\n"contact.kappa" = [1.0, 4.0]\n'
        '[overrides]\n"output.figures" = false\n'
    )
    out = tmp_path / "study"
    ds = sweep(study, out, workers=1, progress=False, figures=False)
    assert ds.attrs["runs_computed"] == 2 and ds.attrs["runs_failed"] == 0
    back = xr.open_dataset(out / "study.nc", engine="h5netcdf")
    mw = back["max_wear"].values
    assert mw[1] > mw[0] > 0  # more wear with a larger kappa
    for i, rid in enumerate(back["run_id"].values):
        groups = list(_groups(out / "runs" / str(rid) / "result.h5").values())
        last = groups[-1]
        assert mw[i] == last["wear"][-1].max()
        assert np.isclose(back["worn_volume"].values[i], last["contact_weights"] @ last["wear"][-1])
        assert back["max_p_soft"].values[i] == max(g["p_soft"].max() for g in groups)
        # the final profile is the final mesh's piecewise linear wear
        profile = back["wear"].isel(contact_kappa=i, time=-1).values
        s = back["s"].values
        inside = (s >= last["contact_s"][0]) & (s <= last["contact_s"][-1])
        want = np.interp(s[inside], last["contact_s"], last["wear"][-1])
        assert np.allclose(profile[inside], want, rtol=0, atol=1e-14)
    back.close()


def test_sigterm_keeps_the_finished_meshes_and_says_how_to_resume(tmp_path: Path) -> None:
    config = _config(tmp_path, steps=KILL_STEPS)
    out = tmp_path / "out"
    proc = run_until_segments(_cli(config, out), out, 2)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 130, err
    done = segments_done(out)
    assert f"continue with: vemwear run {config}" in err.decode() and "--resume" in err.decode()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["partial"] is True and summary["completed"] == 2 * done
    assert "terminated (SIGTERM)" in (out / "PARTIAL.txt").read_text()
    assert len(_groups(out / "result.h5")) >= done  # the finished meshes are kept
    outcome = run_config(config, out, resume=True, progress=False)
    assert outcome.resumed_from == 2 * done and outcome.segments is not None
    assert outcome.segments[-1].last == KILL_STEPS and not (out / "PARTIAL.txt").exists()


def test_wear_beyond_the_layer_stops_at_its_first_level(tmp_path: Path) -> None:
    """A wear that passes the layer's thickness g stops the adaptive run (exit 3) at the
    first level where it does, the one simulate_adaptive's arrays show."""
    config = tmp_path / "worn.toml"
    config.write_text(small_config("worn", steps=8, contact={"kappa": 40.0}) + ADAPT)
    done = subprocess.run(_cli(config, tmp_path / "out"), capture_output=True, text=True)
    assert done.returncode == 3, done.stderr
    said = done.stderr.split("exceeds the layer thickness at time level ")[1]
    cfg = load_config(config)
    assert cfg.adapt is not None
    segs = simulate_adaptive(cfg.problem, **dataclasses.asdict(cfg.adapt), solver=cfg.solver)
    first = min(
        lv
        for k, s in enumerate(segs)
        for lv in range(s.first, s.last + (k == len(segs) - 1))
        if np.any(s.result.wear[int(np.searchsorted(s.result.levels, lv))] > s.problem.nodal["g"])
    )
    assert said.startswith(f"{first} "), said


def test_the_progress_bar_counts_the_levels_of_every_mesh(tmp_path: Path, capsys) -> None:
    config = _config(tmp_path)
    run_config(config, tmp_path / "out", progress=True)
    err = capsys.readouterr().err
    # one update per mesh change, with the cells of the mesh that computed the levels
    counts = [int(m) for m in re.findall(r"time levels:\s+\d+%\|[^|]*\|\s+(\d+)/9", err)]
    assert counts[-1] == 9 and counts == sorted(counts) and len(set(counts)) >= 3
    assert re.search(r"\d+ cells", err)
    run_config(config, tmp_path / "quiet", progress=False)
    assert "time levels" not in capsys.readouterr().err


def test_resume_takes_a_checkpoint_written_before_the_wear_settings(tmp_path: Path) -> None:
    """A checkpoint without ``estimator`` and ``transfer`` (written before they existed) is
    one of the residual estimator and the linear transfer: resumed with those, refused
    with others."""
    config = _config(tmp_path, steps=KILL_STEPS)
    out = tmp_path / "out"
    proc = run_until_segments(_cli(config, out), out, 1)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    path = out / "checkpoint.npz"
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    meta = json.loads(str(arrays["meta"]))
    assert meta["adapt"]["estimator"] == "residual" and meta["adapt"]["transfer"] == "linear"
    del meta["adapt"]["estimator"], meta["adapt"]["transfer"]
    arrays["meta"] = np.array(json.dumps(meta))
    with path.open("wb") as fh:
        np.savez(fh, **arrays)
    text = config.read_text()
    config.write_text(text.replace("[adapt]\n", '[adapt]\ntransfer = "cubic"\n'))
    with pytest.raises(ResumeError, match=r"--resume refused: .* other \[adapt\] settings"):
        run_config(config, out, resume=True, progress=False)
    config.write_text(text)
    outcome = run_config(config, out, resume=True, progress=False)
    assert outcome.segments is not None and (out / "result.h5").is_file()
