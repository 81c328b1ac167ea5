"""The schema of configuration files: pydantic models of every section and key.

The models declare what a file may hold: its sections and keys (an unknown one is an
error with a suggestion), their types (numbers finite, integers where required),
defaults (those of the library objects), and the forms a key may take: the
compliance law by its ``type``, ``[time]`` by which of ``steps``, ``dt``, ``pattern``,
``levels`` it holds, ``[mesh]`` by its ``generator`` or ``file``
(:mod:`vemwear.config.mesh_forms`), a coefficient as a number, an expression string
(parsed by :mod:`vemwear.config.expr`) or a table. The physics (signs, monotone laws,
time grids) is checked by the library objects the values become
(:mod:`vemwear.config.build`), not here. The field descriptions are the key reference
of ``docs/config.md`` and of the JSON Schema that ``vemwear schema`` prints.

One job, one module: every section's model is here, down to :class:`ConfigFile` (the
file), so that the schema reads in one place; most of its length is the one-line
description of each key. The base model and the union and expression types the keys
are declared with are in :mod:`vemwear.config.sections`, the ``[mesh]`` forms (built
from the mesh registries) in :mod:`vemwear.config.mesh_forms`, ``[adapt]`` with its
checks in :mod:`vemwear.config.adapt`.
"""

import difflib
from typing import Annotated, Any, Literal, TypeAlias

from pydantic import AfterValidator, ConfigDict, Field, model_validator

from ..mesh.boundary import SIDES
from ..simulate import Problem, SolverOptions
from ..solvers import BACKENDS, SOLVERS
from ..vem import STABILIZATIONS
from .adapt import Adapt
from .errors import error, got, show, suggest
from .mesh_forms import MeshFile, MeshForm
from .sections import Section, by_kind, choice, components, expression, library_default

Vector: TypeAlias = Annotated[list[float], Field(min_length=2, max_length=2)]
#: A vector of a 2D (2 components) or a 3D (3 components) problem; the mesh decides which.
Vector23: TypeAlias = Annotated[list[float], Field(min_length=2, max_length=3)]


# ---------------------------------------------------------------------------- boundary
class Segment(Section):
    """The boundary edges lying on a segment (validated into the pair of its ends)."""

    model_config = ConfigDict(title="segment { from, to }")
    start: Vector = Field(alias="from", description="one end [x, y]")
    to: Vector = Field(description="the other end [x, y]")


_SIDES = f"a side ({', '.join(map(repr, SIDES))})"
Ends: TypeAlias = Annotated[Segment, AfterValidator(lambda g: (tuple(g.start), tuple(g.to)))]
Piece: TypeAlias = by_kind(  # type: ignore[valid-type]
    f"{_SIDES}, a part of the mesh file or a segment {{ from, to }}", string=str, table=Ends
)
Selector: TypeAlias = by_kind(  # type: ignore[valid-type]
    f"{_SIDES}, 'rest', a segment {{ from = [x, y], to = [x, y] }}, the name of a part of "
    "the mesh file, or an array of these",
    string=str,
    table=Ends,
    array=Annotated[list[Piece], Field(min_length=1)],  # type: ignore[valid-type]
)


# ---------------------------------------------------------------------------- contact
class CoefficientTable(Section):
    """Piecewise linear along Gamma_C, constant beyond the ends."""

    model_config = ConfigDict(title="table { along, at, values }")
    along: Literal["x", "y", "s"] = Field(
        "x",
        description="coordinate of the contact nodes: x, y or s (arc length along Gamma_C; "
        "x in 3D)",
    )
    at: list[float] = Field(description="interpolation points, strictly increasing")
    values: list[float] = Field(description="the values there, as many as `at`")


class LinearLaw(Section):
    """``p(r) = c r_+``."""

    model_config = ConfigDict(title="{ type = 'linear', c }")
    type: Literal["linear"]
    c: float = Field(description="stiffness c >= 0 (a stress per length)")


