"""One run of the orders study at t = T, and its errors against the reference.

:func:`run_final` solves Example 5.5's problem with k = 1 or k = 2 and keeps every dof
of the displacement and the wear at T (:class:`FinalState`); :class:`OrdersReference`
measures the relative errors ``u_H1``, ``w_L2``, ``u_H1_int`` and ``w_L2_int`` of a run
against a reference run on a mesh nested in it (their definitions:
:mod:`vemwear.paper.orders`, which runs the study and writes its tables).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
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

__all__ = ["FinalState", "OrdersReference", "run_final"]

#: The x-range of the interior region of the ``*_int`` errors: away from the clamped side
#: x = 0, whose corners make u singular, and from the side x = 2.
INTERIOR: tuple[float, float] = (0.25, 1.75)

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
    assert full.u is not None  # recovered
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
    reference contact edge (:mod:`vemwear.paper.orders`).

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
        """The relative errors of ``state`` at T (:mod:`vemwear.paper.orders`): ``u_H1``,
        ``w_L2`` and ``u_H1_int``, ``w_L2_int`` on the interior region only.

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
