"""The ``vemwear mesh`` commands: ``generate``, ``inspect``, ``plot`` and ``convert``.

``vemwear mesh generate FAMILY -o FILE``
    Build a mesh of a rectangle from one of the families of
    :data:`vemwear.mesh.registry.FAMILIES`, tag the paper's boundary parts (clamped left
    side, traction top and right sides, contact bottom side), optionally refine it along the
    contact part (hanging nodes) and write it as ``.vtu`` (any polygons) or ``.msh``
    (gmsh 2.2: triangles and quadrilaterals only). A 3D family of
    :data:`vemwear.mesh.registry3d.FAMILIES_3D` builds a mesh of a box whose six sides are
    the parts ``xmin`` ... ``zmax`` (:func:`vemwear.mesh.registry3d.generate_mesh3d`),
    written as ``.vtu`` (VTK polyhedra) only.
``vemwear mesh inspect FILE_OR_CONFIG``
    Counts (points, cells by vertex count, boundary edges per part, contact and
    hanging nodes), validity (:func:`vemwear.mesh.check_mesh`) and the quality
    report of assumption A1 (:func:`vemwear.mesh.quality_report`). For a 3D mesh:
    points, faces, cells by face count, boundary faces per part,
    :func:`vemwear.mesh.checks3d.check_mesh3d` and
    :func:`vemwear.mesh.quality3d.quality_report3d`.
``vemwear mesh plot FILE_OR_CONFIG -o PNG [--quality]``
    The mesh with its boundary parts coloured, optionally every cell coloured by
    ``rho_K / h_K``. A 3D mesh: its boundary faces in a 3D view coloured by part
    (:func:`vemwear.mesh.plot3d.plot_mesh3d`; no ``--quality``; refused for very large
    meshes, for which ParaView on the ``.vtu`` file is the tool).
``vemwear mesh convert IN OUT``
    Read a mesh (or build the mesh of a configuration file) and write it in
    another format (a 3D mesh: ``.vtu`` only).

Wherever a mesh is read, a ``.toml`` path is a configuration file (``docs/config.md``)
whose ``[mesh]`` and ``[boundary]`` sections give the tagged mesh. Output files are
written atomically (through a temporary file in the same directory) and an existing
file is replaced only with ``--force``. Invalid input is reported as one line and
exit code 2, as for the other commands (:mod:`vemwear.cli.main`).

The module is one job, the parser of the four ``mesh`` subcommands (their arguments and
help); what they do is in :mod:`.mesh_actions`, the reading and writing of mesh files in
:mod:`.mesh_files`, the work itself in :mod:`vemwear.mesh` (generation:
:func:`vemwear.mesh.registry.generate_mesh`).
"""

from __future__ import annotations

import argparse

from .common import add_debug_option, add_subcommand
from .mesh_actions import cmd_convert, cmd_generate, cmd_inspect, cmd_plot

__all__ = ["SUMMARY", "setup"]

#: The one-line summary of ``vemwear mesh``.
SUMMARY = "Generate, inspect, plot and convert polygonal meshes."


# ---------------------------------------------------------------------------- parser
def _family_listing() -> str:
    from ..mesh.registry import FAMILIES
    from ..mesh.registry3d import FAMILIES_3D

    return (
        "2D families (a rectangle):\n"
        + "\n".join(f"  {f.name:<11}{f.description}" for f in FAMILIES.values())
        + "\n3D families (a box, sides tagged xmin ... zmax; .vtu only):\n"
        + "\n".join(f"  {f.name:<11}{f.description}" for f in FAMILIES_3D.values())
    )


