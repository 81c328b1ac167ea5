"""Global dofs, assembly and loads of second-order virtual elements (k = 2, 2D elasticity).

Global numbering (``n_p`` vertices, ``n_e`` edges, ``n_c`` cells):

* ``2 v + c``: component c at vertex v (as for k = 1, :func:`vemwear.vem.assembly._dofs`);
* ``2 n_p + 2 e + c``: the mean of component c over edge e, ``e`` the row of
  :attr:`vemwear.mesh.Mesh.edges` (unique undirected edges, ``a < b``). A mean against P0
  does not depend on the edge's orientation, so both cells of an edge share the dof as is;
* ``2 n_p + 2 n_e + 2 k + c``: the mean of component c over cell k.

Hanging nodes are vertices of every cell whose boundary passes through them, so the
large cell has two edges where its neighbours have two: the edges, and the dofs, are
conforming without any special treatment.
"""

from __future__ import annotations

import sys
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from ..mesh.polymesh import Mesh
from ..util.arrays import members
from ..util.arrays import unique as _unique
from .local import Material
from .local2 import (
    ElementWork,
    _check_stabilization,
    basis_gradients,
    basis_values,
    element_stiffness_into,
    local_dof_count,
    local_projection2,
)
from .quadrature import Field, cell_means, eval_field, fan

__all__ = [
    "GAUSS3",
    "LOAD_RULES",
    "Numbering2",
    "P2Fields",
    "body_force_vector2",
    "cell_dofs2",
    "edge_ids",
    "edge_load_vector2",
    "edge_shape_functions",
    "facet_dofs2",
    "interpolate2",
    "numbering2",
    "project2",
    "stiffness2",
    "traction_vector2",
]

#: Cells per batch of local matrices in :func:`stiffness2`.
CHUNK = 256

#: Three-point Gauss rule on [0, 1]: points and weights (exact for degree 5).
GAUSS3 = (
    np.array([0.5 - 0.5 * np.sqrt(0.6), 0.5, 0.5 + 0.5 * np.sqrt(0.6)]),
    np.array([5.0, 8.0, 5.0]) / 18.0,
)


class Numbering2(NamedTuple):
    """Sizes and offsets of the k = 2 global dofs of a mesh."""

    n_points: int
    n_edges: int
    n_cells: int

    @property
    def edge_offset(self) -> int:
        return 2 * self.n_points

    @property
    def cell_offset(self) -> int:
        return 2 * (self.n_points + self.n_edges)

    @property
    def n_dofs(self) -> int:
        return 2 * (self.n_points + self.n_edges + self.n_cells)


def numbering2(mesh: Mesh) -> Numbering2:
    """The global dof counts of ``mesh`` for k = 2."""
    return Numbering2(mesh.n_points, len(mesh.edges), mesh.n_cells)


def edge_ids(mesh: Mesh, a: ArrayLike, b: ArrayLike) -> NDArray[np.int64]:
    """Rows of :attr:`Mesh.edges` of the edges ``(a, b)`` (either orientation).

    Raises
    ------
    ValueError
        If some ``(a, b)`` is not an edge of the mesh.
    """
    a, b = np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    E = mesh.edges
    n = max(mesh.n_points, 1)
    keys = E[:, 0] * n + E[:, 1]  # sorted: np.unique sorts the rows
    k = lo * n + hi
    pos = np.minimum(np.searchsorted(keys, k), len(keys) - 1)
    if np.any(keys[pos] != k):
        raise ValueError("edge_ids: some vertex pairs are not edges of the mesh")
    return pos


def cell_dofs2(mesh: Mesh, ids: NDArray[np.int64], verts: NDArray[np.int64]) -> NDArray[np.int64]:
    """Global dofs (m, 4 n + 2) of cells ``ids`` with vertices ``verts`` (m, n), in the local
    order of :mod:`vemwear.vem.local2`."""
    num = numbering2(mesh)
    m, n = verts.shape
    d = np.empty((m, local_dof_count(n)), dtype=np.int64)
    d[:, 0 : 2 * n : 2] = 2 * verts
    d[:, 1 : 2 * n : 2] = 2 * verts + 1
    e = num.edge_offset + 2 * edge_ids(mesh, verts, np.roll(verts, -1, axis=1))
    d[:, 2 * n : 4 * n : 2] = e
    d[:, 2 * n + 1 : 4 * n : 2] = e + 1
    d[:, 4 * n] = num.cell_offset + 2 * ids
    d[:, 4 * n + 1] = num.cell_offset + 2 * ids + 1
    return d


