"""Scan conversion: clipping, fixed-point edge functions, z-buffer, perspective-correct (s, t).

Pipeline for a batch of triangles given in clip space (x, y, w per vertex; OpenGL conventions,
w = -z_eye):

1. **Clipping** against the near plane ``w >= near`` and a guard band ``|x|, |y| <= G w`` (G keeps
   screen coordinates below 2^19 pixels so the integer edge functions cannot overflow). A triangle
   with one vertex out becomes two triangles, with two out one. A new vertex on an edge is always
   computed from the inside endpoint towards the outside one, ``P = P_in + d_in/(d_in - d_out) *
   (P_out - P_in)``, so two triangles sharing that edge get bit-identical vertices (no cracks).
   (s, t) are interpolated linearly in clip space, which is correct before the perspective divide.
2. **Snapping**: screen positions ``X = (x/w + 1) W/2``, ``Y = (1 - y/w) H/2`` (y down) are rounded
   to ``SUBPIXEL_BITS`` = 8 fractional bits (int64).
3. **Coverage**: the pixel centres (x + 1/2, y + 1/2) inside each triangle's bounding box are tested
   with exact integer edge functions ``E_ab(p) = (bx-ax)(py-ay) - (by-ay)(px-ax)`` after orienting the
   triangle so its area is positive. A centre exactly on an edge belongs to the triangle only if the
   edge is a *top* edge (horizontal, interior below) or a *left* edge (interior to its right):
   ``dy < 0 or (dy == 0 and dx > 0)`` for the oriented edge (dx, dy). So a pixel centre on an edge
   shared by two triangles is drawn exactly once. Degenerate (zero-area) triangles draw nothing.
4. **Depth test**: q = 1/w is affine in screen space; per pixel the fragment with the largest q
   (nearest) wins, ties going to the lowest triangle index (submission order), so the result does
   not depend on evaluation order.
5. **Interpolation** of the winner at the pixel centre: u = s q, v = t q and q are affine in screen
   space, u = u0 + a_u (x - x0) + b_u (y - y0) from the snapped vertices; s = u/q, t = v/q.
   Analytic screen derivatives of the perspective-correct interpolants:
   ``ds/dx = (a_u - s a_q) / q``, ``ds/dy = (b_u - s b_q) / q`` (and the same for t).

**Limits** (checked by :func:`rasterize`, ValueError otherwise): every clip-space coordinate and
texture coordinate is finite; a triangle that is clipped (a vertex outside a plane, not wholly
behind the near plane) has every coordinate
``|x|, |y|, |w|`` at most ``CLIP_RANGE * near`` (2^40 near, about 1.1e12 near). Within it a cut
vertex is off by a few ``2^-52 * 2^40 * near`` in clip space, a small fraction of a pixel where it
matters (coverage is exact: a full-screen quad covers every pixel once at every scale up to the
bound); beyond it float64 cannot place the cut vertices (a quad scaled by 1e21 came out as half the
frame), so such a triangle is refused rather than drawn wrong. A triangle that needs no clipping
(inside the guard band, in front of the near plane) has no bound but finiteness: it scales exactly.
The interpolated (s, t) and their derivatives must come out finite (ValueError otherwise).

Everything is vectorised: triangles' bounding boxes (split into bands of rows when large) are
processed in steps of at most ``CHUNK`` candidate pixels; there is no Python loop over pixels.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "SUBPIXEL_BITS", "Fragments", "clip_triangles", "to_screen", "snap", "coverage",
    "rasterize_screen", "rasterize", "CLIP_RANGE",
]

SUBPIXEL_BITS = 8
CHUNK = 1 << 20  # candidate pixels per vectorised step
_ONE = 1 << SUBPIXEL_BITS
_HALF = _ONE >> 1
_GUARD_PIXELS = float(1 << 19)
#: A triangle that needs clipping has every |x|, |y|, |w| at most CLIP_RANGE * near (module docstring).
CLIP_RANGE = float(1 << 40)


@dataclass
class Fragments:
    """The visible fragment of every covered pixel, one entry per pixel in row-major order.

    Members:
        width, height: frame size.
        pixel: (M,) int64 ``y * width + x``, strictly increasing.
        tri: (M,) int64 index of the winning input triangle.
        tex: (M,) int64 texture id of that triangle.
        s, t: (M,) float64 perspective-correct texture coordinates at the pixel centre.
        dsdx, dsdy, dtdx, dtdy: (M,) float64 analytic screen-space derivatives of s and t.
    """

    width: int
    height: int
    pixel: np.ndarray
    tri: np.ndarray
    tex: np.ndarray
    s: np.ndarray
    t: np.ndarray
    dsdx: np.ndarray
    dsdy: np.ndarray
    dtdx: np.ndarray
    dtdy: np.ndarray

    def __len__(self) -> int:
        return len(self.pixel)


def _clip_plane(verts: np.ndarray, attrs: np.ndarray, ids: np.ndarray, dist: np.ndarray):
    """Clip triangles (T, 3, 4) against the half-space dist >= 0 (dist (T, 3) per vertex)."""
    inside = dist >= 0
    n_in = inside.sum(1)
    keep = n_in == 3
    out_v, out_a, out_i = [verts[keep]], [attrs[keep]], [ids[keep]]

    def cut(vi, ai, di, vo, ao, do):
        # from the inside vertex towards the outside one: identical for both triangles of an edge
        f = (di / (di - do))[:, None]
        return vi + f * (vo - vi), ai + f * (ao - ai)

    for n_keep in (1, 2):
        sel = np.nonzero(n_in == n_keep)[0]
        if not len(sel):
            continue
        v, a, d, ins = verts[sel], attrs[sel], dist[sel], inside[sel]
        # rotate so that vertex 0 is the odd one out (the only inside / the only outside vertex)
        odd = ins if n_keep == 1 else ~ins
        r = np.argmax(odd, axis=1)
        order = (r[:, None] + np.arange(3)[None, :]) % 3
        rows = np.arange(len(sel))[:, None]
        v, a, d = v[rows, order], a[rows, order], d[rows, order]
        if n_keep == 1:  # (in, out1, out2) -> (in, I1, I2)
            p1, a1 = cut(v[:, 0], a[:, 0], d[:, 0], v[:, 1], a[:, 1], d[:, 1])
            p2, a2 = cut(v[:, 0], a[:, 0], d[:, 0], v[:, 2], a[:, 2], d[:, 2])
            out_v.append(np.stack([v[:, 0], p1, p2], 1))
            out_a.append(np.stack([a[:, 0], a1, a2], 1))
            out_i.append(ids[sel])
        else:  # (out, in1, in2) -> (I1, in1, in2) + (I1, in2, I2)
            p1, a1 = cut(v[:, 1], a[:, 1], d[:, 1], v[:, 0], a[:, 0], d[:, 0])
            p2, a2 = cut(v[:, 2], a[:, 2], d[:, 2], v[:, 0], a[:, 0], d[:, 0])
            out_v += [np.stack([p1, v[:, 1], v[:, 2]], 1), np.stack([p1, v[:, 2], p2], 1)]
            out_a += [np.stack([a1, a[:, 1], a[:, 2]], 1), np.stack([a1, a[:, 2], a2], 1)]
            out_i += [ids[sel], ids[sel]]
    return np.concatenate(out_v), np.concatenate(out_a), np.concatenate(out_i)


def clip_triangles(clip: np.ndarray, attrs: np.ndarray, width: int, height: int, near: float):
    """Clip (T, 3, 4) clip-space triangles (x, y, z, w) with (T, 3, K) attributes.

    Returns (clip', attrs', source) where source[k] is the input triangle of output triangle k;
    output triangles keep the order of their sources.
    """
    clip = np.asarray(clip, np.float64)
    attrs = np.asarray(attrs, np.float64)
    ids = np.arange(len(clip))
    gx = _GUARD_PIXELS / (width / 2.0)
    gy = _GUARD_PIXELS / (height / 2.0)
    planes = [
        lambda v: v[..., 3] - near,
        lambda v: gx * v[..., 3] - v[..., 0],
        lambda v: gx * v[..., 3] + v[..., 0],
        lambda v: gy * v[..., 3] - v[..., 1],
        lambda v: gy * v[..., 3] + v[..., 1],
    ]
    for plane in planes:
        d = plane(clip)
        if (d >= 0).all():
            continue
        clip, attrs, ids = _clip_plane(clip, attrs, ids, d)
    order = np.argsort(ids, kind="stable")
    return clip[order], attrs[order], ids[order]


def to_screen(clip: np.ndarray, width: int, height: int) -> np.ndarray:
    """Screen positions (..., 2) of clip-space points (..., 4) with w > 0 (y down)."""
    w = clip[..., 3]
    x = (clip[..., 0] / w + 1.0) * (width / 2.0)
    y = (1.0 - clip[..., 1] / w) * (height / 2.0)
    return np.stack([x, y], -1)


def snap(xy: np.ndarray) -> np.ndarray:
    """Screen positions to int64 fixed point with SUBPIXEL_BITS fractional bits (round to nearest)."""
    return np.floor(np.asarray(xy, np.float64) * _ONE + 0.5).astype(np.int64)


def coverage(fx: np.ndarray, width: int, height: int, chunk: int = CHUNK):
    """Pixels covered by snapped triangles ``fx`` (T, 3, 2) int64, top-left rule.

    Yields, per chunk of triangles, (tri (N,), x (N,), y (N,)) int64 arrays of covered pixel
    centres (tri indexes ``fx``).
    """
    fx = np.asarray(fx, np.int64)
    if not len(fx):
        return
    if np.abs(fx).max() >= (1 << 30):
        raise ValueError("screen coordinates beyond the guard band (clip the triangles first)")
    X, Y = fx[..., 0].copy(), fx[..., 1].copy()
    area = (X[:, 1] - X[:, 0]) * (Y[:, 2] - Y[:, 0]) - (X[:, 2] - X[:, 0]) * (Y[:, 1] - Y[:, 0])
    flip = area < 0  # orient every triangle so its area is positive
    X[flip, 1], X[flip, 2] = X[flip, 2].copy(), X[flip, 1].copy()
    Y[flip, 1], Y[flip, 2] = Y[flip, 2].copy(), Y[flip, 1].copy()
    # pixel range of the bounding box: centres c = x*ONE + HALF with min <= c <= max
    x0 = np.maximum(-((-(X.min(1) - _HALF)) // _ONE), 0)
    x1 = np.minimum((X.max(1) - _HALF) // _ONE, width - 1)
    y0 = np.maximum(-((-(Y.min(1) - _HALF)) // _ONE), 0)
    y1 = np.minimum((Y.max(1) - _HALF) // _ONE, height - 1)
    bw = x1 - x0 + 1
    bh = y1 - y0 + 1
    live = (area != 0) & (bw > 0) & (bh > 0)
    tris = np.nonzero(live)[0]
    if not len(tris):
        return
    # edge coefficients E = A*px + B*py + C for edges (0,1), (1,2), (2,0), with the top-left bias
    coef = []
    for a, b in ((0, 1), (1, 2), (2, 0)):
        dx = X[tris, b] - X[tris, a]
        dy = Y[tris, b] - Y[tris, a]
        A = -dy
        B = dx
        # evaluate relative to the first candidate centre to keep the numbers small
        cx = x0[tris] * _ONE + _HALF
        cy = y0[tris] * _ONE + _HALF
        E0 = dx * (cy - Y[tris, a]) - dy * (cx - X[tris, a])
        topleft = (dy < 0) | ((dy == 0) & (dx > 0))
        E0 = E0 - (~topleft)  # a centre exactly on a non-top-left edge fails E >= 0
        coef.append((A * _ONE, B * _ONE, E0))
    # split tall bounding boxes into bands of rows so no single step exceeds `chunk` candidates
    bwt, bht = bw[tris], bh[tris]
    rows = np.maximum(1, chunk // bwt)
    nb = -(-bht // rows)
    ep = np.repeat(np.arange(len(tris)), nb)  # entry -> position in `tris`
    band = np.arange(int(nb.sum()), dtype=np.int64) - np.repeat(np.cumsum(nb) - nb, nb)
    eyoff = band * rows[ep]
    ecount = bwt[ep] * np.minimum(rows[ep], bht[ep] - eyoff)
    ends = np.cumsum(ecount)
    start = 0
    while start < len(ep):
        # entries [start, stop) hold at most `chunk` candidates (at least one entry)
        base = ends[start - 1] if start else 0
        stop = max(int(np.searchsorted(ends, base + chunk, side="right")), start + 1)
        cnt = ecount[start:stop]
        local = np.repeat(np.arange(start, stop), cnt)
        k = np.arange(int(cnt.sum()), dtype=np.int64) - np.repeat(np.cumsum(cnt) - cnt, cnt)
        p = ep[local]
        w = bwt[p]
        dxp = k % w
        dyp = eyoff[local] + k // w
        ok = None
        for A, B, E0 in coef:
            e = E0[p] + A[p] * dxp + B[p] * dyp
            ok = e >= 0 if ok is None else ok & (e >= 0)
        idx = np.nonzero(ok)[0]
        t = tris[p[idx]]
        yield t, x0[t] + dxp[idx], y0[t] + dyp[idx]
        start = stop


def rasterize_screen(xy: np.ndarray, width: int, height: int):
    """Coverage of screen-space triangles (T, 3, 2) float: (tri, x, y) of every covered pixel."""
    parts = list(coverage(snap(xy), width, height))
    if not parts:
        e = np.zeros(0, np.int64)
        return e, e, e
    return tuple(np.concatenate(p) for p in zip(*parts))


def _planes(fxy: np.ndarray, values: np.ndarray):
    """Screen-space affine planes of per-vertex values: returns (a, b) with v = v0 + a dx + b dy."""
    X = fxy[..., 0] / _ONE
    Y = fxy[..., 1] / _ONE
    dx1, dy1 = X[:, 1] - X[:, 0], Y[:, 1] - Y[:, 0]
    dx2, dy2 = X[:, 2] - X[:, 0], Y[:, 2] - Y[:, 0]
    det = dx1 * dy2 - dx2 * dy1
    det = np.where(det == 0, 1.0, det)
    dv1 = values[:, 1] - values[:, 0]
    dv2 = values[:, 2] - values[:, 0]
    a = (dv1 * dy2[:, None] - dv2 * dy1[:, None]) / det[:, None]
    b = (dv2 * dx1[:, None] - dv1 * dx2[:, None]) / det[:, None]
    return a, b


def rasterize(clip: np.ndarray, st: np.ndarray, tex: np.ndarray, width: int, height: int,
              near: float = 0.1) -> Fragments:
    """Visible fragments of clip-space triangles.

    Arguments:
        clip: (T, 3, 4) clip-space vertices (x, y, z, w); z is ignored (depth is 1/w).
        st: (T, 3, 2) texture coordinates per vertex.
        tex: (T,) texture id per triangle.
        width, height: frame size in pixels.
        near: near plane distance (clip w >= near), a positive finite number (w = 0 would divide by
            zero in the perspective divide).

    Raises:
        ValueError: if ``near`` is not positive and finite; if a coordinate (clip space or texture)
            is not finite; if a triangle that needs clipping has a coordinate beyond
            ``CLIP_RANGE * near``; if the interpolated texture coordinates overflow.
    """
    if not (np.isfinite(near) and near > 0):
        raise ValueError(f"near plane distance must be positive and finite, got {near!r}")
    clip = np.asarray(clip, np.float64)
    st = np.asarray(st, np.float64)
    _check_limits(clip, st, width, height, near)
    tex = np.asarray(tex, np.int64)
    cv, ca, src = clip_triangles(clip, st, width, height, near)
    empty = np.zeros(0)
    if not len(cv):
        z = np.zeros(0, np.int64)
        return Fragments(width, height, z, z, z, empty, empty, empty, empty, empty, empty)
    fxy = snap(to_screen(cv, width, height))
    q = 1.0 / cv[..., 3]
    vals = np.stack([ca[..., 0] * q, ca[..., 1] * q, q], -1)  # u = s q, v = t q, q: affine on screen
    with np.errstate(over="ignore", invalid="ignore"):     # (s, t) that overflow: refused at the end
        a, b = _planes(fxy, vals)
    x0 = fxy[:, 0, 0] / _ONE
    y0 = fxy[:, 0, 1] / _ONE
    v0 = vals[:, 0]
    npix = width * height
    # depth test over all chunks: largest q wins, ties to the lowest source triangle
    zbuf = np.full(npix, -np.inf)
    tbuf = np.full(npix, np.iinfo(np.int64).max)
    frags = []
    for t, px, py in coverage(fxy, width, height):
        xc = px + 0.5 - x0[t]
        yc = py + 0.5 - y0[t]
        qq = v0[t, 2] + a[t, 2] * xc + b[t, 2] * yc
        pix = py * width + px
        np.maximum.at(zbuf, pix, qq)
        frags.append((pix, qq, t))
    if not frags:
        z = np.zeros(0, np.int64)
        return Fragments(width, height, z, z, z, empty, empty, empty, empty, empty, empty)
    pix = np.concatenate([f[0] for f in frags])
    qq = np.concatenate([f[1] for f in frags])
    tt = np.concatenate([f[2] for f in frags])
    win = qq == zbuf[pix]
    # ties between different triangles: the lowest source triangle (then lowest clipped piece)
    np.minimum.at(tbuf, pix[win], tt[win])
    covered = np.nonzero(tbuf != np.iinfo(np.int64).max)[0]
    t = tbuf[covered]
    py, px = np.divmod(covered, width)
    xc = px + 0.5 - x0[t]
    yc = py + 0.5 - y0[t]
    au, bu, av, bv, aq, bq = a[t, 0], b[t, 0], a[t, 1], b[t, 1], a[t, 2], b[t, 2]
    qw = v0[t, 2] + aq * xc + bq * yc
    with np.errstate(over="ignore", invalid="ignore"):
        u = v0[t, 0] + au * xc + bu * yc
        v = v0[t, 1] + av * xc + bv * yc
        s = u / qw
        tc = v / qw
        out = Fragments(
            width, height, covered.astype(np.int64), src[t], tex[src[t]], s, tc,
            (au - s * aq) / qw, (bu - s * bq) / qw, (av - tc * aq) / qw, (bv - tc * bq) / qw,
        )
    for name in ("s", "t", "dsdx", "dsdy", "dtdx", "dtdy"):
        bad = ~np.isfinite(getattr(out, name))
        if bad.any():
            k = int(np.argmax(bad))
            raise ValueError(f"texture coordinates overflow float64 at pixel {int(out.pixel[k])} "
                             f"({name} of triangle {int(out.tri[k])}): scale them down")
    return out


def _check_limits(clip: np.ndarray, st: np.ndarray, width: int, height: int, near: float) -> None:
    """ValueError unless ``clip`` (T, 3, 4) and ``st`` (T, 3, 2) are finite and every triangle that
    needs clipping is within ``CLIP_RANGE * near`` (the module's Limits)."""
    for what, a in (("clip-space coordinates", clip), ("texture coordinates", st)):
        bad = ~np.isfinite(a)
        if bad.any():
            k = int(np.argwhere(bad)[0][0])
            raise ValueError(f"{what} of triangle {k} are not finite: a NaN or infinite vertex has no place")
    if not len(clip):
        return
    x, y, w = clip[..., 0], clip[..., 1], clip[..., 3]
    gx, gy = _GUARD_PIXELS / (width / 2.0), _GUARD_PIXELS / (height / 2.0)
    outside = (w < near) | (np.abs(x) > gx * w) | (np.abs(y) > gy * w)
    # every triangle with a vertex outside a plane is cut, but for one wholly behind the near plane
    # (the first plane: dropped before any arithmetic)
    cut = outside.any(1) & ~(w < near).all(1)
    big = np.max(np.maximum(np.maximum(np.abs(x), np.abs(y)), np.abs(w)), axis=1) > CLIP_RANGE * near
    bad = cut & big
    if bad.any():
        k = int(np.argmax(bad))
        raise ValueError(f"triangle {k} needs clipping and has a clip-space coordinate beyond {CLIP_RANGE:.3g} "
                         f"times the near plane distance ({near:g}): float64 cannot clip it exactly; "
                         "scale the scene down or clip it first")
