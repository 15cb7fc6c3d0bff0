"""float32 GEMM screening of codewords, and exact float64 distances.

Contract: :class:`Screen` holds a set of vectors (centred on ``shift``, in float32 with a column
of ones); ``Screen.codebook`` turns a codebook into GEMM columns; ``Screen.chunks`` is the one
chunked matmul-and-argmax loop (about ``SCORE_BYTES`` of float32 scores per chunk, reusing one
buffer); ``Screen.argmax``/``top2`` give the best (first maximum) and second-best screened
codewords.  A screened score s~_j of x against c_j (centred: x', c'_j) approximates
s_j = x'.c'_j - |c'_j|^2 / 2 (larger = nearer; distance = |x'|^2 - 2 s_j) with
|s~_j - s_j| <= (d + 4) u (|x'| |c'_j| + |c'_j|^2 / 2) (1 + 1e-3), u = ``U32``; screened
results are only ever used under that bound.  ``exact_d2`` is the exact float64 squared
distance (the sum of squared differences) of each vector to one codeword, in chunks of
``EXACT_ROWS`` rows on the worker threads (each row's sum does not depend on them); temporaries
stay below ``MAX_TEMP_BYTES``.
"""
from __future__ import annotations

import numpy as np

from .workers import local_buffer, map_ordered

__all__ = ["U32", "SCORE_BYTES", "MAX_TEMP_BYTES", "Screen", "exact_d2"]

U32 = float(np.finfo(np.float32).eps) / 2.0  # unit roundoff of float32
# Score buffer for the float32 screening GEMM: rows per chunk are chosen so that a chunk of
# scores is about this many bytes (keeps argmax in cache; measured best around 1-2 MiB).
SCORE_BYTES = 1 << 21
# Hard cap on any temporary (float64 pairs, chunks): well below the 1 GB budget.
MAX_TEMP_BYTES = 1 << 27
# Rows per chunk of ``exact_d2`` (chunks run on the worker threads).
EXACT_ROWS = 4096


