"""Splitting one TSVQ cell into two (the paper's principal-axis cut, then 2-means).

Contract: ``split_cell`` and ``split_cells`` (many small cells at once, vectorised) return for
a cell a split record ``(mask of the second child, c0, c1, sse0, sse1)`` (children's weighted
centroids and total squared errors; a one-row child's centroid is that row exactly) or None
when the cell cannot be cut.  A cell's split depends only on its rows and its start vector
``v0`` (and the sample ``rng`` gives), never on other cells: deterministic for a seed.
"""
from __future__ import annotations

import numpy as np

__all__ = ["split_cell", "split_cells"]

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


def split_cell(x, w, m, v0, rng, n_power=3, n_lloyd=4, sample=2048):
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


def split_cells(xs, ws, starts, ends, cents, v0, n_power=3, n_lloyd=4):
    """:func:`split_cell` for many small cells at once (segment-vectorised over the concatenated
    rows; no sampling).  Returns a list of split records, None where the batch could not cut a
    cell (the caller then uses :func:`split_cell`)."""
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
