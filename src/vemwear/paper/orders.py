"""Orders of k = 1 and k = 2 on the contact problem, and accuracy against cost.

Example 5.5's setting (Example 5.2's data with mu = 0.2, kappa = 2, (2/h) x (1/h)
squares, T = 1; :mod:`vemwear.paper.ex55_reference`) solved with the virtual elements of
order k = 1 on h = 1/4 ... 1/64 and k = 2 on h = 1/4 ... 1/32, in two settings:

``"k = h"``
    the time step equal to h (the paper's choice): space and time error together;
``"k small"``
    every run on the reference's time grid (``steps`` = :data:`SMALL_STEPS`): the time
    errors of the run and of the reference are the same to first order, so the
    difference is the space error.

Both are measured at t = T against one reference, k = 2 on h = 1/:data:`REFERENCE_N`
with the small time step (docs/method.md, section 9, "Orders of the contact problem"):

``u_H1``
    ``||Pi_h u_h - Pi_ref u_ref||_{H1} / ||Pi_ref u_ref||_{H1}``: each solution projected
    by its own Pi (linear per cell for k = 1, (3.8)-(3.10); quadratic for k = 2,
    :func:`~vemwear.vem.dofs2.project2`), the difference integrated over the reference
    cells by the degree-5 rule on their fans (exact: it is at most quartic there), the
    coarse Pi evaluated in the coarse cell that contains each reference cell
    (:func:`~vemwear.mesh.nested_cells`); full H1 norm.
``w_L2``
    ``||w_h - w_ref||_{L2(Gamma_C)} / ||w_ref||_{L2(Gamma_C)}`` with ``w_h`` linear (k = 1)
    or quadratic (k = 2, through the values at the vertices and the midpoint) on every
    contact edge, by three-point Gauss on every reference contact edge (exact: the
    difference is quadratic there).
``u_H1_int``, ``w_L2_int``
    The same on the interior region x in
    :data:`~vemwear.paper.orders_errors.INTERIOR` = (1/4, 7/4) only, away from the side
    x = 0 whose corners make u singular (docs/paper.md).

Orders are log2 of the ratios of successive errors (h halved). The wall time of a run is
the least over ``repeats`` runs of building the problem and :func:`~vemwear.simulate.simulate`
(assembly, factorization, time loop; not the error evaluation).

``python -m vemwear.paper.orders -o DIR`` (or ``vemwear example orders -o DIR``) prints the
two tables and writes ``orders.md`` and ``orders.csv``.

The runs and their errors are computed in :mod:`vemwear.paper.orders_errors`; this
module runs the study, writes its two tables and is its command line.
"""

from __future__ import annotations

import argparse
import csv
import io
import itertools
import math
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from ..simulate import SolverOptions
from .markdown import num, table
from .orders_errors import OrdersReference, run_final

__all__ = [
    "COLUMNS",
    "LEVELS",
    "REFERENCE_N",
    "SETTINGS",
    "SMALL_STEPS",
    "cmd_example",
    "cost_markdown",
    "main",
    "orders_markdown",
    "orders_study",
    "rows_csv",
    "run",
]

#: ``1/h`` of the compared runs by order k.
LEVELS: dict[int, tuple[int, ...]] = {1: (4, 8, 16, 32, 64), 2: (4, 8, 16, 32)}
#: ``1/h`` of the reference (k = 2).
REFERENCE_N = 128
#: Time steps of the reference and of the ``"k small"`` runs (k = 1/1024).
SMALL_STEPS = 1024
#: The two time-step settings.
SETTINGS: tuple[str, str] = ("k = h", "k small")
#: Columns of the rows (and of ``orders.csv``).
COLUMNS: tuple[str, ...] = (
    "setting",
    "order",
    "inv_h",
    "steps",
    "dofs",
    "wall_s",
    "u_H1",
    "u_H1_order",
    "w_L2",
    "w_L2_order",
    "u_H1_int",
    "u_H1_int_order",
    "w_L2_int",
    "w_L2_int_order",
)

#: The error columns (each with its ``_order``).
ERRORS: tuple[str, ...] = ("u_H1", "w_L2", "u_H1_int", "w_L2_int")


# ----------------------------------------------------------------------------- the study
def _orders(e: Sequence[float]) -> list[float]:
    return [math.nan] + [
        math.log2(a / b) if a > 0 and b > 0 else math.nan for a, b in itertools.pairwise(e)
    ]


