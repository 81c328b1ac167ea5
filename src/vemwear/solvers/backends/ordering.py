"""Fill-reducing orderings that keep a given set of unknowns last.

Geometric nested dissection (George 1973): split the vertices at the median of
their longer coordinate extent, take as separator the vertices of one half that
touch the other half, order ``[left, right, separator]`` and recurse. The
vertices asked to come last (the contact nodes) are left out of the recursion and
appended at the end, so the trailing block of the factors is the Schur complement
onto them.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray


def _neighbour_hits(adj: sp.csr_matrix, rows: NDArray[np.int64], flag: NDArray[np.bool_]):
    """For every vertex in ``rows``: does it have a neighbour with ``flag`` set?"""
    start, stop = adj.indptr[rows], adj.indptr[rows + 1]
    cnt = stop - start
    owner = np.repeat(np.arange(len(rows)), cnt)
    offs = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    nbrs = adj.indices[np.repeat(start, cnt) + offs]
    hit = np.zeros(len(rows), dtype=bool)
    np.logical_or.at(hit, owner, flag[nbrs])
    return hit


def nested_dissection(
    adj: sp.csr_matrix,
    points: NDArray[np.float64],
    last: NDArray[np.int64] | None = None,
    leaf: int = 64,
) -> NDArray[np.int64]:
    """Vertex permutation by geometric nested dissection, with ``last`` at the end.

    Parameters
    ----------
    adj : (n, n) sparse, symmetric pattern of the vertex graph
    points : (n, 2) vertex coordinates
    last : vertex ids to order last, in the given order
    leaf : subsets of at most this many vertices are not split further

    Returns
    -------
    (n,) array: ``order[k]`` is the vertex eliminated k-th.
    """
    n = adj.shape[0]
    adj = sp.csr_matrix(adj)
    last = np.zeros(0, np.int64) if last is None else np.asarray(last, dtype=np.int64)
    keep = np.ones(n, dtype=bool)
    keep[last] = False
    flag = np.zeros(n, dtype=bool)
    blocks: list[NDArray[np.int64]] = []
    stack: list[tuple[NDArray[np.int64], bool]] = [(np.flatnonzero(keep), False)]
    # iterative post-order: a subset is emitted as [left, right, separator]
    while stack:
        ids, emit = stack.pop()
        if emit or len(ids) <= leaf:
            blocks.append(ids)
            continue
        p = points[ids]
        ax = int(np.argmax(p.max(axis=0) - p.min(axis=0)))
        order = np.argsort(p[:, ax], kind="stable")
        left = np.zeros(len(ids), dtype=bool)
        left[order[: len(ids) // 2]] = True
        L, R = ids[left], ids[~left]
        flag[R] = True
        on_sep = _neighbour_hits(adj, L, flag)
        flag[R] = False
        # pushed in reverse: left is processed (and emitted) first, separator last
        stack.append((L[on_sep], True))
        stack.append((R, False))
        stack.append((L[~on_sep], False))
    return np.concatenate([*blocks, last])
