"""Example 5.5 of the paper: errors and convergence orders against a fine reference.

Data of Example 5.2 on Omega = (0, 2) x (0, 1) with uniform squares (divisions
(2/h, 1/h), Gamma_C in 2/h parts), T = 1 and uniform time steps k = h, for
h = k = 1/4, 1/8, ..., 1/64, against the reference solution h = k = 1/256
(paper Tables 1 and 2). The paper does not state mu and kappa for this example; we
use Example 5.3's (= Example 5.2's data set 1): mu = 0.2, kappa = 2, v* = (1, 0),
the data set of every other single-data-set example of the paper (5.3, 5.4).

Errors (:mod:`vemwear.post.errors`, design note section 5), relative, at the common
time levels (the levels of the coarse grid; all of them are reference levels):

- displacement: ``||Pi(u_h - I_h u_ref)||_{H1} / ||Pi I_h u_ref||_{H1}`` (Table 1), and
  the H1-seminorm variant;
- wear: ``||w_h - I_h w_ref||_{L2(Gamma_C)} / ||I_h w_ref||_{L2(Gamma_C)}`` (Table 2),
  w piecewise linear (exact integral), and the nodal-quadrature variant;

each at t = T and as the maximum over the common levels. Orders are log2 of the
ratios of successive errors.

The reference is computed with ``simulate(..., store=[common times])`` so that only
the needed displacements are recovered, and cached on disk (``.npz`` plus a ``.json``
with the hash of its inputs) in a cache directory; it is reused whenever its inputs
(problem data, reference size, solver method and tolerance, vemwear version) did not
change and it holds the displacement at every needed time.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import os
import tempfile
import time
from collections.abc import Callable, Sequence
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__
from ..post.errors import Comparison, ErrorHistory, Solution, convergence_orders
from ..simulate import Problem, Result, SolverOptions, simulate
from . import ExampleRun, ex52

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

#: The paper's Table 1 (relative H1 displacement errors) and Table 2 (relative L2 wear
#: errors), by 1/h, and their orders.
PAPER_TABLE1: dict[str, Any] = {
    "errors": {4: 7.0581e-2, 8: 3.9059e-2, 16: 2.1698e-2, 32: 1.2084e-2, 64: 6.5023e-3},
    "orders": {8: 0.85365, 16: 0.84807, 32: 0.84448, 64: 0.89407},
}
PAPER_TABLE2: dict[str, Any] = {
    "errors": {4: 1.1153e-1, 8: 5.4917e-2, 16: 2.5228e-2, 32: 1.1795e-2, 64: 5.4869e-3},
    "orders": {8: 1.0221, 16: 1.1223, 32: 1.0968, 64: 1.1041},
}

#: Columns of the error tables: (key, where, quantity, variant, when); ``where`` is
#: ``coarse`` (design note section 5) or ``fine`` (the coarse solution prolongated to
#: the reference mesh, :meth:`vemwear.post.errors.Comparison.errors`).
COLUMNS: tuple[tuple[str, str, str, str, str], ...] = (
    ("u_H1_T", "coarse", "displacement", "H1", "T"),
    ("u_H1_max", "coarse", "displacement", "H1", "max"),
    ("u_H1semi_T", "coarse", "displacement", "H1semi", "T"),
    ("u_H1semi_max", "coarse", "displacement", "H1semi", "max"),
    ("u_fine_H1_T", "fine", "displacement", "H1", "T"),
    ("u_fine_H1semi_T", "fine", "displacement", "H1semi", "T"),
    ("u_fine_H1semi_max", "fine", "displacement", "H1semi", "max"),
    ("w_L2_T", "coarse", "wear", "exact", "T"),
    ("w_L2_max", "coarse", "wear", "exact", "max"),
    ("w_nodal_T", "coarse", "wear", "nodal", "T"),
    ("w_nodal_max", "coarse", "wear", "nodal", "max"),
    ("w_fine_L2_T", "fine", "wear", "exact", "T"),
    ("w_fine_L2_max", "fine", "wear", "exact", "max"),
)


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


def problem(n: int) -> Problem:
    """The problem with h = k = 1/n: (2n) x n squares, n uniform steps on [0, 1]."""
    return ex52.problem(MU, KAPPA, divisions=(2 * n, n), steps=n)


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


def cache_key(reference: int, solver: SolverOptions) -> tuple[str, dict[str, Any]]:
    """The hash (hex SHA-256) and the JSON inputs identifying a reference run.

    The inputs are the format tag, the vemwear version, ``1/h``, the problem's
    description (mesh sizes, material, time grid, loads, contact law and data) and
    the solver method, tolerance and iteration limit (not the linear algebra
    backend: it does not change the solution beyond the tolerance).
    """
    inputs = {
        "format": CACHE_FORMAT,
        "vemwear": __version__,
        "reference": int(reference),
        "problem": problem(reference).describe(),
        "solver": _solver_desc(solver),
    }
    text = json.dumps(inputs, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest(), inputs


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
    key, inputs = cache_key(reference, opts)
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
    pr = problem(reference)
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
            log(f"{TITLE}: reference cached in {npz}")
    return sol, extra


# ----------------------------------------------------------------------------- tables
def error_tables(histories: dict[str, dict[int, ErrorHistory]]) -> dict[str, Any]:
    """Errors and orders of every column of :data:`COLUMNS`, by increasing ``1/h``.

    Parameters
    ----------
    histories : dict
        ``{"coarse": {n: ErrorHistory}, "fine": {n: ErrorHistory}}``.

    Returns
    -------
    dict
        ``{column: {"errors": [...], "orders": [nan, ...]}}`` plus ``"n": [4, 8, ...]``.
    """
    ns = sorted(histories["coarse"])
    out: dict[str, Any] = {"n": ns}
    for key, where, q, variant, when in COLUMNS:
        hs = histories[where]
        e = [hs[n].at_T(q, variant) if when == "T" else hs[n].max(q, variant) for n in ns]
        o = [float("nan"), *convergence_orders(e).tolist()]
        out[key] = {"errors": e, "orders": o}
    return out


def _e(v: float | None) -> str:
    return "-" if v is None or not np.isfinite(v) else f"{v:.4e}"


def _o(v: float | None) -> str:
    return "-" if v is None or not np.isfinite(v) else f"{v:.4f}"


def _pow2(n: int) -> str:
    k = round(float(np.log2(n)))
    return f"2^-{k}" if 2**k == n else f"1/{n}"


#: Our rows of Tables 1 and 2 in :func:`tables_markdown`: (label, column, part).
TABLE1_ROWS: tuple[tuple[str, str, str], ...] = (
    ("ours, t = T: error", "u_H1_T", "errors"),
    ("ours, t = T: order", "u_H1_T", "orders"),
    ("ours, max over t: error", "u_H1_max", "errors"),
    ("ours, max over t: order", "u_H1_max", "orders"),
    ("ours, H1 seminorm, t = T", "u_H1semi_T", "errors"),
    ("ours, H1 seminorm, order", "u_H1semi_T", "orders"),
    ("ours, H1 seminorm, max over t", "u_H1semi_max", "errors"),
    ("ours on the fine mesh, H1 seminorm, t = T", "u_fine_H1semi_T", "errors"),
    ("ours on the fine mesh, H1 seminorm, order", "u_fine_H1semi_T", "orders"),
    ("ours on the fine mesh, H1 seminorm, max over t", "u_fine_H1semi_max", "errors"),
    ("ours on the fine mesh, H1, t = T", "u_fine_H1_T", "errors"),
)
TABLE2_ROWS: tuple[tuple[str, str, str], ...] = (
    ("ours, t = T: error", "w_L2_T", "errors"),
    ("ours, t = T: order", "w_L2_T", "orders"),
    ("ours, max over t: error", "w_L2_max", "errors"),
    ("ours, max over t: order", "w_L2_max", "orders"),
    ("ours, nodal quadrature, t = T", "w_nodal_T", "errors"),
    ("ours, nodal quadrature, order", "w_nodal_T", "orders"),
    ("ours on the fine mesh, t = T", "w_fine_L2_T", "errors"),
    ("ours on the fine mesh, order", "w_fine_L2_T", "orders"),
)


def tables_markdown(tables: dict[str, Any], reference: int) -> str:
    """Tables 1 and 2 (ours beside the paper's) and the variants, as Markdown."""
    ns = tables["n"]
    fmt = {"errors": _e, "orders": _o}

    def row(label: str, vals: Sequence[float | None], part: str) -> str:
        return f"| {label} | " + " | ".join(fmt[part](v) for v in vals) + " |"

    def table(title: str, paper: dict[str, Any], rows: Sequence[tuple[str, str, str]]) -> list[str]:
        return [
            f"### {title} (reference h = k = 1/{reference})",
            "",
            "| h = k | " + " | ".join(_pow2(n) for n in ns) + " |",
            "|---|" + "---|" * len(ns),
            *(row(f"paper: {p[:-1]}", [paper[p].get(n) for n in ns], p) for p in fmt),
            *(row(label, tables[key][part], part) for label, key, part in rows),
            "",
        ]

    lines = [
        *table("Table 1: relative H1 error of the displacement", PAPER_TABLE1, TABLE1_ROWS),
        *table("Table 2: relative L2(Gamma_C) error of the wear", PAPER_TABLE2, TABLE2_ROWS),
    ]
    return "\n".join(lines)


def tables_csv(tables: dict[str, Any]) -> str:
    """Every column of :data:`COLUMNS` (error and order) and the paper's, one row per h."""
    buf = io.StringIO()
    wr = csv.writer(buf, lineterminator="\n")
    keys = [c[0] for c in COLUMNS]
    wr.writerow(
        [
            "inv_h",
            "h",
            "k",
            *[f"{k}{s}" for k in keys for s in ("", "_order")],
            "paper_table1",
            "paper_table1_order",
            "paper_table2",
            "paper_table2_order",
        ]
    )
    for i, n in enumerate(tables["n"]):
        vals: list[str] = []
        for k in keys:
            e, o = tables[k]["errors"][i], tables[k]["orders"][i]
            vals += [f"{e:.6e}", "" if not np.isfinite(o) else f"{o:.6f}"]
        p1, p1o = PAPER_TABLE1["errors"].get(n), PAPER_TABLE1["orders"].get(n)
        p2, p2o = PAPER_TABLE2["errors"].get(n), PAPER_TABLE2["orders"].get(n)
        wr.writerow(
            [
                n,
                f"{1 / n:.10g}",
                f"{1 / n:.10g}",
                *vals,
                "" if p1 is None else p1,
                "" if p1o is None else p1o,
                "" if p2 is None else p2,
                "" if p2o is None else p2o,
            ]
        )
    return buf.getvalue()


def _plot(tables: dict[str, Any], reference: int, path: Path) -> None:
    from matplotlib.figure import Figure
    from matplotlib.ticker import NullLocator

    ns = np.asarray(tables["n"], dtype=float)
    h = 1.0 / ns
    fig = Figure(figsize=(10.0, 4.2), layout="constrained")
    axes = fig.subplots(1, 2)
    spec = [
        (
            "Displacement, relative H1 error (Table 1)",
            PAPER_TABLE1,
            [
                ("u_H1_T", "ours, t = T"),
                ("u_H1_max", "ours, max over t"),
                ("u_fine_H1semi_T", "ours on the fine mesh, H1 seminorm, t = T"),
            ],
        ),
        (
            "Wear, relative L2($\\Gamma_C$) error (Table 2)",
            PAPER_TABLE2,
            [
                ("w_L2_T", "ours, t = T"),
                ("w_L2_max", "ours, max over t"),
                ("w_fine_L2_T", "ours on the fine mesh, t = T"),
            ],
        ),
    ]
    for ax, (title, paper, cols) in zip(axes, spec, strict=True):
        for (key, label), mk in zip(cols, ("o", "s", "^"), strict=True):
            ax.loglog(h, tables[key]["errors"], marker=mk, label=label)
        pn = [n for n in tables["n"] if n in paper["errors"]]
        if pn:
            ax.loglog(
                [1.0 / n for n in pn],
                [paper["errors"][n] for n in pn],
                "k--",
                marker="x",
                label="paper",
            )
        e0 = tables[cols[0][0]]["errors"][0]
        ax.loglog(h, e0 * h / h[0], ":", color="gray", label="slope 1")
        ax.set_xticks(h, [f"1/{int(n)}" for n in ns])
        ax.xaxis.set_minor_locator(NullLocator())
        ax.set_xlabel("h = k")
        ax.set_ylabel("relative error")
        ax.set_title(title, fontsize="medium")
        ax.grid(True, which="both", lw=0.3, alpha=0.5)
        ax.legend(frameon=False, fontsize="small")
    fig.suptitle(f"{TITLE}: errors against the reference h = k = 1/{reference}")
    fig.savefig(path, dpi=150)


def _report(tables: dict[str, Any], info: dict[str, Any]) -> str:
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
        "Errors are relative, on the coarse mesh, against the nodal interpolant of the "
        "reference at the coarse vertices (nested meshes), at t = T and as the maximum over "
        "the coarse time levels (all of them are reference levels). Displacement: "
        "||Pi(u_h - I_h u_ref)||_H1 / ||Pi I_h u_ref||_H1 with Pi the coarse VEM projection "
        "(full H1 norm; the seminorm variant below). Wear: ||w_h - I_h w_ref||_L2(Gamma_C) / "
        "||I_h w_ref||_L2(Gamma_C), w piecewise linear along Gamma_C and integrated exactly "
        "(the nodal-quadrature variant below).",
        "",
        '"On the fine mesh": the coarse solution is prolongated to the reference mesh '
        "(exact on coarse edges, mean value interpolation of the vertex values inside coarse "
        "cells, i.e. nearly bilinear on squares) and compared there with Pi of the reference "
        "mesh; this error includes the interpolation error u_ref - I_h u_ref, which the "
        "coarse-mesh error does not see. The paper's Table 1 is close to this variant with "
        "the H1 seminorm.",
        "",
        tables_markdown(tables, ref),
        "## Files",
        "",
        "- `table1.md`, `table2.md`, `errors.csv`: the tables (every variant in the CSV).",
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

    Returns
    -------
    ExampleRun
        ``results``: the coarse runs by name (``h4``, ...); ``details``: ``tables``
        (:func:`error_tables`), ``reference`` (1/h), ``reference_info`` (cached?, its
        run time) and ``paper`` (Tables 1 and 2).
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
    histories: dict[str, dict[int, ErrorHistory]] = {"coarse": {}, "fine": {}}
    comparison = Comparison(ref_sol)
    files: list[str] = []
    from ..cli.output import write_outputs

    for n in lv:
        name = f"h{n}"
        if log is not None:
            log(f"{TITLE}, {name}: h = k = 1/{n}")
        res = simulate(problem(n), opts, progress=progress, store="all")
        results[name] = res
        for where in ("coarse", "fine"):
            histories[where][n] = comparison.errors(res, on=where)
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
        _plot(tables, ref, out / "convergence.png")
        files.append("convergence.png")
    elapsed = time.perf_counter() - t0
    info = {"reference": ref, "reference_info": ref_info, "solver": opts.method, "elapsed": elapsed}
    report = out / "example_5_5.md"
    report.write_text(_report(tables, info), encoding="utf-8")
    files.append(report.name)
    details = {
        "tables": tables,
        "reference": ref,
        "reference_info": ref_info,
        "levels": list(lv),
        "paper": {"table1": PAPER_TABLE1, "table2": PAPER_TABLE2},
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
