"""The numerical examples of the paper (Wu, Wang, Han, Section 5), defined in Python.

Every example lives in a sibling module (``ex52`` for Example 5.2, later ``ex53``,
``ex54``, ``ex55``) registered in :data:`EXAMPLES`, and follows one pattern:

``NAME``, ``TITLE``, ``DESCRIPTION``
    The example's number (``"5.2"``), a title and a one-line description (shown by
    ``vemwear example --help``).
``problems(**size) -> dict[str, Problem]``
    The example's problems by name (``set1``, ``set2``, ...); size parameters (mesh
    divisions, time steps) default to the paper's values so that tests can build
    smaller versions.
``run(outdir, *, solver="newton", progress=False, figures=True, vtk=True, log=None,
**size) -> ExampleRun``
    Solve every problem and write into the existing directory ``outdir``: one
    subdirectory per problem with the standard output of ``vemwear run``, plus the
    example's own figures and a Markdown report at the top.

``vemwear example NAME -o OUTDIR`` runs ``run`` inside an atomic output directory.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ..simulate import Result

__all__ = ["EXAMPLES", "ExampleRun", "available_examples", "load_example"]

#: Example number -> module name in this package.
EXAMPLES: dict[str, str] = {
    "5.2": "ex52",
    "5.3": "ex53",
    "5.4": "ex54",
    "5.5": "ex55",
}


@dataclass
class ExampleRun:
    """What an example's ``run`` produced.

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
        Example-specific numbers (e.g. maximal wear per data set, the paper's findings).
    elapsed : float
        Wall time of ``run`` in seconds.
    """

    name: str
    outdir: Path
    results: dict[str, Result]
    files: list[str] = field(default_factory=list)
    report: Path | None = None
    details: dict[str, Any] = field(default_factory=dict)
    elapsed: float = 0.0


def load_example(name: str) -> ModuleType:
    """The module of example ``name`` (e.g. ``"5.2"``).

    Raises
    ------
    KeyError
        If there is no such example; the message lists the available ones.
    """
    if name not in EXAMPLES:
        raise KeyError(f"unknown example {name!r}; available: {', '.join(EXAMPLES)}")
    return importlib.import_module(f"{__name__}.{EXAMPLES[name]}")


def available_examples() -> dict[str, str]:
    """``{number: one-line description}`` of every registered example."""
    out = {}
    for name in EXAMPLES:
        mod = load_example(name)
        out[name] = f"{mod.TITLE}: {mod.DESCRIPTION}"
    return out
