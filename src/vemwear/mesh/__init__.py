"""Polygonal meshes: the mesh type, generators, boundary parts, checks, file I/O and point
location."""

from .boundary import segment_predicate, select_parts, side_predicate, tag_rectangle
from .checks import check_mesh
from .curves import BoundaryCurve
from .families import (
    distorted_quads,
    hexagons,
    nonconvex_mesh,
    perturb_vertices,
    rectangle_voronoi,
    squares_with_hanging_nodes,
)
from .generate import rectangle_squares, rectangle_triangles
from .io import read_mesh, write_mesh
from .locate import NonNestedMeshError, locate_cells, match_vertices, nested_cells
from .polymesh import PARTS, Mesh, MeshError, part_code
from .quality import QualityReport, kernel_disks, quality_report
from .refine import refine_along, refine_cells, refine_where
from .summary import contact_nodes, mesh_summary
from .voronoi import (
    l_shape_domain,
    point_in_domain,
    rectangle_domain,
    voronoi_from_seeds,
    voronoi_mesh,
)

__all__ = [
    "PARTS",
    "BoundaryCurve",
    "Mesh",
    "MeshError",
    "NonNestedMeshError",
    "QualityReport",
    "check_mesh",
    "contact_nodes",
    "distorted_quads",
    "hexagons",
    "kernel_disks",
    "l_shape_domain",
    "locate_cells",
    "match_vertices",
    "mesh_summary",
    "nested_cells",
    "nonconvex_mesh",
    "part_code",
    "perturb_vertices",
    "point_in_domain",
    "quality_report",
    "read_mesh",
    "rectangle_domain",
    "rectangle_squares",
    "rectangle_triangles",
    "rectangle_voronoi",
    "refine_along",
    "refine_cells",
    "refine_where",
    "segment_predicate",
    "select_parts",
    "side_predicate",
    "squares_with_hanging_nodes",
    "tag_rectangle",
    "voronoi_from_seeds",
    "voronoi_mesh",
    "write_mesh",
]
