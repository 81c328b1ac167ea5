"""What a stopped run leaves, and the names a run writes.

A run stops at a signal, a solver failure or a wear beyond the layer thickness g
(:class:`WearGuard`). With finished levels it leaves ``PARTIAL.txt`` and a partial
``summary.json`` (:func:`write_partial`) that say why (:func:`reason_line`) and how to
resume; without any, it removes what it wrote (:func:`discard`). Shared by the runs on
one mesh (:mod:`~vemwear.runner.run`) and on adaptive meshes
(:mod:`~vemwear.runner.adaptive`).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from datetime import UTC, datetime
from typing import TYPE_CHECKING, Any

import numpy as np

from ..util.atomic import write_atomic
from .checkpoint import CHECKPOINT_NAME
from .outdir import LOCK_NAME, MARKER_NAME, PARTIAL_NAME, write_marker
from .signals import check_stop, saving, stop_reason

if TYPE_CHECKING:
    from .run import RunPlan

__all__ = [
    "WearGuard",
    "WornThroughError",
    "discard",
    "keep_stopped",
    "output_names",
    "outputs_failed",
    "reason_line",
    "worn_through",
    "write_partial",
]


def output_names() -> list[str]:
    """Every top-level name a run may write into its output directory (a user's file of
    one of these names is never overwritten: ``--force`` refuses)."""
    from ..post.outputs import FIGURE_NAMES, FIGURE_NAMES_3D, FIGURE_NAMES_ADAPTIVE
    from ..post.results import NPZ_NAME, SUMMARY_NAME
    from ..post.stream import STREAM_NAME

    series = ["solution.xdmf", "solution.h5", "solution.pvd", "solution"]
    figures = [*FIGURE_NAMES.values(), *FIGURE_NAMES_3D.values(), *FIGURE_NAMES_ADAPTIVE.values()]
    names = {STREAM_NAME, CHECKPOINT_NAME, PARTIAL_NAME, SUMMARY_NAME, NPZ_NAME}
    return sorted({*names, *figures, *series})


class WornThroughError(ValueError):
    """The wear exceeds the thickness g of the soft layer: the run stops there."""


class WearGuard:
    """A level sink that stops the run at the first level whose wear exceeds g.

    In the model the wear stays below the penetration ``u_nu <= g``: once ``w`` reaches
    ``u_nu`` the soft layer carries no pressure there and wears no more. Wear beyond g is
    the explicit rule (3.22) overshooting (``k kappa |v*| L_p >= 1``), and every level
    after it is meaningless (``kappa = 1e308`` gave a wear of 5.5e304 on a layer 0.1
    thick); so the run stops with the finished levels saved, and says why.
    """

    def __init__(self, sink: Any, problem: Any) -> None:
        self._sink, self._problem = sink, problem
        self._g = problem.nodal["g"]

    def __getattr__(self, name: str) -> Any:
        return getattr(self._sink, name)

    def level(self, n: int, w: Any, solution: Any) -> None:
        check_stop()  # a safe point of every level
        if np.any(w > self._g):
            raise worn_through(self._problem, n, w, self._g)
        self._sink.level(n, w, solution)


def worn_through(problem: Any, n: int, w: Any, g: Any) -> WornThroughError:
    from ..simulate.explicit import overshoot

    a = int(np.argmax(w - g))
    x = ", ".join(f"{c:.4g}" for c in problem.contact.points[a])
    t = problem.time.t
    value, _, safe = overshoot(problem)
    why = (
        f"the explicit wear step overshoots (k kappa |v*| L_p up to {value:.3g}); use time "
        f"steps below {safe:.3g} or a smaller kappa"
        if value >= 1.0 and safe > 0
        else "check the scale of [contact] kappa, v_star and the compliance law"
    )
    return WornThroughError(
        f"the wear exceeds the layer thickness at time level {n} (t = {t[n]:g}): w = "
        f"{w[a]:.6g} > g = {float(np.broadcast_to(g, w.shape)[a]):g} at contact node {a} "
        f"(x = ({x})); the soft layer is worn through and the levels from here on would "
        f"not be physical: {why}"
    )


def reason_line(exc: BaseException) -> str:
    from ..simulate.levels import WearOverflowError
    from ..solvers import ConvergenceError

    by_signal = stop_reason(exc)
    if by_signal is not None:
        return by_signal
    if isinstance(exc, WearOverflowError | WornThroughError):
        return str(exc)
    if isinstance(exc, ConvergenceError):
        return f"the solver did not converge: {exc}"
    return f"error: {type(exc).__name__}: {exc}"


def discard(plan: RunPlan) -> None:
    """A run stopped before its first level: remove what it wrote (nothing else)."""
    from ..post.stream import STREAM_NAME

    for name in (STREAM_NAME, CHECKPOINT_NAME, MARKER_NAME, LOCK_NAME):
        (plan.out / name).unlink(missing_ok=True)
    if plan.created:
        try:
            plan.out.rmdir()  # only if nothing else was put there meanwhile
        except OSError:
            pass


def write_partial(plan: RunPlan, c: int, reason: str) -> None:
    """``summary.json`` (partial) and ``PARTIAL.txt`` of a stopped run."""
    from ..post.results import FORMAT, SUMMARY_NAME, jsonable
    from ..post.stream import STREAM_NAME

    cfg, L = plan.cfg, plan.storage.n_levels
    t = cfg.problem.time.t
    summary = {
        "format": FORMAT,
        "partial": True,
        "reason": reason,
        "completed": c,
        "levels": L,
        "inputs": {"config": cfg.data, "config_path": str(plan.config_path.resolve())},
        "solver": plan.meta["solver"],
        "files": {"stream": STREAM_NAME, "checkpoint": CHECKPOINT_NAME},
    }
    write_atomic(plan.out / SUMMARY_NAME, json.dumps(jsonable(summary), indent=2) + "\n")
    t_done = f"t = 0 .. {t[c - 1]:.6g}" if c > 0 else "none"
    text = f"""\
