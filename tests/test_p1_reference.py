"""On triangles the lowest-order VEM is P1: compare with scikit-fem, then run the whole
contact-and-wear scheme against an independent P1 implementation.

The reference of the time loop assembles K and F with scikit-fem, builds the contact
nodes, weights and normals of the bottom side from coordinates, and solves every step
problem of design.md section 4 by enumerating all 3^m contact states (no contact,
soft layer only, rigid contact) with one batched dense solve, keeping the states whose
solution satisfies all sign conditions. Nothing of vemwear.vem, vemwear.contact or
vemwear.solvers is used for the reference.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from skfem import (
    Basis,
    ElementTriP1,
    ElementVector,
    FacetBasis,
    LinearForm,
    MeshTri,
    asm,
)
from skfem.models.elasticity import linear_elasticity

from vemwear.contact import LinearCompliance
from vemwear.mesh import Mesh, rectangle_triangles, tag_rectangle
from vemwear.simulate import Problem, SolverOptions, TimeGrid, simulate
from vemwear.vem import (
    STABILIZATIONS,
    Material,
    body_force_vector,
    edge_load_vector,
    stiffness,
    traction_vector,
)

# the paper's data (Section 5, Example 5.2 first set)
LAM, ETA = 4.0, 4.0
F1 = np.array([0.0, -0.06])
C_P, G, MU, KAPPA = 0.4, 0.1, 0.2, 2.0
V_STAR = np.array([1.0, 0.0])
T_END, STEPS = 1.0, 8


def skfem_setup(mesh):
    """scikit-fem mesh on the same vertex ids, P1 vector basis, and the permutation
    taking skfem's dof numbering to vemwear's (dof 2 v + c)."""
    sm = MeshTri(np.ascontiguousarray(mesh.points.T), np.array(mesh.cells).T.copy())
    assert np.array_equal(sm.p.T, mesh.points)  # same vertex ids
    basis = Basis(sm, ElementVector(ElementTriP1()))
    nd = basis.nodal_dofs  # (2, n_points): skfem dof of component c at vertex v
    perm = np.empty(2 * mesh.n_points, dtype=np.int64)
    perm[0::2], perm[1::2] = nd[0], nd[1]
    return sm, basis, perm


def constant_load(f):
    @LinearForm
    def form(v, w):
        return f[0] * v[0] + f[1] * v[1]

    return form


@pytest.fixture(scope="module")
def tri_mesh():
    return rectangle_triangles((2.0, 1.0), (8, 4), diagonal="alternate")


# ----------------------------------------------------------------------------- 6. matrices
@pytest.mark.parametrize("stab", STABILIZATIONS)
@pytest.mark.parametrize("mat", [(LAM, ETA), (7.5, 1.3)])
def test_stiffness_equals_p1(tri_mesh, stab, mat):
    lam, eta = mat
    _sm, basis, perm = skfem_setup(tri_mesh)
    Kref = asm(linear_elasticity(Lambda=lam, Mu=eta), basis).toarray()[np.ix_(perm, perm)]
    K = stiffness(tri_mesh, Material(lam=lam, eta=eta), stab).toarray()
    err = np.abs(K - Kref).max() / np.abs(Kref).max()
    assert err < 1e-12, err


@pytest.mark.parametrize("stab", STABILIZATIONS)
@pytest.mark.parametrize("diagonal", ["right", "left", "alternate"])
def test_stiffness_equals_p1_general_triangles(diagonal, stab):
    """Non-dyadic spacing and randomly moved interior vertices: general triangles."""
    mesh = rectangle_triangles((1.0, 3.0), (3, 5), origin=(-0.5, 2.0), diagonal=diagonal)
    P = mesh.points.copy()
    lo, hi = P.min(axis=0), P.max(axis=0)
    inner = np.all((P > lo + 1e-9) & (P < hi - 1e-9), axis=1)
    P[inner] += np.random.default_rng(3).uniform(-0.08, 0.08, (int(inner.sum()), 2))
    mesh = Mesh.from_cells(P, mesh.cells)
    assert np.all(mesh.cell_areas > 0)
    _sm, basis, perm = skfem_setup(mesh)
    Kref = asm(linear_elasticity(Lambda=LAM, Mu=ETA), basis).toarray()[np.ix_(perm, perm)]
    K = stiffness(mesh, Material(lam=LAM, eta=ETA), stab).toarray()
    assert np.abs(K - Kref).max() <= 1e-12 * np.abs(Kref).max()


def test_body_force_equals_p1(tri_mesh):
    """For constant f, |K| f / 3 per vertex is the P1 load int f . phi_a."""
    _sm, basis, perm = skfem_setup(tri_mesh)
    for f in (F1, np.array([0.3, -1.1])):
        Fref = asm(constant_load(f), basis)[perm]
        F = body_force_vector(tri_mesh, f)
        assert np.abs(F - Fref).max() <= 1e-14 * np.abs(Fref).max()
        assert np.allclose(F.reshape(-1, 2).sum(axis=0), 2.0 * f, rtol=1e-13)


def test_edge_load_equals_p1_facet_load(tri_mesh):
    """Traction linear in x on the top side: vemwear's edge quadrature against skfem's
    facet assembly (both exact for linear f2 times linear v)."""
    sm, _basis, perm = skfem_setup(tri_mesh)
    fb = FacetBasis(
        sm,
        ElementVector(ElementTriP1()),
        facets=sm.facets_satisfying(lambda x: np.isclose(x[1], 1.0)),
    )

    @LinearForm
    def top(v, w):
        x = w.x[0]
        return (0.5 - 0.3 * x) * v[0] + (1.0 + 2.0 * x) * v[1]

    Fref = asm(top, fb)[perm]
    mesh = tag_rectangle(
        tri_mesh, {"clamped": "left", "traction": "top", "contact": ["bottom", "right"]}
    )
    f2 = lambda x, t: np.column_stack([0.5 - 0.3 * x[:, 0], 1.0 + 2.0 * x[:, 0]])  # noqa: E731
    F = traction_vector(mesh, f2)
    assert np.abs(F - Fref).max() <= 1e-14 * np.abs(Fref).max()
    F = edge_load_vector(mesh, mesh.part_edges("traction"), f2)
    assert np.abs(F - Fref).max() <= 1e-14 * np.abs(Fref).max()


# ----------------------------------------------------------------------------- 7. time loop
class P1Reference:
    """Independent P1 contact-and-wear solver on the paper's rectangle (design.md 3-4).

    Residual of the step problem, with the friction direction from the tangential part
    of the foundation velocity, n*_a(t) = -v*_tau(a)/|v*_tau(a)| with
    v*_tau(a) = v* - (v* . nu_a) nu_a (paper 2.2 written for any Gamma_C), and the
    friction law -sigma_tau = mu p(u_nu - w) n*, so that the contact work is
    sum_a omega_a [(p_a + lam_a) v_nu(a) + mu p_a n*_a . v_tau(a)]:

        K u - F + sum_a omega_a [(p_a + lam_a) nu_a + mu p_a n*_a] = 0,
        p_a = c (u_nu(a) - w_a)_+,  lam_a >= 0,  u_nu(a) <= g,  lam_a (u_nu(a) - g) = 0,

    and the wear rate alpha_a = kappa |v*_tau(a)|.

    ``friction_sign=+1`` flips n* (only to show that the comparison can tell).
    """

    def __init__(self, mesh, friction_sign=-1.0):
        P = mesh.points
        _sm, basis, perm = skfem_setup(mesh)
        K = asm(linear_elasticity(Lambda=LAM, Mu=ETA), basis).toarray()[np.ix_(perm, perm)]
        F = asm(constant_load(F1), basis)[perm]
        nv = len(P)
        clamped = np.flatnonzero(np.abs(P[:, 0]) < 1e-12)  # Gamma_D = {0} x [0, 1]
        fixed = np.zeros(2 * nv, bool)
        fixed[2 * clamped] = fixed[2 * clamped + 1] = True
        self.free = np.flatnonzero(~fixed)
        bottom = np.flatnonzero(np.abs(P[:, 1]) < 1e-12)
        bottom = bottom[np.argsort(P[bottom, 0])]
        xb = P[bottom, 0]
        half = 0.5 * np.diff(xb)  # half lengths of the bottom edges
        weight = np.zeros(len(bottom))
        weight[:-1] += half
        weight[1:] += half
        keep = xb > 1e-12  # contact nodes: not on the closure of Gamma_D
        self.nodes, self.omega = bottom[keep], weight[keep]
        m = self.m = len(self.nodes)
        self.nu = np.tile([0.0, -1.0], (m, 1))
        self.sign = friction_sign
        # condensation onto the contact dofs (dense; the mesh is small)
        Kf = K[np.ix_(self.free, self.free)]
        pos = {d: i for i, d in enumerate(self.free)}
        cdofs = np.array([[pos[2 * a], pos[2 * a + 1]] for a in self.nodes]).ravel()
        C = np.zeros((2 * m, len(self.free)))
        C[np.arange(2 * m), cdofs] = 1.0
        self.Kf, self.Ff, self.C = Kf, F[self.free], C
        self.H = C @ np.linalg.solve(Kf, C.T)  # compliance at the contact dofs
        self.y0 = C @ np.linalg.solve(Kf, self.Ff)
        self.states = np.array(list(itertools.product(range(3), repeat=m)))
        self.nv = nv

    def tangential(self, vs):
        """v*_tau at every contact node, (m, 2)."""
        return vs[None, :] - (self.nu @ vs)[:, None] * self.nu

    def step(self, w, n_star):
        """All 3^m contact states solved at once; returns the unique admissible one."""
        m, S = self.m, self.states
        nu, om = self.nu, self.omega
        on = S >= 1  # soft layer compressed: p = c (u_nu - w)
        rigid = S == 2  # u_nu = g, lam >= 0
        tstar = n_star  # (m, 2): the friction direction at every node, tangential
        dirn = nu + MU * tstar  # nodal force per unit soft-layer pressure, (m, 2)
        # nodal force at node j: f_j = om_j [on_j c (y_nu_j - w_j) dirn_j + lam_j nu_j];
        # contact displacements y = y0 - H f, so with the normal components
        # y_nu = yn0 - Nd diag(on c om) (y_nu - w) - Nn diag(om) lam
        H3 = self.H.reshape(m, 2, m, 2)
        Nd = np.einsum("ia,iajb,jb->ij", nu, H3, dirn)
        Nn = np.einsum("ia,iajb,jb->ij", nu, H3, nu)
        yn0 = np.einsum("ia,ia->i", nu, self.y0.reshape(m, 2))
        soft = on * (C_P * om)  # (states, m)
        ns = len(S)
        M = np.zeros((ns, 2 * m, 2 * m))
        rhs = np.zeros((ns, 2 * m))
        M[:, :m, :m] = np.eye(m) + Nd[None] * soft[:, None, :]
        M[:, :m, m:] = Nn * om
        rhs[:, :m] = yn0 + (soft * w) @ Nd.T
        jj = np.arange(m)
        M[:, m + jj, jj] = rigid  # rigid: y_nu_j = g
        M[:, m + jj, m + jj] = ~rigid  # otherwise: lam_j = 0
        rhs[:, m:] = np.where(rigid, G, 0.0)
        sol = np.linalg.solve(M, rhs[..., None])[..., 0]
        y_nu, lam = sol[:, :m], sol[:, m:]
        r = y_nu - w
        tol = 1e-11
        ok = np.where(on, r >= -tol, r <= tol) & (y_nu <= G + tol) & (~rigid | (lam >= -tol))
        valid = np.flatnonzero(np.all(ok, axis=1))
        assert valid.size >= 1, "no admissible contact state"
        # uniqueness (Theorem 3.4): every admissible state gives the same solution
        assert np.abs(sol[valid] - sol[valid[0]]).max() <= 1e-10
        k = valid[0]
        p = np.where(on[k], C_P * np.maximum(r[k], 0.0), 0.0)
        # nodal forces in the convention of design.md section 4, then u from K u = F - f
        force = np.zeros(2 * self.nv)
        for j, a in enumerate(self.nodes):
            force[2 * a : 2 * a + 2] = om[j] * ((p[j] + lam[k, j]) * nu[j] + MU * p[j] * tstar[j])
        uf = np.linalg.solve(self.Kf, self.Ff - force[self.free])
        # the condensed solution is consistent with the full one, and the residual vanishes
        y_full = (self.C @ uf).reshape(m, 2)
        assert np.allclose(np.einsum("ja,ja->j", y_full, nu), y_nu[k], rtol=0, atol=1e-13)
        res = self.Kf @ uf - self.Ff + force[self.free]
        assert np.abs(res).max() <= 1e-12 * np.abs(self.Ff).max()
        U = np.zeros(2 * self.nv)
        U[self.free] = uf
        return U.reshape(-1, 2), y_nu[k], lam[k], p, S[k]

    def run(self, t, v_star):
        L = len(t)
        U = np.zeros((L, self.nv, 2))
        W, Y, LAM_, P_, ST = (np.zeros((L, self.m)) for _ in range(5))
        w = np.zeros(self.m)
        for n in range(L):
            vt = self.tangential(np.asarray(v_star(t[n]), float))
            speed = np.linalg.norm(vt, axis=1)
            n_star = self.sign * vt / speed[:, None]
            U[n], Y[n], LAM_[n], P_[n], ST[n] = self.step(w, n_star)
            W[n] = w
            if n + 1 < L:  # left rectangle rule (3.22), alpha(t_n) = kappa |v*_tau(t_n)|
                w = w + (t[n + 1] - t[n]) * KAPPA * speed * P_[n]
        return {
            "u": U,
            "wear": W,
            "u_nu": Y,
            "lam": LAM_,
            "p": P_,
            "states": ST,
            "nodes": self.nodes,
        }


def v_star_paper(t):
    return V_STAR


def v_star_varying(t):
    """Speed varies, v* has a normal part, and the tangential direction reverses at
    t = 2/3 (the tangential part never vanishes on the grid)."""
    return np.array([1.0 - 1.5 * t, 0.5])


SCENARIOS = {
    # the paper's data on a uniform grid
    "paper": (TimeGrid.uniform(T_END, STEPS), v_star_paper),
    # non-uniform steps 1/16, 3/16, ... and a time-dependent v*: n*(t_n), alpha(t_n), k_n
    "varying": (TimeGrid.from_steps([1 / 16, 3 / 16] * 4), v_star_varying),
}


@pytest.fixture(scope="module")
def reference(tri_mesh):
    cache = {}

    def get(name):
        if name not in cache:
            grid, vs = SCENARIOS[name]
            cache[name] = P1Reference(tri_mesh).run(grid.t, vs)
        return cache[name]

    return get


def test_reference_exercises_everything(reference):
    """The paper's data drive the rigid constraint active and produce wear and friction."""
    ref = reference("paper")
    assert np.any(ref["states"] == 2) and ref["lam"].max() > 1e-3
    assert np.isclose(ref["u_nu"].max(), G, rtol=1e-12)
    assert ref["wear"][-1].max() > 0.01 and np.all(ref["wear"] >= 0)
    assert np.all(ref["p"][0] > 0)  # the soft layer carries load at every node


