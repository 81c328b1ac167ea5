"""What the ``vemwear mesh`` commands do: ``generate``, ``inspect``, ``plot``, ``convert``.

Each ``cmd_*`` function takes the parsed arguments of its subcommand
(:func:`vemwear.cli.mesh_cmd.setup`), prints its one report and returns the exit code;
invalid input is raised (``MeshError``, ``ConfigError``, ``OutputDirError``) for
:mod:`vemwear.cli.main` to report as one line and exit code 2. Mesh files are read and
written by :mod:`.mesh_files`; the work itself is in :mod:`vemwear.mesh` (generation:
:func:`vemwear.mesh.registry.generate_mesh`), imported when a command runs.
"""

from __future__ import annotations

import argparse
import ast
import json
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from ..util.atomic import atomic_file
from .common import EXIT_INPUT, EXIT_OK, PROG, rows_text
from .mesh_files import MESH_SUFFIXES, check_target, load_mesh, refuse_msh3d, save_mesh

__all__ = ["cmd_convert", "cmd_generate", "cmd_inspect", "cmd_plot"]


# ---------------------------------------------------------------------------- generate
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

    refuse_msh3d(out)
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

    out = check_target(Path(args.output), args.force, tuple(MESH_SUFFIXES))
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


# ---------------------------------------------------------------------------- inspect
def _ngons(counts: Mapping[int, int]) -> str:
    return ", ".join(f"{n}-gons {c}" for n, c in counts.items())


def _inspect_report(
    source: str, kind: str, rows: list[tuple[str, str]], s: Mapping[str, Any]
) -> str:
    """The report of ``vemwear mesh inspect``: the verdict, the rows and the quality."""
    head = f"{PROG}: {source}: {'valid' if s['valid'] else 'INVALID'} {kind}"
    text = head + "\n" + rows_text(rows)
    if "_report" in s:
        text += "\n" + str(s["_report"])
    return text


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
    return _inspect_report(source, "mesh", rows, s)


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
    return _inspect_report(source, "3D mesh", rows, s)


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


# ---------------------------------------------------------------------------- plot and convert
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
    out = check_target(Path(args.output), args.force, types)
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
    out = check_target(Path(args.output), args.force, tuple(MESH_SUFFIXES))
    mesh = load_mesh(args.input)
    save_mesh(mesh, out, force=args.force)
    print(f"{PROG}: mesh convert: wrote {out} ({mesh.n_cells} cells, {mesh.n_points} vertices)")
    return EXIT_OK
