"""Reassignment of vectors to codewords with Hamerly/Elkan bounds (the Lloyd step's search).

Contract: a :class:`State` holds a codebook ``c``, each vector's codeword ``a``, its exact
squared distance ``d2`` and ``lb``, a lower bound of the distance to every other codeword.
``assign_full`` and ``reassign`` return a new State in which each vector has moved to its
nearest codeword (exact in exact arithmetic; candidates screened under the error bound of
:mod:`.screen`); a vector changes codeword only when the exact float64 distance strictly
decreases, so the distortion never increases.  The GLA's final indices are certified against
``lb`` or settled by the exact search (:func:`.fullsearch.nearest_screened`).
"""
from __future__ import annotations

import numpy as np

from .screen import SCORE_BYTES, U32, exact_d2
from .workers import map_ordered

__all__ = ["State", "assign_full", "reassign"]

class State:
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
        e1[ch] = exact_d2(u[rows[ch]], c, b1[ch])
    take = np.zeros(rows.size, dtype=bool)
    take[ch] = e1[ch] < d[ch]
    na = np.where(take, b1, a)
    nd = np.where(take, e1, d)
    o = np.minimum(np.where(take, d, np.inf), np.where(b1 != na, q1, np.inf))
    o = np.minimum(o, np.where((b2 >= 0) & (b2 != na), q2, np.inf))
    return na, nd, np.minimum(rest, np.sqrt(np.maximum(o, 0.0)))


def assign_full(u, c, scr, chunk=0):
    """Fresh assignment of every vector: screened top-2 over the whole codebook."""
    ca, rmax = scr.codebook(c)
    rows = np.arange(u.shape[0])
    b1, b2, s1, s2 = scr.top2(ca, chunk=chunk)
    e1 = exact_d2(u, c, b1)
    a, d2, lb = _combine(u, c, scr, rmax, rows, b1, e1, b1, b2, s1, s2,
                         np.full(rows.size, np.inf))
    return State(c, a, d2, lb)


# Per-vector overhead of screening a vector against a column subset, in units of one score
# (gathers, two argmax passes, bookkeeping); measured ~100 ns against ~0.5 ns per score.
_ROW_COST = 200


# Bound of |T_ij - D_ij| / rmax^2 for the float32 distances T_ij = fl(fl(cn_i) - 2 s~_ij) of two
# codewords (D_ij exact, rmax the largest centred codeword norm): twice the screened score's error,
# 2 (d + 4) u (|c_i| |c_j| + |c_j|^2 / 2) (1 + 1e-3) <= 3 (d + 4) u rmax^2 (1 + 1e-3), plus the
# rounding of cn_i and of the sum, at most 5 u rmax^2 (1 + 1e-6).
def _subset_err(d):
    return 3.0 * (d + 4) * U32 * (1 + 1e-3) + 5.1 * U32


def _half_gaps(c, scr, moved=None, old=None, cols=None):
    """Lower bounds of s_j = half the distance from codeword j to its nearest other codeword
    (Elkan's bound), from float32 screening lowered by its error bound.

    With ``moved`` (indices of the codewords that changed) and ``old`` (the bounds before the
    change) only the rows of the moved codewords are screened: a codeword that did not move is
    at least as far from every unmoved codeword as before, so its new bound is the smaller of
    its old bound and half its distance to the nearest moved codeword.  ``cols``: the result of
    ``scr.codebook(c)`` when the caller has it."""
    k = c.shape[0]
    if k < 2:
        return np.full(k, np.inf)
    rows = np.arange(k) if moved is None or old is None or 2 * moved.size > k else moved
    cc = c - scr.shift
    ca, rmax = scr.codebook(c) if cols is None else cols
    cn = np.einsum("ij,ij->i", cc, cc)
    cn32 = cn.astype(np.float32)
    xa = np.empty((rows.size, scr.d + 1), dtype=np.float32)
    xa[:, : scr.d] = cc[rows]
    xa[:, scr.d] = 1.0
    gam = 2.0 * (scr.d + 4) * U32 * (1 + 1e-3)
    row_min = np.empty(rows.size)
    col_min = np.full(k, np.inf)
    step = max(1, SCORE_BYTES // (4 * k))

    full = rows.size == k

    def one_chunk(s0):  # rows [s0, e) of row_min; its column minima are returned (min is exact)
        e = min(rows.size, s0 + step)
        sc = xa[s0:e] @ ca
        r_cn = cn[rows[s0:e]]
        if full:
            # every row screened: no column minima needed, and the row minimum of the distances
            # r_cn - 2 s is r_cn - 2 max(s) (monotone, exact), lowered by its bound once
            sc[np.arange(e - s0), rows[s0:e]] = -np.inf  # not its own neighbour
            q = r_cn - 2.0 * sc.max(axis=1).astype(np.float64)
            q -= 2.0 * gam * (np.sqrt(r_cn) * rmax + 0.5 * rmax * rmax) + np.abs(q) * 1e-6
            row_min[s0:e] = q
            return None
        # squared distances in float32, T = fl(cn_i - 2 s~_ij), one pass in place; the rounding
        # of T and of the screened scores is lowered once, after the minima (_subset_err)
        sc *= -2.0
        sc += cn32[rows[s0:e], None]
        sc[np.arange(e - s0), rows[s0:e]] = np.inf  # not its own neighbour
        row_min[s0:e] = sc.min(axis=1)
        return sc.min(axis=0)

    for part in map_ordered(one_chunk, range(0, rows.size, step)):
        if part is not None:
            np.minimum(col_min, part, out=col_min)
    out = np.empty(k)
    if full:
        out[:] = 0.5 * np.sqrt(np.maximum(row_min, 0.0))
        return out
    err = _subset_err(scr.d) * rmax * rmax
    # q - |q| 1e-6 - err, written so that q = +inf (no other codeword screened) stays +inf
    col_min = np.minimum(col_min * (1 - 1e-6), col_min * (1 + 1e-6)) - err
    row_min = np.minimum(row_min * (1 - 1e-6), row_min * (1 + 1e-6)) - err
    out[:] = np.minimum(old, 0.5 * np.sqrt(np.maximum(col_min, 0.0)))
    out[rows] = 0.5 * np.sqrt(np.maximum(row_min, 0.0))
    return out


def reassign(u, scr, st: State, c_new, chunk=0, force=None):
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
        return State(c_new, a, d2, lb, st.gaps)
    diff = c_new - st.c
    drift = np.sqrt(np.einsum("ij,ij->i", diff, diff)) * (1 + 1e-12)
    mv = np.flatnonzero(moved)
    pm = moved[a]
    if force is not None:
        pm |= force
        lb[force] = 0.0
    rows = np.flatnonzero(pm)
    if rows.size > n // 2:
        d2 = np.where(pm, exact_d2(u, c_new, a), d2)
    elif rows.size:
        d2[rows] = exact_d2(u[rows], c_new, a[rows])
    ub = np.sqrt(d2) * (1 + 1e-12)
    mv_sorted = mv[np.argsort(-drift[mv], kind="stable")]
    ds = np.append(drift[mv_sorted], 0.0)  # ds[t]: largest drift outside the t largest movers
    ca, rmax = scr.codebook(c_new)
    gaps = _half_gaps(c_new, scr, mv, st.gaps, (ca, rmax))
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
    return State(c_new, a, d2, new_lb, gaps)
