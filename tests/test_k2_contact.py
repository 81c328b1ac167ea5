"""Second-order virtual elements (k = 2) in the whole scheme: contact nodes at vertices
and edge midpoints with Simpson's weights, the three step solvers, closed forms, the
order against k = 1, configuration, CLI and resume (docs/method.md, section 9)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from conftest import npz_arrays, small_config
from test_closed_forms import K_S, KAPPA, W, block
from test_solvers import paper_problem, rel
from vemwear.cli.main import main
from vemwear.config import load_config
from vemwear.contact import LinearCompliance
from vemwear.contact.phi import phi_h
from vemwear.mesh import rectangle_squares, select_parts
from vemwear.paper import ex52
from vemwear.paper.manufactured import convergence_study
from vemwear.post.norms import contact_l2_norm
from vemwear.simulate import Prescribed, Problem, SolverOptions, TimeGrid, simulate
from vemwear.util.hashing import sha256_json
from vemwear.vem import Material
from vemwear.vem.dofs2 import interpolate2


@pytest.fixture(scope="module")
def small():
    pr = paper_problem(divisions=(8, 4), steps=8, order=2)
    return pr, simulate(pr, SolverOptions("newton", tol=1e-12))


# ----------------------------------------------------------------------------- contact nodes
def test_contact_nodes_vertices_and_midpoints(small):
    pr, _ = small
    cb, mesh = pr.contact, pr.mesh
    n = mesh.n_points
    mid = cb.nodes >= n
    # bottom of (0, 2): 8 edges of 1/4; the vertex x = 0 is clamped
    assert mid.sum() == 8 and (~mid).sum() == 8
    assert np.all(np.diff(cb.s) > 0) and np.allclose(cb.s, cb.points[:, 0])
    assert np.allclose(cb.points[mid], 0.5 * (mesh.points[mesh.edges[cb.nodes[mid] - n]]).sum(1))
    assert np.allclose(cb.weights[mid], 4 * 0.25 / 6)
    assert np.allclose(cb.weights[~mid][:-1], 2 * 0.25 / 6)  # the last vertex: one edge
    # Simpson's weights plus the clamped end's 1/24 integrate constants on Gamma_C
    assert cb.weights.sum() == pytest.approx(2.0 - 0.25 / 6)
    assert np.allclose(cb.normals, [0.0, -1.0])


def test_trace_is_the_quadratic_at_the_midpoints(small):
    """N and T of the nodes give the normal and tangential components of a quadratic
    field at the vertices and the midpoints exactly; phi_h is Simpson's rule."""
    pr, _ = small
    cb = pr.contact

    def u(x, t=0.0):
        X, Y = x[:, 0], x[:, 1]
        return np.column_stack([1 + X * X - 0.5 * X * Y, -2 * X - Y * Y + 0.3 * X * Y])

    dofs = interpolate2(pr.mesh, u)
    val = u(cb.points)
    assert np.abs(cb.N @ dofs - np.sum(val * cb.normals, axis=1)).max() < 1e-13
    assert np.abs(cb.Tau @ dofs - np.sum(val * cb.tangents, axis=1)).max() < 1e-13
    # phi_h with p(r) = r, w = 0, mu = 0 is Simpson's rule for int u_nu^2 over Gamma_C,
    # exact for u_nu = -u_y(x, 0) = 2 x (the clamped end x = 0 has u = 0)
    law = LinearCompliance(1.0)
    phi = phi_h(cb, law, np.zeros(cb.m), np.zeros(2), np.zeros(cb.m), dofs, dofs)
    assert phi == pytest.approx(32.0 / 3.0, rel=1e-13)
    # the L2 norm of a quadratic wear along Gamma_C is exact (0 at the clamped end)
    w = cb.points[:, 0] ** 2
    assert contact_l2_norm(pr.mesh, cb.nodes, w) ** 2 == pytest.approx(32.0 / 5.0, rel=1e-13)


# ----------------------------------------------------------------------------- solvers
def test_solvers_agree_k2(small):
    pr, rn = small
    assert pr.space.order == 2 and rn.u.shape == (9, pr.mesh.n_points, 2)
    rf = simulate(pr, SolverOptions("newton-full"))
    ru = simulate(pr, SolverOptions("uzawa", tol=1e-12))
    for other, tol in ((rf, 1e-10), (ru, 1e-8)):
        for name in ("u", "wear", "p_rigid", "p_soft", "u_nu"):
            assert rel(getattr(other, name), getattr(rn, name)) < tol, name
    assert ru.iterations.min() > rn.iterations.max()


