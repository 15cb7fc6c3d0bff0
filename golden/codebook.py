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
* Distances are squared Euclidean distances.  The *exact* distance of x to c is the float64 sum
  of the squared differences; ``nearest`` is exact with respect to it (ties go to the lowest
  index).  Inner loops screen candidates with a float32 GEMM (||x||^2 - 2 x.c + ||c||^2 form, on
  mean-centred data, in chunks of about 2 MiB of scores) and settle them in float64.
* Everything is deterministic: the same inputs and seed give the same output bits run to run.
  ``nearest`` is moreover independent of the BLAS; the designed codebooks can differ between
  BLAS builds (the float32 screening steers which near-tie a Lloyd iteration resolves first).
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
    x = np.ascontiguousarray(x, dtype=np.float64)
    h = _row_hash(x)
    _, first, inv = np.unique(h, return_index=True, return_inverse=True)
    inv = inv.reshape(-1)
    u = np.take(x, first, axis=0)
    if not np.array_equal(x, np.take(u, inv, axis=0)):
        # a hash collision (astronomically rare): exact lexicographic dedup
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
        self._buf = None

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
        return self._best(ca, rows, chunk, two=False)[0]

    def top2(self, ca: np.ndarray, rows=None, chunk: int = 0, two=True):
        """Best and second-best screened codewords and their scores (float32); the second is
        -1 with score -inf when there is one column.  two=False: the second is not searched
        (returned as -1, -inf)."""
        return self._best(ca, rows, chunk, two=two)

    def scores_buffer(self, size):
        """A reusable float32 buffer of at least ``size`` elements (fresh large allocations
        cost page faults on every call)."""
        if self._buf is None or self._buf.size < size:
            self._buf = np.empty(size, dtype=np.float32)
        return self._buf

    def _best(self, ca, rows, chunk, two):
        k = ca.shape[1]
        xa = self.xa if rows is None else np.take(self.xa, rows, axis=0)
        n = xa.shape[0]
        b1 = np.empty(n, dtype=np.int64)
        b2 = np.full(n, -1, dtype=np.int64)
        s1 = np.empty(n, dtype=np.float32)
        s2 = np.full(n, -np.inf, dtype=np.float32)
        step = self.rows_per_chunk(k, chunk)
        buf = self.scores_buffer(min(step, n) * k)[: min(step, n) * k].reshape(-1, k)
        for s in range(0, n, step):
            e = min(n, s + step)
            sc = buf[: e - s]
            np.matmul(xa[s:e], ca, out=sc)
            best = sc.argmax(axis=1)
            b1[s:e] = best
            r = np.arange(e - s)
            s1[s:e] = sc[r, best]
            if two:
                if k > 1:
                    sc[r, best] = -np.inf
                    b2[s:e] = nb = sc.argmax(axis=1)
                    s2[s:e] = sc[r, nb]
        return b1, b2, s1, s2

    def approx_d2(self, rows, s, ca_rmax):
        """Screened squared distances from scores, lowered by their rounding-error bound
        (so they can serve in lower bounds)."""
        xn = self.xnorm[rows]
        gam = 2.0 * (self.d + 4) * _U32 * (1 + 1e-3)
        q = xn * xn - 2.0 * s.astype(np.float64)  # s = -inf (no candidate) gives +inf
        # q - |q| 1e-6 - margin, written so that q = +inf stays +inf
        low = np.minimum(q * (1 - 1e-6), q * (1 + 1e-6))
        low -= 2.0 * gam * ca_rmax * xn + gam * ca_rmax * ca_rmax
        return low


