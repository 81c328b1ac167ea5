"""The full-space Newton stops at the rounding floor of its residual, as the condensed one.

On Example 5.2's data with 64 x 32 squares the full-space iteration ran to 57 of its 100
iterations at level 0 (and to max_iter on finer meshes): its step ``du`` never fell
below 1e-14 of ``u``, while the residual had been at its floor for dozens of steps.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np

from conftest import small_config


def _run(tmp_path: Path, method: str) -> dict[str, np.ndarray]:
    cfg = tmp_path / f"{method}.toml"
    cfg.write_text(small_config(method, divisions=(64, 32), steps=5, solver={"method": method}))
    out = tmp_path / method
    cmd = [sys.executable, "-m", "vemwear", "run", str(cfg), "-o", str(out), "--no-progress"]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    with np.load(out / "result.npz") as z:
        return {k: z[k] for k in ("iterations", "wear", "residuals")}


def test_full_newton_stops_at_the_rounding_floor(tmp_path: Path) -> None:
    full, condensed = _run(tmp_path, "newton-full"), _run(tmp_path, "newton")
    assert full["iterations"].max() <= 10, full["iterations"]
    assert full["residuals"].max() <= 1e-10
    np.testing.assert_allclose(full["wear"], condensed["wear"], rtol=0, atol=1e-13)
