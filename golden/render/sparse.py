"""Sparse request streams: only the texels that can change a pixel are requested.

The fixed stream (:class:`~golden.render.sampling.Sampler` with ``stream="fixed"``) issues every
covered pixel's whole footprint, K requests (8 for trilinear), each with an integer weight, and the
pixel is ``(sum_k w_k texel_k + 2^23) >> 24``. Two kinds of request provably cannot change that sum:

- **zero weight**: ``w_k == 0`` (trilinear at an exact level, ``f == 0``, which includes the last
  level and magnification: the whole L1 footprint; ``fu == 0`` or ``fv == 0``: half of a bilinear
  footprint);
- **repeats**: the same (texture, level, i, j) twice in one pixel's footprint (a 1-texel-wide level,
  or clamp at a border, maps i0 and i1 to one texel). The fetch is a function of the request, so both
  answers are the same texel and ``w_a t + w_b t == (w_a + w_b) t``: the first occurrence carries the
  merged weight, the others are dropped. Exact in the integer arithmetic.

:func:`sparse_stream` keeps, per pixel and in the fixed stream's order, the first occurrence of every
distinct request whose merged weight is not zero. The resolved frame is identical, bit for bit, to the
fixed stream's (the per-pixel sum is the same integer); the stream is shorter, so the texel-fetch
unit spends fewer cycles on a frame (one request per clock).

Vectorised: each request becomes one integer key, and the K (K - 1) / 2 pairs of places in a
footprint are compared over all pixels at once; no Python loop over pixels.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["STREAMS", "SkipCounts", "sparse_stream", "stream_offsets", "request_keys"]

#: Request streams a Sampler can issue: ``sparse`` (default) or the constant-rate ``fixed`` one.
STREAMS = ("sparse", "fixed")


@dataclass(frozen=True)
class SkipCounts:
    """What :func:`sparse_stream` left out of a fixed stream of ``fixed`` requests.

    Members:
        fixed: requests of the fixed stream (M K).
        zero_weight: requests left out whose own weight is 0.
        repeats: requests left out whose own weight is not 0: an earlier request of the pixel names
            the same texel and carries it.
    """

    fixed: int
    zero_weight: int
    repeats: int

    @property
    def kept(self) -> int:
        return self.fixed - self.zero_weight - self.repeats

    def as_dict(self) -> dict:
        return {"fixed": self.fixed, "sparse": self.kept, "skipped_zero_weight": self.zero_weight,
                "skipped_repeats": self.repeats}


def sparse_stream(reqs: np.ndarray, weights: np.ndarray, spans=None):
    """The sparse stream of a fixed one.

    Arguments:
        reqs: (M, K, 4) int64 (texture, level, i, j), K requests per pixel in the fixed order.
        weights: (M, K) non-negative integer weights.
        spans: optional bounds of the four columns (each in ``[0, span)``; see :func:`request_keys`).

    Returns:
        (requests (N, 4) int64, weights (N,) of ``weights``' dtype, counts (M,) int64 requests per
        pixel (0 for a pixel whose weights are all 0), :class:`SkipCounts`). Row order is the fixed
        order with the dropped requests removed; per pixel the kept weights sum to the fixed ones'.
    """
    reqs = np.asarray(reqs)
    weights = np.asarray(weights)
    m, k = weights.shape
    if reqs.shape != (m, k, 4):
        raise ValueError(f"requests {reqs.shape} do not match weights {weights.shape}")
    key = request_keys(reqs.reshape(-1, 4), spans).reshape(m, k)
    # first[p, b]: the first of pixel p's requests that names the same texel as its request b
    first = np.broadcast_to(np.arange(k), (m, k)).copy()
    for b in range(k - 1, 0, -1):                        # K (K - 1) / 2 pairs of places, not pixels
        for a in range(b - 1, -1, -1):
            first[key[:, a] == key[:, b], b] = a         # the smallest a wins: it is written last
    # merged[p, a]: the weight of every request of pixel p whose first occurrence is a
    # (float64 sums of integers below 2^53 are exact; the callers' weights sum to 2^24 per pixel)
    if m and k and (int(weights.min()) < 0 or int(weights.max()) * k >= 1 << 53):
        raise ValueError("weights must be non-negative and small enough to add exactly")
    at = (np.arange(m, dtype=np.int64)[:, None] * k + first).ravel()
    merged = np.bincount(at, weights=weights.ravel(), minlength=m * k).astype(np.int64).reshape(m, k)
    keep = merged > 0                                    # only a first occurrence can hold weight
    counts = keep.sum(1)
    dropped_zero = int((~keep & (weights == 0)).sum())
    skip = SkipCounts(m * k, dropped_zero, m * k - int(counts.sum()) - dropped_zero)
    kept = np.flatnonzero(keep)
    return (np.take(reqs.reshape(-1, 4), kept, axis=0), np.take(merged, kept).astype(weights.dtype),
            counts.astype(np.int64), skip)


def request_keys(reqs: np.ndarray, spans=None) -> np.ndarray:
    """(N,) int64, equal exactly where the rows of ``reqs`` (N, 4) are equal: the columns' offsets
    from their minima packed into one number when their spans' product is below 2^62 (always, for
    real textures), else the row's rank among the distinct rows. ``spans``: the caller's promise that
    column c is in ``[0, spans[c])`` (saves finding the minima and maxima)."""
    reqs = np.asarray(reqs, np.int64)
    if len(reqs) == 0:
        return np.zeros(0, np.int64)
    if spans is None:
        lo, hi = reqs.min(0), reqs.max(0)
        spans = [int(h) - int(l) + 1 for l, h in zip(lo, hi)]
    else:
        lo, spans = np.zeros(reqs.shape[1], np.int64), [int(v) for v in spans]
    if np.prod([float(v) for v in spans]) < 2.0 ** 62:
        key = np.zeros(len(reqs), np.int64)
        for c in range(reqs.shape[1]):                   # 4 columns
            key = key * spans[c] + (reqs[:, c] - lo[c])
        return key
    return np.unique(reqs, axis=0, return_inverse=True)[1].reshape(-1).astype(np.int64)


def stream_offsets(counts: np.ndarray) -> np.ndarray:
    """(M,) int64 start of each pixel's requests in a stream with ``counts`` requests per pixel."""
    counts = np.asarray(counts, np.int64)
    out = np.zeros(len(counts), np.int64)
    np.cumsum(counts[:-1], out=out[1:])
    return out
