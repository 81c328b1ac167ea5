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
    The same on the interior region x in :data:`INTERIOR` = (1/4, 7/4) only, away from
    the side x = 0 whose corners make u singular (docs/paper.md).

Orders are log2 of the ratios of successive errors (h halved). The wall time of a run is
the least over ``repeats`` runs of building the problem and :func:`~vemwear.simulate.simulate`
(assembly, factorization, time loop; not the error evaluation).

``python -m vemwear.paper.orders -o DIR`` (or ``vemwear example orders -o DIR``) prints the
two tables and writes ``orders.md`` and ``orders.csv``.

One job, the study and its two tables; a little over 500 lines with the error
definitions, which are this study's own (k = 2 wear on Gamma_C, nested comparison).
"""

from __future__ import annotations

import argparse
import csv
import io
import itertools
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..mesh.locate import nested_cells, point_segment_distance
from ..mesh.polymesh import Mesh
from ..simulate import SolverOptions, simulate
from ..vem.dofs2 import GAUSS3, edge_ids, project2
from ..vem.local import Material
from ..vem.projection import Projection
from ..vem.quadrature import polygon_quadrature
from . import ex55_reference
from .markdown import num, table

__all__ = [
    "COLUMNS",
    "LEVELS",
    "REFERENCE_N",
    "SETTINGS",
    "SMALL_STEPS",
    "FinalState",
    "OrdersReference",
    "cmd_example",
    "cost_markdown",
    "main",
    "orders_markdown",
    "orders_study",
    "rows_csv",
    "run",
    "run_final",
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
#: The x-range of the interior region of the ``*_int`` errors: away from the clamped side
#: x = 0, whose corners make u singular, and from the side x = 2.
INTERIOR: tuple[float, float] = (0.25, 1.75)

#: The error columns (each with its ``_order``).
ERRORS: tuple[str, ...] = ("u_H1", "w_L2", "u_H1_int", "w_L2_int")

_CHUNK = 65536  # quadrature points per block of Pi evaluations


# ----------------------------------------------------------------------------- one run
@dataclass(frozen=True, eq=False)
class FinalState:
    """A run at t = T: all its dofs and its wear, and what it cost.

    Attributes
    ----------
    mesh : Mesh
    material : Material
    order : int
        k of the space.
    dofs : (n_dofs,) array
        Every dof of the displacement at T (k = 2: vertex values, edge and cell means).
    contact_nodes : (m,) int array
        As :attr:`vemwear.simulate.Result.contact_nodes` (k = 2: ``n_points + e`` is the
        midpoint of ``mesh.edges[e]``).
    wear : (m,) array
        The wear at T at the contact nodes.
    steps : int
        Time steps.
    wall : float
        Least wall time (s) of building the problem and simulating it.
    """

    mesh: Mesh
    material: Material
    order: int
    dofs: NDArray[np.float64]
    contact_nodes: NDArray[np.int64]
    wear: NDArray[np.float64]
    steps: int
    wall: float

    @property
    def n_dofs(self) -> int:
        return int(self.dofs.size)

    def pi_at(
        self, points: NDArray[np.float64], cells: NDArray[np.int64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Values (q, 2) and gradients (q, 2, 2), ``[i, j] = d_j u_i``, of ``Pi u`` of the
        cell ``cells[j]`` at ``points[j]``, in blocks of points."""
        if self.order == 1:
            lf = Projection(self.mesh)(self.dofs)
            return lf.at(points, cells), lf.gradient[cells]
        f = project2(self.mesh, self.material, self.dofs)
        val, grad = np.empty((len(points), 2)), np.empty((len(points), 2, 2))
        for a in range(0, len(points), _CHUNK):
            val[a : a + _CHUNK], grad[a : a + _CHUNK] = f.at(
                points[a : a + _CHUNK], cells[a : a + _CHUNK]
            )
        return val, grad

    def wear_at(self, x: NDArray[np.float64]) -> NDArray[np.float64]:
        """The wear at T at points ``x`` (q, 2) of Gamma_C: linear (k = 1) or quadratic
        (k = 2) on the contact edge nearest each point; 0 at the clamped end."""
        m, nodes = self.mesh, self.contact_nodes
        n = m.n_points
        full = np.zeros(n + len(m.edges))
        full[nodes] = self.wear
        E = m.part_edges("contact")
        dist, s = point_segment_distance(
            x[:, None, :], m.points[E[:, 0]][None], m.points[E[:, 1]][None]
        )
        j = np.argmin(dist, axis=1)
        s = s[np.arange(len(x)), j]
        a, b = full[E[j, 0]], full[E[j, 1]]
        if not np.any(nodes >= n):
            return np.asarray((1.0 - s) * a + s * b)
        c = full[n + edge_ids(m, E[j, 0], E[j, 1])]
        return np.asarray(a * (1 - s) * (1 - 2 * s) + 4.0 * c * s * (1 - s) + b * s * (2 * s - 1))


