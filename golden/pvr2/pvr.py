"""Reader and decoder of pvrtex ``.dt`` VQ textures (Sega Dreamcast PowerVR2).

pvrtex (KallistiOS ``utils/pvrtex``) is an independent encoder of Dreamcast textures. Decoding its VQ
output and reproducing its own previews bit for bit checks our reading of VQ data (codebook of 2x2
blocks, twiddled index maps, small codebooks, mip chains) and, through the YUV422 format, the
fixed-point colour unit :data:`golden.color.DREAMCAST_YUV422` against an outside implementation.

File layout (all little-endian)
-------------------------------
A 32-byte header::

    0  'DcTx'
    4  u32  size of the whole file in bytes
    8  u8   version (0)
    9  u8   header size in 32-byte units, minus one (data starts at 32 * (this + 1))
    10 u8   codebook entries minus one (VQ)
    11 u8   palette colours minus one (palettised formats; unused here)
    12 u16  width, u16 height
    16 u32  PVR texture control bits: 31 mipmapped, 30 VQ, 29-27 pixel format,
            26 not twiddled, 25 strided (low bits: size codes, ignored)
    20      12 bytes of zero padding

then, for a VQ texture, ``N`` codebook entries of four 16-bit texels each (a 2x2 block in twiddled
order: texel k sits at (x, y) = (k >> 1, k & 1)), then one index byte per 2x2 block in twiddled
(Morton) order with y in the low bit. With ``N < 256`` the index bytes use entries ``256-N .. 255``
(the file stores only those ``N`` entries). A mipmapped texture (square only) stores every level's
index map after the one shared codebook, smallest level first; the file is then padded (to a
multiple of 32 bytes). The mip chain is addressed as if uncompressed: the 1x1 level is texel
address 3, i.e. texel 3 (bottom right) of the block named by the first index byte; the 2x2 level is
the block of the second index byte, the 4x4 level the next four bytes, and so on.

Pixel formats (the 3-bit format field): 0 ARGB1555, 1 RGB565, 2 ARGB4444, 3 YUV422. Fields of
fewer than eight bits expand to eight by bit replication (``v << (8-n) | v >> (2n-8)``, 4 bits:
``v * 17``); RGB565 and YUV422 are opaque (alpha 255).

YUV422 layout (established from pvrtex's previews, see tests/golden/pvr2/test_pvrtex.py)
---------------------------------------------------------------------------------
Every texel holds its own Y in the high byte and one chroma sample in the low byte. The two
horizontally adjacent texels of each row of a 2x2 codebook block -- twiddled texels 0 and 2 (top
row) and 1 and 3 (bottom row), i.e. twiddled addresses i and i + 2 -- share one U and one V: the
left texel (x even) carries U and the right texel (x odd) carries V. Both texels of the pair are
converted with that (U, V) and their own Y by :data:`golden.color.DREAMCAST_YUV422`. Every other
arrangement tried (pairing the vertically adjacent texels 0/1 and 2/3 or the diagonals 0/3 and 1/2,
V in the left texel, Y in the low byte) fails to reproduce pvrtex's coloured (crate) previews; a
grey picture (grass, U = V = 128 throughout) cannot tell them apart.

A lone 1x1 texel has no partner to share chroma with, so in a mipmapped YUV422 texture the 1x1
level is stored (and decoded) as RGB565; every other level is YUV422.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from ..color import DREAMCAST_YUV422

__all__ = [
    "PvrError", "DtHeader", "PvrTexture", "FORMAT_NAMES", "ARGB1555", "RGB565", "ARGB4444", "YUV422",
    "parse_header", "parse_dt", "read_dt", "decode_dt", "decode_texels", "decode_yuv422_blocks",
    "twiddle_indices", "preview", "MAX_DT_BYTES",
]

ARGB1555, RGB565, ARGB4444, YUV422 = 0, 1, 2, 3
FORMAT_NAMES = {ARGB1555: "ARGB1555", RGB565: "RGB565", ARGB4444: "ARGB4444", YUV422: "YUV422",
                4: "BUMP", 5: "PAL4BPP", 6: "PAL8BPP", 7: "RESERVED"}

MAGIC = b"DcTx"
HEADER_BYTES = 32
CODEBOOK_ENTRY_BYTES = 8
#: No VQ .dt is larger (1024x1024 mip chain: 256 KiB + 85 KiB of indices, 2 KiB codebook, header).
MAX_DT_BYTES = 1 << 22

#: YUV422 pairing inside a twiddled 2x2 block: (texel carrying U, texel carrying V) for each row.
YUV422_PAIRS = ((0, 2), (1, 3))


class PvrError(ValueError):
    """A ``.dt`` file is malformed, truncated or uses a feature this decoder does not cover."""


@dataclass(frozen=True)
class DtHeader:
    """The 32-byte ``.dt`` header, decoded."""

    size: int
    version: int
    data_offset: int
    codebook_entries: int
    colours: int
    width: int
    height: int
    control: int

    @property
    def mipmapped(self) -> bool:
        return bool(self.control >> 31 & 1)

    @property
    def vq(self) -> bool:
        return bool(self.control >> 30 & 1)

    @property
    def pixel_format(self) -> int:
        return self.control >> 27 & 7

    @property
    def format_name(self) -> str:
        return FORMAT_NAMES[self.pixel_format]

    @property
    def twiddled(self) -> bool:
        return not (self.control >> 26 & 1)

    @property
    def strided(self) -> bool:
        return bool(self.control >> 25 & 1)

    @property
    def level_sizes(self) -> list[tuple[int, int]]:
        """(width, height) of every level, largest first."""
        if not self.mipmapped:
            return [(self.width, self.height)]
        return [(self.width >> k, self.height >> k) for k in range(self.width.bit_length())]


@dataclass(frozen=True)
class PvrTexture:
    """A parsed VQ texture.

    ``codebook`` is ``(N, 4)`` uint16 (texels in twiddled order); ``indices`` holds, per level and
    largest first, the ``(bh, bw)`` codebook entry of every 2x2 block in raster order, already
    rebased to ``0 .. N-1``; ``levels`` the decoded RGBA uint8 images, largest first.
    """

    header: DtHeader
    codebook: np.ndarray
    indices: list
    levels: list


def _pow2(n: int) -> bool:
    return n > 0 and n & (n - 1) == 0


def parse_header(data: bytes) -> DtHeader:
    """Decode and sanity-check the header of ``data`` (the whole file).

    Raises:
        PvrError: bad magic, short file, size field not matching the data, bad dimensions.
    """
    if len(data) < HEADER_BYTES:
        raise PvrError(f"truncated .dt: {len(data)} bytes, the header alone is {HEADER_BYTES}")
    if data[:4] != MAGIC:
        raise PvrError(f"not a .dt texture: magic {bytes(data[:4])!r}, expected {MAGIC!r}")
    size = int.from_bytes(data[4:8], "little")
    version, hunits, cb, pal = data[8], data[9], data[10], data[11]
    width = int.from_bytes(data[12:14], "little")
    height = int.from_bytes(data[14:16], "little")
    control = int.from_bytes(data[16:20], "little")
    hdr = DtHeader(size=size, version=version, data_offset=HEADER_BYTES * (hunits + 1),
                   codebook_entries=cb + 1, colours=pal + 1, width=width, height=height,
                   control=control)
    if size != len(data):
        kind = "truncated" if len(data) < size else "oversized"
        raise PvrError(f"{kind} .dt: header says {size} bytes, got {len(data)}")
    if hdr.data_offset > len(data):
        raise PvrError(f"truncated .dt: data starts at {hdr.data_offset}, file has {len(data)} bytes")
    if not (_pow2(width) and _pow2(height) and 8 <= width <= 1024 and 8 <= height <= 1024):
        raise PvrError(f"bad .dt dimensions {width}x{height} (powers of two, 8..1024)")
    if hdr.mipmapped and width != height:
        raise PvrError(f"mipmapped .dt must be square, got {width}x{height}")
    return hdr


def twiddle_indices(bw: int, bh: int, y0: int = 0, y1: int | None = None) -> np.ndarray:
    """Twiddled position of every cell of a ``bw x bh`` grid, as a ``(bh, bw)`` int64 array.

    Morton order with y in bit 0 and x in bit 1 (then y in bit 2, ...). A rectangular grid is
    twiddled in squares of side ``min(bw, bh)`` stored one after another along the longer side.
    ``y0``, ``y1``: only rows ``y0 .. y1 - 1`` of the grid (``(y1 - y0, bw)``; a band of a large grid
    without computing the rest).
    """
    m = min(bw, bh)
    y1 = bh if y1 is None else y1
    y, x = np.mgrid[y0:y1, 0:bw].astype(np.int64)
    sx, sy = x % m, y % m
    out = (x // m + y // m) * m * m
    for bit in range(max(m.bit_length() - 1, 0)):
        out |= ((sy >> bit) & 1) << (2 * bit)
        out |= ((sx >> bit) & 1) << (2 * bit + 1)
    return out


def _expand(v: np.ndarray, bits: int) -> np.ndarray:
    """Expand ``bits``-wide fields to 8 bits by bit replication (``v << (8-bits) | v >> (2*bits-8)``
    for 5 and 6 bits, ``v * 17`` for 4 bits)."""
    out = np.zeros_like(v)
    pos = 8
    while pos > 0:  # at most twice for 4..6-bit fields, over whole arrays
        pos -= bits
        out |= (v << pos) if pos >= 0 else (v >> -pos)
    return out


def decode_texels(texels: np.ndarray, pixel_format: int) -> np.ndarray:
    """16-bit RGB texels -> ``(..., 4)`` RGBA uint8 (ARGB1555, RGB565, ARGB4444; not YUV422)."""
    t = np.asarray(texels).astype(np.int64)
    if pixel_format == ARGB1555:
        a = ((t >> 15) & 1) * 255
        r, g, b = (_expand((t >> s) & 31, 5) for s in (10, 5, 0))
    elif pixel_format == RGB565:
        a = np.full_like(t, 255)
        r, g, b = _expand((t >> 11) & 31, 5), _expand((t >> 5) & 63, 6), _expand(t & 31, 5)
    elif pixel_format == ARGB4444:
        a, r, g, b = (_expand((t >> s) & 15, 4) for s in (12, 8, 4, 0))
    else:
        raise PvrError(f"decode_texels: pixel format {FORMAT_NAMES.get(pixel_format, pixel_format)}"
                       " is not a 16-bit RGB format")
    return np.stack([r, g, b, a], axis=-1).astype(np.uint8)


def decode_yuv422_blocks(codebook: np.ndarray, pairs=YUV422_PAIRS, u_first: bool = True,
                         y_high: bool = True, matrix=None) -> np.ndarray:
    """YUV422 codebook ``(N, 4)`` uint16 -> ``(N, 4, 4)`` RGBA uint8 (texels in twiddled order).

    ``pairs`` lists the texel pairs that share chroma, ``u_first`` says whether the first texel
    of a pair carries U (else V) and ``y_high`` whether Y is the high byte. The defaults are the
    layout pvrtex uses (module docstring); the parameters exist so tests can show that the
    alternatives fail. The colour conversion is ``matrix.apply``, by default (and always when
    decoding a file) :data:`golden.color.DREAMCAST_YUV422`.
    """
    if matrix is None:
        matrix = DREAMCAST_YUV422
    t = np.asarray(codebook).astype(np.int64)
    luma = (t >> 8) & 0xFF if y_high else t & 0xFF
    chroma = t & 0xFF if y_high else (t >> 8) & 0xFF
    u = np.empty_like(t)
    v = np.empty_like(t)
    for first, second in pairs:  # two pairs per block, over all entries at once
        cu, cv = (chroma[:, first], chroma[:, second]) if u_first else (chroma[:, second], chroma[:, first])
        u[:, first] = u[:, second] = cu
        v[:, first] = v[:, second] = cv
    rgb = matrix.apply(np.stack([luma, u, v], axis=-1))
    alpha = np.full(rgb.shape[:-1] + (1,), 255, dtype=np.uint8)
    return np.concatenate([rgb, alpha], axis=-1)


def _decode_codebook(codebook: np.ndarray, pixel_format: int) -> np.ndarray:
    if pixel_format == YUV422:
        return decode_yuv422_blocks(codebook)
    return decode_texels(codebook, pixel_format)


def _blocks_to_image(blocks: np.ndarray, idx: np.ndarray, width: int, height: int) -> np.ndarray:
    """Gather ``(N, 4, 4)`` decoded blocks by a ``(bh, bw)`` index map into an RGBA image."""
    bh, bw = idx.shape
    tiles = blocks[idx]  # (bh, bw, 4 texels, 4 channels); texel k at (x, y) = (k >> 1, k & 1)
    tiles = tiles.reshape(bh, bw, 2, 2, 4)  # [.., x, y, c]
    img = tiles.transpose(0, 3, 1, 2, 4).reshape(bh * 2, bw * 2, 4)
    return np.ascontiguousarray(img[:height, :width])


def parse_dt(data: bytes, *, decode: bool = True) -> PvrTexture:
    """Parse (and by default decode) a VQ ``.dt`` texture held in memory.

    Raises:
        PvrError: malformed or truncated file, not VQ, a format other than ARGB1555 / RGB565 /
            ARGB4444 / YUV422, or an index byte outside the codebook.
    """
    data = bytes(data)
    hdr = parse_header(data)
    if not hdr.vq:
        raise PvrError(f".dt is not VQ-compressed (control word {hdr.control:#010x})")
    if hdr.pixel_format not in (ARGB1555, RGB565, ARGB4444, YUV422):
        raise PvrError(f"unsupported VQ pixel format {hdr.format_name}")
    if not hdr.twiddled or hdr.strided:
        raise PvrError("VQ .dt must be twiddled and not strided")
    n = hdr.codebook_entries
    cb_end = hdr.data_offset + n * CODEBOOK_ENTRY_BYTES
    sizes = hdr.level_sizes
    # index bytes per level, largest first; levels below 2x2 still take one byte
    counts = [max(1, (w // 2) * (h // 2)) for w, h in sizes]
    end = cb_end + sum(counts)
    if end > len(data):
        raise PvrError(f"truncated .dt: codebook and index maps need {end} bytes, file has {len(data)}")
    codebook = np.frombuffer(data, dtype="<u2", count=n * 4, offset=hdr.data_offset).reshape(n, 4)
    blocks = _decode_codebook(codebook, hdr.pixel_format) if decode else None
    indices, levels = [], []
    offset = end
    for (w, h), count in zip(sizes, counts):  # largest first, stored last
        offset -= count
        raw = np.frombuffer(data, dtype=np.uint8, count=count, offset=offset).astype(np.int64)
        bw, bh = max(w // 2, 1), max(h // 2, 1)
        idx = raw[twiddle_indices(bw, bh)] - (256 - n)
        if idx.min() < 0:
            bad = int(raw.min())
            raise PvrError(f"index byte {bad} in level {w}x{h} is outside the {n}-entry codebook "
                           f"(entries {256 - n}..255)")
        indices.append(idx)
        if not decode:
            continue
        if w == 1:
            # the 1x1 level is texel 3 of its block (texel address 3, as for twiddled mip chains);
            # for YUV422 that lone texel cannot carry a chroma pair and is stored as RGB565
            texel = codebook[idx[0, 0], 3]
            fmt = RGB565 if hdr.pixel_format == YUV422 else hdr.pixel_format
            levels.append(decode_texels(np.array([[texel]]), fmt))
        else:
            levels.append(_blocks_to_image(blocks, idx, w, h))
    return PvrTexture(header=hdr, codebook=codebook.copy(), indices=indices, levels=levels)


def read_dt(path: str | os.PathLike, *, decode: bool = True) -> PvrTexture:
    """Read and decode a VQ ``.dt`` file (see :func:`parse_dt`). Raises :class:`PvrError` (naming the
    file) also when it cannot be read or is larger than any VQ ``.dt`` (:data:`MAX_DT_BYTES`)."""
    try:
        with open(path, "rb") as f:
            size = os.fstat(f.fileno()).st_size
            if size > MAX_DT_BYTES:
                raise PvrError(f"{os.fspath(path)}: {size} bytes, larger than any VQ .dt ({MAX_DT_BYTES})")
            data = f.read(MAX_DT_BYTES + 1)
    except OSError as e:
        raise PvrError(f"{os.fspath(path)}: cannot read: {e.strerror or e}") from None
    try:
        return parse_dt(data, decode=decode)
    except PvrError as e:
        raise PvrError(f"{os.fspath(path)}: {e}") from None


def decode_dt(source) -> list:
    """RGBA uint8 levels (largest first) of a ``.dt`` file path or in-memory ``bytes``."""
    if isinstance(source, (bytes, bytearray, memoryview)):
        return parse_dt(source).levels
    return read_dt(source).levels


def preview(levels) -> np.ndarray:
    """pvrtex's preview layout: one level as is; a mip chain as the top level at the left and the
    smaller levels stacked top to bottom to its right, on a transparent black (0, 0, 0, 0) ground.

    (pvrtex stacks them bottom-up from row ``h - 1`` of a square chain; the levels below the top
    fill ``h - 1`` rows, so both orders put them at the same rows and leave the last row empty.)"""
    levels = list(levels)
    if len(levels) == 1:
        return levels[0].copy()
    top = levels[0]
    h, w = top.shape[:2]
    out_w = w + max(lv.shape[1] for lv in levels[1:])
    out_h = max(h, sum(lv.shape[0] for lv in levels[1:]))
    out = np.zeros((out_h, out_w, 4), dtype=np.uint8)
    out[:h, :w] = top
    y = 0
    for lv in levels[1:]:
        lh, lw = lv.shape[:2]
        out[y:y + lh, w:w + lw] = lv
        y += lh
    return out
