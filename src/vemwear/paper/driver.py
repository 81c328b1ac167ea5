"""The one driver of the paper's examples: solve, write each run's output, compute, report.

:func:`run_example` runs any :class:`~vemwear.paper.spec.Example`: it validates the
parameters, builds the problems, solves each with :func:`vemwear.simulate`, writes its
standard output (:func:`vemwear.post.outputs.write_outputs`) into a subdirectory named
after it, calls the example's hooks (a reference, differences, error tables), writes
the example's files and figures, and the Markdown report ``example_5_N.md``:

.. code-block:: text

    # Example 5.N: heading
    the citation, the setup paragraph, the table of runs, the example's sections,
    ## Files  (every file written, with its description)

``vemwear example NAME`` and ``vemwear paper`` (:mod:`vemwear.paper.report`) go
through it.
"""

from __future__ import annotations

import inspect
import os
import time
from collections.abc import Callable, Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any

from ..simulate import SolverOptions
from . import ExampleRun
from .spec import CITATION, Context, Example

__all__ = ["call_with", "render_report", "resolve_parameters", "run_example"]


def call_with(fn: Callable[..., Any], params: Mapping[str, Any], *args: Any) -> Any:
    """Call ``fn(*args, **kw)`` with the entries of ``params`` that its signature names."""
    names = inspect.signature(fn).parameters
    return fn(*args, **{k: v for k, v in params.items() if k in names})


def resolve_parameters(example: Example, given: Mapping[str, Any]) -> dict[str, Any]:
    """The example's parameters: its defaults updated by ``given``.

    Raises
    ------
    TypeError
        For a parameter the example does not take (the message lists those it takes).
    """
    unknown = sorted(set(given) - set(example.parameters))
    if unknown:
        raise TypeError(
            f"{example.title}: unknown parameter(s) {', '.join(unknown)}; it takes "
            f"{', '.join(example.parameters)} (and solver, progress, figures, vtk, log)"
        )
    return {**example.parameters, **given}


def run_example(
    example: Example,
    outdir: str | os.PathLike[str],
    *,
    solver: SolverOptions | str = "newton",
    progress: bool = False,
    figures: bool = True,
    vtk: bool | None = None,
    log: Callable[[str], None] | None = None,
    order: int = 1,
    **parameters: Any,
) -> ExampleRun:
    """Run an example and write everything into the existing directory ``outdir``.

    Parameters
    ----------
    example : Example
        The example's data (``vemwear.paper.ex52.EXAMPLE``, ...).
    outdir : path
        An existing directory (``vemwear example`` passes the temporary one of an
        atomic output directory).
    solver : SolverOptions or str
        Step solver of every run (default: condensed Newton).
    progress : bool
        Show a progress bar per run.
    figures : bool
        Write the figures (the runs' and the example's); reports and data always.
    vtk : bool, optional
        Write the runs' VTK series (default: the example's choice).
    log : callable, optional
        Receives one line of text per stage.
    order : int
        The order k of the virtual element space of every problem (1: the paper's).
    **parameters
        The example's parameters (:attr:`Example.parameters`: sizes, levels, ...);
        the paper's values by default.

    Returns
    -------
    ExampleRun
        The runs, the files written, the report, the example's numbers (``details``)
        and its headline numbers.

    Raises
    ------
    TypeError
        For a parameter the example does not take.
    ValueError
        For invalid parameters (before any solve).
    ConvergenceError
        If a step problem does not converge.
    """
    ex = example
    params = resolve_parameters(ex, parameters)
    if ex.check is not None:
        ex.check(params)
    opts = SolverOptions(method=solver) if isinstance(solver, str) else solver
    ctx = Context(
        example=ex,
        outdir=Path(outdir),
        params=params,
        solver=opts,
        figures=figures,
        vtk=ex.vtk if vtk is None else vtk,
        progress=progress,
        log=log,
    )
    with _timed(ctx, "problems"):
        ctx.problems = call_with(ex.problems, params)
        if order != 1:
            ctx.problems = {n: replace(pr, order=order) for n, pr in ctx.problems.items()}
    if ex.prepare is not None:
        ex.prepare(ctx)
    for name, pr in ctx.problems.items():
        _solve_and_write(ctx, name, pr)
    if ex.analyse is not None:
        with _timed(ctx, "analysis"):
            ctx.details.update(ex.analyse(ctx))
    for f in ex.outputs:
        if (f.figure and not figures) or (f.when is not None and not f.when(ctx)):
            continue
        with _timed(ctx, f"write {f.name}"):
            f.write(ctx, ctx.outdir / f.name)
        ctx.files.append(f.name)
    headlines = {k: float(fn(ctx)) for k, fn in ex.headlines.items()}
    report = ctx.outdir / ex.report_name
    report.write_text(render_report(ctx), encoding="utf-8")
    ctx.files.append(report.name)
    return ExampleRun(
        name=ex.name,
        outdir=ctx.outdir,
        results=ctx.results,
        files=ctx.files,
        report=report,
        details=ctx.details,
        elapsed=ctx.elapsed(),
        headlines=headlines,
    )


class _timed:
    """``with _timed(ctx, key):`` adds the block's wall time to ``ctx.timings[key]``."""

    def __init__(self, ctx: Context, key: str) -> None:
        self.ctx, self.key = ctx, key

    def __enter__(self) -> None:
        self.t0 = time.perf_counter()

    def __exit__(self, *exc: object) -> None:
        dt = time.perf_counter() - self.t0
        self.ctx.timings[self.key] = self.ctx.timings.get(self.key, 0.0) + dt


def _solve_and_write(ctx: Context, name: str, pr: Any) -> None:
    from ..post.outputs import write_outputs
    from ..simulate import simulate

    ex = ctx.example
    label = ex.run_label(ctx, name, pr) if ex.run_label is not None else name
    ctx.say(f"{ex.title}, {label}")
    with _timed(ctx, f"solve {name}"):
        res = simulate(pr, ctx.solver, progress=ctx.progress, store=ex.store)
    ctx.results[name] = res
    with _timed(ctx, f"write {name}"):
        sub = ctx.outdir / name
        sub.mkdir(parents=True, exist_ok=True)
        extra = {"example": ex.name, **ex.run_extra(ctx, name, pr)}
        written = write_outputs(
            res,
            sub,
            times=ex.figure_times(pr),
            figures=ctx.figures and ex.run_figures,
            vtk=ctx.vtk,
            extra=extra,
        )
    ctx.files += [f"{name}/{f}" for group in written.values() for f in group]
    if ex.after_run is not None:
        ex.after_run(ctx, name, res)


def render_report(ctx: Context) -> str:
    """The example's Markdown report (module docstring)."""
    ex = ctx.example
    lines = [f"# {ex.title}: {ex.heading}", "", f"{CITATION}, {ex.title}.", "", ex.setup(ctx), ""]
    if ex.columns and ctx.results:
        lines += [
            "| " + " | ".join(c.header for c in ex.columns) + " |",
            "|" + "---|" * len(ex.columns),
            *(
                "| " + " | ".join(c.value(ctx, name, r) for c in ex.columns) + " |"
                for name, r in ctx.results.items()
            ),
            "",
        ]
    for section in ex.sections:
        lines += section(ctx)
    written = set(ctx.files)
    lines += [
        "## Files",
        "",
        *(f"- `{f.name}`: {f.description}" for f in ex.outputs if f.name in written),
        "- " + ", ".join(f"`{n}/`" for n in ctx.results) + f": {ex.runs_description}",
        "",
    ]
    return "\n".join(lines)
