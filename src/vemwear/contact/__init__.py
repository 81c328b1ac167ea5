"""The contact part: nodal quadrature on Gamma_C, compliance laws, coefficients, v*(t)."""

from .boundary import ContactBoundary, arc_length, contact_boundary
from .boundary3d import contact_boundary3d, velocity_line
from .data import FoundationVelocity, NodalField, nodal_values, table_values
from .law import (
    CallableCompliance,
    ComplianceLaw,
    LinearCompliance,
    TableCompliance,
    as_law,
    check_law,
)
from .parts import ContactPart, NodalLaw, tangential_velocity, velocity_levels

__all__ = [
    "CallableCompliance",
    "ComplianceLaw",
    "ContactBoundary",
    "ContactPart",
    "FoundationVelocity",
    "LinearCompliance",
    "NodalField",
    "NodalLaw",
    "TableCompliance",
    "arc_length",
    "as_law",
    "check_law",
    "contact_boundary",
    "contact_boundary3d",
    "nodal_values",
    "table_values",
    "tangential_velocity",
    "velocity_levels",
    "velocity_line",
]
