"""The stiffness as a sum over the cells of a partition (the MPI ranks' assembly).

Each rank of an MPI run assembles the part of K of its own cells
(:class:`vemwear.simulate.cellparts.CellAssembly`); these tests check in one process
that the parts of every partition add up to the K that the serial run factorizes (2D
k = 1 and 2, 3D, the rigid parts' ties), that the partitions cover every cell once in
parts of about equal size, and that the recipe sent to the ranks (pickled) assembles
the same parts.
"""

from __future__ import annotations

import copy
import pickle
from typing import Any

import numpy as np
import pytest
import scipy.sparse as sp

from conftest import CONFIG_3D, small_config
from vemwear.config import parse_config
from vemwear.config.build import load_config
from vemwear.mesh.partition import partition_cells

HOLDER: dict[str, Any] = {  # a rigid holder on top: K is Q^T K Q (docs/method.md 1d)
    "mesh": {"generator": "squares", "size": [1.0, 0.5], "divisions": [12, 6]},
    "boundary": {
        "contact": "bottom",
        "displacement": [{"name": "rollers", "on": ["left", "right"], "ux": 0.0}],
        "rigid": [{"name": "holder", "on": "top", "fy": "-0.06"}],
    },
    "material": {"lam": 4.0, "eta": 4.0},
    "contact": {
        "p": {"type": "linear", "c": 1.0},
        "g": 0.1,
        "mu": 0.0,
        "kappa": 0.5,
        "v_star": [1.0, 0.0],
    },
    "time": {"T": 1.0, "steps": 2},
    "output": {"figures": False, "vtk": False},
}


def _discrete(case: str, tmp_path: Any) -> Any:
    if case.startswith("holder"):
        d = copy.deepcopy(HOLDER)
        d["vem"] = {"order": int(case[-1])}
        return parse_config(d, source="c.toml").problem.discrete
    text = {
        "2d k=1": small_config("p", divisions=(12, 6), steps=2),
        "2d k=2": small_config("p", divisions=(12, 6), steps=2, vem={"order": 2}),
        "3d": CONFIG_3D,
        # more cells than a batch of the element matrices (512, 256)
        "2d k=1 large": small_config("p", divisions=(80, 40), steps=2),
        "2d k=2 large": small_config("p", divisions=(48, 24), steps=2, vem={"order": 2}),
        "3d large": CONFIG_3D.replace("divisions = [4, 2, 2]", "divisions = [16, 8, 8]"),
    }[case]
    cfg = tmp_path / "c.toml"
    cfg.write_text(text)
    return load_config(cfg).problem.discrete


def _system(case: str, tmp_path: Any) -> Any:
    return _discrete(case, tmp_path).system


@pytest.mark.parametrize("case", ["2d k=1", "2d k=2", "3d", "holder k=1", "holder k=2"])
@pytest.mark.parametrize(
    ("parts", "method"), [(2, "rows"), (3, "rows"), (2, "metis"), (3, "metis"), (3, "slabs")]
)
def test_the_parts_of_a_partition_add_up_to_the_stiffness(
    tmp_path: Any, case: str, parts: int, method: str
) -> None:
    if method == "metis":
        pytest.importorskip("pymetis")
    s = _system(case, tmp_path)
    asm = s.assembly
    part, used = asm.partition(parts, method)
    assert used == method
    assert part.shape == (asm.n_cells,) and set(np.unique(part)) == set(range(parts))
    pieces = [asm.part(np.flatnonzero(part == r)) for r in range(parts)]
    total = sum(pieces[1:], pieces[0])
    scale = abs(s.K).max()
    assert abs(total - s.K).max() <= 1e-14 * scale
    # a part is not the whole: each rank's matrix misses the other ranks' cells
    assert all(abs(p - s.K).max() > 1e-3 * scale for p in pieces)
    # the recipe that rank 0 sends to the other ranks assembles the same part
    again = pickle.loads(pickle.dumps(asm)).part(np.flatnonzero(part == 1))
    assert abs(again - pieces[1]).max() == 0.0


