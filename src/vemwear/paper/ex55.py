"""Example 5.5 of the paper: errors and convergence orders against a fine reference.

Data of Example 5.2 on Omega = (0, 2) x (0, 1) with uniform squares (divisions
(2/h, 1/h), Gamma_C in 2/h parts), T = 1 and uniform time steps k = h, for
h = k = 1/4, 1/8, ..., 1/64, against the reference solution h = k = 1/256
(paper Tables 1 and 2). The paper does not state mu and kappa for this example; we
use Example 5.3's (= Example 5.2's data set 1): mu = 0.2, kappa = 2, v* = (1, 0),
the data set of every other single-data-set example of the paper (5.3, 5.4).

Errors (:mod:`vemwear.post.compare`; docs/paper.md), relative, at the common time
levels (the levels of the coarse grid; all of them are reference levels):

- displacement (Table 1), column ``u_H1``: each solution projected by its own ``Pi``
  (3.8)-(3.10) on its own mesh, the difference of the two piecewise linear fields
  integrated over the cells of the reference mesh, full H1 norm:
  ``||Pi_h u_h - Pi_ref u_ref||_{H1} / ||Pi_ref u_ref||_{H1}``;
- wear (Table 2), column ``w_L2``: ``||w_h - w_ref||_{L2(Gamma_C)} /
  ||w_ref||_{L2(Gamma_C)}``, both piecewise linear along Gamma_C, integrated exactly;

at t = T (the tables) and as the maximum over the common levels; secondary variants in
``errors.csv`` (:mod:`vemwear.paper.ex55_tables`). Orders are log2 of the ratios of
successive errors. :mod:`vemwear.paper.ex55_study` splits the wear error into its
space and time parts.

The reference is computed with ``simulate(..., store=[common times])`` so that only
the needed displacements are recovered, and cached on disk (``.npz`` plus a ``.json``
with the hash of its inputs) in a cache directory; it is reused whenever its inputs
(problem data, reference size, solver method and tolerance, vemwear version) did not
change and it holds the displacement at every needed time.
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

from ..post.compare import Comparison, ErrorHistory, Solution
from ..simulate import Problem, Result, SolverOptions, simulate
from ..util.atomic import atomic_file, write_atomic
from ..util.hashing import sha256_json
from . import ExampleRun, ex52
from .ex55_tables import (
    PAPER_TABLE1,
    PAPER_TABLE2,
    error_tables,
    paper_ratios,
    plot_tables,
    tables_csv,
    tables_markdown,
)

__all__ = [
    "CACHE_FORMAT",
    "DESCRIPTION",
    "KAPPA",
    "LEVELS",
    "MU",
    "NAME",
    "PAPER_TABLE1",
    "PAPER_TABLE2",
    "REFERENCE",
    "TITLE",
    "cache_key",
    "check_sizes",
    "common_times",
    "default_cache_dir",
    "error_tables",
    "paper_ratios",
    "problem",
    "problems",
    "reference_solution",
    "run",
    "tables_csv",
    "tables_markdown",
]

NAME = "5.5"
TITLE = "Example 5.5"
DESCRIPTION = (
    "relative errors and orders for h = k = 1/4 ... 1/64 against h = k = 1/256 "
    "(paper Tables 1 and 2)"
)

# not stated for 5.5 in the paper: Example 5.3's data (Example 5.2's data set 1)
MU, KAPPA = ex52.DATA_SETS["set1"]["mu"], ex52.DATA_SETS["set1"]["kappa"]
LEVELS: tuple[int, ...] = (4, 8, 16, 32, 64)  # 1/h = 1/k
REFERENCE: int = 256
T = ex52.T
CACHE_FORMAT = "vemwear-ex55-reference/1"


def check_sizes(levels: Sequence[int], reference: int) -> tuple[tuple[int, ...], int]:
    """Validate the mesh levels and the reference size (all as ``1/h``).

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
    """The problem with h = 1/n ((2n) x n squares) and ``steps`` uniform steps on [0, 1]
    (default n: k = h, the paper's choice)."""
    return ex52.problem(MU, KAPPA, divisions=(2 * n, n), steps=n if steps is None else steps)


