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
from collections.abc import Mapping, Sequence
from dataclasses import replace
from math import gcd
from pathlib import Path
from typing import Any

import numpy as np

from ..simulate import Problem, Result, TimeGrid
from . import DESCRIPTIONS, ExampleRun, ex52
from .driver import run_example
from .markdown import links, num
from .spec import Column, Context, Example, OutputFile, text_output

__all__ = [
    "BASE_STEPS",
    "DESCRIPTION",
    "DIVISIONS",
    "EXAMPLE",
    "GRID_LABELS",
    "KAPPA",
    "MU",
    "NAME",
    "TITLE",
    "differences",
    "differences_csv",
    "differences_markdown",
    "first_order_note",
    "problems",
    "run",
    "time_grids",
]

NAME = "5.3"
TITLE = f"Example {NAME}"
DESCRIPTION = DESCRIPTIONS[NAME]

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


def _frac(a: int, b: int) -> str:
    g = gcd(a, b)
    return f"{a // g}/{b // g}"


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


def differences(results: Mapping[str, Result]) -> list[dict[str, Any]]:
    """Pairwise differences of w(T) between the partitions.

    Parameters
    ----------
    results : mapping of str to Result
        The runs, by partition name, finest first.

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


def differences_csv(rows: Sequence[dict[str, Any]]) -> str:
    """The rows of :func:`differences` as CSV.

    Parameters
    ----------
    rows : sequence of dict
        The rows of :func:`differences`.
    """
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


def differences_markdown(rows: Sequence[dict[str, Any]], labels: Mapping[str, str]) -> str:
    """The rows of :func:`differences` as a Markdown table.

    Parameters
    ----------
    rows : sequence of dict
        The rows of :func:`differences`.
    labels : mapping of str to str
        Legend label of each partition, by name.
    """
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


def _between(results: Mapping[str, Result], labels: Mapping[str, str]) -> str:
    m = {n: float(r.wear[-1].max()) for n, r in results.items()}
    if not {"k64", "alt128", "k32"} <= set(m):
        return ""
    lo, hi = sorted((m["k64"], m["k32"]))
    where = "lies between" if lo <= m["alt128"] <= hi else "does not lie between"
    return (
        f"The maximal wear of the alternating partition ({labels['alt128']}) {where} "
        f"those of {labels['k64']} and {labels['k32']}."
    )


def first_order_note(rows: Sequence[dict[str, Any]]) -> str:
    """How the differences scale with the step (a first-order method gives 3 and 2).

    For ``w_k(T) = w(T) + C k``: ``|w_16 - w_64| / |w_32 - w_64| = 3`` and
    ``|w_16 - w_32| / |w_32 - w_64| = 2`` (steps 1/16, 1/32, 1/64).

    Parameters
    ----------
    rows : sequence of dict
        The rows of :func:`differences`.
    """
    d = {(r["a"], r["b"]): r["max_abs"] for r in rows}
    try:
        r1 = d[("k64", "k16")] / d[("k64", "k32")]
        r2 = d[("k32", "k16")] / d[("k64", "k32")]
    except (KeyError, ZeroDivisionError):
        return ""
    return (
        f"Differences to the uniform k = 1/64 run: the k = 1/16 one is {r1:.2f} times the "
        f"k = 1/32 one, and k = 1/16 vs 1/32 is {r2:.2f} times k = 1/32 vs 1/64; a method "
        "of first order in k (the left rectangle rule 3.22) gives 3 and 2."
    )


# ----------------------------------------------------------------------------- the example
def _labels(params: Mapping[str, Any]) -> dict[str, str]:
    return {name: lab for name, (lab, _g) in time_grids(params["base_steps"]).items()}


def _analyse(ctx: Context) -> dict[str, Any]:
    rows = differences(ctx.results)
    return {
        "differences": rows,
        "max_rel_diff": max(r["rel"] for r in rows),
        "max_wear": {n: float(r.wear[-1].max()) for n, r in ctx.results.items()},
        "labels": _labels(ctx.params),
    }


def _setup(ctx: Context) -> str:
    nx, ny = ctx.params["divisions"]
    return (
        "Paper Fig. 6. Data set mu = 0.2, kappa = 2, v* = (1, 0); "
        f"{nx} x {ny} squares (h = 1/{ny}); solver `{ctx.solver.method}`; "
        f"wall time {ctx.elapsed():.2f} s."
    )


def _differences_section(ctx: Context) -> list[str]:
    rows, labels = ctx.details["differences"], ctx.details["labels"]
    worst = max(rows, key=lambda r: r["rel"])
    return [
        "## Pairwise differences of w(T)",
        "",
        "max abs diff = max over contact nodes of |w_a(T) - w_b(T)|; relative = that divided "
        "by the larger of max w_a(T), max w_b(T).",
        "",
        differences_markdown(rows, labels),
        f"Largest relative difference: {worst['rel']:.2%} ({labels[worst['a']]} vs "
        f"{labels[worst['b']]}). The wear update (3.22) is first order in k, so the "
        "differences grow with the difference of the step sizes. " + _between(ctx.results, labels),
        "",
    ]


def _fig6(ctx: Context, path: Path) -> None:
    from ..post import compare_profiles

    labels = ctx.details["labels"]
    compare_profiles(
        {labels[n]: r for n, r in ctx.results.items()},
        T,
        "wear",
        path,
        title=f"{TITLE}: wear at t = {T:g} (paper Fig. 6)",
    )


def _paper_section(out: Path, sub: str, run: ExampleRun) -> list[str]:
    d = run.details
    rows = d.get("differences", [])
    labels = d.get("labels", {})
    return [
        "## Example 5.3: wear at t = 1 on four time partitions (paper Fig. 6)",
        "",
        f"Report: [{sub}/example_5_3.md]({sub}/example_5_3.md). Wall time {run.elapsed:.1f} s.",
        "",
        "| partition | our max w(1) |",
        "|---|---|",
        *[f"| {labels.get(n, n)} | {num(v, '.6g')} |" for n, v in d.get("max_wear", {}).items()],
        "",
        "Pairwise differences of w(1) (largest nodal difference, absolute and relative to the "
        "larger maximum):",
        "",
        differences_markdown(rows, labels) if rows else "(none)",
        f"The paper says the four curves are similar (Fig. 6, no numbers). Ours differ by at "
        f"most {num(100 * d.get('max_rel_diff', float('nan')), '.2f')} %. "
        + first_order_note(rows),
        "",
        "Figures:",
        "",
        *links(out, sub),
        "",
    ]


def _check(params: Mapping[str, Any]) -> None:
    time_grids(params["base_steps"])  # raises for an invalid base_steps


EXAMPLE = Example(
    name=NAME,
    heading="wear at t = 1 on four time partitions",
    parameters={"divisions": DIVISIONS, "base_steps": BASE_STEPS},
    problems=problems,
    check=_check,
    setup=_setup,
    runs_description="the output of `vemwear run` for each partition.",
    run_label=lambda ctx, name, pr: (
        f"{name}: {_labels(ctx.params)[name]} ({pr.time.n_steps} steps)"
    ),
    run_extra=lambda ctx, name, pr: {
        "grid": name,
        "partition": _labels(ctx.params)[name],
        "data": {"mu": MU, "kappa": KAPPA},
        "divisions": list(ctx.params["divisions"]),
    },
    analyse=_analyse,
    columns=(
        Column("grid", lambda ctx, n, r: n),
        Column("partition", lambda ctx, n, r: ctx.details["labels"][n]),
        Column("levels", lambda ctx, n, r: str(len(r.t))),
        Column("max w(T)", lambda ctx, n, r: f"{r.wear[-1].max():.6g}"),
        Column("at x", lambda ctx, n, r: f"{r.contact_points[int(np.argmax(r.wear[-1])), 0]:.4g}"),
        Column(
            "worn area sum(omega w)",
            lambda ctx, n, r: f"{float(np.dot(r.problem.contact.weights, r.wear[-1])):.6g}",
        ),
        Column("max iterations", lambda ctx, n, r: str(int(r.iterations.max()))),
        Column("max KKT residual", lambda ctx, n, r: f"{float(r.residuals.max()):.2e}"),
    ),
    sections=(_differences_section,),
    outputs=(
        text_output(
            "wear_differences.md",
            "the table of pairwise differences above.",
            lambda ctx: differences_markdown(ctx.details["differences"], ctx.details["labels"]),
        ),
        text_output(
            "wear_differences.csv",
            "the same as CSV.",
            lambda ctx: differences_csv(ctx.details["differences"]),
        ),
        OutputFile("fig6.png", "w at t = 1 for the four partitions (paper Fig. 6).", _fig6, True),
    ),
    headlines={"max_rel_diff": lambda ctx: ctx.details["max_rel_diff"]},
    paper_section=_paper_section,
)


def run(outdir: str | Path, **options: Any) -> ExampleRun:
    """Solve the four partitions and write everything into the existing directory ``outdir``.

    Writes ``k64/``, ``alt128/``, ``k32/``, ``k16/`` (the standard output of
    ``vemwear run`` each), ``fig6.png`` (w(1) of the four, paper Fig. 6),
    ``wear_differences.md`` / ``.csv`` (pairwise max differences of w(T)) and
    ``example_5_3.md``.

    Parameters
    ----------
    outdir : path
        An existing directory.
    **options
        ``divisions`` (paper: 32 x 16) and ``base_steps`` (:func:`time_grids`; paper:
        64), and the driver's ``solver``, ``progress``, ``figures``, ``vtk``, ``log``
        (:func:`vemwear.paper.driver.run_example`).

    Returns
    -------
    ExampleRun
        ``details``: ``differences`` (the rows of :func:`differences`), ``max_rel_diff``,
        ``max_wear`` by grid and ``labels``.
    """
    return run_example(EXAMPLE, outdir, **options)
