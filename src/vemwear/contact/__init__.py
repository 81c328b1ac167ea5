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

__all__ = [
    "CallableCompliance",
    "ComplianceLaw",
    "ContactBoundary",
    "FoundationVelocity",
    "LinearCompliance",
    "NodalField",
    "TableCompliance",
    "as_law",
    "check_law",
    "contact_boundary",
    "nodal_values",
]
