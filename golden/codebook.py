"""Codebook design for the VQ texture encoder: full-search nearest codeword, the paper's
tree-structured VQ (TSVQ) and the generalized Lloyd algorithm (GLA).

numpy and the standard library only (``golden`` is the executable specification).

Conventions shared by every function here
-----------------------------------------
* ``vectors`` is a float array ``(N, d)`` (any real dtype; it is read as float64), N >= 1, finite.
  Blocks of texels flattened row-major are the usual input (d = 12 for 2x2 RGB, 48 for 4x4 RGB...).
* ``weights`` (optional) is ``(N,)``, finite, >= 0, with a positive sum.  A weight multiplies the
  vector's squared error in every distortion sum; identical vectors are merged internally and their
  weights added (so passing duplicates or their count as weight is the same problem).
  Vectors of weight 0 take no part in training but still get an index.
* Codebooks are ``(k, d)`` float64; indices are int64 ``(N,)``.
* Distances are squared Euclidean distances.  The *exact* distance of x to c is
  ``np.sum((x - c) ** 2)`` evaluated in float64; ``nearest`` is exact with respect to it
  (ties go to the lowest index).  Inner loops screen candidates with a float32 GEMM
  (||x||^2 - 2 x.c + ||c||^2 form, on mean-centred data) and settle them in float64.
* Everything is deterministic: the same inputs and seed give the same output bits (for a given
  numpy/BLAS build and thread count, which only affects float32 screening, never the exact
  float64 decisions except for ties that the screening cannot see -- see ``nearest``).
* Degenerate inputs: when there are at most k distinct vectors (of positive weight) every design
  function returns all of them, exactly, followed by repeats (``np.resize`` order) up to k rows;
  the distortion is then 0.
"""
from __future__ import annotations

import heapq
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "nearest",
    "tsvq",
    "tsvq_tree",
    "TsvqTree",
    "gla",
    "GlaResult",
    "design",
    "unique_weighted",
]

_U32 = float(np.finfo(np.float32).eps) / 2.0  # unit roundoff of float32
# Score buffer for the float32 screening GEMM: rows per chunk are chosen so that a chunk of
# scores is about this many bytes (keeps argmax in cache; measured best around 1-2 MiB).
_SCORE_BYTES = 1 << 21
# Hard cap on any temporary (float64 pairs, chunks): well below the 1 GB budget.
_MAX_TEMP_BYTES = 1 << 27


# --------------------------------------------------------------------------------------------
# input handling and deduplication
# --------------------------------------------------------------------------------------------
def _as_vectors(vectors) -> np.ndarray:
    x = np.asarray(vectors)
    if x.ndim != 2 or x.shape[0] < 1 or x.shape[1] < 1:
        raise ValueError(f"vectors must be a non-empty (N, d) array, got shape {x.shape}")
    if not np.issubdtype(x.dtype, np.number) or np.iscomplexobj(x):
        raise ValueError("vectors must be real numbers")
    x = np.ascontiguousarray(x, dtype=np.float64) + 0.0  # copy; -0.0 -> +0.0 for dedup
    if not np.all(np.isfinite(x)):
        raise ValueError("vectors must be finite")
    return x


def _as_weights(weights, n: int) -> np.ndarray:
    if weights is None:
        return np.ones(n, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64).reshape(-1)
    if w.shape[0] != n:
        raise ValueError(f"weights must have shape ({n},), got {np.shape(weights)}")
    if not np.all(np.isfinite(w)) or np.any(w < 0) or not w.sum() > 0:
        raise ValueError("weights must be finite, >= 0 and have a positive sum")
    return w


def _check_k(k) -> int:
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
        raise ValueError(f"k must be a positive integer, got {k!r}")
    return int(k)


def _row_hash(x: np.ndarray) -> np.ndarray:
    """64-bit hash of each row's float64 bit pattern (multiply-xorshift chain)."""
    v = x.view(np.uint64)
    h = np.full(x.shape[0], 0x9E3779B97F4A7C15, dtype=np.uint64)
    mul = np.uint64(0xBF58476D1CE4E5B9)
    with np.errstate(over="ignore"):
        for j in range(x.shape[1]):
            h ^= v[:, j]
            h *= mul
            h ^= h >> np.uint64(31)
    return h


