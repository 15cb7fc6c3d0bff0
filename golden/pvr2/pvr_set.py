"""The PowerVR2 layout as a mode of the texture set: ``.dt`` textures in and out of a TextureSet.

The Sega Dreamcast's PowerVR2 is the commercial descendant of the paper's unit: 2x2 codewords, one
index byte per block, a codebook of at most 256 entries. A PowerVR2 texture in a
:class:`golden.format.TextureSet` is (see docs/pvr2.md):

* **Codebook memory**: one entry per codeword, the file's 8 bytes: four 16-bit little-endian texels
  in twiddled order (texel ``t`` at ``(x, y) = (t >> 1, t & 1)``, i.e. column by column), colour
  ``argb1555``, ``rgb565``, ``argb4444`` or ``yuv422`` (the codes after the paper's four). A small
  codebook (``N < 256`` entries, which the file's index bytes name ``256-N .. 255``) is stored as its
  ``N`` entries; the index maps hold the bytes less ``256 - N`` (:func:`to_dt` adds it back).
* **Index memory**: every mip level has its own map (sub-level 0; the paper's extended codewords are
  not used), 8-bit indices in the file's twiddled (Morton) order, each map starting at a word. The
  descriptor's ``layout`` field is 1: the block address shifter interleaves the block coordinates
  into the twiddled block number and transposes the offset inside the block.
* **The 1x1 level** of a mip chain (addressed as if uncompressed: texel 3 of the block the first index
  byte names) is a level of 1x1 blocks whose texel sits at byte 6 of the entry; in a yuv422
  texture that lone texel is rgb565 (the descriptor's colour says so).
* **Colour**: 16-bit texels widen to 8 bits per channel by bit replication in the codebook ROM;
  yuv422 texel pairs (twiddled 0/2 and 1/3: U in the left texel's low byte, V in the right one's, Y
  in each texel's high byte) go through the set's colour matrix, which for an imported set is
  :data:`golden.color.DREAMCAST_YUV422` (the fixed-point form of pvrtex's decode).

:func:`from_dt` builds a one-texture set from a parsed ``.dt``; :func:`import_dt` reads several files
into one set (each keeps its codebook); :func:`to_dt` writes a texture back in pvrtex's layout.
"""

from __future__ import annotations

import os

import numpy as np

from ..color import DREAMCAST_YUV422
from ..constants import COLOR_CODES, DESCRIPTOR_DTYPE, LAYOUT_CODES, MAX_LEVELS, PVR2_COLORS, FormatError
from ..format import (PVR2_ONE_BY_ONE_TEXEL_OFF, CodebookInfo, TextureInfo, TextureSet, entry_layout, log2,
                     pack_indices, unpack_indices)
from .pvr import HEADER_BYTES, MAGIC, PvrError, PvrTexture, read_dt, twiddle_indices

__all__ = ["from_dt", "import_dt", "to_dt", "dt_bytes", "stream_order", "is_pvr2", "dt_control", "WORD_BITS", "ENTRY_BYTES"]

#: Index memory word width of an imported set.
WORD_BITS = 32
#: Bytes of a PowerVR2 codebook entry (four 16-bit texels).
ENTRY_BYTES = 8


def is_pvr2(ts: TextureSet, tex: int) -> bool:
    """True if texture ``tex`` of ``ts`` is in the PowerVR2 layout."""
    return ts.textures[tex].color in PVR2_COLORS


def stream_order(raster: np.ndarray) -> np.ndarray:
    """A ``(bh, bw)`` index map in raster order -> the file's twiddled order (1-D)."""
    bh, bw = raster.shape
    out = np.empty(bh * bw, dtype=np.int64)
    out[twiddle_indices(bw, bh).ravel()] = raster.ravel()
    return out


def from_dt(tex: PvrTexture, name: str = "dt") -> TextureSet:
    """A one-texture set in the PowerVR2 layout holding the parsed ``.dt`` ``tex`` (indices already
    rebased to ``0 .. N-1`` by :func:`golden.pvr2.pvr.parse_dt`). The colour matrix is DREAMCAST_YUV422."""
    hdr = tex.header
    color = PVR2_COLORS[hdr.pixel_format]
    n = hdr.codebook_entries
    codebook = np.ascontiguousarray(tex.codebook.astype("<u2")).view(np.uint8).reshape(n, ENTRY_BYTES).copy()
    cb_layout = entry_layout(color, 2, 2, 1)
    sizes = hdr.level_sizes
    descriptors = np.zeros((1, MAX_LEVELS), DESCRIPTOR_DTYPE)
    parts, base = [], 0
    for L, ((w, h), raster) in enumerate(zip(sizes, tex.indices)):
        words = pack_indices(stream_order(raster), 8, WORD_BITS)
        row = descriptors[0, L]
        row["valid"] = row["compressed"] = 1
        row["base"] = base
        row["log2w"], row["log2h"] = log2(w), log2(h)
        row["index_bits"] = 8
        row["layout"] = LAYOUT_CODES["pvr2"]
        if w == 1 and h == 1:
            row["color"] = COLOR_CODES["rgb565" if color == "yuv422" else color]
            row["texel_off"] = PVR2_ONE_BY_ONE_TEXEL_OFF
        else:
            row["log2bw"] = row["log2bh"] = 1
            row["color"] = COLOR_CODES[color]
            row["texel_off"], row["u_off"], row["v_off"] = cb_layout.planes[0]
        parts.append(words)
        base += len(words)
    parts.append(np.zeros(1, np.dtype("<u4")))             # the guard word
    info = TextureInfo(name=name[:256], width=hdr.width, height=hdr.height, levels=len(sizes), color=color,
                       block=(2, 2), codebook=0, index_bits=8, mipmapped=hdr.mipmapped,
                       params={"layout": "pvr2", "dt_control": hdr.control})
    ts = TextureSet(word_bits=WORD_BITS, index_words=np.concatenate(parts).astype("<u4"), codebook=codebook,
                    raw_words=np.zeros(0, "<u4"), descriptors=descriptors, textures=[info],
                    codebooks=[CodebookInfo(color, (2, 2), 1, n, 0)], matrix=DREAMCAST_YUV422)
    ts.validate()
    ts.check_consistency()
    return ts


