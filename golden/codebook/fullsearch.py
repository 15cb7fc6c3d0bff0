"""Exact full-search nearest codeword.

Contract: ``nearest(vectors, codebook)`` returns, for each vector, the index of the codeword
minimising the true squared distance of the float64 values (sum of squared differences, in
exact arithmetic, not its float64 rounding) and that distance as float64 (the rounded sum).
Ties go to the lowest codeword index (``nearest_screened``: to the lowest ``tie[j]`` when
given).  A float32 GEMM (:class:`Screen`) only screens candidates under its rigorous
rounding-error bound; the candidates are compared in float64, and where float64 cannot tell
them apart (a near or exact tie of non-integral or huge values) in Python integers after
scaling by a power of two (:func:`as_integers`).  The result depends neither on the BLAS nor
on the number of threads.
"""
from __future__ import annotations

import numpy as np

from .inputs import as_vectors
from .screen import U32, Screen, exact_d2
from .workers import one_blas_thread

__all__ = ["nearest", "nearest_screened", "as_integers", "group_starts", "settle",
           "settle_in_integers"]

U64 = 2.0 ** -53  # unit roundoff of float64
# absolute slack per component of the float64 closeness test (squares in the subnormal range)
TINY = 2.0 ** -1000


def as_integers(v: np.ndarray) -> np.ndarray:
    """Exact Python integers ``v * 2^s`` (object array, same shape) for one s >= 0 that makes
    every value of ``v`` (finite float64) integral: equal values map to equal integers and
    every sum or product of them is exact."""
    m, e = np.frexp(np.asarray(v, dtype=np.float64))  # v = m 2^e, 0.5 <= |m| < 1 (or 0)
    mi = np.ldexp(m, 53).astype(np.int64)              # exact: 53-bit mantissas
    sh = e.astype(np.int64) - 53                       # v = mi 2^sh
    nz = mi != 0
    s = max(0, -int(sh[nz].min())) if nz.any() else 0
    return np.left_shift(mi.astype(object), np.where(nz, sh + s, 0).astype(object))


def group_starts(r: np.ndarray) -> np.ndarray:
    """Boolean mask of the first element of every run of equal values in ``r`` (any length)."""
    first = np.ones(r.size, dtype=bool)
    first[1:] = r[1:] != r[:-1]
    return first


def settle(x, c, r, cc, dd, tk):
    """The nearest candidate of each row among (row, candidate) pairs: ``r`` rows (grouped,
    ascending), ``cc`` codeword indices, ``dd`` their float64 distances (``exact_d2``), ``tk``
    the tie key of each pair (lower wins).  Returns (rows, winners), one per distinct row.

    Pairs whose float64 distance is within its rounding bound ((d + 4) 2^-53 relative) of the
    row's least are the row's contenders; a row with several is decided by float64 when it is
    exact there (integral values, distances below 2^53), else in Python integers
    (:func:`settle_in_integers`)."""
    d = x.shape[1]
    start = np.flatnonzero(group_starts(r))
    size = np.diff(np.r_[start, r.size])
    least = np.repeat(np.minimum.reduceat(dd, start), size)
    close = dd <= least * (1.0 + 4.0 * (d + 4) * U64) + d * TINY
    xr = x[r[start]]
    inexact = np.repeat(~np.all(np.floor(xr) == xr, axis=1), size)
    inexact |= ~np.all(np.floor(c) == c, axis=1)[cc] | ~(dd < 2.0 ** 53)
    hard_row = ((np.add.reduceat(close.astype(np.int64), start) > 1)
                & (np.add.reduceat((close & inexact).astype(np.int64), start) > 0))
    hard = np.repeat(hard_row, size) & close
    easy = ~np.repeat(hard_row, size)  # float64 decides: smallest distance, then lowest key
    order = np.lexsort((tk[easy], dd[easy], r[easy]))
    re, ce = r[easy][order], cc[easy][order]
    first = group_starts(re)
    win_r, win_c = [re[first]], [ce[first]]
    if hard.any():
        rh, ch = settle_in_integers(x, c, r[hard], cc[hard], tk[hard])
        win_r.append(rh)
        win_c.append(ch)
    return np.concatenate(win_r), np.concatenate(win_c)


