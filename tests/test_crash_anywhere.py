"""The crash-anywhere suite (benchmarks/crash_anywhere.py) at 20 random instants.

Real runs and exports killed with SIGKILL or SIGTERM at instants drawn over import,
set-up, the time loop with its checkpoints, and the final writes; each is resumed (or
run again) to arrays bitwise equal to an uninterrupted run, and ``vemwear clean``
leaves only the files of an uninterrupted run. The benchmark runs 200 and more.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

SUITE = Path(__file__).resolve().parents[1] / "benchmarks" / "crash_anywhere.py"


def test_twenty_random_kills_resume_bitwise_and_clean(tmp_path: Path) -> None:
    spec = importlib.util.spec_from_file_location("crash_anywhere", SUITE)
    assert spec is not None and spec.loader is not None
    suite = importlib.util.module_from_spec(spec)
    sys.modules["crash_anywhere"] = suite  # its dataclasses look their module up
    spec.loader.exec_module(suite)
    trials = suite.run_trials(20, seed=20, work=tmp_path, say=False)
    print("\n" + suite.table(trials))
    failed = [t for t in trials if not t.ok]
    assert not failed, [(t.phase, t.sig, round(t.delay, 2), t.why) for t in failed]
    assert {t.phase for t in trials} >= {"import", "set-up", "levels", "final writes"}
