"""One name per quantity in result files, and files of the earlier format still read.

``tests/data/result_v1`` holds files written by vemwear before format 2 (the pressures
were ``lam`` and ``p`` then, and ``result.npz`` had no ``format``): ``done/`` a finished
run of ``case.toml`` (``result.npz``, ``result.h5``, ``summary.json``) and ``stopped/`` the
same run stopped by a solver failure after 4 of its 7 levels (checkpoint, streamed
levels, marker).
"""

from __future__ import annotations

import json
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import h5py
import numpy as np
import pytest

from vemwear.cli.main import main
from vemwear.post import load_result
from vemwear.post.stream import read_stream

V1 = Path(__file__).parent / "data" / "result_v1"
OLD = {"lam": "p_rigid", "p": "p_soft"}


def raw_npz(path: Path) -> dict[str, np.ndarray]:
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def test_fixture_is_format_1() -> None:
    raw = raw_npz(V1 / "done" / "result.npz")
    assert {"lam", "p"} <= raw.keys() and "format" not in raw and "p_rigid" not in raw
    with h5py.File(V1 / "stopped" / "result.h5", "r") as f:
        assert "lam" in f and "p" in f and "format" not in f


def test_format_1_npz_and_h5_read_under_todays_names() -> None:
    raw = raw_npz(V1 / "done" / "result.npz")
    data = load_result(V1 / "done")
    assert "lam" not in data and "p" not in data
    assert data["format"].item() == "vemwear-result/2"
    for old, new in OLD.items():
        assert np.array_equal(data[new], raw[old])
    stream = read_stream(V1 / "done" / "result.h5")
    assert "lam" not in stream and "p" not in stream
    for key in ("t", "wear", "u_nu", "p_rigid", "p_soft", "iterations", "u"):
        assert np.array_equal(stream[key], data[key]), key


def test_newer_format_is_refused_in_one_line(tmp_path: Path) -> None:
    raw = raw_npz(V1 / "done" / "result.npz")
    raw["format"] = np.array("vemwear-result/9")
    with open(tmp_path / "result.npz", "wb") as fh:
        np.savez(fh, **raw)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"result\.npz: .*'vemwear-result/9' is newer"):
        load_result(tmp_path)


def test_run_writes_one_name_everywhere(tmp_path: Path) -> None:
    config = tmp_path / "case.toml"
    config.write_text((V1 / "case.toml").read_text().replace("vtk = false", "vtk = true"))
    out = tmp_path / "out"
    assert main(["run", str(config), "-o", str(out), "--no-progress"]) == 0
    raw = raw_npz(out / "result.npz")
    assert raw["format"].item() == "vemwear-result/2"
    assert {"p_rigid", "p_soft"} <= raw.keys() and not {"lam", "p"} & raw.keys()
    with h5py.File(out / "result.h5", "r") as f:
        assert "p_rigid" in f and "p_soft" in f and "lam" not in f and "p" not in f
        assert f["format"][()].decode() == "vemwear-result/2"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["format"] == "vemwear-result/2"
    assert summary["outputs"]["p_rigid_max"] == pytest.approx(raw["p_rigid"].max())
    assert summary["outputs"]["p_soft_max"] == pytest.approx(raw["p_soft"].max())
    assert "lam_max" not in summary["outputs"]
    xdmf = ET.parse(out / "solution.xdmf")
    names = {a.get("Name") for a in xdmf.iter("Attribute") if a.get("Center") == "Node"}
    assert {"p_rigid", "p_soft"} <= names and not {"lam", "p"} & names
    # the same numbers as the run of format 1 (same inputs, same code path)
    old = raw_npz(V1 / "done" / "result.npz")
    for old_name, new in OLD.items():
        assert np.array_equal(raw[new], old[old_name])


def test_export_of_format_1_stream_writes_format_2(tmp_path: Path) -> None:
    out = tmp_path / "done"
    out.mkdir()
    shutil.copy2(V1 / "done" / "result.h5", out / "result.h5")
    assert main(["export", str(out)]) == 0
    raw = raw_npz(out / "result.npz")
    assert raw["format"].item() == "vemwear-result/2" and "lam" not in raw
    old = raw_npz(V1 / "done" / "result.npz")
    for old_name, new in OLD.items():
        assert np.array_equal(raw[new], old[old_name])


def test_stopped_run_of_format_1_resumes_bitwise(tmp_path: Path) -> None:
    shutil.copy2(V1 / "case.toml", tmp_path / "case.toml")
    out = tmp_path / "stopped"
    shutil.copytree(V1 / "stopped", out)
    code = main(["run", str(tmp_path / "case.toml"), "-o", str(out), "--resume", "--no-progress"])
    assert code == 0
    raw = raw_npz(out / "result.npz")
    old = raw_npz(V1 / "done" / "result.npz")
    assert raw["format"].item() == "vemwear-result/2" and not {"lam", "p"} & raw.keys()
    for key in ("t", "u", "u_levels", "wear", "u_nu", "penetration", "iterations", "residuals"):
        assert np.array_equal(raw[key], old[key]), key
    for old_name, new in OLD.items():
        assert np.array_equal(raw[new], old[old_name])
    with h5py.File(out / "result.h5", "r") as f:  # renamed in place, not copied
        assert "p_rigid" in f and "lam" not in f and "p" not in f
