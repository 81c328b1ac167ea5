"""Example 5.4: the difference of two runs of one problem on two meshes of one domain.

Contact quantities are compared along Gamma_C (the bottom side): the values of one
run are interpolated piecewise linearly in x_1 at the contact nodes of the other
(:func:`profile_difference`). The displacement is compared at the boundary vertices
both meshes share and at probe points, where ``Pi u`` of the containing cell
(paper (3.8)-(3.10), :meth:`vemwear.vem.Projection.evaluate`) is evaluated on each
mesh (:func:`displacement_difference`). :func:`compare_runs` gathers both and the
headline numbers.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from ..mesh import Mesh
from ..post.norms import contact_l2_norm
from ..simulate import Result
from ..vem import Projection
from .ex52 import SIZE, T

__all__ = [
    "compare_runs",
    "displacement_difference",
    "probe_points",
    "profile_difference",
    "shared_vertices",
]

FloatArray = NDArray[np.float64]


# ---------------------------------------------------------------------------- contact profiles
def _profile(result: Result, quantity: str, level: int) -> tuple[FloatArray, FloatArray]:
    """``(x_1, values)`` along Gamma_C sorted by x_1, with the clamped ends of Gamma_C
    (vertices of the contact part on Gamma_D, where u = 0 and w = 0) as zeros."""
    mesh = result.problem.mesh
    ends = np.setdiff1d(mesh.part_vertices("contact"), result.contact_nodes)
    x = np.concatenate([result.contact_points[:, 0], mesh.points[ends, 0]])
    v = np.concatenate([np.asarray(getattr(result, quantity))[level], np.zeros(len(ends))])
    order = np.argsort(x, kind="stable")
    return x[order], v[order]


def profile_difference(
    reference: Result, other: Result, quantity: str = "wear", time: float = T
) -> dict[str, float]:
    """Difference of a contact quantity between two runs, on the reference's contact nodes.

    The values of ``other`` are interpolated piecewise linearly in x_1 (Gamma_C is the
    bottom side) at the contact nodes of ``reference``, the clamped end of Gamma_C
    counting as 0 (u = 0 and w = 0 there).

    Parameters
    ----------
    reference, other : Result
        Runs on two meshes of the same domain.
    quantity : str
        ``wear``, ``u_nu``, ``penetration``, ``p_rigid`` or ``p_soft``.
    time : float
        A time level of both runs.

    Returns
    -------
    dict
        ``max_abs`` (max |a - I b|), ``rel_max`` (max |a - I b| / max |a|), ``rel_l2``
        (``||a - I b|| / ||a||`` in L2(Gamma_C), both piecewise linear on the
        reference's contact edges, integrated exactly:
        :func:`vemwear.post.norms.contact_l2_norm`), ``max_reference``, ``max_other``.
    """
    la, lb = reference.level(time), other.level(time)
    a = np.asarray(getattr(reference, quantity))[la]
    xb, b = _profile(other, quantity, lb)
    ib = np.interp(reference.contact_points[:, 0], xb, b)
    d = a - ib
    mesh, nodes = reference.problem.mesh, reference.contact_nodes
    scale_max = float(np.abs(a).max())
    scale_l2 = contact_l2_norm(mesh, nodes, a, "exact")
    return {
        "max_abs": float(np.abs(d).max()),
        "rel_max": float(np.abs(d).max()) / scale_max if scale_max > 0 else float("nan"),
        "rel_l2": contact_l2_norm(mesh, nodes, d, "exact") / scale_l2
        if scale_l2 > 0
        else float("nan"),
        "max_reference": scale_max,
        "max_other": float(np.abs(b).max()),
    }


# ---------------------------------------------------------------------------- probes
def probe_points(
    size: tuple[float, float] = SIZE, n: tuple[int, int] = (16, 8)
) -> NDArray[np.float64]:
    """Cell-centred ``n[0] x n[1]`` grid of probe points in ``(0, lx) x (0, ly)``."""
    x = (np.arange(n[0]) + 0.5) * size[0] / n[0]
    y = (np.arange(n[1]) + 0.5) * size[1] / n[1]
    X, Y = np.meshgrid(x, y)
    return np.column_stack([X.ravel(), Y.ravel()])


def shared_vertices(
    a: Mesh, b: Mesh, rtol: float = 1e-9, boundary_only: bool = True
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Vertex pairs of two meshes at the same coordinates (up to ``rtol`` of the extent).

    Parameters
    ----------
    a, b : Mesh
    rtol : float
    boundary_only : bool
        Only vertices on the boundary of both meshes (the domain corners and the
        boundary points the meshes share).

    Returns
    -------
    ia, ib : int arrays
        ``a.points[ia]`` coincides with ``b.points[ib]``; sorted by ``ia``.
    """
    va = np.unique(a.boundary_edges) if boundary_only else np.arange(a.n_points)
    vb = np.unique(b.boundary_edges) if boundary_only else np.arange(b.n_points)
    tol = rtol * float(np.ptp(a.points, axis=0).max())
    d, j = cKDTree(b.points[vb]).query(a.points[va], distance_upper_bound=tol)
    ok = np.isfinite(d)
    return va[ok], vb[j[ok]]


