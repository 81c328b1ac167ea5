"""Example 5.5's reference solution: computed once, cached on disk by the hash of its inputs.

The cache holds ``ex55_reference_h{n}_{hash}.npz`` (the reference as a
:class:`vemwear.post.compare.Solution`) and a ``.json`` with its inputs and their hash
(:func:`cache_key`). A cached reference is reused whenever its inputs did not change
and it holds the displacement at every time asked for.
"""

from __future__ import annotations

import json
import os
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..post.compare import Solution
from ..simulate import Problem, SolverOptions, simulate
from ..util.hashing import sha256_json

__all__ = ["CACHE_FORMAT", "cache_key", "cached_solution", "default_cache_dir"]

CACHE_FORMAT = "vemwear-ex55-reference/2"


def default_cache_dir(outdir: str | os.PathLike[str]) -> Path:
    """``OUTDIR/../.vemwear-cache``.

    Parameters
    ----------
    outdir : path
        The output directory.
    """
    return Path(outdir).absolute().parent / ".vemwear-cache"


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


def _atomic_write(path: Path, write: Callable[[Any], None], mode: str) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.tmp-")
    try:
        with os.fdopen(fd, mode) as fh:
            write(fh)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


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
        _atomic_write(npz, lambda fh: np.savez(fh, **arrays), "wb")
        record = {
            "hash": key,
            "inputs": inputs,
            "elapsed": elapsed,
            "unknowns": extra["unknowns"],
            "timings": extra["timings"],
            "stored_times": [float(t) for t in sol.t[sol.u_levels]],
            "created": time.strftime("%Y-%m-%dT%H:%M:%S"),
        }
        _atomic_write(meta, lambda fh: json.dump(record, fh, indent=1), "w")
        extra["npz"] = str(npz)
        if log is not None:
            log(f"{label}: cached in {npz}")
    return sol, extra
