"""Example 5.2 of the paper: how the friction and wear coefficients change the wear.

Data (paper Section 5; design note, section 6): Omega = (0, 2) x (0, 1),
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

The same problems are described by ``examples/example_5_2_set{1,2,3}.toml``; a test
checks that both give the same discrete data.
"""

from __future__ import annotations

import shutil
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ..contact import LinearCompliance
from ..mesh import Mesh, rectangle_squares, tag_rectangle
from ..post.outputs import FIGURE_NAMES, write_outputs
from ..simulate import Problem, Result, SolverOptions, TimeGrid, simulate
from ..vem import Material
from . import ExampleRun

__all__ = [
    "DATA_SETS",
    "DESCRIPTION",
    "DIVISIONS",
    "NAME",
    "PAPER_FIGURES",
    "STEPS",
    "TIMES",
    "TITLE",
    "findings",
    "mesh",
    "problem",
    "problems",
    "report_markdown",
    "run",
]

NAME = "5.2"
TITLE = "Example 5.2"
DESCRIPTION = (
    "wear and penetration for (mu, kappa) = (0.2, 2), (0.2, 10), (0.6, 10) (paper Figs. 3-5)"
)

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


def mesh(divisions: tuple[int, int] = DIVISIONS) -> Mesh:
    """The tagged mesh of (0, 2) x (0, 1) with ``divisions`` squares (paper: 32 x 16)."""
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


def _worn_area(result: Result) -> float:
    return float(np.dot(result.problem.contact.weights, result.wear[-1]))