def test_kkt_and_wear_k2(small):
    pr, r = small
    assert r.residuals.max() < 1e-10
    assert np.any(np.isclose(r.u_nu, pr.nodal["g"], rtol=0, atol=1e-12))  # rigid layer
    assert np.any(r.p_soft > 1e-6)
    assert np.all(r.wear >= 0) and np.all(np.diff(r.wear, axis=0) >= 0)
    assert r.wear[-1].max() > 0.01
    # the force of the layer balances body force and clamped reaction
    assert np.abs(r.forces.sum(axis=1)[1:] - [0.0, 0.06 * 2.0]).max() < 1e-10


def test_order_1_default_and_fingerprint():
    p1 = paper_problem(divisions=(4, 2), steps=2)
    p2 = replace(p1, order=2)
    assert p1.order == 1 and "order" not in p1.describe()
    assert p2.describe()["order"] == 2
    assert sha256_json(p1.fingerprint()) != sha256_json(p2.fingerprint())
    assert p2.discrete.n_dof == 2 * (p2.mesh.n_points + len(p2.mesh.edges) + p2.mesh.n_cells)
    with pytest.raises(ValueError, match="order"):
        replace(p1, order=3)


def test_rigid_motions_named_k2():
    mesh = select_parts(
        rectangle_squares((2.0, 1.0), (4, 2)),
        {"rollers": "left", "contact": "bottom", "free": "rest"},
    )
    with pytest.raises(Exception, match="translation in x"):
        Problem(
            mesh,
            Material(4.0, 4.0),
            TimeGrid.uniform(1.0, 2),
            clamped=(),
            displacement=(Prescribed("rollers", uy=0.0),),
            order=2,
        )
    # rollers on the left and a prescribed u_y on the top hold the block
    mesh = select_parts(
        rectangle_squares((2.0, 1.0), (4, 2)),
        {"rollers": "left", "top": "top", "contact": "bottom", "free": "rest"},
    )
    Problem(
        mesh,
        Material(4.0, 4.0),
        TimeGrid.uniform(1.0, 2),
        clamped=(),
        displacement=(Prescribed("rollers", ux=0.0), Prescribed("top", uy=-0.01)),
        order=2,
    )


# ----------------------------------------------------------------------------- closed form
@pytest.mark.parametrize("family", ["squares", "voronoi"])
def test_pushed_block_closed_form_k2(family: str) -> None:
    """The uniaxial field is in the k = 2 space: the discrete closed form of the k = 1
    test holds to round-off at every contact node, vertices and midpoints."""
    delta, gap, n = 0.05, 0.01, 20
    r = simulate(replace(block(family, -delta, gap, n), order=2), SolverOptions("newton"))
    assert np.any(r.contact_nodes >= r.problem.mesh.n_points)
    k = 1.0 / n
    e = (delta - gap) * (1 - k * KAPPA * K_S) ** np.arange(n + 1)
    assert np.abs(r.wear - (delta - gap - e)[:, None]).max() < 1e-13
    assert np.abs(r.p_soft - K_S * e[:, None]).max() < 1e-13
    assert np.abs(r.p_rigid).max() == 0.0
    F = r.forces
    assert np.abs(F[:, 0, 1] - K_S * e * W).max() < 1e-12
    assert np.abs(F.sum(axis=1)).max() < 1e-12
    u = r.displacement(-1)
    assert np.abs(u[:, 0]).max() < 1e-13


# ----------------------------------------------------------------------------- accuracy
def _profile(r, x):
    """w(T) along x: piecewise linear (k = 1), quadratic through vertex, midpoint,
    vertex (k = 2)."""
    n = r.problem.mesh.n_points
    s, w = np.asarray(r.contact_s), np.asarray(r.wear[-1])
    if not np.any(r.contact_nodes >= n):
        return np.interp(x, s, w)
    v = r.contact_nodes < n
    sv, wv, sm, wm = s[v], w[v], s[~v], w[~v]
    j = np.clip(np.searchsorted(sv, x) - 1, 0, len(sv) - 2)
    a, b = sv[j], sv[j + 1]
    t = (x - a) / (b - a)
    mid = wm[np.searchsorted(sm, 0.5 * (a + b))]
    return wv[j] * (1 - t) * (1 - 2 * t) + wv[j + 1] * t * (2 * t - 1) + mid * 4 * t * (1 - t)


def test_k2_closer_to_a_fine_solution_on_example_5_2() -> None:
    """Example 5.2 (set 2) at h = 1/16: the wear at T of k = 2 is closer to k = 1 on
    h = 1/64 (same time grid) than k = 1 at h = 1/16 is (max over x in [1/16, 2])."""
    x = np.linspace(1 / 16, 2.0, 1001)
    d = ex52.DATA_SETS["set2"]

    def wear(div, order):
        pr = replace(ex52.problem(d["mu"], d["kappa"], divisions=div, steps=16), order=order)
        return _profile(simulate(pr, "newton", store="final"), x)

    ref = wear((128, 64), 1)
    e1 = np.abs(wear((32, 16), 1) - ref).max()
    e2 = np.abs(wear((32, 16), 2) - ref).max()
    assert e2 < 0.7 * e1, (e1, e2)


