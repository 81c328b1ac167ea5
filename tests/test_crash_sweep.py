"""The crash suite of studies (benchmarks/crash_sweep.py) at a few random instants.

``vemwear sweep`` on a real embedded Dask cluster (two worker processes), its client
process, a worker process or both killed with SIGKILL or SIGTERM at a random instant of
the runs or of the final writes; the sweep goes on by itself (a lost worker) or is
started again, and ends with a ``study.nc`` bitwise equal, variable by variable (read
with xarray), to that of an uninterrupted sweep, and with exactly its files. The
benchmark runs 40 and more trials over every phase.
"""

from __future__ import annotations

import importlib.util
import signal
import sys
from pathlib import Path

import pytest

pytest.importorskip("distributed")
pytest.importorskip("xarray")

SUITE = Path(__file__).resolve().parents[1] / "benchmarks" / "crash_sweep.py"


def test_killed_clients_and_workers_resume_to_the_same_study(tmp_path: Path) -> None:
    spec = importlib.util.spec_from_file_location("crash_sweep", SUITE)
    assert spec is not None and spec.loader is not None
    suite = importlib.util.module_from_spec(spec)
    sys.modules["crash_sweep"] = suite  # its dataclasses look their module up
    spec.loader.exec_module(suite)
    plan = [
        ("runs", "client", signal.SIGKILL),
        ("runs", "worker", signal.SIGKILL),
        ("runs", "both", signal.SIGTERM),
        ("final writes", "client", signal.SIGKILL),
    ]
    trials = suite.run_trials(len(plan), seed=7, work=tmp_path, say=False, plan=plan)
    print("\n" + suite.table(trials))
    failed = [t for t in trials if not t.ok]
    assert not failed, [(t.phase, t.kind, t.sig, round(t.delay, 2), t.why) for t in failed]
