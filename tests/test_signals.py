"""Stop signals in real processes: never lost in a finalizer, a stop within 2 s.

A signal handler that raises inside a finalizer (``weakref.finalize``, as PARDISO's
handles use) has its exception printed and swallowed by Python, and the run goes on.
These tests send real signals to real processes at instants where that happened.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from conftest import small_config

SRC = str(Path(__file__).resolve().parents[1] / "src")

FINALIZER = textwrap.dedent(
    """
    import os, signal, sys, time, weakref
    from vemwear.runner.signals import signals_as_interrupts

    class Handle:
        pass

    def release():
        os.kill(os.getpid(), signal.SIG{sig})  # the signal lands inside the finalizer
        t = time.monotonic()
        while time.monotonic() - t < 0.3:  # Python code runs there: the handler too
            pass

    t0 = time.monotonic()
    try:
        with signals_as_interrupts():
            h = Handle()
            weakref.finalize(h, release)
            del h
            while time.monotonic() - t0 < 20:  # the run goes on after the finalizer
                sum(range(1000))
        print("not stopped")
    except KeyboardInterrupt as exc:
        print(f"stopped by {{type(exc).__name__}} after {{time.monotonic() - t0:.3f}} s")
    """
)


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = SRC + os.pathsep + env.get("PYTHONPATH", "")
    return env


@pytest.mark.parametrize("sig", ["TERM", "INT", "HUP"])
def test_a_signal_inside_a_finalizer_stops_the_process(tmp_path: Path, sig: str) -> None:
    script = tmp_path / "finalizer.py"
    script.write_text(FINALIZER.format(sig=sig))
    done = subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, timeout=60, env=_env()
    )
    assert "Exception ignored" not in done.stderr, done.stderr
    assert done.stdout.startswith("stopped by "), done.stdout + done.stderr
    name = "KeyboardInterrupt" if sig == "INT" else "Terminated"
    assert f"stopped by {name} after" in done.stdout
    assert float(done.stdout.split()[-2]) < 2.0  # just after the finalizer's 0.3 s


def test_sigterm_stops_newton_full_within_two_seconds(tmp_path: Path) -> None:
    """SIGTERM at instants spread over import, set-up and the levels of the full-space
    Newton with PARDISO-like finalized handles: exit 130 (or the default action before
    the handlers exist) within 2 s, never a run that goes on."""
    cfg = tmp_path / "long.toml"
    cfg.write_text(
        small_config(
            "long",
            divisions=(32, 16),
            steps=4000,
            solver={"method": "newton-full"},
            output={"checkpoint": 0.3},
        )
    )
    for i, delay in enumerate((0.05, 0.4, 0.9, 1.5, 2.2, 3.0)):
        out = tmp_path / f"out{i}"
        cmd = [sys.executable, "-m", "vemwear", "run", str(cfg), "-o", str(out), "--no-progress"]
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=_env())
        time.sleep(delay)
        t_sig = time.monotonic()
        proc.send_signal(signal.SIGTERM)
        try:
            _, err = proc.communicate(timeout=20)
        finally:
            proc.kill()
        took = time.monotonic() - t_sig
        assert proc.returncode in (130, -signal.SIGTERM), err
        assert b"Exception ignored" not in err, err
        assert took < 2.0, (delay, took, err)


IN_ZIP_CLOSE = textwrap.dedent(
    """
    import os, signal, sys, zipfile
    from vemwear.cli.main import main

    close = zipfile._ZipWriteFile.close
    sent = []

    def close_with_signal(self):  # the signal lands as a member of result.npz is closed
        name = os.path.basename(str(self._zipfile.filename))
        if not sent and not self.closed and name.startswith(".result"):
            sent.append(1)
            os.kill(os.getpid(), signal.SIGTERM)
        return close(self)

    zipfile._ZipWriteFile.close = close_with_signal
    sys.exit(main(sys.argv[1:]))
    """
)


def _stopped_in_the_final_writes(tmp_path: Path, script: str, figures: bool) -> Path:
    """Run a small case through ``script`` (the CLI with a library patched to meet a
    SIGTERM in the final writes) and check the stop: exit 130, every level saved,
    ``PARTIAL.txt`` naming the signal. Returns OUTDIR as the stop left it."""
    cfg = tmp_path / "small.toml"
    cfg.write_text(small_config("small", steps=4, output={"figures": figures}))
    out = tmp_path / "out"
    path = tmp_path / "patched.py"
    path.write_text(script)
    done = subprocess.run(
        [sys.executable, str(path), "run", str(cfg), "-o", str(out), "--no-progress"],
        capture_output=True,
        text=True,
        env=_env(),
    )
    assert done.returncode == 130, done.stderr
    assert "interrupted; every time level is solved and saved" in done.stderr, done.stderr
    assert "terminated (SIGTERM)" in (out / "PARTIAL.txt").read_text()
    return out


def _resume(out: Path) -> None:
    """``--resume`` of the stopped run of :func:`_stopped_in_the_final_writes` completes."""
    cfg = out.parent / "small.toml"
    cmd = [sys.executable, "-m", "vemwear", "run", str(cfg), "-o", str(out), "--no-progress"]
    again = subprocess.run(
        [*cmd, "--resume"],
        capture_output=True,
        text=True,
        env=_env(),
    )
    assert again.returncode == 0, again.stderr
    assert (out / "result.npz").is_file() and not (out / "PARTIAL.txt").exists()


def test_sigterm_while_a_zip_member_is_closed_is_a_stop_then_resume(tmp_path: Path) -> None:
    """A signal raised inside ``zipfile``'s member close makes ``numpy.savez`` fail with
    a ValueError (the zip closed with a handle open) whose context is the signal: the
    run is stopped (exit 130, its levels saved), not an internal error, and resumes."""
    _resume(_stopped_in_the_final_writes(tmp_path, IN_ZIP_CLOSE, figures=False))


IN_SAVEFIG = textwrap.dedent(
    """
    import os, signal, sys, time
    import matplotlib.figure
    from vemwear.cli.main import main

    savefig = matplotlib.figure.Figure.savefig
    sent = []

    def savefig_with_signal(self, *args, **kwargs):
        # the signal lands in compiled code that replaces it by its own error, with no
        # chain (matplotlib's C++ path code: "Invalid bounding box")
        if not sent:
            sent.append(1)
            lost = False
            try:
                os.kill(os.getpid(), signal.SIGTERM)
                time.sleep(5)
            except KeyboardInterrupt:
                lost = True
            if lost:
                raise ValueError("Invalid bounding box")
        return savefig(self, *args, **kwargs)

    matplotlib.figure.Figure.savefig = savefig_with_signal
    sys.exit(main(sys.argv[1:]))
    """
)


def test_sigterm_replaced_by_a_libraries_own_error_is_a_stop_then_resume(
    tmp_path: Path,
) -> None:
    """A signal that a compiled library turns into its own exception, with no chain to the
    signal, during the final writes: still a stop (exit 130, every level saved), not an
    internal error; --resume writes the outputs."""
    _resume(_stopped_in_the_final_writes(tmp_path, IN_SAVEFIG, figures=True))


IN_SAVEFIG_SWALLOWED = textwrap.dedent(
    """
    import os, signal, sys, time
    import matplotlib.figure
    from vemwear.cli.main import main

    savefig = matplotlib.figure.Figure.savefig
    sent = []

    def savefig_swallowing(self, *args, **kwargs):
        # a library that catches the signal's exception and goes on
        if not sent:
            sent.append(1)
            try:
                os.kill(os.getpid(), signal.SIGTERM)
                time.sleep(5)
            except KeyboardInterrupt:
                pass
        return savefig(self, *args, **kwargs)

    matplotlib.figure.Figure.savefig = savefig_swallowing
    sys.exit(main(sys.argv[1:]))
    """
)


def test_sigterm_swallowed_by_a_library_stops_at_the_next_file(tmp_path: Path) -> None:
    """A library that catches the signal's exception and goes on (here in the first
    figure): the run still stops at the next safe point, between two output files, with
    exit 130; the files after it are not written; --resume writes them."""
    out = _stopped_in_the_final_writes(tmp_path, IN_SAVEFIG_SWALLOWED, figures=True)
    assert not (out / "forces.png").exists()  # stopped before the last figure
    _resume(out)
    assert (out / "forces.png").is_file()