def problems(*, levels: Sequence[int] = LEVELS) -> dict[str, Problem]:
    """The coarse problems by name (``h4``, ``h8``, ...)."""
    return {f"h{n}": problem(n) for n in levels}


def common_times(levels: Sequence[int], T_: float = T) -> list[float]:
    """The union of the time levels ``j T / n`` of every level ``n`` (exact fractions)."""
    s = {Fraction(j, n) for n in levels for j in range(n + 1)}
    return [float(f) * T_ for f in sorted(s)]


# ----------------------------------------------------------------------------- reference cache
def default_cache_dir(outdir: str | os.PathLike[str]) -> Path:
    """``OUTDIR/../.vemwear-cache``."""
    return Path(outdir).absolute().parent / ".vemwear-cache"


def _solver_desc(opts: SolverOptions) -> dict[str, Any]:
    return {"method": opts.method, "tol": opts.tol, "max_iter": opts.max_iter}


def cache_key(
    reference: int, solver: SolverOptions, pr: Problem | None = None
) -> tuple[str, dict[str, Any]]:
    """The hash (hex SHA-256) and the JSON inputs identifying a reference run.

    The inputs are the format tag, ``1/h``, the problem's fingerprint
    (:meth:`~vemwear.simulate.Problem.fingerprint`: the physics and the discretization,
    with the vemwear version) and the solver method, tolerance and iteration limit (the
    tolerance bounds how far the cached solution may be from the exact discrete one;
    the linear algebra backend does not change it beyond that), hashed by
    :func:`vemwear.util.hashing.sha256_json`.
    """
    inputs = {
        "format": CACHE_FORMAT,
        "reference": int(reference),
        "problem": (problem(reference) if pr is None else pr).fingerprint(),
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
        ``1/h`` of the reference.
    times : sequence of float
        Times at which its displacement is needed (levels of its grid).
    solver : SolverOptions or str
    cache_dir : path, optional
        Where ``ex55_reference_h{n}_{hash}.npz`` / ``.json`` live; ``None``: no cache.
    progress : bool
        Progress bar of the time loop.
    log : callable, optional
        Receives one line of text.

    Returns
    -------
    (Solution, dict)
        The reference, and ``{"cached": bool, "elapsed": s of the run (or of the
        original run when cached), "hash", "npz", "unknowns", "timings"}``.
    """
    opts = SolverOptions(method=solver) if isinstance(solver, str) else solver
    pr = problem(reference)
    key, inputs = cache_key(reference, opts, pr)
    npz = meta = None
    if cache_dir is not None:
        cdir = Path(cache_dir)
        stem = f"ex55_reference_h{reference}_{key[:16]}"
        npz, meta = cdir / f"{stem}.npz", cdir / f"{stem}.json"
        sol = _load_cached(npz, meta, key, times)
        if sol is not None:
            info = json.loads(meta.read_text(encoding="utf-8"))
            if log is not None:
                log(f"{TITLE}: reference h = k = 1/{reference} from the cache {npz}")
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
            f"{TITLE}: reference h = k = 1/{reference} ({2 * pr.mesh.n_points} unknowns, "
            f"{reference} steps), storing u at {len(times)} levels"
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
        arrays = sol.arrays()
        with atomic_file(npz) as tmp, open(tmp, "wb") as fh:
            np.savez(fh, **arrays)  # type: ignore[arg-type]
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
            log(f"{TITLE}: reference cached in {npz}")
    return sol, extra


# ----------------------------------------------------------------------------- driver
def _ratio_lines(tables: dict[str, Any]) -> list[str]:
    """One line per table: the range of ours / paper."""
    out = []
    for key, name in (("u_H1", "Table 1"), ("w_L2", "Table 2")):
        r = [x for x in paper_ratios(tables)[key] if np.isfinite(x)]
        if r:
            out.append(
                f"- {name}: ours / paper = "
                + ", ".join(f"{x:.3f}" for x in r)
                + f" (range {min(r):.3f}-{max(r):.3f})."
            )
    return [*out, ""] if out else []


def _report(tables: dict[str, Any], info: dict[str, Any], study_lines: Sequence[str] = ()) -> str:
    ref = info["reference"]
    r = info["reference_info"]
    how = "read from the cache" if r["cached"] else "computed in this run"
    el = r.get("elapsed")
    lines = [
        "# Example 5.5: convergence against a reference solution",
        "",
        "Wu, Wang, Han, Section 5, Example 5.5 (Tables 1 and 2). Omega = (0, 2) x (0, 1), "
        "squares with Gamma_C in 2/h parts, uniform steps k = h, T = 1, data of Example 5.2 "
        f"with mu = {MU:g}, kappa = {KAPPA:g} (not stated in the paper for 5.5; Example 5.3's "
        "data set 1).",
        "",
        f"Reference: h = k = 1/{ref} ({r.get('unknowns')} unknowns), {how}"
        + (f"; its run took {el:.1f} s" if isinstance(el, (int, float)) else "")
        + ". "
        f"Solver `{info['solver']}`; wall time of this example {info['elapsed']:.1f} s.",
        "",
        "Errors are relative, at t = T (the maximum over the coarse time levels as a "
        "secondary row). Displacement (Table 1, column `u_H1`): each solution is projected by "
        "its own Pi (3.8)-(3.10) on its own mesh, a linear field per cell, and the difference "
        "of the two piecewise linear fields is integrated exactly over the cells of the "
        "reference mesh (every reference cell lies in one coarse cell): "
        "||Pi_h u_h - Pi_ref u_ref||_H1 / ||Pi_ref u_ref||_H1, full H1 norm. Wear (Table 2, "
        "column `w_L2`): ||w_h - w_ref||_L2(Gamma_C) / ||w_ref||_L2(Gamma_C), both piecewise "
        "linear along Gamma_C, integrated exactly over the reference's contact edges. "
        "Secondary variants (in `errors.csv`): the seminorm; `I_h u_ref`, the reference at "
        "the coarse vertices, compared on the coarse mesh (blind to u_ref - I_h u_ref); the "
        "coarse vertex values carried to the reference mesh by mean value coordinates.",
        "",
        tables_markdown(tables, ref),
        *_ratio_lines(tables),
        *study_lines,
        "## Files",
        "",
        "- `table1.md`, `table2.md`, `errors.csv`: the tables (every variant in the CSV).",
        *(
            ["- `table2_study.md`: the space / time split of the wear error."]
            if study_lines
            else []
        ),
        "- `convergence.png`: log-log plot of the errors, with the paper's.",
        "- `h4/`, `h8/`, ...: `result.npz` and `summary.json` of every coarse run.",
        "",
    ]
    return "\n".join(lines)


def run(
    outdir: str | Path,
    *,
    solver: SolverOptions | str = "newton",
    levels: Sequence[int] = LEVELS,
    reference: int = REFERENCE,
    cache: str | os.PathLike[str] | bool | None = True,
    progress: bool = False,
    figures: bool = True,
    vtk: bool = False,
    study: bool = False,
    log: Callable[[str], None] | None = None,
) -> ExampleRun:
    """Compute Tables 1 and 2 and write them into the existing directory ``outdir``.

    Writes ``h{n}/`` for every level (``result.npz``, ``summary.json``; the VTK series if
    asked), ``table1.md``, ``table2.md``, ``errors.csv``, ``convergence.png`` and
    ``example_5_5.md``.

    Parameters
    ----------
    outdir : path
        An existing directory.
    solver : SolverOptions or str
        Step solver of every run (default: condensed Newton).
    levels : sequence of int
        ``1/h = 1/k`` of the coarse runs (paper: 4, 8, 16, 32, 64).
    reference : int
        ``1/h = 1/k`` of the reference (paper: 256); must be a multiple of every level.
    cache : path, True, False or None
        Cache directory of the reference; ``True``: :func:`default_cache_dir` of
        ``outdir``; ``False`` / ``None``: no cache.
    progress, log
        As for :func:`vemwear.paper.ex52.run`.
    figures : bool
        Write ``convergence.png`` (the coarse runs get no figures).
    vtk : bool
        Write the VTK series of the coarse runs (off by default).
    study : bool
        Also split the wear error into its space and time parts
        (:func:`vemwear.paper.ex55_study.wear_error_study`, reusing the reference) and
        write ``table2_study.md``.

    Returns
    -------
    ExampleRun
        ``results``: the coarse runs by name (``h4``, ...); ``details``: ``tables``
        (:func:`~vemwear.paper.ex55_tables.error_tables`), ``ratios`` (ours / paper),
        ``reference`` (1/h), ``reference_info`` (cached?, its run time), ``paper``
        (Tables 1 and 2) and ``study`` (or None).
    """
    t0 = time.perf_counter()
    out = Path(outdir)
    lv, ref = check_sizes(levels, reference)
    opts = SolverOptions(method=solver) if isinstance(solver, str) else solver
    if cache is True:
        cache_dir: Path | None = default_cache_dir(out)
    elif cache is False or cache is None:
        cache_dir = None
    else:
        cache_dir = Path(cache)
    times = common_times(lv)
    ref_sol, ref_info = reference_solution(
        ref, times, solver=opts, cache_dir=cache_dir, progress=progress, log=log
    )
    results: dict[str, Result] = {}
    histories: dict[int, ErrorHistory] = {}
    comparison = Comparison(ref_sol)
    files: list[str] = []
    from ..post.outputs import write_outputs

    for n in lv:
        name = f"h{n}"
        if log is not None:
            log(f"{TITLE}, {name}: h = k = 1/{n}")
        res = simulate(problem(n), opts, progress=progress, store="all")
        results[name] = res
        histories[n] = comparison.errors(res)
        sub = out / name
        sub.mkdir(parents=True, exist_ok=True)
        extra = {"example": NAME, "inv_h": n, "data": {"mu": MU, "kappa": KAPPA}}
        w = write_outputs(res, sub, times=(T,), figures=False, vtk=vtk, extra=extra)
        files += [f"{name}/{f}" for group in w.values() for f in group]
    tables = error_tables(histories)
    md = tables_markdown(tables, ref)
    t1, t2 = md.split("### Table 2")
    (out / "table1.md").write_text(t1.strip() + "\n", encoding="utf-8")
    (out / "table2.md").write_text(("### Table 2" + t2).strip() + "\n", encoding="utf-8")
    (out / "errors.csv").write_text(tables_csv(tables), encoding="utf-8")
    files += ["table1.md", "table2.md", "errors.csv"]
    if figures:
        plot_tables(tables, ref, out / "convergence.png", TITLE)
        files.append("convergence.png")
    study_result: dict[str, Any] | None = None
    study_lines: list[str] = []
    if study:
        from .ex55_study import study_markdown, wear_error_study

        study_result = wear_error_study(
            levels=lv, reference=ref, solver=opts, comparison=comparison, coarse=results, log=log
        )
        study_lines = study_markdown(study_result).splitlines()
        (out / "table2_study.md").write_text("\n".join(study_lines) + "\n", encoding="utf-8")
        files.append("table2_study.md")
    elapsed = time.perf_counter() - t0
    info = {"reference": ref, "reference_info": ref_info, "solver": opts.method, "elapsed": elapsed}
    report = out / "example_5_5.md"
    report.write_text(_report(tables, info, study_lines), encoding="utf-8")
    files.append(report.name)
    details = {
        "tables": tables,
        "reference": ref,
        "reference_info": ref_info,
        "levels": list(lv),
        "paper": {"table1": PAPER_TABLE1, "table2": PAPER_TABLE2},
        "ratios": paper_ratios(tables),
        "study": study_result,
        "summary": md.splitlines(),
    }
    return ExampleRun(
        name=NAME,
        outdir=out,
        results=results,
        files=files,
        report=report,
        details=details,
        elapsed=time.perf_counter() - t0,
    )