def orders_study(
    *,
    levels: Mapping[int, Sequence[int]] | None = None,
    reference: int = REFERENCE_N,
    small_steps: int = SMALL_STEPS,
    solver: SolverOptions | str = "newton",
    repeats: int = 3,
    log: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """Run every level of k = 1 and k = 2 in both settings and measure the errors.

    Parameters
    ----------
    levels : mapping of int to sequence of int, optional
        ``1/h`` of the compared runs by order (default :data:`LEVELS`); each must divide
        ``reference``.
    reference : int
        ``1/h`` of the reference (k = 2, ``small_steps`` steps).
    small_steps : int
        Time steps of the reference and of the ``"k small"`` runs.
    solver : SolverOptions or str
    repeats : int
        Runs per level whose least wall time is reported.
    log : callable, optional
        Receives one line per run.

    Returns
    -------
    dict
        ``rows`` (one dict per run with the keys :data:`COLUMNS`, grouped by setting and
        order, h decreasing) and ``reference`` (its ``inv_h``, ``steps``, ``dofs``,
        ``wall_s``).
    """
    lv = {int(k): tuple(sorted(int(n) for n in v)) for k, v in (levels or LEVELS).items()}
    bad = [n for v in lv.values() for n in v if n >= reference or reference % n]
    if bad or any(k not in (1, 2) for k in lv):
        raise ValueError(
            f"orders: orders must be 1 or 2 and every level must divide the reference "
            f"1/h = {reference} and be smaller; offending: {bad}"
        )
    say = log or (lambda _s: None)
    say(f"reference: k = 2, h = 1/{reference}, {small_steps} steps")
    ref = run_final(2, reference, small_steps, solver=solver)
    cmp = OrdersReference(ref)
    rows: list[dict[str, Any]] = []
    for setting in SETTINGS:
        for order, ns in lv.items():
            block: list[dict[str, Any]] = []
            for n in ns:
                steps = n if setting == SETTINGS[0] else small_steps
                st = run_final(order, n, steps, solver=solver, repeats=repeats)
                e = cmp.errors(st)
                block.append(
                    {
                        "setting": setting,
                        "order": order,
                        "inv_h": n,
                        "steps": steps,
                        "dofs": st.n_dofs,
                        "wall_s": st.wall,
                        **e,
                    }
                )
                say(
                    f"{setting}, k = {order}, h = 1/{n}: u_H1 {e['u_H1']:.3e}, "
                    f"w_L2 {e['w_L2']:.3e} ({st.wall:.2f} s)"
                )
            for key in ERRORS:
                for r, o in zip(block, _orders([r[key] for r in block]), strict=True):
                    r[f"{key}_order"] = o
            rows += block
    return {
        "rows": rows,
        "reference": {
            "order": 2,
            "inv_h": reference,
            "steps": small_steps,
            "dofs": ref.n_dofs,
            "wall_s": ref.wall,
        },
    }


# ----------------------------------------------------------------------------- tables
def orders_markdown(rows: Sequence[Mapping[str, Any]]) -> str:
    """The table of errors and orders (one row per run)."""
    body = [
        [
            str(r["setting"]),
            str(r["order"]),
            f"1/{r['inv_h']}",
            f"1/{r['steps']}",
            str(r["dofs"]),
            *(x for key in ERRORS for x in (num(r[key], ".3e"), num(r[f"{key}_order"], ".2f"))),
        ]
        for r in rows
    ]
    head = ["time step", "k", "h", "step", "dofs"]
    head += [x for key in ERRORS for x in (f"`{key}`", "order")]
    return "\n".join(table(head, body)) + "\n"


def cost_markdown(rows: Sequence[Mapping[str, Any]]) -> str:
    """The table of accuracy against cost: by setting, the runs in increasing dofs."""
    ordered = sorted(rows, key=lambda r: (SETTINGS.index(r["setting"]), r["dofs"], r["order"]))
    body = [
        [
            str(r["setting"]),
            str(r["dofs"]),
            str(r["order"]),
            f"1/{r['inv_h']}",
            num(r["wall_s"], ".3f"),
            num(r["u_H1"], ".3e"),
            num(r["w_L2"], ".3e"),
            num(r["u_H1_int"], ".3e"),
        ]
        for r in ordered
    ]
    head = ["time step", "dofs", "k", "h", "wall time (s)", "`u_H1`", "`w_L2`", "`u_H1_int`"]
    return "\n".join(table(head, body)) + "\n"


def rows_csv(rows: Sequence[Mapping[str, Any]]) -> str:
    """The rows as CSV with the header :data:`COLUMNS`."""
    buf = io.StringIO()
    wr = csv.DictWriter(buf, fieldnames=list(COLUMNS), lineterminator="\n")
    wr.writeheader()
    for r in rows:
        wr.writerow({k: r[k] for k in COLUMNS})
    return buf.getvalue()


def report_markdown(study: Mapping[str, Any]) -> str:
    """Both tables under headings, with the reference."""
    ref = study["reference"]
    return (
        "# Orders of k = 1 and k = 2 (Example 5.5's setting)\n\n"
        f"Reference: k = 2, h = 1/{ref['inv_h']}, step 1/{ref['steps']} ({ref['dofs']} dofs, "
        f"{ref['wall_s']:.2f} s). Errors relative, at t = T.\n\n"
        "## Errors and orders\n\n"
        + orders_markdown(study["rows"])
        + "\n## Accuracy against cost\n\n"
        + cost_markdown(study["rows"])
    )


def run(outdir: str | Path | None = None, **options: Any) -> dict[str, Any]:
    """:func:`orders_study`, and with ``outdir`` (an existing directory) ``orders.md``
    and ``orders.csv`` written into it.

    Parameters
    ----------
    outdir : path, optional
    **options
        Of :func:`orders_study`.
    """
    study = orders_study(**options)
    if outdir is not None:
        out = Path(outdir)
        (out / "orders.md").write_text(report_markdown(study), encoding="utf-8")
        (out / "orders.csv").write_text(rows_csv(study["rows"]), encoding="utf-8")
        study["files"] = ["orders.md", "orders.csv"]
    return study


def cmd_example(args: argparse.Namespace) -> int:
    """``vemwear example orders -o OUTDIR [--reference-h N] [--solver S]``: the default
    study (the reference 1/N, levels below it) written atomically into ``OUTDIR``."""
    from ..runner import atomic_output_dir, check_output_dir

    ref = int(args.reference_h or REFERENCE_N)
    opts: dict[str, Any] = {
        "reference": ref,
        "levels": {k: tuple(n for n in v if n < ref) for k, v in LEVELS.items()},
        "solver": SolverOptions(method=args.solver or "newton"),
    }
    log = None if args.no_progress else (lambda s: print(s, flush=True))
    out = check_output_dir(args.outdir, args.force)
    t0 = time.perf_counter()
    with atomic_output_dir(out, args.force) as tmp:
        study = run(tmp, log=log, **opts)
    print(report_markdown(study))
    print(f"total {time.perf_counter() - t0:.1f} s; written to {out}")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m vemwear.paper.orders [-o DIR] [--quick] ...``: print both tables."""
    p = argparse.ArgumentParser(prog="python -m vemwear.paper.orders", description=__doc__)
    p.add_argument("-o", "--outdir", help="write orders.md and orders.csv here (created)")
    p.add_argument("--reference-h", type=int, default=REFERENCE_N, metavar="N")
    p.add_argument("--small-steps", type=int, default=SMALL_STEPS, metavar="S")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument(
        "--quick",
        action="store_true",
        help="reference 1/64 with 256 steps, k = 1 up to 1/32, k = 2 up to 1/16",
    )
    p.add_argument("--solver", default="newton")
    a = p.parse_args(argv)
    opts: dict[str, Any] = {
        "reference": a.reference_h,
        "small_steps": a.small_steps,
        "repeats": a.repeats,
        "solver": a.solver,
    }
    if a.quick:
        opts.update(reference=64, small_steps=256, levels={1: (4, 8, 16, 32), 2: (4, 8, 16)})
    else:
        opts["levels"] = {k: tuple(n for n in v if n < a.reference_h) for k, v in LEVELS.items()}
    out = None
    if a.outdir:
        out = Path(a.outdir)
        out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    study = run(out, log=lambda s: print(s, flush=True), **opts)
    print()
    print(report_markdown(study))
    print(f"total {time.perf_counter() - t0:.1f} s" + (f"; written to {out}" if out else ""))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
