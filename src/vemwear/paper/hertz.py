"""Hertz contact under load control, against the closed forms (not in the paper).

A body pressed by a rigid holder with the force P on a rigid foundation (no soft layer:
p = 0, Signorini contact on the rigid layer at the distance g), with the initial gap of a
parabola of radius R (docs/method.md sections 1c, 1d and 8):

* **2D line contact** (plane strain): a block of (0, 8) x (0, 4) with the gap
  (x - 4)^2 / (2R), squares refined towards the contact zone (hanging nodes), the
  holder on its top; half-width a = sqrt(4 P R / (pi E*)), peak pressure
  p0 = 2 P / (pi a), p(x) = p0 sqrt(1 - x^2/a^2), E* = E / (1 - nu^2) (Johnson, *Contact
  Mechanics*, 1985, section 5.6);
* **3D sphere on a flat**: a quarter of the box (0, 1)^3 (rollers on its planes of
  symmetry x = 0 and y = 0) with the gap (x^2 + y^2) / (2R), hexahedra graded towards
  the contact zone, the holder on its top with P/4; a = (3 P R / (4 E*))^(1/3),
  p0 = 3 P / (2 pi a^2) (Johnson, section 4.2).

The discrete half-width is measured by the pressure's second moment (exact for the
Hertz profile): a_h^2 = 4 sum w p x^2 / sum w p in 2D, a_h^2 = 5/2 sum w p r^2 / sum w p
in 3D; the peak by the largest nodal pressure, the 2D profile by its relative L2 error
with the nodal weights.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..contact import LinearCompliance
from ..mesh import rectangle_squares, tag_rectangle
from ..mesh.generate3d import box_hexahedra, tag_box
from ..mesh.refine import refine_where
from ..simulate import Prescribed, Problem, Result, RigidPart, TimeGrid
from ..vem import Material
from . import ExampleRun
from .driver import run_example
from .markdown import num
from .spec import Column, Context, Example, text_output

__all__ = ["EXAMPLE", "NAME", "TITLE", "closed_form", "line_contact", "measure", "run", "sphere"]

NAME = "hertz"
TITLE = "Example hertz"
E, NU, R = 1.0, 0.3, 1.0
E_STAR = E / (1.0 - NU**2)  # plane strain, and the sphere's contact modulus
ETA, LAM = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))
WIDTH, HEIGHT = 8.0, 4.0  # the 2D block


def closed_form(dim: int, a: float) -> dict[str, float]:
    """The load P that gives the half-width (radius) a, and the peak pressure p0."""
    if dim == 2:
        P = a * a * math.pi * E_STAR / (4 * R)
        return {"P": P, "a": a, "p0": 2 * P / (math.pi * a)}
    P = 4 * E_STAR * a**3 / (3 * R)
    return {"P": P, "a": a, "p0": 3 * P / (2 * math.pi * a * a)}


def _signorini(mesh: Any, gap: Any, **kw: Any) -> Problem:
    """No soft layer: the rigid layer at g = 0.1 carries the load; no wear."""
    dim = 3 if mesh.points.shape[1] == 3 else 2
    return Problem(
        mesh,
        Material(LAM, ETA),
        TimeGrid.uniform(1.0, 1),
        p=LinearCompliance(0.0),
        g=0.1,
        gap=gap,
        mu=0.0,
        kappa=0.0,
        v_star=(1.0, 0.0, 0.0)[:dim],
        clamped=(),
        **kw,
    )


def line_contact(a: float, levels: int, n: int = 32) -> Problem:
    """The 2D line contact: n x n/2 squares refined ``levels`` times towards the contact
    zone (each level in a region of half the size, down to 2.5 a), the smallest cells of
    side 8 / n / 2^levels."""
    mesh = rectangle_squares((WIDTH, HEIGHT), (n, n // 2))
    h0 = WIDTH / n
    for k in range(levels):
        w = max(2.5 * a, 3 * h0 * 2.0**-k)

        def near(c: NDArray[np.float64], w: float = w) -> NDArray[np.bool_]:
            return (np.abs(c[:, 0] - WIDTH / 2) < w) & (c[:, 1] < w)

        mesh = refine_where(mesh, near)
    mesh = tag_rectangle(mesh, {"holder": "top", "free": ["left", "right"], "contact": "bottom"})
    P = closed_form(2, a)["P"]
    return _signorini(
        mesh,
        lambda x: (x[:, 0] - WIDTH / 2) ** 2 / (2 * R),
        rigid=(RigidPart("holder", force=(None, -P), translation=(0.0, None)),),
    )


def _graded(n_fine: int, n_coarse: int, fine: float, length: float) -> NDArray[np.float64]:
    """Coordinates on (0, length): n_fine equal cells on (0, fine), then n_coarse cells
    growing geometrically from that size."""
    import scipy.optimize as so

    h = fine / n_fine
    q = so.brentq(lambda q: h * q * (q**n_coarse - 1) / (q - 1) - (length - fine), 1.0001, 10)
    coarse = fine + np.cumsum(h * q ** np.arange(1, n_coarse + 1))
    return np.concatenate([np.linspace(0.0, fine, n_fine + 1), coarse])


def sphere(a: float, n_fine: int, n_coarse: int = 8) -> Problem:
    """The quarter of the 3D sphere problem: hexahedra of side 1.5 a / n_fine on
    (0, 1.5 a)^3, growing geometrically to the unit box."""
    axis = _graded(n_fine, n_coarse, 1.5 * a, 1.0)
    n = len(axis) - 1
    mesh = box_hexahedra((1.0, 1.0, 1.0), (n, n, n))
    u = np.linspace(0.0, 1.0, n + 1)
    points = np.column_stack([np.interp(mesh.points[:, k], u, axis) for k in range(3)])
    mesh = tag_box(
        dataclasses.replace(mesh, points=points),
        {"contact": "zmin", "holder": "zmax", "sx": "xmin", "sy": "ymin", "free": ["xmax", "ymax"]},
    )
    P = closed_form(3, a)["P"]
    return _signorini(
        mesh,
        lambda x: (x[:, 0] ** 2 + x[:, 1] ** 2) / (2 * R),
        displacement=(Prescribed("sx", ux=0.0), Prescribed("sy", uy=0.0)),
        rigid=(RigidPart("holder", force=(None, None, -P / 4)),),
    )


def measure(result: Result, a: float) -> dict[str, float]:
    """The discrete half-width, peak pressure (and in 2D the profile's L2 error) of a run,
    relative to the closed form, and the resultant of the pressure over P."""
    pr = result.problem
    dim = pr.dim
    exact = closed_form(dim, a)
    w, p = pr.contact.weights, result.p_rigid[-1]
    X = result.contact_points
    if dim == 2:
        x = X[:, 0] - WIDTH / 2
        r2, factor, total = x * x, 4.0, float(np.sum(w * p))
    else:
        r2, factor, total = X[:, 0] ** 2 + X[:, 1] ** 2, 2.5, 4 * float(np.sum(w * p))
    a_h = math.sqrt(factor * float(np.sum(w * p * r2)) / float(np.sum(w * p)))
    out = {
        "h": float(np.min(np.diff(np.unique(X[:, 0])))),  # the smallest contact edge
        "a_err": a_h / a - 1.0,
        "p0_err": float(p.max()) / exact["p0"] - 1.0,
        "load_err": total / exact["P"] - 1.0,
    }
    if dim == 2:
        ex = exact["p0"] * np.sqrt(np.maximum(1.0 - r2 / (a * a), 0.0))
        out["l2_err"] = math.sqrt(float(np.sum(w * (p - ex) ** 2) / np.sum(w * ex * ex)))
    return out


def problems(a: float, levels: tuple[int, ...], fine3d: tuple[int, ...]) -> dict[str, Problem]:
    """``line<l>`` for the 2D refinement levels and ``sphere<n>`` for the 3D ones."""
    out = {f"line{lv}": line_contact(a, lv) for lv in levels}
    out.update({f"sphere{nf}": sphere(a, nf) for nf in fine3d})
    return out


def _analyse(ctx: Context) -> dict[str, Any]:
    a = float(ctx.params["a"])
    rows = {name: measure(r, a) for name, r in ctx.results.items()}
    last2 = f"line{ctx.params['levels'][-1]}"
    last3 = f"sphere{ctx.params['fine3d'][-1]}"
    return {
        "rows": rows,
        "summary": [
            f"2D line contact at h = a/{a / rows[last2]['h']:.0f}: half-width "
            f"{100 * rows[last2]['a_err']:+.2f} %, peak {100 * rows[last2]['p0_err']:+.2f} %, "
            f"profile L2 {100 * rows[last2]['l2_err']:.2f} %",
            f"3D sphere at h = a/{a / rows[last3]['h']:.0f}: radius "
            f"{100 * rows[last3]['a_err']:+.2f} %, peak {100 * rows[last3]['p0_err']:+.2f} %",
        ],
    }


def table_markdown(ctx: Context) -> str:
    """The errors against refinement, one row a run."""
    a = float(ctx.params["a"])
    head = "| run | cells | a / h | a_h / a - 1 | p0_h / p0 - 1 | profile L2 | resultant / P - 1 |"
    lines = [head, "| --- | --- | --- | --- | --- | --- | --- |"]
    for name, m in ctx.details["rows"].items():
        cells = ctx.results[name].problem.mesh.n_cells
        l2 = num(m["l2_err"], ".2e") if "l2_err" in m else "-"
        lines.append(
            f"| {name} | {cells} | {a / m['h']:.0f} | {num(m['a_err'], '+.2e')} | "
            f"{num(m['p0_err'], '+.2e')} | {l2} | {num(m['load_err'], '+.1e')} |"
        )
    return "\n".join(lines) + "\n"


def _setup(ctx: Context) -> str:
    p = ctx.params
    return (
        f"E = {E}, nu = {NU} (lam = {LAM:.4g}, eta = {ETA:.4g}), R = {R}, a = {p['a']}; the "
        "load P of the closed form for that a on a rigid holder (load control), no soft "
        "layer (p = 0), Signorini contact. 2D: squares of (0, 8) x (0, 4), refinement levels "
        f"{list(p['levels'])} towards the contact zone; 3D: a quarter of (0, 1)^3 with "
        f"{list(p['fine3d'])} hexahedra across 1.5 a, graded to the box."
    )


def _sections(ctx: Context) -> list[str]:
    return [
        "## Errors against the closed forms",
        "",
        table_markdown(ctx),
        "Closed forms (Johnson, Contact Mechanics, 1985): 2D a = sqrt(4PR/(pi E*)), "
        "p0 = 2P/(pi a); 3D a = (3PR/(4E*))^(1/3), p0 = 3P/(2 pi a^2); E* = E/(1 - nu^2).",
        "",
    ]


def _check(params: Mapping[str, Any]) -> None:
    if not (0 < float(params["a"]) < 0.2) or not params["levels"] or not params["fine3d"]:
        raise ValueError(f"{TITLE}: a in (0, 0.2) and at least one level of each")


EXAMPLE = Example(
    name=NAME,
    heading="Hertz contact under load control against the closed forms",
    parameters={"a": 0.05, "levels": (5, 6, 7, 8), "fine3d": (6, 12, 18)},
    problems=problems,
    check=_check,
    setup=_setup,
    runs_description="the output of `vemwear run` for each mesh.",
    run_label=lambda ctx, name, pr: f"{name}: {pr.mesh.n_cells} cells",
    analyse=_analyse,
    columns=(
        Column("run", lambda ctx, n, r: n),
        Column("cells", lambda ctx, n, r: str(r.problem.mesh.n_cells)),
        Column("max iterations", lambda ctx, n, r: str(int(r.iterations.max()))),
        Column("max KKT residual", lambda ctx, n, r: f"{float(r.residuals.max()):.2e}"),
    ),
    sections=(_sections,),
    outputs=(text_output("hertz.md", "the table of errors.", table_markdown),),
    figure_times=lambda pr: (1.0,),
    run_figures=False,
    store="final",
    vtk=False,
    quick={"levels": (4, 5), "fine3d": (4, 6)},
    paper_section=lambda out, sub, run: [
        "## Example hertz: Hertz contact under load control",
        "",
        *run.details.get("summary", []),
        "",
    ],
    headlines={
        "line_a_err": lambda ctx: ctx.details["rows"][f"line{ctx.params['levels'][-1]}"]["a_err"],
        "sphere_a_err": lambda ctx: ctx.details["rows"][f"sphere{ctx.params['fine3d'][-1]}"][
            "a_err"
        ],
    },
)


def run(outdir: Any, **options: Any) -> ExampleRun:
    """Run the example into ``outdir`` (:func:`vemwear.paper.driver.run_example`)."""
    return run_example(EXAMPLE, outdir, **options)
