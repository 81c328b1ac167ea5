"""``result.h5`` of an adaptive run: one group per mesh, streamed segment by segment.

An adaptive run (:func:`~vemwear.simulate.adaptive_time.simulate_adaptive`) computes
its levels on a sequence of meshes. :class:`AdaptiveH5` writes each finished segment
into the group ``mesh_NNN`` (NNN its number from 000) and makes the file durable
(HDF5 flush plus ``fsync``), so a checkpoint written afterwards never refers to a
segment that could be lost. A group holds the arrays of ``result.npz``
(:mod:`vemwear.post.results`, same names) for the levels the mesh owns: ``levels``,
``t``, the rows ``wear``, ``u_nu``, ``penetration``, ``p_rigid``, ``p_soft``,
``iterations``, ``residuals``, ``forces``, the displacement ``u`` of every owned level
(``u_levels`` its rows), the mesh (``points``, ``cells_offsets``, ``cells_vertices``,
``boundary_tags``, ``part_names``) and its contact nodes with their data; besides, its
cell tree (``tree_level``, ``tree_family``, ``tree_parent_family``, ``tree_born``:
:class:`~vemwear.mesh.adapt.CellTree`), ``first`` and ``last`` (the levels it computed;
it owns ``first .. last - 1``, the final mesh ``.. last``) and the estimator's terms at
its last level (``eta_element``, ``eta_jump``, ...: :data:`~vemwear.simulate.estimate.
TERMS`). The file itself holds ``t`` (every level of the run), ``format``,
``vemwear_version``, ``adaptive`` (1) and, once the run is complete, ``segment_first``,
``segment_last`` and ``completed`` (the number of levels).

:func:`read_adaptive` rebuilds the segments of a complete file for a problem (the
outputs of a resumed run are written from it, as those of a run that never stopped).
:func:`contact_arrays` puts the contact arrays of every level on one set of points, the
contact nodes of all the meshes (the arrays a study's Dataset takes from a run).
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from .results import FORMAT, mesh_from_arrays, result_from_arrays, static_arrays

if TYPE_CHECKING:
    from ..mesh.polymesh import Mesh
    from ..simulate import Problem
    from ..simulate.adaptive_time import Segment

__all__ = [
    "AdaptiveH5",
    "contact_arrays",
    "group_name",
    "is_adaptive",
    "read_adaptive",
    "read_groups",
    "read_passes",
    "segment_arrays",
]

_TREE = ("level", "family", "parent_family", "born")


def group_name(k: int) -> str:
    """The group of the ``k``-th mesh (from 0)."""
    return f"mesh_{k:03d}"


def _h5py() -> Any:
    import h5py

    return h5py


def owned_levels(seg: Segment, final: bool) -> NDArray[np.int64]:
    """The levels a segment owns: ``first .. last - 1``, the final one ``.. last``."""
    return np.arange(seg.first, seg.last + 1 if final else seg.last, dtype=np.int64)


def segment_arrays(seg: Segment, final: bool) -> dict[str, NDArray[Any]]:
    """The arrays of the group of a segment (module docstring)."""
    from ..simulate.estimate import TERMS

    res, own = seg.result, owned_levels(seg, final)
    assert res.levels is not None
    rows = np.searchsorted(res.levels, own)
    urows = np.searchsorted(res.u_levels, rows)
    out = static_arrays(seg.problem, _Levels(own))
    out.update(
        u=np.asarray(res.u, dtype=np.float64)[urows],
        wear=res.wear[rows],
        u_nu=res.u_nu[rows],
        penetration=res.penetration[rows],
        p_rigid=res.p_rigid[rows],
        p_soft=res.p_soft[rows],
        iterations=res.iterations[rows],
        residuals=res.residuals[rows],
        first=np.array(seg.first, dtype=np.int64),
        last=np.array(seg.last, dtype=np.int64),
    )
    if res.forces is not None:
        out["forces"] = res.forces[rows]
    for name in _TREE:
        out[f"tree_{name}"] = np.asarray(getattr(seg.tree, name), dtype=np.int64)
    for term in TERMS:
        out[f"eta_{term}"] = np.asarray(seg.estimate.terms[term], dtype=np.float64)
    return out


@dataclasses.dataclass(frozen=True)
class _Levels:
    """The storage plan of a group: every owned level, with its displacement."""

    levels: NDArray[np.int64]

    @property
    def u_levels(self) -> NDArray[np.int64]:
        return self.levels


class AdaptiveH5:
    """Write the segments of an adaptive run into ``result.h5``.

    Parameters
    ----------
    path : path
        The file.
    t : (L,) array
        Every level of the run.
    resume : bool
        Open the file of a stopped run and go on from segment ``keep`` (the groups from
        there on, written after the last checkpoint, are removed).
    keep : int
        With ``resume``: the number of finished segments of the checkpoint.
    """

    def __init__(
        self, path: str | os.PathLike[str], t: NDArray[np.float64], *, resume: bool, keep: int = 0
    ) -> None:
        h5py = _h5py()
        self.path = Path(path)
        if resume:
            self.file = h5py.File(self.path, "r+")
            if "adaptive" not in self.file or not np.array_equal(self.file["t"][()], t):
                self.file.close()
                raise ValueError(f"{self.path} is not the result of this adaptive run")
            for name in list(self.file):
                if name.startswith("mesh_") and int(name[5:]) >= keep:
                    del self.file[name]
            for name in ("segment_first", "segment_last", "completed"):
                if name in self.file:
                    del self.file[name]
            self.sync()
            return
        self.file = h5py.File(self.path, "w")
        from .. import __version__

        self.file.create_dataset("t", data=np.asarray(t, dtype=np.float64))
        self.file.create_dataset("format", data=np.char.encode(np.array(FORMAT), "utf-8"))
        self.file.create_dataset("vemwear_version", data=np.char.encode(np.array(__version__)))
        self.file.create_dataset("adaptive", data=np.int64(1))
        self.sync()

    def segment(self, k: int, seg: Segment, final: bool) -> None:
        """Write the ``k``-th segment and make the file durable."""
        name = group_name(k)
        if name in self.file:  # written before a kill, not covered by a checkpoint
            del self.file[name]
        g = self.file.create_group(name)
        for key, value in segment_arrays(seg, final).items():
            if value.dtype.kind == "U":  # HDF5 strings are bytes (UTF-8)
                value = np.char.encode(value, "utf-8")
            g.create_dataset(key, data=value)
        self.sync()

    def passes(self, cells: list[int], eta: list[float]) -> None:
        """Record the whole runs before the run (``[adapt] passes``) so far: the cells of
        each one's mesh and its estimate; make the file durable."""
        for name, values in (("pass_cells", np.array(cells, np.int64)), ("pass_eta", eta)):
            if name in self.file:
                del self.file[name]
            self.file.create_dataset(name, data=np.asarray(values))
        self.sync()

    def sync(self) -> None:
        """Flush the file to the disk (HDF5 flush plus ``fsync``)."""
        self.file.flush()
        with open(self.path, "rb") as fh:
            os.fsync(fh.fileno())

    def close(self, completed: bool = False) -> None:
        """Close the file; with ``completed``, record the segments and the level count."""
        if not self.file.id.valid:
            return
        try:
            if completed:
                groups = sorted(n for n in self.file if n.startswith("mesh_"))
                first = [int(self.file[n]["first"][()]) for n in groups]
                last = [int(self.file[n]["last"][()]) for n in groups]
                self.file.create_dataset("segment_first", data=np.array(first, np.int64))
                self.file.create_dataset("segment_last", data=np.array(last, np.int64))
                self.file.create_dataset("completed", data=np.int64(len(self.file["t"])))
                self.sync()
        finally:
            self.file.close()