def displacement_difference(
    reference: Result,
    other: Result,
    time: float = T,
    probes: ArrayLike | None = None,
) -> dict[str, Any]:
    """Displacement differences between two runs at shared vertices and at probe points.

    Parameters
    ----------
    reference, other : Result
        Runs on two meshes of the same domain.
    time : float
        A time level whose displacement both runs stored.
    probes : (n, 2) array_like, optional
        Points where ``Pi u`` is compared (default: :func:`probe_points`).

    Returns
    -------
    dict
        ``shared``: list of ``{"x", "u_reference", "u_other", "diff"}`` at the shared
        boundary vertices; ``probes``: ``n``, ``max_abs`` and ``rel_max`` per component
        (``u1``, ``u2``; relative to the component's max over the probes of the
        reference) and for the vector (``vector``: max |d| / max |u|, ``vector_rms``:
        rms |d| / rms |u|).
    """
    ua = reference.displacement(reference.level(time))
    ub = other.displacement(other.level(time))
    ia, ib = shared_vertices(reference.problem.mesh, other.problem.mesh)
    shared = [
        {
            "x": reference.problem.mesh.points[i].tolist(),
            "u_reference": ua[i].tolist(),
            "u_other": ub[j].tolist(),
            "diff": float(np.linalg.norm(ua[i] - ub[j])),
        }
        for i, j in zip(ia, ib, strict=True)
    ]
    pts = probe_points() if probes is None else np.asarray(probes, dtype=float).reshape(-1, 2)
    pa = Projection(reference.problem.mesh).evaluate(ua, pts)
    pb = Projection(other.problem.mesh).evaluate(ub, pts)
    d = pa - pb
    comp: dict[str, Any] = {}
    for c, name in enumerate(("u1", "u2")):
        scale = float(np.abs(pa[:, c]).max())
        m = float(np.abs(d[:, c]).max())
        comp[name] = {
            "max_abs": m,
            "max_reference": scale,
            "rel_max": m / scale if scale > 0 else float("nan"),
        }
    na, nd = np.linalg.norm(pa, axis=1), np.linalg.norm(d, axis=1)
    comp["vector"] = {
        "max_abs": float(nd.max()),
        "max_reference": float(na.max()),
        "rel_max": float(nd.max() / na.max()) if na.max() > 0 else float("nan"),
    }
    comp["vector_rms"] = (
        float(np.sqrt(np.mean(nd**2) / np.mean(na**2))) if na.max() > 0 else float("nan")
    )
    return {"shared": shared, "probes": {"n": len(pts), **comp}}


def compare_runs(
    reference: Result, other: Result, time: float = T, probes: ArrayLike | None = None
) -> dict[str, Any]:
    """Wear, u_nu and displacement differences of ``other`` against ``reference``.

    Returns
    -------
    dict
        ``wear`` and ``u_nu`` (:func:`profile_difference`) and ``displacement``
        (:func:`displacement_difference`, when both runs stored the displacement at
        ``time``; otherwise only the contact quantities); and the headline numbers as
        plain floats: ``wear_rel_max``, ``wear_rel_l2``, ``u_nu_rel_max``,
        ``u_nu_rel_l2``, ``u_probes_rel_max`` and ``u_probes_rel_rms`` (vector, at the
        probe points).
    """
    out: dict[str, Any] = {
        q: profile_difference(reference, other, q, time) for q in ("wear", "u_nu")
    }
    for q in ("wear", "u_nu"):
        out[f"{q}_rel_max"] = out[q]["rel_max"]
        out[f"{q}_rel_l2"] = out[q]["rel_l2"]
    try:
        out["displacement"] = displacement_difference(reference, other, time, probes)
    except KeyError:  # displacement not stored at that level
        return out
    pr = out["displacement"]["probes"]
    out["u_probes_rel_max"] = pr["vector"]["rel_max"]
    out["u_probes_rel_rms"] = pr["vector_rms"]
    return out
