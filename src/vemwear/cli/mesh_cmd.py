"""The ``vemwear mesh`` commands: ``generate``, ``inspect``, ``plot`` and ``convert``.

``vemwear mesh generate FAMILY -o FILE``
    Build a mesh of a rectangle from one of the families of
    :data:`vemwear.mesh.registry.FAMILIES`, tag the paper's boundary parts (clamped left
    side, traction top and right sides, contact bottom side), optionally refine it along the
    contact part (hanging nodes) and write it as ``.vtu`` (any polygons) or ``.msh``
    (gmsh 2.2: triangles and quadrilaterals only).
``vemwear mesh inspect FILE_OR_CONFIG``
    Counts (points, cells by vertex count, boundary edges per part, contact and
    hanging nodes), validity (:func:`vemwear.mesh.check_mesh`) and the quality
    report of assumption A1 (:func:`vemwear.mesh.quality_report`).
``vemwear mesh plot FILE_OR_CONFIG -o PNG [--quality]``
    The mesh with its boundary parts coloured, optionally every cell coloured by
    ``rho_K / h_K``.
``vemwear mesh convert IN OUT``
    Read a mesh (or build the mesh of a configuration file) and write it in
    another format.

Wherever a mesh is read, a ``.toml`` path is a configuration file (``docs/config.md``)
whose ``[mesh]`` and ``[boundary]`` sections give the tagged mesh. Output files are
written atomically (through a temporary file in the same directory) and an existing
file is replaced only with ``--force``. Invalid input is reported as one line and
exit code 2, as for the other commands (:mod:`vemwear.cli.main`).

The module is one job, the arguments and output of the four ``mesh`` subcommands;
the work itself is in :mod:`vemwear.mesh`.
"""

from __future__ import annotations

import argparse
import ast
import contextlib
import io
import json
import math
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

