"""An indicator of the error of the wear profile at the final time, for adaptive runs
whose goal is the wear (docs/method.md, section 11; ``[adapt] estimator = "wear"``).

The wear lives at the contact nodes and is piecewise linear along Gamma_C (k = 1). When
the body is much stiffer than the layer, the nodal values are accurate on coarse meshes
and the error of the wear profile is that of its interpolant between the nodes: its L2
norm on a piece of length ``L`` is ``L^{5/2} |w''| / sqrt(120)`` for a smooth profile.
The indicator measures that error for the wear *predicted at the final time* ``T`` from
a level ``t_n``, ``W = w^n + (T - t_n) alpha(t_n) P^n`` (3.22 with the pressure of the
level held), so that a mesh change refines where the wear will be, not only where it is:

    eta_e^2 = L_e^5 kappa_e^2 / 120,

``kappa_e`` the smaller of the discrete second derivatives of ``W`` at the two ends of
the piece (``2 (s_out - s_in) / (L_in + L_out)``, ``s`` the slopes of the two pieces at a
node; zero at the ends of a chain of contact edges). The smaller one, because the
profile has a kink where the contact zone ends: the kink is inside one piece and its
L2 error, ``O(L^{3/2})`` on that piece alone, would take all the refinement if both ends'
second derivatives counted, while the error of the wear at T is that of the smooth
profile over the whole zone. Each piece's indicator goes to its cell.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..contact.transfer import vertex_slopes
from ..mesh.polymesh import Mesh

__all__ = ["predicted_wear", "wear_indicators"]

FloatArray = NDArray[np.float64]


def predicted_wear(
    discrete: object,
    wear: ArrayLike,
    p_soft: ArrayLike,
    p_rigid: ArrayLike,
    t: float,
    T: float,
) -> FloatArray:
    """``W = w + (T - t) alpha(t) P`` at the contact nodes: the wear at ``T`` if the
    pressure of the level at ``t`` held (the explicit update 3.22 over ``T - t``).

    Parameters
    ----------
    discrete : Discretization
        Of the level's problem (its ``alpha`` and ``wear_pressure``).
    wear, p_soft, p_rigid : (m,) array_like
        The level's wear and pressures at the contact nodes.
    t, T : float
        The level's time and the final time.
    """
    d = discrete
    alpha = d.alpha(t)  # type: ignore[attr-defined]
    P = d.wear_pressure(np.asarray(p_soft, float), np.asarray(p_rigid, float))  # type: ignore[attr-defined]
    return np.asarray(np.asarray(wear, float) + (T - t) * alpha * P, dtype=np.float64)


def wear_indicators(
    mesh: Mesh, nodes: ArrayLike, values: ArrayLike, parts: Sequence[str]
) -> FloatArray:
    """``eta_K^2``: the indicators of the contact pieces of every cell for the profile
    ``values`` at the contact ``nodes`` (vertex ids) along the ``parts`` (module
    docstring); zero on cells without a contact piece.

    Returns
    -------
    (n_cells,) array
    """
    nodes = np.asarray(nodes, dtype=np.int64)
    W = np.zeros(mesh.n_points)
    W[nodes] = np.asarray(values, dtype=float)  # an end that is no contact node: 0
    rows = np.concatenate([np.flatnonzero(mesh.boundary_tags == mesh.part_code(p)) for p in parts])
    E, C = mesh.boundary_edges[rows], mesh.boundary_edge_cells[rows]
    L = np.linalg.norm(mesh.points[E[:, 1]] - mesh.points[E[:, 0]], axis=1)
    # a node's incoming and outgoing pieces along the boundary's orientation
    s_in, s_out, l_in, l_out = vertex_slopes(mesh.n_points, E, (W[E[:, 1]] - W[E[:, 0]]) / L, L)
    both = (l_in > 0) & (l_out > 0)
    kappa = np.where(both, 2.0 * (s_out - s_in) / np.where(both, l_in + l_out, 1.0), 0.0)
    k_e = np.minimum(np.abs(kappa[E[:, 0]]), np.abs(kappa[E[:, 1]]))
    eta2 = L**5 * k_e**2 / 120.0
    return np.asarray(np.bincount(C, eta2, minlength=mesh.n_cells), dtype=np.float64)