class TableLaw(Section):
    """Piecewise linear through the points ``(r_i, p_i)``, zero for ``r <= 0``, continued
    with the last slope."""

    model_config = ConfigDict(title="{ type = 'table', r, p }")
    type: Literal["table"]
    r: list[float] = Field(description="0 = r_0 < r_1 < ..., at least 2 points")
    p: list[float] = Field(description="0 = p_0 <= p_1 <= ..., as many as r")


class VelocityTable(Section):
    """``v*(t)`` piecewise linear in time, constant beyond the ends."""

    model_config = ConfigDict(title="table { t, values }")
    t: list[float] = Field(min_length=1, description="times, strictly increasing")
    values: list[Vector23] = Field(description="velocities [vx, vy] (3D: [vx, vy, vz]) there")

    @model_validator(mode="after")
    def _increasing(self) -> "VelocityTable":
        if len(self.t) != len(self.values):
            n, m = len(self.t), len(self.values)
            raise error(f": 't' and 'values' must have the same length, got {n} and {m}")
        bad = [i for i in range(1, len(self.t)) if not self.t[i] > self.t[i - 1]]
        if bad:
            raise error(f".t = {show(self.t)} must increase strictly (entry {bad[0]})")
        return self


class Rotation(Section):
    """A counterface turning about an axis: ``v* = omega a x (x - c)``."""

    model_config = ConfigDict(title="{ center, axis, omega }")
    center: Vector23 = Field(description="a point c of the axis [x, y] (3D: [x, y, z])")
    axis: Annotated[list[float], Field(min_length=3, max_length=3)] = Field(
        [0.0, 0.0, 1.0],
        description="direction a of the axis (normalized); in 2D (0, 0, 1) or (0, 0, -1)",
    )
    omega: by_kind(  # type: ignore[valid-type]
        "a number or an expression string in t", number=float, string=expression("t")
    ) = Field(description="angular velocity (rad per unit time): a number or an expression in t")


class VelocityRotation(Section):
    """``v*`` of a rotating counterface (a disc turning under a pin)."""

    model_config = ConfigDict(title="{ rotation = { center, axis, omega } }")
    rotation: Rotation = Field(description="the axis and the angular velocity")


LAWS: dict[str, type[Section]] = {"linear": LinearLaw, "table": TableLaw}


def _law_error(v: Any) -> str:
    if not isinstance(v, dict):
        return f"must be a table, {got(v)}"
    if "type" not in v:
        return "missing required key 'type' ('linear' or 'table')"
    t = v["type"]
    hint = suggest(t, list(LAWS)) if isinstance(t, str) else ""
    return f".type must be one of {', '.join(map(repr, LAWS))}, got {show(t)}{hint}"


def _law_form(v: Any) -> str | None:
    t = v.get("type") if isinstance(v, dict) else None
    return t if isinstance(t, str) and t in LAWS else None


Law: TypeAlias = choice(_law_form, _law_error, **LAWS)  # type: ignore[valid-type]
Coefficient: TypeAlias = by_kind(  # type: ignore[valid-type]
    "a number, an expression string in x, y, z or a table { along, at, values }",
    number=float,
    string=expression("x", "y", "z"),
    table=CoefficientTable,
)


def _vstar_form(v: Any) -> str | None:
    if isinstance(v, list):
        return "array"
    if isinstance(v, dict):
        return "rotation" if "rotation" in v else "table"
    return None


