"""``vemwear run`` of a configuration with ``[adapt]``: the mesh follows the contact zone.

The run (:func:`~vemwear.simulate.adaptive_time.simulate_adaptive`) streams every
finished segment into ``OUTDIR/result.h5``, one group per mesh
(:mod:`vemwear.post.adaptive_stream`), and at every mesh change, once that file is
durable, writes the checkpoint (:func:`~vemwear.runner.checkpoint.
write_adaptive_checkpoint`: the next mesh, its cell tree and the wear carried over). A
run stopped or killed goes on with ``--resume`` from its last mesh change and gives the
same arrays, bitwise: the outputs of every run are written from ``result.h5`` read back
(:func:`~vemwear.post.adaptive_stream.read_adaptive`), never from the memory of the run.

When the run completes, OUTDIR gets ``summary.json`` (with ``"adaptive"``: the settings
and, per mesh, its cells, dofs, contact nodes, owned levels and estimate), the figures
``contact_profiles.png`` (wear and pressure along Gamma_C at ``[output] times``, each on
its mesh) and ``meshes.png`` (the first and the last mesh), and the ParaView series:
``solution.xdmf`` + ``solution.h5`` (:func:`~vemwear.post.adaptive.write_adaptive_xdmf`:
every mesh once) or, with ``[output] paraview = "pvd"``, ``solution.pvd`` +
``solution/*.vtu`` (:func:`~vemwear.post.adaptive.write_adaptive_series`), every level
on its mesh, hanging nodes as vertices of their polygons.
"""

from __future__ import annotations

import dataclasses
import json
from datetime import UTC, datetime
from typing import TYPE_CHECKING, Any

import numpy as np

from ..util.atomic import write_atomic
from .checkpoint import CHECKPOINT_NAME, write_adaptive_checkpoint
from .outdir import PARTIAL_NAME, write_marker
from .partial import (
    discard,
    keep_stopped,
    output_names,
    outputs_failed,
    worn_through,
)
from .run import hold_lock
from .signals import check_stop, saving

if TYPE_CHECKING:
    from ..simulate.adapt import AdaptiveStep
    from ..simulate.adaptive_time import AdaptiveState, Segment
    from .run import RunPlan

__all__ = ["adaptive_summary", "execute_adaptive"]

_SERIES = "solution"


def execute_adaptive(plan: RunPlan, *, progress: bool = True) -> list[Segment]:
    """Run ``plan.cfg`` on adaptive meshes, streaming and checkpointing at every mesh
    change; write the outputs when done.

    Returns
    -------
    list of Segment
        Read back from ``result.h5``.

    On any error or interruption after a mesh change, the finished segments stay in
    ``result.h5`` with the checkpoint of the last mesh change, and the exception
    propagates with an attribute ``vemwear_note`` saying how to resume.
    """
    from ..post.adaptive_stream import AdaptiveH5
    from ..post.stream import STREAM_NAME
    from ..simulate.adaptive_time import AdaptiveState, simulate_adaptive

    out, cfg = plan.out, plan.cfg
    assert cfg.adapt is not None
    start = plan.state if isinstance(plan.state, AdaptiveState) else None
    hold_lock(plan)
    with plan.lock:
        write_marker(out, "running", output_names(), command="run")
        meta = {**plan.meta, "written": ""}
        h5 = AdaptiveH5(
            out / STREAM_NAME,
            cfg.problem.time.t,
            resume=start is not None,
            keep=start.segment if start is not None else 0,
        )
        done: list[AdaptiveState] = [start] if start is not None else []
        cells: list[int] = []
        eta: list[float] = []

        def on_pass(step: AdaptiveStep) -> None:  # a whole run before the run
            cells.append(step.problem.mesh.n_cells)
            eta.append(step.eta)
            with saving():
                h5.passes(cells, eta)
            check_stop()

        bar = _bar(progress, len(cfg.problem.time.t), start.first if start is not None else 0)

        def on_segment(seg: Segment, nxt: AdaptiveState | None) -> None:
            _check_wear(seg, nxt is None)
            with saving():
                h5.segment(nxt.segment - 1 if nxt else len(_groups(h5)), seg, nxt is None)
                if nxt is not None:
                    meta["written"] = datetime.now(UTC).isoformat(timespec="seconds")
                    write_adaptive_checkpoint(out, nxt, meta)
                    done.append(nxt)
            if bar is not None:  # the levels the segment owns, and the mesh it ran on
                bar.set_postfix_str(f"{seg.problem.mesh.n_cells} cells", refresh=False)
                bar.update(seg.last - seg.first + (nxt is None))
            check_stop()  # a safe point of every mesh change

        try:
            simulate_adaptive(
                cfg.problem,
                **dataclasses.asdict(cfg.adapt),
                solver=plan.solver,
                start=start,
                on_segment=on_segment,
                on_pass=on_pass,
                keep=False,
            )
            h5.close(completed=True)
        except BaseException as exc:
            _stop(plan, h5, done[-1] if done else None, exc)
            raise
        finally:
            if bar is not None:
                bar.close()
        try:
            segments = _finish(plan)
        except BaseException as exc:
            outputs_failed(plan, exc)
            raise
    return segments


