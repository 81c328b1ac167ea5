"""Energy errors of a discrete displacement, for the effectivity of the estimator
(docs/method.md, section 11).

The error is ``||u - Pi u_h||_E^2 = sum_K int_K eps(u - Pi u_h) : C eps(u - Pi u_h)``:
against an exact gradient by quadrature (:func:`energy_error_exact`), or against a
reference on a nested finer mesh, ``u ~ Pi_ref u_ref`` cell by cell
(:func:`energy_error_reference`); the same for k = 2 with the quadratic ``Pi u_h``
(:func:`energy_error_exact2`, :func:`energy_error_reference2`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..mesh.locate import nested_cells
from ..mesh.polymesh import Mesh
from ..vem import Material, Projection, polygon_quadrature
from ..vem.dofs2 import project2
from ..vem.estimator import cell_sums

__all__ = [
    "energy_error_exact",
    "energy_error_exact2",
    "energy_error_reference",
    "energy_error_reference2",
    "energy_sq",
]

FloatArray = NDArray[np.float64]


def energy_sq(strain: FloatArray, material: Material) -> FloatArray:
    """``eps : C eps = 2 eta |eps|^2 + lam tr(eps)^2`` of strains (q, 2, 2)."""
    tr = strain[:, 0, 0] + strain[:, 1, 1]
    return 2.0 * material.eta * np.sum(strain * strain, axis=(1, 2)) + material.lam * tr * tr


def energy_error_exact(
    mesh: Mesh,
    material: Material,
    u_h: ArrayLike,
    grad_u: Callable[[FloatArray], FloatArray],
) -> FloatArray:
    """Squared energy error per cell of ``Pi u_h`` against the exact gradient ``grad_u(x)``
    ((q, 2, 2), ``[:, i, j] = d_j u_i``), by the degree-5 rule on the fan of every cell."""
    fields = Projection(mesh)(np.asarray(u_h, dtype=float).reshape(-1))
    x, w, cell = polygon_quadrature(mesh, degree=5)
    return _energy(grad_u(x) - fields.gradient[cell], w, cell, material, mesh.n_cells)


def _energy(
    G: FloatArray, w: FloatArray, cell: NDArray[np.int64], material: Material, n: int
) -> FloatArray:
    """``sum w eps : C eps`` per cell of the symmetric parts of the gradients ``G``."""
    e = 0.5 * (G + G.transpose(0, 2, 1))
    return cell_sums(cell, w * energy_sq(e, material), minlength=n)


def energy_error_reference(
    mesh: Mesh,
    material: Material,
    u_h: ArrayLike,
    reference: Mesh,
    u_ref: ArrayLike,
) -> FloatArray:
    """Squared energy error per cell of ``mesh`` of ``Pi u_h`` against ``Pi_ref u_ref`` on a
    nested finer mesh (every reference cell inside one cell of ``mesh``)."""
    owner = nested_cells(mesh, reference)
    a = Projection(mesh)(np.asarray(u_h, dtype=float).reshape(-1)).strain
    b = Projection(reference)(np.asarray(u_ref, dtype=float).reshape(-1)).strain
    e = energy_sq(a[owner] - b, material) * reference.cell_areas
    return cell_sums(owner, e, minlength=mesh.n_cells)


def energy_error_exact2(
    mesh: Mesh,
    material: Material,
    u_h: ArrayLike,
    grad_u: Callable[[FloatArray], FloatArray],
) -> FloatArray:
    """:func:`energy_error_exact` for k = 2: ``u_h`` all the dofs of the second-order space,
    ``Pi u_h`` quadratic on every cell (:func:`~vemwear.vem.dofs2.project2`)."""
    x, w, cell = polygon_quadrature(mesh, degree=5)
    _, grad = project2(mesh, material, u_h).at(x, cell)
    return _energy(grad_u(x) - grad, w, cell, material, mesh.n_cells)


def energy_error_reference2(
    mesh: Mesh,
    material: Material,
    u_h: ArrayLike,
    reference: Mesh,
    u_ref: ArrayLike,
) -> FloatArray:
    """:func:`energy_error_reference` for k = 2 (all the dofs of both): the quadratic
    ``Pi u_h`` of the owner cell and ``Pi_ref u_ref`` at the degree-5 points of every
    reference cell."""
    owner = nested_cells(mesh, reference)
    x, w, cell = polygon_quadrature(reference, degree=5)
    _, a = project2(mesh, material, u_h).at(x, owner[cell])
    _, b = project2(reference, material, u_ref).at(x, cell)
    return _energy(a - b, w, owner[cell], material, mesh.n_cells)
