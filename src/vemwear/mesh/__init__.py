"""Polygonal meshes: the mesh type, generators, boundary parts, checks and file I/O."""

from .boundary import segment_predicate, side_predicate, tag_rectangle
from .checks import check_mesh
from .generate import rectangle_squares, rectangle_triangles
from .io import read_mesh, write_mesh
from .polymesh import PARTS, Mesh, MeshError, part_code

__all__ = [
    "PARTS",
    "Mesh",
    "MeshError",
    "check_mesh",
    "part_code",
    "read_mesh",
    "rectangle_squares",
    "rectangle_triangles",
    "segment_predicate",
    "side_predicate",
    "tag_rectangle",
    "write_mesh",
]
