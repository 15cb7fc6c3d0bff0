"""The PowerVR2 VQ encoder: an image -> a texture in the PowerVR2 layout (and a pvrtex-style ``.dt``).

Contract: :func:`encode_pvr2` takes a uint8 image (sides powers of two, 8..1024; square when
mipmapped) and returns a one-texture :class:`golden.format.TextureSet` in the PowerVR2 layout
(:mod:`golden.pvr2.pvr_set`): one codebook of ``k`` entries of four 16-bit texels (``k <= 256``; with
``k < 256`` the ``.dt`` names them ``256-k .. 255``), one twiddled index map per mip level;
:func:`golden.pvr2.pvr_set.to_dt` writes it as pvrtex does, and :func:`golden.pvr2.pvr.parse_dt` reads it back
to the same texels. Deterministic for a seed.

How it is built (docs/pvr2.md):

1. The blocks: every 2x2 block of every level of at least 2x2 (the box-filtered pyramid of
   :mod:`golden.mipmap` when mipmapped), as vectors of their texels' R, G, B (and A for argb1555 and
   argb4444) in the decoded space, where the error is measured.
2. A float codebook by the generalized Lloyd algorithm of :mod:`golden.codebook` (TSVQ start,
   codeword migration).
3. Quantisation-aware Lloyd iterations: each codeword becomes the best 16-bit codeword for its cell
   and every block moves to its nearest *decoded* codeword. For argb1555, rgb565 and argb4444 the
   best codeword is each channel's representable value nearest the cell's mean (the squared error of
   a cell is separable, so that is exact). For yuv422 it is the least-squares (Y, Y, U, V) of each row
   pair under the Dreamcast matrix, rounded, then improved by coordinate search on the exact decoded
   error (through :data:`golden.color.DREAMCAST_YUV422`, truncation and clamping included), scored
   from the cell's sums alone (``SSE = n |q|^2 - 2 q.S + const``). A codeword is replaced only when
   its cell's error drops, so the distortion never rises.
4. The 1x1 level of a mip chain is the entry whose texel 3 (rgb565 in a yuv422 texture) is nearest
   the 1x1 texel.
"""

from __future__ import annotations

import numpy as np

from ..codebook import gla, nearest
from ..color import DREAMCAST_YUV422
from ..constants import PVR2_COLORS
from ..mipmap import build_pyramid, to_rgba
from .pvr import PvrError, decode_texels, decode_yuv422_blocks, parse_dt
from .pvr_set import dt_bytes, from_dt, stream_order

__all__ = ["encode_pvr2", "quantize_channel", "PvrEncodeError", "ERROR_CHANNELS"]

#: Channels the error is measured on, per format (alpha only where the format stores it).
ERROR_CHANNELS = {"argb1555": 4, "rgb565": 3, "argb4444": 4, "yuv422": 3}
#: (bits, shift) of R, G, B, A in each 16-bit RGB format (bits 0: the channel is constant 255).
_FIELDS = {
    "argb1555": ((5, 10), (5, 5), (5, 0), (1, 15)),
    "rgb565": ((5, 11), (6, 5), (5, 0), (0, 0)),
    "argb4444": ((4, 8), (4, 4), (4, 0), (4, 12)),
}


class PvrEncodeError(ValueError):
    """Settings or an image the PowerVR2 encoder cannot take."""


def _widen(v: np.ndarray, bits: int) -> np.ndarray:
    """``bits``-wide values widened to 8 by bit replication (1 bit: 0 or 255)."""
    if bits == 1:
        return v * 255
    out = np.zeros_like(v)
    pos = 8
    while pos > 0:
        pos -= bits
        out |= (v << pos) if pos >= 0 else (v >> -pos)
    return out


def quantize_channel(values: np.ndarray, bits: int) -> np.ndarray:
    """The ``bits``-wide field whose widened value is nearest each float value (ties to the lower)."""
    levels = _widen(np.arange(1 << bits, dtype=np.int64), bits).astype(np.float64)
    v = np.asarray(values, dtype=np.float64)
    idx = np.clip(np.searchsorted(levels, v), 1, len(levels) - 1)
    lower = v - levels[idx - 1] <= levels[idx] - v
    return np.where(lower, idx - 1, idx)


