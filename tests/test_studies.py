"""Parameter studies and calibration on Dask (vemwear.studies; ``vemwear sweep``/``fit``).

Real components throughout: study files on disk, Dask clusters (an embedded LocalCluster,
and a ``dask scheduler`` with ``dask worker`` processes on 127.0.0.1), runs through
vemwear.runner, netCDF files read back by xarray.
"""

from __future__ import annotations

import itertools
import json
import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from conftest import small_config
from vemwear.studies import StudyError, load_study

xr = pytest.importorskip("xarray")
pytest.importorskip("distributed")

VEMWEAR = [sys.executable, "-m", "vemwear"]


def _study(tmp: Path, body: str, base: str | None = None, name: str = "study.toml") -> Path:
    (tmp / "case.toml").write_text(base or small_config("case"), encoding="utf-8")
    path = tmp / name
    path.write_text('base = "case.toml"\n' + body, encoding="utf-8")
    return path


def _json(path: Path) -> dict:
    return json.loads(path.read_text())


# ---------------------------------------------------------------------------- designs
def test_grid_zip_and_ranges(tmp_path: Path) -> None:
    st = load_study(
        _study(
            tmp_path,
            '[axes]\n"contact.kappa" = { start = 1.0, stop = 3.0, num = 3 }\n'
            '"time.steps" = { start = 4, stop = 8, step = 2 }\n'
            '"mesh.divisions" = [[8, 4], [4, 2]]\n',
        )
    )
    assert st.kind == "grid" and st.shape == (3, 3, 2) and len(st.runs) == 18
    assert st.axes["contact.kappa"] == [1.0, 2.0, 3.0]
    assert st.axes["time.steps"] == [4, 6, 8] and all(type(v) is int for v in st.axes["time.steps"])
    first, last = st.runs[0], st.runs[-1]  # the first axis varies slowest
    assert first.params == {"contact.kappa": 1.0, "time.steps": 4, "mesh.divisions": [8, 4]}
    assert last.params == {"contact.kappa": 3.0, "time.steps": 8, "mesh.divisions": [4, 2]}
    assert last.data["contact"]["kappa"] == 3.0 and last.data["mesh"]["divisions"] == [4, 2]
    assert len({r.id for r in st.runs}) == 18
    assert load_study(st.path).runs[5].id == st.runs[5].id  # stable ids
    z = load_study(
        _study(
            tmp_path,
            '[axes]\n"contact.kappa" = [1.0, 2.0]\n"contact.mu" = [0.1, 0.3]\n'
            '[design]\nkind = "zip"\n',
            name="zip.toml",
        )
    )
    assert [r.params for r in z.runs] == [
        {"contact.kappa": 1.0, "contact.mu": 0.1},
        {"contact.kappa": 2.0, "contact.mu": 0.3},
    ]
    with pytest.raises(StudyError, match="one length"):
        load_study(
            _study(
                tmp_path,
                '[axes]\n"contact.kappa" = [1.0, 2.0]\n"contact.mu" = [0.1]\n'
                '[design]\nkind = "zip"\n',
                name="zip2.toml",
            )
        )


@pytest.mark.parametrize("kind", ["lhs", "sobol"])
def test_random_designs_within_bounds_and_seeded(tmp_path: Path, kind: str) -> None:
    body = (
        '[axes]\n"contact.kappa" = { low = 1.0, high = 10.0, scale = "log" }\n'
        '"contact.mu" = { low = 0.1, high = 0.6 }\n"time.steps" = { low = 4, high = 9 }\n'
        f'[design]\nkind = "{kind}"\nsamples = 8\nseed = 3\n'
    )
    st = load_study(_study(tmp_path, body))
    again = load_study(st.path)  # type: ignore[arg-type]
    other = load_study(_study(tmp_path, body.replace("seed = 3", "seed = 4"), name="b.toml"))
    k = np.array([r.params["contact.kappa"] for r in st.runs])
    mu = np.array([r.params["contact.mu"] for r in st.runs])
    steps = [r.params["time.steps"] for r in st.runs]
    assert len(st.runs) == 8 and st.shape == (8,)
    assert np.all((k >= 1.0) & (k <= 10.0)) and np.all((mu >= 0.1) & (mu <= 0.6))
    assert all(type(s) is int and 4 <= s <= 9 for s in steps)
    assert [r.params for r in again.runs] == [r.params for r in st.runs]
    assert [r.params for r in other.runs] != [r.params for r in st.runs]
    if kind == "lhs":  # one point in each eighth of every axis
        strata = np.floor((mu - 0.1) / 0.5 * 8).astype(int)
        assert sorted(strata) == list(range(8))