def _read_group(g: Any) -> dict[str, NDArray[Any]]:
    out = {k: np.asarray(g[k][()]) for k in g}
    return {k: np.char.decode(v, "utf-8") if v.dtype.kind == "S" else v for k, v in out.items()}


def read_passes(path: str | os.PathLike[str]) -> list[dict[str, Any]]:
    """The whole runs before an adaptive run (:meth:`AdaptiveH5.passes`): per pass, the
    cells of its mesh and its estimate; empty without ``[adapt] passes``."""
    with _h5py().File(path, "r") as f:
        if "pass_cells" not in f:
            return []
        cells, eta = f["pass_cells"][()], f["pass_eta"][()]
    return [{"cells": int(c), "eta": float(e)} for c, e in zip(cells, eta, strict=True)]


def is_adaptive(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` is the ``result.h5`` of an adaptive run (complete or not)."""
    try:
        with _h5py().File(path, "r") as f:
            return "adaptive" in f
    except OSError:
        return False


def read_groups(path: str | os.PathLike[str]) -> list[dict[str, NDArray[Any]]]:
    """The arrays of every group of an adaptive ``result.h5``, in order."""
    with _h5py().File(path, "r") as f:
        return [_read_group(f[n]) for n in sorted(n for n in f if n.startswith("mesh_"))]


def contact_arrays(groups: list[dict[str, NDArray[Any]]]) -> dict[str, NDArray[Any]]:
    """The contact arrays of every level of an adaptive run on one set of points.

    The points are the contact nodes of all the meshes (merged along the arc length
    ``contact_s``), and the values of a level there are those of its mesh, piecewise
    linear along Gamma_C (:func:`~vemwear.contact.transfer.transfer_along_contact`: exact
    at every node of that mesh, 0 at a clamped end), so the profiles of every level are
    kept whole. ``contact_weights`` are those of the final mesh at its nodes (0 at the
    other points): the dot product with the final wear is its worn volume.

    Parameters
    ----------
    groups : list of dict
        The groups of ``result.h5`` (:func:`read_groups`, :func:`segment_arrays`).

    Raises
    ------
    ValueError
        With several contact parts (their arc lengths do not make one line).
    """
    from ..contact.transfer import transfer_along_contact

    last = groups[-1]
    parts = tuple(str(p) for p in np.atleast_1d(last["contact_part_names"]))
    if len(parts) != 1 or any(not np.all(np.diff(g["contact_s"]) > 0) for g in groups):
        raise ValueError(
            "the contact arrays of an adaptive run are put on one line of points along one "
            f"contact part; this run has {len(parts)} ({', '.join(parts)})"
        )
    s_all = np.concatenate([g["contact_s"] for g in groups])
    X_all = np.concatenate([g["contact_points"] for g in groups])
    order = np.argsort(s_all, kind="stable")
    s_all, X_all = s_all[order], X_all[order]
    tol = 1e-9 * max(float(s_all[-1] - s_all[0]), 1e-300)
    keep = np.concatenate([[True], np.diff(s_all) > tol])
    s, X = s_all[keep], X_all[keep]
    out: dict[str, NDArray[Any]] = {
        "t": np.concatenate([g["t"] for g in groups]),
        "levels": np.concatenate([g["levels"] for g in groups]),
        "contact_s": s,
        "contact_points": X,
        "contact_part": np.zeros(len(s), dtype=np.int64),
        "contact_part_names": np.array(parts, dtype=str),
    }
    meshes = [_mesh2d(g) for g in groups]
    for name in ("wear", "u_nu", "penetration", "p_rigid", "p_soft"):
        out[name] = np.array(
            [
                transfer_along_contact(m, g["contact_nodes"], row, X, parts)
                for m, g in zip(meshes, groups, strict=True)
                for row in g[name]
            ]
        )
    for name in ("iterations", "residuals", "forces"):
        if all(name in g for g in groups):
            out[name] = np.concatenate([g[name] for g in groups])
    weights = np.zeros(len(s))
    weights[np.searchsorted(s, last["contact_s"] - tol)] = last["contact_weights"]
    out["contact_weights"] = weights
    for name in ("force_parts", "force_kinds", "residual_names", "format", "vemwear_version"):
        if name in last:
            out[name] = last[name]
    return out


def _mesh2d(data: dict[str, NDArray[Any]]) -> Mesh:
    from ..mesh.polymesh import Mesh

    mesh = mesh_from_arrays(data)
    assert isinstance(mesh, Mesh)  # adaptive runs are 2D
    return mesh


def read_adaptive(
    problem: Problem, path: str | os.PathLike[str], *, solver: dict[str, Any] | None = None
) -> list[Segment]:
    """The segments of a complete adaptive ``result.h5`` of ``problem`` (on its initial
    mesh), each with its mesh, problem, owned rows, cell tree and estimator terms."""
    from ..mesh.adapt import CellTree
    from ..simulate.adaptive_time import Segment
    from ..simulate.estimate import TERMS, Estimate
    from ..simulate.timegrid import TimeGrid

    h5py = _h5py()
    segments = []
    with h5py.File(path, "r") as f:
        t = np.asarray(f["t"][()])
        groups = sorted(n for n in f if n.startswith("mesh_"))
        datas = [_read_group(f[n]) for n in groups]
    for data in datas:
        first, last = int(data["first"]), int(data["last"])
        mesh = mesh_from_arrays(data)
        pr = dataclasses.replace(problem, mesh=mesh, time=TimeGrid(t[: last + 1]))
        res = result_from_arrays(pr, data, solver=solver, copy=False)
        tree = CellTree(*(data[f"tree_{n}"] for n in _TREE))
        est = Estimate({term: data[f"eta_{term}"] for term in TERMS})
        segments.append(Segment(pr, first, last, res, tree, known_estimate=est))
    return segments
