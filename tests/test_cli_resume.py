"""``vemwear run`` keeps the finished levels of a stopped run in OUTDIR.partial; --resume.

A run is stopped at a chosen level by wrapping :func:`vemwear.simulate.simulate` (looked
up by ``vemwear run`` at call time) so that its ``callback`` raises there: a
:class:`ConvergenceError`, a ``KeyboardInterrupt`` or a real SIGTERM sent to this process.
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
from vemwear.runner.run import CONFIG_COPY, README_NAME, partial_path
from vemwear.solvers import ConvergenceError

sim = importlib.import_module("vemwear.simulate")  # the subpackage, not the function

STEPS = 40  # > 32: the condensed Newton solver finishes levels in blocks of 32

CONFIG = small_config("resume test", steps=STEPS, contact={"v_star": ["1 + 0.5*sin(2*pi*t)", "0"]})

REAL_SIMULATE = sim.simulate
ARRAYS = (
    "t",
    "u",
    "u_levels",
    "wear",
    "u_nu",
    "penetration",
    "lam",
    "p",
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
    ``stop_at(None)`` restores the plain :func:`simulate`."""

    def install(level: int | None, action: Callable[[], None] | None = None) -> None:
        if level is None:
            monkeypatch.setattr(sim, "simulate", REAL_SIMULATE)
            return

        def patched(*args: object, **kwargs: object) -> object:
            def cb(n: int, _sol: object) -> None:
                if n == level and action is not None:
                    action()

            kwargs["callback"] = cb
            return REAL_SIMULATE(*args, **kwargs)  # type: ignore[arg-type]

        monkeypatch.setattr(sim, "simulate", patched)

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
    :func:`simulate`; return the partial directory (32 finished levels)."""
    stop_at(36, no_convergence)
    assert run(config, out) == 3
    stop_at(None)
    return partial_path(out)


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
    part = stopped_run(config, out, stop_at)
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err  # one line
    assert err.startswith(
        "vemwear: error: the solver did not converge: newton did not "
        "converge at time level 36 (test); the 32 finished time levels "
        f"(of {STEPS + 1}) are saved in {part}; continue with: vemwear run "
    )
    assert err.rstrip().endswith(f"-o {out} --resume")
    assert not out.exists() and part.is_dir()
    assert sorted(p.name for p in part.iterdir()) == sorted(
        [CONFIG_COPY, README_NAME, "result.npz", "summary.json"]
    )
    summary = json.loads((part / "summary.json").read_text())
    assert summary["partial"] is True and summary["completed"] == 32
    assert summary["levels"] == STEPS + 1
    assert summary["reason"].startswith("the solver did not converge: newton did not converge")
    assert summary["statistics"]["iterations_total"] > 0
    resume = summary["inputs"]["extra"]["resume"]
    assert len(resume["inputs_sha256"]) == len(resume["config_sha256"]) == 64
    assert (part / CONFIG_COPY).read_bytes() == config.read_bytes()
    readme = (part / README_NAME).read_text()
    assert "PARTIAL" in readme and "--resume" in readme and "32 of 41" in readme
    a = arrays(part)
    assert int(a["completed"]) == 32 and np.all(a["u_levels"] < 32)
    assert np.all(a["wear"][32:] == 0) and np.all(a["iterations"][32:] == 0)
    assert leftovers(tmp_path) == []

    # without --resume the partial result is protected
    assert run(config, out) == 2
    assert (
        "holds the finished levels of a stopped run; continue it with --resume"
        in capsys.readouterr().err
    )


def test_resume_completes_bitwise_and_removes_partial(
    config: Path,
    tmp_path: Path,
    stop_at: Callable[..., None],
    capsys: pytest.CaptureFixture[str],
) -> None:
    out = tmp_path / "out"
    part = stopped_run(config, out, stop_at)
    assert part.is_dir()
    assert run(config, out, "--resume") == 0
    text = capsys.readouterr().out
    assert f"resumed from level 32 ({part} removed)" in text
    assert not part.exists() and (out / "result.npz").is_file()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["partial"] is False
    assert summary["inputs"]["extra"]["resumed_from_level"] == 32

    ref = tmp_path / "ref"
    assert run(config, ref) == 0
    got, want = arrays(out), arrays(ref)
    assert set(got) == set(want)
    for k in ARRAYS:
        assert np.array_equal(got[k], want[k]), k  # bitwise
    assert int(got["completed"]) == STEPS + 1
    assert (out / "result.npz").read_bytes() == (ref / "result.npz").read_bytes()
    assert leftovers(tmp_path) == []


def test_sigterm_partial_and_resume_newton_full(
    config: Path,
    tmp_path: Path,
    stop_at: Callable[..., None],
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A real SIGTERM in the middle of the time loop; newton-full finishes every level."""
    config.write_text(CONFIG.replace('method = "newton"', 'method = "newton-full"'))
    out = tmp_path / "out"
    part = partial_path(out)
    stop_at(7, lambda: os.kill(os.getpid(), signal.SIGTERM))
    assert run(config, out) == 130
    err = capsys.readouterr().err
    assert err.startswith(
        f"vemwear: interrupted; the 7 finished time levels (of {STEPS + 1}) are saved in {part}"
    )
    summary = json.loads((part / "summary.json").read_text())
    assert summary["reason"] == "terminated (SIGTERM)" and summary["completed"] == 7
    assert signal.getsignal(signal.SIGTERM) is not None  # the handler was restored
    # Ctrl-C during the resumed run: the partial result grows
    stop_at(20, lambda: (_ for _ in ()).throw(KeyboardInterrupt()))
    assert run(config, out, "--resume") == 130
    err = capsys.readouterr().err
    assert err.startswith("vemwear: interrupted; the 20 finished time levels")
    assert json.loads((part / "summary.json").read_text())["reason"] == "interrupted (Ctrl-C)"
    stop_at(None)
    assert run(config, out, "--resume") == 0
    ref = tmp_path / "ref"
    assert run(config, ref) == 0
    got, want = arrays(out), arrays(ref)
    for k in ARRAYS:
        assert np.array_equal(got[k], want[k]), k
    assert not part.exists() and leftovers(tmp_path) == []


