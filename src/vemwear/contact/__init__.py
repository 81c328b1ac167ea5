"""The contact part: nodal quadrature on Gamma_C, compliance laws, coefficients, v*(t)."""

from .boundary import ContactBoundary, contact_boundary
from .data import FoundationVelocity, NodalField, nodal_values
from .law import (
    CallableCompliance,
    ComplianceLaw,
    LinearCompliance,
    TableCompliance,
    as_law,
    check_law,
)
from .parts import ContactPart, NodalLaw, tangential_velocity

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
    "as_law",
    "check_law",
    "contact_boundary",
    "nodal_values",
    "tangential_velocity",
]
