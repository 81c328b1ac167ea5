"""Several contact parts, each with its own data (docs/method.md, section 3b).

A :class:`ContactPart` is one named boundary part of Gamma_C with its own layer
thickness g, friction and wear coefficients mu and kappa, compliance law p, initial
gap and foundation velocity v*(t). The scheme sees them through nodal arrays: every
contact node belongs to one part (:attr:`ContactBoundary.part`), and
:class:`NodalLaw` applies each part's law at its nodes.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .data import FoundationVelocity, NodalField
from .law import ComplianceLaw, LinearCompliance

__all__ = [
    "PRESSURES",
    "ContactPart",
    "NodalLaw",
    "nodal_velocity",
    "tangential_velocity",
    "velocity_levels",
]

#: The pressures friction and wear may act on: the soft layer's or the whole contact
#: pressure (soft + rigid).
PRESSURES = ("soft", "total")


@dataclass(frozen=True, eq=False)
class ContactPart:
    """One part of Gamma_C and its data.

    Parameters
    ----------
    part : str
        The boundary part of the mesh.
    p : ComplianceLaw
        Normal compliance law of the soft layer.
    g, mu, kappa : NodalField
        Thickness of the soft layer (> 0), friction coefficient (>= 0), wear
        coefficient (>= 0) along the part.
    v_star : FoundationVelocity or 2-vector
        Velocity of the foundation under this part (of the time, or a field of the
        points and the time: :class:`~vemwear.contact.data.FoundationVelocity`).
    gap : NodalField
        Initial gap (>= 0) between the body and the layer: the penetration is
        ``u_nu - gap - w`` and the constraint ``u_nu - gap <= g``.
    friction_on : {"soft", "total"}
        The pressure friction acts on: the soft layer's, ``mu p(u_nu - w) n*`` (the
        paper's law 2.8), or the whole contact pressure, ``mu (p(u_nu - w) + p_rigid)
        n*`` (Coulomb friction on the rigid layer too; docs/method.md, section 4b).
    wear_on : {"soft", "total"}
        The pressure of Archard's wear rate: the soft layer's (the paper's 2.9; the
        rigid layer does not wear) or the whole contact pressure.
    """

    part: str = "contact"
    p: ComplianceLaw = field(default_factory=lambda: LinearCompliance(0.4))
    g: NodalField = 0.1
    mu: NodalField = 0.0
    kappa: NodalField = 0.0
    v_star: FoundationVelocity | ArrayLike = (1.0, 0.0)
    gap: NodalField = 0.0
    friction_on: str = "soft"
    wear_on: str = "soft"

    def __post_init__(self) -> None:
        if not isinstance(self.v_star, FoundationVelocity):
            object.__setattr__(self, "v_star", FoundationVelocity(self.v_star))
        for key in ("friction_on", "wear_on"):
            if getattr(self, key) not in PRESSURES:
                raise ValueError(
                    f"{key} of contact part {self.part!r} must be 'soft' or 'total', got "
                    f"{getattr(self, key)!r}"
                )

    @property
    def velocity(self) -> FoundationVelocity:
        return self.v_star  # type: ignore[return-value]


@dataclass(frozen=True, eq=False)
class NodalLaw(ComplianceLaw):
    """The compliance laws of several parts, each applied at its own nodes.

    Parameters
    ----------
    laws : sequence of ComplianceLaw
        One law per part.
    part : (m,) int array
        The part of every contact node.
    """

    laws: tuple[ComplianceLaw, ...]
    part: NDArray[np.int64]

    @property
    def lipschitz(self) -> float:  # type: ignore[override]
        return float(max(law.lipschitz for law in self.laws))

    def _apply(self, r: ArrayLike, derivative: bool) -> NDArray[np.float64]:
        r = np.asarray(r, dtype=float)
        out = np.zeros_like(r)
        for i, law in enumerate(self.laws):
            sel = self.part == i
            out[sel] = law.derivative(r[sel]) if derivative else law(r[sel])
        return out

    def __call__(self, r: ArrayLike) -> NDArray[np.float64]:
        return self._apply(r, False)

    def derivative(self, r: ArrayLike) -> NDArray[np.float64]:
        return self._apply(r, True)

    def describe(self) -> dict[str, Any]:
        return {"type": "by part", "laws": [law.describe() for law in self.laws]}


def nodal_velocity(
    parts: Sequence[ContactPart],
    part: NDArray[np.int64],
    points: NDArray[np.float64],
    t: float,
) -> NDArray[np.float64]:
    """``v*(x_a, t)`` at every contact node, (m, d), with the v* of the node's part: a
    v* of the time alone is evaluated once per part, a field at the part's nodes."""
    if not any(pc.velocity.spatial for pc in parts):
        return np.array([pc.velocity(t) for pc in parts])[part]
    v = np.empty(np.shape(points))
    for i, pc in enumerate(parts):
        sel = part == i
        if np.any(sel):
            v[sel] = pc.velocity.at(points[sel], t)
    return v


