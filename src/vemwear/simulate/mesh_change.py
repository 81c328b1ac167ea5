"""How and when the mesh of an adaptive run changes (:class:`AdaptSettings`, the
``[adapt]`` table), and one mesh change: coarsen and refine by the residual estimator's
indicators (:func:`change_mesh`), or refine, round after round, by the wear indicator
of a wear profile (:func:`change_mesh_for_wear`). Shared by the runs whose mesh changes
in time (:mod:`.adaptive_time`) and the loop of whole runs (:mod:`.adapt`)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..contact.transfer import transfer_along_contact
from ..mesh.adapt import CellTree, dorfler_marking, refine_tree
from ..mesh.coarsen import coarsen_tree, coarsening_marking
from ..mesh.curves import BoundaryCurve
from ..mesh.polymesh import Mesh
from .wear_estimate import wear_indicators

__all__ = ["WEAR_ROUNDS", "AdaptSettings", "change_mesh", "change_mesh_for_wear"]


@dataclass(frozen=True)
class AdaptSettings:
    """When and how the mesh of an adaptive run changes (the ``[adapt]`` table).

    Attributes
    ----------
    every : int
        Levels between mesh changes (>= 1).
    theta : float
        Dörfler's bulk fraction of the refinement, in (0, 1].
    coarsen : float
        The fraction of eta^2 the coarsened cells may carry, in [0, 1 - theta); 0: no
        coarsening.
    max_cells : int, optional
        No refinement that would give more cells (coarsening still applies).
    target_error : float, optional
        No refinement at a level whose estimate eta is at most this (coarsening still
        applies); for the wear, a mesh change refines until eta is at most this.
    max_level : int, optional
        Cells of this level are not refined further.
    max_difference : int
        Largest level difference of neighbours (>= 1).
    curved : bool
        Put the new vertices of curved boundary edges onto the curve of the initial
        mesh's boundary (:mod:`vemwear.mesh.curves`); straight edges are not affected.
    estimator : {"residual", "wear"}
        What marks the cells: the residual estimator (:mod:`.estimate`), or the error of
        the wear profile predicted at the final time (:mod:`.wear_estimate`, k = 1), with
        which a mesh change refines, round after round on the predicted profile, until
        that error has fallen as one uniform refinement would make it fall, or to
        ``target_error``.
    transfer : {"linear", "cubic"}
        How the wear moves to a new mesh (:func:`~vemwear.contact.transfer.
        transfer_along_contact`): the piecewise linear function along Gamma_C, or the
        monotone piecewise cubic through its nodal values (k = 1).
    passes : int
        Whole runs before the run (>= 1): the run starts on the mesh refined after
        ``passes - 1`` solves of the whole time interval, each marked by the estimator
        at its final level (:func:`~vemwear.simulate.adapt.adapt_passes`); 1: none.

    Raises
    ------
    ValueError
        Naming the setting (its message starts with the key's name).
    """

    every: int
    theta: float = 0.5
    coarsen: float = 0.0
    max_cells: int | None = None
    target_error: float | None = None
    max_level: int | None = None
    max_difference: int = 1
    curved: bool = True
    estimator: str = "residual"
    transfer: str = "linear"
    passes: int = 1

    def __post_init__(self) -> None:
        theta, coarsen = self.theta, self.coarsen
        if int(self.every) < 1:
            raise ValueError(f"every must be at least 1 level, got {self.every}")
        if not 0.0 < theta <= 1.0:
            raise ValueError(f"theta must lie in (0, 1], got {theta}")
        if not 0.0 <= coarsen < 1.0:
            raise ValueError(f"coarsen must lie in [0, 1), got {coarsen}")
        if coarsen >= 1.0 - theta + 1e-12 and coarsen > 0:
            raise ValueError(
                f"coarsen = {coarsen} and theta = {theta} overlap: the cells to coarsen "
                "would carry part of the bulk marked for refinement (need coarsen < 1 - theta)"
            )
        if self.max_cells is not None and self.max_cells < 1:
            raise ValueError(f"max_cells must be at least 1, got {self.max_cells}")
        if self.target_error is not None and not self.target_error > 0:
            raise ValueError(f"target_error must be positive, got {self.target_error}")
        if self.max_level is not None and self.max_level < 0:
            raise ValueError(f"max_level must be >= 0, got {self.max_level}")
        if self.max_difference < 1:
            raise ValueError(f"max_difference must be at least 1, got {self.max_difference}")
        if self.estimator not in ("residual", "wear"):
            raise ValueError(f"estimator must be 'residual' or 'wear', got {self.estimator!r}")
        if int(self.passes) < 1:
            raise ValueError(f"passes must be at least 1, got {self.passes}")
        if self.transfer not in ("linear", "cubic"):
            raise ValueError(f"transfer must be 'linear' or 'cubic', got {self.transfer!r}")


def change_mesh(
    mesh: Mesh,
    tree: CellTree,
    eta2: NDArray[np.float64],
    total: float,
    cfg: AdaptSettings,
    curve: BoundaryCurve | None,
) -> tuple[Mesh, CellTree, NDArray[np.int64]]:
    """Coarsen, then refine, once, by the indicators ``eta2`` (their estimate ``total``):
    the new mesh, its tree, and the cells Dörfler's criterion marked for refinement
    (before the graded closure; empty when nothing was refined)."""
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
            return new, tree2, refine
    return mesh, tree, refine[:0]


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
) -> tuple[Mesh, CellTree, NDArray[np.int64]]:
    """A mesh change by the wear indicator of the predicted profile ``W`` at the contact
    ``nodes``: coarsen and refine once (:func:`change_mesh`), then refine again, the profile
    moved onto each new mesh (no solve), until its estimate is at most ``target_error``
    or, without one, a sixteenth of the old mesh's in eta^2 (what one uniform refinement
    gives a smooth profile, ``L^5`` per piece over twice the pieces), at most
    :data:`WEAR_ROUNDS` rounds or ``max_cells``; returned as :func:`change_mesh` does, with
    the marks of the first round."""
    parts, off_chord, cubic = move
    eta2 = wear_indicators(mesh, nodes, W, parts)
    goal = float(eta2.sum()) / 16.0 if cfg.target_error is None else cfg.target_error**2
    new, tree, marked = change_mesh(mesh, tree, eta2, float(np.sqrt(eta2.sum())), cfg, curve)
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
        new, tree, _ = change_mesh(mesh, tree, eta2, float(np.sqrt(eta2.sum())), cfg_refine, curve)
    return new, tree, marked
