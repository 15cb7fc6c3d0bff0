"""Bit-exact texel fetch from the memory images, vectorised over many requests.

This is the specification of the hardware pipeline in executable form. Each stage below has a twin of
the same name in ``hw/`` and computes exactly what that stage computes, from the memory images of a
:class:`golden.format.TextureSet` only (never from a decoded picture):

1. :func:`lookup_descriptor` -- (texture, level) -> descriptor row;
2. :func:`block_address` -- (i, j) -> block number ``k`` and offset (x, y) inside the block, by shifts;
3. :func:`read_index` -- bit address ``k*b`` -> word ``w`` and bit offset; the index from words
   ``w`` and ``w+1`` (the even/odd banks);
4. :func:`read_codeword` -- codebook entry ``cb_base + index``; the sub-level and offset select the
   texel (or Y, U, V samples);
5. :func:`convert_color` -- the fixed-point colour matrix for yuv411, expansion for the others;
   raw levels read a word of the raw memory instead of steps 3-4.

``i`` is the column (x) and ``j`` the row (y), both already inside the level.
"""

from __future__ import annotations

import numpy as np

from .format import COLOR_CODES, COLORS, LAYOUT_CODES, MAX_LEVELS, PVR2_COLORS, TextureSet, unpack_indices
from .pvr2.pvr import decode_texels, decode_yuv422_blocks, twiddle_indices

__all__ = ["fetch", "decode", "decode_bands", "FETCH_CHUNK", "DECODE_CHUNK_TEXELS", "random_requests", "lookup_descriptor", "block_address", "read_index", "read_codeword",
           "convert_color", "straddles", "twiddled_block", "expand_texels", "RequestError", "check_requests"]


class RequestError(ValueError):
    """A request names a texture, level or texel that does not exist."""


def check_requests(ts: TextureSet, tex, level, i, j) -> None:
    """Raise :class:`RequestError` (one line) unless every request is inside its level, and, in a
    pruned set (``golden.need.prune``), its level and block are stored."""
    tex, level, i, j = (np.asarray(a, dtype=np.int64) for a in (tex, level, i, j))
    bad = (tex < 0) | (tex >= ts.n_textures) | (level < 0) | (level >= MAX_LEVELS)
    if bad.any():
        n = int(np.argmax(bad))
        raise RequestError(f"request {n}: texture {int(tex[n])} level {int(level[n])} does not exist")
    d = ts.descriptors[tex, level]
    bad = ~d["valid"].astype(bool)
    if bad.any():
        n = int(np.argmax(bad))
        t, L = int(tex[n]), int(level[n])
        if L < ts.textures[t].levels:
            raise RequestError(f"request {n}: texture {t} level {L} was pruned from this texture set "
                               f"(the frames it was pruned for never read it)")
        raise RequestError(f"request {n}: texture {t} has no level {L}")
    bad = (i < 0) | (j < 0) | (i >= (1 << d["log2w"].astype(np.int64))) | (j >= (1 << d["log2h"].astype(np.int64)))
    if bad.any():
        n = int(np.argmax(bad))
        raise RequestError(f"request {n}: texel ({int(i[n])}, {int(j[n])}) is outside texture "
                           f"{int(tex[n])} level {int(level[n])} ({1 << int(d['log2w'][n])}x{1 << int(d['log2h'][n])})")
    comp = d["compressed"].astype(bool)
    if ts.present_blocks is not None and comp.any():
        k, _, _ = block_address(d[comp], i[comp], j[comp])
        bad = ~ts.block_present(tex[comp], level[comp], k)
        if bad.any():
            n = int(np.flatnonzero(comp)[np.argmax(bad)])
            raise RequestError(f"request {n}: texel ({int(i[n])}, {int(j[n])}) of texture {int(tex[n])} level "
                               f"{int(level[n])} is in a block pruned from this texture set (the frames it was "
                               f"pruned for never read it)")


