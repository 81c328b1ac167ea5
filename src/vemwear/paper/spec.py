"""An example of the paper as data: what it solves, computes, compares, writes and reports.

An :class:`Example` names its problems (a function of the example's parameters, whose
defaults are the paper's sizes), the hooks that compute what the example is about
(a reference solution, differences between runs, error tables), the files it writes
besides the standard output of every run (:class:`OutputFile`), the rows and
sections of its Markdown report (:class:`Column`, section functions), its section of
the ``vemwear paper`` report and its headline numbers (pinned by
``tests/test_paper_numbers.py``). :func:`vemwear.paper.driver.run_example` runs any of
them; the hooks receive the :class:`Context` of the run.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ..simulate import Problem, Result, SolverOptions
    from . import ExampleRun

__all__ = ["CITATION", "Column", "Context", "Example", "OutputFile", "text_output"]

#: The paper, as cited at the top of every report.
CITATION = (
    "Wu, Wang, Han, *The virtual element method for a contact problem with wear and "
    "unilateral constraint*, Section 5"
)


@dataclass
class Context:
    """One run of an example: its inputs, and what the driver and the hooks produced.

    Attributes
    ----------
    example : Example
        The example being run.
    outdir : Path
        The directory written into.
    params : dict
        The example's parameters (its defaults updated by the caller's).
    solver : SolverOptions
        Step solver of every run.
    figures, vtk, progress : bool
        Whether figures and VTK series are written and progress bars shown.
    log : callable or None
        Receives lines of text.
    problems, results : dict
        The example's problems and their runs, by name.
    details : dict
        The example's numbers (from its ``analyse`` hook), returned in
        :attr:`vemwear.paper.ExampleRun.details`.
    state : dict
        Working data shared by the hooks (a reference solution, error histories).
    files : list of str
        Files written, relative to ``outdir``.
    timings : dict
        Wall times of the stages, in seconds.
    """

    example: Example
    outdir: Path
    params: dict[str, Any]
    solver: SolverOptions
    figures: bool = True
    vtk: bool = True
    progress: bool = False
    log: Callable[[str], None] | None = None
    problems: dict[str, Problem] = field(default_factory=dict)
    results: dict[str, Result] = field(default_factory=dict)
    details: dict[str, Any] = field(default_factory=dict)
    state: dict[str, Any] = field(default_factory=dict)
    files: list[str] = field(default_factory=list)
    timings: dict[str, float] = field(default_factory=dict)
    started: float = field(default_factory=time.perf_counter)

    def say(self, text: str) -> None:
        """Pass one line to ``log``, if any."""
        if self.log is not None:
            self.log(text)

    def elapsed(self) -> float:
        """Seconds since the run started."""
        return time.perf_counter() - self.started


@dataclass(frozen=True)
class OutputFile:
    """A file an example writes at the top of its output directory.

    Attributes
    ----------
    name : str
        File name.
    description : str
        One line for the report's list of files.
    write : callable
        ``write(ctx, path)`` writes the file.
    figure : bool
        A figure: written only when figures are asked for.
    when : callable, optional
        ``when(ctx)``: whether to write it at all (default: always).
    """

    name: str
    description: str
    write: Callable[[Context, Path], None]
    figure: bool = False
    when: Callable[[Context], bool] | None = None


def text_output(name: str, description: str, render: Callable[[Context], str]) -> OutputFile:
    """An :class:`OutputFile` holding the text ``render(ctx)`` (UTF-8).

    Parameters
    ----------
    name, description : str
        As for :class:`OutputFile`.
    render : callable
        ``render(ctx) -> str``.
    """

    def write(ctx: Context, path: Path) -> None:
        path.write_text(render(ctx), encoding="utf-8")

    return OutputFile(name, description, write)


@dataclass(frozen=True)
class Column:
    """A column of the report's table of runs (one row per run).

    Attributes
    ----------
    header : str
    value : callable
        ``value(ctx, name, result)``: the cell's text.
    """

    header: str
    value: Callable[[Context, str, Result], str]


def _final_time(problem: Problem) -> tuple[float, ...]:
    return (float(problem.time.T),)


def _no_extra(ctx: Context, name: str, problem: Problem) -> dict[str, Any]:
    return {}


@dataclass(frozen=True)
class Example:
    """One of the paper's examples, as data for :func:`vemwear.paper.driver.run_example`.

    Attributes
    ----------
    name : str
        The example's number, e.g. ``"5.2"``.
    heading : str
        The report's title after ``Example 5.N:``.
    parameters : mapping
        The keyword arguments the example takes and their defaults, the paper's values
        (mesh divisions, time steps, levels, ...).
    problems : callable
        ``problems(**params) -> {name: Problem}``, called with the parameters its
        signature names.
    setup : callable
        ``setup(ctx)``: the report's paragraph on the data, sizes and solver.
    runs_description : str
        What each run's subdirectory holds, for the report's list of files.
    columns : tuple of Column
        The report's table of runs (none: no table).
    sections : tuple of callables
        ``section(ctx) -> list of lines``: the report's sections after the table.
    outputs : tuple of OutputFile
        The example's own files, in the order they are written.
    check : callable, optional
        ``check(params)`` raises ``ValueError`` for invalid parameters, before any solve.
    prepare : callable, optional
        ``prepare(ctx)`` before the runs (e.g. a reference solution).
    after_run : callable, optional
        ``after_run(ctx, name, result)`` after each run's output is written.
    analyse : callable, optional
        ``analyse(ctx) -> details``: the example's numbers, after every run.
    run_label : callable, optional
        ``run_label(ctx, name, problem)``: the log line before each run.
    run_extra : callable
        ``run_extra(ctx, name, problem)``: stored under ``inputs.extra`` of each run's
        ``summary.json`` (with ``example``).
    figure_times : callable
        ``figure_times(problem)``: the times of each run's contact-profile figure.
    run_figures : bool
        Whether the runs get the figures of ``vemwear run``.
    vtk : bool
        Default of the runs' VTK series.
    store : str
        Which displacements :func:`vemwear.simulate` keeps (``"all"``, ``"final"``).
    quick : mapping
        Parameters of ``vemwear paper --quick``.
    headlines : mapping
        ``{name: value(ctx)}``: the numbers that ``tests/test_paper_numbers.py`` pins.
    paper_section : callable, optional
        ``paper_section(out, sub, run) -> list of lines``: the example's section of the
        ``vemwear paper`` report (``sub``: the example's subdirectory of ``out``).
    description : str
        One line, from :data:`vemwear.paper.DESCRIPTIONS`.
    """

    name: str
    heading: str
    parameters: Mapping[str, Any]
    problems: Callable[..., dict[str, Problem]]
    setup: Callable[[Context], str]
    runs_description: str
    columns: tuple[Column, ...] = ()
    sections: tuple[Callable[[Context], list[str]], ...] = ()
    outputs: tuple[OutputFile, ...] = ()
    check: Callable[[Mapping[str, Any]], None] | None = None
    prepare: Callable[[Context], None] | None = None
    after_run: Callable[[Context, str, Result], None] | None = None
    analyse: Callable[[Context], dict[str, Any]] | None = None
    run_label: Callable[[Context, str, Problem], str] | None = None
    run_extra: Callable[[Context, str, Problem], dict[str, Any]] = _no_extra
    figure_times: Callable[[Problem], tuple[float, ...]] = _final_time
    run_figures: bool = True
    vtk: bool = True
    store: str = "all"
    quick: Mapping[str, Any] = field(default_factory=dict)
    headlines: Mapping[str, Callable[[Context], float]] = field(default_factory=dict)
    paper_section: Callable[[Path, str, ExampleRun], list[str]] | None = None

    @property
    def title(self) -> str:
        """``"Example 5.N"``."""
        return f"Example {self.name}"

    @property
    def description(self) -> str:
        """The one-line description of :data:`vemwear.paper.DESCRIPTIONS`."""
        from . import DESCRIPTIONS

        return DESCRIPTIONS[self.name]

    @property
    def report_name(self) -> str:
        """The report's file name, ``example_5_N.md``."""
        return f"example_{self.name.replace('.', '_')}.md"
