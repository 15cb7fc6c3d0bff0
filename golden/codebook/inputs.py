"""Input checks and deduplication shared by every codebook design function.

Contract: ``as_vectors`` returns a C-contiguous float64 copy of an (N, d) real, finite array
with -0.0 mapped to +0.0 (or raises ValueError); ``as_weights`` an (N,) float64 array of finite
weights >= 0 with a positive sum (ones when None); ``check_k`` a positive int.
``unique_weighted`` merges bit-identical rows and adds their weights, deterministically;
``prepare`` does all of that and drops distinct rows of weight 0 (their ``inverse`` is -1).
``pad`` repeats rows in ``np.resize`` order up to k; ``wmean`` is the weighted mean row.
"""
from __future__ import annotations

import numpy as np

__all__ = ["as_vectors", "as_weights", "check_k", "row_hash", "unique_weighted", "prepare",
           "pad", "wmean"]

def as_vectors(vectors) -> np.ndarray:
    x = np.asarray(vectors)
    if x.ndim != 2 or x.shape[0] < 1 or x.shape[1] < 1:
        raise ValueError(f"vectors must be a non-empty (N, d) array, got shape {x.shape}")
    if not np.issubdtype(x.dtype, np.number) or np.iscomplexobj(x):
        raise ValueError("vectors must be real numbers")
    x = np.array(x, dtype=np.float64, order="C")  # a copy
    x += 0.0  # -0.0 -> +0.0 for dedup (in place: one copy of the vectors, not two)
    if not np.all(np.isfinite(x)):
        raise ValueError("vectors must be finite")
    return x


def as_weights(weights, n: int) -> np.ndarray:
    if weights is None:
        return np.ones(n, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64).reshape(-1)
    if w.shape[0] != n:
        raise ValueError(f"weights must have shape ({n},), got {np.shape(weights)}")
    if not np.all(np.isfinite(w)) or np.any(w < 0) or not w.sum() > 0:
        raise ValueError("weights must be finite, >= 0 and have a positive sum")
    return w


def check_k(k) -> int:
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
        raise ValueError(f"k must be a positive integer, got {k!r}")
    return int(k)


def row_hash(x: np.ndarray) -> np.ndarray:
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


def _rows_equal(x: np.ndarray, u: np.ndarray, inv: np.ndarray) -> bool:
    """x == u[inv], compared in chunks of about 64 MiB (no full (N, d) copy)."""
    step = max(1, (1 << 26) // (8 * x.shape[1]))
    return all(np.array_equal(x[s:s + step], np.take(u, inv[s:s + step], axis=0))
               for s in range(0, x.shape[0], step))


def unique_weighted(x: np.ndarray, w: np.ndarray):
    """Merge identical rows of ``x`` (float64, (N, d)) and add their weights.

    Returns ``(u, wu, inverse)``: the distinct rows ``u`` (M, d) float64 in a deterministic order,
    their summed weights ``wu`` (M,) and ``inverse`` (N,) int64 with ``u[inverse] == x``.
    Rows are compared bit for bit (call with -0.0 already mapped to +0.0).
    """
    x = np.ascontiguousarray(x, dtype=np.float64)
    h = row_hash(x)
    _, first, inv = np.unique(h, return_index=True, return_inverse=True)
    inv = inv.reshape(-1)
    u = np.take(x, first, axis=0)
    if not _rows_equal(x, u, inv):
        # a hash collision (astronomically rare): exact lexicographic dedup
        u, inv = np.unique(x, axis=0, return_inverse=True)
        inv = inv.reshape(-1)
    wu = np.bincount(inv, weights=w, minlength=u.shape[0])
    return u, wu, inv.astype(np.int64, copy=False)


def prepare(vectors, weights):
    """-> (x (N,d), w (N,), u (M,d) distinct rows with positive weight, wu (M,), inv (N,) or -1)."""
    x = as_vectors(vectors)
    w = as_weights(weights, x.shape[0])
    u, wu, inv = unique_weighted(x, w)
    keep = wu > 0
    if not keep.all():
        remap = np.full(u.shape[0], -1, dtype=np.int64)
        remap[keep] = np.arange(int(keep.sum()))
        u, wu, inv = u[keep], wu[keep], remap[inv]
    return x, w, u, wu, inv


def pad(codebook: np.ndarray, k: int) -> np.ndarray:
    """Repeat rows (np.resize order) up to k rows; the first rows are kept exactly."""
    if codebook.shape[0] == k:
        return codebook
    return np.resize(codebook, (k, codebook.shape[1])).astype(np.float64, copy=False)


def wmean(x, w):
    return (w @ x) / w.sum()