def random_requests(ts: TextureSet, n: int, seed: int = 0) -> np.ndarray:
    """``n`` valid requests (N, 4) int64 (texture, level, i, j) spread over every texture and level
    of ``ts`` (seeded; for tests and benchmarks)."""
    rng = np.random.default_rng(seed)
    tex = rng.integers(0, ts.n_textures, n)
    levels = np.array([t.levels for t in ts.textures])
    lv = (rng.random(n) * levels[tex]).astype(np.int64)
    d = ts.descriptors[tex, lv]
    w = 1 << d["log2w"].astype(np.int64)
    h = 1 << d["log2h"].astype(np.int64)
    return np.stack([tex, lv, rng.integers(0, 1 << 30, n) % w, rng.integers(0, 1 << 30, n) % h], 1)


def lookup_descriptor(ts: TextureSet, tex, level) -> np.ndarray:
    """Descriptor rows for each request (structured array, fields of DESCRIPTOR_FIELDS)."""
    return ts.descriptors[np.asarray(tex, dtype=np.int64), np.asarray(level, dtype=np.int64)]


def block_address(d: np.ndarray, i, j):
    """Block number ``k`` (row-major in the level group's index map) and offset (x, y) in the block.

    ``bx = i >> log2bw``, ``by = j >> log2bh``, ``k = (by << (log2w - log2bw)) | bx``,
    ``x = i & (bw - 1)``, ``y = j & (bh - 1)`` (block sizes of this level's sub-level).

    With the PowerVR2 layout (``layout`` 1) ``k`` is the twiddled block number
    (:func:`twiddled_block`) and the offsets are transposed, ``x = j & (bh - 1)``, ``y = i & (bw - 1)``:
    a PowerVR2 codeword lists its texels column by column (twiddled), so the texel number
    ``(y << log2bw) | x`` of :func:`read_codeword` is the twiddled one (PowerVR2 blocks are square).
    """
    i = np.asarray(i, dtype=np.int64)
    j = np.asarray(j, dtype=np.int64)
    lbw = d["log2bw"].astype(np.int64)
    lbh = d["log2bh"].astype(np.int64)
    k = ((j >> lbh) << (d["log2w"].astype(np.int64) - lbw)) | (i >> lbw)
    x, y = i & ((1 << lbw) - 1), j & ((1 << lbh) - 1)
    tw = d["layout"] == LAYOUT_CODES["pvr2"]
    if tw.any():
        gw = d["log2w"].astype(np.int64) - lbw
        gh = d["log2h"].astype(np.int64) - lbh
        k = np.where(tw, twiddled_block(i >> lbw, j >> lbh, gw, gh), k)
        x, y = np.where(tw, y, x), np.where(tw, x, y)
    return k, x, y


def twiddled_block(bx, by, log2gw, log2gh) -> np.ndarray:
    """Twiddled (Morton) number of block (bx, by) in a grid of ``2**log2gw x 2**log2gh`` blocks, the
    PowerVR2 order: inside squares of side ``m = 2**min(log2gw, log2gh)`` the bits of ``by`` and
    ``bx`` interleave (``by`` bit n -> bit 2n, ``bx`` bit n -> bit 2n+1); the squares follow one
    another along the longer side: ``k = ((bx | by) >> log2m) << 2 log2m | morton(bx mod m, by mod m)``
    (one of ``bx >> log2m``, ``by >> log2m`` is 0). Twin of :class:`hw.address.BlockAddress`'s
    twiddle; agrees with :func:`golden.pvr2.pvr.twiddle_indices`."""
    bx = np.asarray(bx, dtype=np.int64)
    by = np.asarray(by, dtype=np.int64)
    lm = np.minimum(np.asarray(log2gw, dtype=np.int64), np.asarray(log2gh, dtype=np.int64))
    mask = (1 << lm) - 1
    sx, sy = bx & mask, by & mask
    k = ((bx | by) >> lm) << (2 * lm)
    for bit in range(12):                       # over the coordinate bits, not the blocks
        k |= ((sy >> bit) & 1) << (2 * bit)
        k |= ((sx >> bit) & 1) << (2 * bit + 1)
    return k


