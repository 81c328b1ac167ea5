"""``vemwear paper``: run the paper's examples and write one report beside the paper's numbers.

:func:`run_paper` runs Examples 5.2, 5.3, 5.4 and 5.5 (those registered in
:data:`vemwear.paper.EXAMPLES`) through the driver
(:func:`vemwear.paper.driver.run_example`) into the subdirectories ``example_5_2/``, ...
of an output directory and writes ``report.md``: each example's section (its
``paper_section``: every figure linked, our numbers beside the paper's, Tables 1 and 2
side by side), a discussion of the differences and the wall times. ``quick=True``
runs each example with its ``quick`` parameters (Example 5.5: the reference
h = k = 1/64 instead of 1/256, the levels h = k = 1/4 ... 1/32) and skips nothing.
"""

from __future__ import annotations

import os
import platform
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .. import __version__
from ..simulate import SolverOptions
from . import EXAMPLES, ExampleRun, load_example
from .driver import resolve_parameters, run_example
from .markdown import subdir
from .spec import Example

__all__ = ["PAPER_ORDER", "PaperRun", "report_markdown", "run_paper"]

_DRIVER_OPTIONS = ("solver", "progress", "figures", "vtk", "log")

#: The examples of the report, in order (those not registered are skipped).
PAPER_ORDER: tuple[str, ...] = ("5.2", "5.3", "5.4", "5.5")


@dataclass
class PaperRun:
    """What :func:`run_paper` produced.

    Attributes
    ----------
    outdir : Path
        The directory written into.
    runs : dict of str to ExampleRun
        By example number.
    report : Path
        ``report.md``.
    elapsed : float
        Total wall time in seconds.
    quick : bool
        Whether the examples ran with their ``quick`` parameters.
    skipped : list of str
        Examples of :data:`PAPER_ORDER` that are not registered.
    """

    outdir: Path
    runs: dict[str, ExampleRun]
    report: Path
    elapsed: float
    quick: bool
    skipped: list[str] = field(default_factory=list)


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
        Run each example with its ``quick`` parameters (Example 5.5 against the reference
        h = k = 1/64 instead of 1/256, so with the levels h = k = 1/4 ... 1/32).
    solver : SolverOptions or str
        Step solver of every run.
    cache : path, optional
        Cache directory of the examples that take one (Example 5.5's reference; default:
        the user's cache directory, :func:`vemwear.util.cache.user_cache_dir`).
    examples : sequence of str
        Which examples (default: all of :data:`PAPER_ORDER` that are registered).
    progress : bool
        Progress bars.
    log : callable, optional
        Receives lines of text.
    sizes : dict, optional
        Parameters and driver options of each example by number (smaller sizes for
        tests), e.g. ``{"5.3": {"divisions": (8, 4), "base_steps": 8}}``.

    Raises
    ------
    TypeError, ValueError
        For invalid parameters of an example, before any run.

    Returns
    -------
    PaperRun
    """
    t0 = time.perf_counter()
    out = Path(outdir)
    opts = SolverOptions(method=solver) if isinstance(solver, str) else solver
    if cache is None:
        from ..util.cache import user_cache_dir

        cache = user_cache_dir()
    cache_dir = Path(cache)
    skipped = [n for n in examples if n not in EXAMPLES]
    plan: dict[str, tuple[Example, dict[str, Any]]] = {}
    for name in examples:  # invalid sizes fail before any run
        if name not in EXAMPLES:
            continue
        ex: Example = load_example(name).EXAMPLE
        kw: dict[str, Any] = {"figures": True, "vtk": False}
        if "cache" in ex.parameters:
            kw["cache"] = cache_dir
        if quick:
            kw.update(ex.quick)
        kw.update((sizes or {}).get(name, {}))
        params = {k: v for k, v in kw.items() if k not in _DRIVER_OPTIONS}
        if ex.check is not None:
            ex.check(resolve_parameters(ex, params))
        plan[name] = (ex, kw)
    runs: dict[str, ExampleRun] = {}
    for name in examples:
        if name not in plan:
            if log is not None:
                log(f"paper: Example {name} is not available (not registered); skipped")
            continue
        ex, kw = plan[name]
        sub = out / subdir(name)
        sub.mkdir(parents=True, exist_ok=True)
        if log is not None:
            log(f"paper: {ex.title} -> {sub}")
        runs[name] = run_example(ex, sub, solver=opts, progress=progress, log=log, **kw)
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


def report_markdown(
    out: Path,
    runs: dict[str, ExampleRun],
    *,
    elapsed: float,
    quick: bool,
    solver: str,
    skipped: Sequence[str] = (),
) -> str:
    """The text of ``report.md`` (see :func:`run_paper`).

    Parameters
    ----------
    out : Path
        The output directory (figure links are relative to it).
    runs : dict of str to ExampleRun
        The examples' runs, by number.
    elapsed : float
        Total wall time in seconds.
    quick : bool
        Whether the examples ran with their ``quick`` parameters.
    solver : str
        The step solver's method.
    skipped : sequence of str
        Examples not run.
    """
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
    for name, run in runs.items():
        section = load_example(name).EXAMPLE.paper_section
        if section is None:
            continue
        try:
            lines += section(out, subdir(name), run)
        except (KeyError, TypeError, ValueError) as exc:  # a report section must not kill
            lines += [f"## Example {name}", "", f"(section not available: {exc})", ""]
    lines += [
        "## Differences from the paper, and why",
        "",
        "- **Contact quadrature.** The contact terms (phi_h, the constraint u_nu <= g and the "
        "wear) use nodal quadrature on Gamma_C (docs/method.md); the paper does not "
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