VStar: TypeAlias = choice(  # type: ignore[valid-type]
    _vstar_form,
    lambda v: (
        "must be an array [vx, vy] (3D: [vx, vy, vz]) of numbers or expression strings "
        f"in x, y, z, t, a table {{ t, values }} or {{ rotation = {{ center, axis, omega }} }}, "
        f"{got(v)}"
    ),
    array=components("x", "y", "z", "t"),
    table=VelocityTable,
    rotation=VelocityRotation,
)
Load: TypeAlias = components("x", "y", "z", "t")  # type: ignore[valid-type]
TractionComponent: TypeAlias = by_kind(  # type: ignore[valid-type]
    "a number, an expression string in x, y, z, t or a table { along, at, values }",
    number=float,
    string=expression("x", "y", "z", "t"),
    table=CoefficientTable,
)
TractionLoad: TypeAlias = Annotated[
    list[TractionComponent],  # type: ignore[valid-type]
    Field(min_length=2, max_length=3),
]
DispComponent: TypeAlias = by_kind(  # type: ignore[valid-type]
    "a number or an expression string in x, y, z, t",
    number=float,
    string=expression("x", "y", "z", "t"),
)


class Contact(Section):
    """A contact part of Gamma_C: the soft layer and the foundation. ``[contact]`` is one
    part (where: ``[boundary] contact`` or ``on``); ``[[contact]]`` tables are several
    parts, each with its own ``on``."""

    name: str | None = Field(
        None, description="name of the part (default: contact, or contact1, contact2, ...)"
    )
    on: Selector | None = Field(
        None, title="selector", description="where (default: [boundary] contact)"
    )
    p: Law = Field(description="normal compliance law of the soft layer, see below")
    g: Coefficient = Field(description="thickness of the soft layer, > 0 (u_nu - gap <= g)")
    mu: Coefficient = Field(description="friction coefficient, >= 0")
    kappa: Coefficient = Field(
        description="wear coefficient, >= 0 (wear rate kappa |v*_tau| p, v*_tau the part of "
        "v* along the boundary)"
    )
    v_star: VStar = Field(
        description="velocity of the foundation, of t or a field of x, y, z and t; it may "
        "vanish at times and places"
    )
    gap: Coefficient = Field(
        0.0,
        description="initial gap between the body and the layer, >= 0 (penetration u_nu - gap - w)",
    )
    friction_on: Literal["soft", "total"] = Field(
        "soft",
        description="pressure friction acts on: 'soft', the soft layer's p(u_nu - w) (the "
        "paper's law), or 'total', the whole contact pressure p(u_nu - w) + p_rigid (Coulomb "
        "friction on the rigid layer too)",
    )
    wear_on: Literal["soft", "total"] = Field(
        "soft",
        description="pressure of the wear rate kappa |v*_tau| p: 'soft' (the soft layer "
        "wears, the rigid layer does not) or 'total' (the whole contact pressure)",
    )


class Loads(Section):
    """Body force and traction."""

    f1: Load = Field(
        library_default(Problem, "f1"), description="body force [f1x, f1y] (3D: [f1x, f1y, f1z])"
    )
    f2: Load = Field(
        library_default(Problem, "f2"),
        description="traction [f2x, f2y] (3D: [f2x, f2y, f2z]) on Gamma_N",
    )


class Material(Section):
    """Isotropic linear elasticity, ``sigma = 2 eta eps + lam tr(eps) I``."""

    lam: float = Field(description="Lamé coefficient lambda, > 0")
    eta: float = Field(description="Lamé coefficient eta (the shear modulus), > 0")


class Vem(Section):
    """The virtual element bilinear form."""

    stabilization: Literal[STABILIZATIONS] = Field(  # type: ignore[valid-type]
        library_default(Problem, "stabilization"),
        description="weight of the dofi-dofi stabilization: 'paper' (1, as in the paper), "
        "'eta' (2 eta) or 'trace' (trace of the consistency matrix / n_dof)",
    )
    order: int = Field(
        library_default(Problem, "order"),
        ge=1,
        le=2,
        description="order k of the virtual element space: 1 (the paper's examples: vertex "
        "values) or 2 (vertex values, edge and cell means; contact at the vertices and edge "
        "midpoints of Gamma_C with Simpson's weights)",
    )


