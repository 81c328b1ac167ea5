"""The contact arrays of a run as point data of a visualisation mesh (ParaView output
of 2D, k = 2 and 3D runs)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from ..simulate.loop import Result

__all__ = ["contact_point_data"]


def contact_point_data(
    result: Result,
    level: int,
    n: int,
    nodes: NDArray[np.int64],
    keep: NDArray[np.bool_] | slice = slice(None),
) -> dict[str, NDArray[np.float64]]:
    """The contact arrays of a stored level as point data of ``n`` vertices (0 off
    Gamma_C), and the indicator ``contact``; ``keep`` selects the contact nodes that are
    the vertices ``nodes`` (k = 2: not the edge midpoints)."""
    out: dict[str, NDArray[np.float64]] = {}
    for key, arr in (
        ("wear", result.wear),
        ("u_nu", result.u_nu),
        ("penetration", result.penetration),
        ("p_rigid", result.p_rigid),
        ("p_soft", result.p_soft),
    ):
        full = np.zeros(n)
        full[nodes] = np.asarray(arr[level])[keep]
        out[key] = full
    contact = np.zeros(n)
    contact[nodes] = 1.0
    out["contact"] = contact
    return out
