"""Example 5.5 of the paper: errors and convergence orders against a fine reference.

Data of Example 5.2 on Omega = (0, 2) x (0, 1) with uniform squares (divisions
(2/h, 1/h), Gamma_C in 2/h parts), T = 1 and uniform time steps k = h, for
h = k = 1/4, 1/8, ..., 1/64, against the reference solution h = k = 1/256
(paper Tables 1 and 2). The paper does not state mu and kappa for this example; we
use Example 5.3's (= Example 5.2's data set 1): mu = 0.2, kappa = 2, v* = (1, 0),
the data set of every other single-data-set example of the paper (5.3, 5.4).

Errors (:mod:`vemwear.post.compare`; docs/method.md), relative, at the common time
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
space and time parts. The headline numbers are the first rows (h = k = 1/4) of
Tables 1 and 2.

The reference is computed with ``simulate(..., store=[common times])`` so that only
the needed displacements are recovered, and cached on disk (``.npz`` plus a ``.json``
with the hash of its inputs) in a cache directory; it is reused whenever its inputs
(the problem's fingerprint, reference size, solver method and tolerance) did not
change and it holds the displacement at every needed time.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from ..post.compare import Comparison
from . import DESCRIPTIONS, ExampleRun
from . import ex55_report as R
from .driver import run_example
from .ex55_reference import (
    CACHE_FORMAT,
    KAPPA,
    LEVELS,
    MU,
    NAME,
    QUICK_REFERENCE,
    REFERENCE,
    TITLE,
    cache_key,
    check_sizes,
    common_times,
    default_cache_dir,
    problem,
    problems,
    reference_solution,
)
from .ex55_tables import (
    PAPER_TABLE1,
    PAPER_TABLE2,
    error_tables,
    paper_ratios,
    tables_csv,
    tables_markdown,
)
from .spec import Context, Example, OutputFile, text_output

__all__ = [
    "CACHE_FORMAT",
    "DESCRIPTION",
    "EXAMPLE",
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

DESCRIPTION = DESCRIPTIONS[NAME]


# ----------------------------------------------------------------------------- the example
def _check(params: Mapping[str, Any]) -> None:
    check_sizes(params["levels"], params["reference"])


def _prepare(ctx: Context) -> None:
    lv, ref = check_sizes(ctx.params["levels"], ctx.params["reference"])
    cache = ctx.params["cache"]
    cache_dir = (
        default_cache_dir(ctx.outdir)
        if cache is True
        else (None if cache is False or cache is None else Path(cache))
    )
    sol, info = reference_solution(
        ref,
        common_times(lv),
        solver=ctx.solver,
        cache_dir=cache_dir,
        progress=ctx.progress,
        log=ctx.log,
    )
    ctx.state.update(levels=lv, reference=ref, reference_info=info)
    ctx.state["comparison"] = Comparison(sol)


def _analyse(ctx: Context) -> dict[str, Any]:
    st = ctx.state
    # all the runs at once: the reference's projection at a level serves every run; the
    # tables take the secondary variants at t = T only
    names = list(ctx.results)
    runs = [ctx.results[n] for n in names]
    histories = st["comparison"].errors_many(runs, secondary="final")
    tables = error_tables({int(n[1:]): h for n, h in zip(names, histories, strict=True)})
    study = None
    if ctx.params["study"]:
        from .ex55_study import wear_error_study

        study = wear_error_study(
            levels=st["levels"],
            reference=st["reference"],
            solver=ctx.solver,
            comparison=st["comparison"],
            coarse=ctx.results,
            log=ctx.log,
        )
    return {
        "mu": MU,
        "kappa": KAPPA,
        "tables": tables,
        "reference": st["reference"],
        "reference_info": st["reference_info"],
        "levels": list(st["levels"]),
        "paper": {"table1": PAPER_TABLE1, "table2": PAPER_TABLE2},
        "ratios": paper_ratios(tables),
        "study": study,
        "summary": tables_markdown(tables, st["reference"]).splitlines(),
    }


def _table(number: int) -> Callable[[Context], str]:
    def render(ctx: Context) -> str:
        md = tables_markdown(ctx.details["tables"], ctx.details["reference"])
        t1, t2 = md.split("### Table 2")
        return (t1 if number == 1 else "### Table 2" + t2).strip() + "\n"

    return render


def _study_md(ctx: Context) -> str:
    from .ex55_study import study_markdown

    return study_markdown(ctx.details["study"])


def _write_study(ctx: Context, path: Path) -> None:
    path.write_text(_study_md(ctx), encoding="utf-8")


def _convergence(ctx: Context, path: Path) -> None:
    from .ex55_tables import plot_tables

    plot_tables(ctx.details["tables"], ctx.details["reference"], path, TITLE)


EXAMPLE = Example(
    name=NAME,
    heading="convergence against a reference solution",
    parameters={"levels": LEVELS, "reference": REFERENCE, "cache": True, "study": False},
    quick={
        "reference": QUICK_REFERENCE,
        "levels": tuple(n for n in LEVELS if n < QUICK_REFERENCE),
    },
    problems=problems,
    check=_check,
    prepare=_prepare,
    analyse=_analyse,
    setup=R.setup,
    sections=(R.errors_section,),
    runs_description="`result.npz` and `summary.json` of every coarse run.",
    run_label=lambda ctx, name, pr: f"{name}: h = k = 1/{name[1:]}",
    run_extra=lambda ctx, name, pr: {"inv_h": int(name[1:]), "data": {"mu": MU, "kappa": KAPPA}},
    run_figures=False,
    vtk=False,
    store="all",
    outputs=(
        text_output("table1.md", "Table 1, ours beside the paper's.", _table(1)),
        text_output("table2.md", "Table 2, ours beside the paper's.", _table(2)),
        text_output(
            "errors.csv",
            "every error variant and its order, with the paper's numbers.",
            lambda ctx: tables_csv(ctx.details["tables"]),
        ),
        OutputFile(
            "convergence.png",
            "log-log plot of the errors, with the paper's.",
            _convergence,
            figure=True,
        ),
        OutputFile(
            "table2_study.md",
            "the space / time split of the wear error.",
            _write_study,
            when=lambda ctx: ctx.details["study"] is not None,
        ),
    ),
    headlines={
        "u_H1.h4": lambda ctx: R.first_row(ctx, "u_H1"),
        "w_L2.h4": lambda ctx: R.first_row(ctx, "w_L2"),
    },
    paper_section=R.paper_section,
)


def run(outdir: str | Path, **options: Any) -> ExampleRun:
    """Compute Tables 1 and 2 and write them into the existing directory ``outdir``.

    Writes ``h{n}/`` for every level (``result.npz``, ``summary.json``; the VTK series if
    asked), ``table1.md``, ``table2.md``, ``errors.csv``, ``convergence.png``,
    ``table2_study.md`` (with ``study=True``) and ``example_5_5.md``.

    Parameters
    ----------
    outdir : path
        An existing directory.
    **options
        The example's parameters: ``levels`` (``1/h = 1/k`` of the coarse runs; paper:
        4, 8, 16, 32, 64), ``reference`` (``1/h = 1/k`` of the reference; paper: 256; a
        multiple of every level), ``cache`` (cache directory of the reference; True:
        :func:`default_cache_dir` of ``outdir``; False or None: no cache), ``study``
        (also split the wear error into its space and time parts,
        :func:`vemwear.paper.ex55_study.wear_error_study`, reusing the reference); and
        the driver's ``solver``, ``progress``, ``figures`` (``convergence.png``; the
        coarse runs get no figures), ``vtk`` (off by default), ``log``
        (:func:`vemwear.paper.driver.run_example`).

    Returns
    -------
    ExampleRun
        ``results``: the coarse runs by name (``h4``, ...); ``details``: ``tables``
        (:func:`~vemwear.paper.ex55_tables.error_tables`), ``ratios`` (ours / paper),
        ``reference`` (1/h), ``reference_info`` (cached?, its run time), ``paper``
        (Tables 1 and 2), ``study`` (or None) and ``summary`` (the tables' lines).
    """
    return run_example(EXAMPLE, outdir, **options)
