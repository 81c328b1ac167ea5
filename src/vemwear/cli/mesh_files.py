"""Reading and writing the mesh files of the ``vemwear mesh`` commands.

:func:`load_mesh` reads a mesh file (2D or 3D) or builds the tagged mesh of a
configuration file (``.toml``); :func:`save_mesh` writes a mesh as ``.vtu`` or ``.msh``
atomically (through a temporary file in the same directory), replacing an existing file
only with ``force``; :func:`check_target` refuses an unknown file type or an existing
file before any work is done. The library is imported when a function runs.
"""

from __future__ import annotations

import contextlib
import io
import os
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from ..util.atomic import atomic_file

if TYPE_CHECKING:
    from ..mesh import Mesh
    from ..mesh.polyhedra import Mesh3D

__all__ = [
    "MESH_SUFFIXES",
    "check_target",
    "load_mesh",
    "refuse_msh3d",
    "save_mesh",
]

#: Mesh file types that ``generate`` and ``convert`` write.
MESH_SUFFIXES: dict[str, str] = {
    ".vtu": "VTK unstructured grid (any polygons)",
    ".msh": "gmsh 2.2 (triangles and quadrilaterals only)",
}


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


def check_target(path: Path, force: bool, suffixes: Sequence[str] | None) -> Path:
    """Refuse an unknown file type or an existing file (unless ``force``).

    Parameters
    ----------
    path : Path
        The output file.
    force : bool
        An existing file may be replaced.
    suffixes : sequence of str or None
        The file types allowed (lower case, with the dot); None: any.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    OutputDirError
        Unknown suffix, ``path`` is a directory or its parent is not one, or the file
        exists and ``force`` is False.
    """
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


def refuse_msh3d(path: Path) -> None:
    """A 3D mesh is written as ``.vtu`` only.

    Raises
    ------
    MeshError
        If ``path`` is not a ``.vtu`` file.
    """
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

    p = check_target(Path(path), force, tuple(MESH_SUFFIXES))
    if isinstance(mesh, Mesh3D):
        refuse_msh3d(p)
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
