"""Crash anywhere: real runs killed at random instants, then resumed to the same bits.

In the spirit of SQLite's crash tests. Each trial starts ``vemwear run`` (or ``vemwear
export``) as a child process and, after a random delay spread over the whole command
(import, set-up, the time loop and its checkpoint writes, the final writes of
``result.npz``, ``summary.json``, figures and the ParaView series), sends it SIGKILL or
SIGTERM. Then it checks:

* SIGTERM stops the command within 2 s (exit 130, or the default action before the
  handlers are installed);
* ``vemwear run --resume`` (a plain ``vemwear run`` when nothing is left, or
  ``vemwear export --force``) completes with exit 0 and a ``result.npz`` whose every
  array is bitwise the one of an uninterrupted run;
* ``vemwear clean OUTDIR`` then leaves exactly the files of an uninterrupted run, and
  nothing beside OUTDIR.

What the kill left is classified from the directory (``state``): ``none`` (killed before
the output directory was made), ``set-up`` (the lock, perhaps the marker and a stream
with no checkpoint), ``levels`` (a checkpoint of a running or stopped run),
``final writes`` (every level checkpointed; outputs being written), ``complete`` (the
command had finished), ``export`` (an export killed). The table counts trials by state
and signal, with the failures.

Usage::

    python benchmarks/crash_anywhere.py                 # 200 instants
    python benchmarks/crash_anywhere.py --trials 40 --seed 3
"""

from __future__ import annotations

import argparse
import json
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

CONFIG = """\
title = "crash"
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
v_star = [1.0, 0.0]
[time]
T = 1.0
steps = 1500
[solver]
method = "newton"
[output]
store_u = 150
checkpoint = 0.05
figures = true
vtk = true
"""

#: Seconds a SIGTERM may take to stop the command.
STOP_WITHIN = 2.0


def _cmd(*args: str) -> list[str]:
    return [sys.executable, "-m", "vemwear", *args]


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["MPLBACKEND"] = "Agg"
    return env


def _arrays(out: Path) -> dict[str, np.ndarray]:
    with np.load(out / "result.npz", allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


@dataclass
class Reference:
    config: Path
    arrays: dict[str, np.ndarray]
    names: set[str]
    phases: list[tuple[float, float]]  # (start, end) seconds of each phase of a run
    export_seconds: float
    done: Path


def _watch(cmd: list[str], out: Path) -> list[tuple[float, float]]:
    """Run ``cmd`` to its end, noting when OUTDIR appears, the first checkpoint, the
    checkpoint of every level and the exit: the phases import, set-up, levels, final
    writes."""
    marks: dict[str, float] = {}
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=_env())
    t0 = time.monotonic()
    while proc.poll() is None:
        now = time.monotonic() - t0
        if "dir" not in marks and out.exists():
            marks["dir"] = now
        if "ckpt" not in marks and (out / "checkpoint.npz").exists():
            marks["ckpt"] = now
        if "ckpt" in marks and "final" not in marks and _state(out, None) == "final writes":
            marks["final"] = now
        time.sleep(0.005)
    end = time.monotonic() - t0
    if proc.returncode != 0:
        raise SystemExit(f"the reference run failed: {proc.stderr.read() if proc.stderr else ''}")
    a = marks.get("dir", 0.0)
    b = marks.get("ckpt", a)
    c = marks.get("final", b)
    return [(0.0, a), (a, b), (b, c), (c, end * 1.05)]


def reference(work: Path) -> Reference:
    """An uninterrupted run: its arrays, its files, its phases (and export's time)."""
    config = work / "crash.toml"
    config.write_text(CONFIG)
    out = work / "reference"
    phases = _watch(_cmd("run", str(config), "-o", str(out), "--no-progress"), out)
    exp = work / "export-reference"
    shutil.copytree(out, exp)
    (exp / "result.npz").unlink()
    t0 = time.monotonic()
    subprocess.run(_cmd("export", str(exp)), check=True, capture_output=True, env=_env())
    export_seconds = time.monotonic() - t0
    return Reference(
        config, _arrays(out), {p.name for p in out.iterdir()}, phases, export_seconds, out
    )


def _state(out: Path, rc: int | None) -> str:
    if not out.exists() or not any(out.iterdir()):
        return "none"
    try:
        marker = json.loads((out / ".vemwear").read_text())
    except (OSError, ValueError):
        marker = {}
    if marker.get("state") == "complete" and rc == 0:
        return "complete"
    if marker.get("state") == "complete":
        return "final writes"
    if (out / "checkpoint.npz").exists():
        try:
            with np.load(out / "checkpoint.npz") as z:
                done = int(z["completed"])
            levels = int(CONFIG.split("steps = ")[1].split()[0]) + 1
        except (OSError, ValueError, KeyError):
            return "levels"
        return "final writes" if done == levels else "levels"
    return "set-up"


PHASES = ("import", "set-up", "levels", "final writes")


@dataclass
class Trial:
    phase: str  # the phase of the reference run at the instant of the kill, or "export"
    kind: str  # "run" or "export"
    sig: str
    delay: float
    state: str
    rc: int | None
    stop: float
    ok: bool
    why: str


def _kill(cmd: list[str], delay: float, sig: signal.Signals) -> tuple[int | None, float, str]:
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=_env())
    time.sleep(delay)
    t0 = time.monotonic()
    if proc.poll() is None:
        proc.send_signal(sig)
    err = b""
    try:
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    lines = err.decode(errors="replace").strip().splitlines() if err else []
    fatal = [i for i, line in enumerate(lines) if line.startswith("Fatal Python error")]
    if fatal:  # the interpreter's own account, and the Python frames it printed
        return proc.returncode, time.monotonic() - t0, " | ".join(lines[fatal[0] :][:12])
    return proc.returncode, time.monotonic() - t0, lines[-1] if lines else ""


