"""Example 5.3 of the paper: the wear at t = 1 on four time partitions (paper Fig. 6).

Data as in Example 5.2, data set 1 (mu = 0.2, kappa = 2, v* = (1, 0)), mesh size
h = 1/16 (32 x 16 squares, Gamma_C in 32 parts), T = 1, and four partitions of [0, 1]:

1. ``k64``:    uniform, k = 1/64;
2. ``alt128``: alternating k_{2l-1} = 1/128, k_{2l} = 3/128 (``TimeGrid.pattern``);
3. ``k32``:    uniform, k = 1/32;
4. ``k16``:    uniform, k = 1/16.

The paper shows w(1) for the four partitions in one figure (Fig. 6) and observes that
the non-uniform partition gives a solution similar to the uniform ones. Here Fig. 6
is ``fig6.png``; the table ``wear_differences.md`` / ``.csv`` quantifies the
similarity: for every pair of partitions, the largest nodal difference of w(T), absolute
and relative to the larger of the two maxima of w(T).

The wear update is the left rectangle rule (3.22), first order in k, so the
differences between partitions should be of the order of the step sizes: with
``w(T) = O(T alpha p)``, partitions with largest steps k_a, k_b differ by about
``C |k_a - k_b|`` relative to w(T), a few percent here.
"""

from __future__ import annotations

import csv
import io
import itertools
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from ..post.outputs import write_outputs
from ..simulate import Problem, Result, SolverOptions, TimeGrid, simulate
from . import ExampleRun, ex52

__all__ = [
    "BASE_STEPS",
    "DESCRIPTION",
    "DIVISIONS",
    "GRID_LABELS",
    "KAPPA",
    "MU",
    "NAME",
    "TITLE",
    "differences",
    "differences_csv",
    "differences_markdown",
    "problems",
    "run",
    "time_grids",
]

NAME = "5.3"
TITLE = "Example 5.3"
DESCRIPTION = (
    "wear at t = 1 for uniform k = 1/64, alternating 1/128, 3/128, uniform 1/32 "
    "and 1/16 (paper Fig. 6)"
)

DIVISIONS: tuple[int, int] = ex52.DIVISIONS  # h = 1/16
BASE_STEPS: int = 64  # the finest uniform partition, k = 1/BASE_STEPS
MU, KAPPA = ex52.DATA_SETS["set1"]["mu"], ex52.DATA_SETS["set1"]["kappa"]
T = ex52.T

#: Legend labels of the four partitions (by subdirectory name), for BASE_STEPS = 64.
GRID_LABELS: dict[str, str] = {
    "k64": "uniform k = 1/64",
    "alt128": "alternating k = 1/128, 3/128",
    "k32": "uniform k = 1/32",
    "k16": "uniform k = 1/16",
}


def _frac(num: int, den: int) -> str:
    from math import gcd

    g = gcd(num, den)
    return f"{num // g}/{den // g}"


