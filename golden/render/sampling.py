"""Texture sampling in two phases: texel *requests*, then *resolve* of the returned texels.

    sampler = Sampler(level_shapes, address, mode)
    reqs = sampler.requests(fragments)          # (N, 4) int64 (texture, level, i, j)
    frame = sampler.resolve(texels)             # texels (N, 4) uint8 RGBA, in request order

Any backend (reference pyramids, the golden VQ fetch, the RTL) supplies the texels between the two
calls; the same texels always give the same frame, bit for bit.

**Request order.** Covered pixels in row-major order (y, then x); per pixel:

- ``point``: 1 request, level 0, the nearest texel ``i = floor(s W0)``, ``j = floor(t H0)``.
- ``bilinear``: 4 requests, the 2x2 footprint of level L0 (the finer of trilinear's two levels) in
  the order below, weighted by the bilinear weights alone.
- ``trilinear``: 8 requests, level L0 first then level L1, and within a level the 2x2 footprint in
  the order (i0, j0), (i1, j0), (i0, j1), (i1, j1).

With ``stream="fixed"`` every covered pixel issues its whole footprint (4 bilinear, 8 trilinear),
even when a weight is zero (a constant-rate stream). With ``stream="sparse"`` (the default) the same
stream leaves out what cannot change the pixel (:mod:`golden.render.sparse`): requests of weight 0,
and a texel named twice in the footprint is requested once, at its first place, with the weights
added; 1 to 4 (bilinear) or 1 to 8 (trilinear) requests per pixel, and the same frame bit for bit.
Point sampling issues one request per pixel in both streams. Uncovered pixels issue nothing and get
the background colour.

**Level of detail** (per pixel, from the rasterizer's analytic derivatives and the level-0 size
W0 x H0 of the pixel's texture)::

    rho_x^2 = (ds/dx W0)^2 + (dt/dx H0)^2,   rho_y^2 = (ds/dy W0)^2 + (dt/dy H0)^2
    lambda  = log2(max(rho_x, rho_y)) = 0.5 log2(max(rho_x^2, rho_y^2))

(the OpenGL scale factor), then clamped to [-LOD_LIMIT, LOD_LIMIT] = [-64, 64] so it is finite for
every fragment: zero derivatives (texture coordinates constant across the triangle, or derivatives
whose squares underflow) give -64, derivatives whose squares overflow give +64, NaN derivatives (never
made by the rasterizer) give -64. A texture has at most 63 levels (int64 sizes), so the clamp changes
no level or blend.
lambda is quantised to ``FRAC_BITS`` = 8 fractional bits with round to
nearest, ``lam = floor(lambda 256 + 1/2)``, clamped to [0, 256 (levels - 1)]; ``L0 = lam >> 8``,
level blend ``f = lam & 255``, ``L1 = min(L0 + 1, levels - 1)``. lambda <= 0 (magnification) thus
gives bilinear filtering of level 0. With a :class:`~golden.render.fovea.Fovea`, its integer bias
(1/256 levels, 0 inside the fovea) is added to ``floor(lambda 256 + 1/2)`` before the clamp
(bilinear and trilinear; point sampling has no level to bias).

**Bilinear footprint** in level L of size W x H: ``u = floor(s W 256) - 128`` (texel centres at
half-integers; s W 256 is exact in float64 because W 256 is a power of two), ``i0 = u >> 8``,
``i1 = i0 + 1``, ``fu = u & 255``; the same for t, j, fv.

**Fixed-point weights** (all integers): bilinear ``(256-fu)(256-fv), fu(256-fv), (256-fu)fv, fu fv``
(sum 2^16), times the level weights ``256 - f`` for L0 and ``f`` for L1 (sum 2^8): eight weights that
sum to exactly 2^24. Per channel ``out = (sum w_k texel_k + 2^23) >> 24``; the sum is below 2^32.

**Addressing** per texture and axis: ``wrap`` (i mod W), ``clamp`` (clip to [0, W-1]) or ``mirror``
(period 2W: 0..W-1, then W-1..0), applied to integer texel indices, so a clamped footprint at the
border repeats the edge texel.

**Far coordinates** (:func:`fold_coordinate`): before the footprint, a wrapped coordinate with
``|s| >= 1`` loses its integer part (``s - floor(s)``, exact in float64), a mirrored one with
``|s| >= 2`` loses a multiple of 2 (``s - 2 floor(s/2)``, exact) and a clamped one is clipped
to [-1, 2]; wrapped or mirrored, an infinity is 0 (clamped, the edge). The texels and the frame are exactly those of the
formulas above wherever ``s W 256`` fits int64, and coordinates of any size (1e15, inf) stay defined.
A NaN coordinate names no texel: :meth:`Sampler.requests` and :meth:`Sampler.filter_inputs` refuse it
(ValueError) rather than sample one (:func:`fold_coordinate` alone still maps it to 0).

**Fixed point** (:mod:`golden.filter`, the specification of the RTL filter): the folded coordinate is
quantised to ``s_q = floor(s 2^F)`` with ``F = 8 + log2`` of the largest level-0 side; every floor
above is then a shift of ``s_q`` (nested floors), so the footprint, the weights and the frame are
those of the float formulas exactly. :meth:`Sampler.requests` computes them with
:func:`golden.filter.footprint`; :meth:`Sampler.filter_inputs` gives the same per-pixel inputs the
RTL filter takes.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from .. import filter as fixed
from .fovea import Fovea
from .raster import Fragments
from .sparse import STREAMS, SkipCounts, sparse_stream, stream_offsets

__all__ = [
    "FRAC_BITS", "WEIGHT_BITS", "LOD_LIMIT", "MODES", "BACKGROUND", "level_of_detail", "quantize_lod",
    "address", "fold_coordinate", "trilinear_weights", "Sampler", "STREAMS",
]

FRAC_BITS = 8
WEIGHT_BITS = 3 * FRAC_BITS
MODES = ("point", "bilinear", "trilinear")
BACKGROUND = (0, 0, 0, 255)
_ONE = 1 << FRAC_BITS
#: |lambda| never exceeds this (levels; finite where log2 would give -inf, +inf or NaN).
LOD_LIMIT = 64.0


def level_of_detail(frags: Fragments, width0: np.ndarray, height0: np.ndarray) -> np.ndarray:
    """lambda (float64) per fragment, for level-0 sizes per fragment, always finite: clamped to
    [-LOD_LIMIT, LOD_LIMIT], with zero (or underflowing) derivatives at -LOD_LIMIT, overflowing ones at
    +LOD_LIMIT and NaN ones at -LOD_LIMIT (level 0)."""
    w = np.asarray(width0, np.float64)
    h = np.asarray(height0, np.float64)
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        rx = (frags.dsdx * w) ** 2 + (frags.dtdx * h) ** 2
        ry = (frags.dsdy * w) ** 2 + (frags.dtdy * h) ** 2
        lam = 0.5 * np.log2(np.maximum(rx, ry))
    return np.clip(np.nan_to_num(lam, nan=-LOD_LIMIT, posinf=LOD_LIMIT, neginf=-LOD_LIMIT), -LOD_LIMIT, LOD_LIMIT)


def quantize_lod(lam: np.ndarray, levels: np.ndarray, bias: np.ndarray | None = None) -> np.ndarray:
    """lambda -> int64 with FRAC_BITS fraction, round to nearest, plus ``bias`` (integer 1/256 levels,
    default 0), clamped to [0, (levels-1) 2^8]. Exact: ``floor(x + b) == floor(x) + b`` for integer b
    (here |x| <= 2^15 and |b| <= 2^14, so ``x + b`` is exact in float64)."""
    top = (np.asarray(levels, np.int64) - 1) * _ONE
    x = np.nan_to_num(np.asarray(lam, np.float64) * _ONE + 0.5, nan=0.0, neginf=0.0)
    if bias is not None:
        x = x + np.asarray(bias, np.int64)
    return np.floor(np.minimum(np.maximum(x, 0.0), top)).astype(np.int64)


def address(i: np.ndarray, size: np.ndarray, wrap: np.ndarray) -> np.ndarray:
    """Integer texel index into [0, size): wrap (power-of-two size) where ``wrap``, else clamp."""
    return np.where(wrap, i & (size - 1), np.clip(i, 0, size - 1))


def fold_coordinate(s: np.ndarray, wrap: np.ndarray, mirror=False) -> np.ndarray:
    """An equivalent texture coordinate, small enough that ``s W 256`` fits int64 at every level:
    where ``wrap``, ``s - floor(s)`` if ``|s| >= 1`` (exact: Sterbenz), else ``s``; where ``mirror``
    (and not ``wrap``), ``s - 2 floor(s / 2)`` if ``|s| >= 2`` (exact), else ``s``; elsewhere ``s``
    clipped to [-1, 2] (beyond, both texels of a footprint are already the edge texel). NaN, and
    infinities where ``wrap`` or ``mirror``, become 0. Same texels and same filtered colour as ``s``.
    The result is in (-1, 1) wrapped, (-2, 2) mirrored, [-1, 2] clamped."""
    s = np.asarray(s, np.float64)
    with np.errstate(invalid="ignore"):
        folded = np.where(wrap, np.where(np.abs(s) >= 1, s - np.floor(s), s),
                          np.where(mirror, np.where(np.abs(s) >= 2, s - 2 * np.floor(s / 2), s),
                                   np.clip(s, -1.0, 2.0)))
    return np.nan_to_num(folded, nan=0.0)


def trilinear_weights(fu0, fv0, fu1, fv1, f) -> np.ndarray:
    """(M, 8) int64 weights in request order from 8-bit fractions; each row sums to 2^24."""
    fu0, fv0, fu1, fv1, f = (np.asarray(x, np.int64) for x in (fu0, fv0, fu1, fv1, f))
    def bil(fu, fv):
        gu, gv = _ONE - fu, _ONE - fv
        return np.stack([gu * gv, fu * gv, gu * fv, fu * fv], 1)
    return np.concatenate([bil(fu0, fv0) * (_ONE - f)[:, None], bil(fu1, fv1) * f[:, None]], 1)


def _parse_address(a) -> tuple[int, int]:
    """Addressing codes (golden.filter.ADDRESS_MODES) of the s and t axes."""
    if isinstance(a, str):
        a = (a, a)
    if len(a) != 2 or any(m not in fixed.ADDRESS_MODES for m in a):
        raise ValueError(f"addressing must be 'wrap', 'clamp', 'mirror' or a pair of them, got {a!r}")
    return fixed.ADDRESS_MODES.index(a[0]), fixed.ADDRESS_MODES.index(a[1])


class Sampler:
    """Point, bilinear or trilinear sampling of one frame, split into requests() and resolve().

    Arguments:
        level_shapes: per texture id, [(width, height) of level 0, 1, ...] (power-of-two sizes).
        address: per texture id, "wrap", "clamp", "mirror" or a pair (s, t); default wrap everywhere.
        mode: "point", "bilinear" or "trilinear".
        background: RGBA of uncovered pixels.
        stream: "sparse" (default: no request that cannot change the pixel) or "fixed" (every pixel
            issues its whole footprint, 4 requests bilinear, 8 trilinear); the same frames.
        fovea: an optional :class:`~golden.render.fovea.Fovea`: its LOD bias (bilinear and trilinear;
            also in :meth:`filter_inputs`, so the RTL filter samples the biased levels).

    After :meth:`requests`: ``counts`` (M,) int64 requests per covered pixel, ``weights`` (N,) uint32
    per request (2^24 in point mode), ``lam`` (M,) int64 quantised LOD per pixel (bilinear and
    trilinear; None in point mode) and ``skipped`` (:class:`~golden.render.sparse.SkipCounts`).
    """

    def __init__(self, level_shapes: Sequence[Sequence[tuple[int, int]]], address=None,
                 mode: str = "trilinear", background=BACKGROUND, stream: str = "sparse",
                 fovea: Fovea | None = None):
        if mode not in MODES:
            raise ValueError(f"unknown sampling mode {mode!r} (known: {', '.join(MODES)})")
        if stream not in STREAMS:
            raise ValueError(f"unknown request stream {stream!r} (known: {', '.join(STREAMS)})")
        if fovea is not None and not isinstance(fovea, Fovea):
            raise TypeError(f"fovea must be a Fovea or None, got {type(fovea).__name__}")
        self.mode = mode
        self.stream = stream
        self.fovea = fovea
        t = len(level_shapes)
        nlev = max((len(s) for s in level_shapes), default=1)
        self._widths = np.ones((max(t, 1), nlev), np.int64)
        self._heights = np.ones((max(t, 1), nlev), np.int64)
        self._levels = np.ones(max(t, 1), np.int64)
        for k, shapes in enumerate(level_shapes):
            if not shapes:
                raise ValueError(f"texture {k} has no levels")
            for n, (w, h) in enumerate(shapes):
                if w < 1 or h < 1 or (w & (w - 1)) or (h & (h - 1)):
                    raise ValueError(f"texture {k} level {n}: size {w}x{h} is not a power of two")
                self._widths[k, n], self._heights[k, n] = w, h
            self._levels[k] = len(shapes)
        if address is None:
            address = ["wrap"] * t
        if isinstance(address, str):
            address = [address] * t
        if len(address) != t:
            raise ValueError("one addressing mode per texture")
        codes = [_parse_address(a) for a in address] or [(0, 0)]
        self._addr_s = np.array([c[0] for c in codes], np.int64)
        self._addr_t = np.array([c[1] for c in codes], np.int64)
        self.levels = fixed.LevelTable(level_shapes) if t else fixed.LevelTable([[(1, 1)]])
        #: fractional bits of the quantised coordinates (golden.filter.coordinate_frac_bits)
        self.frac = fixed.coordinate_frac_bits(self.levels.max_log2)
        bg = tuple(int(c) for c in background)
        if len(bg) == 3:
            bg += (255,)
        if len(bg) != 4 or not all(0 <= c <= 255 for c in bg):
            raise ValueError(f"background must be RGB or RGBA bytes, got {background!r}")
        self.background = np.array(bg, np.uint8)
        self._plan = None
        self.counts = self.weights = self.lam = self.skipped = None

    @property
    def requests_per_pixel(self) -> int:
        """Requests per covered pixel of the fixed stream (the most a pixel issues)."""
        return fixed.TEXELS[self.mode]

    def lod(self, frags: Fragments) -> np.ndarray:
        """Unquantised lambda per fragment."""
        return level_of_detail(frags, self._widths[frags.tex, 0], self._heights[frags.tex, 0])

    def requests(self, frags: Fragments) -> np.ndarray:
        """Texel requests (N, 4) int64 (texture, level, i, j) for the fragments, in the documented order.

        Also remembers what resolve() needs (pixels, weights, frame size).
        """
        tex = np.asarray(frags.tex, np.int64)
        if len(tex) and (tex.min() < 0 or tex.max() >= len(self._levels)):
            raise ValueError("fragment texture id out of range")
        p = self.filter_inputs(frags, self.frac, tex=tex)
        level, i, j, weight = fixed.footprint(self.levels, tex, p["s"], p["t"], p["lod"], p["mode"],
                                              p["address_s"], p["address_t"], self.frac)
        m, k = len(tex), self.requests_per_pixel
        reqs = np.stack([np.broadcast_to(tex[:, None], level.shape), level, i, j], 2)[:, :k]
        weights = weight[:, :k].astype(np.uint32)
        self.lam = None if self.mode == "point" else p["lod"]
        if self.stream == "sparse" and k > 1:
            spans = (len(self._levels), self._widths.shape[1], self._widths.max(), self._heights.max())
            reqs, weights, counts, self.skipped = sparse_stream(reqs, weights, spans)
        else:
            reqs, weights, counts = reqs.reshape(-1, 4), weights.reshape(-1), np.full(m, k, np.int64)
            self.skipped = SkipCounts(m * k, 0, 0)
        self.counts, self.weights = counts, weights
        self._plan = (frags.width, frags.height, np.asarray(frags.pixel, np.int64), weights, counts)
        return reqs

    def filter_inputs(self, frags: Fragments, frac: int, *, tex=None) -> dict:
        """The per-pixel inputs of the RTL filter (:mod:`golden.filter`): int64 arrays ``texture``,
        ``s``, ``t`` (folded, quantised with ``frac`` fractional bits), ``lod`` (quantised, with the
        fovea's bias if any, 0 in point mode), ``mode``, ``address_s``, ``address_t`` (codes), one per fragment in request order.

        Raises:
            ValueError: if a fragment's texture id is out of range, a texture coordinate is NaN, or
                ``frac`` is too small.
        """
        if tex is None:
            tex = np.asarray(frags.tex, np.int64)
            if len(tex) and (tex.min() < 0 or tex.max() >= len(self._levels)):
                raise ValueError("fragment texture id out of range")
        if frac < fixed.coordinate_frac_bits(self.levels.max_log2):
            raise ValueError(f"{frac} fractional bits are too few for these textures")
        m = len(tex)
        nan = np.isnan(np.asarray(frags.s, np.float64)) | np.isnan(np.asarray(frags.t, np.float64))
        if nan.any():
            k = int(np.argmax(nan))
            raise ValueError(f"texture coordinates of {int(nan.sum())} fragment(s) are NaN (the first at pixel "
                             f"{int(np.asarray(frags.pixel)[k])}): a NaN coordinate names no texel")
        a_s, a_t = self._addr_s[tex], self._addr_t[tex]
        sc = fold_coordinate(frags.s, a_s == 0, a_s == 2)
        tc = fold_coordinate(frags.t, a_t == 0, a_t == 2)
        if self.mode == "point":
            lam = np.zeros(m, np.int64)
        else:
            bias = None if self.fovea is None else self.fovea.bias(frags.pixel, frags.width)
            lam = quantize_lod(self.lod(frags), self._levels[tex], bias)
        return {"texture": tex, "s": fixed.quantize_coordinate(sc, frac), "t": fixed.quantize_coordinate(tc, frac),
                "lod": lam, "mode": np.full(m, fixed.MODES.index(self.mode), np.int64),
                "address_s": a_s, "address_t": a_t}

    def place(self, colors: np.ndarray) -> np.ndarray:
        """The frame (H, W, 4) uint8 from the filtered colours (M, 4) uint8 of the fragments of the
        last requests() (the RTL filter's responses), in order; uncovered pixels get the background."""
        if self._plan is None:
            raise RuntimeError("place() before requests()")
        width, height, pixel, _, _ = self._plan
        c = np.asarray(colors)
        if c.shape != (len(pixel), 4) or c.dtype != np.uint8:
            raise ValueError(f"expected uint8 colours of shape ({len(pixel)}, 4), got {c.dtype} {c.shape}")
        frame = np.empty((height * width, 4), np.uint8)
        frame[:] = self.background
        frame[pixel] = c
        return frame.reshape(height, width, 4)

    def resolve(self, texels: np.ndarray) -> np.ndarray:
        """The frame (H, W, 4) uint8 from the texels (N, 4) uint8 answering requests(), in order."""
        if self._plan is None:
            raise RuntimeError("resolve() before requests()")
        width, height, pixel, weights, counts = self._plan
        tx = np.asarray(texels)
        n = len(weights)
        if tx.shape != (n, 4):
            raise ValueError(f"expected texels of shape ({n}, 4), got {tx.shape}")
        if tx.dtype != np.uint8:
            raise ValueError(f"expected uint8 texels, got {tx.dtype}")
        frame = np.empty((height * width, 4), np.uint8)
        frame[:] = self.background
        if self.mode == "point":
            frame[pixel] = tx
        else:
            # per pixel sum w texel over its requests (golden.filter.blend's arithmetic on a stream of
            # 1 to K requests per pixel); exact: the weights sum to 2^24, so acc < 2^32
            acc = np.zeros((len(pixel), 4), np.uint32)
            some = counts > 0
            if some.any():
                acc[some] = np.add.reduceat(weights[:, None] * tx, stream_offsets(counts)[some], axis=0,
                                            dtype=np.uint32)
            frame[pixel] = ((acc + (1 << (WEIGHT_BITS - 1))) >> WEIGHT_BITS).astype(np.uint8)
        return frame.reshape(height, width, 4)