def _bar(progress: bool, total: int, initial: int) -> Any:
    """A progress bar over the time levels, updated at every mesh change (or None)."""
    if not progress:
        return None
    from tqdm.auto import tqdm  # here: tqdm.auto imports asyncio (30 ms)

    # drawn at every update: there is one a mesh change
    return tqdm(
        total=total, initial=initial, desc="time levels", unit="lvl", leave=False, mininterval=0
    )


def _groups(h5: Any) -> list[str]:
    return [n for n in h5.file if n.startswith("mesh_")]


def _check_wear(seg: Segment, final: bool) -> None:
    """Stop at the first owned level whose wear exceeds the layer's thickness g."""
    res, g = seg.result, seg.problem.nodal["g"]
    assert res.levels is not None
    owned = np.arange(seg.first, seg.last + 1 if final else seg.last)
    rows = np.searchsorted(res.levels, owned)
    over = np.flatnonzero(np.any(res.wear[rows] > g, axis=1))
    if len(over):
        raise worn_through(seg.problem, int(owned[over[0]]), res.wear[rows[over[0]]], g)


def _stop(plan: RunPlan, h5: Any, state: AdaptiveState | None, exc: BaseException) -> None:
    """Keep the finished segments of a stopped run; attach a one-line note to ``exc``."""
    try:
        h5.close()
    except BaseException:
        pass
    if state is None:  # no mesh change finished: nothing to go on from
        discard(plan)
        return
    keep_stopped(plan, state.first, exc, lambda: None)  # the stream is closed


def _finish(plan: RunPlan) -> list[Segment]:
    """The standard files of a completed adaptive run, from ``result.h5``."""
    from ..post.adaptive import (
        plot_adaptive_profiles,
        plot_meshes,
        write_adaptive_series,
        write_adaptive_xdmf,
    )
    from ..post.adaptive_stream import read_adaptive, read_passes
    from ..post.outputs import FIGURE_NAMES_ADAPTIVE as FIGURE_NAMES
    from ..post.outputs import _use_agg
    from ..post.results import FORMAT, SUMMARY_NAME, jsonable
    from ..post.stream import STREAM_NAME

    cfg, out = plan.cfg, plan.out
    segments = read_adaptive(cfg.problem, out / STREAM_NAME, solver=plan.meta["solver"])
    passes = read_passes(out / STREAM_NAME)
    files = [STREAM_NAME, SUMMARY_NAME]
    if cfg.output.figures:
        _use_agg()
        t = cfg.problem.time.t
        times = list(cfg.output.times) or [float(t[-1])]
        plot_adaptive_profiles(segments, times, out / FIGURE_NAMES["contact_profiles"])
        plot_meshes(segments, out / FIGURE_NAMES["meshes"])
        files += list(FIGURE_NAMES.values())
    if cfg.output.vtk and cfg.output.paraview == "xdmf":
        xdmf = write_adaptive_xdmf(segments, out, name=_SERIES)
        files += [xdmf.name, xdmf.with_suffix(".h5").name]
    elif cfg.output.vtk:
        pvd = write_adaptive_series(segments, out, name=_SERIES)
        files += [pvd.name, _SERIES]
    summary = {
        "format": FORMAT,
        "partial": False,
        "created": datetime.now(UTC).isoformat(timespec="seconds"),
        "title": cfg.title,
        "inputs": {
            "config": cfg.data,
            "config_path": str(plan.config_path.resolve()),
            "inputs_sha256": plan.meta["inputs_sha256"],
        },
        "solver": plan.meta["solver"],
        "adaptive": {**adaptive_summary(segments, plan.meta["adapt"]), "passes": passes},
        "outputs": {
            "levels": len(cfg.problem.time.t),
            "wear_max_final": float(np.max(segments[-1].result.wear[-1], initial=0.0)),
            "cells_final": segments[-1].problem.mesh.n_cells,
        },
        "files": {"stream": STREAM_NAME},
    }
    if plan.state is not None:
        summary["resumed_from_level"] = int(plan.state.completed)
        summary["previous_solver"] = plan.previous_solver
    text = json.dumps(jsonable(summary), indent=2, allow_nan=False) + "\n"
    write_atomic(out / SUMMARY_NAME, text)
    write_marker(out, "complete", sorted(set(files)), command="run")
    for name in (CHECKPOINT_NAME, PARTIAL_NAME):  # after the marker: see completed_leftovers
        (out / name).unlink(missing_ok=True)
    return segments


def adaptive_summary(segments: list[Segment], settings: dict[str, Any]) -> dict[str, Any]:
    """The ``"adaptive"`` entry of ``summary.json``: the settings and every mesh."""
    from ..post.adaptive_stream import group_name

    meshes = []
    for k, seg in enumerate(segments):
        levels = seg.result.levels
        assert levels is not None
        meshes.append(
            {
                "group": group_name(k),
                "first": seg.first,
                "last": seg.last,
                "owns_levels": [int(levels[0]), int(levels[-1])],
                "cells": seg.problem.mesh.n_cells,
                "dofs": int(seg.problem.space.n_dofs),
                "contact_nodes": len(seg.result.contact_nodes),
                "max_refinement_level": int(seg.tree.level.max(initial=0)),
                "eta": seg.estimate.total,
            }
        )
    return {"settings": settings, "meshes": meshes}