def test_manufactured_orders_k2() -> None:
    rows = convergence_study(["squares"], levels=3, n0=4, order=2)
    assert rows[-1]["order"] == 2
    assert rows[-1]["H1_order"] > 1.8 and rows[-1]["L2_order"] > 2.7


# ----------------------------------------------------------------------------- config, CLI
CONFIG = small_config("k = 2", steps=40, vem={"order": 2})


@pytest.fixture
def config(tmp_path: Path) -> Path:
    p = tmp_path / "k2.toml"
    p.write_text(CONFIG)
    return p


def test_config_order_2(config: Path) -> None:
    cfg = load_config(config)
    assert cfg.problem.order == 2


def test_run_and_resume_k2_bitwise(
    config: Path, tmp_path: Path, stop_at: Callable[..., None], capsys: pytest.CaptureFixture
) -> None:
    ref = tmp_path / "ref"
    assert main(["run", str(config), "-o", str(ref), "--no-progress"]) == 0
    a = npz_arrays(ref)
    assert np.any(a["contact_nodes"] >= len(a["points"]))  # the midpoints
    assert a["u"].shape[1:] == a["points"].shape
    out = tmp_path / "out"
    stop_at(36)
    assert main(["run", str(config), "-o", str(out), "--no-progress"]) == 3
    stop_at(None)
    capsys.readouterr()
    assert main(["run", str(config), "-o", str(out), "--no-progress", "--resume"]) == 0
    assert "resumed from level 36" in capsys.readouterr().out
    b = npz_arrays(out)
    for k in ("u", "dofs", "wear", "u_nu", "p_rigid", "p_soft", "iterations", "residuals"):
        assert np.array_equal(a[k], b[k]), k
    assert np.array_equal(a["contact_nodes"], b["contact_nodes"])
    # every dof of the stored levels, its vertex part the displacement
    assert a["dofs"].shape[0] == a["u"].shape[0] and a["dofs"].shape[1] > a["u"][0].size
    assert np.array_equal(a["dofs"][:, : a["u"][0].size], a["u"].reshape(len(a["u"]), -1))


def test_run_writes_the_refined_paraview_series_k2(config: Path, tmp_path: Path) -> None:
    """`vemwear run` of order 2 streams every dof to result.h5 and writes the ParaView
    series on the refined mesh (vertices, edge midpoints, a point per cell)."""
    import tomllib

    import h5py
    import meshio

    from vemwear.config import apply_overrides
    from vemwear.studies import _toml

    data = apply_overrides(
        tomllib.loads(config.read_text()), {"output.vtk": True, "output.store_u": "final"}
    )
    cfg = tmp_path / "c.toml"
    cfg.write_text(_toml.dumps(data))
    out = tmp_path / "out"
    assert main(["run", str(cfg), "-o", str(out), "--no-progress"]) == 0
    mesh = load_config(cfg).problem.mesh
    with h5py.File(out / "result.h5") as f:
        assert f["dofs"].shape[0] == f["u"].shape[0] == 1
    with meshio.xdmf.TimeSeriesReader(out / "solution.xdmf") as rd:
        pts, cells = rd.read_points_cells()
        _t, point_data, _c = rd.read_data(0)
    n_edges = len(mesh.edges)
    assert len(pts) == mesh.n_points + n_edges + mesh.n_cells
    assert [c.type for c in cells] == ["triangle"]
    u_pts = next(v for k, v in point_data.items() if np.shape(v)[-1] in (2, 3))
    assert np.array_equal(u_pts[: mesh.n_points, :2], npz_arrays(out)["u"][-1])


@pytest.mark.parametrize("method", ["newton", "newton-full"])
def test_simulate_resume_k2(small, method: str) -> None:
    """An interrupted k = 2 run resumed in memory: the condensed Newton bitwise, the
    full-space Newton (no displacement guess from vertex values) to its tolerance."""
    pr, _ = small
    ref = simulate(pr, method, recover_block=2)

    def stop(n: int, _sol: object) -> None:
        if n == 5:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt) as exc:
        simulate(pr, method, callback=stop, recover_block=2)
    part = exc.value.partial_result  # type: ignore[attr-defined]
    assert 0 < part.completed <= 5
    r = simulate(pr, method, resume=part, recover_block=2)
    if method == "newton":
        assert np.array_equal(r.wear, ref.wear) and np.array_equal(r.u, ref.u)
    else:
        assert rel(r.wear, ref.wear) < 1e-10 and rel(r.u, ref.u) < 1e-10
