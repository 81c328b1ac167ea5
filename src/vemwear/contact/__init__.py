"""The contact part: nodal quadrature on Gamma_C, compliance laws, coefficients, v*(t)."""

from .boundary import ContactBoundary, arc_length, contact_boundary
from .boundary3d import contact_boundary3d, foundation_rows, sliding_lines, velocity_line
from .data import FoundationVelocity, NodalField, RotatingFoundation, nodal_values, table_values
from .law import (
    CallableCompliance,
    ComplianceLaw,
    LinearCompliance,
    TableCompliance,
    as_law,
    check_law,
)
from .parts import (
    PRESSURES,
    ContactPart,
    NodalLaw,
    nodal_velocity,
    tangential_components,
    tangential_velocity,
    velocity_levels,
)

__all__ = [
    "PRESSURES",
    "CallableCompliance",
    "ComplianceLaw",
    "ContactBoundary",
    "ContactPart",
    "FoundationVelocity",
    "LinearCompliance",
    "NodalField",
    "NodalLaw",
    "RotatingFoundation",
    "TableCompliance",
    "arc_length",
    "as_law",
    "check_law",
    "contact_boundary",
    "contact_boundary3d",
    "foundation_rows",
    "nodal_values",
    "nodal_velocity",
    "sliding_lines",
    "table_values",
    "tangential_components",
    "tangential_velocity",
    "velocity_levels",
    "velocity_line",
]
