"""Write ``punch.msh``: a rounded punch (a block with a circular bottom) as a gmsh file.

The body is ``-a <= x <= a`` between the arc ``y = R - sqrt(R^2 - x^2)`` (its lowest
point at the origin) and the flat top ``y = H``, meshed by quadrilaterals mapped from a
grid. Its boundary lines are the gmsh physical groups ``top``, ``sides`` and ``arc``,
which ``punch.toml`` uses by name. Run ``python -m vemwear.examples.punch_mesh [nx ny]``
to write it again (the shipped file has 24 x 8 cells).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from vemwear.mesh import Mesh, select_parts, write_mesh

A, R, H = 0.5, 1.0, 0.5


def punch_mesh(nx: int = 24, ny: int = 8) -> Mesh:
    """The punch with its parts ``top``, ``sides`` and ``arc``."""
    x = np.linspace(-A, A, nx + 1)
    y_arc = R - np.sqrt(R**2 - x**2)
    s = np.linspace(0.0, 1.0, ny + 1)
    X = np.repeat(x[None, :], ny + 1, axis=0)
    Y = y_arc[None, :] + (H - y_arc[None, :]) * s[:, None]
    points = np.column_stack([X.ravel(), Y.ravel()])
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    v0 = (j * (nx + 1) + i).ravel()
    cells = np.column_stack([v0, v0 + 1, v0 + nx + 2, v0 + nx + 1])
    mesh = Mesh.from_cells(points, cells)
    return select_parts(
        mesh,
        {
            "top": [((-A, H), (A, H))],
            "sides": [((-A, 0.0), (-A, H)), ((A, 0.0), (A, H))],
            "arc": "rest",
        },
    )


def main(argv: list[str]) -> None:
    nx, ny = (int(argv[0]), int(argv[1])) if len(argv) == 2 else (24, 8)
    path = Path(__file__).with_name("punch.msh")
    write_mesh(punch_mesh(nx, ny), path)
    print(f"wrote {path}")


if __name__ == "__main__":
    main(sys.argv[1:])
