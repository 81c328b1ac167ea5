"""Orders of k = 1 and k = 2 on the contact problem (vemwear.paper.orders) and the
ParaView output of k = 2 on the refined visualisation mesh (vemwear.post.quadratic)."""

from __future__ import annotations

import csv
import io
from dataclasses import replace
from pathlib import Path

import meshio
import numpy as np
import pytest

from vemwear.paper import ex52, ex55_reference
from vemwear.paper.orders import (
    COLUMNS,
    cost_markdown,
    orders_markdown,
    rows_csv,
    run,
)
from vemwear.paper.orders_errors import OrdersReference, run_final
from vemwear.post.compare import Comparison
from vemwear.post.norms import contact_l2_norm
from vemwear.post.quadratic import refined_level_fields, refined_mesh
from vemwear.post.xdmf import write_xdmf_series
from vemwear.simulate import simulate
from vemwear.vem.dofs2 import interpolate2


@pytest.fixture(scope="module")
def study(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict, Path]:
    out = tmp_path_factory.mktemp("orders")
    st = run(out, levels={1: (8, 16), 2: (8, 16)}, reference=64, small_steps=64, repeats=1)
    return st, out


def _row(rows: list[dict], setting: str, order: int, n: int) -> dict:
    return next(
        r for r in rows if r["setting"] == setting and r["order"] == order and r["inv_h"] == n
    )


def test_space_orders_k2_above_k1(study: tuple[dict, Path]) -> None:
    rows = study[0]["rows"]
    k1, k2 = _row(rows, "k small", 1, 16), _row(rows, "k small", 2, 16)
    # the wear's space error converges faster for k = 2
    assert k2["w_L2_order"] > k1["w_L2_order"] + 0.3
    # the displacement, away from the corners of the clamped side: order about 2 for k = 2
    assert k2["u_H1_int_order"] > 1.6 and k1["u_H1_int_order"] < 1.3
    # over the whole body both are limited by the corner singularities at x = 0
    assert k1["u_H1_order"] < 1.2 and k2["u_H1_order"] < 1.2
    assert k2["u_H1"] < k1["u_H1"]
    # same dofs: k = 2 on h is the k = 1 mesh of h / 2
    assert _row(rows, "k = h", 2, 8)["dofs"] == _row(rows, "k = h", 1, 16)["dofs"]


def test_tables_have_the_columns(study: tuple[dict, Path]) -> None:
    st, out = study
    assert sorted(p.name for p in out.iterdir()) == ["orders.csv", "orders.md"]
    rows = list(csv.DictReader(io.StringIO((out / "orders.csv").read_text())))
    assert tuple(rows[0]) == COLUMNS and len(rows) == 8
    assert rows_csv(st["rows"]) == (out / "orders.csv").read_text()
    head = orders_markdown(st["rows"]).splitlines()[0]
    for col in ("dofs", "`u_H1`", "`w_L2`", "order", "`u_H1_int`"):
        assert col in head
    head = cost_markdown(st["rows"]).splitlines()[0]
    for col in ("dofs", "wall time (s)", "`u_H1`", "`w_L2`"):
        assert col in head
    text = (out / "orders.md").read_text()
    assert "Accuracy against cost" in text and "Errors and orders" in text


def test_k1_errors_agree_with_example_5_5_comparison() -> None:
    """For k = 1 against a k = 1 reference, the errors are Example 5.5's (post.compare)."""
    ref, coarse = run_final(1, 16, 16), run_final(1, 4, 16)
    e = OrdersReference(ref).errors(coarse)
    rr = simulate(ex55_reference.problem(16, 16), store="final")
    rc = simulate(ex55_reference.problem(4, 16), store="final")
    h = Comparison(rr).errors(rc, levels="final")
    assert e["u_H1"] == pytest.approx(h.at_T("u", "H1"), rel=1e-9)
    assert e["w_L2"] == pytest.approx(h.at_T("w", "L2"), rel=1e-9)