def test_a_bad_combination_is_reported_before_any_run(tmp_path: Path) -> None:
    from vemwear.studies import sweep

    path = _study(
        tmp_path,
        '[axes]\n"contact.kappa" = [1.0, 2.0]\n"contact.g" = [0.1, -0.5]\n',
    )
    out = tmp_path / "out"
    with pytest.raises(StudyError) as info:
        sweep(path, out, progress=False)
    msg = str(info.value)
    assert "run 1 (contact.kappa = 1, contact.g = -0.5)" in msg and "[contact] g" in msg, msg
    assert not out.exists()  # nothing started, nothing written
    bad_key = _study(tmp_path, '[axes]\n"contact.kapa" = [1.0]\n', name="k.toml")
    r = subprocess.run(
        [*VEMWEAR, "sweep", str(bad_key), "-o", str(out)], capture_output=True, text=True
    )
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert "'contact.kapa'" in r.stderr and "did you mean 'kappa'" in r.stderr
    assert not out.exists()


# ---------------------------------------------------------------------------- LocalCluster
def test_sweep_on_the_default_local_cluster(tmp_path: Path) -> None:
    from vemwear.studies import sweep

    path = _study(
        tmp_path,
        '[axes]\n"contact.kappa" = [1.0, 2.0, 4.0]\n"contact.mu" = [0.2, 0.6]\n'
        '[overrides]\n"time.steps" = 8\n',
    )
    out = tmp_path / "out"
    ds = sweep(path, out, workers=2, progress=False)
    assert ds.attrs["runs_computed"] == 6 and ds.attrs["runs_failed"] == 0
    back = xr.open_dataset(out / "study.nc", engine="h5netcdf")
    assert back["max_wear"].dims == ("contact_kappa", "contact_mu")
    assert list(back["contact_kappa"].values) == [1.0, 2.0, 4.0]
    assert back["contact_kappa"].attrs["config_key"] == "contact.kappa"
    assert back["wear"].dims == ("contact_kappa", "contact_mu", "time", "s")
    assert float(back["max_wear"].sel(contact_kappa=2.0, contact_mu=0.6)) == mw_at(back)
    assert back.sizes["time"] == 9 and back.sizes["s"] == 8
    mw = back["max_wear"].values
    assert np.all(np.diff(mw, axis=0) > 0), mw  # more wear with larger kappa
    _assert_cf(out / "study.nc")
    assert np.allclose(back["wear"].isel(time=-1).max("s").values, mw)
    assert (back["status"].values == "done").all() and "[axes]" in back.attrs["study"]
    assert "kappa" in back.attrs["base_config"] and back.attrs["vemwear_version"]
    for name in ("summary.png", "wear_profiles.png", "report.md", "study.toml"):
        assert (out / name).is_file(), name
    ids = list(back["run_id"].values.ravel())
    assert sorted(p.name for p in (out / "runs").iterdir()) == sorted(ids)
    assert all((out / "configs" / f"{i}.toml").is_file() for i in ids)
    back.close()


