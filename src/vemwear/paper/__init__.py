"""The numerical examples of the paper (Wu, Wang, Han, Section 5), as data plus one driver.

Each example is a module (``ex52`` for Example 5.2, ... ``ex55``) registered in
:data:`EXAMPLES` that holds the example's data: its problems as functions of its
sizes (the paper's by default), what it computes and compares, its figures, its
report rows and its headline numbers, gathered in one
:class:`~vemwear.paper.spec.Example` called ``EXAMPLE``. The one driver
:func:`vemwear.paper.driver.run_example` runs any of them (each module's ``run`` is
that call); :func:`vemwear.paper.report.run_paper` runs them all and writes the report
beside the paper's numbers. ``vemwear example NAME`` and ``vemwear paper`` go through
them. The paper's examples are a client of the library: nothing here imports the
command line.

Importing this package is cheap: :func:`available_examples` reads the registry only.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ..simulate import Result

__all__ = [
    "DESCRIPTIONS",
    "EXAMPLES",
    "ExampleRun",
    "available_examples",
    "load_example",
    "run_example",
]

#: Example number -> module name in this package.
EXAMPLES: dict[str, str] = {
    "5.2": "ex52",
    "5.3": "ex53",
    "5.4": "ex54",
    "5.5": "ex55",
    "3d": "ex3d",
    "hertz": "hertz",
}

#: Example number -> one-line description (``vemwear example --list``).
DESCRIPTIONS: dict[str, str] = {
    "5.2": "wear and penetration for (mu, kappa) = (0.2, 2), (0.2, 10), (0.6, 10) "
    "(paper Figs. 3-5)",
    "5.3": "wear at t = 1 for uniform k = 1/64, alternating 1/128, 3/128, uniform 1/32 "
    "and 1/16 (paper Fig. 6)",
    "5.4": "2048 squares against 2048 Voronoi polygons: u_1, u_2, u_nu and wear at t = 1 "
    "(paper Figs. 7-9), with a Voronoi refinement study",
    "5.5": "relative errors and orders for h = k = 1/4 ... 1/64 against h = k = 1/256 "
    "(paper Tables 1 and 2)",
    "3d": "the block in 3D: 1024 hexahedra against 1024 Voronoi polyhedra, and wear errors "
    "for h = k = 1/2, 1/4, 1/8 against 1/16 (not in the paper)",
    "hertz": "2D line contact and 3D sphere under load control against Hertz's closed forms, "
    "errors against refinement (not in the paper)",
}


@dataclass
class ExampleRun:
    """What a run of an example produced.

    Attributes
    ----------
    name : str
        The example number, e.g. ``"5.2"``.
    outdir : Path
        The directory written into.
    results : dict of str to Result
        The runs, by problem name.
    files : list of str
        Files written, relative to ``outdir``.
    report : Path or None
        The Markdown report.
    details : dict
        Example-specific numbers (e.g. maximal wear per data set, error tables).
    elapsed : float
        Wall time of the run in seconds.
    headlines : dict of str to float
        The example's headline numbers (those ``tests/test_paper_numbers.py`` pins).
    """

    name: str
    outdir: Path
    results: dict[str, Result]
    files: list[str] = field(default_factory=list)
    report: Path | None = None
    details: dict[str, Any] = field(default_factory=dict)
    elapsed: float = 0.0
    headlines: dict[str, float] = field(default_factory=dict)


def load_example(name: str) -> ModuleType:
    """The module of example ``name`` (e.g. ``"5.2"``); its data is ``module.EXAMPLE``.

    Parameters
    ----------
    name : str
        The example number.

    Raises
    ------
    KeyError
        If there is no such example; the message lists the available ones.
    """
    if name not in EXAMPLES:
        raise KeyError(f"unknown example {name!r}; available: {', '.join(EXAMPLES)}")
    return importlib.import_module(f"{__name__}.{EXAMPLES[name]}")


def available_examples() -> dict[str, str]:
    """``{number: "Example 5.N: one-line description"}`` of every registered example.

    Reads the registry only (no example module is imported), so it is cheap.
    """
    return {name: f"Example {name}: {DESCRIPTIONS[name]}" for name in EXAMPLES}


def run_example(name: str, outdir: str | Path, **options: Any) -> ExampleRun:
    """Run example ``name`` through the driver (:func:`vemwear.paper.driver.run_example`).

    Parameters
    ----------
    name : str
        The example number, e.g. ``"5.2"``.
    outdir : path
        An existing directory to write into.
    **options
        The driver's options (``solver``, ``progress``, ``figures``, ``vtk``, ``log``)
        and the example's parameters (its sizes).

    Returns
    -------
    ExampleRun
    """
    return load_example(name).run(outdir, **options)  # type: ignore[no-any-return]
