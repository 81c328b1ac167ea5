"""The continuous data of Problem 2.1 and their discretization (paper Sections 2-3).

The discrete choices the paper leaves open (nodal contact quadrature, normals at
corners, the stabilization weight, the load) are those of docs/method.md, sections 1-4.
The paper's setting (one clamped part Gamma_D, one traction part Gamma_N, one contact
part Gamma_C) is the default; a problem may also have prescribed displacement
components, several traction and contact parts, initial gaps and free parts.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any, Generic, TypeVar, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..contact import (
    ComplianceLaw,
    ContactBoundary,
    ContactPart,
    FoundationVelocity,
    LinearCompliance,
    NodalField,
    NodalLaw,
    check_law,
    contact_boundary,
    contact_boundary3d,
    foundation_rows,
    nodal_values,
    nodal_velocity,
    velocity_levels,
    velocity_line,
)
from ..mesh.checks import check_mesh
from ..mesh.checks3d import check_mesh3d
from ..mesh.polyhedra import Mesh3D
from ..mesh.polymesh import Mesh, MeshError
from ..util.hashing import sha256_arrays
from ..vem import Material
from ..vem.assembly import Field
from ..vem.space import ORDERS, P1Space, P1Space3D, P2Space, has_part, make_space, part_facets
from .constraints import Constraints, Prescribed, describe_motions, null_space_rows
from .discrete import DataError
from .rigidparts import RigidPart
from .timegrid import TimeGrid

if TYPE_CHECKING:
    from .discrete import Discretization

__all__ = ["DataError", "Problem"]

#: The mesh type of a problem: polygons (2D) or polyhedra (3D). ``Problem`` without a
#: parameter, as the 2D layers above write it, takes any.
MeshT = TypeVar("MeshT", bound=Mesh | Mesh3D)


@dataclass(frozen=True, eq=False)
class Problem(Generic[MeshT]):
    """Contact problem with wear on a tagged polygonal mesh (Problem 2.1 / 3.3).

    Parameters
    ----------
    mesh : Mesh or Mesh3D
        With tagged boundary parts; the paper's are ``clamped`` (Gamma_D),
        ``traction`` (Gamma_N) and ``contact`` (Gamma_C). On a :class:`Mesh3D` (k = 1,
        docs/method.md section 10) the boundary facets are faces, the loads, v* and the
        prescribed components have three components (the 2-vector defaults of f1, f2
        and v* become (0, 0, 0), (0, 0, 0) and (1, 0, 0)); a v* that turns gets two
        friction rows per node (:func:`~vemwear.contact.foundation_rows`).
    material : Material
        Lamé coefficients lam, eta.
    time : TimeGrid
        The partition of [0, T].
    f1, f2 : Field
        Body force and traction: a 2-vector or a callable ``f(x, t)``.
    p : ComplianceLaw
        Normal compliance law of the soft layer.
    g, mu, kappa : NodalField
        Layer thickness (> 0), friction coefficient (>= 0), wear coefficient (>= 0)
        along Gamma_C.
    v_star : FoundationVelocity, RotatingFoundation or 2-vector
        Velocity of the foundation, of t or a field of the points and t
        (``FoundationVelocity(f, spatial=True)``, a :class:`~vemwear.contact.
        RotatingFoundation`); it may vanish at some times and places (no friction and no
        wear there).
    stabilization : str
        ``"paper"`` (weight 1, the paper's dofi-dofi), ``"eta"`` or ``"trace"``.
    gap : NodalField
        Initial gap (>= 0) between the body and the layer along Gamma_C.
    clamped : tuple of str
        The parts with u = 0 (Gamma_D); ``"clamped"`` by default, skipped if the mesh
        has no such part and other constraints hold the body.
    displacement : tuple of Prescribed
        Parts with prescribed displacement components.
    contacts : tuple of ContactPart
        Several contact parts with their own data; by default one part ``contact``
        with ``p, g, mu, kappa, v_star, gap`` above.
    order : int
        The order k of the virtual element space (:mod:`vemwear.vem.space`): 1 (the
        paper's examples) or 2 (docs/method.md, section 9).
    rigid : tuple of RigidPart
        Parts that move as one rigid body, loaded by a force resultant or with a
        prescribed translation (the holder of a pin or ball, docs/method.md section 1d).

    ``f2`` may also be a mapping ``{part: traction}`` for several traction parts.
    Every boundary edge belongs to one part; parts that are none of the above are
    traction-free.

    Examples
    --------
    The paper's Section 5 setting on 8 x 4 squares, with 8 time steps:

    >>> import vemwear
    >>> mesh = vemwear.tag_rectangle(vemwear.rectangle_squares((2.0, 1.0), (8, 4)))
    >>> problem = vemwear.Problem(
    ...     mesh,
    ...     vemwear.Material(lam=4.0, eta=4.0),
    ...     vemwear.TimeGrid.uniform(T=1.0, steps=8),
    ...     f1=(0.0, -0.06),
    ...     p=vemwear.LinearCompliance(0.4),
    ...     g=0.1, mu=0.2, kappa=2.0, v_star=(1.0, 0.0),
    ... )
    >>> [part.part for part in problem.parts], problem.time.n_steps
    (['contact'], 8)
    """

    mesh: MeshT
    material: Material
    time: TimeGrid
    f1: Field = (0.0, 0.0)
    f2: Field | Mapping[str, Field] = (0.0, 0.0)
    p: ComplianceLaw = field(default_factory=lambda: LinearCompliance(0.4))
    g: NodalField = 0.1
    mu: NodalField = 0.0
    kappa: NodalField = 0.0
    v_star: FoundationVelocity | ArrayLike = (1.0, 0.0)
    stabilization: str = "paper"
    gap: NodalField = 0.0
    clamped: tuple[str, ...] = ("clamped",)
    displacement: tuple[Prescribed, ...] = ()
    contacts: tuple[ContactPart, ...] = ()
    order: int = 1
    rigid: tuple[RigidPart, ...] = ()

    def __post_init__(self) -> None:
        if self.order not in ORDERS:
            raise ValueError(f"order must be one of {ORDERS}, got {self.order!r}")
        if not isinstance(self.v_star, FoundationVelocity):
            object.__setattr__(self, "v_star", FoundationVelocity(self.v_star))
        object.__setattr__(self, "clamped", tuple(self.clamped))
        object.__setattr__(self, "displacement", tuple(self.displacement))
        object.__setattr__(self, "contacts", tuple(self.contacts))
        object.__setattr__(self, "rigid", tuple(self.rigid))
        if isinstance(self.mesh, Mesh3D):
            self._defaults3d()
            check_mesh3d(self.mesh, require=())
        else:
            check_mesh(self.mesh, require=())
        named = [
            *(c for c in self.clamped if c != "clamped" or c in self.mesh.part_names),
            *(d.part for d in self.displacement),
            *(r.part for r in self.rigid),
            *self.tractions,
            *(c.part for c in self.parts),
        ]
        for name in named:
            if not has_part(self.mesh, name):
                kind = "faces" if self.dim == 3 else "edges"
                raise MeshError(f"the mesh has no {name!r} boundary {kind}")
        left = describe_motions(self.mesh, self.held_by_contact_check())
        if left:
            raise MeshError(
                "the boundary conditions leave rigid motions free: "
                + ", ".join(left)
                + "; clamp a part or prescribe the displacement components that stop them "
                "(contact holds only motions that move contact nodes along their normals)"
            )
        nodal = self.nodal  # validates g, mu, kappa, gap
        scale = float(max(np.abs(nodal["g"]).max(), 1e-300))
        for pc in self.parts:
            check_law(pc.p, scale=scale)

    @cached_property
    def rigid_basis(self) -> NDArray[np.float64]:
        """The rigid motions that the constraints leave free and contact holds (load
        control, docs/method.md section 1c): an orthonormal basis (r, 3) in 2D or (r, 6)
        in 3D in the coordinates of :meth:`Constraints.rigid_motion_matrix`; empty when
        the constraints hold the body."""
        return self.constraints.free_rigid_basis()

    def held_by_contact_check(self) -> NDArray[np.float64]:
        """The free rigid motions that contact cannot hold (rows in the coordinates of
        :meth:`Constraints.rigid_motion_matrix`): those that move no contact node along
        its normal, the null space of ``N R`` within :attr:`rigid_basis`."""
        basis = self.rigid_basis
        if len(basis) == 0:
            return basis
        cb, con = self.contact, self.constraints
        if cb.m == 0:
            return basis
        d = self.dim
        # nu_a . r(x_a) of each free motion r at each contact node
        NR = (
            sum(
                cb.normals[:, c, None]
                * con.rigid_motion_matrix(cb.points, np.full(cb.m, c, dtype=np.int64))
                for c in range(d)
            )
            @ basis.T
        )
        return null_space_rows(NR) @ basis

    @property
    def dim(self) -> int:
        """The dimension d of the mesh (2 or 3)."""
        return 3 if isinstance(self.mesh, Mesh3D) else 2

    def _defaults3d(self) -> None:
        """3D: the 2-vector defaults of f1, f2 and v* in three components; constant
        vectors of other lengths refused."""

        def as3(value: Any, default: tuple[float, ...], name: str) -> Any:
            if callable(value) or isinstance(value, (Mapping, FoundationVelocity)):
                return value
            v = np.asarray(value, dtype=float)
            if v.shape == (2,) and np.array_equal(v, default):
                return (*default, 0.0)
            if v.shape != (3,):
                raise ValueError(f"{name} needs three components on a 3D mesh, got {value!r}")
            return value

        object.__setattr__(self, "f1", as3(self.f1, (0.0, 0.0), "f1"))
        object.__setattr__(self, "f2", as3(self.f2, (0.0, 0.0), "f2"))
        v = cast(FoundationVelocity, self.v_star)
        if not callable(v.spec) and not isinstance(v.spec, Mapping):
            object.__setattr__(
                self, "v_star", FoundationVelocity(as3(v.spec, (1.0, 0.0), "v_star"))
            )
        for pc in self.parts:
            if not pc.velocity.spatial and len(pc.velocity(float(self.time.t[0]))) != 3:
                raise ValueError(f"v_star of {pc.part!r} needs three components on a 3D mesh")

    @cached_property
    def parts(self) -> tuple[ContactPart, ...]:
        """The contact parts with their data (one part ``contact`` by default)."""
        if self.contacts:
            return self.contacts
        v = cast(FoundationVelocity, self.v_star)
        return (ContactPart("contact", self.p, self.g, self.mu, self.kappa, v, self.gap),)

    @cached_property
    def tractions(self) -> dict[str, Field]:
        """``{part: f2}``: the traction parts and their loads."""
        if isinstance(self.f2, Mapping):
            return dict(self.f2)
        return {"traction": self.f2} if has_part(self.mesh, "traction") else {}

    @cached_property
    def law(self) -> ComplianceLaw:
        """The compliance law at the contact nodes (each part's own law)."""
        if len(self.parts) == 1:
            return self.parts[0].p
        return NodalLaw(tuple(pc.p for pc in self.parts), self.contact.part)

    @cached_property
    def space(self) -> P1Space | P2Space | P1Space3D:
        """The virtual element space of order :attr:`order` on the mesh."""
        return make_space(self.mesh, self.order)

    @cached_property
    def constraints(self) -> Constraints:
        """The constrained dofs: clamped parts and prescribed components."""
        return Constraints(self.mesh, self.clamped, self.displacement, self.space, self.rigid)

    @cached_property
    def contact(self) -> ContactBoundary:
        """Nodes, weights and normals of Gamma_C (all contact parts)."""
        con = self.constraints
        if isinstance(self.mesh, Mesh3D):
            t = self.time.t
            cb = contact_boundary3d(
                self.mesh,
                tuple(pc.part for pc in self.parts),
                con.fully_fixed_vertices,
                space=cast(P1Space3D, self.space),
                directions=np.array([_line(pc, t) for pc in self.parts]),
            )
            return foundation_rows(cb, self.parts, t)  # fields and turning v*
        return contact_boundary(
            self.mesh,
            tuple(pc.part for pc in self.parts),
            con.fully_fixed_vertices,
            space=self.space,
            constrained=con.mask,
        )

    @cached_property
    def nodal(self) -> dict[str, NDArray[np.float64]]:
        """g, mu, kappa and gap at the contact nodes, each from the node's part, checked
        for their signs."""
        cb = self.contact
        out = {}
        for name, rel in (("g", "> 0"), ("mu", ">= 0"), ("kappa", ">= 0"), ("gap", ">= 0")):
            v = np.zeros(cb.m)
            for i, pc in enumerate(self.parts):
                sel = np.asarray(cb.part == i, dtype=bool)
                if np.any(sel):
                    v[sel] = nodal_values(getattr(pc, name), _subset(cb, sel), name)
            ok = v > 0 if name == "g" else v >= 0
            if not np.all(ok):
                a = int(np.flatnonzero(~ok)[0])
                raise ValueError(
                    f"{name} must be {rel} on the contact part; it is {v[a]:g} at contact node "
                    f"{a} (vertex {cb.nodes[a]}, x = {cb.points[a].tolist()})"
                )
            out[name] = v
        return out

    @cached_property
    def discrete(self) -> Discretization:
        """The assembled discrete problem (built on first use; :meth:`discretize`
        chooses how)."""
        from .discrete import Discretization

        return Discretization(self)

    def discretize(self, distributed: bool = False) -> Discretization:
        """:attr:`discrete`, built here if it is not yet: with ``distributed``, its K
        is kept by the ranks of the MPI job of the petsc backend and rank 0 holds only
        its rows at the contact and the constrained dofs (docs/mpi.md)."""
        from .discrete import Discretization

        made = self.__dict__.get("discrete")
        if made is None:
            made = self.__dict__["discrete"] = Discretization(self, distributed=distributed)
        return made

    def describe(self) -> dict[str, Any]:
        """The inputs as JSON-friendly data (callables by name)."""

        def desc(x: Any) -> Any:
            if callable(x):
                return getattr(x, "__name__", "callable")
            if isinstance(x, dict):
                return {k: desc(v) for k, v in x.items()}
            return np.asarray(x).tolist()

        m = self.mesh
        # the order only when it is not the paper's k = 1 (earlier fingerprints stay valid)
        order = {} if self.order == 1 else {"order": self.order}
        if isinstance(m, Mesh3D):
            nf = np.diff(m.cell_offsets)
            mesh_desc: dict[str, Any] = {
                "dim": 3,
                "points": m.n_points,
                "cells": m.n_cells,
                "h": float(m.cell_diameters.max()),
                "cells_by_face_count": {str(n): int(np.sum(nf == n)) for n in np.unique(nf)},
            }
        else:
            mesh_desc = {
                "points": m.n_points,
                "cells": m.n_cells,
                "h": m.h,
                "cells_by_vertex_count": {str(n): len(i) for n, (i, _) in m.groups.items()},
            }
        return {
            **order,
            "mesh": mesh_desc,
            "material": {"lam": self.material.lam, "eta": self.material.eta},
            "time": self.time.describe(),
            "f1": desc(self.f1),
            "f2": desc(self.f2),
            "p": self.p.describe(),
            "g": desc(self.g),
            "mu": desc(self.mu),
            "kappa": desc(self.kappa),
            "v_star": self.v_star.describe(),  # type: ignore[union-attr]
            "stabilization": self.stabilization,
            "parts": list(m.part_names),
            "clamped": list(self.clamped),
            "displacement": [d.describe() for d in self.displacement],
            # rigid parts only when there are some (earlier fingerprints stay valid)
            **({"rigid": [r.describe() for r in self.rigid]} if self.rigid else {}),
            "gap": desc(self.gap),
            "contacts": [
                {
                    "part": c.part,
                    "p": c.p.describe(),
                    **{k: desc(getattr(c, k)) for k in ("g", "mu", "kappa", "gap")},
                    "v_star": c.velocity.describe(),
                    # the paper's law by default: earlier fingerprints stay valid
                    **{
                        k: getattr(c, k)
                        for k in ("friction_on", "wear_on")
                        if getattr(c, k) != "soft"
                    },
                }
                for c in self.contacts
            ],
        }

    def external_load(self, t: float) -> NDArray[np.float64]:
        """``<f_h(t), v>`` on all dofs: the body force by (3.3) and the traction of every
        traction part by edge quadrature."""
        F = self.space.body_force(self.f1, t)
        for name, f2 in self.tractions.items():
            F = F + self.space.boundary_load(part_facets(self.mesh, name), f2, t)
        return F

    def fingerprint(self) -> dict[str, Any]:
        """What determines the computed numbers: the physics and the discretization.

        Solver options are not part of it: every solver that converges gives the same
        solution to its tolerance. Data given as callables enter by their values (g,
        mu and kappa at the contact nodes, v* at up to 65 sampled levels, the load
        vector at t_0 and T) besides their names. Hash it with
        :func:`vemwear.util.hashing.sha256_json`.
        """
        from .. import __version__

        m, t = self.mesh, self.time.t
        sample = np.unique(np.linspace(0, len(t) - 1, min(len(t), 65)).astype(np.int64))

        return {
            "format": "vemwear-problem/1",
            "vemwear_version": __version__,
            "description": self.describe(),
            "mesh": (
                sha256_arrays(
                    m.points,
                    m.face_offsets,
                    m.face_vertices,
                    m.cell_offsets,
                    m.cell_faces,
                    m.cell_face_signs,
                    m.boundary_tags,
                )
                if isinstance(m, Mesh3D)
                else sha256_arrays(m.points, m.cell_offsets, m.cell_vertices, m.boundary_tags)
            ),
            "time": sha256_arrays(t),
            "nodal": sha256_arrays(*(self.nodal[k] for k in ("g", "mu", "kappa", "gap"))),
            "v_star": sha256_arrays(
                np.array([[pc.velocity(t[i]) for pc in self.parts] for i in sample])
                if not any(pc.velocity.spatial for pc in self.parts)
                else np.array(
                    [
                        nodal_velocity(self.parts, self.contact.part, self.contact.points, t[i])
                        for i in sample
                    ]
                )
            ),
            "load": sha256_arrays(
                self.external_load(float(t[0])), self.external_load(float(t[-1]))
            ),
            "prescribed": sha256_arrays(
                self.constraints.dofs,
                self.constraints.values(float(t[0])),
                self.constraints.values(float(t[-1])),
            ),
        }


def _line(pc: ContactPart, t: NDArray[np.float64]) -> NDArray[np.float64]:
    """The line of a part's v* of the time alone (the x axis for a field or a v* that
    turns, whose friction rows :func:`~vemwear.contact.foundation_rows` sets)."""
    if pc.velocity.spatial:
        return np.array([1.0, 0.0, 0.0])
    try:
        return velocity_line(velocity_levels(pc.velocity, t), f"v_star of {pc.part!r}")
    except ValueError:
        return np.array([1.0, 0.0, 0.0])


def _subset(cb: ContactBoundary, sel: NDArray[np.bool_]) -> ContactBoundary:
    """The contact nodes ``sel`` of ``cb`` (for the data of one contact part)."""
    return ContactBoundary(
        nodes=cb.nodes[sel],
        points=cb.points[sel],
        s=cb.s[sel],
        weights=cb.weights[sel],
        normals=cb.normals[sel],
        tangents=cb.tangents[sel],
        n_dof=cb.n_dof,
    )