def test_the_warnings_of_runs_on_workers_reach_the_user(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A run whose explicit wear step overshoots warns on its worker as ``vemwear run``
    does: the client says the warning with the run and its parameters, the run's record
    keeps it, and a second execution (nothing to compute) does not say it again."""
    from vemwear.studies import sweep

    # kappa = 25: k kappa |v*| L_p = 1.25, in a layer too thick to be worn through
    path = _study(
        tmp_path, '[axes]\n"contact.kappa" = [25.0, 1.0]\n[overrides]\n"contact.g" = 10.0\n'
    )
    out = tmp_path / "out"
    sweep(path, out, workers=1, progress=False, figures=False, say=None)
    err = capsys.readouterr().err.splitlines()
    said = [line for line in err if "warning:" in line]
    assert len(said) == 1, err
    recs = {r["params"]["contact.kappa"]: r for r in map(_json, (out / "log").glob("*.json"))}
    assert said[0].startswith(
        f"vemwear: run {recs[25.0]['id']} (contact.kappa = 25): warning: the explicit wear "
        "update can overshoot: k kappa |v*| L_p = 1.25 "
    ), said
    assert recs[25.0]["status"] == "done" and recs[1.0]["status"] == "done"
    assert recs[25.0]["warnings"] == [said[0].split("warning: ", 1)[1]]
    assert recs[1.0]["warnings"] == []
    sweep(path, out, workers=1, progress=False, figures=False, say=None)
    assert "warning:" not in capsys.readouterr().err


def test_a_failing_run_is_retried_then_recorded_and_the_others_go_on(tmp_path: Path) -> None:
    """A run that cannot converge (tol below round-off) fails on both tries; the other
    runs of its task and of the study finish; the record and the Dataset name the error."""
    from vemwear.studies import sweep

    path = _study(
        tmp_path,
        '[axes]\n"solver.tol" = [1e-10, 1e-30, 1e-9]\n[overrides]\n"time.steps" = 4\n',
    )
    out = tmp_path / "out"
    ds = sweep(path, out, workers=1, progress=False, figures=False, chunk=3)
    assert ds.attrs["runs_computed"] == 2 and ds.attrs["runs_failed"] == 1
    status = list(ds["status"].values)
    assert status == ["done", "failed", "done"], status
    error = str(ds["error"].values[1])
    assert "did not converge" in error and "time level" in error, error
    assert np.isnan(ds["max_wear"].values[1]) and np.all(ds["max_wear"].values[[0, 2]] > 0)
    rid = str(ds["run_id"].values[1])
    rec = json.loads((out / "log" / f"{rid}.json").read_text())
    assert rec["status"] == "failed" and "did not converge" in rec["error"]
    assert not (out / "runs" / rid / "result.npz").exists()


def test_workers_report_each_run_of_a_chunk_as_it_finishes(tmp_path: Path) -> None:
    """Four runs in one task: the worker publishes each finished run (the progress bar's
    events), one after the other, before the task ends."""
    from vemwear.studies import load_study
    from vemwear.studies.dataset import run_arrays
    from vemwear.studies.execute import run_all, study_client
    from vemwear.studies.layout import open_study_dir
    from vemwear.studies.tasks import PROGRESS_TOPIC

    st = load_study(_study(tmp_path, '[axes]\n"contact.kappa" = [1.0, 2.0, 3.0, 4.0]\n'))
    out = open_study_dir(tmp_path / "out", "sweep")
    events: list[tuple[float, str]] = []
    with study_client(workers=1) as client:
        client.subscribe_topic(PROGRESS_TOPIC, events.append)
        ex = run_all(st.runs, out, client, progress=False, chunk=4, extract=run_arrays)
        deadline = time.monotonic() + 10
        while len(events) < 4 and time.monotonic() < deadline:
            time.sleep(0.05)
    assert ex.computed == 4 and set(ex.arrays) == {r.id for r in st.runs}
    assert [rid for _, rid in events] == [r.id for r in st.runs]
    stamps = [t for t, _ in events]
    assert all(b > a for a, b in itertools.pairwise(stamps)), stamps


# ---------------------------------------------------------------------------- dask scheduler
def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _start_worker(address: str, tmp: Path, name: str) -> subprocess.Popen[bytes]:
    return subprocess.Popen(
        [
            "dask",
            "worker",
            address,
            "--nthreads",
            "1",
            "--no-dashboard",
            "--no-nanny",
            "--host",
            "127.0.0.1",
            "--name",
            name,
            "--local-directory",
            str(tmp / f"dask-{name}"),
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


def _wait_workers(address: str, n: int, timeout: float = 60.0) -> None:
    from distributed import Client

    with Client(address, timeout=30) as c:
        c.wait_for_workers(n, timeout=timeout)


@pytest.fixture(scope="module")
def scheduler(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, list[int]]]:
    """A ``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1: the address
    and the workers' pids."""
    tmp = tmp_path_factory.mktemp("dask")
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    procs = [
        subprocess.Popen(
            ["dask", "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    ]
    try:
        procs += [_start_worker(address, tmp, f"w{i}") for i in range(2)]
        _wait_workers(address, 2)
        yield address, [p.pid for p in procs[1:]]
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            try:
                p.wait(timeout=5)
            except subprocess.TimeoutExpired:
                p.kill()


def _pids_of_records(out: Path) -> dict[str, int]:
    import json

    recs = [json.loads(p.read_text()) for p in (out / "log").glob("*.json")]
    return {r["id"]: int(r["worker"].rsplit(":", 1)[1]) for r in recs}


def test_sweep_through_a_dask_scheduler(tmp_path: Path, scheduler: tuple[str, list[int]]) -> None:
    address, pids = scheduler
    path = _study(tmp_path, '[axes]\n"contact.kappa" = [1.0, 2.0, 3.0, 4.0]\n')
    out = tmp_path / "out"
    r = subprocess.run(
        [*VEMWEAR, "sweep", str(path), "-o", str(out), "--scheduler", address, "--no-progress"],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0, r.stderr
    assert "4: 4 computed, 0 finished earlier, 0 failed" in r.stdout
    ds = xr.open_dataset(out / "study.nc", engine="h5netcdf")
    assert np.all(np.diff(ds["max_wear"].values) > 0)
    ds.close()
    assert set(_pids_of_records(out).values()) <= set(pids)  # run by the dask workers


def _locked_by_one_of(out: Path, pids: set[int]) -> Path | None:
    from vemwear.runner.outdir import locked_by

    for d in (out / "runs").glob("r*"):
        pid = locked_by(d)
        if pid in pids:
            return d
    return None


def test_a_stopped_study_started_again_skips_finished_runs(
    tmp_path: Path, scheduler: tuple[str, list[int]]
) -> None:
    from vemwear.runner.outdir import locked_by
    from vemwear.studies.layout import is_complete

    address, _ = scheduler
    base = small_config("case", divisions=(16, 8), steps=600)
    path = _study(
        tmp_path, '[axes]\n"contact.kappa" = { start = 1.0, stop = 10.0, num = 10 }\n', base
    )
    out = tmp_path / "out"
    cmd = [*VEMWEAR, "sweep", str(path), "-o", str(out), "--scheduler", address, "--no-progress"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while len(list((out / "log").glob("*.json"))) < 2 and time.monotonic() < deadline:
        time.sleep(0.02)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    # the runs a worker had already received finish, and may start (lock their
    # directory) a moment after the client stopped: wait until nothing changes for 1.5 s
    state: tuple = ()
    quiet, deadline = time.monotonic(), time.monotonic() + 60
    while time.monotonic() < deadline:
        runs = sorted((out / "runs").glob("r*"))
        locked = [locked_by(d) is not None for d in runs]
        now = ([d.name for d in runs], [is_complete(d) for d in runs], locked)
        if now != state:
            state, quiet = now, time.monotonic()
        elif not any(locked) and time.monotonic() - quiet > 1.5:
            break
        time.sleep(0.05)
    done = {d.name: (d / "result.npz").stat().st_mtime_ns for d in runs if is_complete(d)}
    assert 2 <= len(done) < 10, len(done)
    # a worker killed after a run's result was complete but before its record was logged
    (out / "log" / f"{min(done)}.json").unlink()
    r = subprocess.run(cmd, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert f"10: {10 - len(done)} computed, {len(done)} finished earlier, 0 failed" in r.stdout
    for name, mtime in done.items():  # untouched
        assert (out / "runs" / name / "result.npz").stat().st_mtime_ns == mtime
    logged = {p.stem for p in (out / "log").glob("*.json")}
    assert logged == {d.name for d in (out / "runs").glob("r*")} and len(logged) == 10
    ds = xr.open_dataset(out / "study.nc", engine="h5netcdf")
    assert (ds["status"].values == "done").all() and np.all(np.diff(ds["max_wear"].values) > 0)
    ds.close()


def test_fit_recovers_kappa_from_noisy_synthetic_data(
    tmp_path: Path, scheduler: tuple[str, list[int]]
) -> None:
    """Data made by vemwear with kappa = 2.5 plus 2 % noise; the fit starts at kappa = 2."""
    from distributed import Client

    from vemwear.config import apply_overrides, parse_config
    from vemwear.simulate import simulate
    from vemwear.studies import fit

    text = small_config("case", divisions=(16, 8), steps=16)
    (tmp_path / "case.toml").write_text(text)
    import tomllib

    cfg = parse_config(apply_overrides(tomllib.loads(text), {"contact.kappa": 2.5}))
    res = simulate(cfg.problem, cfg.solver)
    x = cfg.problem.contact.points[:, 0]
    rng = np.random.default_rng(0)
    rows = ["x,t,w"]
    for n in (8, 16):  # t = 0.5 and 1
        w = res.wear[n] * (1 + 0.02 * rng.standard_normal(x.size))
        rows += [f"{a:.17g},{res.t[n]:.17g},{b:.17g}" for a, b in zip(x, w, strict=True)]
    (tmp_path / "measured.csv").write_text("\n".join(rows) + "\n")
    with Client(scheduler[0], timeout=30) as client:  # the user's own client
        fr = fit(
            tmp_path / "case.toml", tmp_path / "measured.csv", client=client, out=tmp_path / "fit"
        )
        assert client.status == "running"  # left open
    lo, hi = fr.interval["kappa"]
    print(f"\nfit: kappa = {fr.estimate['kappa']:.5f}, 95 % interval [{lo:.5f}, {hi:.5f}]")
    assert fr.success and fr.initial["kappa"] == 2.0
    assert lo < 2.5 < hi and hi - lo < 0.1 and fr.errors == "relative"
    assert fr.residuals.size == 2 * x.size
    assert {"fit.json", "fit.md", "fit.png"} <= {p.name for p in (tmp_path / "fit").iterdir()}


def test_a_killed_worker_does_not_stop_the_study(
    tmp_path: Path, scheduler: tuple[str, list[int]]
) -> None:
    """A third worker joins; once it runs a run, it is killed (SIGKILL); its run is
    rescheduled on the others and the study completes."""
    address, _ = scheduler
    victim = _start_worker(address, tmp_path, "victim")
    try:
        _wait_workers(address, 3)
        base = small_config("case", divisions=(16, 8), steps=1000)
        path = _study(tmp_path, '[axes]\n"contact.kappa" = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]\n', base)
        out = tmp_path / "out"
        # two runs per task: the victim's task is rescheduled whole, and the run it
        # may have finished is kept
        cmd = [*VEMWEAR, "sweep", str(path), "-o", str(out), "--scheduler", address, "--chunk", "2"]
        proc = subprocess.Popen(
            [*cmd, "--no-progress"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        )
        deadline = time.monotonic() + 60
        hit = None
        while hit is None and time.monotonic() < deadline and proc.poll() is None:
            hit = _locked_by_one_of(out, {victim.pid})
            time.sleep(0.01)
        assert hit is not None, "the victim never ran a run"
        os.kill(victim.pid, signal.SIGKILL)
        victim.wait(timeout=10)
        stdout, err = proc.communicate(timeout=120)
        assert proc.returncode == 0, err
        assert "6: 6 computed, 0 finished earlier, 0 failed" in stdout
        by = _pids_of_records(out)
        assert by[hit.name] != victim.pid  # finished by another worker
        ds = xr.open_dataset(out / "study.nc", engine="h5netcdf")
        assert (ds["status"].values == "done").all() and np.all(np.diff(ds["max_wear"].values) > 0)
        ds.close()
    finally:
        if victim.poll() is None:
            victim.kill()
            victim.wait()


def mw_at(ds: xr.Dataset) -> float:
    """max_wear at kappa = 2, mu = 0.6 by position (index 1, 1)."""
    return float(ds["max_wear"].values[1, 1])


def _assert_cf(path: Path) -> None:
    """study.nc by CF-1.10, read back with xarray and h5py (the raw attributes)."""
    import h5py

    ds = xr.open_dataset(path, engine="h5netcdf")
    try:
        assert ds.attrs["Conventions"] == "CF-1.10"
        assert " vemwear " in ds.attrs["history"] and " sweep " in ds.attrs["history"]
        for name, var in ds.variables.items():
            assert var.attrs.get("long_name"), name
            if var.dtype.kind in "iuf":
                assert var.attrs.get("units"), name
        assert ds["iterations"].dtype == np.int64 and (ds["iterations"] > 0).all()
        for k in json.loads(ds.attrs["axis_variables"]):
            assert k.isidentifier() and "." in ds[k].attrs["config_key"]
    finally:
        ds.close()
    with h5py.File(path, "r") as f:
        for name in ("time", "s", *json.loads(f.attrs["axis_variables"])):
            if name in f:
                assert "_FillValue" not in f[name].attrs, name
        assert f["iterations"].dtype == np.int64


def test_sweep_uses_the_active_dask_client(
    tmp_path: Path, scheduler: tuple[str, list[int]]
) -> None:
    """With a client active in the process and none given, sweep runs on it (its
    workers' pids are in the run records) and says so, instead of starting a cluster."""
    from distributed import Client

    from vemwear.studies import sweep

    path = _study(tmp_path, '[axes]\n"contact.kappa" = [1.0, 2.0]\n[overrides]\n"time.steps" = 4\n')
    said: list[str] = []
    with Client(scheduler[0], timeout=30) as client:
        ds = sweep(path, tmp_path / "out", progress=False, figures=False, say=said.append)
        assert client.status == "running"  # left open
    assert said == [f"vemwear: using the active Dask client (scheduler {scheduler[0]})"]
    assert ds.attrs["runs_computed"] == 2
    assert set(_pids_of_records(tmp_path / "out").values()) <= set(scheduler[1])