class _Pattern(NamedTuple):
    """The CSR pattern of the k = 2 stiffness and where every local entry goes."""

    indptr: NDArray[np.int64]
    indices: NDArray[np.int32]
    bpos: NDArray[np.signedinteger]  # block (2 x 2) position of every local node pair, cell by cell
    bptr: NDArray[np.int64]  # block row starts (per node)


def _cell_nodes(mesh: Mesh) -> list[tuple[NDArray[np.int64], NDArray[np.int64]]]:
    """Per vertex-count group: the vertex ids (m, n) and the nodes (m, 2 n + 1) of every
    cell: vertex ``v`` is node ``v``, edge ``e`` node ``n_p + e``, cell ``k`` node
    ``n_p + n_e + k``; global dof ``2 node + c`` (:func:`numbering2`)."""
    npt, ne = mesh.n_points, len(mesh.edges)
    out = []
    for n, (ids, verts) in mesh.groups.items():
        nodes = np.empty((len(ids), 2 * n + 1), dtype=np.int64)
        nodes[:, :n] = verts
        nodes[:, n : 2 * n] = npt + edge_ids(mesh, verts, np.roll(verts, -1, axis=1))
        nodes[:, 2 * n] = npt + ne + ids
        out.append((verts, nodes))
    return out


#: Bits of the packed sort keys in :func:`_pattern`: the node pair and the entry index are
#: packed into one integer when they fit in this many bits (one in-place sort, no argsort);
#: larger meshes (about 110,000 Voronoi cells and up) take the argsort.
PACK_BITS = 64

#: Cells per block when the sort keys are written, entries per block after the sort.
_KEY_BLOCK = 2048
_SORT_BLOCK = 1 << 18


def _pair_keys(
    groups: list[tuple[NDArray[np.int64], NDArray[np.int64]]], mult: int, shift: int, packed: bool
) -> NDArray[np.uint64]:
    """``(I N + J) << shift | entry`` (``packed``) or ``I N + J`` of every local node pair
    ``(I, J)`` of every cell, cell by cell (``mult = N << shift``)."""
    nraw = sum(nodes.shape[0] * nodes.shape[1] ** 2 for _v, nodes in groups)
    keys = np.empty(nraw, dtype=np.uint64)
    at = 0
    for _v, nodes in groups:
        m, L = nodes.shape
        u = nodes.astype(np.uint64)
        for a in range(0, m, _KEY_BLOCK):
            nb = u[a : a + _KEY_BLOCK]
            mb = len(nb)
            hi = nb * np.uint64(mult)
            lo = nb << np.uint64(shift)
            if packed:  # the entry index, split between the two broadcast operands
                cell = np.arange(mb, dtype=np.uint64)[:, None] * np.uint64(L * L)
                hi += cell + np.uint64(at + a * L * L)
                hi += np.arange(L, dtype=np.uint64) * np.uint64(L)
                lo += np.arange(L, dtype=np.uint64)
            out = keys[at + a * L * L : at + (a + mb) * L * L].reshape(mb, L, L)
            np.add(hi[:, :, None], lo[:, None, :], out=out)
        at += m * L * L
    return keys


def _row_steps(
    out: NDArray[np.int64], bptr: NDArray[np.int64], step: NDArray[np.int64], inc: int = 0
) -> NDArray[np.int64]:
    """``out[p] = inc p + sum_(I' <= I) step_I'`` for the entries ``p`` of row ``I`` (rows
    from ``bptr``, none empty), in place: a running sum, no array repeated row by row."""
    out.fill(inc)
    out[0] = 0
    out[bptr[:-1]] += step
    return np.cumsum(out, out=out)


