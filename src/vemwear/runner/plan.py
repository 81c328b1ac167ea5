"""Plan before work: the memory and the disk a run will need, checked before it starts.

:func:`estimate` gives peak memory and disk bytes from the sizes of a run. The model:

* memory: the interpreter and the libraries, what this process holds when the plan is
  made plus 60 MB for the libraries loaded later, and at least 160 MB (how much the
  libraries take depends on the machine: OpenBLAS keeps buffers per core); the sparse
  factorization of the stiffness, for N unknowns in 2D (nested dissection) about
  ``min(2000 N, 150 MB) + 160 N log2 N`` bytes with PARDISO (the first part: MKL's
  buffers, which grow up to about 150 MB between 17k and 66k unknowns) and
  ``400 N log2 N`` with SciPy's SuperLU (measured as the peak of ``vemwear run`` over
  the memory before it, after a first small run, on rectangles of 128 x 64 to
  1024 x 512 squares, u kept at t = T only: PARDISO 7, 259, 650 and 2936 MB, that is
  32, 244, 137 and 140 bytes per N log2 N; SuperLU 26, 320 and 1612 MB up to 512 x 256,
  111, 301 and 339 bytes; ``python benchmarks/bench_estimate.py``: the estimates are
  1.1 to 1.4 times these peaks); in 3D (3 unknowns per vertex) the fill-in
  of nested dissection grows as ``N^(4/3)``, not ``N log N``, and with the number
  ``z`` of vertices a vertex shares a cell with (itself included: 22-26 on hexahedra,
  13.5 on Kuhn tetrahedra, 33 on prisms over Voronoi polygons, 66 on Voronoi
  polyhedra; :func:`coupled_vertices`): about ``12 z N^(4/3)`` bytes with PARDISO and
  ``35 z N^(4/3)`` with SciPy's SuperLU (``python benchmarks/bench_estimate3d.py``:
  every 3D family at three sizes, the estimate over the peak in its table); the
  dense Schur block on the ``c = d m`` contact dofs, ``20 c^2`` bytes (the block
  PARDISO returns, its copy in the order of the contact dofs, its inverse in place:
  on prisms, whose contact side is the whole base mesh, it is the largest term); the
  recovery of u, a block of right-hand sides and one of solutions
  (``2 * 8 N`` bytes per stored level in the block, at most ``max(32, 2^20 / N)``
  levels); 24 bytes per time level (the time grid and
  the level tables); and, when
  the run ends, the kept arrays in memory for ``result.npz`` (twice: read and written).
  Mesh generation and the diagnostics before the time loop peak below this: the
  smallness estimate reads the run's own Schur block (a few dense products), and the
  mesh generators' arrays are released before the factorization;
* disk: ``result.h5`` (the kept contact rows, ``7 * 8 m`` bytes each, and the stored
  displacements, ``8 d n`` bytes each), ``result.npz`` (as much again), and the ParaView
  series (about ``16 n + 160 C`` bytes per stored displacement; ``24 n + 560 C`` in 3D:
  the polyhedra's faces and the 3 x 3 tensors).

An ``[adapt]`` run keeps every level with its displacement, on meshes of up to
``max_cells`` cells: its estimate is that of a run on a mesh of ``max_cells`` cells (the
vertices and contact nodes grown in proportion) keeping every level (on the initial mesh
when only ``target_error`` bounds the refinement).

Two checks, one rule: a run is refused (exit 2, with the numbers, unless
``--force-size``) when its estimate exceeds the machine's available memory or the free
disk of the output place (on ``--resume``, the free disk plus what ``result.h5``
already takes there). The numbers of a refusal are those of the estimate from the real
mesh and time grid (:func:`estimate_config`, :func:`check_estimate`), the estimate that
``vemwear check`` prints, made after they are built and before any solving.

Before they are built (:func:`vemwear.config.load_config`'s ``admit`` hook,
:func:`admit_sizes`), a rough check runs on sizes read from the configuration alone, each
a lower bound of the real one: the levels from ``[time]`` (exact), the cells the
generator makes (0 for a mesh file, not known before it is read), ``C/2 + 1`` vertices
for C cells (Euler's formula: no polygonal mesh has fewer; ``C/6 + 4`` in 3D, the
vertices of Kuhn tetrahedra, each coupled with at least 4), the smaller
factorization of the two backends, 2 contact
nodes, ``ceil(L / every)`` kept rows and the stored displacements that ``store_u``
certainly asks for. The estimate grows with every size (and the memory this process
holds only grows meanwhile), so the rough estimate is at most the real-mesh one: it
refuses only runs that the real-mesh estimate refuses too, and refuses them in a
fraction of a second, before anything large is allocated (``steps = 1e9``,
``n_cells = 1e8``). The hook runs a second time once the mesh is built and before the
time grid is: with the mesh's vertices and cells, and the vertices of the contact parts
that lie on no other part (each one a contact node) instead of 2, so that many levels on
a mesh of many contact nodes (``steps = 2e7`` on 64 x 32 squares) are refused before any
array of L levels is made.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ..util.system import available_memory, free_disk, resident_memory

if TYPE_CHECKING:
    from ..config import Config
    from ..config.build import Sizes
    from ..mesh.polyhedra import Mesh3D

__all__ = [
    "Estimate",
    "PlanError",
    "admit_sizes",
    "base_memory",
    "check_estimate",
    "coupled_vertices",
    "estimate",
    "estimate_config",
]

_BASE = 160e6
_LATER = 60e6


def base_memory() -> float:
    """The memory of a run before its arrays: the interpreter and the libraries."""
    return max(_BASE, resident_memory() + _LATER)


#: Bytes per ``N log2 N`` of the factorization in 2D, by resolved backend, and of MKL's
#: buffers with PARDISO (per unknown, up to a bound).
_FACTOR_2D = {"pardiso": 160.0, "scipy": 400.0}
_MKL_BUFFERS = (2000.0, 150e6)
#: Bytes per ``N^(4/3)`` and per coupled vertex of the factorization in 3D, by
#: resolved backend.
_FACTOR_3D = {"pardiso": 12.0, "scipy": 35.0}
#: The fewest vertices a vertex of a 3D mesh is coupled with (itself and the other
#: vertices of its cells): a tetrahedron's four (the rough estimate's lower bound).
_MIN_COUPLED_3D = 4.0
#: Bytes per squared Schur dof: the dense Schur block on the contact dofs, its copy in
#: their order and its inverse in place, about 2.5 blocks of ``8 c^2`` bytes at the peak.
_SCHUR = 20.0


def _factor_bytes(n: int, dim: int, backend: str, coupled: float = 27.0) -> float:
    """The factorization's memory for n unknowns (the module docstring); ``backend``
    ``"any"``: the smaller of the two (the rough estimate's lower bound); ``coupled``
    (3D): the mean number of vertices a vertex shares a cell with, itself included."""
    if backend not in ("pardiso", "scipy"):
        return min(_factor_bytes(n, dim, b, coupled) for b in ("pardiso", "scipy"))
    if dim == 2:
        mkl = min(_MKL_BUFFERS[0] * n, _MKL_BUFFERS[1]) if backend == "pardiso" else 0.0
        return mkl + _FACTOR_2D[backend] * n * math.log2(n)
    return _FACTOR_3D[backend] * coupled * float(n) ** (4 / 3)


def coupled_vertices(mesh: Mesh3D, sample: int = 4096) -> float:
    """The mean number of vertices a vertex of ``mesh`` shares a cell with, itself
    included (the nonzero 3 x 3 blocks of a row of K), over an evenly strided sample of
    at most ``sample`` vertices: a fraction of a second on any mesh."""
    off, ids = mesh.cell_vertex_offsets, mesh.cell_vertex_ids
    cell_of = np.repeat(np.arange(len(off) - 1), np.diff(off))
    order = np.argsort(ids, kind="stable")  # vertex -> its cells (CSR)
    voff = np.searchsorted(ids[order], np.arange(mesh.n_points + 1))
    picked = np.arange(0, mesh.n_points, max(1, mesh.n_points // sample))
    if not len(picked):
        return 0.0

    def ranges(first: NDArray[np.int64], count: NDArray[np.int64]) -> NDArray[np.int64]:
        """The concatenated ``first[i] + arange(count[i])``."""
        return np.repeat(first - np.cumsum(count) + count, count) + np.arange(int(count.sum()))

    nc = voff[picked + 1] - voff[picked]
    cells = cell_of[order[ranges(voff[picked], nc)]]
    sizes = np.diff(off)[cells]
    who = np.repeat(np.repeat(np.arange(len(picked)), nc), sizes)
    keys = np.sort(who * np.int64(mesh.n_points) + ids[ranges(off[cells], sizes)])
    return float(1 + np.count_nonzero(np.diff(keys))) / len(picked)


class PlanError(ValueError):
    """A run that would not fit in the machine's memory or the output's disk."""


@dataclass(frozen=True)
class Estimate:
    """Peak memory and disk of a run, in bytes."""

    memory: float
    disk: float

    def rows(self) -> list[tuple[str, str]]:
        return [("memory (estimate)", _size(self.memory)), ("disk (estimate)", _size(self.disk))]


def _size(n: float) -> str:
    if n >= 1e9:
        return f"{n / 1e9:.2f} GB"
    return f"{n / 1e6:.0f} MB" if n >= 1e7 else f"{n / 1e6:.2g} MB"


def estimate(
    *,
    levels: int,
    points: int,
    cells: int,
    contact: int,
    kept: int,
    stored_u: int,
    paraview: bool,
    npz: bool = True,
    base: float | None = None,
    dim: int = 2,
    backend: str = "pardiso",
    coupled: float = 27.0,
) -> Estimate:
    """Peak memory and disk of a run (the model of the module docstring).

    Parameters
    ----------
    levels : int
        L, the time levels.
    points, cells, contact : int
        Mesh vertices, cells and contact nodes m.
    kept, stored_u : int
        Kept contact rows K and stored displacements S.
    paraview : bool
        Whether a ParaView series is written.
    npz : bool
        Whether ``result.npz`` is written (its arrays are then held in memory).
    base : float, optional
        The memory before the run's arrays; :func:`base_memory` by default.
    dim : int
        2 or 3: the dimension of the mesh (3 unknowns per vertex and more fill-in in 3D).
    backend : str
        The resolved sparse backend (``pardiso`` or ``scipy``), or ``"any"``: the
        smaller factorization of the two.
    coupled : float
        3D: the mean number of vertices a vertex shares a cell with, itself included
        (:func:`coupled_vertices`; 27 on hexahedra).
    """
    n = max(dim * points, 2)
    rows = kept * (7 * 8 * contact + 32)
    disp = stored_u * 8 * dim * points
    arrays = rows + disp
    # the recovery of u: right-hand sides and solutions of a block of stored levels
    # (vemwear.simulate.levels.recover_block_size)
    block = 2 * 8 * n * min(max(stored_u, 1), max(32, 2**20 // n))
    vtk = 16 * points + 160 * cells if dim == 2 else 24 * points + 560 * cells
    memory = (
        (base_memory() if base is None else base)
        + _factor_bytes(n, dim, backend, coupled)
        + block
        + 24 * levels
        + _SCHUR * float(dim * contact) ** 2
        + (2 * arrays if npz else 0)
    )
    disk = arrays * (2 if npz else 1) + (stored_u * vtk if paraview else 0)
    return Estimate(float(memory), float(disk))


def _estimate_sizes(sizes: Sizes) -> Estimate:
    """The rough estimate: every size at its lower bound (the module docstring)."""
    three = sizes.dim == 3
    return estimate(
        levels=sizes.levels,
        points=max(sizes.points, sizes.cells // 6 + 4 if three else sizes.cells // 2 + 1),
        cells=sizes.cells,
        contact=max(sizes.contact, 2),
        kept=sizes.kept,
        stored_u=sizes.stored_u,
        paraview=sizes.paraview,
        dim=sizes.dim,
        backend="any",
        coupled=_MIN_COUPLED_3D,
    )


def check_estimate(
    est: Estimate, outdir: str | Path | None, where: str, *, have: float = 0.0
) -> None:
    """Refuse a run whose estimate does not fit (:class:`PlanError`, one line with the
    numbers and the ``--force-size`` hint).

    Parameters
    ----------
    est : Estimate
        The estimate.
    outdir : path, optional
        The output directory (its nearest existing ancestor's free disk counts); None
        checks the memory only.
    where : str
        The prefix of the message (the configuration file).
    have : float
        Bytes of the output already on the disk there (``result.h5`` of a resumed run):
        they are not asked for again.
    """
    mem = available_memory()
    if mem and est.memory > mem:
        raise PlanError(
            f"{where}: the run needs about {_size(est.memory)} of memory, {_size(mem)} are "
            "available; use a coarser mesh, fewer levels or a larger [output] every, or "
            "--force-size to run anyway"
        )
    if outdir is None:
        return
    free, need = free_disk(outdir), est.disk - have
    if need > free:
        more = f" more (besides the {_size(have)} it holds)" if have > 0 else ""
        raise PlanError(
            f"{where}: the output needs about {_size(need)} of disk{more}, {_size(free)} are "
            f"free at {outdir}; store fewer levels ([output] store_u, every) or use "
            "--force-size to run anyway"
        )


def admit_sizes(
    outdir: str | Path | None = None, *, force_size: bool = False, have: float = 0.0
) -> Callable[[Sizes], None]:
    """An ``admit`` hook for :func:`vemwear.config.load_config`: the rough check of the
    module docstring (:class:`PlanError`) unless ``force_size``; ``have`` as in
    :func:`check_estimate`."""

    def admit(sizes: Sizes) -> None:
        if not force_size:
            check_estimate(_estimate_sizes(sizes), outdir, sizes.source, have=have)

    return admit


def estimate_config(cfg: Config, *, base: float | None = None) -> Estimate:
    """The estimate of a validated configuration, from its real mesh and time grid
    (``base`` as in :func:`estimate`)."""
    from ..solvers import resolve_backend

    out = cfg.output
    pr = cfg.problem
    L = len(pr.time.t)
    stored = len(out.u_levels)
    # the multiples of every, and the final and stored levels that are not
    u = np.union1d(np.asarray(out.u_levels, dtype=np.int64), [L - 1])
    kept = -(-L // out.every) + int(np.count_nonzero(u % out.every))
    points, cells, contact = pr.mesh.n_points, pr.mesh.n_cells, len(pr.contact.nodes)
    if cfg.adapt is not None:  # every level and its u kept, on meshes of up to max_cells
        stored = kept = L
        if cfg.adapt.max_cells is not None:
            grow = cfg.adapt.max_cells / cells
            points, contact = math.ceil(points * grow), math.ceil(contact * grow)
            cells = cfg.adapt.max_cells
    return estimate(
        levels=L,
        points=points,
        cells=cells,
        contact=contact,
        kept=kept,
        stored_u=stored,
        paraview=out.vtk,
        base=base,
        dim=pr.dim,
        backend=resolve_backend(cfg.solver.backend),
        coupled=coupled_vertices(pr.mesh) if pr.dim == 3 else 27.0,
    )
