"""Long runs in real processes: killed, hung up, interrupted twice, run twice at once.

Each test starts ``vemwear run`` as a separate process, sends it real signals, and reads
what it left with NumPy and h5py. A run killed with SIGKILL after a checkpoint resumes
with ``--resume`` to arrays that are bitwise those of a run that never stopped.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from conftest import small_config

STEPS = 50000  # about 0.8 s of solving on 16 x 8 squares (2 cores)

LONG = small_config(
    "long run",
    divisions=(16, 8),
    steps=STEPS,
    output={"store_u": 1000, "checkpoint": 0.2, "figures": False, "vtk": False},
)


def start(config: Path, out: Path, *extra: str) -> subprocess.Popen[str]:
    cmd = [sys.executable, "-m", "vemwear", "run", str(config), "-o", str(out), "--no-progress"]
    return subprocess.Popen(
        [*cmd, *extra], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )


def run(config: Path, out: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    cmd = [sys.executable, "-m", "vemwear", "run", str(config), "-o", str(out), "--no-progress"]
    return subprocess.run([*cmd, *extra], capture_output=True, text=True, timeout=300)


def wait_for(path: Path, proc: subprocess.Popen[str], timeout: float = 120.0) -> None:
    t0 = time.monotonic()
    while not path.exists():
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() - t0 < timeout, f"{path} did not appear"
        time.sleep(0.02)


def arrays(out: Path) -> dict[str, np.ndarray]:
    with np.load(out / "result.npz", allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


@pytest.fixture(scope="module")
def config(tmp_path_factory: pytest.TempPathFactory) -> Path:
    p = tmp_path_factory.mktemp("long") / "long.toml"
    p.write_text(LONG)
    return p


@pytest.fixture(scope="module")
def reference(config: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, np.ndarray]:
    out = tmp_path_factory.mktemp("ref") / "out"
    done = run(config, out)
    assert done.returncode == 0, done.stderr
    return arrays(out)


#: Steps of the run killed with SIGKILL: long enough (a time loop of about 5 s here, its
#: first checkpoint after 0.2 s) that the kill lands well inside the time loop on a
#: faster machine too.
KILL_STEPS = 60000


@pytest.fixture(scope="module")
def long_config(tmp_path_factory: pytest.TempPathFactory) -> Path:
    p = tmp_path_factory.mktemp("longer") / "longer.toml"
    p.write_text(LONG.replace(f"steps = {STEPS}", f"steps = {KILL_STEPS}"))
    return p


def assert_same(out: Path, reference: dict[str, np.ndarray]) -> None:
    got = arrays(out)
    assert got.keys() == reference.keys()
    for k, v in reference.items():
        assert got[k].dtype == v.dtype and np.array_equal(got[k], v), k


def test_sigkill_after_a_checkpoint_resumes_bitwise(long_config: Path, tmp_path: Path) -> None:
    config = long_config
    ref_out = tmp_path / "ref"
    assert run(config, ref_out).returncode == 0
    reference = arrays(ref_out)
    out = tmp_path / "out"
    proc = start(config, out)
    wait_for(out / "checkpoint.npz", proc)
    time.sleep(0.3)  # past the first checkpoint, in the middle of writing levels
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    assert proc.returncode == -signal.SIGKILL
    with np.load(out / "checkpoint.npz") as z:
        completed = int(z["completed"])
    assert 0 < completed < KILL_STEPS + 1
    with h5py.File(out / "result.h5", "r") as f:  # readable after the kill
        assert f["wear"].shape[0] == KILL_STEPS + 1
    marker = json.loads((out / ".vemwear").read_text())
    assert marker["state"] == "running"  # nobody told it otherwise: it was killed
    resumed = run(config, out, "--resume")
    assert resumed.returncode == 0, resumed.stderr
    assert f"resumed from level {completed}" in resumed.stdout or "resumed from level" in (
        resumed.stdout
    )
    assert_same(out, reference)
    assert not (out / "checkpoint.npz").exists()
    assert json.loads((out / ".vemwear").read_text())["state"] == "complete"


@pytest.mark.parametrize("sig", [signal.SIGHUP, signal.SIGTERM])
def test_hangup_and_terminate_keep_the_finished_levels(
    config: Path, tmp_path: Path, reference: dict[str, np.ndarray], sig: signal.Signals
) -> None:
    out = tmp_path / "out"
    proc = start(config, out)
    wait_for(out / "checkpoint.npz", proc)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    lines = err.splitlines()
    reason = {"SIGHUP": "hung up (SIGHUP)", "SIGTERM": "terminated (SIGTERM)"}[sig.name]
    assert lines[0] == f"vemwear: {reason}; stopping", err
    assert lines[-1].startswith("vemwear: interrupted; the ") and "--resume" in lines[-1]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["partial"] is True and summary["reason"] == reason
    assert "UNFINISHED" in (out / "PARTIAL.txt").read_text()
    assert run(config, out, "--resume").returncode == 0
    assert_same(out, reference)


def test_second_ctrl_c_does_not_abandon_the_save(
    config: Path, tmp_path: Path, reference: dict[str, np.ndarray]
) -> None:
    """The second Ctrl-C is sent once the child has said that the first one stops it (its
    first line on stderr), so the two are never merged into one and the second arrives
    while the finished levels are being saved."""
    out = tmp_path / "out"
    proc = start(config, out)
    wait_for(out / "checkpoint.npz", proc)
    proc.send_signal(signal.SIGINT)
    assert proc.stderr is not None
    first = proc.stderr.readline()
    assert first == "vemwear: interrupted (Ctrl-C); stopping\n"
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    lines = err.splitlines()
    assert lines[0] == (
        "vemwear: saving the finished levels; please wait (once more to abandon the save)"
    ), err
    assert len(lines) == 2 and "are saved in" in lines[1] and "--resume" in lines[1]
    assert json.loads((out / "summary.json").read_text())["partial"] is True
    assert run(config, out, "--resume").returncode == 0
    assert_same(out, reference)


def test_a_second_run_into_the_same_directory_is_refused(tmp_path: Path) -> None:
    config = tmp_path / "longer.toml"  # long enough to outlive three refused runs
    config.write_text(LONG.replace(f"steps = {STEPS}", "steps = 400000"))
    out = tmp_path / "out"
    first = start(config, out)
    try:
        wait_for(out / "checkpoint.npz", first)
        before = sorted(p.name for p in out.iterdir())
        for extra in ([], ["--force"], ["--resume"]):
            second = run(config, out, *extra)
            assert second.returncode == 2
            assert f"another vemwear run (pid {first.pid}) is writing into {out}" in second.stderr
        after = sorted(p.name for p in out.iterdir())
        assert set(after) <= set(before) | {"result.npz"}  # the second one added nothing
        other = tmp_path / "other"
        assert run(config, other, "--resume").returncode == 2
        assert not other.exists()  # a refused run leaves nothing behind
        # refused before its configuration is even read: no work at all
        bad = tmp_path / "bad.toml"
        bad.write_text("this is [not TOML")
        second = run(bad, out)
        assert second.returncode == 2 and "another vemwear run (pid" in second.stderr
    finally:
        first.send_signal(signal.SIGINT)
        first.communicate(timeout=60)


def test_stale_temporaries_are_reported_and_cleaned(tmp_path: Path) -> None:
    cfg = tmp_path / "case.toml"
    cfg.write_text(small_config("stale", output={"figures": False, "vtk": False}))
    out = tmp_path / "out"
    first = run(cfg, out)
    assert first.returncode == 0
    # the plan, always printed (one line), before the summary
    assert re.search(
        r"^vemwear: stale: memory \(estimate\) .+, disk \(estimate\) .+$",
        (first.stdout.splitlines()[0]),
    ), first.stdout
    stale_in = out / ".result.tmp-abcd1234.npz"  # what a killed atomic write leaves
    stale_in.write_bytes(b"x")
    stale_next = tmp_path / ".out.tmp-abcd1234"
    stale_next.mkdir()
    (out / "notes.txt").write_text("mine")
    again = run(cfg, out, "--force")
    assert again.returncode == 0
    assert not stale_in.exists() and not stale_next.exists()  # --force removes them
    stale_in.write_bytes(b"x")
    other = tmp_path / "other"
    warn = run(cfg, other)
    assert warn.returncode == 0 and "temporary" not in warn.stderr
    third = tmp_path / "third"
    (tmp_path / ".third.tmp-abcd1234").mkdir()  # a killed atomic write of a third output
    warn = run(cfg, third)
    assert warn.returncode == 0
    assert warn.stderr == (
        f"vemwear: warning: 1 temporary file(s) of killed runs in or next to {third} (e.g. "
        f".third.tmp-abcd1234); remove them with: vemwear clean {third}\n"
    )
    clean = subprocess.run(
        [sys.executable, "-m", "vemwear", "clean", str(out)], capture_output=True, text=True
    )
    assert clean.returncode == 0 and str(stale_in) in clean.stdout
    assert not stale_in.exists() and (out / "notes.txt").read_text() == "mine"
    assert (out / "result.npz").exists()  # vemwear's output stays without --all
    gone = subprocess.run(
        [sys.executable, "-m", "vemwear", "clean", str(out), "--all"],
        capture_output=True,
        text=True,
    )
    assert gone.returncode == 0
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt"]


def test_overshoot_warning(tmp_path: Path) -> None:
    cfg = tmp_path / "case.toml"
    cfg.write_text(small_config("overshoot", contact={"kappa": 500.0}))
    check = subprocess.run(
        [sys.executable, "-m", "vemwear", "check", str(cfg)], capture_output=True, text=True
    )
    assert check.returncode == 0
    assert "vemwear: warning: the explicit wear update can overshoot: k kappa |v*| L_p = 25 " in (
        check.stderr
    )
    assert "Use time steps below 0.005" in check.stderr
    cfg.write_text(small_config("fine", contact={"kappa": 2.0}))
    check = subprocess.run(
        [sys.executable, "-m", "vemwear", "check", str(cfg)], capture_output=True, text=True
    )
    assert check.returncode == 0 and "overshoot" not in check.stderr
    assert "memory (estimate)" in check.stdout and "disk (estimate)" in check.stdout


def test_wear_overflow_is_named_with_its_level(tmp_path: Path) -> None:
    """kappa |v*| overflows: the warning says that no time step is safe, and the run stops
    with exit code 3 at the first level whose wear is not finite, naming the wear."""
    cfg = tmp_path / "case.toml"
    cfg.write_text(small_config("overflow", contact={"kappa": 1e308, "v_star": [1e10, 0.0]}))
    out = tmp_path / "out"
    done = run(cfg, out)
    assert done.returncode == 3, done.stderr
    warning, error = done.stderr.splitlines()
    assert warning.startswith("vemwear: warning: the explicit wear update can overshoot: ")
    assert warning.endswith(
        "No time step is safe: kappa |v*| L_p overflows; use data of a sensible scale"
    )
    assert error.startswith(
        "vemwear: error: the wear is not finite at time level 1 (t = 0.125): inf at contact node 0"
    ), error
    assert "internal error" not in done.stderr and "Warning" not in done.stderr


def test_resume_after_a_real_solver_failure(tmp_path: Path) -> None:
    """Uzawa with 3 iterations fails at level 1 (exit 3, the level kept); the run goes on
    with another max_iter and tol (recorded with the previous ones in summary.json), not
    with another mu (refused with the list of changes)."""
    text = small_config(
        "uzawa",
        steps=40,
        solver={"method": "uzawa", "max_iter": 3},
        loads={"f1": [0.0, "-0.06*t*t*t"]},
    )
    cfg = tmp_path / "case.toml"
    cfg.write_text(text)
    out = tmp_path / "out"
    failed = run(cfg, out)
    assert failed.returncode == 3, failed.stderr
    assert failed.stderr.startswith(
        "vemwear: error: the solver did not converge: Uzawa did not converge at time level 1 "
    ), failed.stderr
    assert f"the 1 finished time levels (of 41) are saved in {out}" in failed.stderr
    assert json.loads((out / "summary.json").read_text())["completed"] == 1
    better = text.replace("max_iter = 3", "tol = 1e-08\nmax_iter = 5000")
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    cfg.write_text(better.replace("mu = 0.2", "mu = 0.3"))
    refused = run(cfg, out, "--resume")
    assert refused.returncode == 2
    assert "--resume refused" in refused.stderr and "[contact] mu: 0.2 -> 0.3" in refused.stderr
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before  # untouched
    cfg.write_text(better)
    done = run(cfg, out, "--resume")
    assert done.returncode == 0, done.stderr
    assert "resumed from level 1" in done.stdout
    summary = json.loads((out / "summary.json").read_text())
    assert summary["partial"] is False
    assert summary["solver"] == {"method": "uzawa", "tol": 1e-8, "max_iter": 5000}
    extra = summary["inputs"]["extra"]
    assert extra["previous_solver"] == {"method": "uzawa", "tol": 1e-10, "max_iter": 3}
    assert extra["resumed_from_level"] == 1
    # the same numbers as a run with the new solver from the start, to its tolerance
    assert run(cfg, tmp_path / "ref").returncode == 0
    got, ref = arrays(out), arrays(tmp_path / "ref")
    assert np.allclose(got["wear"], ref["wear"], rtol=0, atol=1e-7)
    assert np.array_equal(got["wear"][0], ref["wear"][0])


@pytest.mark.parametrize(
    ("section", "value", "code", "says"),
    [
        # K's entries overflow (lam times B's entries of order 1/h): refused at assembly,
        # before any level is solved
        ("material", {"lam": 1e308}, 2, r"\[material\] lam = 1e\+308.*non-finite entries"),
        ("loads", {"f1": [0.0, -1e308]}, 3, "non-finite values at time level 0"),
        # v* divides by zero at t = 0.5: refused with the file, before any work
        (
            "contact",
            {"v_star": ["1/(t-0.5)", "0"]},
            2,
            r"\[contact\] v_star = \['1/\(t-0.5\)', '0'\] is not finite at t = 0.5 \(level 4\)",
        ),
        ("time", {"steps": 1_000_000_000}, 2, "of memory"),
        ("mesh", {"generator": "voronoi", "n_cells": 100_000_000, "divisions": None}, 2, "memory"),
    ],
)
def test_extreme_values_end_in_one_clear_line(
    tmp_path: Path, section: str, value: dict, code: int, says: str
) -> None:
    cfg = tmp_path / "case.toml"
    cfg.write_text(small_config("extreme", **{section: value}))
    out = tmp_path / "out"
    done = run(cfg, out)
    assert done.returncode == code, done.stderr
    assert done.stderr.count("\n") == 1 and re.search(says, done.stderr), done.stderr
    assert "internal error" not in done.stderr and "Warning" not in done.stderr
    # nothing, or the finished levels of a solver failure with the note how to resume
    assert not out.exists() or (code == 3 and (out / "PARTIAL.txt").is_file())


def test_peak_memory_does_not_grow_with_the_levels(tmp_path: Path) -> None:
    """The kept rows stream to disk: 20 times more levels cost no memory (within 25 %),
    while result.h5 grows. Peak RSS of the child measured by the kernel (VmHWM: ru_maxrss
    would carry the test runner's size across exec); the plan's
    estimate made in the child after the libraries are loaded and have run once (a run
    of 2 levels first: the buffers of OpenBLAS and MKL depend on the machine's cores) is
    within a factor 2 of it."""
    code = (
        "import sys\n"
        "from vemwear.cli.main import main\n"
        "from vemwear.config import load_config\n"
        "from vemwear.runner.plan import estimate_config\n"
        "assert main(['run', sys.argv[3], '-o', sys.argv[4], '--no-progress']) == 0\n"
        "est = estimate_config(load_config(sys.argv[1])).memory\n"
        "c = main(['run', sys.argv[1], '-o', sys.argv[2], '--no-progress'])\n"
        "from vemwear.util.system import peak_memory\n"
        "print(est, peak_memory())\n"
        "sys.exit(c)\n"
    )
    peaks = {}
    est = 0.0
    for steps in (500, 10000):
        cfg = tmp_path / f"s{steps}.toml"
        cfg.write_text(
            small_config(
                "mem",
                divisions=(16, 8),
                steps=steps,
                output={"store_u": "final", "every": 10, "figures": False, "vtk": False},
            )
        )
        out = tmp_path / f"o{steps}"
        warm = tmp_path / f"w{steps}.toml"
        warm.write_text(small_config("warm", divisions=(16, 8), steps=2, output={"figures": False}))
        done = subprocess.run(
            [
                sys.executable,
                "-c",
                code,
                str(cfg),
                str(out),
                str(warm),
                str(tmp_path / f"w{steps}"),
            ],
            capture_output=True,
            text=True,
        )
        assert done.returncode == 0, done.stderr
        words = done.stdout.split()
        est, peaks[steps] = float(words[-2]), int(words[-1])
    assert peaks[10000] < 1.25 * peaks[500], peaks
    assert 0.5 < est / peaks[10000] < 2.0, (est, peaks)
    assert os.path.getsize(tmp_path / "o10000" / "result.h5") > os.path.getsize(
        tmp_path / "o500" / "result.h5"
    )


def test_arrays_too_large_for_memory_end_with_result_h5_and_export(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """When the kept arrays would not fit in the memory available at the end of a run,
    the run ends with result.h5 alone (one line says so) and ``vemwear export`` writes
    the result.npz an in-memory run writes. The machine's available memory is made small
    for the end of the run only (the plan before the run reads it on its own)."""
    from vemwear.cli.main import main
    from vemwear.runner.outdir import read_marker

    cfg = tmp_path / "c.toml"
    cfg.write_text(small_config("big", steps=40, output={"figures": False, "vtk": False}))
    assert main(["run", str(cfg), "-o", str(tmp_path / "ref"), "--no-progress"]) == 0
    capsys.readouterr()
    monkeypatch.setattr("vemwear.util.system.available_memory", lambda: 1000)
    out = tmp_path / "out"
    assert main(["run", str(cfg), "-o", str(out), "--no-progress"]) == 0
    said = capsys.readouterr().out
    assert "result.npz, summary.json, figures and ParaView output are not written" in said
    assert f"vemwear export {out}" in said
    assert sorted(p.name for p in out.iterdir()) == [".vemwear", ".vemwear.lock", "result.h5"]
    assert read_marker(out)["state"] == "complete"  # type: ignore[index]
    # export refuses on this machine, then writes on a larger one
    assert main(["export", str(out)]) == 2
    assert "more than the 0.00 GB of memory" in capsys.readouterr().err
    monkeypatch.undo()
    assert main(["export", str(out)]) == 0
    ref, got = arrays(tmp_path / "ref"), arrays(out)
    assert sorted(got) == sorted(ref)
    for k in ref:
        if ref[k].dtype.kind in "fiub":
            assert np.array_equal(got[k], ref[k]), k
    assert "result.npz" in read_marker(out)["files"]  # type: ignore[index]


@pytest.fixture
def small_disk(tmp_path: Path):
    """A real 300 kB file system (tmpfs); mounting needs root, else the test is skipped."""
    disk = tmp_path / "disk"
    disk.mkdir()
    done = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=300k", "tmpfs", str(disk)], capture_output=True
    )
    if done.returncode != 0:
        pytest.skip("mounting a small tmpfs needs root")
    yield disk
    subprocess.run(["umount", "-l", str(disk)], check=False)


def test_full_disk_keeps_every_solved_level_and_resume_writes_the_outputs(
    tmp_path: Path, small_disk: Path
) -> None:
    """A disk that fills up while the outputs are written (run with --force-size past
    the plan): one line, exit 1, the streamed levels and the checkpoint kept; with more
    space, --resume writes the arrays of an uninterrupted run."""
    cfg = tmp_path / "c.toml"
    cfg.write_text(small_config("disk", divisions=(16, 8), steps=40, output={"store_u": "all"}))
    out = small_disk / "out"
    done = run(cfg, out, "--force-size")
    assert done.returncode == 1, done.stderr
    assert done.stderr.count("\n") == 1 and "the disk is full" in done.stderr
    assert "every time level is solved and saved" in done.stderr and "--resume" in done.stderr
    assert (out / "result.h5").is_file() and (out / "checkpoint.npz").is_file()
    subprocess.run(["mount", "-o", "remount,size=20m", str(small_disk)], check=True)
    done = run(cfg, out, "--resume")
    assert done.returncode == 0, done.stderr
    assert run(cfg, tmp_path / "ref").returncode == 0
    ref, got = arrays(tmp_path / "ref"), arrays(out)
    assert sorted(got) == sorted(ref)
    assert all(np.array_equal(got[k], ref[k]) for k in ref if ref[k].dtype.kind in "fiub")


def test_a_run_that_would_not_fit_on_the_disk_is_refused_before_any_work(
    tmp_path: Path, small_disk: Path
) -> None:
    cfg = tmp_path / "c.toml"
    cfg.write_text(small_config("disk", divisions=(16, 8), steps=400, output={"store_u": "all"}))
    done = run(cfg, small_disk / "out")
    assert done.returncode == 2, done.stderr
    assert (
        done.stderr.count("\n") == 1 and "of disk" in done.stderr and "--force-size" in done.stderr
    )
    assert list(small_disk.iterdir()) == []


def test_out_of_memory_is_one_line_and_leaves_nothing(tmp_path: Path) -> None:
    """A real MemoryError: the child's address space is limited to what it holds after
    its imports plus 100 MB, too little to solve on 256 x 128 cells (the libraries a run
    loads have been loaded and have run before the limit is set: a run of 2 levels
    first, so that OpenBLAS and MKL hold their buffers)."""
    cfg = tmp_path / "c.toml"
    cfg.write_text(small_config("oom", divisions=(256, 128), steps=10))
    warm = tmp_path / "warm.toml"
    warm.write_text(small_config("warm", divisions=(16, 8), steps=2, output={"figures": False}))
    code = (
        "import hashlib, resource, sys\n"
        "import h5py, scipy.sparse.linalg\n"
        "from vemwear.cli.main import main\n"
        "assert main(['run', sys.argv[3], '-o', sys.argv[4], '--no-progress']) == 0\n"
        "vm = next(int(l.split()[1]) * 1024 for l in open('/proc/self/status')\n"
        "          if l.startswith('VmSize:'))\n"
        "resource.setrlimit(resource.RLIMIT_AS, (vm + 100_000_000, vm + 100_000_000))\n"
        "sys.exit(main(['run', sys.argv[1], '-o', sys.argv[2], '--no-progress',\n"
        "               '--force-size']))\n"
    )
    out = tmp_path / "out"
    env = {
        **os.environ,
        "OPENBLAS_NUM_THREADS": "1",
        "OMP_NUM_THREADS": "1",
        "MKL_NUM_THREADS": "1",
    }
    done = subprocess.run(
        [sys.executable, "-c", code, str(cfg), str(out), str(warm), str(tmp_path / "w")],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
    )
    assert done.returncode == 1, done.stderr
    assert done.stderr.count("\n") == 1 and "out of memory" in done.stderr, done.stderr
    assert not out.exists()


def remount(disk: Path, options: str) -> None:
    subprocess.run(["mount", "-o", f"remount,{options}", str(disk)], check=True)


def test_a_mount_point_as_the_output_directory(
    config: Path, small_disk: Path, reference: dict[str, np.ndarray]
) -> None:
    """A mount point (a Docker volume) is written into, never renamed or removed: by a
    run, by --force, by a run killed with SIGKILL after a checkpoint and its --resume."""
    remount(small_disk, "size=256m")
    out = small_disk
    done = run(config, out)
    assert done.returncode == 0, done.stderr
    assert os.path.ismount(out)
    assert_same(out, reference)
    (out / "notes.txt").write_text("mine")  # the user's own file in the volume
    again = run(config, out, "--force")
    assert again.returncode == 0, again.stderr
    assert os.path.ismount(out) and (out / "notes.txt").read_text() == "mine"
    assert_same(out, reference)
    proc = start(config, out, "--force")
    wait_for(out / "checkpoint.npz", proc)
    time.sleep(0.3)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    assert os.path.ismount(out)
    resumed = run(config, out, "--resume")
    assert resumed.returncode == 0, resumed.stderr
    assert "resumed from level" in resumed.stdout
    assert os.path.ismount(out) and (out / "notes.txt").read_text() == "mine"
    assert_same(out, reference)


def test_a_read_only_mount_point_is_refused_and_nothing_is_written(
    tmp_path: Path, small_disk: Path
) -> None:
    """A volume mounted read-only: a run into it (replacing an earlier output with
    --force) or into a new directory on it is refused at once, exit code 2."""
    cfg = tmp_path / "c.toml"
    cfg.write_text(small_config("ro", output={"figures": False, "vtk": False}))
    assert run(cfg, small_disk).returncode == 0  # an earlier output in the volume
    remount(small_disk, "ro")
    before = {p.name: p.stat().st_mtime_ns for p in small_disk.iterdir()}
    for target, extra in ((small_disk, ("--force",)), (small_disk / "new", ())):
        done = run(cfg, target, *extra)
        assert done.returncode == 2, done.stderr
        assert done.stderr == (
            f"vemwear: error: cannot write into {target}: {small_disk} is not writable\n"
        )
    assert {p.name: p.stat().st_mtime_ns for p in small_disk.iterdir()} == before
    assert os.path.ismount(small_disk)


def test_the_plan_refuses_with_the_numbers_of_check_and_resume_asks_only_for_the_rest(
    config: Path, small_disk: Path, reference: dict[str, np.ndarray]
) -> None:
    """``run`` refuses with the disk estimate that ``check`` prints (the real mesh's); a
    run that this estimate admits is not refused by the rough one made before the mesh
    is built; a resumed run does not ask again for the disk its result.h5 occupies."""
    check = subprocess.run(
        [sys.executable, "-m", "vemwear", "check", str(config)], capture_output=True, text=True
    )
    assert check.returncode == 0, check.stderr
    disk = re.search(r"disk \(estimate\) +(\d+) MB", check.stdout)
    assert disk is not None, check.stdout
    need = int(disk.group(1))
    out = small_disk / "out"
    remount(small_disk, f"size={(need - 2) * 10**6}")
    refused = run(config, out)
    assert refused.returncode == 2
    said = re.search(r"the output needs about (\d+) MB of disk, (\d+) MB are free", refused.stderr)
    assert said is not None and int(said.group(1)) == need, refused.stderr
    assert "--force-size" in refused.stderr and not out.exists()
    remount(small_disk, f"size={(need + 2) * 10**6}")
    proc = start(config, out)
    wait_for(out / "checkpoint.npz", proc)
    time.sleep(0.3)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    # result.h5 holds every kept row already: less than the estimate is free now
    assert shutil.disk_usage(small_disk).free < need * 1e6
    resumed = run(config, out, "--resume")
    assert resumed.returncode == 0, resumed.stderr
    assert_same(out, reference)


def test_the_memory_model_grows_with_every_size_and_the_rough_estimate_is_a_lower_bound() -> None:
    """The estimate is non-decreasing in every size (the rough check relies on it), the
    factorization's term is larger with SuperLU than with PARDISO at every size past
    MKL's buffers, and the rough estimate, which knows no backend, takes the smaller."""
    from vemwear.runner.plan import estimate

    sizes = dict(levels=65, points=5000, cells=4900, contact=100, kept=65, stored_u=8)
    for dim in (2, 3):
        for backend in ("pardiso", "scipy"):
            base = estimate(**sizes, paraview=False, base=1e8, dim=dim, backend=backend)
            for key in sizes:
                more = dict(sizes, **{key: 2 * sizes[key]})
                grown = estimate(**more, paraview=False, base=1e8, dim=dim, backend=backend)
                assert grown.memory >= base.memory and grown.disk >= base.disk, (dim, key)
        for points in (10, 10**4, 10**6):
            s = dict(sizes, points=points)
            by = {
                b: estimate(**s, paraview=False, base=1e8, dim=dim, backend=b).memory
                for b in ("pardiso", "scipy", "any")
            }
            assert by["any"] == min(by["pardiso"], by["scipy"])
            if points >= 10**4:
                assert by["scipy"] > by["pardiso"]