def test_resume_refused_for_changed_inputs(
    config: Path,
    tmp_path: Path,
    stop_at: Callable[..., None],
    capsys: pytest.CaptureFixture[str],
) -> None:
    out = tmp_path / "out"
    part = stopped_run(config, out, stop_at)
    before = {p.name: p.read_bytes() for p in part.iterdir()}
    capsys.readouterr()

    config.write_text(CONFIG.replace("mu = 0.2", "mu = 0.3"))
    assert run(config, out, "--resume") == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert (
        f"vemwear: error: --resume refused: {part} was computed from another problem "
        "([contact] mu: 0.2 -> 0.3); restore the inputs"
    ) in err
    # [output] and title do not change the numbers, nor do the solver options: a run
    # stopped by a convergence failure continues with another method and tolerance
    assert {p.name: p.read_bytes() for p in part.iterdir()} == before
    assert not out.exists()
    config.write_text(
        CONFIG.replace('title = "resume test"', 'title = "renamed"')
        .replace("figures = false", "figures = false\ntimes = [0.5, 1.0]")
        .replace('method = "newton"', 'method = "newton"\ntol = 1e-11\nmax_iter = 50')
    )
    assert run(config, out, "--resume", "--solver", "newton-full") == 0
    assert not part.exists()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["solver"]["method"] == "newton-full"
    assert summary["inputs"]["extra"]["previous_solver"]["method"] == "newton"


def test_resume_without_partial_and_damaged_partial(
    config: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    out = tmp_path / "out"
    assert run(config, out, "--resume") == 2
    assert "there is no partial result to resume" in capsys.readouterr().err
    part = partial_path(out)
    part.mkdir()
    (part / "summary.json").write_text("{not json")
    assert run(config, out, "--resume") == 2
    assert "is not a readable partial result" in capsys.readouterr().err
    (part / "summary.json").write_text(json.dumps({"format": "vemwear-result/1", "partial": False}))
    assert run(config, out, "--resume") == 2
    assert "is not marked as a partial result" in capsys.readouterr().err
    # --force starts over and removes the stale partial directory on success
    assert run(config, out, "--force") == 0
    assert not part.exists() and (out / "result.npz").is_file()
    assert not out.with_name("out.partial").exists()


def test_stop_before_any_finished_level_leaves_nothing(
    config: Path,
    tmp_path: Path,
    stop_at: Callable[..., None],
    capsys: pytest.CaptureFixture[str],
) -> None:
    out = tmp_path / "out"
    stop_at(3, no_convergence)  # inside the first block of 32 levels
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