This directory holds an UNFINISHED run of vemwear.

  reason:    {reason}
  finished:  {c} of {L} time levels ({t_done}; T = {t[-1]:g})
  config:    {plan.config_path.resolve()} (sha256 {plan.meta["config_sha256"]})
  written:   {datetime.now(UTC).isoformat(timespec="seconds")}

To continue the run from level {c}:

  {plan.command}

The resumed run gives the same numbers as an uninterrupted run with the same solver;
the solver options may change (e.g. a larger max_iter after a convergence failure).
It refuses to start if the physics, the discretization or the kept levels changed.
{STREAM_NAME} holds the finished levels (rows of levels >= {c} are not final);
{CHECKPOINT_NAME} the state to go on from.
"""
    write_atomic(plan.out / PARTIAL_NAME, text)
    write_marker(plan.out, "partial", output_names(), "run")


def keep_stopped(plan: RunPlan, c: int, exc: BaseException, save: Callable[[], None]) -> None:
    """Keep the ``c`` finished levels of a run stopped by ``exc``: ``save()`` (the last
    checkpoint, the stream closed), then ``PARTIAL.txt``, in a section a first signal does
    not interrupt; attach the one-line note saying so, and how to go on, to ``exc``."""
    L = plan.storage.n_levels
    try:
        with saving(reraise=False):
            save()
            write_partial(plan, c, reason_line(exc))
        note = f"; the {c} finished time levels (of {L}) are saved in {plan.out}"
        if not isinstance(exc, WornThroughError):  # the same data would stop there again
            note += f"; continue with: {plan.command}"
    except BaseException as err:  # a second failure must not hide the first one
        note = f"; the {c} finished time levels could not be saved ({type(err).__name__}: {err})"
    try:
        exc.vemwear_note = note  # type: ignore[attr-defined]
    except AttributeError:  # pragma: no cover - exceptions with __slots__
        pass


def outputs_failed(plan: RunPlan, exc: BaseException) -> None:
    """Writing the outputs of a run whose every level is saved failed with ``exc``: say
    so in ``PARTIAL.txt`` and in the note on ``exc`` (``--resume`` writes them)."""
    with saving(reraise=False):
        write_partial(plan, plan.storage.n_levels, f"writing the outputs: {reason_line(exc)}")
    exc.vemwear_note = (  # type: ignore[attr-defined]
        f"; every time level is solved and saved in {plan.out}; write the outputs "
        f"with: {plan.command}"
    )
