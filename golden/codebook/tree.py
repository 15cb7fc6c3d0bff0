"""The paper's greedy tree-structured VQ (TSVQ): the tree, its codebook, tree-search encoding.

Contract: ``tsvq_tree`` grows a binary tree from one cell holding every distinct weighted
vector, splitting the leaf of largest total squared error (or of largest gain) until k leaves;
``tsvq`` returns its leaf centroids, left to right, padded in ``np.resize`` order when there
are fewer than k distinct vectors (then every distinct vector appears exactly).  Deterministic
for a seed.  ``TsvqTree.encode`` is the tree search (ties go left), not the full search.
"""
from __future__ import annotations

import heapq
from dataclasses import dataclass

import numpy as np

from .cells import centroids
from .inputs import as_vectors, check_k, pad, prepare, wmean
from .split import split_cell, split_padded
from .workers import one_blas_thread

__all__ = ["TsvqTree", "tsvq_build", "tsvq_tree", "tsvq"]

_GROUP_ROWS = 4096  # padded rows per split_padded call (measured best among 1024..16384)

@dataclass
class TsvqTree:
    """A binary TSVQ tree.

    ``centroids`` (n_nodes, d) float64 node centroids (node 0 is the root); ``left``/``right``
    (n_nodes,) int64 children, -1 at leaves; ``leaf`` (n_nodes,) int64 codeword index of a leaf,
    -1 at internal nodes.  ``codebook`` (k, d) float64 are the leaf centroids in left-to-right
    order (then ``np.resize`` padding when there were fewer than k distinct vectors).
    """

    centroids: np.ndarray
    left: np.ndarray
    right: np.ndarray
    leaf: np.ndarray
    codebook: np.ndarray

    @property
    def depth(self) -> int:
        depth = np.zeros(len(self.left), dtype=np.int64)
        for p in range(len(self.left)):  # parents are created before their children
            if self.left[p] >= 0:
                depth[self.left[p]] = depth[self.right[p]] = depth[p] + 1
        return int(depth.max())

    def encode(self, vectors) -> np.ndarray:
        """Tree-search encoding: from the root, descend to the child whose centroid is nearer
        (exact float64 squared distance; ties go left).  Returns int64 (N,) codeword indices.
        Cost O(N d depth) instead of O(N d k); the result need not be the full-search nearest."""
        x = as_vectors(vectors)
        if x.shape[1] != self.centroids.shape[1]:
            raise ValueError("dimension mismatch")
        node = np.zeros(x.shape[0], dtype=np.int64)
        act = np.flatnonzero(self.left[node] >= 0)
        while act.size:
            nd = node[act]
            xa = x[act]
            dl = xa - self.centroids[self.left[nd]]
            dr = xa - self.centroids[self.right[nd]]
            go_r = np.sum(dr * dr, axis=1) < np.sum(dl * dl, axis=1)
            node[act] = np.where(go_r, self.right[nd], self.left[nd])
            act = act[self.left[node[act]] >= 0]
        return self.leaf[node]


