"""``vemwear paper``: run the paper's examples and write one report beside the paper's numbers.

:func:`run_paper` runs Examples 5.2, 5.3, 5.4 (when registered in
:data:`vemwear.paper.EXAMPLES`) and 5.5 into the subdirectories ``example_5_2/``, ...
of an output directory and writes ``report.md``: every figure linked, our numbers
beside the paper's (Tables 1 and 2 side by side, the wear maxima of 5.2, the
differences of 5.3), a discussion of the differences and the wall times.
``quick=True`` uses the reference h = k = 1/64 in Example 5.5 (instead of 1/256;
the levels are then h = k = 1/4 ... 1/32) and skips nothing else.
"""

from __future__ import annotations

import inspect
import math
import os
import platform
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__
from ..simulate import SolverOptions
from . import EXAMPLES, ExampleRun, load_example

__all__ = ["PAPER_ORDER", "QUICK_REFERENCE", "PaperRun", "report_markdown", "run_paper"]

#: The examples of the report, in order (those not registered are skipped).
PAPER_ORDER: tuple[str, ...] = ("5.2", "5.3", "5.4", "5.5")
#: 1/h of the Example 5.5 reference with ``quick=True``.
QUICK_REFERENCE = 64


@dataclass
class PaperRun:
    """What :func:`run_paper` produced.

    Attributes
    ----------
    outdir : Path
    runs : dict of str to ExampleRun
        By example number.
    report : Path
        ``report.md``.
    elapsed : float
        Total wall time in seconds.
    quick : bool
    skipped : list of str
        Examples of :data:`PAPER_ORDER` that are not registered.
    """

    outdir: Path
    runs: dict[str, ExampleRun]
    report: Path
    elapsed: float
    quick: bool
    skipped: list[str] = field(default_factory=list)


def _subdir(name: str) -> str:
    return "example_" + name.replace(".", "_")


def _call_run(mod: Any, outdir: Path, kwargs: dict[str, Any]) -> ExampleRun:
    """Call ``mod.run`` with the keyword arguments it accepts."""
    params = inspect.signature(mod.run).parameters
    accepted = {k: v for k, v in kwargs.items() if k in params}
    return mod.run(outdir, **accepted)


def run_paper(
    outdir: str | os.PathLike[str],
    *,
    quick: bool = False,
    solver: SolverOptions | str = "newton",
    cache: str | os.PathLike[str] | None = None,
    examples: Sequence[str] = PAPER_ORDER,
    progress: bool = False,
    log: Callable[[str], None] | None = None,
    sizes: dict[str, dict[str, Any]] | None = None,
) -> PaperRun:
    """Run the paper's examples into ``outdir/example_5_N/`` and write ``outdir/report.md``.

    Parameters
    ----------
    outdir : path
        An existing directory (``vemwear paper`` passes the temporary one of an atomic
        output directory).
    quick : bool
        Example 5.5 against the reference h = k = 1/64 instead of 1/256 (so with the
        levels h = k = 1/4 ... 1/32).
    solver : SolverOptions or str
        Step solver of every run.
    cache : path, optional
        Cache directory of the Example 5.5 reference (default: ``outdir/../.vemwear-cache``).
    examples : sequence of str
        Which examples (default: all of :data:`PAPER_ORDER` that are registered).
    progress : bool
        Progress bars.
    log : callable, optional
        Receives lines of text.
    sizes : dict, optional
        Extra keyword arguments of each example's ``run`` by number (smaller sizes for
        tests), e.g. ``{"5.3": {"divisions": (8, 4), "base_steps": 8}}``.

    Returns
    -------
    PaperRun
    """
    t0 = time.perf_counter()
    out = Path(outdir)
    opts = SolverOptions(method=solver) if isinstance(solver, str) else solver
    cache_dir = Path(cache) if cache is not None else Path(out).absolute().parent / ".vemwear-cache"
    runs: dict[str, ExampleRun] = {}
    skipped = [n for n in examples if n not in EXAMPLES]
    ex55_kw: dict[str, Any] = {"cache": cache_dir}
    if quick:
        from .ex55 import LEVELS

        ex55_kw.update(
            reference=QUICK_REFERENCE, levels=tuple(n for n in LEVELS if n < QUICK_REFERENCE)
        )
    ex55_kw.update((sizes or {}).get("5.5", {}))
    if "5.5" in examples and "5.5" in EXAMPLES:  # invalid sizes fail before any run
        from .ex55 import LEVELS, REFERENCE, check_sizes

        check_sizes(ex55_kw.get("levels", LEVELS), ex55_kw.get("reference", REFERENCE))
    for name in examples:
        if name not in EXAMPLES:
            if log is not None:
                log(f"paper: Example {name} is not available (not registered); skipped")
            continue
        mod = load_example(name)
        sub = out / _subdir(name)
        sub.mkdir(parents=True, exist_ok=True)
        kw: dict[str, Any] = {
            "solver": opts,
            "progress": progress,
            "figures": True,
            "vtk": False,
            "log": log,
        }
        kw.update(ex55_kw if name == "5.5" else (sizes or {}).get(name, {}))
        if log is not None:
            log(f"paper: {mod.TITLE} -> {sub}")
        runs[name] = _call_run(mod, sub, kw)
    elapsed = time.perf_counter() - t0
    report = out / "report.md"
    report.write_text(
        report_markdown(
            out, runs, elapsed=elapsed, quick=quick, solver=opts.method, skipped=skipped
        ),
        encoding="utf-8",
    )
    return PaperRun(
        outdir=out,
        runs=runs,
        report=report,
        elapsed=time.perf_counter() - t0,
        quick=quick,
        skipped=skipped,
    )