def setup(mesh_p: argparse.ArgumentParser) -> None:
    """Fill in the parser of ``vemwear mesh`` with its subcommands.

    Parameters
    ----------
    mesh_p : argparse.ArgumentParser
        The ``mesh`` parser made by :func:`vemwear.cli.main.build_parser`.
    """
    from ..mesh.registry import FAMILIES
    from ..mesh.registry3d import FAMILIES_3D

    families = [*FAMILIES, *FAMILIES_3D]
    msub = mesh_p.add_subparsers(dest="mesh_command", metavar="SUBCOMMAND", title="subcommands")
    msub.required = True

    d = (
        "Generate a mesh of a rectangle, tag the paper's boundary parts (clamped left, "
        "traction top and right, contact bottom) and write it as .vtu or .msh; or, with a "
        "3D family, a mesh of a box with its sides tagged xmin ... zmax, written as .vtu."
    )
    p = add_subcommand(msub, "generate", d, d + "\n\n" + _family_listing())
    p.add_argument(
        "family",
        metavar="FAMILY",
        choices=families,
        help="mesh family: " + ", ".join(families),
    )
    p.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="FILE",
        help="output file: .vtu (any polygons or polyhedra) or .msh (gmsh 2.2, 2D "
        "triangles and quadrilaterals only)",
    )
    p.add_argument(
        "--size",
        nargs="+",
        type=float,
        metavar="L",
        help="side lengths LX LY of the rectangle [0, LX] x [0, LY] (default: 2 1), or "
        "LX LY LZ of the box of a 3D family (default: 2 1 1)",
    )
    g = p.add_mutually_exclusive_group()
    g.add_argument(
        "--cells",
        type=int,
        metavar="N",
        help="number of cells: exact for voronoi and voronoi3d; for squares, triangles, "
        "distorted, nonconvex, hexahedra and tetrahedra the grid closest to square "
        "(cubic) cells; for prisms the cells of the extruded 2D mesh",
    )
    g.add_argument(
        "--divisions",
        nargs="+",
        type=int,
        metavar="N",
        help="grid divisions NX NY (3D: NX NY NZ; not for voronoi, voronoi3d, prisms); "
        "default: the family's own",
    )
    p.add_argument(
        "--seed",
        type=int,
        metavar="S",
        help="random seed (voronoi, distorted, hanging with pattern=random, voronoi3d, prisms)",
    )
    p.add_argument(
        "--param",
        action="append",
        metavar="NAME=VALUE",
        help="further argument of the generator, repeatable, e.g. amplitude=0.1 "
        "(distorted), pattern=random (hanging), diagonal=alternate "
        "(triangles), depth=0.3 (nonconvex), lloyd_iterations=10 (voronoi), "
        "layers=4 (prisms)",
    )
    p.add_argument(
        "--refine-contact",
        type=int,
        default=0,
        metavar="LEVELS",
        help="refine the cells along the contact part LEVELS times (hanging nodes; 2D "
        "only; default 0)",
    )
    p.add_argument(
        "--boundary",
        choices=("paper", "none"),
        default="paper",
        help="boundary parts: paper (default: clamped left, traction top and "
        "right, contact bottom; 3D: the six sides xmin ... zmax) or none (untagged)",
    )
    p.add_argument("--force", action="store_true", help="replace an existing FILE")
    add_debug_option(p)
    p.set_defaults(func=cmd_generate)

    d = (
        "Show the counts (points, cells by vertex count, boundary edges per part, contact "
        "and hanging nodes), the validity and the quality (assumption A1) of a mesh. "
        "Exit code 2 if the mesh is invalid."
    )
    p = add_subcommand(msub, "inspect", d)
    p.add_argument(
        "file",
        metavar="FILE_OR_CONFIG",
        help="mesh file (.vtu, .msh, ...) or configuration file (.toml)",
    )
    p.add_argument("--json", action="store_true", help="print the numbers as JSON")
    add_debug_option(p)
    p.set_defaults(func=cmd_inspect)

    d = (
        "Draw a mesh with its boundary parts coloured and hanging nodes marked; with "
        "--quality, every cell coloured by rho_K / h_K (assumption A1). A 3D mesh: its "
        "boundary faces coloured by part (no --quality; large meshes: use ParaView)."
    )
    p = add_subcommand(msub, "plot", d)
    p.add_argument(
        "file",
        metavar="FILE_OR_CONFIG",
        help="mesh file (.vtu, .msh, ...) or configuration file (.toml)",
    )
    p.add_argument(
        "-o", "--output", required=True, metavar="PNG", help="image file (.png, .pdf, .svg, ...)"
    )
    p.add_argument("--quality", action="store_true", help="colour cells by rho_K / h_K")
    p.add_argument("--force", action="store_true", help="replace an existing image")
    add_debug_option(p)
    p.set_defaults(func=cmd_plot)

    d = (
        "Read a mesh (or build the mesh of a configuration file) and write it as .vtu or "
        ".msh (3D meshes: .vtu only)."
    )
    p = add_subcommand(msub, "convert", d)
    p.add_argument("input", metavar="IN", help="mesh file or configuration file (.toml)")
    p.add_argument("output", metavar="OUT", help="output file: .vtu or .msh (2D only)")
    p.add_argument("--force", action="store_true", help="replace an existing OUT")
    add_debug_option(p)
    p.set_defaults(func=cmd_convert)
