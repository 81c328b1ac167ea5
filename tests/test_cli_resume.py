"""``vemwear run`` keeps the finished levels of a stopped run in OUTDIR; --resume.

A run is stopped at a chosen level by wrapping :func:`vemwear.simulate.levels.run_levels`
(looked up by ``vemwear run`` at call time) so that its ``callback`` raises there: a
:class:`ConvergenceError`, a ``KeyboardInterrupt`` or a real SIGTERM sent to this process.
Runs killed by real signals in separate processes are in ``test_long_runs.py``.
"""

from __future__ import annotations

import importlib
import json
import os
import signal
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest

from conftest import small_config
from vemwear.cli.main import main
from vemwear.runner.checkpoint import CHECKPOINT_NAME
from vemwear.runner.run import PARTIAL_NAME
from vemwear.solvers import ConvergenceError

levels_mod = importlib.import_module("vemwear.simulate.levels")

STEPS = 40  # > 32: the condensed Newton solver finishes levels in blocks of 32

CONFIG = small_config("resume test", steps=STEPS, contact={"v_star": ["1 + 0.5*sin(2*pi*t)", "0"]})

REAL_RUN = levels_mod.run_levels
ARRAYS = (
    "t",
    "u",
    "u_levels",
    "wear",
    "u_nu",
    "penetration",
    "p_rigid",
    "p_soft",
    "iterations",
    "residuals",
    "contact_nodes",
    "completed",
)


@pytest.fixture
def config(tmp_path: Path) -> Path:
    p = tmp_path / "case.toml"
    p.write_text(CONFIG)
    return p


@pytest.fixture
def stop_at(monkeypatch: pytest.MonkeyPatch) -> Iterator[Callable[..., None]]:
    """``stop_at(level, action)``: the next runs call ``action()`` when reaching ``level``;
    ``stop_at(None)`` restores the plain :func:`run_levels`."""

    def install(level: int | None, action: Callable[[], None] | None = None) -> None:
        if level is None:
            monkeypatch.setattr(levels_mod, "run_levels", REAL_RUN)
            return

        def patched(*args: object, **kwargs: object) -> object:
            def cb(n: int, _sol: object) -> None:
                if n == level and action is not None:
                    action()

            kwargs["callback"] = cb
            return REAL_RUN(*args, **kwargs)  # type: ignore[arg-type]

        monkeypatch.setattr(levels_mod, "run_levels", patched)

    yield install


def run(config: Path, out: Path, *extra: str) -> int:
    return main(["run", str(config), "-o", str(out), "--no-progress", *extra])