def _pattern(n_nodes: int, groups: list[tuple[NDArray[np.int64], NDArray[np.int64]]]) -> _Pattern:
    """The sorted CSR pattern from the node pairs of every cell, by one sort.

    The dofs come in 2 x 2 blocks (two components per node), so the pairs of nodes are
    sorted (``n_nodes^2`` keys, with the entry index packed in the low bits when it fits
    in :data:`PACK_BITS` bits: a plain sort, no argsort), and row ``2 I + c`` of the scalar
    matrix lists the columns ``2 J, 2 J + 1`` of the block row ``I``: the entry
    ``(2 I + c, 2 J + c')`` of block ``p`` (of row ``I``, length ``len_I``, start
    ``bptr_I``) is at ``2 p + 2 bptr_I + 2 c len_I + c'``.
    """
    N = n_nodes
    nraw = sum(nodes.shape[0] * nodes.shape[1] ** 2 for _v, nodes in groups)
    ibits = max(nraw - 1, 1).bit_length()
    packed = (N * N - 1).bit_length() + ibits <= PACK_BITS
    index = np.int32 if nraw < 2**31 else np.int64
    bpos = np.empty(nraw, dtype=index)
    if packed:
        keys = _pair_keys(groups, N << ibits, ibits, True)
        keys.sort()
        skey, order = keys, None
    else:
        keys = _pair_keys(groups, N, 0, False)
        order = np.argsort(keys)
        skey = keys[order]
    del keys
    # block by block (cache-sized temporaries): the entry indices, the distinct keys, their
    # ids at the entries, and the distinct keys moved to the front of the sorted array
    nnzb, last = 0, None
    mask = np.uint64((1 << ibits) - 1)
    for a in range(0, nraw, _SORT_BLOCK):
        blk = skey[a : a + _SORT_BLOCK]
        if order is None:
            entry = np.bitwise_and(blk, mask).view(np.int64)
            np.right_shift(blk, np.uint64(ibits), out=blk)
        else:
            entry = order[a : a + _SORT_BLOCK]
        new = np.empty(len(blk), dtype=bool)
        new[0] = last is None or blk[0] != last
        np.not_equal(blk[1:], blk[:-1], out=new[1:])
        uid = np.cumsum(new, dtype=index)
        np.add(uid, nnzb - 1, out=uid)
        bpos[entry] = uid
        last = blk[-1]
        distinct = blk[new]
        skey[nnzb : nnzb + len(distinct)] = distinct
        nnzb += len(distinct)
    del order
    ukey = skey[:nnzb]
    work = np.empty(nnzb, dtype=np.int64)
    bptr = np.searchsorted(ukey, np.arange(N + 1, dtype=np.uint64) * np.uint64(N))
    blen = np.diff(bptr)
    indptr = np.empty(2 * N + 1, dtype=np.int64)
    indptr[0] = 0
    indptr[1::2] = 4 * bptr[:-1] + 2 * blen
    indptr[2::2] = 4 * bptr[1:]
    # both scalar rows of block row I list (2 J, 2 J + 1): one 64-bit word holds the int32
    # pair, 2 J + (2 J + 1) 2^32 = (I N + J) c + 2^32 - I N c mod 2^64, c = 2 + 2^33 (2 J 2^32
    # + 2 J + 1 = ... + 1 - I N c if the high half comes first)
    c = np.uint64(2 + 2**33)
    pair = np.multiply(ukey, c, out=ukey)
    rows = np.arange(N, dtype=np.uint64)
    rows *= np.uint64(N) * c
    _row_steps(work, bptr, -np.diff(rows, prepend=np.uint64(0)).view(np.int64))
    work += 1 if sys.byteorder == "big" else 2**32
    pair += work.view(np.uint64)
    # the first copy of entry p of row I at p + bptr_I, the second at p + bptr_(I+1)
    indices = np.empty(4 * nnzb, dtype=np.int32)
    ind64 = indices.view(np.uint64)
    slot = _row_steps(work, bptr, np.concatenate([[0], blen[:-1]]), 1)
    ind64[slot] = pair
    ind64[_row_steps(work, bptr, blen, 1)] = pair
    return _Pattern(indptr, indices, bpos, bptr)


