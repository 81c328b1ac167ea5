"""Lowest-order virtual elements: the projection Pi, local matrices, assembly, loads, quadrature."""

from .assembly import body_force_vector, edge_load_vector, stiffness, traction_vector
from .local import STABILIZATIONS, Material, element_matrices, triangle_matrices
from .projection import LinearFields, Projection, project
from .quadrature import cell_means, polygon_moments, polygon_quadrature

__all__ = [
    "STABILIZATIONS",
    "LinearFields",
    "Material",
    "Projection",
    "body_force_vector",
    "cell_means",
    "edge_load_vector",
    "element_matrices",
    "polygon_moments",
    "polygon_quadrature",
    "project",
    "stiffness",
    "traction_vector",
    "triangle_matrices",
]
