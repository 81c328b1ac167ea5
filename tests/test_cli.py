"""The ``vemwear`` command: check, run, example, exit codes and atomic output directories."""

from __future__ import annotations

import importlib
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import small_config
from vemwear import __version__
from vemwear.cli.main import main
from vemwear.paper import EXAMPLES, available_examples, ex52, load_example
from vemwear.runner import OutputDirError, atomic_output_dir
from vemwear.simulate import SolverOptions

SMALL = small_config(
    "small run", output={"times": [0.25, 0.5, 0.75, 1.0], "figures": True, "vtk": True}
)


@pytest.fixture
def small(tmp_path: Path) -> Path:
    p = tmp_path / "small.toml"
    p.write_text(SMALL)
    return p


def leftovers(parent: Path) -> list[str]:
    """Temporary directories of the atomic output left in ``parent``."""
    return [p.name for p in parent.iterdir() if p.name.startswith(".") and "tmp" in p.name]


# ---------------------------------------------------------------------------- help
def test_version_and_help(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"vemwear {__version__}"
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    for word in ("run", "check", "example", "exit codes", "130", "docs/config.md"):
        assert word in out
    for cmd in ("run", "check", "example"):
        assert main([cmd, "--help"]) == 0
        assert "usage: vemwear " + cmd in capsys.readouterr().out
    main(["example", "--help"])
    assert "5.2" in capsys.readouterr().out


def test_usage_errors_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    assert main([]) == 2
    assert main(["run"]) == 2
    assert main(["example", "9.9", "-o", "x"]) == 2
    assert "invalid choice" in capsys.readouterr().err


# ---------------------------------------------------------------------------- check
def test_check(small: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["check", str(small)]) == 0
    out = capsys.readouterr().out
    assert "small run: valid" in out
    assert "45 vertices, 32 cells" in out
    assert "contact nodes" in out and "8 on 8 contact edges" in out
    assert "9 on [0, 1], k = 0.125 = 1/8" in out
    assert "smallness" in out


def test_check_invalid_is_exit_2_without_traceback(
    small: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    small.write_text(SMALL.replace("mu = 0.2", "mu = -0.2"))
    assert main(["check", str(small)]) == 2
    err = capsys.readouterr().err
    assert err == (
        f"vemwear: error: {small}: [contact] mu must be >= 0 on the contact part; it is -0.2 "
        "at contact node 0 (vertex 1, x = [0.25, 0.0])\n"
    )
    assert main(["check", str(small), "--debug"]) == 2
    assert "Traceback" in capsys.readouterr().err


def test_check_subprocess(small: Path) -> None:
    ok = subprocess.run(
        [sys.executable, "-m", "vemwear.cli.main", "check", str(small)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert ok.returncode == 0, ok.stderr
    small.write_text(SMALL.replace("kappa = 2.0", "kapa = 2.0"))
    bad = subprocess.run(
        [sys.executable, "-m", "vemwear.cli.main", "check", str(small)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert bad.returncode == 2
    assert bad.stderr.strip() == (
        f"vemwear: error: {small}: [contact] unknown key 'kapa'; did you mean 'kappa'?"
    )


# ---------------------------------------------------------------------------- run
def test_run_writes_everything(
    small: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    assert main(["run", str(small), "-o", str(out), "--no-progress"]) == 0
    names = {p.name for p in out.iterdir()}
    assert {
        "result.npz",
        "summary.json",
        "contact_profiles.png",
        "displacement.png",
        "deformed.png",
        "time_history.png",
        "forces.png",
        "solution.xdmf",
        "solution.h5",
        "result.h5",
        ".vemwear",
    } <= names
    assert "checkpoint.npz" not in names and "PARTIAL.txt" not in names
    # by default the displacement is stored at the levels of [output] times and T
    assert (out / "solution.xdmf").read_text().count("<Time ") == 4
    summary = json.loads((out / "summary.json").read_text())
    extra = summary["inputs"]["extra"]
    assert extra["config"]["contact"]["mu"] == 0.2
    assert extra["config_path"] == str(small.resolve())
    with np.load(out / "result.npz") as z:
        assert z["wear"].shape == (9, 8)
    text = capsys.readouterr().out
    for word in ("levels", "9 (T = 1", "max KKT residual", "max wear at T", "time", str(out)):
        assert word in text
    assert leftovers(tmp_path) == []


def test_output_directory_is_never_a_trap(
    small: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """--force replaces only what vemwear wrote; a user's directory is never touched; an
    existing empty directory is written into as it is (same inode: never renamed)."""
    small.write_text(
        SMALL.replace("figures = true", "figures = false").replace("vtk = true", "vtk = false")
    )
    mine = tmp_path / "myproject"
    mine.mkdir()
    (mine / "thesis.tex").write_text("keep me")
    for extra in ([], ["--force"]):
        assert main(["run", str(small), "-o", str(mine), "--no-progress", *extra]) == 2
        err = capsys.readouterr().err
        assert "is not empty and was not written by vemwear" in err and err.count("\n") == 1
        assert [p.name for p in mine.iterdir()] == ["thesis.tex"]
        assert (mine / "thesis.tex").read_text() == "keep me"

    out = tmp_path / "out"
    assert main(["run", str(small), "-o", str(out), "--no-progress"]) == 0
    assert main(["run", str(small), "-o", str(out), "--no-progress"]) == 2
    assert "holds the output of an earlier vemwear run; use --force" in capsys.readouterr().err
    (out / "notes.txt").write_text("mine")  # a user's file put into vemwear's directory
    assert main(["run", str(small), "-o", str(out), "--no-progress", "--force"]) == 0
    assert (out / "notes.txt").read_text() == "mine" and (out / "result.npz").exists()
    assert leftovers(tmp_path) == []

    empty = tmp_path / "empty"
    empty.mkdir()
    inode = empty.stat().st_ino
    assert main(["run", str(small), "-o", str(empty), "--no-progress"]) == 0
    assert empty.stat().st_ino == inode and (empty / "result.npz").exists()


@pytest.mark.parametrize("method", ["newton-full", "uzawa"])
def test_non_convergence_is_exit_3_and_leaves_nothing(
    small: Path, tmp_path: Path, method: str, capsys: pytest.CaptureFixture[str]
) -> None:
    small.write_text(SMALL.replace('method = "newton"', f'method = "{method}"\nmax_iter = 1'))
    out = tmp_path / "out"
    assert main(["run", str(small), "-o", str(out), "--no-progress"]) == 3
    err = capsys.readouterr().err
    assert err.startswith("vemwear: error: the solver did not converge: ")
    assert err.count("\n") == 1
    assert not out.exists()
    assert leftovers(tmp_path) == []
    empty = tmp_path / "empty"  # an existing empty directory stays, empty
    empty.mkdir()
    assert main(["run", str(small), "-o", str(empty), "--no-progress"]) == 3
    assert list(empty.iterdir()) == []


def test_solver_override(small: Path, tmp_path: Path) -> None:
    small.write_text(
        SMALL.replace('method = "newton"', 'method = "newton-full"\nmax_iter = 1')
        .replace("figures = true", "figures = false")
        .replace("vtk = true", "vtk = false")
    )
    out = tmp_path / "out"  # the configuration's solver would fail; --solver newton does not
    assert main(["run", str(small), "-o", str(out), "--no-progress", "--solver", "newton"]) == 0
    assert json.loads((out / "summary.json").read_text())["solver"]["method"] == "newton"


def test_interrupt_is_130_and_internal_error_is_1(
    small: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    levels = importlib.import_module("vemwear.simulate.levels")

    def interrupted(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt

    def broken(*args: object, **kwargs: object) -> None:
        raise RuntimeError("boom")

    out = tmp_path / "out"
    monkeypatch.setattr(levels, "run_levels", interrupted)
    assert main(["run", str(small), "-o", str(out), "--no-progress"]) == 130
    assert capsys.readouterr().err == "vemwear: interrupted\n"
    assert not out.exists() and leftovers(tmp_path) == []
    monkeypatch.setattr(levels, "run_levels", broken)
    assert main(["run", str(small), "-o", str(out), "--no-progress"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("vemwear: error: internal error: RuntimeError: boom")
    assert "Traceback" not in err
    assert main(["run", str(small), "-o", str(out), "--no-progress", "--debug"]) == 1
    assert "Traceback" in capsys.readouterr().err
    assert not out.exists() and leftovers(tmp_path) == []


def test_outdir_must_not_hold_the_config(
    small: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["run", str(small), "-o", str(tmp_path), "--force", "--no-progress"]) == 2
    assert "contains" in capsys.readouterr().err
    assert small.exists()


def test_missing_config_is_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", str(tmp_path / "nope.toml"), "-o", str(tmp_path / "o")]) == 2
    assert "config file not found" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


# ---------------------------------------------------------------------------- atomic dirs
def test_atomic_output_dir(tmp_path: Path) -> None:
    out = tmp_path / "a" / "b"
    with atomic_output_dir(out) as tmp:
        assert tmp.parent == out.parent and not out.exists()
        (tmp / "x").write_text("1")
    assert (out / "x").read_text() == "1"
    with pytest.raises(OutputDirError, match="use --force"), atomic_output_dir(out):
        pass  # pragma: no cover
    with pytest.raises(ValueError, match="inside"), atomic_output_dir(out, force=True) as tmp:
        (tmp / "y").write_text("2")
        raise ValueError("inside")
    assert sorted(p.name for p in out.iterdir()) == [".vemwear", "x"]
    (out / "mine.txt").write_text("a user's file")
    with atomic_output_dir(out, force=True) as tmp:
        (tmp / "y").write_text("2")
    assert sorted(p.name for p in out.iterdir()) == [".vemwear", "mine.txt", "y"]
    assert leftovers(out.parent) == []
    (tmp_path / "file").write_text("")
    with pytest.raises(OutputDirError, match="not a directory"):
        with atomic_output_dir(tmp_path / "file", force=True):
            pass  # pragma: no cover


# ---------------------------------------------------------------------------- examples
def test_example_registry() -> None:
    assert "5.2" in EXAMPLES and "5.2" in available_examples()
    assert load_example("5.2") is ex52
    with pytest.raises(KeyError, match=r"available: 5\.2"):
        load_example("5.9")


def test_example_52_small(tmp_path: Path) -> None:
    run = ex52.run(
        tmp_path, divisions=(8, 4), steps=8, vtk=False, solver=SolverOptions(backend="scipy")
    )
    names = {p.name for p in tmp_path.iterdir()}
    assert {
        "set1",
        "set2",
        "set3",
        "fig3.png",
        "fig4.png",
        "fig5.png",
        "wear_T_comparison.png",
        "example_5_2.md",
    } <= names
    for s in ("set1", "set2", "set3"):
        assert (tmp_path / s / "result.npz").exists()
        assert (tmp_path / s / "contact_profiles.png").exists()
    f = run.details
    assert set(f["max_wear"]) == {"set1", "set2", "set3"}
    assert f["kappa_increases_wear"]["max"]  # more wear with larger kappa
    report = (tmp_path / "example_5_2.md").read_text()
    assert "| set1 | 0.2 | 2 |" in report and "Larger mu, less wear" in report
    with pytest.raises(ValueError, match="multiple of 4"):
        ex52.run(tmp_path / "x", steps=6)


def test_example_cli(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    original = ex52.run

    def small_run(outdir: Path, *, solver: SolverOptions, **kw: object) -> object:
        assert solver.method == "uzawa"
        return original(
            outdir,
            solver=SolverOptions(method="uzawa", backend="scipy"),
            divisions=(4, 2),
            steps=4,
            figures=False,
            vtk=False,
            **kw,
        )

    monkeypatch.setattr(ex52, "run", small_run)
    out = tmp_path / "ex"
    assert main(["example", "5.2", "-o", str(out), "--no-progress", "--solver", "uzawa"]) == 0
    assert (out / "example_5_2.md").exists() and (out / "set3" / "result.npz").exists()
    text = capsys.readouterr().out
    assert "set1" in text and "max wear at T" in text and str(out) in text
    assert main(["example", "5.2", "-o", str(out), "--no-progress"]) == 2
    assert leftovers(tmp_path) == []


# ---------------------------------------------------------------------------- start-up
def test_help_and_version_import_no_heavy_module() -> None:
    """``vemwear --help`` and ``--version`` import neither NumPy nor the library's numerics
    (start-up well under 0.3 s)."""
    code = (
        "import sys\n"
        "from vemwear.cli.main import main\n"
        "for argv in (['--version'], ['--help']):\n"
        "    try:\n"
        "        main(argv)\n"
        "    except SystemExit:\n"
        "        pass\n"
        "heavy = {'numpy', 'scipy', 'matplotlib', 'pydantic', 'meshio', 'h5py'}\n"
        "print(sorted(heavy & set(sys.modules)))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True
    )
    assert out.stdout.strip().splitlines()[-1] == "[]"


def test_run_without_figures_imports_no_matplotlib(small: Path, tmp_path: Path) -> None:
    """A run with ``figures = false`` never imports matplotlib (0.3-0.5 s of start-up):
    its summary's table of forces included."""
    small.write_text(
        SMALL.replace("figures = true", "figures = false").replace("vtk = true", "vtk = false")
    )
    code = (
        "import sys\n"
        "from vemwear.cli.main import main\n"
        f"code = main(['run', {str(small)!r}, '-o', {str(tmp_path / 'out')!r}, '--no-progress'])\n"
        "print(code, 'matplotlib' in sys.modules)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True
    )
    assert out.stdout.strip().splitlines()[-1] == "0 False"
    assert (tmp_path / "out" / "summary.json").exists()


def test_example_list(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["example", "--list"]) == 0
    out = capsys.readouterr().out
    for name, text in available_examples().items():
        assert f"{name}" in out and text in out
    assert main(["example", "5.2"]) == 2  # no -o OUTDIR
    assert "give NAME and -o OUTDIR" in capsys.readouterr().err