def unique_weighted(x: np.ndarray, w: np.ndarray):
    """Merge identical rows of ``x`` (float64, (N, d)) and add their weights.

    Returns ``(u, wu, inverse)``: the distinct rows ``u`` (M, d) float64 in a deterministic order,
    their summed weights ``wu`` (M,) and ``inverse`` (N,) int64 with ``u[inverse] == x``.
    Rows are compared bit for bit (call with -0.0 already mapped to +0.0).
    """
    n = x.shape[0]
    h = _row_hash(x)
    _, first, inv = np.unique(h, return_index=True, return_inverse=True)
    inv = inv.reshape(-1)
    if np.array_equal(x, x[first][inv]):  # no hash collision: the hash classes are the rows
        u = x[first]
    else:  # a collision (astronomically rare): exact lexicographic dedup
        u, inv = np.unique(x, axis=0, return_inverse=True)
        inv = inv.reshape(-1)
    wu = np.bincount(inv, weights=w, minlength=u.shape[0])
    return u, wu, inv.astype(np.int64, copy=False)


def _prepare(vectors, weights):
    """-> (x (N,d), w (N,), u (M,d) distinct rows with positive weight, wu (M,), inv (N,) or -1)."""
    x = _as_vectors(vectors)
    w = _as_weights(weights, x.shape[0])
    u, wu, inv = unique_weighted(x, w)
    keep = wu > 0
    if not keep.all():
        remap = np.full(u.shape[0], -1, dtype=np.int64)
        remap[keep] = np.arange(int(keep.sum()))
        u, wu, inv = u[keep], wu[keep], remap[inv]
    return x, w, u, wu, inv


def _pad(codebook: np.ndarray, k: int) -> np.ndarray:
    """Repeat rows (np.resize order) up to k rows; the first rows are kept exactly."""
    if codebook.shape[0] == k:
        return codebook
    return np.resize(codebook, (k, codebook.shape[1])).astype(np.float64, copy=False)