def findings(results: dict[str, Result]) -> dict[str, Any]:
    """Maximal wear and worn area at t = T per set, and the paper's two findings.

    Returns
    -------
    dict
        ``max_wear`` and ``worn_area`` (by set), ``max_wear_at`` (x of the maximum),
        ``kappa_increases_wear`` (set2 > set1) and ``mu_decreases_wear`` (set3 < set2),
        each judged by the maximal wear and by the worn area ``sum(omega * w)``.
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
    }


def _yes(b: bool) -> str:
    return "yes" if b else "**no**"


def _change(a: float, b: float) -> str:
    rel = (b - a) / a if a != 0 else float("nan")
    return f"{a:.6g} -> {b:.6g}, {rel:+.2%}"


def report_markdown(results: dict[str, Result], info: dict[str, Any]) -> str:
    """The Markdown report ``example_5_2.md``.

    Parameters
    ----------
    results : dict of str to Result
        The three runs.
    info : dict
        ``divisions``, ``steps``, ``solver``, ``elapsed`` (s) and ``files``.
    """
    f = findings(results)
    T_ = float(next(iter(results.values())).t[-1])
    nx, ny = info["divisions"]
    lines = [
        "# Example 5.2: wear for three data sets",
        "",
        "Wu, Wang, Han, *The virtual element method for a contact problem with wear and "
        "unilateral constraint*, Section 5, Example 5.2.",
        "",
        f"Mesh: {nx} x {ny} squares on (0, 2) x (0, 1) (Gamma_C in {nx} parts); "
        f"{info['steps']} uniform time steps (k = 1/{info['steps']}); "
        f"solver `{info['solver']}`; wall time {info['elapsed']:.2f} s.",
        "",
        f"| set | mu | kappa | max w(t={T_:g}) | at x | worn area sum(omega w) "
        "| max iterations | max KKT residual | paper figure |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name, r in results.items():
        d = DATA_SETS[name]
        lines.append(
            f"| {name} | {d['mu']:g} | {d['kappa']:g} | {f['max_wear'][name]:.6g} "
            f"| {f['max_wear_at'][name]:.4g} | {f['worn_area'][name]:.6g} "
            f"| {int(r.iterations.max())} | {float(r.residuals.max()):.2e} "
            f"| {PAPER_FIGURES[name]} |"
        )
    k, m = f["kappa_increases_wear"], f["mu_decreases_wear"]
    growth = all(bool(np.all(np.diff(r.wear.max(axis=1)) >= -1e-14)) for r in results.values())
    lines += [
        "",
        "## The paper's findings",
        "",
        f"- Wear grows in time (max w non-decreasing in t, every set): {_yes(growth)}.",
        f"- Larger kappa, more wear (set2 vs set1, kappa 2 -> 10): {_yes(k['max'])} by the "
        f"maximal wear ({_change(f['max_wear']['set1'], f['max_wear']['set2'])}), "
        f"{_yes(k['area'])} by the worn area "
        f"({_change(f['worn_area']['set1'], f['worn_area']['set2'])}).",
        f"- Larger mu, less wear (set3 vs set2, mu 0.2 -> 0.6): {_yes(m['max'])} by the "
        f"maximal wear ({_change(f['max_wear']['set2'], f['max_wear']['set3'])}), "
        f"{_yes(m['area'])} by the worn area "
        f"({_change(f['worn_area']['set2'], f['worn_area']['set3'])}).",
        "",
        "## Files",
        "",
        "- `fig3.png`, `fig4.png`, `fig5.png`: w and u_nu - w on Gamma_C at t = "
        + ", ".join(f"{t:g}" for t in TIMES)
        + " (paper Figs. 3-5).",
        "- `wear_T_comparison.png`: w(T) of the three sets.",
        "- `set1/`, `set2/`, `set3/`: the output of `vemwear run` for each set "
        "(result.npz, summary.json, figures, VTK series).",
        "",
    ]
    return "\n".join(lines)


def run(
    outdir: str | Path,
    *,
    solver: SolverOptions | str = "newton",
    divisions: tuple[int, int] = DIVISIONS,
    steps: int = STEPS,
    progress: bool = False,
    figures: bool = True,
    vtk: bool = True,
    log: Callable[[str], None] | None = None,
) -> ExampleRun:
    """Solve the three data sets and write everything into the existing directory ``outdir``.

    Writes ``set1/``, ``set2/``, ``set3/`` (each the standard output of ``vemwear run``:
    ``result.npz``, ``summary.json``, figures, VTK series), the paper's figures
    ``fig3.png``, ``fig4.png``, ``fig5.png`` (w and u_nu - w at t = 0.25, 0.5, 0.75, 1),
    ``wear_T_comparison.png`` (w(T) of the three sets) and ``example_5_2.md``.

    Parameters
    ----------
    outdir : path
        An existing directory (``vemwear example`` passes a temporary one that is
        renamed into place when this returns).
    solver : SolverOptions or str
        Step solver (default: condensed Newton).
    divisions, steps : see :func:`problems`
        Smaller values make quick tests; the paper's are the defaults.
    progress : bool
        Show a progress bar per data set.
    figures, vtk : bool
        Write figures / VTK series (``example_5_2.md`` and the data are always written).
    log : callable, optional
        Receives one line of text per data set.

    Returns
    -------
    ExampleRun
        With ``details`` = :func:`findings`.

    Raises
    ------
    ConvergenceError
        If a step problem does not converge.
    """
    t0 = time.perf_counter()
    out = Path(outdir)
    opts = SolverOptions(method=solver) if isinstance(solver, str) else solver
    probs = problems(divisions=divisions, steps=steps)
    grid = next(iter(probs.values())).time
    try:  # before any solve: the figure times must be time levels
        grid.index(TIMES)
    except ValueError:
        raise ValueError(
            f"{TITLE}: steps must be a multiple of 4 (the figures are at t = "
            f"{', '.join(f'{t:g}' for t in TIMES)}), got {steps}"
        ) from None
    results: dict[str, Result] = {}
    files: list[str] = []
    for name, pr in probs.items():
        d = DATA_SETS[name]
        if log is not None:
            log(f"{TITLE}, {name}: mu = {d['mu']:g}, kappa = {d['kappa']:g}")
        res = simulate(pr, opts, progress=progress)
        results[name] = res
        sub = out / name
        sub.mkdir(parents=True, exist_ok=True)
        extra = {
            "example": NAME,
            "set": name,
            "data": dict(d),
            "divisions": list(divisions),
            "steps": steps,
        }
        w = write_outputs(res, sub, times=TIMES, figures=figures, vtk=vtk, extra=extra)
        files += [f"{name}/{f}" for group in w.values() for f in group]
    if figures:
        from .. import post

        for name in results:  # the sets' contact profiles are at TIMES: the paper's figures
            shutil.copyfile(
                out / name / FIGURE_NAMES["contact_profiles"], out / PAPER_FIGURES[name]
            )
            files.append(PAPER_FIGURES[name])
        post.compare_profiles(
            dict(results),
            T,
            "wear",
            out / "wear_T_comparison.png",
            title=f"{TITLE}: wear w at t = {T:g}",
        )
        files.append("wear_T_comparison.png")
    elapsed = time.perf_counter() - t0
    info = {
        "divisions": tuple(divisions),
        "steps": steps,
        "solver": opts.method,
        "elapsed": elapsed,
    }
    report = out / "example_5_2.md"
    report.write_text(report_markdown(results, info), encoding="utf-8")
    files.append(report.name)
    return ExampleRun(
        name=NAME,
        outdir=out,
        results=results,
        files=files,
        report=report,
        details=findings(results),
        elapsed=time.perf_counter() - t0,
    )