# ----------------------------------------------------------------------------- report
def _figures(out: Path, sub: str) -> list[str]:
    d = out / sub
    return sorted(str(p.relative_to(out)) for p in d.rglob("*.png")) if d.is_dir() else []


def _links(out: Path, sub: str, top_only: bool = False) -> list[str]:
    figs = _figures(out, sub)
    top = [f for f in figs if f.count("/") == 1]
    rest = [f for f in figs if f.count("/") > 1]
    lines = [f"- [{Path(f).name}]({f})" for f in top]
    if rest and not top_only:
        lines.append("- per run: " + ", ".join(f"[{f.split('/', 1)[1]}]({f})" for f in rest))
    return lines


def _f(v: Any, fmt: str = ".4e") -> str:
    try:
        x = float(v)
    except (TypeError, ValueError):
        return "-"
    return "-" if not math.isfinite(x) else format(x, fmt)


def _section_52(out: Path, run: ExampleRun) -> list[str]:
    d = run.details
    mw, area = d.get("max_wear", {}), d.get("worn_area", {})
    from .ex52 import DATA_SETS, PAPER_FIGURES

    lines = [
        "## Example 5.2: wear for three data sets (paper Figs. 3-5)",
        "",
        f"Report: [{_subdir('5.2')}/example_5_2.md]({_subdir('5.2')}/example_5_2.md). "
        f"Wall time {run.elapsed:.1f} s.",
        "",
        "| set | mu | kappa | our max w(T) | at x | our worn area | paper |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, ds in DATA_SETS.items():
        if name not in mw:
            continue
        lines.append(
            f"| {name} | {ds['mu']:g} | {ds['kappa']:g} | {_f(mw[name], '.5g')} "
            f"| {_f(d.get('max_wear_at', {}).get(name), '.3g')} "
            f"| {_f(area.get(name), '.5g')} | {PAPER_FIGURES[name]} (figure only, "
            "no number printed) |"
        )
    k, m = d.get("kappa_increases_wear", {}), d.get("mu_decreases_wear", {})
    lines += [
        "",
        "The paper states its findings qualitatively: more wear for larger kappa (Fig. 3 -> "
        f"Fig. 4): ours {'agrees' if k.get('max') and k.get('area') else '**disagrees**'}; "
        "less wear for larger mu (Fig. 4 -> Fig. 5): ours "
        f"{'agrees' if m.get('max') and m.get('area') else '**disagrees**'} (by the maximum "
        "and by the worn area). The paper's figures print no value, so the maxima can only "
        "be compared by eye with Figs. 3-5.",
        "",
        "Figures:",
        "",
        *_links(out, _subdir("5.2")),
        "",
    ]
    return lines


def _section_53(out: Path, run: ExampleRun) -> list[str]:
    from .ex53 import differences_markdown

    d = run.details
    rows = d.get("differences", [])
    labels = d.get("labels", {})
    lines = [
        "## Example 5.3: wear at t = 1 on four time partitions (paper Fig. 6)",
        "",
        f"Report: [{_subdir('5.3')}/example_5_3.md]({_subdir('5.3')}/example_5_3.md). "
        f"Wall time {run.elapsed:.1f} s.",
        "",
        "| partition | our max w(1) |",
        "|---|---|",
        *[f"| {labels.get(n, n)} | {_f(v, '.6g')} |" for n, v in d.get("max_wear", {}).items()],
        "",
        "Pairwise differences of w(1) (largest nodal difference, absolute and relative to the "
        "larger maximum):",
        "",
        differences_markdown(rows, labels) if rows else "(none)",
        f"The paper says the four curves are similar (Fig. 6, no numbers). Ours differ by at "
        f"most {_f(100 * d.get('max_rel_diff', float('nan')), '.2f')} %. "
        + _first_order_note(rows),
        "",
        "Figures:",
        "",
        *_links(out, _subdir("5.3")),
        "",
    ]
    return lines


def _first_order_note(rows: Sequence[dict[str, Any]]) -> str:
    """For w_k(T) = w(T) + C k: |w_16 - w_64| / |w_32 - w_64| = 3, |w_16 - w_32| / |w_32 - w_64|
    = 2 (steps 1/16, 1/32, 1/64)."""
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


def _section_54(out: Path, run: ExampleRun) -> list[str]:
    d = run.details
    sub = _subdir("5.4")
    lines = [
        "## Example 5.4: squares against general polygons (paper Figs. 7-9)",
        "",
        f"Report: [{sub}/{run.report.name if run.report else 'example_5_4.md'}]"
        f"({sub}/{run.report.name if run.report else 'example_5_4.md'}). "
        f"Wall time {run.elapsed:.1f} s.",
        "",
        "| mesh | cells | max w(T) | max u_nu(T) |",
        "|---|---|---|---|",
    ]
    meshes = d.get("meshes", {}) if isinstance(d, dict) else {}
    for name, r in run.results.items():
        info = meshes.get(name, {})
        lines.append(
            f"| {name} | {info.get('cells', r.problem.mesh.n_cells)} "
            f"| {_f(r.wear[-1].max(), '.5g')} | {_f(r.u_nu[-1].max(), '.5g')} |"
        )
    comp = d.get("comparison") if isinstance(d, dict) else None
    if isinstance(comp, dict):
        flat = [(k, v) for k, v in comp.items() if isinstance(v, (int, float))]
        if flat:
            lines += ["", "Agreement of the two meshes (see the example's report):", ""]
            lines += [f"- {k}: {_f(v, '.4g')}" for k, v in flat]
    lines += [
        "",
        'The paper shows the displacements and the contact profiles of both meshes "almost '
        'the same" (figures only, no numbers).',
        "",
        "Figures:",
        "",
        *_links(out, sub),
        "",
    ]
    return lines


def _section_55(out: Path, run: ExampleRun) -> list[str]:
    from .ex55_tables import paper_ratios, tables_markdown

    d = run.details
    tab = d["tables"]
    ref = d["reference"]
    ri = d.get("reference_info", {})
    ratios = paper_ratios(tab)

    def span(values: Sequence[float], fmt: str = ".3f") -> str:
        v = [x for x in values if np.isfinite(x)]
        return f"{min(v):{fmt}}-{max(v):{fmt}}" if v else "-"

    el = ri.get("elapsed")
    return [
        "## Example 5.5: convergence against a reference (paper Tables 1 and 2)",
        "",
        f"Report: [{_subdir('5.5')}/example_5_5.md]({_subdir('5.5')}/example_5_5.md). "
        f"Wall time {run.elapsed:.1f} s. Reference h = k = 1/{ref} "
        f"({ri.get('unknowns', '?')} unknowns; "
        + (
            "read from the cache, computed earlier in "
            if ri.get("cached")
            else "computed in this run in "
        )
        + (f"{el:.1f} s" if isinstance(el, (int, float)) else "?")
        + ")"
        + (" -- **quick mode: the paper's reference is 1/256**" if ref != 256 else "")
        + ".",
        "",
        tables_markdown(tab, ref),
        "Figures:",
        "",
        *_links(out, _subdir("5.5"), top_only=True),
        "",
        "### How our numbers compare",
        "",
        "- Table 1 (`u_H1`: each solution projected by its own Pi (3.8)-(3.10), the "
        "difference integrated over the reference cells, full H1 norm): ours / paper = "
        f"{span(ratios['u_H1'])}; our orders {span(tab['u_H1']['orders'], '.2f')} "
        "(paper 0.84-0.89).",
        "- Table 2 (`w_L2`): ours / paper = "
        f"{span(ratios['w_L2'])}; our orders {span(tab['w_L2']['orders'], '.2f')} "
        "(paper 1.02-1.12). Our wear error is almost all time-discretisation error, of the "
        "left rectangle rule (3.22); the paper's is about twice what that rule gives with "
        "k = h (docs/paper.md, `python -m vemwear.paper.ex55_study`).",
        "",
    ]


def report_markdown(
    out: Path,
    runs: dict[str, ExampleRun],
    *,
    elapsed: float,
    quick: bool,
    solver: str,
    skipped: Sequence[str] = (),
) -> str:
    """The text of ``report.md`` (see :func:`run_paper`)."""
    lines = [
        "# vemwear: the paper's numerical examples",
        "",
        "Wu, Wang, Han, *The virtual element method for a contact problem with wear and "
        "unilateral constraint*, Section 5.",
        "",
        f"vemwear {__version__}; Python {platform.python_version()} on {platform.machine()} "
        f"({os.cpu_count()} cores); solver `{solver}`; "
        f"{'quick mode (Example 5.5 reference h = k = 1/64)' if quick else 'full mode'}; "
        f"generated {time.strftime('%Y-%m-%d %H:%M:%S')}.",
        "",
        f"**Total wall time: {elapsed:.1f} s** ("
        + ", ".join(f"{n}: {r.elapsed:.1f} s" for n, r in runs.items())
        + ").",
        "",
    ]
    if skipped:
        lines += [f"Not run (not registered in this version): {', '.join(skipped)}.", ""]
    sections = {"5.2": _section_52, "5.3": _section_53, "5.4": _section_54, "5.5": _section_55}
    for name, run in runs.items():
        fn = sections.get(name)
        if fn is None:
            continue
        try:
            lines += fn(out, run)
        except (KeyError, TypeError, ValueError) as exc:  # a report section must not kill
            lines += [f"## Example {name}", "", f"(section not available: {exc})", ""]
    lines += [
        "## Differences from the paper, and why",
        "",
        "- **Contact quadrature.** The contact terms (phi_h, the constraint u_nu <= g and the "
        "wear) use nodal quadrature on Gamma_C (design note section 3); the paper does not "
        "say how it integrates them. Another quadrature gives another discrete solution "
        "(the difference is a consistency error of the method, not tested here); it should "
        "not change the orders.",
        "- **Solver tolerance.** The paper solves each step by Uzawa's iteration with an "
        "unstated tolerance; we solve the complementarity problem of every step by a "
        "semismooth Newton method to KKT residuals below 1e-10 (the Uzawa solver of vemwear "
        "gives the same solution). An Uzawa iteration stopped early would add an error of "
        "its tolerance's size to every run, reference included.",
        "- **Error definition (Example 5.5).** The paper's ||Pi_1(u_h - u_ref)|| does not say "
        "on which mesh Pi_1 acts; we project each solution on its own mesh and integrate the "
        "difference over the reference cells (docs/method.md), which reproduces Table 1. "
        "Interpolating the reference at the coarse vertices instead gives errors 3-4 times "
        "smaller (a secondary column).",
        "- **Data of Example 5.5.** mu = 0.2, kappa = 2 (Example 5.3's data set): the paper "
        "does not state them for 5.5.",
        "- **Figures.** The paper's Figs. 3-9 print no values; only the qualitative findings "
        "and the shapes can be compared.",
        "",
    ]
    return "\n".join(lines)
