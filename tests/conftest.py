"""Shared test helpers: the small TOML configuration with the paper's data.

Test modules import :func:`small_config` directly (``from conftest import
small_config``); pytest puts this directory on ``sys.path``.
"""

from __future__ import annotations

import importlib
import json
import subprocess
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from vemwear.solvers.system import ConvergenceError

# the module, not a name the package may export under the same name
levels_mod = importlib.import_module("vemwear.simulate.levels")

# The data of Example 5.2 on a coarse mesh of squares. A key set to None is
# optional: left out unless a test sets it, so that every key keeps its place
# in the text (tests edit the text with str.replace).
_PAPER: dict[str, dict[str, Any]] = {
    "mesh": {"generator": "squares", "size": [2.0, 1.0], "origin": None, "divisions": None},
    "boundary": {"clamped": "left", "traction": "rest", "contact": "bottom"},
    "material": {"lam": 4.0, "eta": 4.0},
    "vem": {"stabilization": None},
    "loads": {"f1": [0.0, -0.06], "f2": None},
    "contact": {
        "p": {"type": "linear", "c": 0.4},
        "g": 0.1,
        "mu": 0.2,
        "kappa": 2.0,
        "v_star": [1.0, 0.0],
    },
    "time": {"T": 1.0, "steps": None},
    "solver": {"method": "newton", "tol": None, "max_iter": None, "backend": "scipy"},
    "output": {"times": None, "figures": False, "vtk": False},
}


def _toml(value: Any) -> str:
    """A TOML value (the few types the configurations use)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, int | float):
        return repr(value)
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    if isinstance(value, Mapping):
        return "{ " + ", ".join(f"{k} = {_toml(v)}" for k, v in value.items()) + " }"
    raise TypeError(f"no TOML form for {value!r}")


def small_config(
    title: str,
    divisions: Sequence[int] = (8, 4),
    steps: int = 8,
    **sections: Mapping[str, Any],
) -> str:
    """TOML text of the paper's data on ``divisions`` squares with ``steps`` time steps.

    ``section={key: value, ...}`` sets keys of a section (``None`` leaves a key
    out); sections without keys are left out. Solver: newton with SciPy; output:
    no figures, no VTK files.
    """
    unknown = set(sections) - set(_PAPER)
    if unknown:
        raise ValueError(f"unknown sections {sorted(unknown)}")
    lines = [f"title = {_toml(title)}"]
    for name, defaults in _PAPER.items():
        keys = dict(defaults)
        if name == "mesh":
            keys["divisions"] = list(divisions)
        elif name == "time":
            keys["steps"] = steps
        keys.update(sections.get(name, {}))
        body = [f"{k} = {_toml(v)}" for k, v in keys.items() if v is not None]
        if body:
            lines += [f"[{name}]", *body]
    return "\n".join(lines) + "\n"


@pytest.fixture
def stop_at(monkeypatch: pytest.MonkeyPatch) -> Iterator[Callable[..., None]]:
    """``stop_at(level)`` makes the next runs stop with a solver failure (exit 3) at
    time level ``level``, as a run that did not converge there; ``stop_at(None)`` undoes
    it. In-process, for tests of ``--resume``."""
    real = levels_mod.run_levels

    def install(level: int | None) -> None:
        if level is None:
            monkeypatch.setattr(levels_mod, "run_levels", real)
            return

        def patched(*args: object, **kwargs: object) -> object:
            def cb(n: int, _sol: object) -> None:
                if n == level:
                    raise ConvergenceError(f"stopped at time level {level} (test)")

            kwargs["callback"] = cb
            return real(*args, **kwargs)  # type: ignore[arg-type]

        monkeypatch.setattr(levels_mod, "run_levels", patched)

    yield install


def npz_arrays(out: Path) -> dict[str, np.ndarray]:
    """Every array of ``out/result.npz``."""
    with np.load(out / "result.npz", allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


#: A small 3D configuration: the 3D analogue of the paper's data on 4 x 2 x 2
#: hexahedra, 8 steps; ``[output]`` last, so that tests can append keys to it.
CONFIG_3D = """
title = "3d small"
[mesh]
generator = "hexahedra"
size = [2.0, 1.0, 1.0]
divisions = [4, 2, 2]
[boundary]
clamped = "xmin"
contact = "zmin"
free = "rest"
[material]
lam = 4.0
eta = 4.0
[loads]
f1 = [0.0, 0.0, -0.06]
[contact]
p = { type = "linear", c = 0.4 }
g = 0.1
mu = 0.2
kappa = 2.0
v_star = [1.0, 0.0, 0.0]
[time]
T = 1.0
steps = 8
[solver]
backend = "scipy"
[output]
"""


def moments(X):
    """Integrals of 1, x, y, x^2, xy, y^2 over a simple polygon by Green's formula."""
    x, y = X[:, 0], X[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    c = x * yn - xn * y
    return np.array(
        [
            c.sum() / 2,
            np.sum(c * (x + xn)) / 6,
            np.sum(c * (y + yn)) / 6,
            np.sum(c * (x * x + x * xn + xn * xn)) / 12,
            np.sum(c * (x * yn + 2 * x * y + 2 * xn * yn + xn * y)) / 24,
            np.sum(c * (y * y + y * yn + yn * yn)) / 12,
        ]
    )


# ----------------------------------------------------------------------------- polygons
def is_convex(X):
    """Whether the counter-clockwise polygon X turns left at every vertex."""
    d = np.roll(X, -1, axis=0) - X
    e = np.roll(d, -1, axis=0)
    return np.all(d[:, 0] * e[:, 1] - d[:, 1] * e[:, 0] > 0)


def angles(rng, n):
    """Sorted angles in [0, 2 pi) with no gap smaller than a third of the mean gap."""
    while True:
        th = np.sort(rng.uniform(0, 2 * np.pi, n))
        gaps = np.diff(np.r_[th, th[0] + 2 * np.pi])
        if gaps.min() > (2 * np.pi / n) / 3 and gaps.max() < 0.9 * np.pi:
            return th


def place(rng, P):
    """Random rotation, scale over three decades and translation."""
    a = rng.uniform(0, 2 * np.pi)
    R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    return P @ R.T * 10 ** rng.uniform(-2, 1) + rng.uniform(-5, 5, 2)


def polygon(rng, n, kind):
    """A random convex (on an ellipse) or star-shaped non-convex polygon of n vertices,
    counter-clockwise, placed at random."""
    while True:
        th = angles(rng, n)
        if kind == "convex":
            ab = rng.uniform(0.4, 1.0, 2)
            return place(rng, np.column_stack([ab[0] * np.cos(th), ab[1] * np.sin(th)]))
        r = rng.uniform(0.35, 1.0, n)
        X = np.column_stack([r * np.cos(th), r * np.sin(th)])
        if not is_convex(X):
            return place(rng, X)


def segments_done(out: Path) -> int:
    """The mesh changes an adaptive run into ``out`` has checkpointed (0 before any)."""
    try:
        with np.load(out / "checkpoint.npz") as z:
            return int(json.loads(str(z["meta"]))["segment"])
    except (OSError, ValueError, KeyError):
        return 0


def run_until_segments(cmd: Sequence[str], out: Path, n: int) -> subprocess.Popen:
    """Start ``cmd`` (an adaptive ``vemwear run`` into ``out``) and return it, still
    running, once it has checkpointed ``n`` mesh changes (at most 60 s)."""
    proc = subprocess.Popen(list(cmd), stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    t0 = time.monotonic()
    while segments_done(out) < n:
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() - t0 < 60, "no checkpoint"
        time.sleep(0.01)
    return proc
