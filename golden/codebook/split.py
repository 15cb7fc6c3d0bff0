"""Splitting one TSVQ cell into two (the paper's principal-axis cut, then 2-means).

Contract: ``split_cell`` and ``split_padded`` (a group of cells at once, padded to one length,
every pass over the rows one batched matmul) return for a cell a split record ``(mask of the
second child, c0, c1, sse0, sse1)`` (children's weighted centroids and total squared errors; a
one-row child's centroid is that row exactly) or None when the cell cannot be cut.  A cell's
split depends only on its rows and its start vector ``v0`` (and the sample ``rng`` gives):
deterministic for a seed.  ``split_padded`` computes what ``split_cell`` computes without a
sample; the two differ only in the rounding of the sums (tests/golden/codebook/test_tsvq_batches.py).
"""
from __future__ import annotations

import numpy as np

__all__ = ["split_cell", "split_padded"]

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
    return mask, c0.astype(np.float64), c1.astype(np.float64), e0, e1


def split_cell(x, w, m, v0, rng, n_power=3, n_lloyd=4, sample=2048):
    """Split one cell (x (n, d), weights w, centroid m) into two.

    Initial cut: along the principal axis (power iteration from ``v0``), at the 1-D 2-means
    optimum of the projections (unlike a cut through the centroid this isolates a small, far
    group, e.g. a few brown texels among green ones); then up to ``n_lloyd`` weighted 2-means
    iterations.  Cells of more than ``sample`` vectors fit the cut on a random sample (``rng``)
    of that size, then partition all their vectors with it.  Returns the split record
    ``(mask of the second child, c0, c1, sse0, sse1)`` or None if the vectors cannot be
    separated.  ``rng``: a callable returning the Generator (made only when needed).  The
    arithmetic runs in the dtype of ``x`` (the TSVQ gives float32); centroids are returned as
    float64."""
    n = x.shape[0]
    w = w.astype(x.dtype, copy=False)
    m = np.asarray(m, dtype=x.dtype)
    if n > sample:
        pick = np.sort(rng().choice(n, size=sample, replace=False))
        xs, ws = x[pick], w[pick]
    else:
        xs, ws = x, w
    xc = xs - m
    v = v0.astype(x.dtype)
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


