"""Example 5.5, Table 2: where the wear error comes from (space or time), measured.

For every level ``n`` (h = 1/n) the wear error ``w_L2`` at t = T against the reference
h = k = 1/N is measured for four runs:

``full``
    h = k = 1/n (the paper's Table 2);
``space``
    h = 1/n with the reference's step k = 1/N (the space part of the error);
``time``
    the reference mesh h = 1/N with k = 1/n (the time part);
``k2h``
    h = 1/n with k = 2/n (twice the paper's step).

The wear update (3.22) is the left rectangle rule for ``w' = rate = alpha p(u_nu - w)``,
``alpha = kappa |v*|``. Where the rate decays like ``exp(-rho t)``, the rule overestimates
``w(t)`` by the relative amount ``(k/2) rho`` to first order in k, and against a reference
with step ``k_ref`` by ``((k - k_ref)/2) rho``. For the linear law ``p(r) = c_p r_+`` the
decay of the discrete rate over one step,

    ``rho_n = (1 - rate_{n+1} / rate_n) / k = alpha c_p - (u_nu^{n+1} - u_nu^n) / (k r_n)``,

is at most ``alpha L_p`` (0.8 for kappa = 2, c_p = 0.4) while ``u_nu`` does not decrease.
:func:`rate_analysis` measures ``rho`` on the reference; :func:`wear_error_study` measures
the errors; ``python -m vemwear.paper.ex55_study`` prints the table.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..post.compare import Comparison, Solution
from ..simulate import Result, SolverOptions, simulate
from . import ex52
from .ex55_reference import (
    KAPPA,
    LEVELS,
    REFERENCE,
    check_sizes,
    common_times,
    problem,
    reference_solution,
)
from .ex55_tables import PAPER_TABLE2

__all__ = ["RUNS", "rate_analysis", "study_markdown", "wear_error_study"]

#: The runs of the study (module docstring).
RUNS: tuple[str, ...] = ("full", "space", "time", "k2h")


def rate_analysis(reference: Solution, alpha: float, lipschitz: float) -> dict[str, Any]:
    """The decay ``rho`` of the wear rates of the reference (module docstring).

    Parameters
    ----------
    reference : Solution
        A run with its wear at every level of its grid.
    alpha, lipschitz : float
        ``kappa |v*|`` and the Lipschitz constant ``L_p`` of ``p``.

    Returns
    -------
    dict
        ``rho0``: ``rho`` of the first step, in the least-squares sense over the contact
        nodes (``sum_a (rate_0 - rate_1) rate_0 / (k sum_a rate_0^2)``); ``rho_max``: the
        largest ``rho_n`` over the nodes and steps where the rate exceeds 1e-3 of its
        maximum; ``rho_bound``: ``alpha L_p``.
    """
    r = reference
    k = np.diff(r.t)
    rate = np.diff(r.wear, axis=0) / k[:, None]  # (L - 1, m): alpha p(u_nu - w) at t_n
    rho0 = float(np.sum((rate[0] - rate[1]) * rate[0]) / (k[0] * np.sum(rate[0] ** 2)))
    big = rate[:-1] > 1e-3 * rate.max()
    rho = (1.0 - rate[1:] / np.where(big, rate[:-1], 1.0)) / k[1:, None]
    rho_max = float(rho[big].max()) if np.any(big) else float("nan")
    return {"rho0": rho0, "rho_max": rho_max, "rho_bound": alpha * lipschitz}


def wear_error_study(
    *,
    levels: Sequence[int] = LEVELS,
    reference: int = REFERENCE,
    solver: SolverOptions | str = "newton",
    cache_dir: str | Path | None = None,
    comparison: Comparison | None = None,
    coarse: Mapping[str, Result] | None = None,
    runs: Sequence[str] = RUNS,
    log: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """Measure the space and time parts of the wear error of Example 5.5 (module docstring).

    Parameters
    ----------
    levels : sequence of int
        ``1/h`` of the coarse levels (``k2h`` needs an even ``1/h``).
    reference : int
        ``1/h = 1/k`` of the reference; a multiple of every level.
    solver : SolverOptions or str
    cache_dir : path, optional
        Cache of the reference (:func:`vemwear.paper.ex55.reference_solution`).
    comparison : Comparison, optional
        Against the reference, if already built (its reference must hold the wear at
        every level; the one of :func:`vemwear.paper.ex55.run` does).
    coarse : mapping, optional
        The runs h = k = 1/n already made, by name ``h{n}``.
    runs : sequence of str
        Which of :data:`RUNS` to make (``time`` costs one factorization of the reference
        mesh per level).
    log : callable, optional

    Returns
    -------
    dict
        ``levels``, ``reference``, ``rows`` (one dict per level: ``n``, ``k``, the
        errors ``full``, ``space``, ``time``, ``k2h`` (NaN if not run), ``paper``,
        ``ratio`` (full / paper), ``k2h_ratio`` (k2h / paper), ``slope`` (full /
        (k - k_ref)), ``paper_slope``, ``time_slope``, ``first_step`` (relative wear
        error of the ``time`` run at t = k) and ``first_step_predicted``
        (``(k - k_ref) rho0 / 2``)),
        and ``rates`` (:func:`rate_analysis` of the reference).
    """
    lv, ref = check_sizes(levels, reference)
    opts = SolverOptions(method=solver) if isinstance(solver, str) else solver
    unknown = set(runs) - set(RUNS)
    if unknown:
        raise ValueError(f"{sorted(unknown)}: unknown runs; expected some of {', '.join(RUNS)}")
    if comparison is None:
        sol, _info = reference_solution(
            ref, common_times(lv), solver=opts, cache_dir=cache_dir, log=log
        )
        comparison = Comparison(sol)
    alpha = KAPPA * math.hypot(*ex52.V_STAR)
    rates = rate_analysis(comparison.reference, alpha, ex52.C_P)
    k_ref = 1.0 / ref
    rows = []
    for n in lv:
        t0 = time.perf_counter()
        row: dict[str, Any] = {"n": n, "k": 1.0 / n}
        specs = {"full": (n, n), "space": (n, ref), "time": (ref, n), "k2h": (n, n // 2)}
        for name in RUNS:
            h_inv, steps = specs[name]
            row[name] = float("nan")
            if name not in runs or steps < 1 or (name == "k2h" and n % 2):
                continue
            res = coarse.get(f"h{n}") if (coarse is not None and name == "full") else None
            if res is None:
                res = simulate(problem(h_inv, steps), opts, store="final")
            hist = comparison.errors(res, levels="common" if name == "time" else "final")
            row[name] = hist.at_T("wear")
            if name == "time" and len(hist.t) > 1:
                row["first_step"] = float(hist.wear["L2"][1])
        # the paper's numbers are against its reference 1/256 only
        p = PAPER_TABLE2["errors"].get(n, float("nan")) if ref == REFERENCE else float("nan")
        dk = 1.0 / n - k_ref
        row.update(
            paper=p,
            ratio=row["full"] / p,
            k2h_ratio=row["k2h"] / p,
            slope=row["full"] / dk,
            paper_slope=p / dk,
            time_slope=row["time"] / dk,
            first_step_predicted=0.5 * dk * rates["rho0"],
        )
        row.setdefault("first_step", float("nan"))
        rows.append(row)
        if log is not None:
            log(f"Example 5.5 study, h = 1/{n}: {time.perf_counter() - t0:.1f} s")
    return {"levels": list(lv), "reference": ref, "rows": rows, "rates": rates}


def _g(v: float) -> str:
    return "-" if not np.isfinite(v) else f"{v:.3g}"


def study_markdown(study: Mapping[str, Any]) -> str:
    """The study as a Markdown table and the rate analysis."""
    ref = study["reference"]
    r = study["rates"]
    cols = [
        ("h = k", lambda w: f"1/{w['n']}"),
        ("paper", lambda w: _g(w["paper"])),
        ("ours (k = h)", lambda w: _g(w["full"])),
        ("ours / paper", lambda w: _g(w["ratio"])),
        (f"space only (k = 1/{ref})", lambda w: _g(w["space"])),
        (f"time only (h = 1/{ref})", lambda w: _g(w["time"])),
        ("ours / (k - k_ref)", lambda w: _g(w["slope"])),
        ("paper / (k - k_ref)", lambda w: _g(w["paper_slope"])),
        ("ours, k = 2h", lambda w: _g(w["k2h"])),
        ("k = 2h / paper", lambda w: _g(w["k2h_ratio"])),
        ("first step: time-only error at t = k", lambda w: _g(w["first_step"])),
        ("(k - k_ref) rho(0) / 2", lambda w: _g(w["first_step_predicted"])),
    ]
    lines = [
        f"### Table 2: the wear error split into space and time (reference h = k = 1/{ref}, t = T)",
        "",
        "| " + " | ".join(c[0] for c in cols) + " |",
        "|" + "---|" * len(cols),
        *("| " + " | ".join(f(w) for _n, f in cols) + " |" for w in study["rows"]),
        "",
        f"Decay of the wear rates of the reference: rho(0) = {r['rho0']:.3f}, so "
        f"(k/2) rho(0) = {r['rho0'] / 2:.3f} k; the largest rho over the nodes and steps is "
        f"{r['rho_max']:.3f} (bound alpha L_p = {r['rho_bound']:.3g} while u_nu does not "
        "decrease).",
        "",
    ]
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m vemwear.paper.ex55_study``: print the study (and write it with ``-o``)."""
    ap = argparse.ArgumentParser(prog="python -m vemwear.paper.ex55_study", description=__doc__)
    ap.add_argument("--levels", default=",".join(map(str, LEVELS)), help="1/h, comma-separated")
    ap.add_argument("--reference", type=int, default=REFERENCE, help="1/h = 1/k of the reference")
    ap.add_argument("--cache", default=None, help="cache directory of the reference")
    ap.add_argument("--runs", default=",".join(RUNS), help=f"some of {','.join(RUNS)}")
    ap.add_argument("-o", "--output", default=None, help="write the Markdown table there")
    a = ap.parse_args(argv)
    study = wear_error_study(
        levels=[int(x) for x in a.levels.split(",")],
        reference=a.reference,
        cache_dir=a.cache,
        runs=a.runs.split(","),
        log=print,
    )
    text = study_markdown(study)
    print(text)
    if a.output:
        Path(a.output).write_text(text, encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