def import_dt(paths) -> TextureSet:
    """Read ``.dt`` files (paths) into one texture set, texture ids in the order given.

    Raises:
        PvrError: a file is unreadable, damaged, or not a VQ texture this reader covers.
    """
    paths = list(paths)
    if not paths:
        raise PvrError("no .dt files to import")
    sets = [from_dt(read_dt(p, decode=False), os.path.splitext(os.path.basename(os.fspath(p)))[0]) for p in paths]
    return sets[0] if len(sets) == 1 else TextureSet.combine(sets)


def dt_control(width: int, height: int, color: str, mipmapped: bool) -> int:
    """The PVR texture control word of a VQ twiddled texture: bit 31 mipmapped, bit 30 VQ, bits 29-27
    the pixel format, and in the low bits what pvrtex writes there (size codes ``log2 - 3`` of the
    width in bits 0-2 and of the height in bits 3-5, and bit 8)."""
    return ((int(mipmapped) << 31) | (1 << 30) | (PVR2_COLORS.index(color) << 27) | (1 << 8)
            | ((log2(height) - 3) << 3) | (log2(width) - 3))


def to_dt(ts: TextureSet, tex: int = 0) -> bytes:
    """Texture ``tex`` of ``ts`` (PowerVR2 layout) as the bytes of a ``.dt`` file in pvrtex's layout:
    header, codebook, index maps smallest level first (bytes ``256 - N + index``), zero padding to a
    multiple of 32 bytes (as pvrtex pads its mip chains). :func:`golden.pvr2.pvr.parse_dt` reads it back to the same texels.

    Raises:
        FormatError: the texture is not in the PowerVR2 layout or not what a ``.dt`` can hold.
    """
    if not 0 <= tex < ts.n_textures or not is_pvr2(ts, tex):
        raise FormatError(f"texture {tex} is not in the PowerVR2 layout")
    info = ts.textures[tex]
    cb = ts.codebooks[info.codebook]
    if cb.size > 256 or not (8 <= info.width <= 1024 and 8 <= info.height <= 1024):
        raise FormatError(f"texture {tex}: a .dt holds 8..1024 texels a side and at most 256 codewords")
    n = cb.size
    codebook = np.ascontiguousarray(ts.codebook[cb.base: cb.base + n, :ENTRY_BYTES]).view("<u2").reshape(n, 4)
    maps = []
    for L in range(info.levels):
        d = ts.descriptor(tex, L)
        w, h = 1 << d["log2w"], 1 << d["log2h"]
        maps.append(unpack_indices(ts.index_words, 8, max(1, (w // 2) * (h // 2)), d["base"], ts.word_bits))
    return dt_bytes(info.width, info.height, info.color, info.mipmapped, codebook, maps)


def dt_bytes(width: int, height: int, color: str, mipmapped: bool, codebook: np.ndarray, maps: list) -> bytes:
    """A VQ ``.dt`` in pvrtex's layout: the 32-byte header, the ``(N, 4)`` uint16 codebook, the index
    maps (``maps``: largest level first, each the level's entries ``0 .. N-1`` in twiddled order) smallest
    first as bytes ``256 - N + entry``, zero padding to a multiple of 32 bytes (as pvrtex pads)."""
    n = len(codebook)
    body = np.ascontiguousarray(np.asarray(codebook).astype("<u2")).tobytes()
    body += b"".join((np.asarray(m, dtype=np.int64) + (256 - n)).astype(np.uint8).tobytes() for m in reversed(maps))
    size = HEADER_BYTES + len(body)
    size += -size % 32
    control = dt_control(width, height, color, mipmapped)
    header = (MAGIC + size.to_bytes(4, "little") + bytes([0, 0, n - 1, 0])
              + width.to_bytes(2, "little") + height.to_bytes(2, "little")
              + control.to_bytes(4, "little") + bytes(12))
    return (header + body).ljust(size, b"\0")