def test_k2_wear_along_contact_and_recovered_dofs() -> None:
    st = run_final(2, 4, 8)
    assert st.n_dofs == 2 * (45 + 76 + 32)  # 9 x 5 vertices, 76 edges, 32 cells
    cmp = OrdersReference(st)
    # the Gauss rule on the quadratic wear is the exact L2 norm of contact_l2_norm
    assert cmp.w_norm == pytest.approx(
        contact_l2_norm(st.mesh, st.contact_nodes, st.wear), rel=1e-12
    )
    e = cmp.errors(st)
    assert max(e.values()) < 1e-12


# ----------------------------------------------------------------------------- ParaView, k = 2
@pytest.fixture(scope="module")
def k2_run():
    pr = replace(ex52.problem(0.2, 2.0, divisions=(8, 4), steps=8), order=2)
    return pr, simulate(pr, store=[0.5, 1.0])


def test_k2_xdmf_is_the_refined_mesh(k2_run, tmp_path: Path) -> None:
    pr, r = k2_run
    mesh = pr.mesh
    npt, ne, nc = mesh.n_points, len(mesh.edges), mesh.n_cells
    assert r.dofs is not None and r.dofs.shape == (2, pr.space.n_dofs)
    assert np.array_equal(pr.space.vertex_values(r.dofs[1]), r.u[1])
    x = write_xdmf_series(r, tmp_path)
    with meshio.xdmf.TimeSeriesReader(x) as rd:
        pts, cells = rd.read_points_cells()
        assert pts.shape == (npt + ne + nc, 2)
        assert np.allclose(pts[npt : npt + ne], mesh.points[mesh.edges].mean(axis=1))
        assert [c.type for c in cells] == ["triangle"]
        assert len(cells[0].data) == 2 * mesh.cell_sizes.sum()
        for k in range(2):
            t, pdata, cdata = rd.read_data(k)
            lv = r.u_levels[k]
            assert t == r.t[lv]
            u = pdata["displacement"][:, :2]
            assert np.array_equal(u[:npt], r.displacement(lv))
            # edge midpoints: the edge's quadratic, (6 m_e - v_a - v_b) / 4
            V = r.dofs[k][: 2 * npt].reshape(-1, 2)
            M = r.dofs[k][2 * npt : 2 * (npt + ne)].reshape(-1, 2)
            E = mesh.edges
            assert np.allclose(u[npt : npt + ne], (6 * M - V[E[:, 0]] - V[E[:, 1]]) / 4, atol=0)
            # ... which is the trace the contact sees: u_nu at the midpoint contact nodes
            nodes = r.contact_nodes
            mid = nodes >= npt
            assert np.allclose(-u[nodes[mid], 1], r.u_nu[lv][mid], rtol=1e-12, atol=1e-15)
            assert np.array_equal(pdata["wear"][nodes], r.wear[lv])
            assert set(cdata) == {"strain", "stress", "von_mises", "cell_id"}
            assert np.array_equal(cdata["cell_id"][0], np.repeat(mesh.edge_cells, 2))


def test_refined_fields_exact_for_quadratics(k2_run) -> None:
    """A quadratic displacement (its dofs) is sampled exactly at every refined point,
    the vertex averages through Pi, and its strain on every sub-triangle."""
    pr, r = k2_run

    def u(x, t=0.0):
        X, Y = x[:, 0], x[:, 1]
        return np.column_stack([1 + X * X - 0.5 * X * Y, -2 * X - Y * Y + 0.3 * X * Y])

    q = replace(r, dofs=np.stack([interpolate2(pr.mesh, u)] * 2))
    rm = refined_mesh(pr.mesh)
    pdata, cdata = refined_level_fields(q, int(r.u_levels[1]), rm)
    assert np.abs(pdata["displacement"][:, :2] - u(rm.points)).max() < 1e-12
    c = rm.points[rm.triangles].mean(axis=1)
    exx, eyy = 2 * c[:, 0] - 0.5 * c[:, 1], -2 * c[:, 1] + 0.3 * c[:, 0]
    exy = 0.5 * (-0.5 * c[:, 0] + (-2 + 0.3 * c[:, 1]))
    strain = cdata["strain"].reshape(-1, 3, 3)
    assert np.abs(strain[:, 0, 0] - exx).max() < 1e-10
    assert np.abs(strain[:, 1, 1] - eyy).max() < 1e-10
    assert np.abs(strain[:, 0, 1] - exy).max() < 1e-10
