"""The curved boundary of an initial mesh, so that refinement refines the geometry too
(docs/method.md, section 11).

A mesh of a curved domain carries the curve only through its boundary vertices. The
curve is taken to be the one of :class:`BoundaryCurve`, built from the initial mesh alone:
its boundary edges are grouped into *chains*, maximal runs of consecutive edges of one
part that turn by less than ``KINK`` (45 degrees) at each joint, and every edge of a
chain is replaced by the cubic graph over its chord ``A + t (B - A) + g(t) n`` (``n`` the
unit normal of the chord, ``t`` in [0, 1]) with ``g(0) = g(1) = 0`` and the slopes of the
tangents at its two ends (cubic Hermite interpolation). The tangent at a joint is the one
of the circle through the joint and its two neighbours (exact on circles, second order
otherwise); at an end of a chain, that of the circle through the end and the next two
vertices. An edge that is collinear with a neighbour in its chain is straight, and its
direction is the tangent at its ends; a chain of one edge is straight too. Straight edges
are never moved: their new vertices stay the chord midpoints, to the bit.

:meth:`BoundaryCurve.snap` moves a point that lies near a curved edge onto the curve at
the parameter of its projection onto the chord. A point on the curve keeps its
parameter, so the midpoint of two points of the curve goes to the curve at the mean of
their parameters: the new boundary vertex of a refined cell halves its boundary side
along the curve (to second order) and the polygon converges to the curve at the rate of
the cubic, ``O(h^3)`` for the general curve and ``O(h^4)`` on a circle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .locate import point_segment_distance
from .polymesh import Mesh

__all__ = ["KINK", "OFF_CHORD", "BoundaryCurve"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: A boundary vertex that turns by more than this angle (radians) ends its chain: a corner.
KINK = np.pi / 4
#: The farthest the curve over an edge gets from its chord, relative to the chord's length:
#: ``max |g| <= 4/27 (|m0| + |m1|)`` with slopes ``|m| <= 1`` (tangents within 45 degrees
#: of the chord, as the chains are); a piece of the edge is closer to its own chord.
OFF_CHORD = 8.0 / 27.0


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _dot(a: FloatArray, b: FloatArray) -> FloatArray:
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1]


def _inverted(d1: FloatArray, d2: FloatArray) -> FloatArray:
    """The tangent at a point P of the circle through P, P + d1 and P + d2 (the image of
    the circle under the inversion about P is a line parallel to that tangent)."""
    return d1 / _dot(d1, d1)[:, None] - d2 / _dot(d2, d2)[:, None]


@dataclass(frozen=True)
class BoundaryCurve:
    """The curve of the boundary of an initial mesh (module docstring).

    Attributes
    ----------
    A, B : (E, 2) arrays
        The ends of every initial boundary edge.
    tag : (E,) int array
        Its part code.
    m0, m1 : (E,) arrays
        The slopes of the curve over the chord at ``A`` and ``B`` (0 on straight edges).
    curved : (E,) bool array
        The edges whose new vertices move onto the curve.
    """

    A: FloatArray
    B: FloatArray
    tag: IntArray
    m0: FloatArray
    m1: FloatArray
    curved: NDArray[np.bool_]

    @classmethod
    def of(cls, mesh: Mesh) -> BoundaryCurve:
        """The curve through the boundary vertices of ``mesh`` (an initial mesh)."""
        be = mesh.boundary_edges
        tags = mesh.boundary_tags
        tag = np.zeros(len(be), np.int64) if tags is None else np.asarray(tags, np.int64)
        P = mesh.points
        A, B = P[be[:, 0]], P[be[:, 1]]
        d = B - A
        L = np.sqrt(_dot(d, d))
        u = d / L[:, None]
        start = np.full(mesh.n_points, -1, dtype=np.int64)
        start[be[:, 0]] = np.arange(len(be))
        nxt = start[be[:, 1]]  # the boundary edge after every edge (the boundary is closed)
        ok = nxt >= 0  # else a vertex where the boundary touches itself: a chain's end
        own = np.arange(len(be))
        nxt = np.where(ok, nxt, own)
        prv = own.copy()
        prv[nxt[ok]] = own[ok]
        cr, dt = _cross(u, u[nxt]), _dot(u, u[nxt])
        # joint[e]: the vertex between e and nxt[e] is inside a chain
        joint = ok & (tag == tag[nxt]) & (np.arctan2(np.abs(cr), dt) <= KINK)
        flat = joint & (np.abs(cr) <= 1e-10) & (dt > 0)  # e and nxt[e] collinear
        has_prev, has_next = joint[prv] & (prv != own), joint
        straight = flat | flat[prv] | ~(has_prev | has_next)
        # the tangent at the end B of every edge (= the start of nxt where joint)
        a2, b2 = L * L, L[nxt] * L[nxt]
        t_joint = a2[:, None] * d[nxt] + b2[:, None] * d  # circle through three vertices
        t_joint = np.where(straight[:, None], u, np.where(straight[nxt][:, None], u[nxt], t_joint))
        # chain ends: the circle through the end and the next two vertices of the chain
        t_end_b = _inverted(A - B, P[be[prv, 0]] - B)
        t_end_a = _inverted(B - A, P[be[nxt, 1]] - A)
        T1 = np.where(has_next[:, None], t_joint, t_end_b)
        T0 = np.where(has_prev[:, None], t_joint[prv], t_end_a)
        T0 = T0 * np.sign(_dot(T0, u))[:, None]
        T1 = T1 * np.sign(_dot(T1, u))[:, None]
        with np.errstate(divide="ignore", invalid="ignore"):
            m0 = np.where(straight, 0.0, _cross(u, T0) / _dot(u, T0))
            m1 = np.where(straight, 0.0, _cross(u, T1) / _dot(u, T1))
        m0, m1 = np.clip(np.nan_to_num(m0), -1, 1), np.clip(np.nan_to_num(m1), -1, 1)
        curved = ~straight & ((np.abs(m0) > 1e-10) | (np.abs(m1) > 1e-10))
        return cls(A, B, tag, m0, m1, curved)

    @property
    def any(self) -> bool:
        """Whether some edge is curved."""
        return bool(np.any(self.curved))

    def at(self, e: IntArray, t: FloatArray) -> FloatArray:
        """The points of edges ``e`` of the curve at parameters ``t``."""
        A, d = self.A[e], self.B[e] - self.A[e]
        n = np.column_stack([-d[:, 1], d[:, 0]])  # the chord's normal, of its length
        g = self.m0[e] * t * (1.0 - t) ** 2 - self.m1[e] * t * t * (1.0 - t)
        return A + t[:, None] * d + g[:, None] * n

    def locate(self, X: FloatArray, tags: IntArray) -> tuple[IntArray, FloatArray, FloatArray]:
        """For points ``X`` (m, 2) on boundary parts ``tags``: the nearest initial edge of
        the same part (-1 if none is near), the distance to its chord and the parameter
        of the projection."""
        X = np.asarray(X, dtype=float).reshape(-1, 2)
        if len(X) == 0 or len(self.A) == 0:
            z = np.zeros(len(X))
            return np.full(len(X), -1, np.int64), z + np.inf, z
        from scipy.spatial import cKDTree  # imported when used: straight meshes never are

        k = min(8, len(self.A))  # the edges nearest by their midpoints, then exactly
        _, cand = cKDTree(0.5 * (self.A + self.B)).query(X, k=k)
        cand = np.asarray(cand, dtype=np.int64).reshape(len(X), k)
        dist, s = point_segment_distance(X[:, None, :], self.A[cand], self.B[cand])
        dist = np.where(self.tag[cand] == np.asarray(tags)[:, None], dist, np.inf)
        best = np.argmin(dist, axis=1)
        rows = np.arange(len(X))
        e = np.where(np.isfinite(dist[rows, best]), cand[rows, best], -1)
        return e, dist[rows, best], s[rows, best]

    def snap(self, X: FloatArray, tags: IntArray) -> FloatArray:
        """Points ``X`` (m, 2) on boundary parts ``tags`` moved onto the curve: those near
        a curved edge to the point of the projection's parameter, the others unchanged
        (the same bits)."""
        X = np.asarray(X, dtype=float).reshape(-1, 2)
        out = X.copy()
        if not self.any or len(X) == 0:
            return out
        e, _, t = self.locate(X, tags)
        move = (e >= 0) & self.curved[np.maximum(e, 0)]
        out[move] = self.at(e[move], t[move])
        return out