__all__ = [
    "MESH_SUFFIXES",
    "SUMMARY",
    "generate_mesh",
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


# ---------------------------------------------------------------------------- families
def _divisions_for(n: int, per: int, size: tuple[float, float], family: str) -> tuple[int, int]:
    """Grid ``(nx, ny)`` with ``per * nx * ny == n`` whose rectangles are closest to squares."""
    from ..mesh import MeshError

    if n < 1 or n % per:
        raise MeshError(
            f"--cells {n}: family {family!r} has {per} cells per grid rectangle, "
            f"so the count must be a positive multiple of {per}"
        )
    m = n // per
    lx, ly = size
    small = [d for d in range(1, math.isqrt(m) + 1) if m % d == 0]
    best = min(
        {*small, *(m // d for d in small)},
        key=lambda nx: abs(math.log((lx / nx) / (ly / (m // nx)))),
    )
    nx, ny = best, m // best
    ratio = max((lx / nx) / (ly / ny), (ly / ny) / (lx / nx))
    if ratio > 2.0 + 1e-12:
        raise MeshError(
            f"--cells {n}: the closest grid for family {family!r} on a {lx:g} x {ly:g} "
            f"rectangle is {nx} x {ny}, whose cells have aspect ratio {ratio:.3g} > 2; "
            "choose another count or give --divisions NX NY"
        )
    return nx, ny


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


def generate_mesh(
    family: str,
    *,
    size: Sequence[float] = (2.0, 1.0),
    cells: int | None = None,
    divisions: Sequence[int] | None = None,
    seed: int | None = None,
    params: Mapping[str, Any] | None = None,
    refine_contact: int = 0,
    boundary: str = "paper",
) -> Mesh:
    """Generate a mesh of the rectangle ``[0, lx] x [0, ly]`` of a mesh family.

    Parameters
    ----------
    family : str
        A key of :data:`vemwear.mesh.registry.FAMILIES`.
    size : (lx, ly)
        Side lengths (default: the paper's ``(2, 1)``).
    cells : int, optional
        Number of cells: exact for ``voronoi``; for grid families (squares, triangles,
        distorted, nonconvex) the grid with that many cells whose rectangles are
        closest to squares (aspect ratio at most 2).
    divisions : (nx, ny), optional
        Grid divisions (not for ``voronoi``). Without ``cells`` and ``divisions``
        the generator's defaults apply.
    seed : int, optional
        Random seed (``voronoi``, ``distorted``, ``hanging`` with
        ``params={"pattern": "random"}``).
    params : mapping, optional
        Further keyword arguments of the generator (e.g. ``amplitude`` of
        ``distorted``, ``pattern`` of ``hanging``, ``diagonal`` of ``triangles``).
    refine_contact : int
        Refine the cells along the contact part this many times
        (:func:`vemwear.mesh.refine_along`; needs ``boundary="paper"``).
    boundary : {"paper", "none"}
        ``paper``: clamped = left, traction = top and right, contact = bottom
        (paper Section 5, :func:`vemwear.mesh.tag_rectangle`); ``none``: untagged.

    Returns
    -------
    Mesh

    Raises
    ------
    MeshError
        For an unknown family, arguments the family does not take, or a generator
        that rejects its arguments (the message says which).
    """
    from ..mesh import MeshError, refine_along, tag_rectangle
    from ..mesh.registry import FAMILIES

    if family not in FAMILIES:
        raise MeshError(f"unknown mesh family {family!r}; available: {', '.join(FAMILIES)}")
    fam = FAMILIES[family]
    takes = {o.name for o in fam.options}
    if boundary not in ("paper", "none"):
        raise MeshError(f"--boundary must be 'paper' or 'none', got {boundary!r}")
    lx, ly = (float(s) for s in size)
    if not (lx > 0 and ly > 0 and math.isfinite(lx) and math.isfinite(ly)):
        raise MeshError(f"--size must be two positive numbers, got {lx:g} {ly:g}")
    if refine_contact < 0:
        raise MeshError(f"--refine-contact must be >= 0, got {refine_contact}")
    if refine_contact and boundary != "paper":
        raise MeshError("--refine-contact needs the boundary parts (--boundary paper)")
    kwargs: dict[str, Any] = {"size": (lx, ly)}
    if cells is not None and divisions is not None:
        raise MeshError("give either --cells or --divisions, not both")
    if cells is not None:
        if "n_cells" in takes:
            if cells < 1:
                raise MeshError(f"--cells must be >= 1, got {cells}")
            kwargs["n_cells"] = int(cells)
        elif fam.cells_per_division:
            kwargs["divisions"] = _divisions_for(
                int(cells), fam.cells_per_division, (lx, ly), family
            )
        else:
            raise MeshError(
                f"family {family!r} does not take --cells (its cell count "
                "follows from the divisions); give --divisions NX NY"
            )
    if divisions is not None:
        if "divisions" not in takes:
            raise MeshError(f"family {family!r} does not take --divisions; give --cells N")
        nx, ny = (int(d) for d in divisions)
        if nx < 1 or ny < 1:
            raise MeshError(f"--divisions must be positive integers, got {nx} {ny}")
        kwargs["divisions"] = (nx, ny)
    if seed is not None:
        if "seed" not in takes:
            raise MeshError(f"family {family!r} is deterministic: --seed does not apply")
        kwargs["seed"] = int(seed)
    for key, value in (params or {}).items():
        if key in ("n_cells", "divisions", "seed", "size"):
            raise MeshError(f"--param {key}: use the option --{key.replace('n_', '')} instead")
        kwargs[key] = value
    try:
        mesh = fam.generate(**kwargs)
    except (TypeError, ValueError) as exc:
        msg = str(exc)
        raise MeshError(
            f"--param {msg}" if msg.startswith(tuple(params or ())) else f"family {family!r}: {msg}"
        ) from exc
    if boundary == "paper":
        mesh = tag_rectangle(mesh)
    if refine_contact:
        mesh = refine_along(mesh, "contact", int(refine_contact))
    return mesh


# ---------------------------------------------------------------------------- reading and writing
@contextlib.contextmanager
def _quiet() -> Iterator[io.StringIO]:
    """Capture what meshio prints (blank lines, its reasons for failing)."""
    chatter = io.StringIO()
    with contextlib.redirect_stdout(chatter), contextlib.redirect_stderr(chatter):
        yield chatter


def load_mesh(path: str | os.PathLike[str], *, check: bool = True) -> Mesh:
    """The mesh of a mesh file (:func:`vemwear.mesh.read_mesh`), or the tagged mesh of a
    configuration file (``.toml``).

    Raises
    ------
    MeshError
        If the file does not exist, cannot be read as a mesh or (with ``check``) is not
        a valid mesh.
    ConfigError
        If a configuration file is invalid.
    """
    from ..mesh import read_mesh

    if Path(path).suffix.lower() == ".toml" and Path(path).is_file():
        from ..config import load_config

        return load_config(path).problem.mesh
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


def save_mesh(mesh: Mesh, path: str | os.PathLike[str], *, force: bool = False) -> Path:
    """Write a mesh as ``.vtu`` or ``.msh``, atomically.

    Parameters
    ----------
    mesh : Mesh
    path : path
        ``.vtu`` (any polygons) or ``.msh`` (gmsh 2.2; triangles and quadrilaterals
        only).
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
        A ``.msh`` file for a mesh with cells of more than four vertices.
    """
    from ..mesh import MeshError, write_mesh

    p = _check_target(Path(path), force, tuple(MESH_SUFFIXES))
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


def cmd_generate(args: argparse.Namespace) -> int:
    """``vemwear mesh generate FAMILY -o FILE``."""
    import numpy as np

    from ..mesh.checks import check_cells, check_conforming, check_vertices
    from ..mesh.quality import hanging_nodes

    out = _check_target(Path(args.output), args.force, tuple(MESH_SUFFIXES))
    params = dict(_parse_param(t) for t in args.param or ())
    mesh = generate_mesh(
        args.family,
        size=args.size,
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


def cmd_inspect(args: argparse.Namespace) -> int:
    """``vemwear mesh inspect FILE_OR_CONFIG``: counts, validity, A1 quality."""
    from ..mesh import mesh_summary

    mesh = load_mesh(args.file, check=False)  # the summary says what is wrong
    s = mesh_summary(mesh)
    if args.json:
        print(json.dumps({k: v for k, v in s.items() if not k.startswith("_")}, indent=2))
    else:
        print(_inspect_text(args.file, s))
    if not s["valid"]:
        print(
            f"{PROG}: error: {args.file}: invalid mesh: {s['error']}", file=sys.stderr, flush=True
        )
        return EXIT_INPUT
    return EXIT_OK


def cmd_plot(args: argparse.Namespace) -> int:
    """``vemwear mesh plot FILE -o PNG [--quality]``."""
    from matplotlib.figure import Figure

    from ..mesh.checks import check_cells
    from ..mesh.plot import plot_mesh

    types = tuple(f".{s}" for s in Figure().canvas.get_supported_filetypes())
    out = _check_target(Path(args.output), args.force, types)
    mesh = load_mesh(args.file, check=False)  # an invalid mesh is drawn as it is
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

    return "families:\n" + "\n".join(f"  {f.name:<11}{f.description}" for f in FAMILIES.values())


def setup(mesh_p: argparse.ArgumentParser) -> None:
    """Fill in the parser of ``vemwear mesh`` with its subcommands.

    Parameters
    ----------
    mesh_p : argparse.ArgumentParser
        The ``mesh`` parser made by :func:`vemwear.cli.main.build_parser`.
    """
    from ..mesh.registry import FAMILIES

    msub = mesh_p.add_subparsers(dest="mesh_command", metavar="SUBCOMMAND", title="subcommands")
    msub.required = True

    d = (
        "Generate a mesh of a rectangle, tag the paper's boundary parts (clamped left, "
        "traction top and right, contact bottom) and write it as .vtu or .msh."
    )
    p = add_subcommand(msub, "generate", d, d + "\n\n" + _family_listing())
    p.add_argument(
        "family",
        metavar="FAMILY",
        choices=list(FAMILIES),
        help="mesh family: " + ", ".join(FAMILIES),
    )
    p.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="FILE",
        help="output file: .vtu (any polygons) or .msh (gmsh 2.2, triangles and "
        "quadrilaterals only)",
    )
    p.add_argument(
        "--size",
        nargs=2,
        type=float,
        default=(2.0, 1.0),
        metavar=("LX", "LY"),
        help="side lengths of the rectangle [0, LX] x [0, LY] (default: 2 1)",
    )
    g = p.add_mutually_exclusive_group()
    g.add_argument(
        "--cells",
        type=int,
        metavar="N",
        help="number of cells: exact for voronoi; for squares, triangles, "
        "distorted and nonconvex the grid closest to square cells",
    )
    g.add_argument(
        "--divisions",
        nargs=2,
        type=int,
        metavar=("NX", "NY"),
        help="grid divisions (not for voronoi); default: the family's own",
    )
    p.add_argument(
        "--seed",
        type=int,
        metavar="S",
        help="random seed (voronoi, distorted, hanging with pattern=random)",
    )
    p.add_argument(
        "--param",
        action="append",
        metavar="NAME=VALUE",
        help="further argument of the generator, repeatable, e.g. amplitude=0.1 "
        "(distorted), pattern=random (hanging), diagonal=alternate "
        "(triangles), depth=0.3 (nonconvex), lloyd_iterations=10 (voronoi)",
    )
    p.add_argument(
        "--refine-contact",
        type=int,
        default=0,
        metavar="LEVELS",
        help="refine the cells along the contact part LEVELS times (hanging nodes; default 0)",
    )
    p.add_argument(
        "--boundary",
        choices=("paper", "none"),
        default="paper",
        help="boundary parts: paper (default: clamped left, traction top and "
        "right, contact bottom) or none (untagged)",
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
        "--quality, every cell coloured by rho_K / h_K (assumption A1)."
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

    d = "Read a mesh (or build the mesh of a configuration file) and write it as .vtu or .msh."
    p = add_subcommand(msub, "convert", d)
    p.add_argument("input", metavar="IN", help="mesh file or configuration file (.toml)")
    p.add_argument("output", metavar="OUT", help="output file: .vtu or .msh")
    p.add_argument("--force", action="store_true", help="replace an existing OUT")
    add_debug_option(p)
    p.set_defaults(func=cmd_convert)
