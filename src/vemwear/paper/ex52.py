"""Example 5.2 of the paper: how the friction and wear coefficients change the wear.

Data (paper Section 5; docs/method.md): Omega = (0, 2) x (0, 1),
Gamma_D = {0} x [0, 1], Gamma_N = top and right sides, Gamma_C = bottom side;
lam = eta = 4, T = 1, u^0 = 0, p(r) = 0.4 r_+, f1 = (0, -0.06), f2 = 0, g = 0.1,
v* = (1, 0); k = 1/64 and Gamma_C in 32 equal parts (32 x 16 squares, h = 1/16).
The three data sets are

1. mu = 0.2, kappa = 2   (paper Fig. 3)
2. mu = 0.2, kappa = 10  (paper Fig. 4)
3. mu = 0.6, kappa = 10  (paper Fig. 5)

and the figures show the wear w and the penetration u_nu - w on Gamma_C at
t = 0.25, 0.5, 0.75, 1. The paper observes that wear grows in time, that it grows
with kappa (Fig. 3 -> Fig. 4) and that it decreases when mu grows (Fig. 4 -> Fig. 5).
The headline numbers are the maximal wear at t = 1 of the three sets.

The same problems are described by the configuration files
``vemwear/examples/example_5_2_set{1,2,3}.toml``; a test checks that both give the
same discrete data.
"""

from __future__ import annotations

import shutil
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..contact import LinearCompliance
from ..mesh import Mesh, rectangle_squares, tag_rectangle
from ..simulate import Problem, Result, TimeGrid
from ..vem import Material
from . import DESCRIPTIONS, ExampleRun
from .driver import run_example
from .markdown import links, num, yes
from .spec import Column, Context, Example, OutputFile

__all__ = [
    "DATA_SETS",
    "DESCRIPTION",
    "DIVISIONS",
    "EXAMPLE",
    "NAME",
    "PAPER_FIGURES",
    "STEPS",
    "TIMES",
    "TITLE",
    "findings",
    "mesh",
    "problem",
    "problems",
    "run",
]

NAME = "5.2"
TITLE = f"Example {NAME}"
DESCRIPTION = DESCRIPTIONS[NAME]

#: The three data sets of the paper, by subdirectory name.
DATA_SETS: dict[str, dict[str, float]] = {
    "set1": {"mu": 0.2, "kappa": 2.0},
    "set2": {"mu": 0.2, "kappa": 10.0},
    "set3": {"mu": 0.6, "kappa": 10.0},
}
#: Paper figure of each data set.
PAPER_FIGURES: dict[str, str] = {"set1": "fig3.png", "set2": "fig4.png", "set3": "fig5.png"}
#: Times of the paper's figures.
TIMES: tuple[float, ...] = (0.25, 0.5, 0.75, 1.0)

SIZE: tuple[float, float] = (2.0, 1.0)
DIVISIONS: tuple[int, int] = (32, 16)  # Gamma_C in 32 parts, h = 1/16 (squares)
T: float = 1.0
STEPS: int = 64  # k = 1/64
LAM = ETA = 4.0
F1: tuple[float, float] = (0.0, -0.06)
F2: tuple[float, float] = (0.0, 0.0)
C_P = 0.4  # p(r) = 0.4 r_+
G = 0.1
V_STAR: tuple[float, float] = (1.0, 0.0)
PARTS: dict[str, Any] = {"clamped": "left", "traction": ["top", "right"], "contact": "bottom"}


# ----------------------------------------------------------------------------- problems
def mesh(divisions: tuple[int, int] = DIVISIONS) -> Mesh:
    """The tagged mesh of (0, 2) x (0, 1) with ``divisions`` squares (paper: 32 x 16).

    Parameters
    ----------
    divisions : (int, int)
        Squares in x and y.
    """
    return tag_rectangle(rectangle_squares(SIZE, divisions, (0.0, 0.0)), PARTS)


def problem(
    mu: float,
    kappa: float,
    *,
    divisions: tuple[int, int] = DIVISIONS,
    steps: int = STEPS,
    tagged_mesh: Mesh | None = None,
) -> Problem:
    """The problem of Example 5.2 with friction coefficient ``mu`` and wear coefficient ``kappa``.

    Parameters
    ----------
    mu, kappa : float
        The data set.
    divisions : (int, int)
        Squares in x and y (paper: 32 x 16).
    steps : int
        Uniform time steps on [0, 1] (paper: 64).
    tagged_mesh : Mesh, optional
        A tagged mesh to reuse (overrides ``divisions``).
    """
    return Problem(
        mesh=mesh(divisions) if tagged_mesh is None else tagged_mesh,
        material=Material(lam=LAM, eta=ETA),
        time=TimeGrid.uniform(T, steps),
        f1=F1,
        f2=F2,
        p=LinearCompliance(C_P),
        g=G,
        mu=mu,
        kappa=kappa,
        v_star=V_STAR,
        stabilization="paper",
    )