@one_blas_thread
def tsvq_build(u, wu, k, seed, criterion="distortion", sample=2048, dtype=np.float32):
    """Greedy TSVQ on distinct weighted vectors.

    criterion "distortion" (the paper's rule): split the leaf of largest total squared error.
    criterion "gain": split the leaf whose split reduces the total squared error most (greedy
    tree growing, Riskin & Gray 1991; evaluated lazily, since a gain never exceeds the leaf's
    error).  Ties go to the older leaf.  Stops at k leaves or when no leaf can be split.

    A leaf's split depends only on its vectors and its node number (seeded start vector and
    sample), not on when it is computed, so splits are computed ahead, in batches: when the
    greedy order reaches a leaf whose split is not known, the splits of every leaf whose error is
    at least the (k-1)-th largest error of the nodes made so far are computed at once (a child's
    error never exceeds its parent's, so no leaf below that is split first; with the "gain" rule
    the batch is only a guess, and a split a batch missed is computed when the order reaches it).
    Leaves of at most ``sample`` vectors are split in padded groups of similar sizes
    (:func:`.split.split_padded`, about ``_GROUP_ROWS`` padded rows a group; a split computed in
    a group can differ from one computed alone only in the rounding of its sums), larger ones
    one by one on a sample.  The splits work in ``dtype`` (float32: half the memory traffic; the
    cuts and errors are those of float32 sums; a cell whose rows float32 cannot tell apart is
    split in float64); the centroids of the finished tree are then the float64 weighted means
    of their vectors (a one-row leaf's is that row, exactly).  The build runs on one thread: its
    numpy calls are too short to leave the GIL for long, and two worker threads measured no
    faster (retina 4x4 k = 1024; 131,072 vectors at k = 4096).
    Deterministic for a seed.
    Returns (TsvqTree, labels of the distinct vectors)."""
    if criterion not in ("distortion", "gain"):
        raise ValueError(f"unknown TSVQ split criterion {criterion!r}")
    m_, d = u.shape
    v0 = np.random.default_rng(seed).standard_normal((2 * k + 1, d))
    uw = u.astype(dtype)  # the padded groups' working copy
    cent, rows, left, right, sse = [], [], [], [], []
    rec = {}
    heap = []

    def new_leaf(r, c, e):
        cid = len(cent)
        cent.append(c)
        rows.append(r)
        left.append(-1)
        right.append(-1)
        sse.append(e)
        if r.size > 1:  # rows are distinct: one row = constant leaf
            heapq.heappush(heap, (-e, cid, False))

    def split_group(ids):
        n = np.array([rows[i].size for i in ids])
        idx = np.empty((n.size, int(n.max())), dtype=np.int64)
        for q, i in enumerate(ids):  # padding repeats the cell's last row (weight 0 inside)
            idx[q, : n[q]] = rows[i]
            idx[q, n[q]:] = rows[i][-1]
        return split_padded(uw, wu, idx, n, np.array([cent[i] for i in ids]), v0[ids])

    def split_one(i):
        rng = lambda: np.random.default_rng([seed, i])  # noqa: E731
        r = split_cell(uw[rows[i]], wu[rows[i]], cent[i], v0[i], rng, sample=sample)
        if r is None and uw.dtype != u.dtype:  # rows distinct in float64 but not in dtype
            r = split_cell(u[rows[i]], wu[rows[i]], cent[i], v0[i], rng, sample=sample)
        return r

    def compute(nids):
        nids = np.array(nids, dtype=np.int64)
        size = np.array([rows[i].size for i in nids])
        order = np.argsort(size, kind="stable")
        small, sz = nids[order], size[order]
        small, sz = small[sz <= sample], sz[sz <= sample]
        if small.size:
            # groups of consecutive (by size) cells of at most _GROUP_ROWS padded rows
            groups, g0 = [], 0
            for g in range(1, small.size + 1):
                if g == small.size or (g + 1 - g0) * sz[g] > _GROUP_ROWS:
                    groups.append(small[g0:g])
                    g0 = g
            for g in groups:
                rec.update(zip(g.tolist(), split_group(g)))
        for i in nids.tolist():
            if rec.get(i) is None:
                rec[i] = split_one(i)

    def threshold():
        """The (k-1)-th largest error of the nodes made so far (-inf while there are fewer)."""
        if len(sse) < k - 1:
            return -np.inf
        return float(np.partition(np.array(sse), len(sse) - (k - 1))[len(sse) - (k - 1)])

    root_c = wmean(u, wu) if m_ > 1 else u[0].copy()
    diff = u - root_c
    new_leaf(np.arange(m_), root_c, float(wu @ np.einsum("ij,ij->i", diff, diff)))
    n_leaves = 1
    while n_leaves < k and heap:
        key, nid, exact = heapq.heappop(heap)
        if nid not in rec:
            t = threshold()
            compute([nid] + [e[1] for e in heap if e[1] not in rec and -e[0] >= t])
        r = rec.pop(nid)
        if r is None:
            continue
        if criterion == "gain" and not exact:
            heapq.heappush(heap, (-(sse[nid] - r[3] - r[4]), nid, True))
            rec[nid] = r
            continue
        mask, c0, c1, e0, e1 = r
        left[nid] = len(cent)
        right[nid] = len(cent) + 1
        new_leaf(rows[nid][~mask], c0, e0)
        new_leaf(rows[nid][mask], c1, e1)
        n_leaves += 1
    left = np.array(left, dtype=np.int64)
    right = np.array(right, dtype=np.int64)
    # leaves numbered left to right (depth-first); nodes are numbered parents-first
    leaf = np.full(len(left), -1, dtype=np.int64)
    leaf_nodes = []
    stack = [0]
    while stack:
        nid = stack.pop()
        if left[nid] < 0:
            leaf[nid] = len(leaf_nodes)
            leaf_nodes.append(nid)
        else:
            stack.append(right[nid])
            stack.append(left[nid])
    # members of each leaf -> codeword index
    labels = np.empty(m_, dtype=np.int64)
    labels[np.concatenate([rows[i] for i in leaf_nodes])] = np.repeat(
        np.arange(len(leaf_nodes)), [rows[i].size for i in leaf_nodes])
    cent = _node_centroids(u, wu, labels, rows, left, right, leaf_nodes)
    codebook = pad(cent[leaf_nodes], k)
    return TsvqTree(cent, left, right, leaf, codebook), labels


