"""Output directories after faults: a user's files under --force, a set-up killed before
its first checkpoint, --resume of a finished run, the manifest in the marker."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import small_config
from vemwear.cli.main import main
from vemwear.runner import atomic_output_dir

OFF = {"figures": False, "vtk": False}


@pytest.fixture
def cfg(tmp_path: Path) -> Path:
    p = tmp_path / "case.toml"
    p.write_text(small_config("case", output=OFF))
    return p


def _run(cfg: Path, out: Path, *extra: str) -> int:
    return main(["run", str(cfg), "-o", str(out), "--no-progress", *extra])


def _dead_pid() -> int:
    """The pid of a process that has ended (what a killed run's lock file holds)."""
    proc = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"],
        text=True,
        capture_output=True,
        check=True,
    )
    return int(proc.stdout)


def _killed_setup(out: Path, marker: bool) -> None:
    """What ``kill -9`` during a run's set-up leaves: the lock file of a dead process and,
    once the time loop was about to start, the marker of a running run and its stream."""
    out.mkdir()
    (out / ".vemwear.lock").write_text(str(_dead_pid()))
    if marker:
        (out / ".vemwear").write_text(
            json.dumps(
                {
                    "format": "vemwear-outdir/1",
                    "state": "running",
                    "command": "run",
                    "files": [".vemwear", ".vemwear.lock", "checkpoint.npz", "result.h5"],
                }
            )
        )
        (out / "result.h5").write_bytes(b"\x89HDF\r\n\x1a\n")  # begun, never checkpointed


def test_force_keeps_a_users_file_that_the_output_would_overwrite(
    cfg: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    assert _run(cfg, out) == 0  # figures and VTK off
    marker = json.loads((out / ".vemwear").read_text())
    assert marker["manifest"]["result.npz"]["size"] == (out / "result.npz").stat().st_size
    for name in ("forces.png", "solution.xdmf"):  # the user's own, put in later
        (out / name).write_text("mine")
    cfg.write_text(small_config("case", output={"figures": True, "vtk": True}))
    capsys.readouterr()
    assert _run(cfg, out, "--force") == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{out / 'forces.png'} was not written by vemwear" in err
    assert (out / "forces.png").read_text() == "mine" == (out / "solution.xdmf").read_text()
    assert (out / "result.npz").exists()  # refused before touching anything
    # a file vemwear wrote and the user changed since is not replaced either
    (out / "forces.png").unlink()
    (out / "solution.xdmf").unlink()
    with open(out / "summary.json", "a") as f:
        f.write("\n")
    assert _run(cfg, out, "--force") == 2
    assert f"{out / 'summary.json'} changed since vemwear wrote it" in capsys.readouterr().err
    (out / "summary.json").unlink()
    (out / "notes.txt").write_text("mine")  # another name: kept, the run goes on
    assert _run(cfg, out, "--force") == 0
    assert (out / "notes.txt").read_text() == "mine" and (out / "forces.png").exists()


def test_atomic_output_keeps_a_users_file_of_an_output_name(tmp_path: Path) -> None:
    out = tmp_path / "ex"
    with atomic_output_dir(out) as tmp:
        (tmp / "table.md").write_text("1")
    (out / "forces.png").write_text("mine")
    with pytest.raises(ValueError, match=r"forces\.png was not written by vemwear"):
        with atomic_output_dir(out, force=True) as tmp:
            (tmp / "forces.png").write_text("ours")
    assert (out / "forces.png").read_text() == "mine" and (out / "table.md").read_text() == "1"


@pytest.mark.parametrize("marker", [False, True], ids=["lock only", "lock and marker"])
@pytest.mark.parametrize("how", [[], ["--force"], ["--resume"]])
def test_a_set_up_killed_before_its_first_checkpoint_is_recognised(
    cfg: Path,
    tmp_path: Path,
    marker: bool,
    how: list[str],
    capsys: pytest.CaptureFixture[str],
) -> None:
    ref = tmp_path / "ref"
    assert _run(cfg, ref) == 0
    out = tmp_path / "out"
    _killed_setup(out, marker)
    assert _run(cfg, out, *how) == 0, capsys.readouterr().err
    with np.load(ref / "result.npz") as a, np.load(out / "result.npz") as b:
        for k in ("u", "wear", "p_soft", "p_rigid"):
            assert np.array_equal(a[k], b[k]), k
    if how == ["--resume"]:
        assert "saved no level; starting from level 0" in capsys.readouterr().err


@pytest.mark.parametrize("marker", [False, True], ids=["lock only", "lock and marker"])
@pytest.mark.parametrize("everything", [False, True], ids=["clean", "clean --all"])
def test_clean_empties_a_set_up_killed_before_its_first_checkpoint(
    tmp_path: Path, marker: bool, everything: bool
) -> None:
    out = tmp_path / "out"
    _killed_setup(out, marker)
    assert main(["clean", str(out), *(["--all"] if everything else [])]) == 0
    assert list(out.iterdir()) == []


def test_a_run_killed_while_probing_its_directory_leaves_a_temporary(
    cfg: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Killed between the probe file's creation and its removal, a run leaves only that
    file: the directory is taken as empty (with a warning), and clean removes it."""
    import tempfile

    from vemwear.runner.outdir import PROBE_PREFIX

    out = tmp_path / "out"
    out.mkdir()
    fd, name = tempfile.mkstemp(dir=out, prefix=PROBE_PREFIX)
    os.close(fd)
    assert _run(cfg, out) == 0
    assert "temporary file(s) of killed runs" in capsys.readouterr().err
    assert main(["clean", str(out)]) == 0
    assert not Path(name).exists() and (out / "result.npz").is_file()


def test_resume_of_a_finished_run_says_it_is_complete(
    cfg: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    assert _run(cfg, out) == 0
    before = {p.name: p.stat().st_mtime_ns for p in out.iterdir()}
    capsys.readouterr()
    assert _run(cfg, out, "--resume") == 0
    got = capsys.readouterr()
    assert got.out == f"vemwear: {out} holds a complete run; there is nothing to resume\n"
    assert got.err == ""
    assert {p.name: p.stat().st_mtime_ns for p in out.iterdir()} == before
    # killed between the marker "complete" and removing the checkpoint: strays go
    (out / "checkpoint.npz").write_bytes(b"x")
    (out / "PARTIAL.txt").write_text("x")
    assert main(["clean", str(out)]) == 0
    assert {p.name for p in out.iterdir()} == set(before)
    assert os.path.exists(out / "result.npz")
