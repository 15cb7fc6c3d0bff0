"""Exact full-search nearest codeword.

Contract: ``nearest(vectors, codebook)`` returns, for each vector, the index of the codeword
minimising the exact float64 squared distance (sum of squared differences) and that distance.
Ties go to the lowest codeword index (``nearest_screened``: to the lowest ``tie[j]`` when
given).  A float32 GEMM (:class:`Screen`) only screens candidates under its rigorous
rounding-error bound; every codeword that could be nearest is settled in float64, so the
result does not depend on the BLAS or on the number of threads.
"""
from __future__ import annotations

import numpy as np

from .inputs import as_vectors
from .screen import U32, Screen, exact_d2

__all__ = ["nearest", "nearest_screened"]

def nearest_screened(x, c, scr: Screen, chunk: int = 0, rows=None, tie=None):
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
    ca, rmax = scr.codebook(c)
    xnorm = scr.xnorm if rows is None else scr.xnorm[rows]
    gam = (d + 4) * U32 * (1 + 1e-3)
    idx = np.empty(n, dtype=np.int64)
    for s, e, sc, best, smax in scr.chunks(ca, rows, chunk):
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
            # per row: smallest exact distance, then lowest codeword index
            order = np.lexsort((cc if tie is None else tie[cc], dd, r))
            r, cc = r[order], cc[order]
            first = np.ones(r.size, dtype=bool)
            first[1:] = r[1:] != r[:-1]
            idx[r[first]] = cc[first]
    return idx, exact_d2(x, c, idx)


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
    x = as_vectors(vectors)
    c = np.asarray(codebook, dtype=np.float64)
    if c.ndim != 2 or c.shape[0] < 1 or c.shape[1] != x.shape[1]:
        raise ValueError(f"codebook must be (k, {x.shape[1]}), got shape {c.shape}")
    if not np.all(np.isfinite(c)):
        raise ValueError("codebook must be finite")
    cu, first = np.unique(c + 0.0, axis=0, return_index=True)  # first = lowest index of a row
    idx, d2 = nearest_screened(x, cu, Screen(x, cu.mean(axis=0)), chunk, tie=first)
    return first[idx], d2
