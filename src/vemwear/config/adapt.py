"""The ``[adapt]`` table: a time-dependent run on a mesh that follows the contact zone.

:class:`Adapt` declares its keys (the schema of :mod:`vemwear.config.schema` holds it as
``ConfigFile.adapt``); :func:`adapt_settings` turns it into the
:class:`~vemwear.simulate.mesh_change.AdaptSettings` of
:func:`~vemwear.simulate.adaptive_time.simulate_adaptive` and refuses, before anything
is solved, the settings that contradict each other or that the adaptive path cannot
honour (a 3D mesh, for which the residual estimator is not implemented; a cycle-jump
run; stored levels it does not keep), each in one line naming the key.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, Literal

from pydantic import Field, model_validator

from .errors import ConfigError, at, error
from .sections import Section

if TYPE_CHECKING:
    from ..simulate.mesh_change import AdaptSettings

__all__ = ["Adapt", "adapt_settings"]


class Adapt(Section):
    """Adaptive meshes in time (docs/method.md section 11; k = 1 and 2, 2D)."""

    estimator: Literal["residual", "wear"] = Field(
        "residual",
        description="what marks the cells: 'residual' (the residual estimator of "
        "docs/method.md section 11, k = 1 and 2) or 'wear' (the error of the wear profile "
        "predicted at the final time along Gamma_C, k = 1; a mesh change refines until it "
        "has fallen as one uniform refinement would make it fall, or to target_error)",
    )
    every: int | None = Field(
        None,
        ge=1,
        description="time levels between mesh changes, >= 1; required unless passes > 1 "
        "(without it the run keeps the mesh the passes made)",
    )
    theta: float = Field(
        0.5, gt=0, le=1, description="Dörfler's bulk fraction of eta^2 marked for refinement"
    )
    max_cells: int | None = Field(
        None,
        ge=1,
        description="no refinement that would give more cells (at least the initial mesh's); "
        "this or target_error is required",
    )
    target_error: float | None = Field(
        None,
        gt=0,
        description="no refinement at a mesh change whose estimate eta is at most this (for "
        "'wear': a mesh change refines until eta is at most this); this or max_cells is "
        "required",
    )
    coarsen: bool = Field(
        False, description="also coarsen (merge) the families of cells of small indicators"
    )
    coarsen_fraction: float = Field(
        0.1,
        ge=0,
        lt=1,
        description="with coarsen = true: the fraction of eta^2 the coarsened cells may "
        "carry, below 1 - theta",
    )
    max_level: int | None = Field(
        None, ge=0, description="cells of this refinement level are not refined further"
    )
    max_difference: int = Field(
        1, ge=1, description="largest refinement level difference of neighbouring cells"
    )
    curved: bool = Field(
        True,
        description="new vertices on curved boundary parts go onto the curve through the "
        "initial mesh's boundary vertices (false: onto the chords); straight parts are "
        "not affected",
    )
    passes: int = Field(
        1,
        ge=1,
        description="whole runs before the run: the run starts on the mesh refined after "
        "passes - 1 solves of the whole time interval, each marked by the estimator at its "
        "final level (for 'wear': the wear at T); 1: none",
    )
    transfer: Literal["linear", "cubic"] = Field(
        "linear",
        description="how the wear moves to a new mesh: 'linear' (the piecewise linear "
        "function along Gamma_C) or 'cubic' (the monotone piecewise cubic through its "
        "nodal values, k = 1); kept nodes keep their values either way",
    )

    @model_validator(mode="before")
    @classmethod
    def _bounded(cls, data: Any) -> Any:
        if not isinstance(data, dict):
            return data
        if "max_cells" not in data and "target_error" not in data:
            raise error(
                "needs max_cells or target_error (or both): without either the refinement "
                "goes on at every mesh change"
            )
        if "every" not in data and not (isinstance(p := data.get("passes"), int) and p > 1):
            raise error(
                "needs every (time levels between mesh changes) unless passes > 1 (whole runs "
                "that make the mesh of the run)"
            )
        if "coarsen_fraction" in data and data.get("coarsen") is not True:
            raise error("coarsen_fraction is given but coarsen is not true; set coarsen = true")
        return data


def adapt_settings(
    src: str,
    a: Adapt,
    raw: Mapping[str, Any],
    *,
    dim: int,
    order: int,
    n_cells: int,
    levels: int,
) -> AdaptSettings:
    """The settings of ``[adapt]`` for a mesh of dimension ``dim`` and ``n_cells`` cells,
    the order ``order`` of the space and a run of ``levels`` time levels (without
    ``every``, the mesh stays for all of them).

    Raises
    ------
    ConfigError
        Naming the key.
    """
    if dim != 2:
        raise ConfigError(
            f"{src}: [adapt] the {a.estimator} estimator and the refinement are implemented "
            f"for 2D meshes; [mesh] is {dim}D (remove [adapt])"
        )
    if order not in (1, 2):
        raise ConfigError(
            f"{src}: [adapt] the {a.estimator} estimator is implemented for k = 1 and 2; [vem] "
            f"order = {order} (remove [adapt] or use order = 1 or 2)"
        )
    if order != 1 and a.estimator == "wear":
        raise ConfigError(
            f"{src}: [adapt] estimator = 'wear' is implemented for k = 1; [vem] order = "
            f"{order} (use estimator = 'residual' or order = 1)"
        )
    if order != 1 and a.transfer == "cubic":
        raise ConfigError(
            f"{src}: [adapt] transfer = 'cubic' is implemented for k = 1 (k = 2 moves the "
            f"wear as a piecewise quadratic); [vem] order = {order} (remove transfer)"
        )
    if a.max_cells is not None and a.max_cells < n_cells:
        raise ConfigError(
            f"{src}: [adapt] max_cells = {a.max_cells} is below the initial mesh's {n_cells} cells"
        )
    if a.coarsen and a.coarsen_fraction >= 1.0 - a.theta:
        raise ConfigError(
            f"{src}: [adapt] coarsen_fraction = {a.coarsen_fraction:g} and theta = {a.theta:g} "
            "overlap: the cells to coarsen would carry part of the bulk marked for refinement "
            "(need coarsen_fraction < 1 - theta)"
        )
    from ..simulate.mesh_change import AdaptSettings  # an adaptive run's module only

    with at(src, "[adapt]", raw.get("adapt", {})):
        return AdaptSettings(
            every=a.every if a.every is not None else max(levels - 1, 1),
            theta=a.theta,
            coarsen=a.coarsen_fraction if a.coarsen else 0.0,
            max_cells=a.max_cells,
            target_error=a.target_error,
            max_level=a.max_level,
            max_difference=a.max_difference,
            curved=a.curved,
            estimator=a.estimator,
            transfer=a.transfer,
            passes=a.passes,
        )


def check_adapt_output(src: str, raw: Mapping[str, Any]) -> None:
    """Refuse the keys of other sections that an adaptive run cannot honour."""
    out = raw.get("output", {})
    time = raw.get("time", {})
    if isinstance(time, dict) and "cycle_jump" in time:
        raise ConfigError(
            f"{src}: [time] cycle_jump does not go with [adapt] (a cycle-jump run keeps one "
            "mesh); remove one of them"
        )
    for key in ("store_u", "every"):
        if key in out:
            raise ConfigError(
                f"{src}: [output] {key} does not go with [adapt]: an adaptive run keeps every "
                "level and its displacement, on the mesh it was computed on; remove it"
            )