def run_final(
    order: int,
    n: int,
    steps: int,
    *,
    solver: SolverOptions | str = "newton",
    repeats: int = 1,
) -> FinalState:
    """Solve Example 5.5's problem with k = ``order``, h = 1/n and ``steps`` time steps.

    The displacement at T is stored as vertex values by :func:`simulate`; all its dofs
    are recovered afterwards from the last level's contact unknowns (one more solve with
    the converged state as the initial guess, not timed).

    Parameters
    ----------
    order : {1, 2}
    n : int
        ``1/h``.
    steps : int
        Uniform time steps on [0, 1].
    solver : SolverOptions or str
    repeats : int
        Runs whose least wall time is kept.
    """
    opts = SolverOptions(method=solver) if isinstance(solver, str) else solver
    best, kept = math.inf, None
    last: dict[str, Any] = {}

    def keep_last(_n: int, sol: Any) -> None:
        last["sol"] = sol

    for _ in range(max(int(repeats), 1)):
        t0 = time.perf_counter()
        pr = replace(ex55_reference.problem(n, steps), order=order)
        res = simulate(pr, opts, store="final", callback=keep_last)
        wall = time.perf_counter() - t0
        if wall < best:
            best, kept = wall, (pr, res, last["sol"])
    assert kept is not None
    pr, res, sol = kept
    d = pr.discrete
    L = len(pr.time.t)
    step = d.step_data(L - 1, res.wear[-1])
    full = d.step_solver(opts).solve(step, sol, recover=True)
    dofs = d.full_dofs(full.u, step.t)
    vert = pr.space.vertex_values(dofs)
    scale = max(float(np.abs(res.u[-1]).max()), 1e-300)
    if float(np.abs(vert - res.u[-1]).max()) > 1e-6 * scale:
        raise RuntimeError("orders: the recovered dofs do not match the stored displacement")
    return FinalState(
        mesh=pr.mesh,
        material=pr.material,
        order=order,
        dofs=np.asarray(dofs, dtype=float),
        contact_nodes=np.asarray(res.contact_nodes, dtype=np.int64),
        wear=np.asarray(res.wear[-1], dtype=float),
        steps=int(steps),
        wall=best,
    )


# ----------------------------------------------------------------------------- errors
class OrdersReference:
    """Errors at T against one reference run on a mesh nested in every compared one.

    The reference's ``Pi u`` and wear are evaluated once at the quadrature points: the
    degree-5 rule on the fan of every reference cell and three-point Gauss on every
    reference contact edge (module docstring).

    Parameters
    ----------
    reference : FinalState
    interior : (float, float)
        The x-range of the interior region (:data:`INTERIOR`); its ends must be lines of
        every compared mesh.
    """

    def __init__(self, reference: FinalState, interior: tuple[float, float] = INTERIOR) -> None:
        self.reference = ref = reference
        self.x, self.w, self.cell = polygon_quadrature(ref.mesh, 5)
        self.val, self.grad = ref.pi_at(self.x, self.cell)
        self.inside = (self.x[:, 0] > interior[0]) & (self.x[:, 0] < interior[1])
        self.u_norm = math.sqrt(_h1_sq(self.w, self.val, self.grad))
        ins = self.inside
        self.u_norm_int = math.sqrt(_h1_sq(self.w[ins], self.val[ins], self.grad[ins]))
        m = ref.mesh
        E = m.part_edges("contact")
        A, B = m.points[E[:, 0]], m.points[E[:, 1]]
        L = np.linalg.norm(B - A, axis=1)
        s, wq = GAUSS3
        self.xc = (A[:, None, :] + s[None, :, None] * (B - A)[:, None, :]).reshape(-1, 2)
        self.wc = (L[:, None] * wq[None, :]).ravel()
        self.wear = ref.wear_at(self.xc)
        self.inside_c = (self.xc[:, 0] > interior[0]) & (self.xc[:, 0] < interior[1])
        self.w_norm = math.sqrt(float(np.sum(self.wc * self.wear**2)))
        self.w_norm_int = math.sqrt(float(np.sum((self.wc * self.wear**2)[self.inside_c])))

    def errors(self, state: FinalState) -> dict[str, float]:
        """The relative errors of ``state`` at T (module docstring): ``u_H1``, ``w_L2``
        and ``u_H1_int``, ``w_L2_int`` on the interior region only.

        Raises
        ------
        NonNestedMeshError
            If the reference mesh is not nested in the run's.
        """
        cells = nested_cells(state.mesh, self.reference.mesh)[self.cell]
        val, grad = state.pi_at(self.x, cells)
        dv, dg = val - self.val, grad - self.grad
        du = np.sum(dv * dv, axis=1) + np.sum(dg * dg, axis=(1, 2))
        dw = self.wc * (state.wear_at(self.xc) - self.wear) ** 2
        ins, insc = self.inside, self.inside_c
        return {
            "u_H1": math.sqrt(float(self.w @ du)) / self.u_norm,
            "w_L2": math.sqrt(float(dw.sum())) / self.w_norm,
            "u_H1_int": math.sqrt(float(self.w[ins] @ du[ins])) / self.u_norm_int,
            "w_L2_int": math.sqrt(float(dw[insc].sum())) / self.w_norm_int,
        }


def _h1_sq(w: NDArray[np.float64], val: NDArray[np.float64], grad: NDArray[np.float64]) -> float:
    return float(w @ (np.sum(val * val, axis=1) + np.sum(grad * grad, axis=(1, 2))))


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
