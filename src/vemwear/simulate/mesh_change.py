"""One mesh change of an adaptive run: coarsen and refine by the residual estimator's
indicators (:func:`change_mesh`), or refine, round after round, by the wear indicator
of a wear profile (:func:`change_mesh_for_wear`). Shared by the runs whose mesh changes
in time (:mod:`.adaptive_time`) and the loop of whole runs (:mod:`.adapt`)."""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ..contact.transfer import transfer_along_contact
from ..mesh.adapt import CellTree, dorfler_marking, refine_tree
from ..mesh.coarsen import coarsen_tree, coarsening_marking
from ..mesh.curves import BoundaryCurve
from ..mesh.polymesh import Mesh
from .wear_estimate import wear_indicators

if TYPE_CHECKING:
    from .adaptive_time import AdaptSettings

__all__ = ["WEAR_ROUNDS", "change_mesh", "change_mesh_for_wear"]


def change_mesh(
    mesh: Mesh,
    tree: CellTree,
    eta2: NDArray[np.float64],
    total: float,
    cfg: AdaptSettings,
    curve: BoundaryCurve | None,
) -> tuple[Mesh, CellTree]:
    """Coarsen, then refine, once, by the indicators ``eta2`` (their estimate ``total``):
    the new mesh and its tree."""
    refine = dorfler_marking(eta2, cfg.theta)
    if cfg.max_level is not None:
        refine = refine[tree.level[refine] < cfg.max_level]
    if cfg.target_error is not None and total <= cfg.target_error:
        refine = refine[:0]  # accurate enough: coarsening only
    owner = np.arange(mesh.n_cells)
    if cfg.coarsen > 0:
        spare = np.setdiff1d(coarsening_marking(eta2, cfg.coarsen), refine)
        mesh, tree, owner = coarsen_tree(mesh, tree, spare, cfg.max_difference, curve)
    if refine.size:
        new, tree2, _ = refine_tree(mesh, tree, owner[refine], cfg.max_difference, curve)
        if cfg.max_cells is None or new.n_cells <= cfg.max_cells:
            return new, tree2
    return mesh, tree


#: Most refinement rounds of one mesh change by the wear indicator.
WEAR_ROUNDS = 8


def change_mesh_for_wear(
    mesh: Mesh,
    tree: CellTree,
    nodes: NDArray[np.int64],
    W: NDArray[np.float64],
    cfg: AdaptSettings,
    curve: BoundaryCurve | None,
    move: tuple[tuple[str, ...], float, bool],
) -> tuple[Mesh, CellTree]:
    """A mesh change by the wear indicator of the predicted profile ``W`` at the contact
    ``nodes``: coarsen and refine once (:func:`change_mesh`), then refine again, the profile
    moved onto each new mesh (no solve), until its estimate is at most ``target_error``
    or, without one, a sixteenth of the old mesh's in eta^2 (what one uniform refinement
    gives a smooth profile, ``L^5`` per piece over twice the pieces), at most
    :data:`WEAR_ROUNDS` rounds or ``max_cells``."""
    parts, off_chord, cubic = move
    eta2 = wear_indicators(mesh, nodes, W, parts)
    goal = float(eta2.sum()) / 16.0 if cfg.target_error is None else cfg.target_error**2
    new, tree = change_mesh(mesh, tree, eta2, float(np.sqrt(eta2.sum())), cfg, curve)
    for _ in range(WEAR_ROUNDS - 1):
        if new is mesh:  # nothing refined: marks at max_level, max_cells or the target
            break
        on = np.unique(np.concatenate([new.part_edges(p) for p in parts]))
        W = transfer_along_contact(mesh, nodes, W, new.points[on], parts, off_chord, cubic)
        mesh, nodes = new, on
        eta2 = wear_indicators(mesh, nodes, W, parts)
        if eta2.sum() <= goal:
            break
        cfg_refine = dataclasses.replace(cfg, coarsen=0.0)
        new, tree = change_mesh(mesh, tree, eta2, float(np.sqrt(eta2.sum())), cfg_refine, curve)
    return new, tree
