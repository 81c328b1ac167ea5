"""Crash anywhere, for studies: ``vemwear sweep`` on a real local Dask cluster, its
client process or a worker process killed at random instants.

The sibling of ``crash_anywhere.py`` for ``vemwear sweep``. Each trial starts
``vemwear sweep STUDY -o OUTDIR --workers 2`` (an embedded ``LocalCluster``: the client
and scheduler in the command's process, two worker processes) and, at a random instant
of the sweep (the cluster's start, the runs, the final writes of ``study.nc``, figures
and report), kills with SIGKILL or SIGTERM:

* ``client``: the command's process. Workers it leaves behind get 5 s to notice and
  exit, then are killed (a batch system ends the job's processes); how many there were
  is counted.
* ``worker``: one worker process; the sweep goes on (Dask starts a new worker and
  reschedules the lost task) and must finish with exit 0 by itself.
* ``both``: a worker, then the client a little later.

Then ``vemwear sweep`` with the same arguments (the command has no ``--resume``: a
sweep into the directory of a stopped one computes only the runs not yet complete)
must exit 0, with a ``study.nc`` whose every variable and coordinate is bitwise equal
(``np.array_equal``, NaN equal to NaN; read with xarray) to that of an uninterrupted
sweep, except ``wall_time`` (seconds), and OUTDIR must hold exactly the files of an
uninterrupted sweep (no temporaries, no partial files). A SIGTERM to the client must
stop it within 5 s (its cluster is closed on the way).

Usage::

    python benchmarks/crash_sweep.py                  # 40 trials
    python benchmarks/crash_sweep.py --trials 100 --seed 3
"""

from __future__ import annotations

import argparse
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import numpy as np

BASE = """\
title = "crash sweep"
[mesh]
generator = "squares"
size = [2.0, 1.0]
divisions = [16, 8]
[boundary]
clamped = "left"
traction = "rest"
contact = "bottom"
[material]
lam = 4.0
eta = 4.0
[loads]
f1 = [0.0, -0.06]
[contact]
p = { type = "linear", c = 0.4 }
g = 0.1
mu = 0.2
kappa = 2.0
v_star = ["1 + 0.5*sin(2*pi*t)", "0"]
[time]
T = 1.0
steps = 300
[solver]
method = "newton"
backend = "scipy"
[output]
checkpoint = 0.05
figures = false
vtk = false
"""

STUDY = """\
title = "crash sweep"
base = "base.toml"
[axes]
"contact.kappa" = [1.0, 2.0, 3.0, 4.0]
"contact.mu" = [0.2, 0.4]
"""
RUNS = 8
#: Seconds a SIGTERM may take to stop the client (it closes its cluster).
STOP_WITHIN = 5.0
#: Seconds the workers of a killed client get to exit by themselves.
ORPHAN_GRACE = 5.0
#: Variables that differ between executions by nature.
TIMINGS = ("wall_time",)


def _cmd(study: Path, out: Path) -> list[str]:
    return [
        *(sys.executable, "-m", "vemwear", "sweep", str(study), "-o", str(out)),
        *("--workers", "2", "--chunk", "1", "--no-progress"),
    ]


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["MPLBACKEND"] = "Agg"
    return env


def study_arrays(out: Path) -> dict[str, np.ndarray]:
    """Every variable and coordinate of ``OUTDIR/study.nc`` (xarray), but the timings."""
    import xarray as xr

    with xr.open_dataset(out / "study.nc", engine="h5netcdf") as ds:
        return {str(k): np.asarray(v.values) for k, v in ds.variables.items() if k not in TIMINGS}


def files(out: Path) -> set[str]:
    """The files under OUTDIR, by relative path."""
    return {str(p.relative_to(out)) for p in out.rglob("*") if p.is_file()}


def _equal(a: np.ndarray, b: np.ndarray) -> bool:
    if a.shape != b.shape or a.dtype != b.dtype:
        return False
    return bool(np.array_equal(a, b, equal_nan=a.dtype.kind in "fc"))


def descendants(pid: int) -> list[int]:
    """The processes below ``pid`` (the cluster's workers and their helpers)."""
    import psutil

    try:
        return [c.pid for c in psutil.Process(pid).children(recursive=True)]
    except psutil.NoSuchProcess:
        return []


def workers_of(pid: int) -> list[int]:
    """The Dask worker processes of the sweep ``pid`` (multiprocessing children)."""
    import psutil

    out = []
    for c in descendants(pid):
        try:
            if "multiprocessing" in " ".join(psutil.Process(c).cmdline()):
                out.append(c)
        except psutil.NoSuchProcess:
            pass
    return out