def _no_stray(out: Path, names: set[str]) -> str:
    have = {p.name for p in out.iterdir()}
    if have != names:
        return f"after clean: extra {sorted(have - names)}, missing {sorted(names - have)}"
    beside = [p.name for p in out.parent.iterdir() if p.name.startswith(f".{out.name}.tmp-")]
    return f"beside OUTDIR: {beside}" if beside else ""


def trial(
    ref: Reference, work: Path, kind: str, delay: float, sig: signal.Signals, phase: str = ""
) -> Trial:
    """One kill and its recovery (module docstring)."""
    out = work / "out"
    if out.exists():
        shutil.rmtree(out)
    if kind == "export":
        shutil.copytree(ref.done, out)
        (out / "result.npz").unlink()
        cmd = _cmd("export", str(out))
    else:
        cmd = _cmd("run", str(ref.config), "-o", str(out), "--no-progress")
    rc, stop, said = _kill(cmd, delay, sig)
    state = "export" if kind == "export" else _state(out, rc)
    why = ""
    if sig == signal.SIGTERM and rc not in (0, 130, -signal.SIGTERM):
        why = f"SIGTERM: exit {rc}: {said[-1200:]}"
    elif sig == signal.SIGTERM and rc != 0 and stop > STOP_WITHIN:
        why = f"SIGTERM took {stop:.2f} s"  # (a command that completed is not stopped)
    if not why:
        if kind == "export":
            again = _cmd("export", str(out), "--force")
        elif out.exists() and any(out.iterdir()):
            again = _cmd("run", str(ref.config), "-o", str(out), "--no-progress", "--resume")
        else:
            again = _cmd("run", str(ref.config), "-o", str(out), "--no-progress")
        done = subprocess.run(again, capture_output=True, text=True, env=_env())
        if done.returncode != 0:
            why = f"recovery exit {done.returncode}: {done.stderr.strip()[-300:]}"
    if not why:
        got = _arrays(out)
        bad = [k for k, v in ref.arrays.items() if k not in got or not np.array_equal(got[k], v)]
        why = f"arrays differ: {bad}" if bad or got.keys() != ref.arrays.keys() else ""
    if not why:
        cleaned = subprocess.run(_cmd("clean", str(out)), capture_output=True, text=True)
        why = f"clean exit {cleaned.returncode}" if cleaned.returncode else ""
        why = why or _no_stray(out, ref.names)
    return Trial(phase or kind, kind, sig.name, delay, state, rc, stop, not why, why)


def run_trials(n: int, seed: int, work: Path, say: bool = True) -> list[Trial]:
    """``n`` trials at random instants (one in eight of them an export), each run's
    instant uniform within a phase (import, set-up, levels, final writes) drawn with
    equal chances, so that short phases are hit as often as long ones."""
    ref = reference(work)
    if say:
        print("phases (s): " + ", ".join(f"{a:.2f}-{b:.2f}" for a, b in ref.phases))
    rng = random.Random(seed)
    trials = []
    for i in range(n):
        kind = "export" if rng.random() < 0.125 else "run"
        if kind == "export":
            phase, delay = "export", rng.uniform(0.0, 1.05 * ref.export_seconds)
        else:
            j = rng.randrange(len(ref.phases))
            phase, delay = PHASES[j], rng.uniform(*ref.phases[j])
        sig = rng.choice([signal.SIGKILL, signal.SIGTERM])
        t = trial(ref, work, kind, delay, sig, phase)
        trials.append(t)
        if say:
            mark = "ok" if t.ok else f"FAIL: {t.why}"
            print(
                f"{i + 1:4d} {t.phase:12s} {t.sig:7s} at {t.delay:5.2f} s  left {t.state:12s} "
                f"exit {t.rc!s:>4s}  {mark}",
                flush=True,
            )
    return trials


def table(trials: list[Trial]) -> str:
    """Instants x outcome: trials by the phase of the kill and the signal, with what the
    kills left and the failures."""
    lines = [
        "| killed in | SIGKILL | SIGTERM | left (state: trials) | failures |",
        "|---|---|---|---|---|",
    ]
    for ph in (*PHASES, "export"):
        sel = [t for t in trials if t.phase == ph]
        if not sel:
            continue
        k = sum(t.sig == "SIGKILL" for t in sel)
        left = ", ".join(f"{s}: {n}" for s, n in Counter(t.state for t in sel).items())
        bad = sum(not t.ok for t in sel)
        lines.append(f"| {ph} | {k} | {len(sel) - k} | {left} | {bad} |")
    stops = [t.stop for t in trials if t.sig == "SIGTERM" and t.rc != 0]
    late = [t.stop for t in trials if t.sig == "SIGTERM" and t.rc == 0]
    ok = sum(t.ok for t in trials)
    lines.append("")
    lines.append(f"{ok} passed, {len(trials) - ok} failed")
    if stops:
        lines.append(
            f"SIGTERM stop time: max {max(stops):.2f} s, median {float(np.median(stops)):.2f} s"
        )
    if late:
        lines.append(
            f"SIGTERM to a command that then completed (exit 0): exit after at most "
            f"{max(late):.2f} s"
        )
    return "\n".join(lines)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trials", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="vemwear-crash-") as tmp:
        trials = run_trials(a.trials, a.seed, Path(tmp))
    print(table(trials))
    return 0 if all(t.ok for t in trials) else 1


if __name__ == "__main__":
    sys.exit(main())
