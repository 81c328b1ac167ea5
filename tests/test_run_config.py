"""vemwear.run_config: the library's entry point of a run, which vemwear run and the
workers of a study call."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import vemwear
from conftest import small_config
from vemwear.cli.main import main
from vemwear.runner.plan import PlanError

OFF = {"figures": False, "vtk": False}


def test_run_config_owns_the_checks_the_warnings_and_the_outcome(tmp_path: Path) -> None:
    cfg = tmp_path / "case.toml"
    cfg.write_text(small_config("case", contact={"kappa": 20.0, "g": 1.0}, output=OFF))
    said: list[str] = []
    warned: list[str] = []
    out = vemwear.run_config(
        cfg, tmp_path / "out", progress=False, say=said.append, warn=warned.append
    )
    assert out.result is not None and out.out == (tmp_path / "out").absolute()
    assert said[0].startswith("case: memory (estimate) ")
    assert len(warned) == 1 and warned[0].startswith(
        "warning: the explicit wear update can overshoot"
    )
    assert out.warnings == [warned[0].removeprefix("warning: ")]
    # the same arrays as the command line
    assert main(["run", str(cfg), "-o", str(tmp_path / "cli"), "--no-progress"]) == 0
    with np.load(tmp_path / "out/result.npz") as a, np.load(tmp_path / "cli/result.npz") as b:
        assert all(np.array_equal(a[k], b[k]) for k in ("u", "wear", "p_soft", "p_rigid"))
    again = vemwear.run_config(cfg, tmp_path / "out", resume=True, progress=False)
    assert again.result is None and "holds a complete run" in again.note


def test_run_config_refuses_before_any_work(tmp_path: Path) -> None:
    """The rough plan refuses a run of 1e9 levels before its configuration is built."""
    cfg = tmp_path / "case.toml"
    cfg.write_text(small_config("case", steps=1_000_000_000, output=OFF))
    with pytest.raises(PlanError, match="of memory"):
        vemwear.run_config(cfg, tmp_path / "out", progress=False)
    assert not (tmp_path / "out").exists()


def test_every_step_solver_offers_the_protocol_of_the_time_loop() -> None:
    """run_levels asks batch, predicts and setup_timings instead of probing attributes."""
    import tomllib

    from conftest import levels_mod  # noqa: F401 - the loop's module is importable
    from vemwear.config import parse_config
    from vemwear.simulate import SolverOptions
    from vemwear.solvers import SOLVERS
    from vemwear.solvers.protocol import StepSolver

    cfg = parse_config(tomllib.loads(small_config("p", output=OFF)))
    d = cfg.problem.discrete
    for method in SOLVERS:
        s = d.step_solver(SolverOptions(method=method))
        assert isinstance(s, StepSolver), method
        assert s.batch == (method == "newton") and isinstance(s.setup_timings, dict)