def split_padded(xs, ws, idx, n, cents, v0, n_power=3, n_lloyd=4):
    """:func:`split_cell` for a group of cells at once (no sampling), padded to one length so
    that every pass over the rows is one batched matmul (no per-row temporaries).

    ``idx`` (b, L) int: row j < n[c] of cell c is ``xs[idx[c, j]]`` (entries j >= n[c] are
    padding: any valid row, ignored); ``cents`` (b, d) the cells' centroids, ``v0`` (b, d)
    their start vectors.  Returns one split record per cell (the mask over its n[c] rows in
    ``idx`` order), None where the cell could not be cut (the caller then uses
    :func:`split_cell`).  Each cell's result depends on its own rows only.

    The passes over the rows run in the dtype of ``xs`` (the TSVQ gives float32: half the
    memory traffic; the cut's 1-D search, the returned centroids and errors are float64)."""
    b, L = idx.shape
    ft = xs.dtype
    valid = np.arange(L) < n[:, None]
    xc = xs[idx]  # (b, L, d), a copy
    xc -= cents.astype(ft)[:, None, :]
    xc[~valid] = 0.0
    wv = np.where(valid, ws[idx], 0.0).astype(ft)

    def proj(v):  # (b, d) -> (b, L): every row of each cell against its cell's vector
        return np.matmul(v[:, None, :], xc.transpose(0, 2, 1))[:, 0]

    def wsum(wr):  # (b, L) -> (b, d): weighted sum of each cell's rows
        return np.matmul(wr[:, None, :], xc)[:, 0]

    v = v0.astype(ft)
    for _ in range(n_power):
        vn = wsum(wv * proj(v))
        nv = np.sqrt(np.einsum("ij,ij->i", vn, vn))
        good = nv > 0
        v[good] = vn[good] / nv[good, None]
    p = proj(v).astype(np.float64)
    # 1-D 2-means optimum per cell over its sorted projections (padding sorts last, weight 0)
    o = np.argsort(np.where(valid, p, np.inf), axis=1, kind="stable")
    ps = np.take_along_axis(p, o, axis=1)
    wsr = np.take_along_axis(wv, o, axis=1).astype(np.float64)
    cw = np.cumsum(wsr, axis=1)
    cs = np.cumsum(wsr * ps, axis=1)
    wt, stt = cw[:, -1:], cs[:, -1:]
    cut = np.zeros((b, L), dtype=bool)  # a cut after sorted position j: j < n-1, distinct values
    cut[:, :-1] = (np.arange(L - 1) < (n - 1)[:, None]) & (ps[:, 1:] > ps[:, :-1])
    with np.errstate(divide="ignore", invalid="ignore"):
        score = np.where(cut, cs * cs / cw + (stt - cs) ** 2 / (wt - cw), -np.inf)
    j = score.argmax(axis=1)  # the first maximiser
    rows = np.arange(b)
    okcut = np.isfinite(score[rows, j])
    jn = np.minimum(j + 1, L - 1)
    thr = np.where(okcut, 0.5 * (ps[rows, j] + ps[rows, jn]), np.inf)
    mask = (p > thr[:, None]) & valid
    wtot = wv.sum(axis=1)
    stot = wsum(wv)
    zero = ft.type(0)
    for _ in range(n_lloyd):
        w1 = np.where(mask, wv, zero)
        ww1 = w1.sum(axis=1)
        s1 = wsum(w1)
        n1 = mask.sum(axis=1)
        live = (n1 > 0) & (n1 < n)
        with np.errstate(divide="ignore", invalid="ignore"):
            c1 = s1 / ww1[:, None]
            c0 = (stot - s1) / (wtot - ww1)[:, None]
        dv = c1 - c0
        th = 0.5 * (np.einsum("ij,ij->i", c1, c1) - np.einsum("ij,ij->i", c0, c0))
        dv[~live] = 0.0
        th[~live] = 0.0
        new = (proj(dv) > th[:, None]) & valid
        nn1 = new.sum(axis=1)
        upd = live & (nn1 > 0) & (nn1 < n)
        new = np.where(upd[:, None], new, mask)
        if np.array_equal(new, mask):
            break
        mask = new
    # children statistics (centred sums, then back to the original coordinates)
    n1 = mask.sum(axis=1)
    w1 = np.where(mask, wv, zero)
    w0 = wv - w1
    ww1, ww0 = w1.sum(axis=1), w0.sum(axis=1)
    ok = (n1 > 0) & (n1 < n)
    with np.errstate(divide="ignore", invalid="ignore"):
        c1 = wsum(w1) / ww1[:, None]
        c0 = wsum(w0) / ww0[:, None]
    # SSE = sum w |xc|^2 - W |c|^2 per side (centred at the parent: mild cancellation)
    wxx = (wv * np.einsum("ijk,ijk->ij", xc, xc)).astype(np.float64)
    c1, c0, ww1, ww0 = (a.astype(np.float64) for a in (c1, c0, ww1, ww0))
    sse1 = np.where(mask, wxx, 0.0).sum(axis=1) - ww1 * np.einsum("ij,ij->i", c1, c1)
    sse0 = np.where(mask, 0.0, wxx).sum(axis=1) - ww0 * np.einsum("ij,ij->i", c0, c0)
    sse1, sse0 = np.maximum(sse1, 0.0), np.maximum(sse0, 0.0)
    c1 += cents
    c0 += cents
    # one-row children: the row itself, exactly
    one1 = ok & (n1 == 1)
    one0 = ok & (n - n1 == 1)
    c1[one1] = xs[idx[one1, mask[one1].argmax(axis=1)]]
    c0[one0] = xs[idx[one0, (valid[one0] & ~mask[one0]).argmax(axis=1)]]
    sse1[one1] = 0.0
    sse0[one0] = 0.0
    return [(mask[i, :n[i]], c0[i], c1[i], float(sse0[i]), float(sse1[i])) if ok[i] else None
            for i in range(b)]  # one record per cell (bookkeeping only, no arithmetic per row)