def _reap(pids: list[int], grace: float) -> int:
    """Wait up to ``grace`` s for ``pids`` to end, then SIGKILL those left; their count."""
    import psutil

    procs = []
    for p in pids:
        try:
            procs.append(psutil.Process(p))
        except psutil.NoSuchProcess:
            pass
    _, alive = psutil.wait_procs(procs, timeout=grace)
    for p in alive:
        try:
            p.kill()
        except psutil.NoSuchProcess:
            pass
    psutil.wait_procs(alive, timeout=5)
    return len(alive)


@dataclass
class Reference:
    study: Path
    arrays: dict[str, np.ndarray]
    files: set[str]
    phases: list[tuple[float, float]]  # cluster start, runs, final writes (seconds)


PHASES = ("start", "runs", "final writes")


def reference(work: Path) -> Reference:
    """An uninterrupted sweep: its arrays, its files, the instants of its phases."""
    (work / "base.toml").write_text(BASE)
    study = work / "study.toml"
    study.write_text(STUDY)
    out = work / "reference"
    proc = subprocess.Popen(
        _cmd(study, out), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=_env()
    )
    t0 = time.monotonic()
    marks: dict[str, float] = {}
    while proc.poll() is None:
        now = time.monotonic() - t0
        logs = len(list((out / "log").glob("*.json"))) if (out / "log").is_dir() else 0
        if "first" not in marks and (out / "runs").is_dir() and any((out / "runs").iterdir()):
            marks["first"] = now
        if "all" not in marks and logs == RUNS:
            marks["all"] = now
        time.sleep(0.01)
    end = time.monotonic() - t0
    err = proc.stderr.read().decode() if proc.stderr else ""
    if proc.returncode != 0:
        raise SystemExit(f"the reference sweep failed: {err}")
    a = marks.get("first", 0.0)
    b = marks.get("all", a)
    return Reference(study, study_arrays(out), files(out), [(0.0, a), (a, b), (b, end)])


def _failures(out: Path) -> str:
    """The errors of the runs logged as failed in ``OUTDIR/log``."""
    import json

    errors = []
    for p in sorted((out / "log").glob("*.json")):
        rec = json.loads(p.read_text())
        if rec.get("status") == "failed":
            errors.append(f"; run {rec['id']}: {rec['error']}")
    return "".join(errors)


@dataclass
class Trial:
    phase: str
    kind: str  # client, worker, both
    sig: str
    delay: float
    rc: int | None  # exit of the killed sweep
    stop: float  # seconds from the client's signal to its exit
    orphans: int  # workers left by a killed client, killed after the grace
    recovered: str  # "by itself" (the killed sweep finished) or "rerun"
    ok: bool
    why: str


def trial(
    ref: Reference, work: Path, kind: str, delay: float, sig: signal.Signals, phase: str = ""
) -> Trial:
    """One kill and the recovery (module docstring)."""
    out = work / "out"
    if out.exists():
        shutil.rmtree(out)
    cmd = _cmd(ref.study, out)
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=_env())
    t0 = time.monotonic()
    why, stop, orphans = "", 0.0, 0
    if kind in ("worker", "both"):
        victim = None
        while proc.poll() is None and time.monotonic() - t0 < delay:
            time.sleep(0.01)
        while proc.poll() is None and victim is None and time.monotonic() - t0 < 60:
            ws = workers_of(proc.pid)  # the workers exist once the cluster started
            victim = random.choice(ws) if ws else None
            time.sleep(0.01) if victim is None else None
        if victim is not None:
            try:
                os.kill(victim, sig)
            except ProcessLookupError:
                pass
        delay = time.monotonic() - t0
        if kind == "both":
            time.sleep(random.uniform(0.0, 1.0))
    else:
        time.sleep(max(0.0, delay - (time.monotonic() - t0)))
    if kind in ("client", "both"):
        below = descendants(proc.pid)
        ts = time.monotonic()
        if proc.poll() is None:
            proc.send_signal(sig)
        try:
            proc.wait(timeout=60)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        stop = time.monotonic() - ts
        orphans = _reap(below, ORPHAN_GRACE)
        if sig == signal.SIGTERM and proc.returncode not in (0, 130, -signal.SIGTERM):
            err = proc.stderr.read().decode(errors="replace") if proc.stderr else ""
            why = f"SIGTERM: exit {proc.returncode}: {err.strip()[-300:]}"
        elif sig == signal.SIGTERM and proc.returncode != 0 and stop > STOP_WITHIN:
            why = f"SIGTERM took {stop:.2f} s"
    else:
        try:
            proc.wait(timeout=180)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        if proc.returncode != 0:
            err = proc.stderr.read().decode(errors="replace") if proc.stderr else ""
            why = f"a killed worker stopped the sweep: exit {proc.returncode}: {err[-300:]}"
    rc = proc.returncode
    recovered = "-" if why else "by itself"
    if not why and rc != 0:
        recovered = "rerun"
        done = subprocess.run(cmd, capture_output=True, text=True, env=_env())
        if done.returncode != 0:
            why = f"rerun exit {done.returncode}: {done.stderr.strip()[-300:]}{_failures(out)}"
    if not why:
        got = study_arrays(out)
        bad = [k for k, v in ref.arrays.items() if k not in got or not _equal(got[k], v)]
        extra = sorted(set(got) - set(ref.arrays))
        why = f"study.nc differs: {bad} {extra}" if bad or extra else ""
    if not why:
        have = files(out)
        if have != ref.files:
            why = f"files: extra {sorted(have - ref.files)}, missing {sorted(ref.files - have)}"
    return Trial(phase or kind, kind, sig.name, delay, rc, stop, orphans, recovered, not why, why)