def time_grids(base_steps: int = BASE_STEPS) -> dict[str, tuple[str, TimeGrid]]:
    """The four partitions of [0, 1], by name, with their legend labels.

    Parameters
    ----------
    base_steps : int
        ``b``: uniform 1/b, alternating 1/(2b), 3/(2b), uniform 2/b and 4/b (the
        paper's b = 64 gives 1/64; 1/128, 3/128; 1/32; 1/16). Must be a multiple of 4.
        The names keep the paper's (``k64``, ``alt128``, ``k32``, ``k16``) whatever b.
    """
    b = int(base_steps)
    if b < 4 or b % 4:
        raise ValueError(f"{TITLE}: base_steps must be a positive multiple of 4, got {base_steps}")
    return {
        "k64": (f"uniform k = {_frac(1, b)}", TimeGrid.uniform(T, b)),
        "alt128": (
            f"alternating k = {_frac(1, 2 * b)}, {_frac(3, 2 * b)}",
            TimeGrid.pattern(T, [1.0 / (2 * b), 3.0 / (2 * b)]),
        ),
        "k32": (f"uniform k = {_frac(2, b)}", TimeGrid.uniform(T, b // 2)),
        "k16": (f"uniform k = {_frac(4, b)}", TimeGrid.uniform(T, b // 4)),
    }


def problems(
    *, divisions: tuple[int, int] = DIVISIONS, base_steps: int = BASE_STEPS
) -> dict[str, Problem]:
    """The four problems of Example 5.3 (same mesh and data, four time grids), by name.

    Parameters
    ----------
    divisions : (int, int)
        Squares in x and y (paper: 32 x 16, h = 1/16).
    base_steps : int
        See :func:`time_grids` (paper: 64).
    """
    m = ex52.mesh(divisions)
    out = {}
    for name, (_label, grid) in time_grids(base_steps).items():
        out[name] = replace(ex52.problem(MU, KAPPA, tagged_mesh=m, steps=1), time=grid)
    return out


def differences(results: dict[str, Result]) -> list[dict[str, Any]]:
    """Pairwise differences of w(T) between the partitions.

    Returns
    -------
    list of dict
        One row per pair ``(a, b)``: ``max_abs = max_a |w_a(T) - w_b(T)|`` over the
        contact nodes, ``rel = max_abs / max(max w_a(T), max w_b(T))``, the maxima of
        both, and ``l2_rel``, the relative L2(Gamma_C) difference (exact for piecewise
        linear w) against the finer of the two (``a``).
    """
    from ..post.norms import contact_l2_norm

    rows = []
    for a, b in itertools.combinations(results, 2):
        ra, rb = results[a], results[b]
        wa, wb = ra.wear[-1], rb.wear[-1]
        d = float(np.max(np.abs(wa - wb)))
        ma, mb = float(wa.max()), float(wb.max())
        mesh = ra.problem.mesh
        l2 = contact_l2_norm(mesh, ra.contact_nodes, wa - wb)
        na = contact_l2_norm(mesh, ra.contact_nodes, wa)
        rows.append(
            {
                "a": a,
                "b": b,
                "max_abs": d,
                "rel": d / max(ma, mb),
                "max_w_a": ma,
                "max_w_b": mb,
                "l2_rel": l2 / na if na > 0 else float("nan"),
            }
        )
    return rows


def differences_csv(rows: list[dict[str, Any]]) -> str:
    """The rows of :func:`differences` as CSV."""
    buf = io.StringIO()
    wr = csv.writer(buf, lineterminator="\n")
    wr.writerow(
        ["grid_a", "grid_b", "max_abs_diff", "rel_diff", "max_w_a", "max_w_b", "l2_rel_diff"]
    )
    for r in rows:
        wr.writerow(
            [
                r["a"],
                r["b"],
                f"{r['max_abs']:.6e}",
                f"{r['rel']:.6e}",
                f"{r['max_w_a']:.6e}",
                f"{r['max_w_b']:.6e}",
                f"{r['l2_rel']:.6e}",
            ]
        )
    return buf.getvalue()


def differences_markdown(rows: list[dict[str, Any]], labels: dict[str, str]) -> str:
    """The rows of :func:`differences` as a Markdown table."""
    lines = [
        "| grid a | grid b | max abs diff of w(T) | relative | L2(Gamma_C) relative |",
        "|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {labels.get(r['a'], r['a'])} | {labels.get(r['b'], r['b'])} "
            f"| {r['max_abs']:.4e} | {r['rel']:.2%} | {r['l2_rel']:.2%} |"
        )
    return "\n".join(lines) + "\n"


def _between(results: dict[str, Result], labels: dict[str, str]) -> str:
    m = {n: float(r.wear[-1].max()) for n, r in results.items()}
    if not {"k64", "alt128", "k32"} <= set(m):
        return ""
    lo, hi = sorted((m["k64"], m["k32"]))
    where = "lies between" if lo <= m["alt128"] <= hi else "does not lie between"
    return (
        f"The maximal wear of the alternating partition ({labels['alt128']}) {where} "
        f"those of {labels['k64']} and {labels['k32']}."
    )


def _report(
    results: dict[str, Result],
    labels: dict[str, str],
    rows: list[dict[str, Any]],
    info: dict[str, Any],
) -> str:
    nx, ny = info["divisions"]
    lines = [
        "# Example 5.3: wear at t = 1 on four time partitions",
        "",
        "Wu, Wang, Han, Section 5, Example 5.3 (paper Fig. 6). Data set mu = 0.2, kappa = 2, "
        f"v* = (1, 0); {nx} x {ny} squares (h = 1/{ny}); solver `{info['solver']}`; "
        f"wall time {info['elapsed']:.2f} s.",
        "",
        "| grid | partition | levels | max w(T) | at x | worn area sum(omega w) "
        "| max iterations | max KKT residual |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name, r in results.items():
        wT = r.wear[-1]
        a = int(np.argmax(wT))
        area = float(np.dot(r.problem.contact.weights, wT))
        lines.append(
            f"| {name} | {labels[name]} | {len(r.t)} | {wT.max():.6g} "
            f"| {r.contact_points[a, 0]:.4g} | {area:.6g} | {int(r.iterations.max())} "
            f"| {float(r.residuals.max()):.2e} |"
        )
    worst = max(rows, key=lambda r: r["rel"])
    lines += [
        "",
        "## Pairwise differences of w(T)",
        "",
        "max abs diff = max over contact nodes of |w_a(T) - w_b(T)|; relative = that divided "
        "by the larger of max w_a(T), max w_b(T).",
        "",
        differences_markdown(rows, labels),
        f"Largest relative difference: {worst['rel']:.2%} ({labels[worst['a']]} vs "
        f"{labels[worst['b']]}). The wear update (3.22) is first order in k, so the "
        "differences grow with the difference of the step sizes. " + _between(results, labels),
        "",
        "## Files",
        "",
        "- `fig6.png`: w at t = 1 for the four partitions (paper Fig. 6).",
        "- `wear_differences.md`, `wear_differences.csv`: the table above.",
        "- `" + "/`, `".join(results) + "/`: the output of `vemwear run` for each partition.",
        "",
    ]
    return "\n".join(lines)


def run(
    outdir: str | Path,
    *,
    solver: SolverOptions | str = "newton",
    divisions: tuple[int, int] = DIVISIONS,
    base_steps: int = BASE_STEPS,
    progress: bool = False,
    figures: bool = True,
    vtk: bool = True,
    log: Callable[[str], None] | None = None,
) -> ExampleRun:
    """Solve the four partitions and write everything into the existing directory ``outdir``.

    Writes ``k64/``, ``alt128/``, ``k32/``, ``k16/`` (the standard output of
    ``vemwear run`` each), ``fig6.png`` (w(1) of the four, paper Fig. 6),
    ``wear_differences.md`` / ``.csv`` (pairwise max differences of w(T)) and
    ``example_5_3.md``.

    Parameters
    ----------
    outdir : path
        An existing directory.
    solver : SolverOptions or str
        Step solver (default: condensed Newton).
    divisions : (int, int)
        Squares in x and y (paper: 32 x 16).
    base_steps : int
        See :func:`time_grids` (paper: 64).
    progress, figures, vtk, log
        As for :func:`vemwear.paper.ex52.run`.

    Returns
    -------
    ExampleRun
        ``details``: ``differences`` (the rows of :func:`differences`), ``max_rel_diff``,
        ``max_wear`` by grid and ``labels``.
    """
    t0 = time.perf_counter()
    out = Path(outdir)
    opts = SolverOptions(method=solver) if isinstance(solver, str) else solver
    grids = time_grids(base_steps)
    labels = {name: lab for name, (lab, _g) in grids.items()}
    probs = problems(divisions=divisions, base_steps=base_steps)
    results: dict[str, Result] = {}
    files: list[str] = []
    for name, pr in probs.items():
        if log is not None:
            log(f"{TITLE}, {name}: {labels[name]} ({pr.time.n_steps} steps)")
        res = simulate(pr, opts, progress=progress)
        results[name] = res
        sub = out / name
        sub.mkdir(parents=True, exist_ok=True)
        extra = {
            "example": NAME,
            "grid": name,
            "partition": labels[name],
            "data": {"mu": MU, "kappa": KAPPA},
            "divisions": list(divisions),
        }
        w = write_outputs(res, sub, times=(T,), figures=figures, vtk=vtk, extra=extra)
        files += [f"{name}/{f}" for group in w.values() for f in group]
    rows = differences(results)
    (out / "wear_differences.md").write_text(differences_markdown(rows, labels), encoding="utf-8")
    (out / "wear_differences.csv").write_text(differences_csv(rows), encoding="utf-8")
    files += ["wear_differences.md", "wear_differences.csv"]
    if figures:
        from .. import post

        post.compare_profiles(
            {labels[n]: r for n, r in results.items()},
            T,
            "wear",
            out / "fig6.png",
            title=f"{TITLE}: wear at t = {T:g} (paper Fig. 6)",
        )
        files.append("fig6.png")
    elapsed = time.perf_counter() - t0
    info = {"divisions": tuple(divisions), "solver": opts.method, "elapsed": elapsed}
    report = out / "example_5_3.md"
    report.write_text(_report(results, labels, rows, info), encoding="utf-8")
    files.append(report.name)
    details = {
        "differences": rows,
        "max_rel_diff": max(r["rel"] for r in rows),
        "max_wear": {n: float(r.wear[-1].max()) for n, r in results.items()},
        "labels": labels,
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
