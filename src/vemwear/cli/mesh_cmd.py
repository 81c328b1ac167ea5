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

The module is one job, the arguments and output of the four ``mesh`` subcommands;
the work itself is in :mod:`vemwear.mesh` (generation:
:func:`vemwear.mesh.registry.generate_mesh`).
"""

from __future__ import annotations

import argparse
import ast
import contextlib
import io
import json
import os
import sys
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..util.atomic import atomic_file
from .common import (
    EXIT_INPUT,
    EXIT_OK,
    PROG,
    add_debug_option,
    add_subcommand,
    rows_text,
)

if TYPE_CHECKING:
    from ..mesh import Mesh
    from ..mesh.polyhedra import Mesh3D

__all__ = [
    "MESH_SUFFIXES",
    "SUMMARY",
    "load_mesh",
    "save_mesh",
    "setup",
]

#: The one-line summary of ``vemwear mesh``.
SUMMARY = "Generate, inspect, plot and convert polygonal meshes."

#: Mesh file types that ``generate`` and ``convert`` write.
MESH_SUFFIXES: dict[str, str] = {
    ".vtu": "VTK unstructured grid (any polygons)",
    ".msh": "gmsh 2.2 (triangles and quadrilaterals only)",
}


def _parse_param(text: str) -> tuple[str, Any]:
    """``NAME=VALUE`` with a Python literal value (a bare word is a string)."""
    from ..mesh import MeshError

    name, sep, value = text.partition("=")
    name = name.strip()
    if not sep or not name.isidentifier():
        raise MeshError(f"--param {text!r}: expected NAME=VALUE, e.g. amplitude=0.1")
    try:
        return name, ast.literal_eval(value.strip())
    except (ValueError, SyntaxError):
        return name, value.strip()


# ---------------------------------------------------------------------------- reading and writing
@contextlib.contextmanager
def _quiet() -> Iterator[io.StringIO]:
    """Capture what meshio prints (blank lines, its reasons for failing)."""
    chatter = io.StringIO()
    with contextlib.redirect_stdout(chatter), contextlib.redirect_stderr(chatter):
        yield chatter


def load_mesh(path: str | os.PathLike[str], *, check: bool = True) -> Mesh | Mesh3D:
    """The mesh of a mesh file (:func:`vemwear.mesh.read_mesh`, or
    :func:`vemwear.mesh.io3d.read_mesh3d` for a file with volume cells), or the tagged
    mesh of a configuration file (``.toml``, 2D or 3D).

    Raises
    ------
    MeshError
        If the file does not exist, cannot be read as a mesh or (with ``check``) is not
        a valid mesh.
    ConfigError
        If a configuration file is invalid.
    """
    from ..mesh import read_mesh
    from ..mesh.io3d import mesh_file_dim, read_mesh3d

    if Path(path).suffix.lower() == ".toml" and Path(path).is_file():
        from ..config import load_config

        mesh: Mesh | Mesh3D = load_config(path).problem.mesh
        return mesh
    if Path(path).is_file() and mesh_file_dim(path) == 3:
        return read_mesh3d(path, check=check)
    return read_mesh(path, check=check)


def _check_target(path: Path, force: bool, suffixes: Sequence[str] | None) -> Path:
    """Refuse an unknown file type or an existing file (unless ``force``)."""
    from ..runner.outdir import OutputDirError

    if suffixes is not None and path.suffix.lower() not in suffixes:
        kinds = "; ".join(
            f"{s} ({MESH_SUFFIXES[s]})" if s in MESH_SUFFIXES else s for s in suffixes
        )
        raise OutputDirError(
            f"{path}: unknown file type {path.suffix or '(none)'!r}; expected {kinds}"
        )
    if path.is_dir():
        raise OutputDirError(f"{path} is a directory")
    if path.exists() and not force:
        raise OutputDirError(f"{path} exists; use --force to replace it")
    parent = path.parent
    if parent.exists() and not parent.is_dir():
        raise OutputDirError(f"cannot create {path}: {parent} is not a directory")
    return path


def _refuse_msh3d(path: Path) -> None:
    """A 3D mesh is written as ``.vtu`` only."""
    from ..mesh import MeshError

    if path.suffix.lower() != ".vtu":
        raise MeshError(
            f"{path}: writing polyhedral (3D) meshes as {path.suffix or '(no suffix)'} is "
            "not supported; write .vtu instead"
        )


def save_mesh(mesh: Mesh | Mesh3D, path: str | os.PathLike[str], *, force: bool = False) -> Path:
    """Write a mesh as ``.vtu`` or ``.msh``, atomically.

    Parameters
    ----------
    mesh : Mesh or Mesh3D
    path : path
        ``.vtu`` (any polygons) or ``.msh`` (gmsh 2.2; triangles and quadrilaterals
        only); a 3D mesh ``.vtu`` only (VTK polyhedra).
    force : bool
        Replace an existing file.

    Returns
    -------
    Path

    Raises
    ------
    OutputDirError
        Unknown suffix, or the file exists and ``force`` is False.
    MeshError
        A ``.msh`` file for a mesh with cells of more than four vertices, or for a 3D mesh.
    """
    from ..mesh import MeshError, write_mesh
    from ..mesh.io3d import write_mesh3d
    from ..mesh.polyhedra import Mesh3D

    p = _check_target(Path(path), force, tuple(MESH_SUFFIXES))
    if isinstance(mesh, Mesh3D):
        _refuse_msh3d(p)
        with atomic_file(p) as tmp:
            write_mesh3d(mesh, tmp)
        return p
    if p.suffix.lower() == ".msh":
        big = sorted(n for n in mesh.groups if n > 4)
        if big:
            counts = ", ".join(f"{len(mesh.groups[n][0])} {n}-gons" for n in big)
            raise MeshError(
                f"{p}: gmsh files hold triangles and quadrilaterals only, but the "
                f"mesh has {counts}; write .vtu instead"
            )
    with atomic_file(p) as tmp, _quiet():
        write_mesh(mesh, tmp)
    return p


# ---------------------------------------------------------------------------- inspection
def _ngons(counts: Mapping[int, int]) -> str:
    return ", ".join(f"{n}-gons {c}" for n, c in counts.items())


def _inspect_text(source: str, s: Mapping[str, Any]) -> str:
    b = s["boundary_edges"]
    rows = [
        ("points", str(s["points"])),
        ("cells", f"{s['cells']} ({_ngons(s['cells_by_vertices'])})"),
        ("size", f"h = {s['h']:.4g} (largest cell diameter), area {s['area']:.6g}"),
        ("boundary edges", f"{sum(b.values())}: " + ", ".join(f"{k} {v}" for k, v in b.items())),
        ("contact nodes", f"{s['contact_nodes']} (vertices on Gamma_C, not on Gamma_D)"),
        ("hanging nodes", f"{s['hanging_nodes']} (vertices on a straight side of a cell)"),
        (
            "validity",
            "valid (vertices, cells, conformity)" if s["valid"] else f"INVALID: {s['error']}",
        ),
        (
            "boundary parts",
            "complete (every edge tagged, clamped and contact present)"
            if s["boundary_error"] is None
            else f"incomplete: {s['boundary_error']}",
        ),
    ]
    head = f"{PROG}: {source}: {'valid' if s['valid'] else 'INVALID'} mesh"
    text = head + "\n" + rows_text(rows)
    if "_report" in s:
        text += "\n" + str(s["_report"])
    return text


def _numbers(option: str, values: Sequence[float] | None, dim: int, family: str) -> None:
    """``--size`` / ``--divisions`` have ``dim`` entries for a ``dim``-D family."""
    from ..mesh import MeshError

    if values is not None and len(values) != dim:
        names = {"--size": ("LX", "LY", "LZ"), "--divisions": ("NX", "NY", "NZ")}[option]
        raise MeshError(
            f"{option} takes {dim} numbers ({' '.join(names[:dim])}) for the {dim}D family "
            f"{family!r}, got {len(values)}"
        )


def _generate3d(args: argparse.Namespace, out: Path) -> int:
    """``vemwear mesh generate`` of a 3D family: a mesh of a box, written as ``.vtu``."""
    import numpy as np

    from ..mesh import MeshError
    from ..mesh.checks3d import check_mesh3d
    from ..mesh.registry3d import generate_mesh3d

    _refuse_msh3d(out)
    _numbers("--size", args.size, 3, args.family)
    _numbers("--divisions", args.divisions, 3, args.family)
    if args.refine_contact:
        raise MeshError(f"--refine-contact applies to 2D families only, not {args.family!r}")
    params = dict(_parse_param(t) for t in args.param or ())
    mesh = generate_mesh3d(
        args.family,
        size=(2.0, 1.0, 1.0) if args.size is None else args.size,
        cells=args.cells,
        divisions=args.divisions,
        seed=args.seed,
        params=params,
    )
    if args.boundary == "none":
        mesh = mesh.with_tags(np.zeros_like(mesh.boundary_tags))
    check_mesh3d(mesh)
    save_mesh(mesh, out, force=args.force)
    nf = np.diff(mesh.cell_offsets)
    kinds, ncells = np.unique(nf, return_counts=True)
    counts = ", ".join(f"{n} faces {c}" for n, c in zip(kinds, ncells, strict=True))
    parts = ", ".join(f"{p} {n}" for p, n in mesh.part_counts().items() if n) or "untagged"
    print(
        f"{PROG}: mesh generate {args.family}: wrote {out}\n"
        f"  {mesh.n_cells} cells ({counts}), {mesh.n_faces} faces, {mesh.n_points} vertices, "
        f"h = {float(np.max(mesh.cell_diameters)):.4g}; boundary faces: {parts}"
    )
    return EXIT_OK


def cmd_generate(args: argparse.Namespace) -> int:
    """``vemwear mesh generate FAMILY -o FILE``."""
    import numpy as np

    from ..mesh.checks import check_cells, check_conforming, check_vertices
    from ..mesh.quality import hanging_nodes
    from ..mesh.registry import generate_mesh
    from ..mesh.registry3d import FAMILIES_3D

    out = _check_target(Path(args.output), args.force, tuple(MESH_SUFFIXES))
    if args.family in FAMILIES_3D:
        return _generate3d(args, out)
    _numbers("--size", args.size, 2, args.family)
    _numbers("--divisions", args.divisions, 2, args.family)
    params = dict(_parse_param(t) for t in args.param or ())
    mesh = generate_mesh(
        args.family,
        size=(2.0, 1.0) if args.size is None else args.size,
        cells=args.cells,
        divisions=args.divisions,
        seed=args.seed,
        params=params,
        refine_contact=args.refine_contact,
        boundary=args.boundary,
    )
    for check in (check_vertices, check_cells, check_conforming):
        check(mesh)
    save_mesh(mesh, out, force=args.force)
    tags = mesh.boundary_tags
    parts = ", ".join(f"{p} {n}" for p, n in mesh.part_counts().items())
    counts = _ngons({n: len(i) for n, (i, _v) in sorted(mesh.groups.items())})
    print(
        f"{PROG}: mesh generate {args.family}: wrote {out}\n"
        f"  {mesh.n_cells} cells ({counts}), {mesh.n_points} vertices, h = {mesh.h:.4g}; "
        f"boundary edges: {parts if np.any(tags) else 'untagged'}; "
        f"hanging nodes {len(hanging_nodes(mesh))}"
    )
    return EXIT_OK


def _inspect_text3d(source: str, s: Mapping[str, Any]) -> str:
    b = s["boundary_faces"]
    by_faces = ", ".join(f"{n} faces {c}" for n, c in s["cells_by_faces"].items())
    rows = [
        ("points", str(s["points"])),
        ("faces", str(s["faces"])),
        ("cells", f"{s['cells']} ({by_faces})"),
        ("size", f"h = {s['h']:.4g} (largest cell diameter), volume {s['volume']:.6g}"),
        ("boundary faces", f"{sum(b.values())}: " + ", ".join(f"{k} {v}" for k, v in b.items())),
        (
            "validity",
            "valid (vertices, faces, cells, conformity)"
            if s["valid"]
            else f"INVALID: {s['error']}",
        ),
        (
            "boundary parts",
            "complete (every boundary face tagged)"
            if s["boundary_error"] is None
            else f"incomplete: {s['boundary_error']}",
        ),
    ]
    head = f"{PROG}: {source}: {'valid' if s['valid'] else 'INVALID'} 3D mesh"
    text = head + "\n" + rows_text(rows)
    if "_report" in s:
        text += "\n" + str(s["_report"])
    return text


def cmd_inspect(args: argparse.Namespace) -> int:
    """``vemwear mesh inspect FILE_OR_CONFIG``: counts, validity, A1 quality."""
    from ..mesh import mesh_summary
    from ..mesh.polyhedra import Mesh3D
    from ..mesh.summary3d import mesh_summary3d

    mesh = load_mesh(args.file, check=False)  # the summary says what is wrong
    three = isinstance(mesh, Mesh3D)
    s = mesh_summary3d(mesh) if isinstance(mesh, Mesh3D) else mesh_summary(mesh)
    if args.json:
        print(json.dumps({k: v for k, v in s.items() if not k.startswith("_")}, indent=2))
    else:
        print(_inspect_text3d(args.file, s) if three else _inspect_text(args.file, s))
    if not s["valid"]:
        print(
            f"{PROG}: error: {args.file}: invalid mesh: {s['error']}", file=sys.stderr, flush=True
        )
        return EXIT_INPUT
    return EXIT_OK


def cmd_plot(args: argparse.Namespace) -> int:
    """``vemwear mesh plot FILE -o PNG [--quality]``."""
    import numpy as np
    from matplotlib.figure import Figure

    from ..mesh import MeshError
    from ..mesh.checks import check_cells
    from ..mesh.plot import plot_mesh
    from ..mesh.plot3d import plot_mesh3d
    from ..mesh.polyhedra import Mesh3D

    types = tuple(f".{s}" for s in Figure().canvas.get_supported_filetypes())
    out = _check_target(Path(args.output), args.force, types)
    mesh = load_mesh(args.file, check=False)  # an invalid mesh is drawn as it is
    if isinstance(mesh, Mesh3D):
        if args.quality:
            raise MeshError(
                f"{args.file}: --quality is for 2D meshes; for a 3D mesh see "
                f"`{PROG} mesh inspect` or open the .vtu file in ParaView"
            )
        try:
            fig = plot_mesh3d(
                mesh,
                title=f"{Path(args.file).name}: {mesh.n_cells} cells, "
                f"{mesh.n_points} vertices, h = {float(np.max(mesh.cell_diameters)):.3g}",
            )
        except ValueError as exc:
            raise MeshError(f"{args.file}: {exc}") from None
        with atomic_file(out) as tmp:
            fig.savefig(tmp, dpi=150, format=out.suffix[1:].lower())
        print(f"{PROG}: mesh plot: wrote {out}")
        return EXIT_OK
    if args.quality:
        check_cells(mesh)  # the kernel disks need counter-clockwise simple cells
    fig = plot_mesh(
        mesh,
        quality=args.quality,
        title=f"{Path(args.file).name}: "
        f"{mesh.n_cells} cells, {mesh.n_points} vertices, h = {mesh.h:.3g}",
    )
    with atomic_file(out) as tmp:
        fig.savefig(tmp, dpi=150, format=out.suffix[1:].lower())
    print(f"{PROG}: mesh plot: wrote {out}")
    return EXIT_OK


def cmd_convert(args: argparse.Namespace) -> int:
    """``vemwear mesh convert IN OUT``."""
    from ..runner.outdir import OutputDirError

    if Path(args.output).resolve() == Path(args.input).resolve():
        raise OutputDirError(f"{args.output}: input and output are the same file")
    out = _check_target(Path(args.output), args.force, tuple(MESH_SUFFIXES))
    mesh = load_mesh(args.input)
    save_mesh(mesh, out, force=args.force)
    print(f"{PROG}: mesh convert: wrote {out} ({mesh.n_cells} cells, {mesh.n_points} vertices)")
    return EXIT_OK


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
