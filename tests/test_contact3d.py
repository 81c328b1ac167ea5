"""Contact with wear in 3D: the solvers agree, a whole run on
tetrahedra equals an independent P1 computation with scikit-fem, the pushed block wears
as its closed form, and prisms with rollers recover the 2D (plane strain) solution.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from vemwear.contact import LinearCompliance
from vemwear.mesh import rectangle_squares, tag_rectangle
from vemwear.mesh.generate3d import box_hexahedra, box_tetrahedra, extrude, tag_box
from vemwear.mesh.polyhedra import Mesh3D
from vemwear.mesh.voronoi3d import box_voronoi
from vemwear.simulate import Prescribed, Problem, SolverOptions, TimeGrid, simulate
from vemwear.vem import Material

# the paper's data (Section 5), in 3D
LAM, ETA = 4.0, 4.0
C_P, G, MU, KAPPA = 0.4, 0.1, 0.2, 2.0
PAPER_SIDES = {"clamped": "xmin", "contact": "zmin", "traction": ["xmax", "ymin", "ymax", "zmax"]}


def rel(a, b):
    return float(np.abs(np.asarray(a) - b).max() / max(np.abs(b).max(), 1e-300))


def paper_problem(mesh: Mesh3D, steps: int = 8, f1=(0.0, 0.0, -0.06), **kw) -> Problem:
    return Problem(
        tag_box(mesh, PAPER_SIDES),
        Material(LAM, ETA),
        TimeGrid.uniform(1.0, steps),
        f1=f1,
        p=LinearCompliance(C_P),
        g=G,
        mu=kw.pop("mu", MU),
        kappa=KAPPA,
        v_star=kw.pop("v_star", (1.0, 0.0, 0.0)),
        **kw,
    )


# ----------------------------------------------------------------------------- (a) solvers
@pytest.mark.parametrize("f1", [(0.0, 0.0, -0.06), (0.0, 0.0, -0.6)], ids=["paper", "rigid"])
def test_solvers_agree_in_3d(f1) -> None:
    """Condensed Newton, full-space Newton and Uzawa on 4 x 2 x 2 hexahedra, 8 steps; with
    the larger load the body reaches the rigid layer."""
    pr = paper_problem(box_hexahedra((2.0, 1.0, 1.0), (4, 2, 2)), f1=f1)
    cb = pr.contact
    assert cb.m == 12 and cb.points.shape == (12, 3)
    assert np.isclose(cb.weights.sum(), 2.0 - 0.25)  # the clamped column's quarter faces
    assert np.allclose(cb.normals, [0.0, 0.0, -1.0]) and np.allclose(cb.tangents, [1, 0, 0])
    ref = simulate(pr, SolverOptions("newton"))
    assert ref.u.shape == (9, pr.mesh.n_points, 3)
    for method in ("newton-full", "uzawa"):
        other = simulate(pr, SolverOptions(method, tol=1e-11, max_iter=20000))
        for name in ("u", "wear", "p_soft", "p_rigid", "u_nu"):
            assert rel(getattr(other, name), getattr(ref, name)) < 1e-8, (method, name)
    assert ref.residuals.max() < 1e-9
    assert np.all(ref.wear >= 0) and np.all(np.diff(ref.wear, axis=0) >= 0)
    assert ref.wear[-1].max() > 0.01
    if f1[2] < -0.1:
        assert ref.p_rigid.max() > 0 and np.isclose(ref.u_nu.max(), G, rtol=1e-12)
    # the forces balance: body force + layer + clamp = 0
    F = ref.forces
    assert F is not None and F.shape == (9, 2, 3)
    weight = np.array(f1) * 2.0
    assert np.abs(F.sum(axis=1) + weight).max() < 1e-10


def test_turning_foundation_velocity_gets_two_friction_rows() -> None:
    """A v* that turns has the two fixed tangents of every node as friction rows
    (tests/test_sliding.py runs it)."""
    pr = paper_problem(
        box_hexahedra((2.0, 1.0, 1.0), (2, 1, 1)),
        v_star=lambda t: (np.cos(3 * t), np.sin(3 * t), 0.0),
    )
    cb = pr.contact
    assert cb.tangents2 is not None and pr.discrete.system.Tau.shape[0] == 2 * cb.m
    assert np.allclose(np.sum(cb.tangents * cb.tangents2, axis=1), 0.0)


def test_free_rigid_motions_named_in_3d() -> None:
    sides = {"contact": "zmin", "top": "zmax", "free": ["xmin", "xmax", "ymin", "ymax"]}
    mesh = tag_box(box_hexahedra((1.0, 1.0, 1.0), (2, 2, 2)), sides)
    with pytest.raises(Exception, match="translation along \\(1, 0, 0\\)"):
        Problem(
            mesh,
            Material(LAM, ETA),
            TimeGrid.uniform(1.0, 2),
            clamped=(),
            displacement=(Prescribed("top", uy=0.0, uz=0.0),),
        )
    with pytest.raises(Exception, match="rotation about the axis \\(0, 0, 1\\)"):
        Problem(
            mesh,
            Material(LAM, ETA),
            TimeGrid.uniform(1.0, 2),
            clamped=(),
            displacement=(Prescribed("top", uz=0.0),),
        )


# ----------------------------------------------------------------------------- (b) P1 on tets
class TetReference:
    """Independent P1 contact-and-wear solver on tetrahedra of (0, 2) x (0, 1) x (0, 1),
    clamped at x = 0, contact on z = 0 (nodes, weights and normals from coordinates),
    with scikit-fem's stiffness and load; every step problem solved by enumerating the
    3^m contact states (no contact, soft layer, rigid layer) as tests/test_p1_reference.py
    does in 2D. Friction force mu p n*_a with n*_a = -v*_tau/|v*_tau|,
    v*_tau = v* - (v* . nu) nu; wear rate kappa |v*_tau|."""

    def __init__(self, mesh: Mesh3D, f1) -> None:
        from skfem import Basis, ElementTetP1, ElementVector, LinearForm, MeshTet, asm
        from skfem.models.elasticity import linear_elasticity

        P = mesh.points
        tets = mesh.cell_vertex_ids.reshape(-1, 4)
        sm = MeshTet(P.T.copy(), tets.T.copy())
        basis = Basis(sm, ElementVector(ElementTetP1()))
        perm = basis.nodal_dofs.T.ravel()  # ours: 3 v + c

        @LinearForm
        def load(v, w):
            return f1[0] * v[0] + f1[1] * v[1] + f1[2] * v[2]

        K = asm(linear_elasticity(LAM, ETA), basis).toarray()[np.ix_(perm, perm)]
        F = asm(load, basis)[perm]
        nv = len(P)
        fixed = np.zeros(3 * nv, bool)
        clamped = np.flatnonzero(np.abs(P[:, 0]) < 1e-12)
        fixed[(3 * clamped[:, None] + np.arange(3)).ravel()] = True
        self.free = np.flatnonzero(~fixed)
        # the z = 0 triangles: a third of the area to each vertex
        facets = sm.facets[:, sm.boundary_facets()].T
        bottom = facets[np.all(np.abs(P[facets, 2]) < 1e-12, axis=1)]
        area = 0.5 * np.linalg.norm(
            np.cross(P[bottom[:, 1]] - P[bottom[:, 0]], P[bottom[:, 2]] - P[bottom[:, 0]]), axis=1
        )
        weight = np.zeros(nv)
        for j in range(3):
            np.add.at(weight, bottom[:, j], area / 3)
        nodes = np.unique(bottom)
        self.nodes = nodes[P[nodes, 0] > 1e-12]
        self.omega = weight[self.nodes]
        m = self.m = len(self.nodes)
        self.nu = np.tile([0.0, 0.0, -1.0], (m, 1))
        Kf = K[np.ix_(self.free, self.free)]
        pos = -np.ones(3 * nv, dtype=np.int64)
        pos[self.free] = np.arange(len(self.free))
        cd = pos[(3 * self.nodes[:, None] + np.arange(3)).ravel()]
        C = np.zeros((3 * m, len(self.free)))
        C[np.arange(3 * m), cd] = 1.0
        self.Kf, self.Ff, self.C = Kf, F[self.free], C
        self.H = C @ np.linalg.solve(Kf, C.T)
        self.y0 = C @ np.linalg.solve(Kf, self.Ff)
        self.states = np.array(list(itertools.product(range(3), repeat=m)))
        self.nv = nv

    def step(self, w, n_star):
        m, S, nu, om = self.m, self.states, self.nu, self.omega
        on, rigid = S >= 1, S == 2
        dirn = nu + MU * n_star
        H3 = self.H.reshape(m, 3, m, 3)
        Nd = np.einsum("ia,iajb,jb->ij", nu, H3, dirn)
        Nn = np.einsum("ia,iajb,jb->ij", nu, H3, nu)
        yn0 = np.einsum("ia,ia->i", nu, self.y0.reshape(m, 3))
        soft = on * (C_P * om)
        M = np.zeros((len(S), 2 * m, 2 * m))
        rhs = np.zeros((len(S), 2 * m))
        M[:, :m, :m] = np.eye(m) + Nd[None] * soft[:, None, :]
        M[:, :m, m:] = Nn * om
        rhs[:, :m] = yn0 + (soft * w) @ Nd.T
        jj = np.arange(m)
        M[:, m + jj, jj] = rigid
        M[:, m + jj, m + jj] = ~rigid
        rhs[:, m:] = np.where(rigid, G, 0.0)
        sol = np.linalg.solve(M, rhs[..., None])[..., 0]
        y_nu, lam = sol[:, :m], sol[:, m:]
        r = y_nu - w
        tol = 1e-11
        ok = np.where(on, r >= -tol, r <= tol) & (y_nu <= G + tol) & (~rigid | (lam >= -tol))
        valid = np.flatnonzero(np.all(ok, axis=1))
        assert valid.size >= 1, "no admissible contact state"
        assert np.abs(sol[valid] - sol[valid[0]]).max() <= 1e-10
        k = valid[0]
        p = np.where(on[k], C_P * np.maximum(r[k], 0.0), 0.0)
        force = np.zeros(3 * self.nv)
        f = om[:, None] * ((p + lam[k])[:, None] * nu + MU * p[:, None] * n_star)
        force[(3 * self.nodes[:, None] + np.arange(3)).ravel()] = f.ravel()
        uf = np.linalg.solve(self.Kf, self.Ff - force[self.free])
        U = np.zeros(3 * self.nv)
        U[self.free] = uf
        return U.reshape(-1, 3), y_nu[k], lam[k], p

    def run(self, t, v_star):
        L = len(t)
        out = {k: np.zeros((L, self.m)) for k in ("wear", "u_nu", "p_rigid", "p_soft")}
        out["u"] = np.zeros((L, self.nv, 3))
        w = np.zeros(self.m)
        for n in range(L):
            vs = np.asarray(v_star(t[n]), dtype=float)
            vt = vs[None, :] - (self.nu @ vs)[:, None] * self.nu
            speed = np.linalg.norm(vt, axis=1)
            n_star = np.where(speed[:, None] > 0, -vt / np.maximum(speed, 1e-300)[:, None], 0.0)
            out["u"][n], out["u_nu"][n], out["p_rigid"][n], out["p_soft"][n] = self.step(w, n_star)
            out["wear"][n] = w
            if n + 1 < L:
                w = w + (t[n + 1] - t[n]) * KAPPA * speed * out["p_soft"][n]
        return out


@pytest.mark.parametrize("f1", [(0.0, 0.0, -0.06), (0.0, 0.3, -0.5)], ids=["paper", "rigid"])
def test_tetrahedra_run_equals_p1_reference(f1) -> None:
    """A whole run on 3 x 1 x 1 boxes of Kuhn tetrahedra (6 contact nodes), v* with a
    normal component, changing length and sign: equal to the scikit-fem reference to
    round-off."""
    pytest.importorskip("skfem")

    def v_star(t):
        return (1.0 - 1.5 * t) * np.array([1.0, 0.5, 0.3])

    mesh = box_tetrahedra((2.0, 1.0, 1.0), (3, 1, 1))
    pr = paper_problem(mesh, steps=8, f1=f1, v_star=v_star)
    got = simulate(pr, SolverOptions("newton"))
    ref_solver = TetReference(pr.mesh, f1)
    assert np.array_equal(ref_solver.nodes, pr.contact.nodes)
    assert np.allclose(ref_solver.omega, pr.contact.weights, rtol=1e-14)
    ref = ref_solver.run(pr.time.t, v_star)
    scale = np.abs(ref["u"]).max()
    assert np.abs(got.u - ref["u"]).max() < 1e-12 * scale
    for name in ("wear", "u_nu", "p_soft", "p_rigid"):
        assert np.abs(getattr(got, name) - ref[name]).max() < 1e-12 * max(
            np.abs(ref[name]).max(), 1e-3
        ), name
    assert ref["wear"][-1].max() > 1e-3
    if f1[1] > 0:
        assert ref["p_rigid"].max() > 0


# ----------------------------------------------------------------------------- (c) closed form
W3, D3, H3 = 2.0, 1.0, 1.0
M_ = LAM + 2 * ETA
K_S = C_P * M_ / (M_ + C_P * H3)


@pytest.mark.parametrize("family", ["hexahedra", "voronoi"])
def test_pushed_block_wears_as_the_closed_form_3d(family: str) -> None:
    """Rollers (u_x = 0 on xmin, xmax; u_y = 0 on ymin, ymax), mu = 0, no body force, the
    top pushed by u_z = -delta: uniaxial, p = k_s (delta - w), and
    delta - w^n = delta (1 - k kappa |v*| k_s)^n exactly."""
    mesh = (
        box_hexahedra((W3, D3, H3), (4, 2, 2))
        if family == "hexahedra"
        else box_voronoi((W3, D3, H3), 24, seed=1)
    )
    mesh = tag_box(
        mesh, {"xr": ["xmin", "xmax"], "yr": ["ymin", "ymax"], "top": "zmax", "contact": "zmin"}
    )
    delta, n = 0.05, 12
    pr = Problem(
        mesh,
        Material(LAM, ETA),
        TimeGrid.uniform(1.0, n),
        f1=(0.0, 0.0, 0.0),
        p=LinearCompliance(C_P),
        g=G,
        mu=0.0,
        kappa=KAPPA,
        v_star=(1.0, 0.0, 0.0),
        clamped=(),
        displacement=(
            Prescribed("xr", ux=0.0),
            Prescribed("yr", uy=0.0),
            Prescribed("top", uz=-delta),
        ),
    )
    r = simulate(pr, SolverOptions("newton"))
    e = delta * (1 - KAPPA * K_S / n) ** np.arange(n + 1)
    assert np.abs(r.wear - (delta - e)[:, None]).max() < 1e-13
    assert np.abs(r.p_soft - K_S * e[:, None]).max() < 1e-13
    assert np.abs(r.p_rigid).max() == 0.0
    u = r.displacement(-1)
    P = pr.mesh.points
    assert np.abs(u[:, :2]).max() < 1e-13
    d = r.u_nu[-1, 0]
    assert np.abs(u[:, 2] - (-d + (d - delta) * P[:, 2] / H3)).max() < 1e-13
    F = r.forces
    assert F is not None
    assert np.abs(F[:, 0, 2] - K_S * e * W3 * D3).max() < 1e-12
    assert np.abs(F.sum(axis=1)).max() < 1e-12


# ----------------------------------------------------------------------------- (d) plane strain
def plane_strain_pair(n: int, steps: int = 8) -> tuple[Problem, Problem]:
    """The paper's 2D problem on 2n x n squares, and the same in 3D on the prisms of that
    mesh turned so that the 2D plane is x-z (one layer of depth 1 along y), with rollers
    u_y = 0 on both faces normal to y."""
    m2 = tag_rectangle(rectangle_squares((2.0, 1.0), (2 * n, n)))
    p3 = extrude(m2, 1, 1.0, bottom="front", top="back")
    x, y, z = p3.points.T
    turned = np.column_stack([x, 1.0 - z, y])  # (x, y, z) -> (x, 1 - z, y): det +1
    m3 = Mesh3D(
        turned,
        p3.face_offsets,
        p3.face_vertices,
        p3.cell_offsets,
        p3.cell_faces,
        p3.cell_face_signs,
        p3.boundary_tags,
        p3.part_names,
    )
    common = dict(p=LinearCompliance(C_P), g=G, mu=MU, kappa=KAPPA)
    pr2 = Problem(
        m2,
        Material(LAM, ETA),
        TimeGrid.uniform(1.0, steps),
        f1=(0.0, -0.06),
        v_star=(1.0, 0.0),
        **common,
    )
    pr3 = Problem(
        m3,
        Material(LAM, ETA),
        TimeGrid.uniform(1.0, steps),
        f1=(0.0, 0.0, -0.06),
        v_star=(1.0, 0.0, 0.0),
        displacement=(Prescribed("front", uy=0.0), Prescribed("back", uy=0.0)),
        **common,
    )
    return pr2, pr3


def plane_strain_difference(n: int) -> float:
    """max |w_3D - w_2D| over the levels and the contact nodes (both faces of the slab)."""
    pr2, pr3 = plane_strain_pair(n)
    r2, r3 = simulate(pr2, "newton"), simulate(pr3, "newton")
    x2, x3 = pr2.contact.points[:, 0], pr3.contact.points[:, 0]
    idx = np.searchsorted(x2, x3)
    assert np.allclose(x2[idx], x3)
    # the 3D solution does not depend on y (rollers)
    front = np.abs(pr3.contact.points[:, 1]) < 1e-12
    assert np.allclose(
        r3.wear[:, front][:, np.argsort(x3[front])],
        r3.wear[:, ~front][:, np.argsort(x3[~front])],
        rtol=0,
        atol=1e-13,
    )
    return float(np.abs(r3.wear - r2.wear[:, idx]).max())


def test_plane_strain_recovered_by_prisms() -> None:
    diffs = [plane_strain_difference(n) for n in (2, 4, 8)]
    assert diffs[0] > diffs[1] > diffs[2]
    assert diffs[2] < 0.5 * diffs[0]