def _blocks(level: np.ndarray) -> np.ndarray:
    """(H, W, 4) -> (nby * nbx, 4 texels in twiddled order, 4) raster order of blocks."""
    h, w = level.shape[:2]
    b = level.reshape(h // 2, 2, w // 2, 2, 4).transpose(0, 2, 3, 1, 4)      # [by, bx, x, y, c]
    return b.reshape(-1, 4, 4)


def _decode(codebook: np.ndarray, color: str) -> np.ndarray:
    """(k, 4) uint16 codebook -> (k, 4, 4) RGBA decoded blocks."""
    if color == "yuv422":
        return decode_yuv422_blocks(codebook, matrix=DREAMCAST_YUV422)
    return decode_texels(codebook, PVR2_COLORS.index(color))


def _vectors(blocks: np.ndarray, color: str) -> np.ndarray:
    return blocks[..., :ERROR_CHANNELS[color]].reshape(len(blocks), -1).astype(np.float64)


def _quantize_rgb(centroids: np.ndarray, color: str) -> np.ndarray:
    """(k, 4 texels, 4) float cell means -> (k, 4) uint16: per channel the nearest representable value."""
    t = np.zeros(centroids.shape[:2], dtype=np.int64)
    for c, (bits, shift) in enumerate(_FIELDS[color]):
        if bits:
            t |= quantize_channel(centroids[..., c], bits) << shift
    return t.astype(np.uint16)


# Least squares of one row pair (texels a, b sharing U, V) under the Dreamcast matrix in float:
# unknowns (Ya, Yb, U', V') with U' = U - 128, V' = V - 128; equations R, G, B of a then b.
_M = np.array([[1.0, 0.0, 1.375], [1.0, -0.34375, -0.6875], [1.0, 1.71875, 0.0]])
_A = np.zeros((6, 4))
_A[0:3, 0] = 1.0
_A[3:6, 1] = 1.0
_A[0:3, 2:] = _A[3:6, 2:] = _M[:, 1:]
_PINV = np.linalg.pinv(_A)


def _fit_yuv(centroids: np.ndarray) -> np.ndarray:
    """(k, 4 texels, >=3) float cell means -> (k, 4) uint16 yuv422 codewords (rows: texels 0/2, 1/3)."""
    k = len(centroids)
    out = np.zeros((k, 4), dtype=np.int64)
    for a, b in ((0, 2), (1, 3)):
        rhs = np.concatenate([centroids[:, a, :3], centroids[:, b, :3]], axis=1)       # (k, 6)
        sol = rhs @ _PINV.T                                                            # (k, 4)
        ya, yb = (np.clip(np.rint(sol[:, n]), 0, 255).astype(np.int64) for n in (0, 1))
        u, v = (np.clip(np.rint(sol[:, n] + 128.5), 0, 255).astype(np.int64) for n in (2, 3))
        out[:, a] = (ya << 8) | u
        out[:, b] = (yb << 8) | v
    return out.astype(np.uint16)


def _cell_scores(cands: np.ndarray, color: str, counts: np.ndarray, sums: np.ndarray) -> np.ndarray:
    """Cell error (up to a per-cell constant) of candidate codewords: (k, m, 4) uint16 -> (k, m),
    ``n |q|^2 - 2 q.S`` with the cell's count ``n`` and vector sum ``S``."""
    k, m = cands.shape[:2]
    dec = _vectors(_decode(cands.reshape(-1, 4), color), color).reshape(k, m, -1)
    return counts[:, None] * (dec * dec).sum(-1) - 2.0 * np.einsum("kmd,kd->km", dec, sums)


def _search_yuv(cb: np.ndarray, counts, sums, rounds: int = 3) -> np.ndarray:
    """Coordinate search on the 8 bytes of each yuv422 codeword (steps -2..2), exact decoded error."""
    cb = cb.astype(np.int64)
    for _ in range(rounds):
        changed = False
        for texel in range(4):
            for shift in (8, 0):
                field = (cb[:, texel] >> shift) & 0xFF
                cands = np.repeat(cb[:, None, :], 5, axis=1)
                for n, step in enumerate((-2, -1, 0, 1, 2)):
                    v = np.clip(field + step, 0, 255)
                    cands[:, n, texel] = (cb[:, texel] & ~(0xFF << shift)) | (v << shift)
                scores = _cell_scores(cands.astype(np.uint16), "yuv422", counts, sums)
                best = np.argmin(scores, axis=1)               # ties: the first (step -2 .. 0 .. 2)
                keep = scores[np.arange(len(cb)), best] < scores[:, 2]
                if keep.any():
                    changed = True
                    cb[keep] = cands[np.arange(len(cb)), best][keep]
        if not changed:
            break
    return cb.astype(np.uint16)


def _cells(vectors: np.ndarray, weights: np.ndarray, idx: np.ndarray, k: int):
    counts = np.bincount(idx, weights=weights, minlength=k)
    sums = np.zeros((k, vectors.shape[1]))
    np.add.at(sums, idx, vectors * weights[:, None])
    return counts, sums


def _refine(vectors, weights, cb, color, iterations):
    """Quantisation-aware Lloyd iterations on (k, 4) uint16 ``cb``; returns (cb, indices)."""
    k = len(cb)
    nch = ERROR_CHANNELS[color]
    idx = nearest(vectors, _vectors(_decode(cb, color), color))[0]
    for _ in range(iterations):
        counts, sums = _cells(vectors, weights, idx, k)
        used = counts > 0
        means = np.zeros((k, 4, 4))
        means[..., :nch] = (sums / np.maximum(counts, 1e-300)[:, None]).reshape(k, 4, nch)
        new = _fit_yuv(means) if color == "yuv422" else _quantize_rgb(means, color)
        if color == "yuv422":
            new = _search_yuv(new, counts, sums)
        both = np.stack([cb, new], axis=1)
        scores = _cell_scores(both, color, counts, sums)
        better = used & (scores[:, 1] < scores[:, 0])
        if not better.any():
            break
        cb = np.where(better[:, None], new, cb).astype(np.uint16)
        idx = nearest(vectors, _vectors(_decode(cb, color), color))[0]
    return cb, idx


def encode_pvr2(image: np.ndarray, color: str = "rgb565", *, codebook_size: int = 256, mipmaps: bool = False,
                seed: int = 0, iterations: int = 30, name: str = "texture"):
    """Encode ``image`` as a PowerVR2 VQ texture; returns ``(texture_set, dt)``: the one-texture set
    in the PowerVR2 layout and the bytes of its ``.dt`` (pvrtex's layout), which hold the same texels.

    Raises:
        PvrEncodeError: a size, colour format or codebook size the PowerVR2 cannot take.
    """
    if color not in PVR2_COLORS:
        raise PvrEncodeError(f"colour format {color!r} is not one of {', '.join(PVR2_COLORS)}")
    if not isinstance(codebook_size, (int, np.integer)) or not 1 <= codebook_size <= 256:
        raise PvrEncodeError(f"a PowerVR2 codebook has 1..256 entries, not {codebook_size}")
    try:
        rgba = to_rgba(image)
    except ValueError as e:
        raise PvrEncodeError(str(e)) from None
    h, w = rgba.shape[:2]
    if not all(8 <= s <= 1024 and s & (s - 1) == 0 for s in (w, h)):
        raise PvrEncodeError(f"a PowerVR2 texture is 8..1024 texels a side, powers of two, not {w}x{h}")
    if mipmaps and w != h:
        raise PvrEncodeError(f"a mipmapped PowerVR2 texture is square, not {w}x{h}")
    levels = build_pyramid(rgba) if mipmaps else [rgba]
    blocks = [_blocks(lv) for lv in levels if lv.shape[0] >= 2]
    allb = np.concatenate(blocks)
    vectors = _vectors(allb, color)
    weights = np.ones(len(vectors))
    k = int(codebook_size)
    start = gla(vectors, k, seed=seed).codebook
    nch = ERROR_CHANNELS[color]
    means = np.zeros((k, 4, 4))
    means[..., :nch] = start.reshape(k, 4, nch)
    cb = _fit_yuv(means) if color == "yuv422" else _quantize_rgb(means, color)
    cb, idx = _refine(vectors, weights, cb, color, iterations)
    maps, at = [], 0
    for lv in levels:
        lh, lw = lv.shape[:2]
        if lh >= 2:
            n = (lh // 2) * (lw // 2)
            maps.append(idx[at: at + n].reshape(lh // 2, lw // 2))
            at += n
        else:                                            # 1x1: the entry whose texel 3 is nearest
            fmt = PVR2_COLORS.index("rgb565" if color == "yuv422" else color)
            t3 = decode_texels(cb[:, 3], fmt)[:, :nch].astype(np.float64)
            want = lv[0, 0, :nch].astype(np.float64)
            maps.append(np.array([[int(np.argmin(((t3 - want) ** 2).sum(-1)))]]))
    data = dt_bytes(w, h, color, mipmaps, cb, [stream_order(m) for m in maps])
    try:
        ts = from_dt(parse_dt(data, decode=False), name)
    except PvrError as e:                               # not reachable: what we write, we read
        raise PvrEncodeError(f"internal: the .dt written does not parse: {e}") from None
    ts.textures[0].params.update({"encoder": "pvr2-gla", "seed": int(seed), "iterations": int(iterations)})
    return ts, data