class Screen:
    """float32 GEMM screening of codewords: scores s_j = x'.c'_j - |c'_j|^2/2 (primes: centred).

    Larger score = smaller distance (distance = |x'|^2 - 2 s_j).  ``xa`` holds the centred vectors
    in float32 with a trailing column of ones so one GEMM yields the scores.
    """

    def __init__(self, x: np.ndarray, shift: np.ndarray):
        n, d = x.shape
        self.d = d
        self.shift = shift
        self.xa = np.empty((n, d + 1), dtype=np.float32)
        self.xa[:, d] = 1.0
        self.xnorm = np.empty(n)
        step = max(1, MAX_TEMP_BYTES // (8 * d))  # centred rows in chunks: no (N, d) temporary
        for s in range(0, n, step):
            xc = x[s:s + step] - shift
            self.xa[s:s + step, :d] = xc
            self.xnorm[s:s + step] = np.sqrt(np.einsum("ij,ij->i", xc, xc))
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
        return int(max(32, min(65536, SCORE_BYTES // (4 * k))))

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

    def chunks(self, ca: np.ndarray, rows=None, chunk: int = 0):
        """The screening loop, serial: for consecutive chunks of the vectors (all, or the subset
        ``rows``) yield ``(s, e, sc, best, smax)``: the chunk's row range [s, e) in that order,
        its float32 scores ``sc`` (e - s, k) against the columns ``ca`` (a view of a reused
        buffer, valid until the next chunk; the caller may overwrite it), the first maximum
        ``best`` of each row and its score ``smax``.  ``chunk``: rows per chunk (0 = about
        ``SCORE_BYTES`` of scores).  :meth:`map_chunks` is the same loop on every core."""
        k = ca.shape[1]
        n = self.xa.shape[0] if rows is None else len(rows)
        step = self.rows_per_chunk(k, chunk)
        buf = self.scores_buffer(min(step, n) * k)[: min(step, n) * k].reshape(-1, k)
        for s in range(0, n, step):
            e = min(n, s + step)
            yield (s, e) + self._score(ca, rows, s, e, buf[: e - s])

    def map_chunks(self, ca: np.ndarray, fn, rows=None, chunk: int = 0) -> list:
        """The screening loop on the encoder's worker threads (:mod:`.workers`): calls
        ``fn(s, e, sc, best, smax)`` once per chunk (the arguments of :meth:`chunks`; ``sc`` is
        the calling thread's buffer, valid during the call) and returns the results in chunk
        order.  Chunk boundaries depend on the sizes only, never on the thread count; ``fn``
        must only write to rows [s, e) of shared outputs."""
        k = ca.shape[1]
        n = self.xa.shape[0] if rows is None else len(rows)
        step = self.rows_per_chunk(k, chunk)
        size = min(step, n) * k

        def one(s):
            e = min(n, s + step)
            sc = local_buffer(size, np.float32)[: (e - s) * k].reshape(e - s, k)
            return fn(s, e, *self._score(ca, rows, s, e, sc))

        return map_ordered(one, range(0, n, step))

    def _score(self, ca, rows, s, e, sc):
        xa = self.xa[s:e] if rows is None else np.take(self.xa, rows[s:e], axis=0)
        np.matmul(xa, ca, out=sc)
        best = sc.argmax(axis=1)
        return sc, best, sc[np.arange(e - s), best]

    def _best(self, ca, rows, chunk, two):
        k = ca.shape[1]
        n = self.xa.shape[0] if rows is None else len(rows)
        b1 = np.empty(n, dtype=np.int64)
        b2 = np.full(n, -1, dtype=np.int64)
        s1 = np.empty(n, dtype=np.float32)
        s2 = np.full(n, -np.inf, dtype=np.float32)

        def fn(s, e, sc, best, smax):
            b1[s:e] = best
            s1[s:e] = smax
            if two and k > 1:
                r = np.arange(e - s)
                sc[r, best] = -np.inf
                b2[s:e] = nb = sc.argmax(axis=1)
                s2[s:e] = sc[r, nb]

        self.map_chunks(ca, fn, rows, chunk)
        return b1, b2, s1, s2

    def approx_d2(self, rows, s, ca_rmax):
        """Screened squared distances from scores, lowered by their rounding-error bound
        (so they can serve in lower bounds)."""
        xn = self.xnorm[rows]
        gam = 2.0 * (self.d + 4) * U32 * (1 + 1e-3)
        q = xn * xn - 2.0 * s.astype(np.float64)  # s = -inf (no candidate) gives +inf
        # q - |q| 1e-6 - margin, written so that q = +inf stays +inf
        low = np.minimum(q * (1 - 1e-6), q * (1 + 1e-6))
        low -= 2.0 * gam * ca_rmax * xn + gam * ca_rmax * ca_rmax
        return low


def exact_d2(x: np.ndarray, c: np.ndarray, idx: np.ndarray, rows=None) -> np.ndarray:
    """Exact float64 squared distance of each x[i] to c[idx[i]] (or of x[rows[i]] to c[idx[i]]
    when ``rows`` is given), chunked so that no temporary exceeds ``MAX_TEMP_BYTES``."""
    n, d = idx.shape[0], x.shape[1]
    out = np.empty(n, dtype=np.float64)
    # chunks of EXACT_ROWS rows on the worker threads (each row's sum is independent of them)
    step = max(1, min(EXACT_ROWS, MAX_TEMP_BYTES // (8 * d * (1 if rows is None else 2))))

    def one(s):
        e = min(n, s + step)
        diff = np.take(c, idx[s:e], axis=0)  # one temporary, reused in place (much faster)
        np.subtract(x[s:e] if rows is None else np.take(x, rows[s:e], axis=0), diff, out=diff)
        np.einsum("ij,ij->i", diff, diff, out=out[s:e])

    map_ordered(one, range(0, n, step))
    return out