def settle_in_integers(x, c, r, cc, tk, elements: int = 1 << 18):
    """``settle`` in exact arithmetic: (rows, winners) of the pairs (``r`` grouped ascending,
    ``cc``, tie keys ``tk``), each row's least exact squared distance, then least key.  Python
    integers (:func:`as_integers`) in chunks of whole rows of about ``elements`` values."""
    d = x.shape[1]
    st = np.flatnonzero(group_starts(r))
    cuts = np.unique(st[np.searchsorted(st, np.arange(0, r.size, max(1, elements // d)),
                                        side="right") - 1])
    win_r, win_c = [], []
    for a, b in zip(cuts, np.r_[cuts[1:], r.size]):
        rh, ch, th = r[a:b], cc[a:b], tk[a:b]
        xi = as_integers(np.concatenate([x[rh].ravel(), c[ch].ravel()]))
        di = ((xi[: rh.size * d] - xi[rh.size * d:]) ** 2).reshape(rh.size, d).sum(axis=1)
        gs = np.flatnonzero(group_starts(rh))
        best = (di == np.repeat(np.minimum.reduceat(di, gs), np.diff(np.r_[gs, rh.size])))
        best = best.astype(bool)  # (object comparisons)
        order = np.lexsort((th[best], rh[best]))
        rb, cb = rh[best][order], ch[best][order]
        first = group_starts(rb)
        win_r.append(rb[first])
        win_c.append(cb[first])
    return np.concatenate(win_r), np.concatenate(win_c)


def nearest_screened(x, c, scr: Screen, chunk: int = 0, rows=None, tie=None):
    """Exact nearest codeword (ties -> lowest index) using float32 screening + float64 settling.

    Error bound of a screened score (x', c' centred; u = 2^-24; GEMM of d+1 terms in float32):
        |s~_j - s_j| <= E = (d + 4) u (|x'| |c'_j| + |c'_j|^2 / 2) (1 + 1e-3)
    so every codeword whose screened score is within 2E of the best screened score is a candidate,
    and the true nearest is always among them.  Rows with a single candidate are decided by the
    screen; the others are settled, chunk by chunk, with exact float64 distances, ties to the
    lowest index (or the lowest ``tie[j]`` when given), exactly (:func:`settle`).
    ``rows``: only these vectors (x must then be the matching subset).
    """
    n, d = x.shape
    ca, rmax = scr.codebook(c)
    xnorm = scr.xnorm if rows is None else scr.xnorm[rows]
    gam = (d + 4) * U32 * (1 + 1e-3)
    idx = np.empty(n, dtype=np.int64)

    def one_chunk(s, e, sc, best, smax):  # writes rows [s, e) of idx only
        idx[s:e] = best
        margin = (2.0 * gam * (xnorm[s:e] * rmax + 0.5 * rmax * rmax)).astype(np.float32)
        # float32 rounding of the threshold itself: widen by a few more ulps
        thr = smax - margin - np.abs(smax) * np.float32(4 * U32)
        cand = sc >= thr[:, None]
        amb = np.flatnonzero(np.count_nonzero(cand, axis=1) > 1)
        if amb.size:
            r, cc = np.nonzero(cand[amb])
            r = amb[r] + s
            dd = exact_d2(x, c, cc, rows=r)  # no (pairs, d) copy of x: bounded memory
            won_r, won_c = settle(x, c, r, cc, dd, cc if tie is None else tie[cc])
            idx[won_r] = won_c

    scr.map_chunks(ca, one_chunk, rows, chunk)
    return idx, exact_d2(x, c, idx)


@one_blas_thread
def nearest(vectors: np.ndarray, codebook: np.ndarray, chunk: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Full-search nearest codeword.

    Parameters: ``vectors`` (N, d) real, ``codebook`` (k, d) real, ``chunk`` rows per distance
    chunk (0 = automatic, about 2 MiB of float32 scores per chunk; memory stays far below 1 GB).

    Returns ``(indices, d2)``: int64 (N,) index of the codeword minimising the squared distance
    (sum of squared differences of the float64 values, in exact arithmetic), ties to the lowest
    index, and float64 (N,) that distance (rounded).  Exact: a float32 GEMM only screens
    candidates under a rigorous rounding-error bound; close calls are settled in float64, and
    those float64 cannot separate in integers.  Repeated codewords are searched once (the
    lowest index answers).  Deterministic, and independent of the BLAS.
    """
    x = as_vectors(vectors)
    c = np.asarray(codebook, dtype=np.float64)
    if c.ndim != 2 or c.shape[0] < 1 or c.shape[1] != x.shape[1]:
        raise ValueError(f"codebook must be (k, {x.shape[1]}), got shape {c.shape}")
    if not np.all(np.isfinite(c)):
        raise ValueError("codebook must be finite")
    cu, first = np.unique(c + 0.0, axis=0, return_index=True)  # first = lowest index of a row
    idx, d2 = nearest_screened(x, cu, Screen(x, cu.mean(axis=0)), chunk, tie=first)
    return first[idx], d2
