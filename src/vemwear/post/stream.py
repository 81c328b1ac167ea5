"""``result.h5``: the levels of a run streamed to disk as they are finished.

:class:`H5Sink` is the :class:`~vemwear.simulate.stream.LevelSink` of runs of the
command line. It creates ``result.h5`` with every dataset at its final size, allocated
and zero-filled at once (HDF5's early allocation), and afterwards only writes data into
them: no dataset grows and no metadata changes while the run goes on. So the file is
never structurally half-written, and after :meth:`H5Sink.checkpoint` (HDF5 flush plus
``fsync``) the levels handed over so far survive a killed process or a lost machine.
Contact rows are buffered in blocks of about 1 MB before they are written, so a level
costs no HDF5 call of its own.

The datasets have the names and meanings of the arrays of ``result.npz``
(:mod:`vemwear.post.results`): the mesh and contact-node arrays, ``t`` (all L levels),
``levels`` (K) the levels whose rows ``wear``, ``u_nu``, ``penetration``, ``p_rigid``,
``p_soft``, ``iterations``, ``residuals`` hold, and ``u`` (S, n, d) at ``u_levels``
(d = 2 or 3). ``completed`` counts the finished levels once the file is closed after
the run; while a run goes on (or after it was killed) the checkpoint next to the file
says how many are final.
``format`` is the format of ``result.npz``; a stopped run's file of format 1 (``lam``
and ``p``) has its two datasets renamed when the run is resumed.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from .results import (
    FORMAT,
    RENAMED_V1,
    array_format,
    result_from_arrays,
    static_arrays,
    upgrade_arrays,
)

if TYPE_CHECKING:
    from ..simulate import Problem, Result
    from ..simulate.stream import LoopState, StoragePlan
    from ..solvers import StepSolution

__all__ = [
    "ROW_ARRAYS",
    "STREAM_NAME",
    "H5Sink",
    "export_npz",
    "read_stream",
    "result_from_stream",
    "stream_bytes",
]

#: File name of the streamed result in an output directory.
STREAM_NAME = "result.h5"
#: Arrays with one row per kept level, and the shape of a row (m: contact nodes).
ROW_ARRAYS = (
    "wear",
    "u_nu",
    "penetration",
    "p_rigid",
    "p_soft",
    "iterations",
    "residuals",
    "forces",
)
_BUFFER_BYTES = 1 << 20


def _h5py() -> Any:
    import h5py

    return h5py


def _early(h5py: Any) -> Any:
    """Dataset creation properties: all storage allocated and zero-filled at creation."""
    dcpl = h5py.h5p.create(h5py.h5p.DATASET_CREATE)
    dcpl.set_alloc_time(h5py.h5d.ALLOC_TIME_EARLY)
    return dcpl


def _read_whole(h5py: Any, f: Any, name: str) -> NDArray[Any]:
    """The dataset ``name`` of the open file ``f``, read whole, as ``f[name][()]``.

    Through HDF5's own calls: a high-level ``Dataset`` costs about 0.3 ms to open, more
    than reading the small arrays of a run (of a 32 x 16 run's 34 arrays, a tenth of
    its wall time). Arrays of h5py's special types (object dtype) take the high-level
    path.
    """
    ds = h5py.h5d.open(f.id, name.encode())
    if ds.dtype.kind == "O":
        return np.asarray(f[name][()])
    out = np.empty(ds.shape, dtype=ds.dtype)
    if out.size:
        ds.read(h5py.h5s.ALL, h5py.h5s.ALL, out)
    return np.asarray(out[()]) if out.ndim == 0 else out


class H5Sink:
    """Stream a run's levels into ``result.h5``.

    Parameters
    ----------
    path : path
        The file.
    problem : Problem
        The problem being solved.
    plan : StoragePlan
        Which levels are kept.
    resume : bool
        Open an existing file (written by an earlier run of the same problem and plan)
        and go on writing into it.
    on_checkpoint : callable, optional
        Called with the :class:`~vemwear.simulate.stream.LoopState` once the levels so
        far are durable (the runner writes its checkpoint file there).
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        problem: Problem,
        plan: StoragePlan,
        *,
        resume: bool = False,
        on_checkpoint: Callable[[LoopState], None] | None = None,
    ) -> None:
        h5py = _h5py()
        self.path = Path(path)
        self.plan = plan
        self.row, self.slot = plan.slots()
        self.on_checkpoint = on_checkpoint
        m = len(problem.contact.nodes)
        gap = problem.nodal["gap"]
        self.gap = gap if np.any(gap) else None
        K, S, nv = len(plan.levels), len(plan.u_levels), problem.mesh.n_points
        d = problem.dim
        # k > 1: every dof of the stored levels (the ParaView output samples the field)
        nd = problem.discrete.n_dof if problem.order > 1 else 0
        whole = [("u", ((S, nv, d), None))] + ([("dofs", ((S, nd), None))] if nd else [])
        shapes: dict[str, tuple[tuple[int, ...], Any]] = {
            "wear": ((K, m), np.float64),
            "u_nu": ((K, m), np.float64),
            "penetration": ((K, m), np.float64),
            "p_rigid": ((K, m), np.float64),
            "p_soft": ((K, m), np.float64),
            "iterations": ((K,), np.int64),
            "residuals": ((K, 3), np.float64),
            "forces": ((K, len(problem.discrete.force_parts), d), np.float64),
        }
        if resume:
            self.file = h5py.File(self.path, "r+")
            _upgrade_file(self.file)
            for name, (shape, _) in (*shapes.items(), *whole):
                if name not in self.file or self.file[name].shape != shape:
                    self.file.close()
                    raise ValueError(f"{self.path}: dataset {name!r} missing or of another shape")
        else:
            self.file = h5py.File(self.path, "w")
            for name, value in static_arrays(problem, plan).items():
                if value.dtype.kind == "U":  # HDF5 strings are bytes (UTF-8)
                    value = np.char.encode(value, "utf-8")
                self.file.create_dataset(name, data=value)
            rows = max(1, min(K, _BUFFER_BYTES // (8 * max(m, 1))))
            for name, (shape, dtype) in shapes.items():
                chunks = (rows, *shape[1:])
                self.file.create_dataset(
                    name, shape=shape, dtype=dtype, chunks=chunks, dcpl=_early(h5py)
                )
            for name, (shape, _) in whole:
                self.file.create_dataset(
                    name,
                    shape=shape,
                    dtype=np.float64,
                    chunks=(1, *shape[1:]) if S else None,
                    dcpl=_early(h5py),
                )
            self.file.create_dataset("completed", data=np.int64(0))
            self.file.flush()
        self.rows_per_block = max(1, min(K, _BUFFER_BYTES // (8 * 5 * max(m, 1))))
        self.buf = {
            name: np.zeros((self.rows_per_block, *shape[1:]), dtype)
            for name, (shape, dtype) in shapes.items()
        }
        self.buf_start = -1  # first row held in the buffer
        self.buf_len = 0

    # ------------------------------------------------------------------ LevelSink
    def level(self, n: int, w: NDArray[np.float64], solution: StepSolution) -> None:
        """Buffer the contact row of level ``n`` (if kept)."""
        r = int(self.row[n])
        if r < 0:
            return
        if self.buf_len and (
            r != self.buf_start + self.buf_len or self.buf_len == self.rows_per_block
        ):
            self._write_buffer()
        if not self.buf_len:
            self.buf_start = r
        i = self.buf_len
        b = self.buf
        b["wear"][i], b["u_nu"][i] = w, solution.u_nu
        b["penetration"][i] = (
            solution.u_nu - w if self.gap is None else solution.u_nu - self.gap - w
        )
        b["p_rigid"][i], b["p_soft"][i] = solution.p_rigid, solution.p_soft
        b["iterations"][i] = solution.iterations
        res = solution.residuals
        b["residuals"][i] = (res["equilibrium"], res["feasibility"], res["complementarity"])
        if solution.forces is not None:
            b["forces"][i] = solution.forces
        self.buf_len += 1

    def displacement(
        self, n: int, u: NDArray[np.float64], residuals: NDArray[np.float64] | None
    ) -> None:
        """Write the displacement of level ``n`` (and its residuals, if given)."""
        self.file["u"][int(self.slot[n])] = u
        r = int(self.row[n])
        if residuals is None or r < 0:
            return
        if self.buf_len and self.buf_start <= r < self.buf_start + self.buf_len:
            self.buf["residuals"][r - self.buf_start] = residuals
        else:
            self.file["residuals"][r] = residuals

    def dofs(self, n: int, u: NDArray[np.float64]) -> None:
        """Write every dof of level ``n`` (a space of order k > 1; k = 1: ``u`` is all)."""
        if "dofs" in self.file:
            self.file["dofs"][int(self.slot[n])] = u

    def checkpoint(self, state: LoopState) -> None:
        """Write the buffer, flush the file to the disk, then call ``on_checkpoint``."""
        self.sync()
        if self.on_checkpoint is not None:
            self.on_checkpoint(state)

    # ------------------------------------------------------------------ file
    def _write_buffer(self) -> None:
        if not self.buf_len:
            return
        a, k = self.buf_start, self.buf_len
        for name, buf in self.buf.items():
            self.file[name][a : a + k] = buf[:k]
        self.buf_len = 0

    def sync(self) -> None:
        """Every level handed over so far, on the disk (HDF5 flush and ``fsync``)."""
        self._write_buffer()
        self.file.flush()
        fd = os.open(self.path, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)

    def close(self, completed: int | None = None) -> None:
        """Write what is buffered, record ``completed`` (if given) and close the file."""
        if not self.file.id.valid:
            return
        try:
            self._write_buffer()
            if completed is not None:
                self.file["completed"][()] = np.int64(completed)
        finally:
            self.file.close()


def _upgrade_file(f: Any) -> None:
    """Rename the datasets of a format-1 ``result.h5`` open for writing to today's
    names and record the format; each step can be repeated, so a file whose upgrade was
    cut short is finished the next time."""
    fmt = f["format"][()].decode("utf-8") if "format" in f else None
    array_format({} if fmt is None else {"format": np.array(fmt)})  # refuses newer ones
    if fmt == FORMAT:
        return
    for old, new in RENAMED_V1.items():
        if old in f and new not in f:
            f.move(old, new)
    f.create_dataset("format", data=np.char.encode(np.array(FORMAT), "utf-8"))
    f.flush()


def read_stream(
    path: str | os.PathLike[str], names: tuple[str, ...] | None = None
) -> dict[str, NDArray[Any]]:
    """Read the datasets of a ``result.h5`` (all, or ``names``) into memory, under
    today's names (a file of format 1 is read with ``lam`` and ``p`` as ``p_rigid`` and
    ``p_soft``: :func:`~vemwear.post.results.upgrade_arrays`).

    Raises
    ------
    ValueError
        If the file is of a newer format than this vemwear reads.
    """
    h5py = _h5py()
    with h5py.File(path, "r") as f:
        old = "format" not in f
        back = {v: k for k, v in RENAMED_V1.items()} if old else {}
        keys = names if names is not None else tuple(f.keys())
        out = {k: _read_whole(h5py, f, back.get(k, k)) for k in keys}
    out = {k: np.char.decode(v, "utf-8") if v.dtype.kind == "S" else v for k, v in out.items()}
    if old and names is None:
        return upgrade_arrays(out)
    try:
        array_format(out)
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None
    return out


def result_from_stream(
    problem: Problem, path: str | os.PathLike[str], *, solver: dict[str, Any] | None = None
) -> Result:
    """The :class:`~vemwear.simulate.Result` held by a closed ``result.h5``, in memory."""
    return result_from_arrays(problem, read_stream(path), solver=solver, copy=False)


def stream_bytes(path: str | os.PathLike[str]) -> int:
    """Bytes the datasets of a ``result.h5`` take in memory."""
    h5py = _h5py()
    with h5py.File(path, "r") as f:  # HDF5's own calls: see _read_whole
        datasets = (h5py.h5d.open(f.id, name) for name in f.id)
        return int(
            sum(d.get_space().get_simple_extent_npoints() * d.dtype.itemsize for d in datasets)
        )


def export_npz(outdir: str | os.PathLike[str], *, force: bool = False) -> Path:
    """Write ``OUTDIR/result.npz`` from ``OUTDIR/result.h5`` (same array names).

    Raises
    ------
    ValueError
        If there is no ``result.h5``, the run is not complete, ``result.npz`` exists and
        not ``force``, or the arrays do not fit in the available memory.
    """
    from ..util.atomic import atomic_file
    from ..util.system import available_memory
    from .results import NPZ_NAME

    out = Path(outdir)
    src, target = out / STREAM_NAME, out / NPZ_NAME
    if not src.is_file():
        raise ValueError(f"{out}: no streamed result {STREAM_NAME} to export")
    from .adaptive_stream import is_adaptive

    if is_adaptive(src):
        raise ValueError(
            f"{src} holds an [adapt] run, one group per mesh (docs/config.md, [adapt]); its "
            "levels have no common mesh to put into one result.npz: read the groups with h5py"
        )
    if target.exists() and not force:
        raise ValueError(f"{target} exists; use --force to write it again")
    need, avail = stream_bytes(src), available_memory()
    if avail and need > avail:
        raise ValueError(
            f"{src}: its arrays take {need / 1e9:.2f} GB, more than the {avail / 1e9:.2f} GB "
            "of memory available here; export it on a larger machine"
        )
    data = read_stream(src)
    if int(data.get("completed", 0)) < int(data["levels"][-1]) + 1:
        raise ValueError(f"{src} holds an unfinished run; finish it with vemwear run --resume")
    with atomic_file(target, durable=True) as tmp, open(tmp, "wb") as fh:
        np.savez(fh, **data)  # type: ignore[arg-type]
    return target
