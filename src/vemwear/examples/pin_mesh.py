"""Write ``pin.vtu``: a cylindrical pin of Voronoi prisms, for ``pin_on_disc.toml``.

The pin's cross-section is a disc of radius 0.25 (a regular 32-gon) meshed by
centroidal Voronoi polygons, extruded in layers to the height 0.5. Its faces are the
parts ``face`` (z = 0, on the disc), ``holder`` (z = 0.5) and ``side``. Run
``python -m vemwear.examples.pin_mesh [n_cells layers]`` to write it again (the shipped
file has 96 cells in 4 layers).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from vemwear.mesh.boundary3d import select_parts3d
from vemwear.mesh.generate3d import extrude
from vemwear.mesh.io3d import write_mesh3d
from vemwear.mesh.polyhedra import Mesh3D
from vemwear.mesh.polymesh import Mesh
from vemwear.mesh.voronoi import voronoi_mesh

RADIUS, HEIGHT, CORNERS = 0.25, 0.5, 32


def pin_mesh(n_cells: int = 96, layers: int = 4) -> Mesh3D:
    """The pin with its parts ``face``, ``holder`` and ``side``."""
    angle = 2 * np.pi * np.arange(CORNERS) / CORNERS
    disc = RADIUS * np.column_stack([np.cos(angle), np.sin(angle)])
    section = voronoi_mesh(disc, n_cells, seed=0)
    assert isinstance(section, Mesh)
    mesh = extrude(section, layers, HEIGHT, bottom="face", top="holder")
    return select_parts3d(mesh, {"face": "face", "holder": "holder", "side": "rest"})


def main(argv: list[str]) -> None:
    n_cells, layers = (int(a) for a in argv) if argv else (96, 4)
    out = Path(__file__).with_name("pin.vtu")
    write_mesh3d(pin_mesh(n_cells, layers), out)
    print(f"wrote {out}")


if __name__ == "__main__":
    main(sys.argv[1:])