# ---------------------------------------------------------------------------- time
class CycleJumpTable(Section):
    """Cycle jumps for a periodic loading: the time grid is one cycle."""

    model_config = ConfigDict(title="{ cycles, jump, period, max_increment }")
    cycles: int = Field(ge=1, description="number of load cycles N")
    jump: int = Field(1, ge=1, description="cycles advanced per computed cycle (1: all computed)")
    period: float | None = Field(
        None, description="the period P of the loading; must equal T (default: T)"
    )
    max_increment: float = Field(
        0.05,
        gt=0,
        le=1,
        description="largest extrapolated wear per jump, as a fraction of g",
    )


class TimeBase(Section):
    """Keys of every time grid."""

    cycle_jump: CycleJumpTable | None = Field(
        None,
        title="{ cycles, jump, period, max_increment }",
        description="run N cycles of a periodic loading, the grid being one cycle, "
        "computing one cycle in every 'jump' and extrapolating the wear between",
    )


class Steps(TimeBase):
    """Uniform."""

    T: float = Field(description="final time, > 0")
    steps: int = Field(description="number of equal steps, >= 1")


class Dt(TimeBase):
    """Explicit step sizes."""

    T: float | None = Field(None, description="final time; if given, the sum of dt")
    dt: list[float] = Field(description="the step sizes k_0, k_1, ..., each > 0")


class Pattern(TimeBase):
    """Repeated step sizes."""

    T: float = Field(description="final time, > 0")
    pattern: list[float] = Field(
        description="step sizes repeated until T, the last step cut to end at T"
    )


class Levels(TimeBase):
    """Explicit time levels."""

    T: float | None = Field(None, description="final time; if given, the last level")
    levels: list[float] = Field(
        min_length=2, description="the levels 0 = t_0 < t_1 < ... themselves"
    )


TIME_FORMS: dict[str, type[Section]] = {
    "steps": Steps,
    "dt": Dt,
    "pattern": Pattern,
    "levels": Levels,
}


def _time_form(v: Any) -> str | None:
    given = [k for k in TIME_FORMS if k in v] if isinstance(v, dict) else []
    return given[0] if len(given) == 1 else None


def _time_error(v: Any) -> str:
    if not isinstance(v, dict):
        return f"must be a table, {got(v)}"
    forms = [f"{k!r} ({(c.__doc__ or '').strip(' .').lower()})" for k, c in TIME_FORMS.items()]
    given = [k for k in TIME_FORMS if k in v]
    return f"needs exactly one of {', '.join(forms[:-1])} or {forms[-1]}" + (
        f"; got {', '.join(given)}" if given else ""
    )


TimeForm: TypeAlias = choice(_time_form, _time_error, **TIME_FORMS)  # type: ignore[valid-type]


# ---------------------------------------------------------------------------- solver, output
class Solver(Section):
    """The solver of the step problems."""

    method: Literal[tuple(SOLVERS)] = Field(  # type: ignore[valid-type]
        library_default(SolverOptions, "method"),
        description="'newton': semismooth Newton condensed onto the contact dofs; "
        "'newton-full': on all dofs; 'uzawa': the paper's Uzawa iteration",
    )
    tol: float = Field(
        library_default(SolverOptions, "tol"),
        description="bound on the scaled KKT residuals of every step, > 0",
    )
    max_iter: int | None = Field(
        None, description="iteration limit per time level, >= 1 (default: the method's own)"
    )
    backend: Literal[BACKENDS] = Field(  # type: ignore[valid-type]
        library_default(SolverOptions, "backend"),
        description="sparse direct solver ('auto': PARDISO if pypardiso is installed, else "
        "SciPy; 'petsc': MUMPS over the ranks of an MPI job, docs/mpi.md)",
    )


StoreU: TypeAlias = by_kind(  # type: ignore[valid-type]
    "'all', 'final', an array of times or an integer N >= 1",
    string=Literal["all", "final"],
    array=list[float],
    number=Annotated[int, Field(ge=1)],
)