# --------------------------------------------------------------------------------------------
# nearest codeword
# --------------------------------------------------------------------------------------------
class _Screen:
    """float32 GEMM screening of codewords: scores s_j = x'.c'_j - |c'_j|^2/2 (primes: centred).

    Larger score = smaller distance (distance = |x'|^2 - 2 s_j).  ``xa`` holds the centred vectors
    in float32 with a trailing column of ones so one GEMM yields the scores.
    """

    def __init__(self, x: np.ndarray, shift: np.ndarray):
        n, d = x.shape
        self.d = d
        self.shift = shift
        self.xa = np.empty((n, d + 1), dtype=np.float32)
        xc = x - shift
        self.xa[:, :d] = xc
        self.xa[:, d] = 1.0
        self.xnorm = np.sqrt(np.einsum("ij,ij->i", xc, xc))

    def codebook(self, c: np.ndarray):
        cc = c - self.shift
        ca = np.empty((self.d + 1, c.shape[0]), dtype=np.float32)
        ca[: self.d] = cc.T
        ca[self.d] = -0.5 * np.einsum("ij,ij->i", cc, cc)
        return ca, float(np.sqrt(np.einsum("ij,ij->i", cc, cc).max()))

    def rows_per_chunk(self, k: int, chunk: int) -> int:
        if chunk and chunk > 0:
            return int(chunk)
        return int(max(32, min(65536, _SCORE_BYTES // (4 * k))))

    def argmax(self, ca: np.ndarray, rows=None, chunk: int = 0) -> np.ndarray:
        """Best screened codeword per vector (first maximum), for all rows or the given subset."""
        k = ca.shape[1]
        xa = self.xa if rows is None else self.xa[rows]
        n = xa.shape[0]
        out = np.empty(n, dtype=np.int64)
        step = self.rows_per_chunk(k, chunk)
        buf = np.empty((min(step, n), k), dtype=np.float32)
        for s in range(0, n, step):
            e = min(n, s + step)
            sc = buf[: e - s]
            np.matmul(xa[s:e], ca, out=sc)
            out[s:e] = sc.argmax(axis=1)
        return out


    def top2(self, ca: np.ndarray, chunk: int = 0):
        """Best and second-best screened codewords per vector (k >= 2)."""
        k = ca.shape[1]
        n = self.xa.shape[0]
        b1 = np.empty(n, dtype=np.int64)
        b2 = np.empty(n, dtype=np.int64)
        step = self.rows_per_chunk(k, chunk)
        buf = np.empty((min(step, n), k), dtype=np.float32)
        for s in range(0, n, step):
            e = min(n, s + step)
            sc = buf[: e - s]
            np.matmul(self.xa[s:e], ca, out=sc)
            best = sc.argmax(axis=1)
            b1[s:e] = best
            sc[np.arange(e - s), best] = -np.inf
            b2[s:e] = sc.argmax(axis=1)
        return b1, b2


def _exact_d2(x: np.ndarray, c: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Exact float64 squared distance of each x[i] to c[idx[i]] (chunked)."""
    n, d = x.shape
    out = np.empty(n, dtype=np.float64)
    step = max(1, _MAX_TEMP_BYTES // (8 * d))
    for s in range(0, n, step):
        e = min(n, s + step)
        diff = x[s:e] - c[idx[s:e]]
        np.einsum("ij,ij->i", diff, diff, out=out[s:e])
    return out


def _nearest_screened(x, c, scr: _Screen, chunk: int = 0):
    """Exact nearest codeword (ties -> lowest index) using float32 screening + float64 settling.

    Error bound of a screened score (x', c' centred; u = 2^-24; GEMM of d+1 terms in float32):
        |s~_j - s_j| <= E = (d + 4) u (|x'| |c'_j| + |c'_j|^2 / 2) (1 + 1e-3)
    so every codeword whose screened score is within 2E of the best screened score is a candidate,
    and the true nearest is always among them.  Rows with a single candidate are decided by the
    screen; the others are settled with exact float64 distances, ties to the lowest index.
    """
    n, d = x.shape
    k = c.shape[0]
    ca, rmax = scr.codebook(c)
    gam = (d + 4) * _U32 * (1 + 1e-3)
    idx = np.empty(n, dtype=np.int64)
    step = scr.rows_per_chunk(k, chunk)
    buf = np.empty((min(step, n), k), dtype=np.float32)
    amb_rows, amb_cols = [], []
    for s in range(0, n, step):
        e = min(n, s + step)
        sc = buf[: e - s]
        np.matmul(scr.xa[s:e], ca, out=sc)
        best = sc.argmax(axis=1)
        idx[s:e] = best
        smax = sc[np.arange(e - s), best]
        margin = (2.0 * gam * (scr.xnorm[s:e] * rmax + 0.5 * rmax * rmax)).astype(np.float32)
        # float32 rounding of the threshold itself: widen by one more ulp-ish step
        thr = smax - margin - np.abs(smax) * np.float32(4 * _U32)
        cand = sc >= thr[:, None]
        ncand = np.count_nonzero(cand, axis=1)
        amb = np.flatnonzero(ncand > 1)
        if amb.size:
            r, cidx = np.nonzero(cand[amb])
            amb_rows.append(amb[r] + s)
            amb_cols.append(cidx)
    if amb_rows:
        r = np.concatenate(amb_rows)
        cc = np.concatenate(amb_cols)
        dd = _exact_d2(x[r], c, cc) if r.size else np.empty(0)
        # per row: smallest exact distance, then lowest codeword index
        order = np.lexsort((cc, dd, r))
        r, cc = r[order], cc[order]
        first = np.ones(r.size, dtype=bool)
        first[1:] = r[1:] != r[:-1]
        idx[r[first]] = cc[first]
    return idx, _exact_d2(x, c, idx)


def nearest(vectors: np.ndarray, codebook: np.ndarray, chunk: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Full-search nearest codeword.

    Parameters: ``vectors`` (N, d) real, ``codebook`` (k, d) real, ``chunk`` rows per distance
    chunk (0 = automatic, about 2 MiB of float32 scores per chunk; memory stays far below 1 GB).

    Returns ``(indices, d2)``: int64 (N,) index of the codeword minimising the exact float64
    squared distance ``sum((x - c) ** 2)``, ties to the lowest index, and float64 (N,) that
    distance.  Exact: a float32 GEMM only screens candidates under a rigorous rounding-error bound;
    close calls are settled in float64.  Deterministic.
    """
    x = _as_vectors(vectors)
    c = np.asarray(codebook, dtype=np.float64)
    if c.ndim != 2 or c.shape[0] < 1 or c.shape[1] != x.shape[1]:
        raise ValueError(f"codebook must be (k, {x.shape[1]}), got shape {c.shape}")
    if not np.all(np.isfinite(c)):
        raise ValueError("codebook must be finite")
    c = np.ascontiguousarray(c)
    shift = c.mean(axis=0)
    return _nearest_screened(x, c, _Screen(x, shift), chunk)


# --------------------------------------------------------------------------------------------
# TSVQ
# --------------------------------------------------------------------------------------------
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
        x = _as_vectors(vectors)
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


def _wmean(x, w):
    return (w @ x) / w.sum()


def _sse(x, w, c):
    diff = x - c
    return float(w @ np.einsum("ij,ij->i", diff, diff))


def _split(x, w, m, rng, n_power=6, n_lloyd=8):
    """Trial split of one cell (x (n, d), weights w, centroid m) into two.

    Initial cut: the hyperplane through the centroid orthogonal to the principal axis (power
    iteration from a seeded random start); then up to ``n_lloyd`` weighted 2-means iterations.
    Returns ``(mask, sse0, sse1)`` -- mask True for the second child, the children's total squared
    errors about their centroids -- or None if the points cannot be separated."""
    xc = x - m
    v = rng.standard_normal(x.shape[1])
    for _ in range(n_power):
        v = (w * (xc @ v)) @ xc
        nv = np.sqrt(v @ v)
        if not nv > 0:
            break
        v /= nv
    mask = (xc @ v) > 0
    if mask.all() or not mask.any():
        # fallback: cut orthogonally to the direction of the farthest point
        far = int(np.argmax(np.einsum("ij,ij->i", xc, xc)))
        mask = (xc @ xc[far]) > 0
        if mask.all() or not mask.any():
            return None
    wt, st = w.sum(), w @ xc
    for _ in range(n_lloyd):
        w1 = np.where(mask, w, 0.0)
        ww1 = w1.sum()
        s1 = w1 @ xc
        c1 = s1 / ww1
        c0 = (st - s1) / (wt - ww1)
        dv = c1 - c0
        new = (xc @ dv) > 0.5 * (c1 @ c1 - c0 @ c0)
        if new.all() or not new.any() or np.array_equal(new, mask):
            break
        mask = new
    w1 = np.where(mask, w, 0.0)
    c1 = _wmean(xc[mask], w[mask])
    c0 = _wmean(xc[~mask], w[~mask])
    diff = xc - np.where(mask[:, None], c1, c0)
    d2 = np.einsum("ij,ij->i", diff, diff)
    return mask, float((w - w1) @ d2), float(w1 @ d2)


def _tsvq_build(u, wu, k, seed, criterion="distortion"):
    """Greedy TSVQ on distinct weighted vectors.

    criterion "distortion" (the paper's rule): split the leaf of largest total squared error.
    criterion "gain": split the leaf whose (trial) split reduces the total squared error most
    (greedy tree growing, Riskin & Gray 1991).  Ties go to the older leaf.  Stops at k leaves or
    when no leaf can be split.  Returns (TsvqTree, labels of the distinct vectors)."""
    if criterion not in ("distortion", "gain"):
        raise ValueError(f"unknown TSVQ split criterion {criterion!r}")
    rng = np.random.default_rng(seed)
    m_, d = u.shape
    order = np.arange(m_)
    xs = u.copy()
    ws = wu.copy()
    cent, start, end, left, right = [], [], [], [], []
    trial = {}
    heap = []

    def new_leaf(a, b):
        xa, wa = xs[a:b], ws[a:b]
        cid = len(cent)
        is_const = bool(np.all(xa == xa[0]))
        c = xa[0].copy() if is_const else _wmean(xa, wa)
        cent.append(c)
        start.append(a)
        end.append(b)
        left.append(-1)
        right.append(-1)
        if is_const:
            return
        sse = _sse(xa, wa, c)
        if criterion == "gain":
            t = _split(xa, wa, c, rng)
            if t is None:
                return
            trial[cid] = t
            heapq.heappush(heap, (-(sse - t[1] - t[2]), cid))
        else:
            heapq.heappush(heap, (-sse, cid))

    new_leaf(0, m_)
    n_leaves = 1
    while n_leaves < k and heap:
        _, nid = heapq.heappop(heap)
        s, e = start[nid], end[nid]
        t = trial.pop(nid, None)
        if t is None:
            t = _split(xs[s:e], ws[s:e], cent[nid], rng)
            if t is None:
                continue
        mask = t[0]
        perm = np.concatenate([np.flatnonzero(~mask), np.flatnonzero(mask)])
        xs[s:e] = xs[s:e][perm]
        ws[s:e] = ws[s:e][perm]
        order[s:e] = order[s:e][perm]
        mid = s + int(np.count_nonzero(~mask))
        left[nid] = len(cent)
        right[nid] = len(cent) + 1
        new_leaf(s, mid)
        new_leaf(mid, e)
        n_leaves += 1
    left = np.array(left, dtype=np.int64)
    right = np.array(right, dtype=np.int64)
    cent = np.array(cent, dtype=np.float64).reshape(-1, d)
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
    leaf_nodes = np.array(leaf_nodes, dtype=np.int64)
    codebook = _pad(cent[leaf_nodes], k)
    # members of each leaf -> codeword index (the leaves' slices tile [0, M) left to right)
    sizes = np.array(end)[leaf_nodes] - np.array(start)[leaf_nodes]
    lab_sorted = np.repeat(np.arange(leaf_nodes.size), sizes)
    labels = np.empty(m_, dtype=np.int64)
    labels[order] = lab_sorted
    return TsvqTree(cent, left, right, leaf, codebook), labels


def tsvq_tree(vectors, k, *, seed=0, weights=None) -> TsvqTree:
    """The paper's greedy tree-structured VQ; returns the tree (see :class:`TsvqTree`).

    Starting from one cell holding every (distinct, weighted) vector, repeatedly split the leaf
    of largest total squared error: cut through its centroid orthogonally to its principal axis,
    then refine the two children with up to 6 weighted 2-means iterations.  Stops at k leaves
    (or when every leaf holds identical vectors).  ``seed`` drives the power-iteration start
    vectors; the result is deterministic for a seed."""
    k = _check_k(k)
    _, _, u, wu, _ = _prepare(vectors, weights)
    return _tsvq_build(u, wu, k, seed)[0]


def tsvq(vectors, k, *, seed=0, weights=None) -> np.ndarray:
    """TSVQ codebook: ``(k, d)`` float64, the leaf centroids of :func:`tsvq_tree`.

    With >= k distinct vectors the k codewords are distinct; with fewer, every distinct vector
    appears exactly, then repeats.  Encode with :func:`nearest` (full search) or with
    ``tsvq_tree(...).encode`` (tree search, the paper's fast encoder)."""
    return tsvq_tree(vectors, k, seed=seed, weights=weights).codebook


# --------------------------------------------------------------------------------------------
# GLA
# --------------------------------------------------------------------------------------------
@dataclass
class GlaResult:
    """Result of :func:`gla`.

    codebook: (k, d) float64.  indices: (N,) int64, exact full-search nearest codeword of every
    input vector (``nearest(vectors, codebook)``).  distortion: weighted mean over vectors of the
    squared error ||x - c||^2 (per vector, not per component) of that final encoding.
    iterations: Lloyd iterations run.  converged: the stop rule fired (False: max_iter reached).
    history: distortion after the initial assignment and after each iteration (non-increasing).
    """

    codebook: np.ndarray
    indices: np.ndarray
    distortion: float
    iterations: int
    converged: bool
    history: list = field(default_factory=list)


def _centroids(u, wu, a, k):
    cnt = np.bincount(a, weights=wu, minlength=k)
    sums = np.empty((k, u.shape[1]), dtype=np.float64)
    for j in range(u.shape[1]):  # one bincount per dimension: O(M d), no loop over vectors
        sums[:, j] = np.bincount(a, weights=wu * u[:, j], minlength=k)
    return cnt, sums


def _repair_empty(u, wu, a, c, cnt, sums, k):
    """Give every empty cell a codeword: take the cells of largest total squared error (SSE)
    and move each one's member farthest from its centroid (ties: lowest vector index) into an
    empty cell as its codeword.  Repeats while empty cells and splittable cells remain.
    Updates a, c, cnt, sums in place; never increases the distortion."""
    while True:
        empty = np.flatnonzero(cnt == 0)
        if empty.size == 0:
            return
        full = cnt > 0
        c[full] = sums[full] / cnt[full, None]
        d2 = _exact_d2(u, c, a)
        sse = np.bincount(a, weights=wu * d2, minlength=k)
        sse[~full] = -1.0
        donors = np.flatnonzero(sse > 0)
        if donors.size == 0:
            return
        # largest SSE first, ties to the lowest cell index
        donors = donors[np.lexsort((donors, -sse[donors]))][: empty.size]
        empty = empty[: donors.size]
        members = np.flatnonzero(np.isin(a, donors))
        order = np.lexsort((members, -d2[members], a[members]))
        members = members[order]
        first = np.ones(members.size, dtype=bool)
        first[1:] = a[members[1:]] != a[members[:-1]]
        pick = members[first]  # farthest member of each donor, sorted by donor cell index
        dcell = a[pick]
        target = np.empty_like(dcell)
        target[np.searchsorted(dcell, donors)] = empty  # donor rank r -> r-th empty cell
        a[pick] = target
        c[target] = u[pick]
        cnt[dcell] -= wu[pick]
        sums[dcell] -= wu[pick, None] * u[pick]
        cnt[target] = wu[pick]
        sums[target] = wu[pick, None] * u[pick]
        # re-derive the touched cells exactly to avoid drift from the subtractions
        touched = np.zeros(k, dtype=bool)
        touched[dcell] = True
        sel = touched[a]
        if sel.any():
            cnt_t, sums_t = _centroids(u[sel], wu[sel], a[sel], k)
            cnt[touched] = cnt_t[touched]
            sums[touched] = sums_t[touched]


def _lloyd(u, wu, k, c, a, d2, scr, tol, budget, chunk=0):
    """Lloyd iterations from codebook ``c`` and an assignment ``a`` made against it (``d2``: exact
    squared distances of u to c[a]).  Stops by the LBG rule (relative decrease <= tol), at a fixed
    point, at distortion 0 or after ``budget`` iterations.

    Incremental assignment (exact in exact arithmetic): a vector whose codeword did not move can
    only be captured by a codeword that moved, so it is screened against the moved codewords only;
    vectors of moved cells get a full search.  A move is accepted only if the exact float64
    distance strictly decreases, so the distortion never increases.
    Returns (c, a, d2, history, iterations, converged); a and d2 are updated copies."""
    a = a.copy()
    d2 = d2.copy()
    wsum = wu.sum()
    dist = float(wu @ d2) / wsum
    hist = []
    it, conv = 0, False
    while True:
        if dist == 0.0:
            conv = True
            break
        if it >= budget:
            break
        it += 1
        a_prev = a.copy()
        cnt, sums = _centroids(u, wu, a, k)
        c_new = c.copy()
        _repair_empty(u, wu, a, c_new, cnt, sums, k)
        full = cnt > 0
        c_new[full] = sums[full] / cnt[full, None]
        moved = np.any(c_new != c, axis=1)
        if not moved.any():  # fixed point: nothing can change any more
            conv = True
            hist.append(dist)
            break
        pm = moved[a] | (a != a_prev)
        rows_m = np.flatnonzero(pm)
        d_old = d2
        d_old[rows_m] = _exact_d2(u[rows_m], c_new, a[rows_m])
        ca, _ = scr.codebook(c_new)
        cand = a.copy()
        cand[rows_m] = scr.argmax(ca, rows=rows_m, chunk=chunk)
        mv = np.flatnonzero(moved)
        rows_s = np.flatnonzero(~pm)
        if rows_s.size:
            cand[rows_s] = mv[scr.argmax(np.ascontiguousarray(ca[:, mv]), rows=rows_s, chunk=chunk)]
        ch = np.flatnonzero(cand != a)
        d_c = _exact_d2(u[ch], c_new, cand[ch])
        acc = d_c < d_old[ch]
        a[ch[acc]] = cand[ch[acc]]
        d2 = d_old
        d2[ch[acc]] = d_c[acc]
        new = float(wu @ d2) / wsum
        c = c_new
        hist.append(new)
        if dist - new <= tol * new:
            conv = True
            dist = new
            break
        dist = new
    return c, a, d2, hist, it, conv


def _migrate(u, wu, k, c, scr, frac, chunk=0):
    """One batch of ELBG-style codeword migrations (Patane & Russo 2001, vectorised).

    Utility of a codeword = the weighted error increase if it were removed (its vectors falling
    to their second-nearest codeword).  The lowest-utility codewords are moved onto the member
    farthest from its codeword of the cells with the largest such error (the empty-cell repair
    rule), pairing lowest utility with largest error while utility < 2 x that error, at most
    ``frac * k`` moves.  Returns (new codebook, assignment, exact d2) or None if nothing moves."""
    ca, _ = scr.codebook(c)
    b1, b2 = scr.top2(ca, chunk)
    d1 = _exact_d2(u, c, b1)
    db = _exact_d2(u, c, b2)
    sw = db < d1
    b1, b2 = np.where(sw, b2, b1), np.where(sw, b1, b2)
    d1, db = np.where(sw, db, d1), np.where(sw, d1, db)
    util = np.bincount(b1, weights=wu * (db - d1), minlength=k)
    err = wu * d1
    order = np.lexsort((np.arange(u.shape[0]), -err, b1))
    first = np.ones(order.size, dtype=bool)
    first[1:] = b1[order[1:]] != b1[order[:-1]]
    far = np.full(k, -1, dtype=np.int64)
    gain = np.zeros(k)
    far[b1[order[first]]] = order[first]
    gain[b1[order[first]]] = err[order[first]]
    m = max(1, int(frac * k))
    rem = np.argsort(util, kind="stable")[:m]
    rec = np.argsort(-gain, kind="stable")
    rec = rec[~np.isin(rec, rem)][: rem.size]
    rem = rem[: rec.size]
    ok = (util[rem] < 2.0 * gain[rec]) & (gain[rec] > 0)
    rem, rec = rem[ok], rec[ok]
    if rem.size == 0:
        return None
    c_new = c.copy()
    c_new[rem] = u[far[rec]]
    # assignment against the new codebook: the old nearest unless the vector's codeword was
    # removed (full search) or a new codeword is closer
    removed = np.zeros(k, dtype=bool)
    removed[rem] = True
    a = b1.copy()
    d2 = d1.copy()
    pm = np.flatnonzero(removed[a])
    ca, _ = scr.codebook(c_new)
    a[pm] = scr.argmax(ca, rows=pm, chunk=chunk)
    d2[pm] = _exact_d2(u[pm], c_new, a[pm])
    rs = np.flatnonzero(~removed[b1])
    cand = rem[scr.argmax(np.ascontiguousarray(ca[:, rem]), rows=rs, chunk=chunk)]
    dc = _exact_d2(u[rs], c_new, cand)
    acc = dc < d2[rs]
    a[rs[acc]] = cand[acc]
    d2[rs[acc]] = dc[acc]
    return c_new, a, d2


def _gla_core(u, wu, k, c0, max_iter, tol, migrate, frac=0.1, chunk=0):
    """GLA on distinct weighted vectors; returns (codebook, history, iterations, converged)."""
    c = np.array(c0, dtype=np.float64, copy=True)
    wsum = wu.sum()
    scr = _Screen(u, _wmean(u, wu))
    a, d2 = _nearest_screened(u, c, scr, chunk)
    hist = [float(wu @ d2) / wsum]
    c, a, d2, h, it, conv = _lloyd(u, wu, k, c, a, d2, scr, tol, max_iter, chunk)
    hist += h
    rounds = 0
    while conv and rounds < migrate and k >= 2 and it < max_iter and hist[-1] > 0:
        rounds += 1
        trial = _migrate(u, wu, k, c, scr, frac, chunk)
        if trial is None:
            break
        c_t, a_t, d2_t, h, it_t, conv_t = _lloyd(u, wu, k, *trial, scr, tol, max_iter - it, chunk)
        it += it_t
        d_t = float(wu @ d2_t) / wsum
        if not d_t < hist[-1]:
            break  # rejected: keep the previous codebook (converged by the stop rule)
        improve = hist[-1] - d_t
        c, a, d2, conv = c_t, a_t, d2_t, conv_t
        hist.append(d_t)
        if improve <= tol * d_t:
            break
    return c, hist, it, conv


def gla(vectors, k, *, seed=0, weights=None, init=None, max_iter=100, tol=1e-4,
        migrate=8) -> GlaResult:
    """Generalized Lloyd algorithm (full-search Lloyd / LBG) with TSVQ initialisation and
    ELBG-style codeword migration.

    Works on the distinct vectors with merged weights.  Each Lloyd iteration: (1) centroid
    update, empty cells repaired by splitting the cell of largest total squared error (its member
    farthest from the centroid becomes the new codeword, so rare colours survive); (2) every
    vector moves to its nearest codeword (float32 GEMM screening; a move is accepted only if its
    exact float64 distance is strictly smaller, so the distortion never increases).

    Stop rule (LBG): a descent stops after the first iteration whose distortion D_m satisfies
    ``D_{m-1} - D_m <= tol * D_m``, or at a fixed point, or when D_m == 0.

    Migration (0 < ``migrate`` rounds, default 8): after a descent has stopped, move up to 10% of
    the codewords, those of least utility, into the cells with the largest error (see
    ``_migrate``) and descend again; keep the result only if the distortion decreased, and stop
    migrating after a rejected round or a round that improved by at most ``tol`` (relative).
    This escapes the poor local minima plain GLA gets stuck in (isolated detailed blocks
    deserve their own codeword); ``migrate=0`` is the plain GLA.

    ``max_iter`` caps the total number of Lloyd iterations (all descents); ``converged`` is False
    iff the cap stopped the last descent.
    ``init``: None or "tsvq" (default: greedy TSVQ with the largest-gain split rule, see
    :func:`tsvq_tree`, with ``seed``), or a (k, d) array.
    Returns :class:`GlaResult`; ``history`` holds the distortion after the initial assignment,
    after each iteration of the first descent and after each accepted migration round
    (non-increasing).  Indices are the exact full-search nearest codewords.
    With at most k distinct vectors the result is exact (see module docstring).
    """
    k = _check_k(k)
    if max_iter < 0:
        raise ValueError("max_iter must be >= 0")
    x, w, u, wu, inv = _prepare(vectors, weights)
    if u.shape[0] <= k:
        cb = _pad(u, k)
        idx, d2 = nearest(x, cb)
        return GlaResult(cb, idx, float(w @ d2) / w.sum(), 0, True, [0.0])
    if init is None or (isinstance(init, str) and init == "tsvq"):
        c0 = _tsvq_build(u, wu, k, seed, "gain")[0].codebook
    elif isinstance(init, str):
        raise ValueError(f"unknown init {init!r}")
    else:
        c0 = np.asarray(init, dtype=np.float64)
        if c0.shape != (k, u.shape[1]) or not np.all(np.isfinite(c0)):
            raise ValueError(f"init must be a finite ({k}, {u.shape[1]}) array")
    c, hist, it, conv = _gla_core(u, wu, k, c0, max_iter, tol, migrate)
    idx, d2 = nearest(x, c)
    return GlaResult(c, idx, float(w @ d2) / w.sum(), it, conv, hist)


def design(vectors, k, *, method="gla", seed=0, weights=None, **kw):
    """Design a k-codeword codebook and encode ``vectors`` with it.

    method "gla" (default; ``kw`` goes to :func:`gla`: init, max_iter, tol) or "tsvq".
    Returns ``(codebook (k, d) float64, indices (N,) int64)``; indices are the exact full-search
    nearest codewords (for "tsvq" too; use ``tsvq_tree(...).encode`` for tree-search indices).
    """
    if method == "gla":
        r = gla(vectors, k, seed=seed, weights=weights, **kw)
        return r.codebook, r.indices
    if method == "tsvq":
        if kw:
            raise TypeError(f"unexpected arguments for tsvq: {sorted(kw)}")
        cb = tsvq(vectors, k, seed=seed, weights=weights)
        return cb, nearest(vectors, cb)[0]
    raise ValueError(f"unknown method {method!r}")
