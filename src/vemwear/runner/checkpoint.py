"""Checkpoints of a run: the state to go on from, durable next to the streamed levels.

A run of the command line streams its levels into ``OUTDIR/result.h5``
(:class:`vemwear.post.stream.H5Sink`). Every ``[output] checkpoint`` seconds, and when
it is stopped by a signal or an error, it flushes that file to the disk and then
writes ``OUTDIR/checkpoint.npz`` atomically and durably (``fsync``): the
:class:`~vemwear.simulate.stream.LoopState` of the finished levels
(:func:`vemwear.simulate.stream.state_arrays`) and, as JSON in the array ``meta``, the
problem's fingerprint (the physics and the discretization), the levels the run keeps
and the solver it used. Whatever killed the run afterwards (SIGKILL, the OOM killer,
a lost machine), ``--resume`` goes on from that checkpoint and gives the same arrays,
bitwise, as a run that never stopped.

The fingerprint covers the physics and the discretization, not the solver options: a
run stopped because its solver did not converge may go on with another ``tol``,
``max_iter`` or method. A change of the physics is refused with the list of what
changed (:func:`differences`).

An adaptive run (``[adapt]``) is checkpointed at its mesh changes instead
(:func:`write_adaptive_checkpoint`): the next segment's mesh, cell tree and wear, after
the finished segments are durable in ``result.h5``
(:class:`vemwear.post.adaptive_stream.AdaptiveH5`).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..simulate.stream import LoopState, state_arrays, state_from_arrays
from ..util.atomic import atomic_file

if TYPE_CHECKING:
    from ..simulate.adaptive_time import AdaptiveState

__all__ = [
    "CHECKPOINT_NAME",
    "differences",
    "read_adaptive_checkpoint",
    "read_checkpoint",
    "write_adaptive_checkpoint",
    "write_checkpoint",
]

#: File name of the checkpoint in an output directory.
CHECKPOINT_NAME = "checkpoint.npz"


def write_checkpoint(outdir: Path, state: LoopState, meta: Mapping[str, Any]) -> Path:
    """Write ``OUTDIR/checkpoint.npz`` atomically and durably.

    Parameters
    ----------
    outdir : Path
        The output directory.
    state : LoopState
        The state of the finished levels.
    meta : mapping
        JSON-friendly data stored with it (fingerprint, storage plan, solver).

    Returns
    -------
    Path
        The file.
    """
    arrays = state_arrays(state)
    arrays["meta"] = np.array(json.dumps({**meta, "completed": state.completed}))
    target = outdir / CHECKPOINT_NAME
    with atomic_file(target, durable=True) as tmp, open(tmp, "wb") as fh:
        np.savez(fh, **arrays)  # type: ignore[arg-type]
    return target


def read_checkpoint(outdir: Path) -> tuple[LoopState, dict[str, Any]]:
    """The state and the metadata of ``OUTDIR/checkpoint.npz``.

    Raises
    ------
    FileNotFoundError
        If there is no checkpoint.
    ValueError
        If the file cannot be read as a checkpoint.
    """
    path = outdir / CHECKPOINT_NAME
    if not path.is_file():
        raise FileNotFoundError(str(path))
    try:
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(data["meta"]))
            state = state_from_arrays({k: data[k] for k in data.files})
    except (OSError, KeyError, ValueError) as exc:
        raise ValueError(f"{path} is not a readable checkpoint: {exc}") from None
    return state, meta


# ---------------------------------------------------------------------------- fingerprint
def _flatten(x: Any, prefix: str = "") -> dict[str, Any]:
    if isinstance(x, Mapping):
        out: dict[str, Any] = {}
        for k, v in x.items():
            out.update(_flatten(v, f"{prefix}.{k}" if prefix else str(k)))
        return out
    return {prefix: x}


#: Section of the configuration of each entry of ``Problem.describe()``.
_SECTIONS = {
    "mesh": "[mesh]",
    "material": "[material]",
    "time": "[time]",
    "f1": "[loads]",
    "f2": "[loads]",
    "p": "[contact]",
    "g": "[contact]",
    "mu": "[contact]",
    "kappa": "[contact]",
    "v_star": "[contact]",
    "stabilization": "[vem]",
}
#: What the hashed parts of the fingerprint are, and the described entries they cover.
_HASHED = {
    "mesh": ("the mesh (vertices, cells or boundary parts)", ("mesh",)),
    "time": ("the time levels", ("time",)),
    "nodal": ("the values of g, mu or kappa at the contact nodes", ("g", "mu", "kappa")),
    "v_star": ("the foundation velocity v_star", ("v_star",)),
    "load": ("the loads f1, f2", ("f1", "f2")),
    "vemwear_version": ("the vemwear version", ()),
    "format": ("the fingerprint format", ()),
}


def _key_name(path: str) -> str:
    """``description.material.lam`` -> ``[material] lam``, ``description.mu`` ->
    ``[contact] mu``."""
    parts = path.split(".")[1:]
    section = _SECTIONS.get(parts[0], f"[{parts[0]}]")
    if parts[0] in ("material", "mesh", "time"):
        return f"{section} {'.'.join(parts[1:])}"
    return f"{section} {'.'.join(parts)}"


def _brief(v: Any) -> str:
    s = json.dumps(v) if not isinstance(v, str) or v == "<absent>" else repr(v)
    s = s.replace('"<absent>"', "<absent>")
    return s if len(s) <= 40 else s[:37] + "..."


def differences(old: Mapping[str, Any], new: Mapping[str, Any], limit: int = 3) -> list[str]:
    """What changed between two problem fingerprints, in words (at most ``limit`` items)."""
    a, b = _flatten(old.get("description", {})), _flatten(new.get("description", {}))
    diffs, changed = [], set()
    for k in sorted(set(a) | set(b)):
        x, y = a.get(k, "<absent>"), b.get(k, "<absent>")
        if x != y:
            diffs.append(f"{_key_name('description.' + k)}: {_brief(x)} -> {_brief(y)}")
            changed.add(k.split(".")[0])
    for key, (what, covers) in _HASHED.items():
        if old.get(key) != new.get(key) and not changed & set(covers):
            diffs.append(f"{what} changed")
    if len(diffs) > limit:
        diffs = [*diffs[:limit], f"and {len(diffs) - limit} more"]
    return diffs


# ---------------------------------------------------------------------------- adaptive runs
def write_adaptive_checkpoint(outdir: Path, state: AdaptiveState, meta: Mapping[str, Any]) -> Path:
    """Write the checkpoint of an adaptive run at a mesh change: the next segment's
    first level, mesh, cell tree and wear (:class:`~vemwear.simulate.adaptive_time.
    AdaptiveState`), atomically and durably, with ``meta`` as for
    :func:`write_checkpoint`."""
    from ..post.results import static_mesh_arrays

    arrays: dict[str, Any] = {f"mesh_{k}": v for k, v in static_mesh_arrays(state.mesh).items()}
    arrays.update({f"tree_{k}": getattr(state.tree, k) for k in _TREE})
    arrays["wear"] = np.asarray(state.wear, dtype=np.float64)
    info = {**meta, "adaptive": True, "segment": state.segment, "completed": state.first}
    arrays["meta"] = np.array(json.dumps(info))
    target = outdir / CHECKPOINT_NAME
    with atomic_file(target, durable=True) as tmp, open(tmp, "wb") as fh:
        np.savez(fh, **arrays)
    return target


def read_adaptive_checkpoint(outdir: Path) -> tuple[AdaptiveState, dict[str, Any]]:
    """The state and the metadata of the checkpoint of an adaptive run.

    Raises
    ------
    ValueError
        If the file cannot be read as the checkpoint of an adaptive run.
    """
    from ..mesh.adapt import CellTree
    from ..post.results import mesh_from_arrays
    from ..simulate.adaptive_time import AdaptiveState

    path = outdir / CHECKPOINT_NAME
    try:
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(data["meta"]))
            if not meta.get("adaptive"):
                raise ValueError("it is the checkpoint of a run without [adapt]")
            mesh = mesh_from_arrays({k[5:]: data[k] for k in data.files if k.startswith("mesh_")})
            tree = CellTree(*(np.asarray(data[f"tree_{k}"]) for k in _TREE))
            wear = np.asarray(data["wear"])
    except (OSError, KeyError, ValueError) as exc:
        raise ValueError(f"{path} is not a readable checkpoint of an adaptive run: {exc}") from None
    from ..mesh.polymesh import Mesh

    assert isinstance(mesh, Mesh)
    state = AdaptiveState(int(meta["segment"]), int(meta["completed"]), mesh, tree, wear)
    return state, meta


_TREE = ("level", "family", "parent_family", "born")