def straddles(d: np.ndarray, k, word_bits: int) -> np.ndarray:
    """True where index ``k`` crosses a word boundary (needs words w and w+1)."""
    b = d["index_bits"].astype(np.int64)
    off = (np.asarray(k, dtype=np.int64) * b) % word_bits
    return off + b > word_bits


def read_index(ts: TextureSet, d: np.ndarray, k) -> np.ndarray:
    """The ``b``-bit index of block ``k``: word ``w = base + (k*b >> log2 W)``, offset ``k*b & (W-1)``,
    taken from the concatenation ``word[w+1] : word[w]`` (even/odd banks read together)."""
    wb = ts.word_bits
    b = d["index_bits"].astype(np.int64)
    bit = np.asarray(k, dtype=np.int64) * b
    w = d["base"].astype(np.int64) + (bit // wb)
    off = (bit % wb).astype(np.uint64)
    words = ts.index_words
    last = len(words) - 1
    lo = words[np.minimum(w, last)].astype(np.uint64)      # the words read, not the whole memory, widened
    hi = words[np.minimum(w + 1, last)].astype(np.uint64)
    if wb == 64:
        # 128-bit concatenation: shift the pair down by ``off`` in two halves.
        sh = off
        low_part = lo >> sh
        high_part = np.where(sh == 0, np.uint64(0), hi << ((np.uint64(64) - sh) % np.uint64(64)))
        both = low_part | high_part
    else:
        both = (lo | (hi << np.uint64(wb))) >> off
    return (both & ((np.uint64(1) << b.astype(np.uint64)) - np.uint64(1))).astype(np.int64)


def read_codeword(ts: TextureSet, d: np.ndarray, index, x, y) -> np.ndarray:
    """Raw samples of the texel at offset (x, y) of sub-level ``d['sublevel']`` of entry
    ``cb_base + index``: (N, 4) uint8 holding (R,G,B,A), (R,G,B,-), (I,-,-,-) or (Y,U,V,-).

    PowerVR2 formats: the 16-bit texel at byte ``texel_off + 2t`` (little-endian), expanded to
    (R,G,B,A) by :func:`expand_texels` (argb1555, rgb565, argb4444); yuv422: (Y,U,V,-) with Y the
    texel's high byte, U the byte at ``u_off + 2x`` and V at ``v_off + 2x`` (the low bytes of the
    left and right texel of the texel's row: ``x`` is the row, the offsets being transposed)."""
    entry = ts.codebook[d["cb_base"].astype(np.int64) + np.asarray(index, dtype=np.int64)]
    n = len(entry)
    x = np.asarray(x, dtype=np.int64)
    y = np.asarray(y, dtype=np.int64)
    t = (y << d["log2bw"].astype(np.int64)) | x
    color = d["color"].astype(np.int64)
    tb = np.choose(color, [3, 4, 1, 1, 2, 2, 2, 2])
    out = np.zeros((n, 4), np.uint8)
    rows = np.arange(n)
    base = d["texel_off"].astype(np.int64) + tb * t
    last = entry.shape[1] - 1
    for c in range(4):
        out[:, c] = entry[rows, np.minimum(base + c, last)]
    yuv = color == COLOR_CODES["yuv411"]
    if yuv.any():
        lcw = np.maximum(d["log2bw"].astype(np.int64) - 1, 0)
        ct = ((y >> 1) << lcw) | (x >> 1)
        out[yuv, 1] = entry[rows, np.minimum(d["u_off"].astype(np.int64) + ct, last)][yuv]
        out[yuv, 2] = entry[rows, np.minimum(d["v_off"].astype(np.int64) + ct, last)][yuv]
    texel16 = out[:, 0].astype(np.int64) | (out[:, 1].astype(np.int64) << 8)
    for name in ("argb1555", "rgb565", "argb4444"):
        sel = color == COLOR_CODES[name]
        if sel.any():
            out[sel] = expand_texels(texel16[sel], name)
    yuv = color == COLOR_CODES["yuv422"]
    if yuv.any():
        # Y is the texel's high byte; U and V the low bytes of the row's left and right texels
        pair = 2 * x
        luma = out[:, 1].copy()
        out[yuv, 0] = luma[yuv]
        out[yuv, 1] = entry[rows, np.minimum(d["u_off"].astype(np.int64) + pair, last)][yuv]
        out[yuv, 2] = entry[rows, np.minimum(d["v_off"].astype(np.int64) + pair, last)][yuv]
    return out


def expand_texels(texels, color: str) -> np.ndarray:
    """16-bit PowerVR2 texels (argb1555, rgb565, argb4444) -> ``(N, 4)`` RGBA uint8, each field
    widened to 8 bits by bit replication (rgb565: alpha 255). Twin of the codebook ROM's expansion;
    the same arithmetic as :func:`golden.pvr2.pvr.decode_texels`."""
    return decode_texels(texels, PVR2_COLORS.index(color))


def convert_color(ts: TextureSet, color, samples: np.ndarray) -> np.ndarray:
    """Samples of :func:`read_codeword` -> RGBA8888. rgb: A=255; intensity: (I,I,I,255);
    yuv411 and yuv422: the colour matrix, A=255; rgba and the 16-bit PowerVR2 formats (expanded by
    :func:`read_codeword`): unchanged."""
    color = np.asarray(color)
    out = samples.copy()
    i8 = color == COLOR_CODES["intensity"]
    out[i8, 1] = out[i8, 0]
    out[i8, 2] = out[i8, 0]
    yuv = (color == COLOR_CODES["yuv411"]) | (color == COLOR_CODES["yuv422"])
    if yuv.any():
        out[yuv, :3] = ts.matrix.apply(samples[yuv, :3])
    opaque = np.isin(color, [COLOR_CODES[c] for c in ("rgb", "intensity", "yuv411", "yuv422")])
    out[opaque, 3] = 255
    return out


#: Requests :func:`fetch` works on at a time: its temporaries are a few hundred bytes a request of
#: the chunk (the codebook rows among them), whatever the number of requests.
FETCH_CHUNK = 1 << 16


def fetch(ts: TextureSet, tex, level, i, j) -> np.ndarray:
    """RGBA8888 texels, (N, 4) uint8, for requests (tex, level, i, j) (int arrays of equal length).

    Requests must be valid (see :func:`check_requests`); the hardware does not check either. Works in
    chunks of :data:`FETCH_CHUNK` requests, so its memory is the requests, the texels and a bounded
    working set.
    """
    tex, level, i, j = np.broadcast_arrays(*(np.asarray(a, dtype=np.int64).ravel() for a in (tex, level, i, j)))
    if len(tex) <= FETCH_CHUNK:
        return _fetch(ts, tex, level, i, j)
    out = np.empty((len(tex), 4), np.uint8)
    for a in range(0, len(tex), FETCH_CHUNK):
        s = slice(a, a + FETCH_CHUNK)
        out[s] = _fetch(ts, tex[s], level[s], i[s], j[s])
    return out


def _fetch(ts: TextureSet, tex, level, i, j) -> np.ndarray:
    d = lookup_descriptor(ts, tex, level)
    out = np.zeros((len(tex), 4), np.uint8)
    comp = d["compressed"].astype(bool)
    if comp.any():
        dc = d[comp]
        k, x, y = block_address(dc, i[comp], j[comp])
        index = read_index(ts, dc, k)
        out[comp] = convert_color(ts, dc["color"], read_codeword(ts, dc, index, x, y))
    raw = ~comp
    if raw.any():
        dr = d[raw]
        addr = dr["base"].astype(np.int64) + (j[raw] << dr["log2w"].astype(np.int64)) + i[raw]
        out[raw] = ts.raw_words[addr].astype("<u4").view(np.uint8).reshape(-1, 4)
    return out


#: Texels :func:`decode` works on at a time (whole rows of blocks, at least one row of blocks): its
#: temporaries are a few tens of bytes a texel of the chunk, whatever the level's size.
DECODE_CHUNK_TEXELS = 1 << 16


def decode(ts: TextureSet, tex: int, level: int = 0) -> np.ndarray:
    """A whole level as an (h, w, 4) uint8 RGBA image.

    An independent path from :func:`fetch` (index maps unpacked, whole codewords tiled), so that
    "fetch over every texel equals decode" checks the per-texel address arithmetic. In a pruned set
    (``golden.need.prune``) a level it does not store raises :class:`RequestError` and the texels of
    blocks it does not store are (0, 0, 0, 0).

    The level is decoded in bands of whole block rows (:func:`decode_bands`), so the memory it takes
    is the picture and a bounded working set.
    """
    d = _stored_level(ts, tex, level)
    out = np.empty((1 << d["log2h"], 1 << d["log2w"], 4), np.uint8)
    for j0, rows in decode_bands(ts, tex, level):
        out[j0: j0 + len(rows)] = rows
    return out


def _stored_level(ts: TextureSet, tex: int, level: int) -> dict:
    d = ts.descriptor(tex, level)
    if not d["valid"]:
        if level < ts.textures[tex].levels:
            raise RequestError(f"texture {tex} level {level} was pruned from this texture set")
        raise RequestError(f"texture {tex} has no level {level}")
    return d


def decode_bands(ts: TextureSet, tex: int, level: int = 0, texels: int = DECODE_CHUNK_TEXELS):
    """Yield ``(j0, rows)``: the level of :func:`decode`, top to bottom, as (n, w, 4) uint8 bands of
    rows ``j0 .. j0 + n - 1``, each a whole number of block rows holding about ``texels`` texels
    (at least one row of blocks). Raises :class:`RequestError` as :func:`decode` does, before the
    first band."""
    d = _stored_level(ts, tex, level)
    w, h = 1 << d["log2w"], 1 << d["log2h"]
    bh = 1 << d["log2bh"] if d["compressed"] else 1
    step = max(bh, texels // w // bh * bh)
    return _bands(ts, tex, level, d, w, h, step)


def _bands(ts, tex, level, d, w, h, step):
    pvr2 = d["compressed"] and d["layout"] == LAYOUT_CODES["pvr2"]
    idx = _index_map(ts, d, w, h) if pvr2 else None
    for j0 in range(0, h, step):
        j1 = min(h, j0 + step)
        if not d["compressed"]:
            a = d["base"] + j0 * w
            rows = ts.raw_words[a: a + (j1 - j0) * w].astype("<u4").view(np.uint8).reshape(j1 - j0, w, 4)
        elif pvr2:
            rows = _decode_pvr2(ts, tex, level, d, idx, w, h, j0, j1)
        else:
            rows = _decode_rows(ts, tex, level, d, w, j0, j1)
        yield j0, rows


def _decode_rows(ts: TextureSet, tex: int, level: int, d: dict, w: int, j0: int, j1: int) -> np.ndarray:
    """Rows ``j0 .. j1 - 1`` (whole block rows) of a compressed level of the paper's layout: the
    blocks' indices unpacked from their stretch of the row-major index map, the codewords' planes
    (only the bytes this sub-level reads) tiled."""
    bw, bh = 1 << d["log2bw"], 1 << d["log2bh"]
    nbx, nby = w // bw, (j1 - j0) // bh
    k0 = (j0 // bh) * nbx                            # the band's first block
    idx = unpack_indices(ts.index_words, d["index_bits"], nbx * nby, d["base"], ts.word_bits, first=k0)
    rows = d["cb_base"] + idx
    h = j1 - j0

    def tile(off, pw, ph, c):       # the plane of pw*ph samples of c bytes at ``off`` -> (h, w, c)
        plane = ts.codebook[rows, off: off + pw * ph * c]
        a = plane.reshape(nby, nbx, ph, pw, c)
        a = np.repeat(np.repeat(a, bh // ph, axis=2), bw // pw, axis=3)
        return a.transpose(0, 2, 1, 3, 4).reshape(h, w, c)

    color = d["color"]
    out = np.zeros((h, w, 4), np.uint8)
    t0 = d["texel_off"]
    if color == COLOR_CODES["yuv411"]:
        cw, ch = max(1, bw >> 1), max(1, bh >> 1)
        yuv = np.concatenate([tile(t0, bw, bh, 1), tile(d["u_off"], cw, ch, 1), tile(d["v_off"], cw, ch, 1)], axis=2)
        out[..., :3] = ts.matrix.apply(yuv)
    else:
        c = {COLOR_CODES["rgb"]: 3, COLOR_CODES["rgba"]: 4, COLOR_CODES["intensity"]: 1}[color]
        out[..., :c] = tile(t0, bw, bh, c)
        if c == 1:
            out[..., 1] = out[..., 2] = out[..., 0]
    if color != COLOR_CODES["rgba"]:
        out[..., 3] = 255
    if ts.present_blocks is not None:                 # a pruned set: blocks it no longer holds are (0, 0, 0, 0)
        k = np.arange(k0, k0 + nbx * nby)
        gone = ~ts.block_present(np.full(k.shape, tex), np.full(k.shape, level), k).reshape(nby, nbx)
        out[np.repeat(np.repeat(gone, bh, axis=0), bw, axis=1)] = 0
    return out


def _index_map(ts: TextureSet, d: dict, w: int, h: int) -> np.ndarray:
    """A PowerVR2 level's whole index map (8-bit indices, in twiddled order) as uint16."""
    n = (w >> d["log2bw"]) * (h >> d["log2bh"])
    out = np.empty(n, np.uint16)
    step = DECODE_CHUNK_TEXELS
    for a in range(0, n, step):
        out[a: a + step] = unpack_indices(ts.index_words, d["index_bits"], min(step, n - a), d["base"],
                                          ts.word_bits, first=a)
    return out


def _decode_pvr2(ts: TextureSet, tex: int, level: int, d: dict, idx: np.ndarray, w: int, h: int,
                 j0: int, j1: int) -> np.ndarray:
    """Rows ``j0 .. j1 - 1`` (whole block rows) of a PowerVR2 level, as :mod:`golden.pvr2.pvr` decodes
    a ``.dt``: the band's twiddled block numbers gathered from the index map into raster order, its
    blocks' 16-bit texels decoded at once (yuv422 pairs through the set's colour matrix), the blocks
    tiled column by column. In a pruned set the blocks it does not store are (0, 0, 0, 0)."""
    bw, bh = 1 << d["log2bw"], 1 << d["log2bh"]
    nbx, nby = w // bw, h // bh
    k = twiddle_indices(nbx, nby, j0 // bh, j1 // bh)            # (band rows, nbx) block numbers
    grid = idx[k].astype(np.int64)
    start = d["texel_off"]
    raw = ts.codebook[d["cb_base"] + grid.ravel(), start: start + 2 * bw * bh]
    texels = np.ascontiguousarray(raw).view("<u2").astype(np.int64)          # (n, bw*bh)
    name = COLORS[d["color"]]
    if name == "yuv422":
        blocks = decode_yuv422_blocks(texels, matrix=ts.matrix)
    else:
        blocks = expand_texels(texels.ravel(), name).reshape(len(texels), bw * bh, 4)
    rows = len(k)
    tiles = blocks.reshape(rows, nbx, bw, bh, 4)                 # texel t = (x << log2bh) | y
    out = np.ascontiguousarray(tiles.transpose(0, 3, 1, 2, 4).reshape(rows * bh, nbx * bw, 4))
    if ts.present_blocks is not None:             # a pruned set, as above; block numbers twiddled
        kk = k.ravel()
        gone = ~ts.block_present(np.full(kk.shape, tex), np.full(kk.shape, level), kk).reshape(k.shape)
        out[np.repeat(np.repeat(gone, bh, axis=0), bw, axis=1)] = 0
    return out
