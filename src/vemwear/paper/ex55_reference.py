"""Example 5.5's sizes and problems, and its reference solution, cached by its inputs' hash.

The problems: Example 5.2's data with mu = 0.2, kappa = 2 (not stated in the paper for
5.5; Example 5.3's data set) on (2/h) x (1/h) squares with k = h, T = 1. The reference
h = k = 1/256 is computed once and cached: the cache holds
``ex55_reference_h{n}_{hash}.npz`` (the reference as a
:class:`vemwear.post.compare.Solution`) and a ``.json`` with its inputs and their hash
(:func:`cache_key`). A cached reference is reused whenever its inputs did not change
and it holds the displacement at every time asked for.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable, Sequence
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from ..post.compare import Solution
from ..simulate import Problem, SolverOptions, simulate
from ..util.atomic import atomic_file, write_atomic
from ..util.hashing import sha256_json
from . import ex52

__all__ = [
    "CACHE_FORMAT",
    "KAPPA",
    "LEVELS",
    "MU",
    "NAME",
    "QUICK_REFERENCE",
    "REFERENCE",
    "TITLE",
    "cache_key",
    "cached_solution",
    "check_sizes",
    "common_times",
    "default_cache_dir",
    "problem",
    "problems",
    "reference_solution",
]

NAME = "5.5"
TITLE = f"Example {NAME}"
CACHE_FORMAT = "vemwear-ex55-reference/1"


# not stated for 5.5 in the paper: Example 5.3's data (Example 5.2's data set 1)
MU, KAPPA = ex52.DATA_SETS["set1"]["mu"], ex52.DATA_SETS["set1"]["kappa"]
LEVELS: tuple[int, ...] = (4, 8, 16, 32, 64)  # 1/h = 1/k
REFERENCE: int = 256
#: The reference and levels of ``vemwear paper --quick``.
QUICK_REFERENCE: int = 64
T = ex52.T


def check_sizes(levels: Sequence[int], reference: int) -> tuple[tuple[int, ...], int]:
    """Validate the mesh levels and the reference size (all as ``1/h``).

    Parameters
    ----------
    levels : sequence of int
        ``1/h`` of the coarse levels.
    reference : int
        ``1/h`` of the reference.

    Returns
    -------
    (levels sorted increasing, reference)

    Raises
    ------
    ValueError
        If a level is not a positive integer, levels repeat, the reference is not
        finer than every level, or a level does not divide the reference (the meshes
        and time grids must be nested).
    """
    lv = [int(n) for n in levels]
    if not lv or any(n < 1 or n != float(m) for n, m in zip(lv, levels, strict=True)):
        raise ValueError(f"{TITLE}: levels must be positive integers (1/h), got {list(levels)}")
    if len(set(lv)) != len(lv):
        raise ValueError(f"{TITLE}: levels repeat: {lv}")
    ref = int(reference)
    if ref != reference or ref < 2:
        raise ValueError(f"{TITLE}: the reference 1/h must be an integer >= 2, got {reference}")
    bad = [n for n in lv if n >= ref or ref % n]
    if bad:
        raise ValueError(
            f"{TITLE}: every level must divide the reference 1/h = {ref} and be "
            f"smaller (nested meshes and time grids); offending: {bad}"
        )
    return tuple(sorted(lv)), ref


def problem(n: int, steps: int | None = None) -> Problem:
    """The problem with h = 1/n ((2n) x n squares) and ``steps`` uniform steps on [0, 1].

    Parameters
    ----------
    n : int
        ``1/h``.
    steps : int, optional
        Uniform time steps (default ``n``: k = h, the paper's choice).
    """
    return ex52.problem(MU, KAPPA, divisions=(2 * n, n), steps=n if steps is None else steps)


def problems(*, levels: Sequence[int] = LEVELS) -> dict[str, Problem]:
    """The coarse problems by name (``h4``, ``h8``, ...).

    Parameters
    ----------
    levels : sequence of int
        ``1/h = 1/k`` of each (paper: 4, 8, 16, 32, 64).
    """
    return {f"h{n}": problem(n) for n in levels}


def common_times(levels: Sequence[int], T_: float = T) -> list[float]:
    """The union of the time levels ``j T / n`` of every level ``n`` (exact fractions).

    Parameters
    ----------
    levels : sequence of int
        ``1/k`` of each uniform grid on [0, T].
    T_ : float
        The final time.
    """
    s = {Fraction(j, n) for n in levels for j in range(n + 1)}
    return [float(f) * T_ for f in sorted(s)]


def reference_solution(
    reference: int,
    times: Sequence[float],
    *,
    solver: SolverOptions | str = "newton",
    cache_dir: str | os.PathLike[str] | None = None,
    progress: bool = False,
    log: Callable[[str], None] | None = None,
) -> tuple[Solution, dict[str, Any]]:
    """The reference solution h = k = 1/reference, from the cache or computed (and cached).

    Parameters
    ----------
    reference : int
        ``1/h = 1/k`` of the reference.
    times : sequence of float
        Times at which its displacement is needed (levels of its grid).
    solver : SolverOptions or str
        The step solver.
    cache_dir : path, optional
        Where ``ex55_reference_h{n}_{hash}.npz`` / ``.json`` live; ``None``: no cache.
    progress : bool
        Progress bar of the time loop.
    log : callable, optional
        Receives one line of text.

    Returns
    -------
    (Solution, dict)
        As :func:`vemwear.paper.ex55_reference.cached_solution`.
    """
    opts = SolverOptions(method=solver) if isinstance(solver, str) else solver
    return cached_solution(
        problem(reference),
        reference,
        times,
        solver=opts,
        cache_dir=cache_dir,
        progress=progress,
        log=log,
        label=f"{TITLE}: reference h = k = 1/{reference}",
    )


# ----------------------------------------------------------------------------- cache
def default_cache_dir(outdir: str | os.PathLike[str] | None = None) -> Path:
    """The user's cache directory of vemwear (:func:`vemwear.util.cache.user_cache_dir`),
    never a place beside the output directory.

    Parameters
    ----------
    outdir : path, optional
        The output directory (not used: the cache does not depend on it).
    """
    from ..util.cache import user_cache_dir

    return user_cache_dir()


def _solver_desc(opts: SolverOptions) -> dict[str, Any]:
    return {"method": opts.method, "tol": opts.tol, "max_iter": opts.max_iter}


def cache_key(reference: Problem, n: int, solver: SolverOptions) -> tuple[str, dict[str, Any]]:
    """The hash (hex SHA-256) and the JSON inputs identifying a reference run.

    The inputs are the format tag, ``1/h``, the problem's fingerprint
    (:meth:`vemwear.simulate.Problem.fingerprint`: its data, mesh, time grid and the
    vemwear version) and the solver method, tolerance and iteration limit (not the
    linear algebra backend: it does not change the solution beyond the tolerance),
    hashed by :func:`vemwear.util.hashing.sha256_json`, the one fingerprint scheme.

    Parameters
    ----------
    reference : Problem
        The reference problem, ``problem(n)``.
    n : int
        Its ``1/h``.
    solver : SolverOptions
        The step solver.
    """
    inputs = {
        "format": CACHE_FORMAT,
        "reference": int(n),
        "problem": reference.fingerprint(),
        "solver": _solver_desc(solver),
    }
    return sha256_json(inputs), inputs


def _load_cached(npz: Path, meta: Path, key: str, times: Sequence[float]) -> Solution | None:
    if not (npz.exists() and meta.exists()):
        return None
    try:
        info = json.loads(meta.read_text(encoding="utf-8"))
        if info.get("hash") != key:
            return None
        with np.load(npz, allow_pickle=False) as data:
            sol = Solution.from_arrays({k: data[k] for k in data.files})
    except (OSError, ValueError, KeyError):
        return None
    stored = sol.t[sol.u_levels]
    if not all(np.any(np.isclose(stored, t, rtol=0, atol=1e-9)) for t in times):
        return None
    return sol


def cached_solution(
    pr: Problem,
    reference: int,
    times: Sequence[float],
    *,
    solver: SolverOptions,
    cache_dir: str | os.PathLike[str] | None = None,
    progress: bool = False,
    log: Callable[[str], None] | None = None,
    label: str = "reference",
) -> tuple[Solution, dict[str, Any]]:
    """The solution of ``pr``, from the cache or computed (and cached).

    Parameters
    ----------
    pr : Problem
        The reference problem.
    reference : int
        Its ``1/h`` (part of the file names and of the hashed inputs).
    times : sequence of float
        Times at which its displacement is needed (levels of its grid).
    solver : SolverOptions
        The step solver.
    cache_dir : path, optional
        Where ``ex55_reference_h{n}_{hash}.npz`` / ``.json`` live; ``None``: no cache.
    progress : bool
        Progress bar of the time loop.
    log : callable, optional
        Receives one line of text.
    label : str
        How the log lines name the run.

    Returns
    -------
    (Solution, dict)
        The reference, and ``{"cached": bool, "elapsed": s of the run (or of the
        original run when cached), "hash", "npz", "unknowns", "timings"}``.
    """
    opts = solver
    key, inputs = cache_key(pr, reference, opts)
    npz = meta = None
    if cache_dir is not None:
        cdir = Path(cache_dir)
        stem = f"ex55_reference_h{reference}_{key[:16]}"
        npz, meta = cdir / f"{stem}.npz", cdir / f"{stem}.json"
        sol = _load_cached(npz, meta, key, times)
        if sol is not None:
            info = json.loads(meta.read_text(encoding="utf-8"))
            if log is not None:
                log(f"{label} from the cache {npz}")
            return sol, {
                "cached": True,
                "elapsed": info.get("elapsed"),
                "hash": key,
                "npz": str(npz),
                "unknowns": info.get("unknowns"),
                "timings": info.get("timings", {}),
            }
    if log is not None:
        log(
            f"{label} ({2 * pr.mesh.n_points} unknowns, "
            f"{pr.time.n_steps} steps), storing u at {len(times)} levels"
        )
    t0 = time.perf_counter()
    res = simulate(pr, opts, progress=progress, store=list(times))
    elapsed = time.perf_counter() - t0
    sol = Solution.from_result(res)
    extra = {
        "cached": False,
        "elapsed": elapsed,
        "hash": key,
        "unknowns": 2 * pr.mesh.n_points,
        "timings": dict(res.timings),
        "max_iterations": int(res.iterations.max()),
        "max_residual": float(res.residuals.max()),
    }
    if npz is not None and meta is not None:
        npz.parent.mkdir(parents=True, exist_ok=True)
        arrays: dict[str, Any] = sol.arrays()
        with atomic_file(npz) as tmp, open(tmp, "wb") as fh:
            np.savez(fh, **arrays)
        record = {
            "hash": key,
            "inputs": inputs,
            "elapsed": elapsed,
            "unknowns": extra["unknowns"],
            "timings": extra["timings"],
            "stored_times": [float(t) for t in sol.t[sol.u_levels]],
            "created": time.strftime("%Y-%m-%dT%H:%M:%S"),
        }
        write_atomic(meta, json.dumps(record, indent=1))
        extra["npz"] = str(npz)
        if log is not None:
            log(f"{label}: cached in {npz}")
    return sol, extra