def stiffness2(
    mesh: Mesh,
    material: Material,
    stabilization: str = "paper",
    cells: NDArray[np.int64] | None = None,
) -> sp.csr_matrix:
    """Assemble ``a_h`` (3.11) of k = 2 on all dofs.

    The CSR pattern and the place of every local entry in it come first from the mesh
    (:func:`_pattern`, one sort of the node pairs); the local matrices are then built by
    vertex count in batches of :data:`CHUNK` cells (:func:`element_stiffness_into`, with
    reused buffers) and added into the CSR data batch by batch (``np.add.at`` on the
    precomputed places, the two columns of a node as one complex number: cache-resident
    batches, no array of all entries). The result is
    the canonical CSR matrix (sorted indices, no duplicates) of the sum of the local
    matrices. ``cells`` (ids) assembles the sum over those cells only (one MPI rank's
    part), in the same global numbering.
    """
    _check_stabilization(stabilization)
    num = numbering2(mesh)
    ndof = num.n_dofs
    groups = _cell_nodes(mesh)
    if cells is not None:
        keep = members(cells, mesh.n_cells)
        chosen = [keep[ids] for ids, _verts in mesh.groups.values()]
        groups = [(v[k], nod[k]) for (v, nod), k in zip(groups, chosen, strict=True)]
        groups = [g for g in groups if len(g[0])]
        # the pattern wants every node row filled: the cells' nodes numbered 0, 1, ...
        used = _unique(np.concatenate([nod.ravel() for _v, nod in groups] + [np.zeros(0, int)]))
        compact = np.full(ndof // 2, -1, dtype=np.int64)
        compact[used] = np.arange(len(used))
        groups = [(v, compact[nod]) for v, nod in groups]
        if not groups:
            return sp.csr_matrix((ndof, ndof))
        local = _stiffness2_nodes(mesh, material, stabilization, groups, 2 * len(used)).tocoo()
        dof = np.empty(2 * len(used), dtype=np.int64)
        dof[0::2], dof[1::2] = 2 * used, 2 * used + 1
        return sp.csr_matrix((local.data, (dof[local.row], dof[local.col])), shape=(ndof, ndof))
    return _stiffness2_nodes(mesh, material, stabilization, groups, ndof)


def _stiffness2_nodes(
    mesh: Mesh,
    material: Material,
    stabilization: str,
    groups: list[tuple[NDArray[np.int64], NDArray[np.int64]]],
    ndof: int,
) -> sp.csr_matrix:
    """:func:`stiffness2` of the cells of ``groups`` (vertex ids, node ids), on the
    ``ndof / 2`` nodes that they number (every one in some cell)."""
    pat = _pattern(ndof // 2, groups)
    bstart, blen = pat.bptr[:-1], np.diff(pat.bptr)
    data = np.zeros(len(pat.indices))
    # the two columns (2 J, 2 J + 1) of a scalar row are adjacent in the data and in the
    # local matrices: summed as one complex number, half the places
    pairs = data.view(np.complex128)
    at = 0  # in node pairs
    for verts, nodes in groups:
        m_all, L = nodes.shape
        nd = 2 * L
        mc = min(CHUNK, m_all)
        work = ElementWork(mc, (L - 1) // 2)
        K_buf, pos_buf = np.empty((mc, nd, nd)), np.empty((mc, L, 2, L), dtype=np.intp)
        row_buf = np.empty((mc, L, 2), dtype=np.intp)
        for a in range(0, m_all, CHUNK):
            v, nod = verts[a : a + CHUNK], nodes[a : a + CHUNK]
            m = len(v)
            K, P, row = K_buf[:m], pos_buf[:m], row_buf[:m]
            element_stiffness_into(mesh.points[v], material, stabilization, K, work)
            # local dofs (2 l + c, 2 l' + c'), c' = 0, 1 -> pair bpos + bptr_I + c len_I
            np.take(bstart, nod, out=row[:, :, 0])
            np.add(row[:, :, 0], blen[nod], out=row[:, :, 1])
            bp = pat.bpos[at : at + m * L * L].reshape(m, L, 1, L)
            np.add(bp, row[:, :, :, None], out=P)
            np.add.at(pairs, P.reshape(-1), K.view(np.complex128).reshape(-1))  # in order
            at += m * L * L
    A = sp.csr_matrix((data, pat.indices, pat.indptr), shape=(ndof, ndof))
    A.has_sorted_indices = True
    A.has_canonical_format = True
    return A


LOAD_RULES = ("paper", "projection")


def body_force_vector2(
    mesh: Mesh,
    f1: Field,
    t: float = 0.0,
    *,
    rule: str = "paper",
    material: Material | None = None,
) -> NDArray[np.float64]:
    """The body-force load of k = 2.

    Parameters
    ----------
    mesh : Mesh
    f1 : Field
    t : float
    rule : {"paper", "projection"}
        ``"paper"`` (Section 3.3, k >= 2): ``<f_1h, v> = sum_K int_K P_0 f1 . v
        = sum_K |K| P_0^K f1 . (cell moment of v)``; only the cell dofs are loaded.
        ``"projection"``: ``<f_1h, v> = sum_K int_K f1 . Pi v``, by the degree-5 rule on the
        fan. Since the cell mean of ``Pi v`` is the cell moment, it equals the paper's load
        for f1 constant on each cell, and ``(f1, v - Pi v) = (f1 - P_0 f1, v - Pi v)`` is
        O(h^3): the L2 error of order 3, where the paper's P_0 load gives order 2 for k = 2
        (docs/method.md, "Second order (k = 2)").
    material : Material
        Needed by ``"projection"`` (Pi of (3.8) depends on it).
    """
    if rule not in LOAD_RULES:
        raise ValueError(f"unknown load rule {rule!r}; expected one of {', '.join(LOAD_RULES)}")
    num = numbering2(mesh)
    F = np.zeros(num.n_dofs)
    if rule == "paper":
        fbar = cell_means(mesh, f1, t, "body force f1")
        F[num.cell_offset :] = (mesh.cell_areas[:, None] * fbar).ravel()
        return F
    if material is None:
        raise ValueError("the 'projection' load rule needs the material (Pi depends on it)")
    for _n, (ids, verts) in mesh.groups.items():
        X = mesh.points[verts]
        lp = local_projection2(X, material)
        pts, w = fan(X).points(5)
        q = basis_values((pts - lp.center[:, None, :]) / lp.h[:, None, None])  # (m, Q, 12, 2)
        f = eval_field(f1, pts.reshape(-1, 2), t, "body force f1").reshape(pts.shape)
        fq = np.einsum("mq,mqc,mqac->ma", w, f, q)  # int_K f1 . q_a
        np.add.at(F, cell_dofs2(mesh, ids, verts), np.einsum("ma,mal->ml", fq, lp.pi))
    return F


def edge_shape_functions(s: NDArray[np.float64]) -> NDArray[np.float64]:
    """The quadratic on an edge from its dofs, at parameters ``s`` in [0, 1]: columns for
    the start value, the end value and the edge mean; shape (len(s), 3).

    With the midpoint value ``(6 mean - v_a - v_b) / 4`` in the Lagrange basis:
    ``phi_a = (1 - s)(1 - 2 s) - s (1 - s)``, ``phi_b = s (2 s - 1) - s (1 - s)``,
    ``phi_mean = 6 s (1 - s)``.
    """
    bub = s * (1.0 - s)
    return np.column_stack([(1 - s) * (1 - 2 * s) - bub, s * (2 * s - 1) - bub, 6.0 * bub])


def edge_load_vector2(
    mesh: Mesh, edges: NDArray[np.int64], f: Field, t: float = 0.0, name: str = "traction f2"
) -> NDArray[np.float64]:
    """``int_E f . v ds`` over the given edges (pairs of vertex ids) by three-point Gauss on
    every edge: exact for f quadratic along the edge (v is quadratic there)."""
    num = numbering2(mesh)
    F = np.zeros(num.n_dofs)
    if len(edges) == 0:
        return F
    edges = np.asarray(edges, dtype=np.int64)
    a, b = mesh.points[edges[:, 0]], mesh.points[edges[:, 1]]
    L = np.linalg.norm(b - a, axis=1)[:, None]
    e = num.edge_offset + 2 * edge_ids(mesh, edges[:, 0], edges[:, 1])
    s, w = GAUSS3
    phi = edge_shape_functions(s)
    for q in range(len(s)):
        val = eval_field(f, (1 - s[q]) * a + s[q] * b, t, name) * (w[q] * L)
        for c in range(2):
            np.add.at(F, 2 * edges[:, 0] + c, phi[q, 0] * val[:, c])
            np.add.at(F, 2 * edges[:, 1] + c, phi[q, 1] * val[:, c])
            np.add.at(F, e + c, phi[q, 2] * val[:, c])
    return F


def traction_vector2(mesh: Mesh, f2: Field, t: float = 0.0) -> NDArray[np.float64]:
    """``int_{Gamma_N} f2 . v ds`` on the traction part (k = 2)."""
    return edge_load_vector2(mesh, mesh.part_edges("traction"), f2, t)


def facet_dofs2(mesh: Mesh, edges: NDArray[np.int64]) -> tuple[NDArray[np.int64], ...]:
    """For each component, the sorted dofs on the closure of the given edges (vertex values
    and edge means): the dofs to clamp or prescribe on a part."""
    num = numbering2(mesh)
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    verts = _unique(edges)
    e = _unique(edge_ids(mesh, edges[:, 0], edges[:, 1]))
    return tuple(np.concatenate([2 * verts + c, num.edge_offset + 2 * e + c]) for c in range(2))


def interpolate2(mesh: Mesh, u: Field, t: float = 0.0) -> NDArray[np.float64]:
    """The dofs of a displacement field: vertex values, edge means (three-point Gauss, exact
    for quintics along the edge) and cell means (the degree-5 rule on the fan)."""
    num = numbering2(mesh)
    out = np.empty(num.n_dofs)
    out[: num.edge_offset] = eval_field(u, mesh.points, t, "u").ravel()
    E = mesh.edges
    a, b = mesh.points[E[:, 0]], mesh.points[E[:, 1]]
    s, w = GAUSS3
    mean = sum(w[q] * eval_field(u, (1 - s[q]) * a + s[q] * b, t, "u") for q in range(len(s)))
    out[num.edge_offset : num.cell_offset] = np.asarray(mean).ravel()
    cm = np.zeros((mesh.n_cells, 2))
    for _n, (ids, verts) in mesh.groups.items():
        fn = fan(mesh.points[verts])
        pts, wt = fn.points(5)
        val = eval_field(u, pts.reshape(-1, 2), t, "u").reshape(pts.shape)
        cm[ids] = np.einsum("mq,mqc->mc", wt, val) / fn.area.sum(axis=1)[:, None]
    out[num.cell_offset :] = cm.ravel()
    return out


class P2Fields(NamedTuple):
    """A quadratic field per cell (e.g. ``Pi u`` for k = 2): ``sum_a coef[k, a] q_a`` in the
    basis :data:`vemwear.vem.local2.BASIS` about ``center[k]`` with scale ``h[k]``."""

    coef: NDArray[np.float64]  # (n_cells, 12)
    center: NDArray[np.float64]  # (n_cells, 2)
    h: NDArray[np.float64]  # (n_cells,)

    def at(
        self, points: ArrayLike, cells: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Values (q, 2) and gradients (q, 2, 2), ``[i, j] = d_j u_i``, of the field of
        ``cells[j]`` at ``points[j]``."""
        x = np.asarray(points, dtype=float).reshape(-1, 2)
        c = np.asarray(cells, dtype=np.int64)
        xi = (x - self.center[c]) / self.h[c][:, None]
        val = np.einsum("qa,qac->qc", self.coef[c], basis_values(xi))
        grad = np.einsum("qa,qacd->qcd", self.coef[c], basis_gradients(xi, self.h[c]))
        return val, grad


def project2(mesh: Mesh, material: Material, u: ArrayLike) -> P2Fields:
    """``Pi u`` (3.8) with the k = 2 rigid-motion conditions on every cell, from the global
    dofs ``u`` (``numbering2(mesh).n_dofs`` entries)."""
    v = np.asarray(u, dtype=float).reshape(-1)
    num = numbering2(mesh)
    if v.size != num.n_dofs:
        raise ValueError(f"project2: u has {v.size} entries, expected {num.n_dofs}")
    nc = mesh.n_cells
    coef, center, h = np.zeros((nc, 12)), np.zeros((nc, 2)), np.zeros(nc)
    for _n, (ids, verts) in mesh.groups.items():
        lp = local_projection2(mesh.points[verts], material)
        coef[ids] = np.einsum("mal,ml->ma", lp.pi, v[cell_dofs2(mesh, ids, verts)])
        center[ids], h[ids] = lp.center, lp.h
    return P2Fields(coef, center, h)