def _exact_d2(x: np.ndarray, c: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Exact float64 squared distance of each x[i] to c[idx[i]] (chunked)."""
    n, d = x.shape
    out = np.empty(n, dtype=np.float64)
    step = max(1, _MAX_TEMP_BYTES // (8 * d))
    for s in range(0, n, step):
        e = min(n, s + step)
        diff = np.take(c, idx[s:e], axis=0)  # one temporary, reused in place (much faster)
        np.subtract(x[s:e], diff, out=diff)
        np.einsum("ij,ij->i", diff, diff, out=out[s:e])
    return out


def _nearest_screened(x, c, scr: _Screen, chunk: int = 0, rows=None, tie=None):
    """Exact nearest codeword (ties -> lowest index) using float32 screening + float64 settling.

    Error bound of a screened score (x', c' centred; u = 2^-24; GEMM of d+1 terms in float32):
        |s~_j - s_j| <= E = (d + 4) u (|x'| |c'_j| + |c'_j|^2 / 2) (1 + 1e-3)
    so every codeword whose screened score is within 2E of the best screened score is a candidate,
    and the true nearest is always among them.  Rows with a single candidate are decided by the
    screen; the others are settled, chunk by chunk, with exact float64 distances, ties to the
    lowest index (or the lowest ``tie[j]`` when given).
    ``rows``: only these vectors (x must then be the matching subset).
    """
    n, d = x.shape
    k = c.shape[0]
    ca, rmax = scr.codebook(c)
    xa = scr.xa if rows is None else np.take(scr.xa, rows, axis=0)
    xnorm = scr.xnorm if rows is None else scr.xnorm[rows]
    gam = (d + 4) * _U32 * (1 + 1e-3)
    idx = np.empty(n, dtype=np.int64)
    step = scr.rows_per_chunk(k, chunk)
    buf = scr.scores_buffer(min(step, n) * k)[: min(step, n) * k].reshape(-1, k)
    for s in range(0, n, step):
        e = min(n, s + step)
        sc = buf[: e - s]
        np.matmul(xa[s:e], ca, out=sc)
        best = sc.argmax(axis=1)
        idx[s:e] = best
        smax = sc[np.arange(e - s), best]
        margin = (2.0 * gam * (xnorm[s:e] * rmax + 0.5 * rmax * rmax)).astype(np.float32)
        # float32 rounding of the threshold itself: widen by a few more ulps
        thr = smax - margin - np.abs(smax) * np.float32(4 * _U32)
        cand = sc >= thr[:, None]
        amb = np.flatnonzero(np.count_nonzero(cand, axis=1) > 1)
        if amb.size:
            r, cc = np.nonzero(cand[amb])
            r = amb[r] + s
            dd = _exact_d2(x[r], c, cc)
            # per row: smallest exact distance, then lowest codeword index
            order = np.lexsort((cc if tie is None else tie[cc], dd, r))
            r, cc = r[order], cc[order]
            first = np.ones(r.size, dtype=bool)
            first[1:] = r[1:] != r[:-1]
            idx[r[first]] = cc[first]
    return idx, _exact_d2(x, c, idx)


def nearest(vectors: np.ndarray, codebook: np.ndarray, chunk: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Full-search nearest codeword.

    Parameters: ``vectors`` (N, d) real, ``codebook`` (k, d) real, ``chunk`` rows per distance
    chunk (0 = automatic, about 2 MiB of float32 scores per chunk; memory stays far below 1 GB).

    Returns ``(indices, d2)``: int64 (N,) index of the codeword minimising the float64 squared
    distance (sum of squared differences), ties to the lowest index, and float64 (N,) that
    distance.  Exact: a float32 GEMM only screens candidates under a rigorous rounding-error
    bound; close calls are settled in float64.  Repeated codewords are searched once (the lowest
    index answers).  Deterministic, and independent of the BLAS.
    """
    x = _as_vectors(vectors)
    c = np.asarray(codebook, dtype=np.float64)
    if c.ndim != 2 or c.shape[0] < 1 or c.shape[1] != x.shape[1]:
        raise ValueError(f"codebook must be (k, {x.shape[1]}), got shape {c.shape}")
    if not np.all(np.isfinite(c)):
        raise ValueError("codebook must be finite")
    cu, first = np.unique(c + 0.0, axis=0, return_index=True)  # first = lowest index of a row
    idx, d2 = _nearest_screened(x, cu, _Screen(x, cu.mean(axis=0)), chunk, tie=first)
    return first[idx], d2


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


def _child_stats(x, w, mask):
    """Split record: mask, the children's centroids and total squared errors (a one-row child's
    centroid is that row, exactly)."""
    w1 = np.where(mask, w, 0.0)
    w0 = w - w1
    c1 = (w1 @ x) / w1.sum()
    c0 = (w0 @ x) / w0.sum()
    xx = np.einsum("ij,ij->i", x, x)
    dd = np.where(mask, xx - 2.0 * (x @ c1) + c1 @ c1, xx - 2.0 * (x @ c0) + c0 @ c0)
    e1, e0 = max(float(w1 @ dd), 0.0), max(float(w0 @ dd), 0.0)
    n1 = int(np.count_nonzero(mask))
    if n1 == 1:
        c1, e1 = x[np.argmax(mask)].copy(), 0.0
    if n1 == mask.size - 1:
        c0, e0 = x[np.argmin(mask)].copy(), 0.0
    return mask, c0, c1, e0, e1


def _split(x, w, m, v0, rng, n_power=3, n_lloyd=4, sample=2048):
    """Split one cell (x (n, d), weights w, centroid m) into two.

    Initial cut: along the principal axis (power iteration from ``v0``), at the 1-D 2-means
    optimum of the projections (unlike a cut through the centroid this isolates a small, far
    group, e.g. a few brown texels among green ones); then up to ``n_lloyd`` weighted 2-means
    iterations.  Cells of more than ``sample`` vectors fit the cut on a random sample (``rng``)
    of that size, then partition all their vectors with it.  Returns the split record
    ``(mask of the second child, c0, c1, sse0, sse1)`` or None if the vectors cannot be
    separated.  ``rng``: a callable returning the Generator (made only when needed)."""
    n = x.shape[0]
    if n > sample:
        pick = np.sort(rng().choice(n, size=sample, replace=False))
        xs, ws = x[pick], w[pick]
    else:
        xs, ws = x, w
    xc = xs - m
    v = v0.copy()
    for _ in range(n_power):
        v = (ws * (xc @ v)) @ xc
        nv = np.sqrt(v @ v)
        if not nv > 0:
            break
        v /= nv
    p = xc @ v
    order = np.argsort(p, kind="stable")
    ps, wsrt = p[order], ws[order]
    cw = np.cumsum(wsrt)[:-1]
    cs = np.cumsum(wsrt * ps)[:-1]
    wt_, st_ = cw[-1] + wsrt[-1], cs[-1] + wsrt[-1] * ps[-1]
    # SSE(left) + SSE(right) = const - cs^2/cw - (st-cs)^2/(wt-cw): maximise the subtracted part
    score = cs * cs / cw + (st_ - cs) ** 2 / (wt_ - cw)
    score[ps[1:] <= ps[:-1]] = -np.inf  # cut only between distinct projections
    j = int(np.argmax(score))
    dv, thr = v, 0.5 * (ps[j] + ps[j + 1]) if np.isfinite(score[j]) else 0.0
    mask = (xc @ dv) > thr
    if not (mask.all() or not mask.any()):
        wt, st = ws.sum(), ws @ xc
        for _ in range(n_lloyd):
            w1 = np.where(mask, ws, 0.0)
            ww1 = w1.sum()
            s1 = w1 @ xc
            c1 = s1 / ww1
            c0 = (st - s1) / (wt - ww1)
            dv_new = c1 - c0
            thr_new = 0.5 * (c1 @ c1 - c0 @ c0)
            new = (xc @ dv_new) > thr_new
            if new.all() or not new.any():
                break
            dv, thr = dv_new, thr_new
            if np.array_equal(new, mask):
                break
            mask = new
    if n > sample:
        mask = (x @ dv) > thr + m @ dv
    if mask.all() or not mask.any():
        # fallback: cut orthogonally to the direction of the farthest vector
        xc = x - m
        far = int(np.argmax(np.einsum("ij,ij->i", xc, xc)))
        mask = (xc @ xc[far]) > 0.5 * (xc[far] @ xc[far])
        if mask.all() or not mask.any():
            mask = (xc @ xc[far]) > 0
            if mask.all() or not mask.any():
                return None
    return _child_stats(x, w, mask)


def _split_batch(xs, ws, starts, ends, cents, v0, n_power=3, n_lloyd=4):
    """:func:`_split` for many small cells at once (segment-vectorised over the concatenated
    rows; no sampling).  Returns a list of split records, None where the batch could not cut a
    cell (the caller then uses :func:`_split`)."""
    b = starts.size
    n = ends - starts
    off = np.zeros(b + 1, dtype=np.int64)
    off[1:] = np.cumsum(n)
    st0 = off[:-1]
    seg = np.repeat(np.arange(b), n)
    idx = np.arange(off[-1]) - np.repeat(st0 - starts, n)
    x, w = xs[idx], ws[idx]
    xc = x - cents[seg]
    v = v0.copy()
    for _ in range(n_power):
        p = np.einsum("ij,ij->i", xc, v[seg])
        vn = np.add.reduceat((w * p)[:, None] * xc, st0)
        nv = np.sqrt(np.einsum("ij,ij->i", vn, vn))
        good = nv > 0
        v[good] = vn[good] / nv[good, None]
    p = np.einsum("ij,ij->i", xc, v[seg])
    # 1-D 2-means optimum per segment over the sorted projections
    o = np.lexsort((p, seg))
    ps, wsr = p[o], w[o]
    cw_all, cs_all = np.cumsum(wsr), np.cumsum(wsr * ps)
    base_w = np.concatenate([[0.0], cw_all[off[1:-1] - 1]])
    base_s = np.concatenate([[0.0], cs_all[off[1:-1] - 1]])
    cw = cw_all - base_w[seg]
    cs = cs_all - base_s[seg]
    wt, stt = cw[off[1:] - 1], cs[off[1:] - 1]
    last = np.zeros(off[-1], dtype=bool)
    last[off[1:] - 1] = True
    valid = ~last
    valid[:-1] &= ps[1:] > ps[:-1]
    with np.errstate(divide="ignore", invalid="ignore"):
        score = np.where(valid, cs * cs / cw + (stt[seg] - cs) ** 2 / (wt[seg] - cw), -np.inf)
    smax = np.maximum.reduceat(score, st0)
    hit = np.flatnonzero(score == smax[seg])
    _, first = np.unique(seg[hit], return_index=True)
    j = hit[first]  # first maximiser of each segment (every segment has a hit)
    okcut = np.isfinite(smax)
    jn = np.minimum(j + 1, off[-1] - 1)
    thr = np.where(okcut, 0.5 * (ps[j] + ps[jn]), np.inf)
    mask = p > thr[seg]
    wtot = np.add.reduceat(w, st0)
    stot = np.add.reduceat(w[:, None] * xc, st0)
    ones = np.ones(off[-1], dtype=np.int64)
    for _ in range(n_lloyd):
        w1 = np.where(mask, w, 0.0)
        ww1 = np.add.reduceat(w1, st0)
        s1 = np.add.reduceat(w1[:, None] * xc, st0)
        n1 = np.add.reduceat(np.where(mask, ones, 0), st0)
        live = (n1 > 0) & (n1 < n)
        with np.errstate(divide="ignore", invalid="ignore"):
            c1 = s1 / ww1[:, None]
            c0 = (stot - s1) / (wtot - ww1)[:, None]
        dv = c1 - c0
        th = 0.5 * (np.einsum("ij,ij->i", c1, c1) - np.einsum("ij,ij->i", c0, c0))
        dv[~live] = 0.0
        th[~live] = 0.0
        new = np.einsum("ij,ij->i", xc, dv[seg]) > th[seg]
        nn1 = np.add.reduceat(np.where(new, ones, 0), st0)
        upd = (live & (nn1 > 0) & (nn1 < n))[seg]
        new = np.where(upd, new, mask)
        if np.array_equal(new, mask):
            break
        mask = new
    # children statistics (centred sums, then back to the original coordinates)
    n1 = np.add.reduceat(np.where(mask, ones, 0), st0)
    w1 = np.where(mask, w, 0.0)
    w0 = w - w1
    ww1, ww0 = np.add.reduceat(w1, st0), np.add.reduceat(w0, st0)
    ok = (n1 > 0) & (n1 < n)
    with np.errstate(divide="ignore", invalid="ignore"):
        c1 = np.add.reduceat(w1[:, None] * xc, st0) / ww1[:, None]
        c0 = np.add.reduceat(w0[:, None] * xc, st0) / ww0[:, None]
    # SSE = sum w |xc|^2 - W |c|^2 per side (centred at the parent: mild cancellation)
    wxx = w * np.einsum("ij,ij->i", xc, xc)
    sse1 = np.add.reduceat(np.where(mask, wxx, 0.0), st0) - ww1 * np.einsum("ij,ij->i", c1, c1)
    sse0 = np.add.reduceat(np.where(mask, 0.0, wxx), st0) - ww0 * np.einsum("ij,ij->i", c0, c0)
    sse1 = np.maximum(sse1, 0.0)
    sse0 = np.maximum(sse0, 0.0)
    c1 += cents
    c0 += cents
    # one-row children: the row itself, exactly
    single1 = mask & (n1 == 1)[seg]
    single0 = ~mask & (n - n1 == 1)[seg]
    c1[seg[single1]] = x[single1]
    c0[seg[single0]] = x[single0]
    sse1[n1 == 1] = 0.0
    sse0[n - n1 == 1] = 0.0
    out = []
    for i in range(b):  # one record per cell (bookkeeping only, no arithmetic per vector)
        if ok[i]:
            out.append((mask[st0[i]:off[i + 1]], c0[i], c1[i], float(sse0[i]), float(sse1[i])))
        else:
            out.append(None)
    return out


def _tsvq_build(u, wu, k, seed, criterion="distortion", batch=128, sample=2048, small_cell=256):
    """Greedy TSVQ on distinct weighted vectors.

    criterion "distortion" (the paper's rule): split the leaf of largest total squared error.
    criterion "gain": split the leaf whose split reduces the total squared error most (greedy
    tree growing, Riskin & Gray 1991; evaluated lazily, since a gain never exceeds the leaf's
    error).  Ties go to the older leaf.  Stops at k leaves or when no leaf can be split.

    A leaf's split depends only on its vectors and its node number (seeded start vector and
    sample), never on when it is computed, so splits are computed ahead in vectorised batches
    of up to ``batch`` high-error leaves without changing the tree (leaves of at most
    ``small_cell`` vectors, whose cost is all interpreter overhead; larger ones one by one).
    Returns (TsvqTree, labels of the distinct vectors)."""
    if criterion not in ("distortion", "gain"):
        raise ValueError(f"unknown TSVQ split criterion {criterion!r}")
    m_, d = u.shape
    v0 = np.random.default_rng(seed).standard_normal((2 * k + 1, d))
    order = np.arange(m_)
    xs = u.copy()
    ws = wu.copy()
    cent, start, end, left, right, sse = [], [], [], [], [], []
    rec = {}
    heap = []

    def new_leaf(a, b, c, e):
        cid = len(cent)
        cent.append(c)
        start.append(a)
        end.append(b)
        left.append(-1)
        right.append(-1)
        sse.append(e)
        if b - a > 1:  # rows are distinct: one row = constant leaf
            heapq.heappush(heap, (-e, cid, False))

    def compute(nids):
        small = [i for i in nids if end[i] - start[i] <= small_cell]
        if small:
            arr = np.array(small, dtype=np.int64)
            res = _split_batch(xs, ws, np.array(start)[arr], np.array(end)[arr],
                               np.array([cent[i] for i in small]), v0[arr])
            for i, r in zip(small, res):
                rec[i] = r
        for i in nids:
            if rec.get(i, None) is None:
                s, e = start[i], end[i]
                rng = lambda i=i: np.random.default_rng([seed, i])  # noqa: E731
                rec[i] = _split(xs[s:e], ws[s:e], cent[i], v0[i], rng, sample=sample)

    root_c = _wmean(xs, ws) if m_ > 1 else xs[0].copy()
    diff = xs - root_c
    new_leaf(0, m_, root_c, float(ws @ np.einsum("ij,ij->i", diff, diff)))
    n_leaves = 1
    while n_leaves < k and heap:
        key, nid, exact = heapq.heappop(heap)
        if nid not in rec:
            want = max(1, min(batch, k - n_leaves))
            top = [e[1] for e in heapq.nsmallest(2 * want, heap) if e[1] not in rec]
            compute([nid] + top[: want - 1])
        r = rec.pop(nid)
        if r is None:
            continue
        if criterion == "gain" and not exact:
            heapq.heappush(heap, (-(sse[nid] - r[3] - r[4]), nid, True))
            rec[nid] = r
            continue
        mask, c0, c1, e0, e1 = r
        s, e = start[nid], end[nid]
        perm = np.concatenate([np.flatnonzero(~mask), np.flatnonzero(mask)])
        xs[s:e] = xs[s:e][perm]
        ws[s:e] = ws[s:e][perm]
        order[s:e] = order[s:e][perm]
        mid = s + int(np.count_nonzero(~mask))
        left[nid] = len(cent)
        right[nid] = len(cent) + 1
        new_leaf(s, mid, c0, e0)
        new_leaf(mid, e, c1, e1)
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
    k = _check_k(k)
    _, _, u, wu, _ = _prepare(vectors, weights)
    return _tsvq_build(u, wu, k, seed, criterion)[0]


def tsvq(vectors, k, *, seed=0, weights=None, criterion="distortion") -> np.ndarray:
    """TSVQ codebook: ``(k, d)`` float64, the leaf centroids of :func:`tsvq_tree` (left to
    right).  With >= k distinct vectors the k codewords are distinct; with fewer, every distinct
    vector appears exactly, then repeats.  Encode with :func:`nearest` (full search) or with
    ``tsvq_tree(...).encode`` (tree search, the paper's fast encoder)."""
    return tsvq_tree(vectors, k, seed=seed, weights=weights, criterion=criterion).codebook


# --------------------------------------------------------------------------------------------
# GLA
# --------------------------------------------------------------------------------------------
@dataclass
class GlaResult:
    """Result of :func:`gla`.

    codebook: (k, d) float64.  indices: (N,) int64, exact full-search nearest codeword of every
    input vector (``nearest(vectors, codebook)``).  distortion: weighted mean over vectors of the
    squared error ||x - c||^2 (per vector, not per component) of that final encoding.
    iterations: Lloyd iterations run (all phases and migration rounds).  converged: the stop
    rule fired (False: max_iter reached).  history: distortion (same definition, all vectors)
    after the initial assignment, after each iteration of the first full-data descent and after
    each accepted migration round; non-increasing.
    """

    codebook: np.ndarray
    indices: np.ndarray
    distortion: float
    iterations: int
    converged: bool
    history: list = field(default_factory=list)


def _centroids(u, wu, a, k):
    """Per cell: total weight (k,) and weighted sum of the vectors (k, d).  Each cell's sum
    depends only on its members in index order, so recomputing a subset of cells gives the same
    bits as a full recomputation."""
    cnt = np.bincount(a, weights=wu, minlength=k)
    sums = np.empty((k, u.shape[1]), dtype=np.float64)
    for j in range(u.shape[1]):  # one bincount per dimension (measured faster than sorting)
        sums[:, j] = np.bincount(a, weights=wu * u[:, j], minlength=k)
    return cnt, sums


def _update_centroids(u, wu, a_old, a_new, cnt, sums):
    """Update cnt and sums (in place) for the vectors that changed cell: their weight and
    weighted vector move from the old cell to the new one.  Cells that neither gained nor lost
    vectors keep their sums bit for bit (so their codewords do not "move")."""
    ch = np.flatnonzero(a_old != a_new)
    if ch.size == 0:
        return
    if 4 * ch.size > a_new.size:  # large change: recompute
        cnt[:], sums[:] = _centroids(u, wu, a_new, k=cnt.shape[0])
        return
    wv = wu[ch, None] * u[ch]
    np.subtract.at(sums, a_old[ch], wv)
    np.add.at(sums, a_new[ch], wv)
    np.subtract.at(cnt, a_old[ch], wu[ch])
    np.add.at(cnt, a_new[ch], wu[ch])
    # a cell that lost all its vectors is empty: clear the rounding residue exactly
    gone = np.unique(a_old[ch])
    gone = gone[np.bincount(a_new, minlength=cnt.shape[0])[gone] == 0]
    cnt[gone] = 0.0
    sums[gone] = 0.0


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
        # re-derive the touched cells exactly (bit-identical to a full recomputation)
        touched = np.zeros(k, dtype=bool)
        touched[dcell] = True
        touched[target] = True
        sel = touched[a]
        cnt_t, sums_t = _centroids(u[sel], wu[sel], a[sel], k)
        cnt[touched] = cnt_t[touched]
        sums[touched] = sums_t[touched]


class _State:
    """Assignment state of the Lloyd iterations on the distinct vectors: codebook ``c``, codeword
    ``a`` of each vector, exact squared distance ``d2`` to it and ``lb``, a lower bound of the
    (Euclidean, not squared) distance to every other codeword (Hamerly's bound)."""

    __slots__ = ("c", "a", "d2", "lb", "gaps")

    def __init__(self, c, a, d2, lb, gaps=None):
        self.c, self.a, self.d2, self.lb, self.gaps = c, a, d2, lb, gaps


def _combine(u, c, scr, rmax, rows, a, d, b1, b2, s1, s2, rest):
    """Merge a vector's current codeword (a, d: exact squared distance) with screened candidates
    b1, b2 (scores s1, s2; b2 = -1: no second candidate; b2 = k: no index, s2 bounds the score
    of every other screened codeword) and a lower bound ``rest`` (distance) for all codewords
    not looked at.  The best candidate replaces the current codeword only if its exact float64
    distance is strictly smaller.  Returns the new (a, d2, lb); lb uses the screened distances
    lowered by their error bound."""
    q1 = scr.approx_d2(rows, s1, rmax)
    q2 = scr.approx_d2(rows, s2, rmax)
    ch = np.flatnonzero((b1 != a) & (q1 < d))
    e1 = q1.copy()
    if ch.size:
        e1[ch] = _exact_d2(u[rows[ch]], c, b1[ch])
    take = np.zeros(rows.size, dtype=bool)
    take[ch] = e1[ch] < d[ch]
    na = np.where(take, b1, a)
    nd = np.where(take, e1, d)
    o = np.minimum(np.where(take, d, np.inf), np.where(b1 != na, q1, np.inf))
    o = np.minimum(o, np.where((b2 >= 0) & (b2 != na), q2, np.inf))
    return na, nd, np.minimum(rest, np.sqrt(np.maximum(o, 0.0)))


def _assign_full(u, c, scr, chunk=0):
    """Fresh assignment of every vector: screened top-2 over the whole codebook."""
    ca, rmax = scr.codebook(c)
    rows = np.arange(u.shape[0])
    b1, b2, s1, s2 = scr.top2(ca, chunk=chunk)
    e1 = _exact_d2(u, c, b1)
    a, d2, lb = _combine(u, c, scr, rmax, rows, b1, e1, b1, b2, s1, s2,
                         np.full(rows.size, np.inf))
    return _State(c, a, d2, lb)


# Per-vector overhead of screening a vector against a column subset, in units of one score
# (gathers, two argmax passes, bookkeeping); measured ~100 ns against ~0.5 ns per score.
_ROW_COST = 200
_FULL_MIGRATE = 1
_MIGRATE_FRAC = 0.1
_MIGRATE_RATIO = 2.0
_COARSE_FACTOR = 1.5
_COARSE_MIN = 8192  # smaller samples could miss rare colours altogether


def _half_gaps(c, scr, moved=None, old=None):
    """Lower bounds of s_j = half the distance from codeword j to its nearest other codeword
    (Elkan's bound), from float32 screening lowered by its error bound.

    With ``moved`` (indices of the codewords that changed) and ``old`` (the bounds before the
    change) only the rows of the moved codewords are screened: a codeword that did not move is
    at least as far from every unmoved codeword as before, so its new bound is the smaller of
    its old bound and half its distance to the nearest moved codeword."""
    k = c.shape[0]
    if k < 2:
        return np.full(k, np.inf)
    rows = np.arange(k) if moved is None or old is None or 2 * moved.size > k else moved
    cc = c - scr.shift
    ca, rmax = scr.codebook(c)
    cn = np.einsum("ij,ij->i", cc, cc)
    xa = np.empty((rows.size, scr.d + 1), dtype=np.float32)
    xa[:, : scr.d] = cc[rows]
    xa[:, scr.d] = 1.0
    gam = 2.0 * (scr.d + 4) * _U32 * (1 + 1e-3)
    row_min = np.empty(rows.size)
    col_min = np.full(k, np.inf)
    step = max(1, _SCORE_BYTES // (4 * k))
    for s0 in range(0, rows.size, step):
        e = min(rows.size, s0 + step)
        sc = xa[s0:e] @ ca
        r_cn = cn[rows[s0:e]]
        # squared distances, lowered by the screening error bound
        q = r_cn[:, None] - 2.0 * sc.astype(np.float64)
        q -= (2.0 * gam * (np.sqrt(r_cn) * rmax + 0.5 * rmax * rmax))[:, None] + np.abs(q) * 1e-6
        q[np.arange(e - s0), rows[s0:e]] = np.inf  # not its own neighbour
        row_min[s0:e] = q.min(axis=1)
        np.minimum(col_min, q.min(axis=0), out=col_min)
    out = np.empty(k)
    if rows.size == k:
        out[:] = 0.5 * np.sqrt(np.maximum(row_min, 0.0))
        return out
    out[:] = np.minimum(old, 0.5 * np.sqrt(np.maximum(col_min, 0.0)))
    out[rows] = 0.5 * np.sqrt(np.maximum(row_min, 0.0))
    return out


def _reassign(u, scr, st: _State, c_new, chunk=0, force=None):
    """Move every vector of ``st`` to its nearest codeword of ``c_new`` (screened), doing as
    little work as the bounds allow.  ``force``: vectors whose codeword index changed outside
    (empty-cell repair).  Exact in exact arithmetic; a vector changes codeword only if the exact
    float64 distance strictly decreases.

    With drift_j = |c_new_j - c_j| and ub = |x - c_new_a|: a vector keeps its codeword if
    ub <= s_a (half the gap from c_new_a to its nearest codeword; Elkan), and it keeps it against
    every codeword outside a set J of the largest movers if ub <= lb - max drift outside J
    (Hamerly); a vector whose codeword did not move can only be captured by a codeword that
    moved.  So: vectors passing the first test are skipped, those passing the second are
    screened against J only, those of unmoved cells against the moved codewords, the rest
    against everything.  |J| is chosen per call to minimise the estimated work."""
    k = c_new.shape[0]
    n = u.shape[0]
    a, d2, lb = st.a.copy(), st.d2.copy(), st.lb.copy()
    moved = np.any(c_new != st.c, axis=1)
    if not moved.any():
        return _State(c_new, a, d2, lb, st.gaps)
    diff = c_new - st.c
    drift = np.sqrt(np.einsum("ij,ij->i", diff, diff)) * (1 + 1e-12)
    mv = np.flatnonzero(moved)
    pm = moved[a]
    if force is not None:
        pm |= force
        lb[force] = 0.0
    rows = np.flatnonzero(pm)
    if rows.size > n // 2:
        d2 = np.where(pm, _exact_d2(u, c_new, a), d2)
    elif rows.size:
        d2[rows] = _exact_d2(u[rows], c_new, a[rows])
    ub = np.sqrt(d2) * (1 + 1e-12)
    mv_sorted = mv[np.argsort(-drift[mv], kind="stable")]
    ds = np.append(drift[mv_sorted], 0.0)  # ds[t]: largest drift outside the t largest movers
    gaps = _half_gaps(c_new, scr, mv, st.gaps)
    skip = ub <= gaps[a]
    # choose |J| = t among 0, 1, 2, 4, ..., |mv|: vectors with slack <= -ds[t] need J only
    slack = ub - lb
    ts = np.array(sorted({0, mv.size} | {1 << i for i in range(mv.size.bit_length())
                                         if (1 << i) < mv.size}))
    thr = -ds[ts]  # increasing in t
    live = ~skip
    stride = max(1, n // 8192)  # the cost model only needs estimates: count a strided sample
    samp = np.flatnonzero(live[::stride]) * stride
    pos = np.searchsorted(thr, slack[samp], side="left")  # first t whose test passes
    cnt_pm = np.bincount(pos[pm[samp]], minlength=ts.size + 1)
    cnt_np = np.bincount(pos[~pm[samp]], minlength=ts.size + 1)
    pass_cum = np.cumsum(cnt_pm + cnt_np)[: ts.size]  # vectors passing the test at each t
    fail_pm = cnt_pm.sum() - np.cumsum(cnt_pm)[: ts.size]
    fail_np = cnt_np.sum() - np.cumsum(cnt_np)[: ts.size]
    # vectors passing with J empty (slack <= -ds[0]) need no work at all
    cost = ((pass_cum - pass_cum[0]) * (ts + _ROW_COST) + fail_np * (mv.size + _ROW_COST)
            + fail_pm * (k + _ROW_COST))
    ti = int(np.argmin(cost))
    t, dec = int(ts[ti]), float(ds[ts[ti]])
    free = live & (slack <= -ds[0])
    skip |= free
    live &= ~free
    pa = live & (slack <= -dec)
    ca, rmax = scr.codebook(c_new)
    groups = (
        (np.flatnonzero(pa), mv_sorted[:t], lb - dec),
        (np.flatnonzero(live & ~pa & ~pm), mv, lb),
        (np.flatnonzero(live & ~pa & pm), None, np.inf),
    )
    new_lb = lb - np.where(skip, ds[0], dec)  # skipped vectors and group A with an empty J
    if t > 0 and groups[0][0].size:
        # group A: a vector whose own codeword is not in J needs only the best of J (all of J
        # is then at least that far); the others need the best two
        g = groups[0][0]
        in_j = np.zeros(k, dtype=bool)
        in_j[mv_sorted[:t]] = True
        own = in_j[a[g]]
        groups = ((g[own], mv_sorted[:t], lb - dec, True),
                  (g[~own], mv_sorted[:t], lb - dec, False)) + tuple(x + (True,) for x in groups[1:])
    else:
        groups = tuple(x + (True,) for x in groups)
    for g, cols, rest, two in groups:
        if g.size == 0 or (cols is not None and cols.size == 0):
            continue
        rest_g = rest[g] if isinstance(rest, np.ndarray) else np.full(g.size, rest)
        if cols is None:
            b1, b2, s1, s2 = scr.top2(ca, rows=g, chunk=chunk)
        else:
            b1, b2, s1, s2 = scr.top2(np.ascontiguousarray(ca[:, cols]), rows=g, chunk=chunk,
                                      two=two)
            b1 = cols[b1]
            b2 = np.where(b2 >= 0, cols[np.maximum(b2, 0)], -1)
            if not two and cols.size > 1:
                b2 = np.full(g.size, k)  # "the other columns": no index, bounded by s1
                s2 = s1
        a[g], d2[g], new_lb[g] = _combine(u, c_new, scr, rmax, g, a[g], d2[g], b1, b2, s1, s2,
                                          rest_g)
    return _State(c_new, a, d2, new_lb, gaps)


def _lloyd(u, wu, k, st: _State, scr, tol, budget, chunk=0):
    """Lloyd iterations from state ``st``.  Stops by the LBG rule (relative decrease <= tol),
    at a fixed point, at distortion 0 or after ``budget`` iterations.
    Returns (state, history, iterations, converged)."""
    wsum = wu.sum()
    dist = float(wu @ st.d2) / wsum
    hist = []
    it, conv = 0, False
    cnt, sums = _centroids(u, wu, st.a, k)
    while True:
        if dist == 0.0:
            conv = True
            break
        if it >= budget:
            break
        it += 1
        a = st.a.copy()
        c_new = st.c.copy()
        _repair_empty(u, wu, a, c_new, cnt, sums, k)
        full = cnt > 0
        c_new[full] = sums[full] / cnt[full, None]
        if np.array_equal(c_new, st.c):  # fixed point: nothing can change any more
            conv = True
            hist.append(dist)
            break
        force = a != st.a
        st_new = _reassign(u, scr, _State(st.c, a, st.d2, st.lb, st.gaps), c_new, chunk,
                           force if force.any() else None)
        new = float(wu @ st_new.d2) / wsum
        if new > dist:  # only float rounding could do this: keep the contract, stop here
            conv = True
            break
        _update_centroids(u, wu, a, st_new.a, cnt, sums)
        st = st_new
        hist.append(new)
        if dist - new <= tol * new:
            conv = True
            dist = new
            break
        dist = new
    return st, hist, it, conv


def _migrate(u, wu, k, st: _State, scr, frac, chunk=0):
    """One batch of ELBG-style codeword migrations (Patane & Russo 2001, vectorised).

    Utility of a codeword = the weighted error increase if it were removed (its vectors falling
    to their second-nearest codeword).  The lowest-utility codewords are moved onto the member
    farthest from its codeword of the cells with the largest such error (the empty-cell repair
    rule), pairing lowest utility with largest error while utility < 2 x that error, at most
    ``frac * k`` moves.  Utilities are first bounded from below with the state's second-nearest
    bounds, then computed exactly (screened search) for the 3 * frac * k least useful codewords.
    Returns the new state (vectors reassigned) or None if nothing moves."""
    c, a, d1 = st.c, st.a, st.d2
    m = max(1, int(frac * k))
    util = np.bincount(a, weights=wu * np.maximum(st.lb * st.lb - d1, 0.0), minlength=k)
    pool = np.argsort(util, kind="stable")[: min(k, 3 * m)]
    in_pool = np.zeros(k, dtype=bool)
    in_pool[pool] = True
    rows = np.flatnonzero(in_pool[a])
    if rows.size:
        ca, _ = scr.codebook(c)
        b1, b2, _, _ = scr.top2(ca, rows=rows, chunk=chunk)
        other = np.where(b1 != a[rows], b1, b2)
        d_other = np.full(rows.size, np.inf)
        ok = other >= 0
        d_other[ok] = _exact_d2(u[rows[ok]], c, other[ok])
        util_p = np.bincount(a[rows], weights=wu[rows] * np.maximum(d_other - d1[rows], 0.0),
                             minlength=k)
        util[pool] = util_p[pool]
    rem = pool[np.argsort(util[pool], kind="stable")][:m]
    err = wu * d1
    order = np.lexsort((np.arange(u.shape[0]), -err, a))
    first = np.ones(order.size, dtype=bool)
    first[1:] = a[order[1:]] != a[order[:-1]]
    far = np.full(k, -1, dtype=np.int64)
    gain = np.zeros(k)
    far[a[order[first]]] = order[first]
    gain[a[order[first]]] = err[order[first]]
    rec = np.argsort(-gain, kind="stable")
    rec = rec[~np.isin(rec, rem)][: rem.size]
    rem = rem[: rec.size]
    ok = (util[rem] < _MIGRATE_RATIO * gain[rec]) & (gain[rec] > 0)
    rem, rec = rem[ok], rec[ok]
    if rem.size == 0:
        return None
    c_new = c.copy()
    c_new[rem] = u[far[rec]]
    return _reassign(u, scr, st, c_new, chunk)


def _gla_core(u, wu, k, c0, max_iter, tol, migrate, frac=None, chunk=0):
    """GLA on distinct weighted vectors; returns (codebook, history, iterations, converged)."""
    frac = _MIGRATE_FRAC if frac is None else frac
    wsum = wu.sum()
    scr = _Screen(u, _wmean(u, wu))
    st = _assign_full(u, np.array(c0, dtype=np.float64, copy=True), scr, chunk)
    hist = [float(wu @ st.d2) / wsum]
    st, h, it, conv = _lloyd(u, wu, k, st, scr, tol, max_iter, chunk)
    hist += h
    rounds = 0
    while conv and rounds < migrate and k >= 2 and it < max_iter and hist[-1] > 0:
        rounds += 1
        trial = _migrate(u, wu, k, st, scr, frac, chunk)
        if trial is None:
            break
        st_t, h, it_t, conv_t = _lloyd(u, wu, k, trial, scr, tol, max_iter - it, chunk)
        it += it_t
        d_t = float(wu @ st_t.d2) / wsum
        if not d_t < hist[-1]:
            break  # rejected: keep the previous codebook (converged by the stop rule)
        improve = hist[-1] - d_t
        st, conv = st_t, conv_t
        hist.append(d_t)
        if improve <= tol * d_t:
            break
    return st, scr, hist, it, conv


def _final_indices(u, st: _State, scr, chunk=0):
    """Exact nearest codeword (ties -> lowest index) of every distinct vector for st.c: a vector
    whose distance to its codeword is certified below the lower bound of all others keeps it,
    the rest go through the exact full search.  Returns (indices, exact d2)."""
    a, d2 = st.a.copy(), st.d2.copy()
    ub = np.sqrt(d2)
    unsure = np.flatnonzero(~(ub * (1 + 1e-9) + 1e-12 < st.lb))
    if unsure.size:
        a[unsure], d2[unsure] = _nearest_screened(u[unsure], st.c, scr, chunk, rows=unsure)
    return a, d2


def gla(vectors, k, *, seed=0, weights=None, init=None, max_iter=100, tol=1e-3,
        migrate=8, subsample=32) -> GlaResult:
    """Generalized Lloyd algorithm (full-search Lloyd / LBG) with TSVQ initialisation and
    ELBG-style codeword migration.

    Works on the distinct vectors with merged weights.  Each Lloyd iteration: (1) centroid
    update, empty cells repaired by splitting the cell of largest total squared error (its member
    farthest from the centroid becomes the new codeword, so rare colours survive); (2) every
    vector moves to its nearest codeword (float32 GEMM screening pruned by Hamerly-style bounds;
    a move is accepted only if its exact float64 distance is strictly smaller, so the distortion
    never increases).

    Stop rule (LBG): a descent stops after the first iteration whose distortion D_m satisfies
    ``D_{m-1} - D_m <= tol * D_m``, or at a fixed point, or when D_m == 0.  The default
    tol = 1e-3 (at most ~0.004 dB gained by the last iteration) was chosen by measurement: on
    the benchmark photographs tol = 1e-4 doubles the running time for 0.01-0.02 dB.

    Migration (``migrate`` rounds at most, default 8; 0 = plain GLA): after a descent has
    stopped, move up to 10% of the codewords, those of least utility, onto the worst-coded
    vectors of the cells with the largest error (see ``_migrate``) and descend again; keep the
    result only if the distortion decreased, and stop after a rejected round or a round that
    improved by at most ``tol`` (relative).  This escapes the poor local minima plain GLA gets
    stuck in (isolated detailed blocks deserve their own codeword).

    Coarse phase (``subsample`` vectors per codeword, default 32; 0 disables): with more than
    1.5 * subsample * k distinct vectors and subsample * k >= 8192, the initial codebook is
    designed (TSVQ, descent, migration) on a seeded uniform sample of subsample * k distinct
    vectors, then refined on all of them (descent, one migration round).

    ``max_iter`` caps the number of Lloyd iterations of each phase; ``iterations`` counts all of
    them; ``converged`` is False iff the cap stopped the last descent.
    ``init``: None or "tsvq" (default: the paper's greedy TSVQ, :func:`tsvq`, with ``seed``), or
    a (k, d) array (then there is no coarse phase).
    Returns :class:`GlaResult`; ``history`` holds the distortion (all vectors) after the initial
    assignment, after each iteration of the first full-data descent and after each accepted
    migration round (non-increasing).  Indices are the exact full-search nearest codewords.
    With at most k distinct vectors the result is exact (see module docstring).
    Deterministic for a given seed.
    """
    k = _check_k(k)
    if max_iter < 0:
        raise ValueError("max_iter must be >= 0")
    x, w, u, wu, inv = _prepare(vectors, weights)
    zero = np.flatnonzero(inv < 0)  # weight-0 vectors: not trained on, encoded at the end
    xz = x[zero]
    del x  # only the distinct vectors are needed from here on
    if u.shape[0] <= k:
        cb = _pad(u, k)  # row j < M is u[j]: the lowest index holding that vector
        idx, d2 = inv.copy(), np.zeros(inv.size)
        if zero.size:
            idx[zero], d2[zero] = nearest(xz, cb)
        return GlaResult(cb, idx, float(w @ d2) / w.sum(), 0, True, [0.0])
    it0 = 0
    mig_full = migrate
    if init is None or (isinstance(init, str) and init == "tsvq"):
        ns = subsample * k if subsample else 0
        if ns >= _COARSE_MIN and u.shape[0] > _COARSE_FACTOR * ns:
            pick = np.sort(np.random.default_rng(seed).permutation(u.shape[0])[:ns])
            us, wus = u[pick], wu[pick]
            c0 = _tsvq_build(us, wus, k, seed)[0].codebook
            st, _, _, it0, _ = _gla_core(us, wus, k, c0, max_iter, tol, migrate)
            c0 = st.c
            mig_full = min(migrate, _FULL_MIGRATE)
        else:
            c0 = _tsvq_build(u, wu, k, seed)[0].codebook
    elif isinstance(init, str):
        raise ValueError(f"unknown init {init!r}")
    else:
        c0 = np.asarray(init, dtype=np.float64)
        if c0.shape != (k, u.shape[1]) or not np.all(np.isfinite(c0)):
            raise ValueError(f"init must be a finite ({k}, {u.shape[1]}) array")
    st, scr, hist, it, conv = _gla_core(u, wu, k, c0, max_iter, tol, mig_full)
    iu, du = _final_indices(u, st, scr)
    idx = iu[np.maximum(inv, 0)]
    d2 = du[np.maximum(inv, 0)]
    if zero.size:
        idx[zero], d2[zero] = nearest(xz, st.c)
    return GlaResult(st.c, idx, float(w @ d2) / w.sum(), it0 + it, conv, hist)


def design(vectors, k, *, method="gla", seed=0, weights=None, **kw):
    """Design a k-codeword codebook and encode ``vectors`` with it.

    method "gla" (default; ``kw`` goes to :func:`gla`: init, max_iter, tol, migrate, subsample)
    or "tsvq" (``kw``: criterion).
    Returns ``(codebook (k, d) float64, indices (N,) int64)``; indices are the exact full-search
    nearest codewords (for "tsvq" too; use ``tsvq_tree(...).encode`` for tree-search indices).
    Deterministic for a given seed.
    """
    if method == "gla":
        r = gla(vectors, k, seed=seed, weights=weights, **kw)
        return r.codebook, r.indices
    if method == "tsvq":
        cb = tsvq(vectors, k, seed=seed, weights=weights, **kw)
        return cb, nearest(vectors, cb)[0]
    raise ValueError(f"unknown method {method!r}")