def _node_centroids(u, wu, labels, rows, left, right, leaf_nodes):
    """float64 weighted mean of every node's vectors (a one-row leaf's is that row, exactly).
    ``leaf_nodes``: the leaves left to right, ``labels`` each vector's leaf in that order; a
    leaf's sums are :func:`.cells.centroids`'s, and an internal node's leaves are a contiguous
    run of them, so its sums are a difference of prefix sums over the leaves (exact for integer
    texels and weights, whose sums stay integers below 2^53; for other data, to a few ulps of
    the total).  Internal centroids serve the tree search only."""
    nn = left.size
    lw, ls = centroids(u, wu, labels, len(leaf_nodes))
    pw = np.concatenate([[0.0], np.cumsum(lw)])
    ps = np.vstack([np.zeros((1, u.shape[1])), np.cumsum(ls, axis=0)])
    lo, hi = [0] * nn, [0] * nn
    for q, i in enumerate(leaf_nodes):
        lo[i], hi[i] = q, q + 1
    lft, rgt = left.tolist(), right.tolist()
    for p in range(nn - 1, -1, -1):  # children are numbered after their parent
        if lft[p] >= 0:
            lo[p], hi[p] = lo[lft[p]], hi[rgt[p]]
    lo, hi = np.array(lo), np.array(hi)
    cent = (ps[hi] - ps[lo]) / (pw[hi] - pw[lo])[:, None]
    cent[leaf_nodes] = ls / lw[:, None]  # a leaf's own sums
    one = [i for i in leaf_nodes if rows[i].size == 1]
    cent[one] = u[[rows[i][0] for i in one]]
    return cent


def tsvq_tree(vectors, k, *, seed=0, weights=None, criterion="distortion") -> TsvqTree:
    """The paper's greedy tree-structured VQ; returns the tree (see :class:`TsvqTree`).

    Starting from one cell holding every (distinct, weighted) vector, repeatedly split the leaf
    of largest total squared error (``criterion="distortion"``, the paper's rule; "gain" splits
    the leaf whose split reduces the error most instead).  A split cuts the cell orthogonally to
    its principal axis (3 power iterations) at the best 1-D two-cluster threshold of the
    projections, then refines the two children with up to 4 weighted 2-means iterations (cells
    of more than 2048 vectors fit the cut on a seeded sample of 2048).  Stops at k leaves (or
    when every leaf holds a single distinct vector).  ``seed`` drives the power-iteration start
    vectors and the samples; the tree is deterministic for a seed."""
    k = check_k(k)
    _, _, u, wu, _ = prepare(vectors, weights)
    return tsvq_build(u, wu, k, seed, criterion)[0]


def tsvq(vectors, k, *, seed=0, weights=None, criterion="distortion") -> np.ndarray:
    """TSVQ codebook: ``(k, d)`` float64, the leaf centroids of :func:`tsvq_tree` (left to
    right).  With >= k distinct vectors the k codewords are distinct; with fewer, every distinct
    vector appears exactly, then repeats.  Encode with :func:`nearest` (full search) or with
    ``tsvq_tree(...).encode`` (tree search, the paper's fast encoder)."""
    return tsvq_tree(vectors, k, seed=seed, weights=weights, criterion=criterion).codebook