def tangential_velocity(
    parts: Sequence[ContactPart],
    part: NDArray[np.int64],
    tangents: NDArray[np.float64],
    t: float,
    points: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """The tangential foundation velocity ``v*(x_a, t) · tau_a`` at every contact node.

    Each node takes the v* of its part; ``points``, the nodes, are needed for a v* that
    is a field.

    The tangential part of the foundation velocity is ``v*_tau = (v* . tau_a) tau_a``
    in 2D; its sign gives the friction direction ``n* = -v*_tau / |v*_tau|`` and its
    length the wear rate ``alpha = kappa |v*_tau|`` (docs/method.md, section 3b).
    """
    if points is None:
        if any(pc.velocity.spatial for pc in parts):
            raise ValueError("tangential_velocity: a v* field needs the contact points")
        points = np.zeros((len(part), tangents.shape[1]))
    return tangential_components(nodal_velocity(parts, part, points, t), tangents)


def tangential_components(v: NDArray[np.float64], tangents: NDArray[np.float64]) -> NDArray:
    """The products ``v_a · tau_a`` of (m, d) velocities and tangents, node by node."""
    if tangents.shape[1] != v.shape[1]:
        raise ValueError(
            f"v_star has {v.shape[1]} components, the contact tangents {tangents.shape[1]}"
        )
    out = v[:, 0] * tangents[:, 0] + v[:, 1] * tangents[:, 1]
    if tangents.shape[1] == 3:  # 3D: tau_a is the line of v*_tau (contact.boundary3d)
        out = out + v[:, 2] * tangents[:, 2]
    return np.asarray(out, dtype=np.float64)


def velocity_levels(v: FoundationVelocity, t: NDArray[np.float64]) -> NDArray[np.float64]:
    """``v*(t_n)`` at many times at once, (len(t), d), not checked for being finite
    (a v* of the time alone; a field: :func:`nodal_velocity` level by level).

    Numbers and tables of t are evaluated in one go, as is a callable with a method
    ``at_times(t)`` (the expressions of a configuration file); any other callable one
    time at a time.
    """
    ts = np.asarray(t, dtype=float).ravel()
    if ts.size == 0:
        return np.zeros((0, len(v(0.0))))
    s = v.spec
    if callable(s):
        many = getattr(s, "at_times", None)
        if many is not None:
            return np.asarray(many(ts), dtype=float).reshape(len(ts), -1)
        return np.array([np.asarray(s(x), dtype=float) for x in ts]).reshape(len(ts), -1)
    if isinstance(s, Mapping):
        at, vals = np.asarray(s["t"], dtype=float), np.asarray(s["values"], dtype=float)
        return np.column_stack([np.interp(ts, at, vals[:, c]) for c in range(vals.shape[1])])
    c = np.asarray(s, dtype=float).ravel()
    return np.broadcast_to(c, (len(ts), len(c))).copy()
