"""Example 5.5: the paper's Tables 1 and 2, ours beside them (Markdown, CSV, a plot).

The columns of ``errors.csv`` (:data:`COLUMNS`) are the variants of
:mod:`vemwear.post.compare`: ``u_H1`` and ``w_L2`` (at t = T) are the primary errors, the
paper's definitions (docs/method.md, section 7); the others are secondary.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..post.compare import ErrorHistory, convergence_orders

__all__ = [
    "COLUMNS",
    "PAPER_TABLE1",
    "PAPER_TABLE2",
    "TABLE1_ROWS",
    "TABLE2_ROWS",
    "error_tables",
    "paper_ratios",
    "plot_tables",
    "tables_csv",
    "tables_markdown",
]

#: The paper's Table 1 (relative H1 displacement errors) and Table 2 (relative L2 wear
#: errors), by 1/h, and their orders.
PAPER_TABLE1: dict[str, Any] = {
    "errors": {4: 7.0581e-2, 8: 3.9059e-2, 16: 2.1698e-2, 32: 1.2084e-2, 64: 6.5023e-3},
    "orders": {8: 0.85365, 16: 0.84807, 32: 0.84448, 64: 0.89407},
}
PAPER_TABLE2: dict[str, Any] = {
    "errors": {4: 1.1153e-1, 8: 5.4917e-2, 16: 2.5228e-2, 32: 1.1795e-2, 64: 5.4869e-3},
    "orders": {8: 1.0221, 16: 1.1223, 32: 1.0968, 64: 1.1041},
}

#: Columns of the error tables: (key, quantity, variant of :mod:`vemwear.post.compare`,
#: when: ``T`` (at t = T) or ``max`` (over the common levels)).
COLUMNS: tuple[tuple[str, str, str, str], ...] = (
    ("u_H1", "displacement", "H1", "T"),
    ("u_H1_max", "displacement", "H1", "max"),
    ("u_H1semi", "displacement", "H1semi", "T"),
    ("u_H1_coarse", "displacement", "H1_coarse", "T"),
    ("u_H1semi_meanvalue", "displacement", "H1semi_meanvalue", "T"),
    ("w_L2", "wear", "L2", "T"),
    ("w_L2_max", "wear", "L2", "max"),
    ("w_L2_coarse", "wear", "L2_coarse", "T"),
    ("w_nodal_coarse", "wear", "nodal_coarse", "T"),
)

#: Our rows of Tables 1 and 2 in :func:`tables_markdown`: (label, column, part).
TABLE1_ROWS: tuple[tuple[str, str, str], ...] = (
    ("**ours: error**", "u_H1", "errors"),
    ("**ours: order**", "u_H1", "orders"),
    ("ours / paper", "u_H1", "ratio1"),
    ("ours, max over t", "u_H1_max", "errors"),
    ("ours, H1 seminorm", "u_H1semi", "errors"),
    ("ours, H1 seminorm: order", "u_H1semi", "orders"),
    ("secondary: I_h u_ref on the coarse mesh", "u_H1_coarse", "errors"),
    ("secondary: mean value prolongation, seminorm", "u_H1semi_meanvalue", "errors"),
)
TABLE2_ROWS: tuple[tuple[str, str, str], ...] = (
    ("**ours: error**", "w_L2", "errors"),
    ("**ours: order**", "w_L2", "orders"),
    ("ours / paper", "w_L2", "ratio2"),
    ("ours, max over t", "w_L2_max", "errors"),
    ("secondary: I_h w_ref on the coarse Gamma_C", "w_L2_coarse", "errors"),
    ("secondary: the same, nodal quadrature", "w_nodal_coarse", "errors"),
)


def error_tables(histories: dict[int, ErrorHistory]) -> dict[str, Any]:
    """Errors and orders of every column of :data:`COLUMNS`, by increasing ``1/h``.

    Parameters
    ----------
    histories : dict
        ``{1/h: ErrorHistory}``.

    Returns
    -------
    dict
        ``{column: {"errors": [...], "orders": [nan, ...]}}`` plus ``"n": [4, 8, ...]``.
    """
    ns = sorted(histories)
    out: dict[str, Any] = {"n": ns}
    for key, q, variant, when in COLUMNS:
        hs = histories
        e = [hs[n].at_T(q, variant) if when == "T" else hs[n].max(q, variant) for n in ns]
        o = [float("nan"), *convergence_orders(e).tolist()]
        out[key] = {"errors": e, "orders": o}
    return out


def paper_ratios(tables: dict[str, Any]) -> dict[str, list[float]]:
    """Ours over the paper's, at every ``1/h`` of the paper: ``u_H1`` against Table 1 and
    ``w_L2`` against Table 2 (NaN where the paper has no value)."""
    out = {}
    for key, paper in (("u_H1", PAPER_TABLE1), ("w_L2", PAPER_TABLE2)):
        out[key] = [
            e / paper["errors"][n] if n in paper["errors"] else float("nan")
            for n, e in zip(tables["n"], tables[key]["errors"], strict=True)
        ]
    return out


def _e(v: float | None) -> str:
    return "-" if v is None or not np.isfinite(v) else f"{v:.4e}"


def _o(v: float | None) -> str:
    return "-" if v is None or not np.isfinite(v) else f"{v:.4f}"


def _r(v: float | None) -> str:
    return "-" if v is None or not np.isfinite(v) else f"{v:.3f}"


def _pow2(n: int) -> str:
    k = round(float(np.log2(n)))
    return f"2^-{k}" if 2**k == n else f"1/{n}"


def tables_markdown(tables: dict[str, Any], reference: int) -> str:
    """Tables 1 and 2 (ours beside the paper's, with the ratios) and the variants."""
    ns = tables["n"]
    ratios = paper_ratios(tables)
    fmt = {"errors": _e, "orders": _o, "ratio1": _r, "ratio2": _r}

    def values(key: str, part: str) -> list[float]:
        if part == "ratio1":
            return ratios["u_H1"]
        if part == "ratio2":
            return ratios["w_L2"]
        return tables[key][part]

    def row(label: str, vals: Sequence[float | None], part: str) -> str:
        return f"| {label} | " + " | ".join(fmt[part](v) for v in vals) + " |"

    def table(title: str, paper: dict[str, Any], rows: Sequence[tuple[str, str, str]]) -> list[str]:
        return [
            f"### {title} (reference h = k = 1/{reference}, t = T)",
            "",
            "| h = k | " + " | ".join(_pow2(n) for n in ns) + " |",
            "|---|" + "---|" * len(ns),
            *(
                row(f"paper: {p[:-1]}", [paper[p].get(n) for n in ns], p)
                for p in ("errors", "orders")
            ),
            *(row(label, values(key, part), part) for label, key, part in rows),
            "",
        ]

    return "\n".join(
        [
            *table("Table 1: relative H1 error of the displacement", PAPER_TABLE1, TABLE1_ROWS),
            *table("Table 2: relative L2(Gamma_C) error of the wear", PAPER_TABLE2, TABLE2_ROWS),
        ]
    )


def tables_csv(tables: dict[str, Any]) -> str:
    """Every column of :data:`COLUMNS` (error and order) and the paper's, one row per h."""
    buf = io.StringIO()
    wr = csv.writer(buf, lineterminator="\n")
    keys = [c[0] for c in COLUMNS]
    wr.writerow(
        [
            "inv_h",
            "h",
            "k",
            *[f"{k}{s}" for k in keys for s in ("", "_order")],
            "paper_table1",
            "paper_table1_order",
            "paper_table2",
            "paper_table2_order",
        ]
    )

    def cell(v: float | None, fmt: str) -> str:
        return "" if v is None or not np.isfinite(v) else format(v, fmt)

    for i, n in enumerate(tables["n"]):
        vals: list[str] = []
        for k in keys:
            vals += [cell(tables[k]["errors"][i], ".6e"), cell(tables[k]["orders"][i], ".6f")]
        paper = [
            cell(t[part].get(n), "g")
            for t in (PAPER_TABLE1, PAPER_TABLE2)
            for part in ("errors", "orders")
        ]
        wr.writerow([n, f"{1 / n:.10g}", f"{1 / n:.10g}", *vals, *paper])
    return buf.getvalue()


def plot_tables(tables: dict[str, Any], reference: int, path: Path, title: str) -> None:
    """Log-log plot of the primary errors (and the max over t), with the paper's."""
    from matplotlib.figure import Figure
    from matplotlib.ticker import LogFormatter, NullLocator

    ns = np.asarray(tables["n"], dtype=float)
    h = 1.0 / ns
    # fixed margins (room for the titles, the labels and the legends): the constrained
    # layout measured every label in a draw of its own before the real one
    fig = Figure(figsize=(10.0, 4.2))
    axes = fig.subplots(1, 2)
    fig.subplots_adjust(left=0.09, right=0.985, bottom=0.12, top=0.86, wspace=0.25)
    spec = [
        ("Displacement, relative H1 error (Table 1)", PAPER_TABLE1, ("u_H1", "u_H1_max")),
        ("Wear, relative L2(\u0393_C) error (Table 2)", PAPER_TABLE2, ("w_L2", "w_L2_max")),
    ]
    for ax, (name, paper, (key, key_max)) in zip(axes, spec, strict=True):
        ax.loglog(h, tables[key]["errors"], marker="o", label="ours, t = T")
        ax.loglog(h, tables[key_max]["errors"], marker="s", label="ours, max over t")
        pn = [n for n in tables["n"] if n in paper["errors"]]
        if pn:
            ax.loglog(
                [1.0 / n for n in pn],
                [paper["errors"][n] for n in pn],
                "k--",
                marker="x",
                label="paper",
            )
        e0 = tables[key]["errors"][0]
        ax.loglog(h, e0 * h / h[0], ":", color="gray", label="slope 1")
        ax.set_xticks(h, [f"1/{int(n)}" for n in ns])
        ax.xaxis.set_minor_locator(NullLocator())
        # plain tick labels: the first mathtext label costs a parser set-up of 0.3 s
        ax.yaxis.set_major_formatter(LogFormatter(labelOnlyBase=True))
        ax.yaxis.set_minor_formatter(LogFormatter(labelOnlyBase=False))
        ax.set_xlabel("h = k")
        ax.set_ylabel("relative error")
        ax.set_title(name, fontsize="medium")
        ax.grid(True, which="both", lw=0.3, alpha=0.5)
        ax.legend(frameon=False, fontsize="small")
    fig.suptitle(f"{title}: errors against the reference h = k = 1/{reference}")
    fig.savefig(path, dpi=150)