class Output(Section):
    """What ``vemwear run`` writes besides ``result.npz`` and ``summary.json``."""

    times: list[float] | None = Field(
        None,
        description="times of the contact-profile figure, each a time level "
        "(default: the levels nearest T/4, T/2, 3T/4, T)",
    )
    figures: bool = Field(True, description="write the PNG figures")
    vtk: bool = Field(True, description="write the ParaView time series")
    paraview: Literal["xdmf", "pvd"] = Field(
        "xdmf",
        description="format of the ParaView series: 'xdmf' (solution.xdmf + solution.h5, one "
        "file pair) or 'pvd' (solution.pvd + one .vtu per stored level)",
    )
    store_u: StoreU | None = Field(
        None,
        description="levels whose displacement is stored: 'all', 'final', a list of times "
        "(time levels) or N (every N-th level and the final one); default: the levels of "
        "`times` and the final one",
    )
    every: int = Field(
        1, ge=1, description="keep the contact arrays of every N-th level (and the final one)"
    )
    checkpoint: float = Field(
        60.0,
        ge=0,
        description="seconds between durable checkpoints of a run (0: only when stopped)",
    )


class DisplacementPart(Section):
    """Prescribed displacement components on a part; an omitted component is free."""

    name: str | None = Field(
        None, description="name of the part (default: displacement1, displacement2, ...)"
    )
    on: Selector = Field(title="selector", description="where")
    ux: DispComponent | None = Field(None, description="prescribed u_x")
    uy: DispComponent | None = Field(None, description="prescribed u_y")
    uz: DispComponent | None = Field(None, description="prescribed u_z (3D meshes)")


TimeComponent: TypeAlias = by_kind(  # type: ignore[valid-type]
    "a number or an expression string in t",
    number=float,
    string=expression("t"),
)


class RigidPartTable(Section):
    """A part that moves as one rigid body (the holder of a pin or ball): each component
    of its translation is prescribed (ux, uy, uz) or loaded by a force resultant (force,
    or fx, fy, fz; zero when omitted); its rotation is fixed, or free and loaded by a
    moment."""

    name: str | None = Field(None, description="name of the part (default: rigid1, rigid2, ...)")
    on: Selector = Field(title="selector", description="where")
    force: list[TimeComponent] | None = Field(  # type: ignore[valid-type]
        None,
        min_length=2,
        max_length=3,
        description="resultant [fx, fy] (3D: [fx, fy, fz]) on the part: numbers or expressions "
        "in t",
    )
    fx: TimeComponent | None = Field(None, description="x component of the resultant")
    fy: TimeComponent | None = Field(None, description="y component of the resultant")
    fz: TimeComponent | None = Field(None, description="z component of the resultant (3D)")
    ux: TimeComponent | None = Field(None, description="prescribed x translation of the part")
    uy: TimeComponent | None = Field(None, description="prescribed y translation of the part")
    uz: TimeComponent | None = Field(None, description="prescribed z translation (3D)")
    rotation: Literal["fixed", "free"] | list[Literal["fixed", "free"]] = Field(
        "fixed",
        description="'fixed': the part translates only; 'free': it also turns about the mean "
        "of its vertices; 3D: also one per axis, ['free', 'free', 'fixed'] (tilts, no turn "
        "about z)",
    )
    moment: TimeComponent | list[TimeComponent] | None = Field(  # type: ignore[valid-type]
        None,
        description="moment resultant about the mean of the part's vertices, with rotation = "
        "'free': M_z in 2D, [M_x, M_y, M_z] in 3D (numbers or expressions in t; 0 when omitted)",
    )


class TractionPart(Section):
    """A traction part with its own load."""

    name: str | None = Field(
        None, description="name of the part (default: traction1, traction2, ...)"
    )
    on: Selector = Field(title="selector", description="where")
    f2: TractionLoad = Field(
        description="traction [f2x, f2y] (3D: [f2x, f2y, f2z]) on this part; a table is taken "
        "at the points of the part (along s: the arc length along it; x in 3D)"
    )


