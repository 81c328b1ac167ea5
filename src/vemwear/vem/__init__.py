"""Lowest-order virtual elements: projection, local matrices, assembly, loads."""

from .assembly import (
    body_force_vector,
    cell_means,
    edge_load_vector,
    projection_coefficients,
    stiffness,
    traction_vector,
)
from .local import STABILIZATIONS, Material, element_matrices

__all__ = [
    "STABILIZATIONS",
    "Material",
    "body_force_vector",
    "cell_means",
    "edge_load_vector",
    "element_matrices",
    "projection_coefficients",
    "stiffness",
    "traction_vector",
]