def problems(*, divisions: tuple[int, int] = DIVISIONS, steps: int = STEPS) -> dict[str, Problem]:
    """The three problems of Example 5.2 by name (``set1``, ``set2``, ``set3``).

    Parameters
    ----------
    divisions : (int, int)
        Squares in x and y (paper: 32 x 16).
    steps : int
        Uniform time steps on [0, 1] (paper: 64); the figure times 0.25, 0.5, 0.75, 1
        must be levels, so ``steps`` must be a multiple of 4 for :func:`run`.
    """
    m = mesh(divisions)
    return {
        name: problem(d["mu"], d["kappa"], tagged_mesh=m, steps=steps)
        for name, d in DATA_SETS.items()
    }


def _check(params: Mapping[str, Any]) -> None:
    try:  # before any solve: the figure times must be time levels
        TimeGrid.uniform(T, params["steps"]).index(TIMES)
    except ValueError:
        raise ValueError(
            f"{TITLE}: steps must be a multiple of 4 (the figures are at t = "
            f"{', '.join(f'{t:g}' for t in TIMES)}), got {params['steps']}"
        ) from None


# ----------------------------------------------------------------------------- findings
def _worn_area(result: Result) -> float:
    return float(np.dot(result.problem.contact.weights, result.wear[-1]))


def findings(results: Mapping[str, Result]) -> dict[str, Any]:
    """Maximal wear and worn area at t = T per set, and the paper's two findings.

    Parameters
    ----------
    results : mapping of str to Result
        The runs of ``set1``, ``set2``, ``set3``.

    Returns
    -------
    dict
        ``max_wear`` and ``worn_area`` (by set), ``max_wear_at`` (x of the maximum),
        ``kappa_increases_wear`` (set2 > set1) and ``mu_decreases_wear`` (set3 < set2),
        each judged by the maximal wear and by the worn area ``sum(weights * w)``, and
        ``wear_grows`` (max w non-decreasing in t for every set).
    """
    mw = {k: float(r.wear[-1].max()) for k, r in results.items()}
    area = {k: _worn_area(r) for k, r in results.items()}
    at = {k: float(r.contact_points[int(np.argmax(r.wear[-1])), 0]) for k, r in results.items()}
    return {
        "max_wear": mw,
        "max_wear_at": at,
        "worn_area": area,
        "kappa_increases_wear": {
            "max": mw["set2"] > mw["set1"],
            "area": area["set2"] > area["set1"],
        },
        "mu_decreases_wear": {"max": mw["set3"] < mw["set2"], "area": area["set3"] < area["set2"]},
        "wear_grows": all(
            bool(np.all(np.diff(r.wear.max(axis=1)) >= -1e-14)) for r in results.values()
        ),
    }


# ----------------------------------------------------------------------------- report
def _change(a: float, b: float) -> str:
    rel = (b - a) / a if a != 0 else float("nan")
    return f"{a:.6g} -> {b:.6g}, {rel:+.2%}"


def _setup(ctx: Context) -> str:
    nx, ny = ctx.params["divisions"]
    steps = ctx.params["steps"]
    return (
        f"Mesh: {nx} x {ny} squares on (0, 2) x (0, 1) (Gamma_C in {nx} parts); "
        f"{steps} uniform time steps (k = 1/{steps}); solver `{ctx.solver.method}`; "
        f"wall time {ctx.elapsed():.2f} s."
    )


def _findings_section(ctx: Context) -> list[str]:
    f = ctx.details
    k, m = f["kappa_increases_wear"], f["mu_decreases_wear"]
    mw, area = f["max_wear"], f["worn_area"]
    return [
        "## The paper's findings",
        "",
        f"- Wear grows in time (max w non-decreasing in t, every set): {yes(f['wear_grows'])}.",
        f"- Larger kappa, more wear (set2 vs set1, kappa 2 -> 10): {yes(k['max'])} by the "
        f"maximal wear ({_change(mw['set1'], mw['set2'])}), {yes(k['area'])} by the worn "
        f"area ({_change(area['set1'], area['set2'])}).",
        f"- Larger mu, less wear (set3 vs set2, mu 0.2 -> 0.6): {yes(m['max'])} by the "
        f"maximal wear ({_change(mw['set2'], mw['set3'])}), {yes(m['area'])} by the worn "
        f"area ({_change(area['set2'], area['set3'])}).",
        "",
    ]


def _paper_figure(name: str) -> OutputFile:
    """The paper's figure of a set: the set's contact profiles at :data:`TIMES`."""
    from ..post.outputs import FIGURE_NAMES

    def write(ctx: Context, path: Path) -> None:
        shutil.copyfile(ctx.outdir / name / FIGURE_NAMES["contact_profiles"], path)

    d = DATA_SETS[name]
    return OutputFile(
        PAPER_FIGURES[name],
        f"w and u_nu - w on Gamma_C at t = {', '.join(f'{t:g}' for t in TIMES)} for "
        f"mu = {d['mu']:g}, kappa = {d['kappa']:g} (paper Fig. {PAPER_FIGURES[name][3]}).",
        write,
        figure=True,
    )