def _traction_form(v: Any) -> str | None:
    if isinstance(v, list) and v and all(isinstance(x, dict) and "on" in x for x in v):
        return "tables"
    return "selector"


Tractions: TypeAlias = choice(  # type: ignore[valid-type]
    _traction_form,
    lambda v: "is invalid",
    selector=Selector,
    tables=Annotated[list[TractionPart], Field(title="[[boundary.traction]] tables")],
)


class Boundary(Section):
    """The boundary parts, selected by the midpoints of the boundary edges. Every
    boundary edge belongs to exactly one part."""

    clamped: Selector | None = Field(None, title="selector", description="Gamma_D, where u = 0")
    traction: Tractions | None = Field(
        None,
        title="selector or tables",
        description="Gamma_N with the traction [loads] f2, or [[boundary.traction]] tables "
        "{ name, on, f2 }, each with its own traction",
    )
    contact: Selector | None = Field(
        None, title="selector", description="Gamma_C of the [contact] section"
    )
    free: Selector | None = Field(
        None, title="selector", description="traction-free parts (zero traction)"
    )
    displacement: list[DisplacementPart] | None = Field(
        None,
        title="tables",
        description="[[boundary.displacement]] tables { name, on, ux, uy, uz }: prescribed "
        "displacement components",
    )
    rigid: list[RigidPartTable] | None = Field(
        None,
        title="tables",
        description="[[boundary.rigid]] tables { name, on, force, ux, uy, uz, rotation }: parts "
        "that move as one rigid body, loaded by a resultant or with a prescribed translation",
    )


BoundaryForm: TypeAlias = by_kind(  # type: ignore[valid-type]
    "a table or the string 'file'", table=Boundary, string=Literal["file"]
)


# ---------------------------------------------------------------------------- the file
class ConfigFile(Section):
    """A vemwear configuration file (docs/config.md)."""

    model_config = ConfigDict(title="vemwear configuration")
    title: str | None = Field(
        None, description="name of the run (default: the file name without .toml)"
    )
    mesh: MeshForm = Field(description="a generator and its options, or a file")
    boundary: BoundaryForm | None = Field(
        None,
        description="the boundary parts; with [mesh] file, 'file' or absent means the parts "
        "stored in the file",
    )
    material: Material
    vem: Vem = Vem.model_construct()
    loads: Loads = Loads.model_construct()
    contact: by_kind(  # type: ignore[valid-type]
        "a table [contact] or [[contact]] tables",
        table=Contact,
        array=Annotated[list[Contact], Field(min_length=1)],
    ) = Field(description="one contact part [contact], or several [[contact]] tables with 'on'")
    time: TimeForm = Field(description="exactly one of steps, dt, pattern, levels")
    solver: Solver = Solver.model_construct()
    output: Output = Output.model_construct()
    adapt: Adapt | None = Field(
        None,
        description="adaptive meshes in time: the estimator, the marking and when the mesh "
        "changes (absent: the mesh stays)",
    )

    @classmethod
    def _unknown(cls, key: str, names: list[str], data: dict[str, Any]) -> str:
        close = difflib.get_close_matches(key, names, n=1, cutoff=0.6)
        sections = [f"[{n}]" for n in names if n != "title"]
        hint = f"; valid sections: {', '.join(sections)}"
        if close:
            hint = f"; did you mean {close[0]!r}?" if close[0] == "title" else ""
            hint = hint or f"; did you mean [{close[0]}]?"
        return f"unknown section or key {key!r}{hint}"

    @model_validator(mode="after")
    def _boundary_parts(self) -> "ConfigFile":
        if not isinstance(self.mesh, MeshFile):
            if self.boundary is None:
                raise error(
                    "missing required section [boundary] (which sides are clamped, traction "
                    "and contact)"
                )
            if self.boundary == "file":
                raise error("boundary = 'file' needs [mesh] file (generated meshes have no tags)")
        return self