def arrays(d: Path) -> dict[str, np.ndarray]:
    with np.load(d / "result.npz", allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def leftovers(parent: Path) -> list[str]:
    return sorted(p.name for p in parent.iterdir() if p.name.startswith("."))


def no_convergence() -> None:
    raise ConvergenceError("newton did not converge at time level 36 (test)")


def stopped_run(config: Path, out: Path, stop_at: Callable[..., None]) -> Path:
    """Run ``config`` into a ConvergenceError at level 36 (exit code 3), restore the plain
    :func:`run_levels`; return the output directory (36 finished levels)."""
    stop_at(36, no_convergence)
    assert run(config, out) == 3
    stop_at(None)
    return out


def test_convergence_error_keeps_partial_and_resume_is_bitwise(
    config: Path,
    tmp_path: Path,
    stop_at: Callable[..., None],
    capsys: pytest.CaptureFixture[str],
) -> None:
    ref = tmp_path / "ref"
    assert run(config, ref) == 0
    capsys.readouterr()

    out = tmp_path / "out"
    stopped_run(config, out, stop_at)
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err  # one line
    assert err.startswith(
        "vemwear: error: the solver did not converge: newton did not "
        "converge at time level 36 (test); the 36 finished time levels "
        f"(of {STEPS + 1}) are saved in {out}; continue with: vemwear run "
    )
    assert err.rstrip().endswith(f"-o {out} --resume")
    names = {p.name for p in out.iterdir()}
    assert {CHECKPOINT_NAME, PARTIAL_NAME, "result.h5", "summary.json"} <= names
    assert "result.npz" not in names
    summary = json.loads((out / "summary.json").read_text())
    assert summary["partial"] is True and summary["completed"] == 36
    assert summary["levels"] == STEPS + 1
    assert summary["reason"].startswith("the solver did not converge: newton did not converge")
    readme = (out / PARTIAL_NAME).read_text()
    assert "UNFINISHED" in readme and "--resume" in readme and "36 of 41" in readme
    assert [p for p in tmp_path.iterdir() if p.name.startswith(".")] == []

    # without --resume the stopped run is protected
    assert run(config, out) == 2
    assert "holds a stopped run (partial); continue it with --resume" in capsys.readouterr().err

    assert run(config, out, "--resume") == 0
    text = capsys.readouterr().out
    assert "resumed from level 36" in text
    assert not (out / CHECKPOINT_NAME).exists() and not (out / PARTIAL_NAME).exists()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["partial"] is False
    assert summary["inputs"]["extra"]["resumed_from_level"] == 36
    got, want = arrays(out), arrays(ref)
    assert set(got) == set(want)
    for k in ARRAYS:
        assert np.array_equal(got[k], want[k]), k  # bitwise
    assert int(got["completed"]) == STEPS + 1
    assert (out / "result.npz").read_bytes() == (ref / "result.npz").read_bytes()


def test_sigterm_partial_and_resume_newton_full(
    config: Path,
    tmp_path: Path,
    stop_at: Callable[..., None],
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A real SIGTERM in the middle of the time loop; newton-full finishes every level."""
    config.write_text(CONFIG.replace('method = "newton"', 'method = "newton-full"'))
    out = tmp_path / "out"
    stop_at(7, lambda: os.kill(os.getpid(), signal.SIGTERM))
    assert run(config, out) == 130
    first, last = capsys.readouterr().err.splitlines()
    assert first == "vemwear: terminated (SIGTERM); stopping"  # said when the signal comes
    assert last.startswith(
        f"vemwear: interrupted; the 7 finished time levels (of {STEPS + 1}) are saved in {out}"
    )
    summary = json.loads((out / "summary.json").read_text())
    assert summary["reason"] == "terminated (SIGTERM)" and summary["completed"] == 7
    assert signal.getsignal(signal.SIGTERM) is not None  # the handler was restored
    # Ctrl-C during the resumed run: the checkpoint moves on
    stop_at(20, lambda: (_ for _ in ()).throw(KeyboardInterrupt()))
    assert run(config, out, "--resume") == 130
    err = capsys.readouterr().err
    assert err.startswith("vemwear: interrupted; the 20 finished time levels")
    assert json.loads((out / "summary.json").read_text())["reason"] == "interrupted (Ctrl-C)"
    stop_at(None)
    assert run(config, out, "--resume") == 0
    ref = tmp_path / "ref"
    assert run(config, ref) == 0
    got, want = arrays(out), arrays(ref)
    for k in ARRAYS:
        assert np.array_equal(got[k], want[k]), k


def test_resume_refused_for_changed_inputs(
    config: Path,
    tmp_path: Path,
    stop_at: Callable[..., None],
    capsys: pytest.CaptureFixture[str],
) -> None:
    out = tmp_path / "out"
    stopped_run(config, out, stop_at)
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    capsys.readouterr()

    config.write_text(CONFIG.replace("mu = 0.2", "mu = 0.3"))
    assert run(config, out, "--resume") == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert (
        f"vemwear: error: --resume refused: {out} was computed from another problem "
        "([contact] mu: 0.2 -> 0.3); restore the inputs"
    ) in err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    # the title and the figures do not change the numbers, nor do the solver options: a
    # run stopped by a convergence failure continues with another method and tolerance
    config.write_text(
        CONFIG.replace('title = "resume test"', 'title = "renamed"').replace(
            'method = "newton"', 'method = "newton"\ntol = 1e-11\nmax_iter = 50'
        )
    )
    assert run(config, out, "--resume", "--solver", "newton-full") == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["solver"]["method"] == "newton-full"
    assert summary["inputs"]["extra"]["previous_solver"]["method"] == "newton"


def test_resume_without_checkpoint_and_damaged_checkpoint(
    config: Path,
    tmp_path: Path,
    stop_at: Callable[..., None],
    capsys: pytest.CaptureFixture[str],
) -> None:
    out = tmp_path / "out"
    assert run(config, out, "--resume") == 2
    assert "holds no checkpoint to resume from" in capsys.readouterr().err
    stopped_run(config, out, stop_at)
    (out / CHECKPOINT_NAME).write_bytes(b"not a checkpoint")
    capsys.readouterr()
    assert run(config, out, "--resume") == 2
    assert "is not a readable checkpoint" in capsys.readouterr().err
    # --force starts over in the directory vemwear wrote
    assert run(config, out, "--force") == 0
    assert (out / "result.npz").is_file() and not (out / CHECKPOINT_NAME).exists()


def test_stop_before_any_finished_level_leaves_nothing(
    config: Path,
    tmp_path: Path,
    stop_at: Callable[..., None],
    capsys: pytest.CaptureFixture[str],
) -> None:
    out = tmp_path / "out"
    stop_at(0, no_convergence)
    assert run(config, out) == 3
    assert capsys.readouterr().err.count("saved") == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["case.toml"]


def test_same_input_twice_gives_identical_arrays(config: Path, tmp_path: Path) -> None:
    a, b = tmp_path / "a", tmp_path / "b"
    assert run(config, a) == 0 and run(config, b) == 0
    x, y = arrays(a), arrays(b)
    assert set(x) == set(y)
    for k in x:
        assert x[k].dtype == y[k].dtype and np.array_equal(x[k], y[k]), k
    # NumPy writes the archive deterministically: the files are byte-identical too
    assert (a / "result.npz").read_bytes() == (b / "result.npz").read_bytes()
