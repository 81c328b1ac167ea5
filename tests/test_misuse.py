"""A new user's misuse: each ends in one line naming the real cause, before any work.

Run in-process through :func:`vemwear.cli.main.main`, as ``vemwear ...`` would.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from conftest import small_config
from vemwear.cli.main import main

OFF = {"figures": False, "vtk": False}


def _err(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    return err


# ---------------------------------------------------------------------------- encodings
@pytest.mark.parametrize(
    ("data", "where"),
    [
        (
            'title = "x"\n'.encode("utf-16"),
            "a UTF-16 (little-endian) byte-order mark at byte offset 0",
        ),
        (b'title = "caf\xe9"\n[mesh]\n', "byte 0xe9 at byte offset 12 (line 1)"),
        (b'title = "x"\n\n\x80\x81\x82', "byte 0x80 at byte offset 13 (line 3)"),
    ],
    ids=["utf-16", "latin-1", "binary"],
)
def test_a_config_that_is_not_utf8_is_exit_2_with_the_byte_offset(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], data: bytes, where: str
) -> None:
    cfg = tmp_path / "case.toml"
    cfg.write_bytes(data)
    for cmd in (["run", str(cfg), "-o", str(tmp_path / "out")], ["check", str(cfg)]):
        assert main(cmd) == 2
        assert (
            _err(capsys)
            == f"vemwear: error: {cfg}: not UTF-8 text: {where}; save the file as UTF-8\n"
        )
    assert not (tmp_path / "out").exists()
    study = tmp_path / "study.toml"
    study.write_bytes(data)
    assert main(["sweep", str(study), "-o", str(tmp_path / "sw")]) == 2
    assert f"{study}: not UTF-8 text: {where}" in _err(capsys)
    good = tmp_path / "good.toml"
    good.write_text(small_config("good", output=OFF))
    csv = tmp_path / "data.csv"
    csv.write_bytes(data)
    assert main(["fit", str(good), "--data", str(csv)]) == 2
    assert f"{csv}: not UTF-8 text: {where}" in _err(capsys)
    # a UTF-8 byte-order mark is fine
    good.write_bytes(b"\xef\xbb\xbf" + good.read_bytes())
    assert main(["check", str(good)]) == 0


# ---------------------------------------------------------------------------- scales
@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        (
            "size = [2.0, 1.0]",
            "size = [2e-300, 1e-300]",
            "[mesh] the body measures 2e-300 across: too small or too large to compute with",
        ),
        (
            "size = [2.0, 1.0]",
            "size = [2e300, 1e300]",
            "[mesh] the body measures 2e+300 across: too small or too large to compute with",
        ),
        ("g = 0.1", "g = 1e308", "[contact] g = 1e+308 is too large to compute with"),
    ],
    ids=["tiny body", "huge body", "huge g"],
)
def test_a_scale_out_of_floating_point_range_is_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], old: str, new: str, message: str
) -> None:
    """Before: the tiny body blamed ``[material] lam = 4, eta = 4`` and the huge g the
    compliance law ``p(r)``."""
    cfg = tmp_path / "case.toml"
    cfg.write_text(small_config("scale", output=OFF).replace(old, new))
    assert main(["check", str(cfg)]) == 2
    err = _err(capsys)
    assert err.startswith(f"vemwear: error: {cfg}: {message}"), err
    assert "[material]" not in err and "must return finite values" not in err


# ---------------------------------------------------------------------------- worn through
@pytest.mark.parametrize("key", ["kappa", "T"])
def test_wear_beyond_the_layer_thickness_stops_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], key: str
) -> None:
    """kappa = 1e308 (or T = 1e308) exited 0 with a wear of 5.5e304 on a layer 0.1 thick."""
    text = small_config("worn", output=OFF)
    text = (
        text.replace("kappa = 2.0", "kappa = 1e308")
        if key == "kappa"
        else (text.replace("T = 1.0", "T = 1e308"))
    )
    cfg = tmp_path / "case.toml"
    cfg.write_text(text)
    out = tmp_path / "out"
    assert main(["run", str(cfg), "-o", str(out), "--no-progress"]) == 3
    err = capsys.readouterr().err.splitlines()
    assert err[0].startswith("vemwear: warning: the explicit wear update can overshoot")
    assert err[1].startswith(
        "vemwear: error: the wear exceeds the layer thickness at time level 1 (t = "
    ), err
    assert "> g = 0.1 at contact node" in err[1] and "worn through" in err[1]
    assert "--resume" not in err[1] and len(err) == 2
    import json

    summary = json.loads((out / "summary.json").read_text())
    assert summary["partial"] is True and summary["completed"] == 1
    assert "exceeds the layer thickness" in summary["reason"]
    assert not (out / "result.npz").exists()  # no final output of a meaningless run


# ---------------------------------------------------------------------------- studies
EXAMPLE_BASE = Path(__file__).resolve().parents[1] / "src/vemwear/examples/example_5_2_set1.toml"


def test_a_study_of_too_many_runs_is_refused_before_any_is_built(tmp_path: Path) -> None:
    """A 100 x 100 x 100 grid printed nothing for 11 minutes while every run's
    configuration was built (2.5 ms a run); the runs are counted first."""
    import subprocess
    import sys
    import time

    study = tmp_path / "big.toml"
    study.write_text(
        f'title = "big"\nbase = "{EXAMPLE_BASE}"\n[axes]\n'
        '"contact.kappa" = { start = 1.0, stop = 100.0, num = 100 }\n'
        '"contact.mu" = { start = 0.0, stop = 1.0, num = 100 }\n'
        '"contact.g" = { start = 0.05, stop = 0.15, num = 100 }\n'
    )
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "vemwear", "sweep", str(study), "-o", str(out)]
    t0 = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    took = time.perf_counter() - t0
    assert done.returncode == 2, done.stderr
    assert done.stderr == (
        f"vemwear: error: {study}: the design has 1000000 runs (100 x 100 x 100), more than "
        "--max-runs = 100000; use fewer values per axis, or raise --max-runs\n"
    )
    assert took < 2.0, took
    assert not out.exists()
    done = subprocess.run([*cmd, "--max-runs", "9999"], capture_output=True, text=True)
    assert done.returncode == 2 and "more than --max-runs = 9999" in done.stderr


# ---------------------------------------------------------------------------- fit
@pytest.mark.parametrize(
    ("rows", "message"),
    [
        (
            ["5.5,1.0,0.01", "1.0,1.0,0.02"],
            "data point 1 at x = 5.5 is off the contact part: its contact nodes, where the "
            "model's wear is known, span x = 0.25 .. 2",
        ),
        (["1.0,1.0,0.01", "-0.5,1.0,0.02"], "data point 2 at x = -0.5 is off the contact part"),
        (["1.0,3.0,0.01", "1.5,1.0,0.02"], "t = 3 is outside the configuration's time grid [0, 1]"),
        (
            ["1.0,1.0,0.01"],
            "1 data points for 1 parameters; a fit needs more points than parameters",
        ),
    ],
    ids=["right of the part", "left of the part", "after T", "n = p"],
)
def test_fit_refuses_data_it_cannot_fit(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], rows: list[str], message: str
) -> None:
    """np.interp clamped x = 5.5 on a part spanning 0 .. 2 to the end value; n = p gave
    a zero-width interval."""
    cfg = tmp_path / "case.toml"
    cfg.write_text(small_config("fit", output=OFF))
    csv = tmp_path / "data.csv"
    csv.write_text("x,t,w\n" + "\n".join(rows) + "\n")
    out = tmp_path / "out"
    assert main(["fit", str(cfg), "--data", str(csv), "-o", str(out)]) == 2
    err = _err(capsys)
    assert message in err, err
    assert not out.exists()  # refused before any run


def test_fit_intervals_stay_within_the_bounds() -> None:
    """A linear interval mu +- t se reached mu = -0.68 for an estimate of 0.04."""
    from vemwear.studies.fitting import interval95

    lo, hi = interval95(0.04, 0.3, 2.0, 0.0, float("inf"))
    assert 0.0 < lo < 0.04 < hi
    assert lo * hi == pytest.approx(0.04**2)  # symmetric in log mu
    lo, hi = interval95(2.5, 0.01, 2.0, 0.0, float("inf"))  # a small error: about +- t se
    assert lo == pytest.approx(2.48, abs=1e-4) and hi == pytest.approx(2.52, abs=1e-4)
    assert interval95(0.0, 0.1, 2.0, 0.0, 1.0) == (0.0, pytest.approx(0.2))  # at a bound
    assert interval95(0.9, 0.5, 2.0, 0.0, 1.0)[1] == 1.0  # clipped to the upper bound


# ---------------------------------------------------------------------------- many steps
def test_output_times_of_many_levels_take_no_levels_sized_temporaries() -> None:
    """steps = 2e7 took 10 s and 640 MB in the (times, levels) array of the default
    output times before the plan could refuse it; the nearest levels are by bisection,
    with the same indices as the argmin over the levels."""
    import tracemalloc

    import numpy as np

    from vemwear.simulate import TimeGrid

    rng = np.random.default_rng(1)
    for _ in range(100):
        t = np.concatenate([[0.0], np.cumsum(rng.random(rng.integers(1, 40)))])
        grid = TimeGrid(t)
        x = np.concatenate([rng.uniform(-0.1, 1.1, 20) * t[-1], t, (t[:-1] + t[1:]) / 2])
        assert np.array_equal(grid.nearest(x), np.abs(t[None, :] - x[:, None]).argmin(axis=1))
    big = TimeGrid.uniform(1.0, 20_000_000)
    tracemalloc.start()
    try:
        idx = big.index([0.25, 0.5, 0.75, 1.0])
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert idx.tolist() == [5_000_000, 10_000_000, 15_000_000, 20_000_000]
    assert peak < 1e6, peak


def test_many_levels_on_a_fine_contact_are_refused_before_the_time_grid(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """steps = 2e7 on 64 x 32 squares (63 contact nodes) passed the rough check of 2
    contact nodes, then built the 2e7-level time grid and its velocities (1.5 GB, 4 s)
    before the real-mesh estimate refused it. The check with the built mesh refuses it
    before any array of L levels exists: no allocation near the grid's 160 MB."""
    import tracemalloc

    from vemwear.config import load_config
    from vemwear.runner.plan import PlanError, admit_sizes
    from vemwear.util.system import available_memory

    if available_memory() > 140e9:
        pytest.skip("this machine could hold the run")
    cfg = tmp_path / "long.toml"
    cfg.write_text(small_config("long", divisions=(64, 32), steps=20_000_000, output=OFF))
    expected = r"the run needs about 14\d\.\d\d GB of memory, [\d.]+ [GM]B are available"
    for command in ("check", "run"):
        extra = ["-o", str(tmp_path / "out")] if command == "run" else []
        assert main([command, str(cfg), *extra]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and re.match(
            f"vemwear: error: {re.escape(str(cfg))}: {expected}", err
        ), err
        assert "--force-size to run anyway" in err
    assert not (tmp_path / "out").exists()
    seen: list[object] = []
    admit = admit_sizes()
    tracemalloc.start()
    try:
        with pytest.raises(PlanError, match=expected):
            load_config(cfg, admit=lambda s: (seen.append(s), admit(s)))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 20e6, peak
    assert [(s.levels, s.contact, s.points) for s in seen] == [  # type: ignore[attr-defined]
        (20_000_001, 0, 0),
        (20_000_001, 63, 65 * 33),
    ]