def run_trials(
    n: int,
    seed: int,
    work: Path,
    say: bool = True,
    plan: list[tuple[str, str, signal.Signals]] | None = None,
) -> list[Trial]:
    """``n`` trials: the kind (client, worker, both), the signal and the phase drawn with
    equal chances, the instant uniform within the phase of the reference sweep; or, with
    ``plan``, one trial per ``(phase, kind, signal)`` (the instant still random)."""
    ref = reference(work)
    if say:
        print("phases (s): " + ", ".join(f"{a:.2f}-{b:.2f}" for a, b in ref.phases), flush=True)
    rng = random.Random(seed)
    random.seed(seed + 1)  # the choice of the victim among the workers
    if plan is None:
        plan = [
            (
                rng.choice(PHASES),
                rng.choice(["client", "worker", "both"]),
                rng.choice([signal.SIGKILL, signal.SIGTERM]),
            )
            for _ in range(n)
        ]
    trials = []
    for i, (phase, kind, sig) in enumerate(plan):
        delay = rng.uniform(*ref.phases[PHASES.index(phase)])
        t = trial(ref, work, kind, delay, sig, phase)
        trials.append(t)
        if say:
            mark = "ok" if t.ok else f"FAIL: {t.why}"
            print(
                f"{i + 1:4d} {t.phase:12s} {t.kind:6s} {t.sig:7s} at {t.delay:5.2f} s  exit "
                f"{t.rc!s:>4s}  orphans {t.orphans}  {t.recovered:9s}  {mark}",
                flush=True,
            )
    return trials


def table(trials: list[Trial]) -> str:
    """Instants x outcome: trials by phase, what was killed and how, with the failures."""
    lines = [
        "| killed in | client | worker | both | SIGKILL | SIGTERM | recovered | failures |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for ph in PHASES:
        sel = [t for t in trials if t.phase == ph]
        if not sel:
            continue
        kinds = Counter(t.kind for t in sel)
        k = sum(t.sig == "SIGKILL" for t in sel)
        rec = ", ".join(f"{r}: {n}" for r, n in Counter(t.recovered for t in sel).items())
        bad = sum(not t.ok for t in sel)
        lines.append(
            f"| {ph} | {kinds['client']} | {kinds['worker']} | {kinds['both']} | {k} | "
            f"{len(sel) - k} | {rec} | {bad} |"
        )
    ok = sum(t.ok for t in trials)
    lines += ["", f"{ok} passed, {len(trials) - ok} failed"]
    stops = [t.stop for t in trials if t.sig == "SIGTERM" and t.kind != "worker" and t.rc != 0]
    if stops:
        lines.append(f"SIGTERM to the client: stopped within {max(stops):.2f} s (max)")
    orphans = [t.orphans for t in trials if t.kind != "worker"]
    if orphans:
        lines.append(
            f"workers left by a killed client after {ORPHAN_GRACE:g} s: {sum(orphans)} in "
            f"{sum(o > 0 for o in orphans)} of {len(orphans)} trials"
        )
    return "\n".join(lines)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trials", type=int, default=40)
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="vemwear-crash-sweep-") as tmp:
        trials = run_trials(a.trials, a.seed, Path(tmp))
    print(table(trials))
    return 0 if all(t.ok for t in trials) else 1


if __name__ == "__main__":
    sys.exit(main())