@pytest.mark.parametrize("method", ["metis", "slabs"])
def test_partitions_are_balanced_and_cut_along_facets(method: str) -> None:
    """64 x 32 squares in 4 parts: equal counts within 3 %, and each part's cells are
    connected through their edges (no scattered cells: a short interface)."""
    from vemwear.mesh import rectangle_squares

    if method == "metis":
        pytest.importorskip("pymetis")
    mesh = rectangle_squares((2.0, 1.0), (64, 32))
    part, used = partition_cells(mesh.cell_offsets, mesh.cell_vertices, mesh.points, 4, method)
    assert used == method
    counts = np.bincount(part, minlength=4)
    assert counts.sum() == mesh.n_cells and counts.max() <= 1.03 * mesh.n_cells / 4
    inc = sp.csr_matrix(
        (np.ones(len(mesh.cell_vertices)), mesh.cell_vertices, mesh.cell_offsets),
        shape=(mesh.n_cells, mesh.n_points),
    )
    shared = sp.csr_matrix(inc @ inc.T)
    shared.data[shared.data < 2] = 0.0
    shared.eliminate_zeros()
    for r in range(4):
        ids = np.flatnonzero(part == r)
        n_comp, _ = sp.csgraph.connected_components(shared[ids][:, ids], directed=False)
        assert n_comp == 1
    # the interface: the vertices in cells of two parts, few against the mesh's
    owners = sp.csr_matrix((np.ones(len(part)), (np.arange(len(part)), part)))
    per_vertex = (inc.T @ owners).tocsr()
    shared_vertices = int(np.count_nonzero(np.diff(per_vertex.indptr) > 1))
    assert shared_vertices <= 0.1 * mesh.n_points


@pytest.mark.parametrize("case", ["2d k=1", "2d k=2", "3d"])
def test_the_row_split_follows_the_numbering_of_k(tmp_path: Any, case: str) -> None:
    """``"rows"``: the cells in the order of their vertices' first row of K, in parts of
    equal count (the ranks' cells then follow the contiguous blocks of K's rows)."""
    asm = _system(case, tmp_path).assembly
    part, used = asm.partition(3, "rows")
    assert used == "rows"
    mesh = asm.space.mesh
    if case == "3d":
        offsets, vertices = mesh.cell_vertex_offsets, mesh.cell_vertex_ids
    else:
        offsets, vertices = mesh.cell_offsets, mesh.cell_vertices
    first_dof = asm.space.dim * np.minimum.reduceat(vertices, offsets[:-1])
    row = np.searchsorted(asm.free, first_dof)
    assert np.all(np.diff(part[np.argsort(row, kind="stable")]) >= 0)  # monotone in row
    counts = np.bincount(part, minlength=3)
    assert counts.max() - counts.min() <= 1 and counts.sum() == mesh.n_cells


def test_an_unknown_partitioner_is_refused() -> None:
    from vemwear.mesh import rectangle_squares

    mesh = rectangle_squares((2.0, 1.0), (4, 2))
    with pytest.raises(ValueError, match="unknown partitioner 'chaco'"):
        partition_cells(mesh.cell_offsets, mesh.cell_vertices, mesh.points, 2, "chaco")


@pytest.mark.parametrize(
    "case",
    [
        *("2d k=1", "2d k=2", "3d", "holder k=1", "holder k=2"),
        *("2d k=1 large", "2d k=2 large", "3d large"),
    ],
)
def test_the_cells_around_the_contact_and_constrained_dofs_give_their_rows_bitwise(
    tmp_path: Any, case: str
) -> None:
    """Rank 0 of an MPI run assembles only the cells that touch the contact and the
    constrained dofs (:meth:`CellAssembly.around`): the rows and columns of the tied
    stiffness there are those of the whole matrix, bit for bit, and the cells are few."""
    d = _discrete(case, tmp_path)
    s, asm = d.system, d.system.assembly
    full = d.K_full
    free, fixed = d.free, d.constraints.dofs
    contact = free[s.contact_cols]
    near = np.union1d(contact, fixed)
    A = asm.around(near)
    assert np.array_equal(A[near].toarray(), full[near].toarray())
    assert np.array_equal(A[:, near].toarray(), full[:, near].toarray())
    # and the blocks the run reads: K's rows at the contact dofs, K_fc, K_cc
    assert np.array_equal(A[contact][:, free].toarray(), s.K[s.contact_cols].toarray())
    assert np.array_equal(A[free][:, fixed].toarray(), d._K_fc.toarray())
    assert np.array_equal(A.diagonal()[contact], s.K.diagonal()[s.contact_cols])
    # the cells are those along Gamma_C and the constrained parts, not the whole mesh
    cells = asm.touching(near)
    assert 0 < len(cells) < asm.n_cells
    # a row elsewhere is not the whole K's (cells left out)
    inner = np.setdiff1d(np.arange(full.shape[0]), near)
    assert abs(A[inner] - full[inner]).max() > 0