def _wear_comparison(ctx: Context, path: Path) -> None:
    from ..post import compare_profiles

    compare_profiles(dict(ctx.results), T, "wear", path, title=f"{TITLE}: wear w at t = {T:g}")


def _paper_section(out: Path, sub: str, run: ExampleRun) -> list[str]:
    d = run.details
    mw, area = d.get("max_wear", {}), d.get("worn_area", {})
    rows = [
        f"| {name} | {ds['mu']:g} | {ds['kappa']:g} | {num(mw[name], '.5g')} "
        f"| {num(d.get('max_wear_at', {}).get(name), '.3g')} | {num(area.get(name), '.5g')} "
        f"| {PAPER_FIGURES[name]} (figure only, no number printed) |"
        for name, ds in DATA_SETS.items()
        if name in mw
    ]
    k, m = d.get("kappa_increases_wear", {}), d.get("mu_decreases_wear", {})
    return [
        "## Example 5.2: wear for three data sets (paper Figs. 3-5)",
        "",
        f"Report: [{sub}/example_5_2.md]({sub}/example_5_2.md). Wall time {run.elapsed:.1f} s.",
        "",
        "| set | mu | kappa | our max w(T) | at x | our worn area | paper |",
        "|---|---|---|---|---|---|---|",
        *rows,
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
        *links(out, sub),
        "",
    ]


def _max_wear(name: str) -> Callable[[Context], float]:
    """The headline number max w(T) of one set."""
    return lambda ctx: float(ctx.details["max_wear"][name])


EXAMPLE = Example(
    name=NAME,
    heading="wear for three data sets",
    parameters={"divisions": DIVISIONS, "steps": STEPS},
    problems=problems,
    check=_check,
    setup=_setup,
    runs_description="the output of `vemwear run` for each set (result.npz, summary.json, "
    "figures, VTK series).",
    run_label=lambda ctx, name, pr: (
        f"{name}: mu = {DATA_SETS[name]['mu']:g}, kappa = {DATA_SETS[name]['kappa']:g}"
    ),
    run_extra=lambda ctx, name, pr: {
        "set": name,
        "data": dict(DATA_SETS[name]),
        "divisions": list(ctx.params["divisions"]),
        "steps": ctx.params["steps"],
    },
    figure_times=lambda pr: TIMES,
    analyse=lambda ctx: findings(ctx.results),
    columns=(
        Column("set", lambda ctx, n, r: n),
        Column("mu", lambda ctx, n, r: f"{DATA_SETS[n]['mu']:g}"),
        Column("kappa", lambda ctx, n, r: f"{DATA_SETS[n]['kappa']:g}"),
        Column("max w(t=1)", lambda ctx, n, r: f"{ctx.details['max_wear'][n]:.6g}"),
        Column("at x", lambda ctx, n, r: f"{ctx.details['max_wear_at'][n]:.4g}"),
        Column("worn area sum(omega w)", lambda ctx, n, r: f"{ctx.details['worn_area'][n]:.6g}"),
        Column("max iterations", lambda ctx, n, r: str(int(r.iterations.max()))),
        Column("max KKT residual", lambda ctx, n, r: f"{float(r.residuals.max()):.2e}"),
        Column("paper figure", lambda ctx, n, r: PAPER_FIGURES[n]),
    ),
    sections=(_findings_section,),
    outputs=(
        *(_paper_figure(name) for name in DATA_SETS),
        OutputFile("wear_T_comparison.png", "w(T) of the three sets.", _wear_comparison, True),
    ),
    headlines={f"max_wear.{name}": _max_wear(name) for name in DATA_SETS},
    paper_section=_paper_section,
)


def run(outdir: str | Path, **options: Any) -> ExampleRun:
    """Solve the three data sets and write everything into the existing directory ``outdir``.

    Writes ``set1/``, ``set2/``, ``set3/`` (each the standard output of ``vemwear run``:
    ``result.npz``, ``summary.json``, figures, VTK series), the paper's figures
    ``fig3.png``, ``fig4.png``, ``fig5.png`` (w and u_nu - w at t = 0.25, 0.5, 0.75, 1),
    ``wear_T_comparison.png`` (w(T) of the three sets) and ``example_5_2.md``.

    Parameters
    ----------
    outdir : path
        An existing directory.
    **options
        ``divisions`` and ``steps`` (see :func:`problems`; ``steps`` a multiple of 4),
        and the driver's ``solver``, ``progress``, ``figures``, ``vtk``, ``log``
        (:func:`vemwear.paper.driver.run_example`).

    Returns
    -------
    ExampleRun
        With ``details`` = :func:`findings`.
    """
    return run_example(EXAMPLE, outdir, **options)