def rel(a, b):
    return np.abs(np.asarray(a) - np.asarray(b)).max() / max(np.abs(b).max(), 1e-300)


@pytest.mark.parametrize("scenario", list(SCENARIOS))
@pytest.mark.parametrize(
    ("method", "tol"), [("newton", 1e-9), ("newton-full", 1e-9), ("uzawa", 1e-8)]
)
def test_contact_wear_matches_independent_p1(tri_mesh, reference, scenario, method, tol):
    grid, v_star = SCENARIOS[scenario]
    problem = Problem(
        mesh=tag_rectangle(tri_mesh),
        material=Material(lam=LAM, eta=ETA),
        time=grid,
        f1=tuple(F1),
        f2=(0.0, 0.0),
        p=LinearCompliance(C_P),
        g=G,
        mu=MU,
        kappa=KAPPA,
        v_star=v_star if scenario != "paper" else tuple(V_STAR),
    )
    # "newton" runs on the default linear-algebra backend; the others on SciPy's SuperLU
    # (a PARDISO factorization has a fixed cost of about a second here)
    opts = SolverOptions(
        method=method,
        tol=1e-10 if method == "uzawa" else 1e-12,
        backend="auto" if method == "newton" else "scipy",
    )
    res = simulate(problem, opts)
    ref = reference(scenario)
    # match contact nodes by vertex id
    assert len(res.contact_nodes) == len(ref["nodes"])
    order = np.array([np.flatnonzero(res.contact_nodes == a)[0] for a in ref["nodes"]])
    errs = {
        "u": rel(res.u, ref["u"]),
        "wear": rel(res.wear[:, order], ref["wear"]),
        "u_nu": rel(res.u_nu[:, order], ref["u_nu"]),
        "lam": rel(res.p_rigid[:, order], ref["lam"]),
        "p": rel(res.p_soft[:, order], ref["p"]),
    }
    assert max(errs.values()) < tol, errs


def test_reference_is_sensitive_to_friction_sign(tri_mesh, reference):
    """The comparison above can tell the friction convention apart: with n* = +v*/|v*|
    the reference moves far more than the tolerance."""
    grid, vs = SCENARIOS["paper"]
    flipped = P1Reference(tri_mesh, friction_sign=+1.0).run(grid.t, vs)
    assert rel(flipped["u"], reference("paper")["u"]) > 1e-3
    assert rel(flipped["wear"], reference("paper")["wear"]) > 1e-4
