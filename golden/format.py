"""The VQ texture format: memory images, bit packing and the ``.vqt`` container.

Everything the hardware holds in its memories is produced here, so "what is in the file is what is in
the chip". The contract (see ``docs/format.md`` for the hardware engineer's version):

* **Index memory** -- ``word_bits``-bit words (16, 32 or 64; default 32). A level group's index map
  lists its blocks in row-major order; index ``k`` occupies bits ``[k*b, k*b+b)`` of the
  little-endian bit stream that starts at the group's base word. ``b`` is 1..16. One zero word is
  appended after the last map so that reading words ``w`` and ``w+1`` never leaves the memory.
* **Codebook memory** -- one entry per codeword, ``entry_bytes`` wide (the widest codebook's entry;
  narrower ones are zero-padded). An entry is a little-endian byte string: for each sub-level ``s``
  of the (extended) codeword, the ``(bw>>s) x (bh>>s)`` texels row-major (RGB888: R,G,B; RGBA8888:
  R,G,B,A; I8: I), or for YUV 4:1:1 the Y plane, then the U plane, then the V plane, each row-major
  (chroma planes are ``max(1,w/2) x max(1,h/2)``).
* **Raw memory** -- 32-bit words, one texel per word, RGBA8888 with R in bits 0..7 (the response
  format: raw levels need no colour conversion).
* **Descriptor table** -- one row per (texture, level), ``MAX_LEVELS`` rows per texture; see
  :data:`DESCRIPTOR_FIELDS`.
* **The PowerVR2 layout** (descriptor ``layout`` 1, colours argb1555 / rgb565 / argb4444 / yuv422):
  Dreamcast VQ textures; 8-bit indices in twiddled (Morton) order, one index map per mip level,
  codebook entries of four 16-bit texels listed column by column. See :mod:`golden.pvr2.pvr_set` and
  ``docs/pvr2.md``.

A fetch of texel (i, j) of a level (``i`` is the column, ``j`` the row, both inside the level) is
defined by :mod:`golden.fetch` from these images alone.
"""

from __future__ import annotations

import json
import math
import os
import struct
import tempfile
import zlib
from dataclasses import dataclass, field

import numpy as np

from .color import JFIF_BT601, ColorMatrix
from .constants import (COLOR_CODES, COLORS, DESCRIPTOR_DTYPE, DESCRIPTOR_FIELDS, LAYOUT_CODES, LAYOUTS, MAX_LEVELS,
                        MAX_SIZE, PVR2_COLORS, RAW_BELOW, RAW_WORD_BITS, WORD_BITS_ALLOWED, FormatError)
from .vqt_header import parse_header

__all__ = [
    "FormatError", "COLORS", "COLOR_CODES", "MAX_LEVELS", "MAX_SIZE", "DESCRIPTOR_FIELDS",
    "DESCRIPTOR_DTYPE", "PVR2_COLORS", "LAYOUTS", "LAYOUT_CODES", "texel_bytes", "sub_levels", "entry_layout", "EntryLayout", "pack_indices",
    "unpack_indices", "TextureInfo", "CodebookInfo", "TextureSet", "is_pow2", "log2", "RAW_BELOW", "RAW_WORD_BITS",
    "WORD_BITS_ALLOWED",
]

def is_pow2(n: int) -> bool:
    return isinstance(n, (int, np.integer)) and n > 0 and (n & (n - 1)) == 0


def log2(n: int) -> int:
    return int(n).bit_length() - 1


def texel_bytes(color: str) -> int:
    """Bytes per texel of a codeword plane (Y only for yuv411; the PowerVR2 formats are 16-bit)."""
    return {"rgb": 3, "rgba": 4, "intensity": 1, "yuv411": 1,
            "argb1555": 2, "rgb565": 2, "argb4444": 2, "yuv422": 2}[color]


def sub_levels(bw: int, bh: int) -> int:
    """Sub-levels of an extended codeword of ``bw x bh`` blocks: each halves both sides, at most 3
    (4x4 -> 4x4, 2x2, 1x1; 2x2 -> 2, 4x1 -> 1)."""
    return min(3, 1 + min(log2(bw), log2(bh)))


@dataclass(frozen=True)
class EntryLayout:
    """Byte layout of one codeword entry. ``planes[s]`` = (texel_off, u_off, v_off) of sub-level s."""
    color: str
    bw: int
    bh: int
    nsub: int
    planes: tuple
    size: int

    def sub_shape(self, s: int) -> tuple[int, int]:
        return self.bw >> s, self.bh >> s

    def chroma_shape(self, s: int) -> tuple[int, int]:
        w, h = self.sub_shape(s)
        return max(1, w >> 1), max(1, h >> 1)


def entry_layout(color: str, bw: int, bh: int, nsub: int = 1) -> EntryLayout:
    """Where each sub-level's texels (and yuv411 planes) sit inside a codeword entry."""
    planes, off = [], 0
    for s in range(nsub):
        w, h = bw >> s, bh >> s
        if color == "yuv411":
            cw, ch = max(1, w >> 1), max(1, h >> 1)
            planes.append((off, off + w * h, off + w * h + cw * ch))
            off += w * h + 2 * cw * ch
        elif color == "yuv422":
            # texel pairs (twiddled texels 0/2 and 1/3) share chroma: U in the left texel's low byte
            # (texels 0, 1: bytes off + 2x), V in the right texel's (texels 2, 3: bytes off + 4 + 2x)
            planes.append((off, off, off + h * texel_bytes(color)))
            off += w * h * texel_bytes(color)
        else:
            planes.append((off, 0, 0))
            off += w * h * texel_bytes(color)
    return EntryLayout(color, bw, bh, nsub, tuple(planes), off)


# ---------------------------------------------------------------------------------------------
# Bit packing

#: Indices :func:`pack_indices` and :func:`unpack_indices` handle at a time (their temporaries: about
#: 17 bytes a bit of the chunk).
UNPACK_CHUNK = 1 << 16

def pack_indices(indices: np.ndarray, b: int, word_bits: int = 32) -> np.ndarray:
    """Pack indices into the little-endian bit stream of ``word_bits``-bit words.

    Index ``k`` occupies bits ``[k*b, k*b+b)``; the last word is zero-padded.
    Returns an unsigned array of ``ceil(n*b/word_bits)`` words (dtype of ``word_bits``). Works in
    chunks of :data:`UNPACK_CHUNK` indices.
    """
    idx = np.asarray(indices, dtype=np.uint64).ravel()
    if not 1 <= b <= 16:
        raise FormatError(f"index width {b} is outside 1..16")
    if idx.size and int(idx.max()) >> b:
        raise FormatError(f"an index does not fit in {b} bits")
    nwords = -(-(idx.size * b) // word_bits)
    out = np.zeros(nwords * word_bits // 8, np.uint8)
    shifts = np.arange(b, dtype=np.uint64)
    for a in range(0, idx.size, UNPACK_CHUNK):     # bounded temporaries; a * b is a whole byte
        bits = ((idx[a: a + UNPACK_CHUNK, None] >> shifts) & 1).astype(np.uint8).ravel()
        packed = np.packbits(bits, bitorder="little")
        out[a * b // 8: a * b // 8 + len(packed)] = packed
    return out.view(np.dtype(f"<u{word_bits // 8}"))


def unpack_indices(words: np.ndarray, b: int, n: int, base: int = 0, word_bits: int = 32,
                   first: int = 0) -> np.ndarray:
    """Inverse of :func:`pack_indices`: ``n`` indices from the map starting at word ``base``, from
    index ``first`` of the map on (int64). Works in chunks of :data:`UNPACK_CHUNK` indices, so its
    memory is the result and a bounded working set."""
    out = np.empty(n, np.int64)
    for a in range(0, n, UNPACK_CHUNK):
        m = min(UNPACK_CHUNK, n - a)
        start = (first + a) * b                    # the chunk's first bit in the map
        skip = start % word_bits
        w0 = base + start // word_bits
        span = -(-(skip + m * b) // word_bits)     # the words the chunk occupies, and no more
        w = np.asarray(words[w0: w0 + span]).astype(f"<u{word_bits // 8}")
        bits = np.unpackbits(w.view(np.uint8), bitorder="little")[skip: skip + m * b]
        out[a: a + m] = (bits.reshape(m, b).astype(np.int64) << np.arange(b)).sum(axis=1)
    return out


# ---------------------------------------------------------------------------------------------
# The texture set

class _Record:
    """JSON round trip of a metadata dataclass (``block`` is a tuple in Python, a list in JSON)."""

    def to_dict(self):
        d = dict(self.__dict__)
        d["block"] = list(self.block)
        return d

    @classmethod
    def from_dict(cls, d):
        d = dict(d)
        d["block"] = tuple(d["block"])
        return cls(**d)


@dataclass
class TextureInfo(_Record):
    """What a texture is and how it was encoded (metadata; the memory images are the truth)."""
    name: str
    width: int
    height: int
    levels: int
    color: str
    block: tuple
    codebook: int          # index into TextureSet.codebooks, or -1 if stored raw
    index_bits: int
    mipmapped: bool
    params: dict = field(default_factory=dict)
    #: Levels a pruned set does not store (``golden.need.prune``): their descriptor rows are not valid but
    #: keep the level's size, so level numbers and shapes (and a scene's requests) stay as they were.
    absent_levels: list = field(default_factory=list)

    def to_dict(self):
        d = super().to_dict()
        d["absent_levels"] = [int(L) for L in d["absent_levels"]]
        if not d["absent_levels"]:
            del d["absent_levels"]                  # the header of a set that is not pruned is unchanged
        return d

    def stored(self, level: int) -> bool:
        """Whether ``level`` exists and this set stores it."""
        return 0 <= level < self.levels and level not in self.absent_levels



@dataclass
class CodebookInfo(_Record):
    """One codebook in the codebook memory."""
    color: str
    block: tuple
    nsub: int
    size: int              # number of codewords K
    base: int              # first entry in the codebook memory

    @property
    def layout(self) -> EntryLayout:
        return entry_layout(self.color, self.block[0], self.block[1], self.nsub)



#: Byte offset in a PowerVR2 codebook entry of the texel a 1x1 mip level reads (texel 3, bottom right).
PVR2_ONE_BY_ONE_TEXEL_OFF = 6


def _check_pvr2_level(row, info, cb, level: int, where: str) -> None:
    """A compressed level of a PowerVR2 texture (twiddled layout) must be what
    :mod:`golden.pvr2.pvr_set` writes: 8-bit indices into one 2x2 codebook of 16-bit texels, sub-level 0
    (every level has its own index map); a 1x1 level reads texel 3 of its block (a 1x1 block at byte
    offset 6), and in yuv422 that lone texel is rgb565. Raises FormatError."""
    if tuple(info.block) != (2, 2) or info.index_bits != 8 or cb is None or cb.nsub != 1:
        raise FormatError(f"{where}: a PowerVR2 texture has 2x2 blocks, 8-bit indices and a one-level codebook")
    if int(row["sublevel"]) or int(row["index_bits"]) != 8:
        raise FormatError(f"{where}: a PowerVR2 level reads sub-level 0 of its own 8-bit index map")
    lw, lh = int(row["log2w"]), int(row["log2h"])
    if lw and lh:
        want = (1, 1, COLOR_CODES[info.color]) + tuple(cb.layout.planes[0])
    elif not lw and not lh and info.mipmapped:
        color = "rgb565" if info.color == "yuv422" else info.color
        want = (0, 0, COLOR_CODES[color], PVR2_ONE_BY_ONE_TEXEL_OFF, 0, 0)
    else:
        raise FormatError(f"{where}: a {1 << lw}x{1 << lh} PowerVR2 level (square mip chains only)")
    have = tuple(int(row[f]) for f in ("log2bw", "log2bh", "color", "texel_off", "u_off", "v_off"))
    if have != want:
        raise FormatError(f"{where}: block size, colour or texel offsets disagree with the PowerVR2 layout")


MAGIC = b"VQTX\r\n\x1a\n"
VERSION = 1
_ARRAYS = ("index_words", "codebook", "raw_words", "descriptors")


@dataclass
class TextureSet:
    """Textures, their codebooks and the memory images the hardware holds.

    Members
    -------
    word_bits : int
        Index memory word width (16, 32 or 64).
    index_words : ndarray of ``<u{word_bits/8}``
        The index memory (level groups' packed index maps, then one zero word).
    codebook : ndarray uint8 (entries, entry_bytes)
        The codebook memory, one row per codeword entry.
    raw_words : ndarray ``<u4``
        The raw memory, RGBA8888 texel per word.
    descriptors : structured ndarray (n_textures, MAX_LEVELS) of :data:`DESCRIPTOR_DTYPE`
    textures, codebooks : metadata lists
    matrix : ColorMatrix used for yuv411 textures
    present_blocks : ndarray uint8 or None
        Only in a pruned set (``golden.need.prune``): for every stored compressed level, in texture then
        level order, one bit per block of the level's index map (bit ``k % 8`` of byte ``k // 8`` of
        the level's share, each share a whole number of bytes), 1 where block ``k`` is stored. A
        block whose bit is 0 has lost its codeword: requests for it are refused
        (:func:`golden.fetch.check_requests`). ``None``: every block of every stored level is there.
    """
    word_bits: int
    index_words: np.ndarray
    codebook: np.ndarray
    raw_words: np.ndarray
    descriptors: np.ndarray
    textures: list
    codebooks: list
    matrix: ColorMatrix = JFIF_BT601
    present_blocks: np.ndarray | None = None

    # -- queries ------------------------------------------------------------------------------
    @property
    def n_textures(self) -> int:
        return len(self.textures)

    @property
    def entry_bytes(self) -> int:
        return int(self.codebook.shape[1])

    def level_shapes(self, tex: int) -> list[tuple[int, int]]:
        """[(width, height)] of every level of texture ``tex``."""
        d = self.descriptors[tex]
        return [(1 << int(d["log2w"][L]), 1 << int(d["log2h"][L]))
                for L in range(self.textures[tex].levels)]

    def present_rows(self):
        """(rows, offsets, nblocks): the stored compressed (texture, level) rows as a bool
        (n_textures, MAX_LEVELS) array, each row's first byte in :attr:`present_blocks` and its block
        count (int64 arrays of the same shape, 0 elsewhere)."""
        d = self.descriptors
        rows = d["valid"].astype(bool) & d["compressed"].astype(bool)
        shift_w = np.where(rows, d["log2w"].astype(np.int64) - d["log2bw"].astype(np.int64), 0)
        shift_h = np.where(rows, d["log2h"].astype(np.int64) - d["log2bh"].astype(np.int64), 0)
        nblocks = np.where(rows, 1 << np.clip(shift_w + shift_h, 0, 24), 0)
        nbytes = (nblocks + 7) // 8
        offsets = (np.cumsum(nbytes) - nbytes.ravel()).reshape(nbytes.shape)
        return rows, offsets, nblocks

    def block_present(self, tex, level, k) -> np.ndarray:
        """bool per request: block ``k`` of (tex, level) is stored (always True without
        :attr:`present_blocks`; the rows must be stored compressed rows)."""
        k = np.asarray(k, np.int64)
        if self.present_blocks is None:
            return np.ones(k.shape, bool)
        _, offsets, _ = self.present_rows()
        byte = offsets[np.asarray(tex, np.int64), np.asarray(level, np.int64)] + (k >> 3)
        return ((self.present_blocks[byte] >> (k & 7).astype(np.uint8)) & 1).astype(bool)

    def descriptor(self, tex: int, level: int) -> dict:
        row = self.descriptors[tex, level]
        return {name: int(row[name]) for name in DESCRIPTOR_FIELDS}

    def rates(self, tex: int | None = None) -> dict:
        """Compression rates counted as the paper counts them.

        ``base``: original bits of a block over its index bits (24-bit RGB source for rgb and yuv411,
        32 for rgba, 8 for intensity). ``overall``: original bits of every stored level over the bits
        actually stored for them: index maps, raw levels, and the texture's share of its codebook
        (a shared codebook is split in proportion to the level-0 texels of the textures sharing it).
        With ``tex=None`` the whole set: total original bits over total stored bits. Levels a pruned
        set does not store count neither way (a texture with none stored has an overall rate of 1).
        """
        if tex is None:
            orig = stored = 0.0
            for t in range(self.n_textures):
                r = self.rates(t)
                orig += r["original_bits"]
                stored += r["stored_bits"]
            return {"overall": orig / stored if stored else 1.0, "original_bits": orig, "stored_bits": stored}
        info = self.textures[tex]
        src_bits = {"rgb": 24, "rgba": 32, "intensity": 8, "yuv411": 24}.get(info.color, 16)  # PowerVR2: 16-bit
        orig = index = raw = 0
        for L, (w, h) in enumerate(self.level_shapes(tex)):
            d = self.descriptors[tex, L]
            if not d["valid"]:
                continue                              # pruned: neither original nor stored
            orig += w * h * src_bits
            if d["compressed"]:
                if d["sublevel"] == 0:
                    nblocks = (w >> int(d["log2bw"])) * (h >> int(d["log2bh"]))
                    index += nblocks * int(d["index_bits"])
            else:
                raw += w * h * src_bits
        cb_share = 0.0
        if info.codebook >= 0:
            cb = self.codebooks[info.codebook]
            sharers = [t for t in self.textures if t.codebook == info.codebook]
            total = sum(t.width * t.height for t in sharers)
            cb_share = cb.size * cb.layout.size * 8 * (info.width * info.height) / total
        bw, bh = info.block
        stored = index + raw + cb_share
        return {
            "base": (bw * bh * src_bits / info.index_bits) if info.codebook >= 0 else 1.0,
            "overall": orig / stored if stored else 1.0,     # a pruned texture: nothing for nothing
            "original_bits": orig, "stored_bits": stored,
            "index_bits_total": index, "raw_bits": raw, "codebook_bits_share": cb_share,
        }

    # -- validation -----------------------------------------------------------------------------
    def validate(self) -> None:
        """Check that the descriptors only point inside the memories. Raises FormatError."""
        if self.word_bits not in WORD_BITS_ALLOWED:
            raise FormatError(f"index word width {self.word_bits} is not one of {WORD_BITS_ALLOWED}")
        if self.index_words.dtype != np.dtype(f"<u{self.word_bits // 8}"):
            raise FormatError("index memory dtype does not match its word width")
        if self.codebook.dtype != np.uint8 or self.codebook.ndim != 2:
            raise FormatError("codebook memory must be a 2-D uint8 array")
        if self.raw_words.dtype != np.dtype("<u4") or self.raw_words.ndim != 1:
            raise FormatError("raw memory must be a 1-D array of 32-bit words")
        d = self.descriptors
        if d.dtype != DESCRIPTOR_DTYPE or d.shape != (len(self.textures), MAX_LEVELS):
            raise FormatError("descriptor table has the wrong shape or fields")
        for t, info in enumerate(self.textures):
            if not (1 <= info.levels <= MAX_LEVELS):
                raise FormatError(f"texture {t}: {info.levels} levels")
            absent = info.absent_levels
            if (not isinstance(absent, list) or any(type(L) is not int for L in absent)
                    or absent != sorted(set(absent)) or any(not 0 <= L < info.levels for L in absent)):
                raise FormatError(f"texture {t}: absent levels must be distinct increasing level numbers")
            for L in range(MAX_LEVELS):
                row = d[t, L]
                if bool(row["valid"]) != info.stored(L):
                    raise FormatError(f"texture {t} level {L}: valid flag disagrees with the stored levels")
                if not row["valid"]:
                    continue
                if row["log2w"] > 12 or row["log2h"] > 12:      # before any shift by them
                    raise FormatError(f"texture {t} level {L}: size out of range")
                w, h = 1 << int(row["log2w"]), 1 << int(row["log2h"])
                if row["compressed"]:
                    b = int(row["index_bits"])
                    if not 1 <= b <= 16 or row["color"] >= len(COLORS) or row["sublevel"] > 2 or row["layout"] > 1:
                        raise FormatError(f"texture {t} level {L}: bad index width, colour or sub-level")
                    if row["log2bw"] > row["log2w"] or row["log2bh"] > row["log2h"]:
                        raise FormatError(f"texture {t} level {L}: block larger than level")
                    nblocks = (w >> int(row["log2bw"])) * (h >> int(row["log2bh"]))
                    last_word = int(row["base"]) + (nblocks * b - 1) // self.word_bits + 1
                    if last_word >= len(self.index_words):
                        raise FormatError(f"texture {t} level {L}: index map runs past the index memory")
                    cb = self.codebooks[info.codebook] if 0 <= info.codebook < len(self.codebooks) else None
                    if cb is None or int(row["cb_base"]) != cb.base or cb.base + cb.size > len(self.codebook):
                        raise FormatError(f"texture {t} level {L}: codebook missing or past the codebook memory")
                    if max(int(row["texel_off"]), int(row["u_off"]), int(row["v_off"])) >= self.entry_bytes:
                        raise FormatError(f"texture {t} level {L}: plane offset outside the entry")
                elif int(row["base"]) + w * h > len(self.raw_words):
                    raise FormatError(f"texture {t} level {L}: raw level runs past the raw memory")
        if self.present_blocks is not None:
            pb = self.present_blocks
            if pb.dtype != np.uint8 or pb.ndim != 1:
                raise FormatError("block presence must be a 1-D uint8 array")
            rows, offsets, nblocks = self.present_rows()
            need = int((offsets + (nblocks + 7) // 8).max(initial=0))
            if len(pb) != need:
                raise FormatError(f"block presence holds {len(pb)} bytes, the stored compressed levels need {need}")

    def check_consistency(self) -> None:
        """Check that the metadata, the codebooks and every descriptor row agree, as the encoder
        writes them (a loaded file must hold what :mod:`golden.encode` could have made). Call after
        :meth:`validate`. Raises FormatError."""
        if self.codebook.shape[1] < 1 and self.codebooks:
            raise FormatError("codebook memory has entries of 0 bytes")
        for k, cb in enumerate(self.codebooks):
            if cb.base + cb.size > len(self.codebook) or cb.layout.size > self.entry_bytes:
                raise FormatError(f"codebook {k} does not fit the codebook memory")
            if cb.nsub > sub_levels(*cb.block):
                raise FormatError(f"codebook {k}: {cb.nsub} sub-levels for {cb.block[0]}x{cb.block[1]} blocks")
        d = self.descriptors
        for name in ("valid", "compressed"):
            if (d[name] > 1).any():
                raise FormatError(f"descriptor field {name} is not 0 or 1")
        for t, info in enumerate(self.textures):
            lw, lh = log2(info.width), log2(info.height)
            if info.levels > 1 + max(lw, lh):
                raise FormatError(f"texture {t}: {info.levels} levels for a {info.width}x{info.height} texture")
            cb = self.codebooks[info.codebook] if 0 <= info.codebook < len(self.codebooks) else None
            if info.codebook >= len(self.codebooks) or (cb is not None and (cb.color, tuple(cb.block)) != (info.color, tuple(info.block))):
                raise FormatError(f"texture {t}: codebook {info.codebook} missing or of another format")
            for L in range(info.levels):
                row = d[t, L]
                where = f"texture {t} level {L}"
                if (int(row["log2w"]), int(row["log2h"])) != (max(0, lw - L), max(0, lh - L)):
                    raise FormatError(f"{where}: size disagrees with the texture's")
                if not row["valid"] and row["compressed"]:
                    raise FormatError(f"{where}: an absent level marked compressed")
                if not row["compressed"]:
                    if int(row["layout"]):
                        raise FormatError(f"{where}: a raw level has no index map to twiddle")
                    continue
                if (info.color in PVR2_COLORS) != (int(row["layout"]) == LAYOUT_CODES["pvr2"]):
                    raise FormatError(f"{where}: layout disagrees with the colour format {info.color}")
                if info.color in PVR2_COLORS:
                    _check_pvr2_level(row, info, cb, L, where)
                    continue
                s = int(row["sublevel"])
                if cb is None or s >= cb.nsub:
                    raise FormatError(f"{where}: compressed without a codebook of sub-level {s}")
                if (int(row["color"]), int(row["index_bits"])) != (COLOR_CODES[info.color], info.index_bits):
                    raise FormatError(f"{where}: colour or index width disagrees with the texture's")
                bw, bh = info.block
                if (1 << int(row["log2bw"]), 1 << int(row["log2bh"])) != (bw >> s, bh >> s) or (bw >> s) < 1 or (bh >> s) < 1:
                    raise FormatError(f"{where}: block size disagrees with sub-level {s} of {bw}x{bh} blocks")
                if (int(row["texel_off"]), int(row["u_off"]), int(row["v_off"])) != tuple(cb.layout.planes[s]):
                    raise FormatError(f"{where}: plane offsets disagree with the codeword layout")
                if s:
                    if L < s:
                        raise FormatError(f"{where}: sub-level {s} of a group that would start before level 0")
                    # the group's first stored level: its top, unless a pruned set dropped that
                    first = next(M for M in range(L - s, L + 1) if d[t, M]["valid"])
                    group = d[t, first]
                    if not group["compressed"] or int(group["sublevel"]) != first - (L - s) or group["base"] != row["base"]:
                        raise FormatError(f"{where}: sub-level {s} does not read its level group's index map")

    def index_maps(self):
        """Each stored index map once, from the first stored level of its group (sub-levels read
        their group's map): ``(texture, level, base, index_bits, n, codebook_size)``, with ``n`` the
        map's indices. Texture and level order; a loop over maps, not over indices."""
        for t, info in enumerate(self.textures):
            if info.codebook < 0:
                continue
            size = self.codebooks[info.codebook].size
            for L in range(info.levels):
                row = self.descriptors[t, L]
                s = int(row["sublevel"])
                if not row["compressed"] or (s and self.descriptors[t, L - 1]["compressed"]):
                    continue                          # the group's first stored level reads it
                n = (1 << int(row["log2w"]) >> int(row["log2bw"])) * (1 << int(row["log2h"]) >> int(row["log2bh"]))
                yield t, L, int(row["base"]), int(row["index_bits"]), n, size

    def check_indices(self) -> None:
        """Raise FormatError if an index in any map points past its codebook (the hardware would
        read another codebook's entry, or past the memory)."""
        for t, L, base, b, n, size in self.index_maps():
            step = self.word_bits * (1 << 14)          # indices per chunk: a whole number of words
            for k in range(0, n, step):
                idx = unpack_indices(self.index_words, b, min(step, n - k), base + k * b // self.word_bits,
                                     self.word_bits)
                if int(idx.max()) >= size:
                    raise FormatError(f"texture {t} level {L}: index {int(idx.max())} past codebook of {size}")

    # -- combining --------------------------------------------------------------------------------
    @classmethod
    def combine(cls, sets: list["TextureSet"]) -> "TextureSet":
        """One texture set holding all textures of ``sets`` (each keeps its own codebooks).

        Memories are concatenated and descriptors rebased; texture ids follow the order of ``sets``.
        All sets must share the word width, and the sets holding YUV textures their colour matrix.
        """
        if not sets:
            raise FormatError("nothing to combine")
        wb = sets[0].word_bits
        if any(s.present_blocks is not None for s in sets):
            raise FormatError("sets pruned to blocks are not combined (combine, then prune)")
        if any(s.word_bits != wb for s in sets):
            raise FormatError("combined texture sets must share word width")
        # the colour matrix matters only to sets holding a YUV texture (yuv411 or yuv422): they must agree
        yuv = [s.matrix for s in sets if any(t.color in ("yuv411", "yuv422") for t in s.textures)]
        matrix = yuv[0] if yuv else sets[0].matrix
        if any(m != matrix for m in yuv):
            raise FormatError("combined texture sets holding YUV textures must share the colour matrix")
        entry_bytes = max(s.entry_bytes for s in sets)
        index_parts, cb_parts, raw_parts, desc_parts, textures, codebooks = [], [], [], [], [], []
        iw = ce = rw = 0
        for s in sets:
            words = s.index_words[:-1]        # drop the guard word; one is appended at the end
            index_parts.append(words)
            cb = np.zeros((len(s.codebook), entry_bytes), np.uint8)
            cb[:, : s.entry_bytes] = s.codebook
            cb_parts.append(cb)
            raw_parts.append(s.raw_words)
            d = s.descriptors.copy()
            comp = d["compressed"].astype(bool) & d["valid"].astype(bool)
            raw = ~d["compressed"].astype(bool) & d["valid"].astype(bool)
            d["base"][comp] += iw
            d["base"][raw] += rw
            d["cb_base"][comp] += ce
            desc_parts.append(d)
            for info in s.textures:
                info = TextureInfo.from_dict(info.to_dict())
                if info.codebook >= 0:
                    info.codebook += len(codebooks)
                textures.append(info)
            for cbi in s.codebooks:
                codebooks.append(CodebookInfo(cbi.color, cbi.block, cbi.nsub, cbi.size, cbi.base + ce))
            iw += len(words)
            ce += len(s.codebook)
            rw += len(s.raw_words)
        dt = np.dtype(f"<u{wb // 8}")
        index_parts.append(np.zeros(1, dt))
        out = cls(
            word_bits=wb,
            index_words=np.concatenate(index_parts).astype(dt),
            codebook=np.concatenate(cb_parts) if cb_parts else np.zeros((0, 1), np.uint8),
            raw_words=np.concatenate(raw_parts).astype("<u4"),
            descriptors=np.concatenate(desc_parts),
            textures=textures, codebooks=codebooks, matrix=matrix,
        )
        out.validate()
        return out

    # -- the .vqt container ---------------------------------------------------------------------
    def to_bytes(self) -> bytes:
        """Serialise: magic, version, header length, JSON header, arrays, CRC-32 (little-endian)."""
        arrays = {
            "index_words": np.ascontiguousarray(self.index_words),
            "codebook": np.ascontiguousarray(self.codebook),
            "raw_words": np.ascontiguousarray(self.raw_words),
            "descriptors": np.ascontiguousarray(self.descriptors),
        }
        names = _ARRAYS
        if self.present_blocks is not None:
            arrays["present_blocks"] = np.ascontiguousarray(self.present_blocks, np.uint8)
            names = _ARRAYS + ("present_blocks",)
        table, blobs, off = {}, [], 0
        for name in names:
            a = arrays[name]
            raw = a.tobytes()
            table[name] = {"shape": list(a.shape), "offset": off, "nbytes": len(raw),
                           "dtype": a.dtype.str if a.dtype.names is None else "descriptor"}
            blobs.append(raw)
            off += len(raw)
        header = json.dumps({
            "word_bits": self.word_bits,
            "entry_bytes": self.entry_bytes,
            "descriptor_fields": list(DESCRIPTOR_FIELDS),
            "matrix": self.matrix.to_dict(),
            "textures": [t.to_dict() for t in self.textures],
            "codebooks": [c.to_dict() for c in self.codebooks],
            "arrays": table,
        }, sort_keys=True).encode()
        body = MAGIC + struct.pack("<II", VERSION, len(header)) + header + b"".join(blobs)
        return body + struct.pack("<I", zlib.crc32(body))

    @classmethod
    def from_bytes(cls, data: bytes) -> "TextureSet":
        """Parse a ``.vqt`` image. Raises :class:`FormatError` on anything truncated or corrupt."""
        if len(data) < len(MAGIC) + 12:
            raise FormatError("file is too short to be a .vqt texture set")
        if data[: len(MAGIC)] != MAGIC:
            raise FormatError("not a .vqt texture set (bad magic)")
        version, hlen = struct.unpack_from("<II", data, len(MAGIC))
        if version != VERSION:
            raise FormatError(f"unsupported .vqt version {version} (this reader knows {VERSION})")
        (crc,) = struct.unpack_from("<I", data, len(data) - 4)
        if zlib.crc32(data[:-4]) != crc:
            raise FormatError("checksum mismatch: the file is truncated or corrupted")
        start = len(MAGIC) + 8
        if start + hlen > len(data) - 4:
            raise FormatError("header runs past the end of the file")
        body = memoryview(data)[start + hlen: len(data) - 4]
        header = parse_header(bytes(data[start: start + hlen]), len(body))   # every size bounded by the file
        try:
            arrays = {}
            for name, (dt, shape, off, nbytes) in header["arrays"].items():
                dtype = header["descriptor_dtype"] if dt == "descriptor" else np.dtype(dt)
                arrays[name] = np.frombuffer(body[off: off + nbytes], dtype=dtype).reshape(shape).copy()
            if arrays["descriptors"].dtype != DESCRIPTOR_DTYPE:     # a file from before ``layout``: 0
                old = arrays["descriptors"]
                arrays["descriptors"] = np.zeros(old.shape, DESCRIPTOR_DTYPE)
                for name in old.dtype.names:
                    arrays["descriptors"][name] = old[name]
            if arrays["codebook"].shape[1] != header["entry_bytes"]:
                raise FormatError("codebook memory width disagrees with entry_bytes")
            ts = cls(
                word_bits=header["word_bits"],
                index_words=arrays["index_words"], codebook=arrays["codebook"],
                raw_words=arrays["raw_words"], descriptors=arrays["descriptors"],
                textures=[TextureInfo.from_dict(t) for t in header["textures"]],
                codebooks=[CodebookInfo.from_dict(c) for c in header["codebooks"]],
                matrix=ColorMatrix.from_dict(header["matrix"]),
                present_blocks=arrays.get("present_blocks"),
            )
            ts.validate()
            ts.check_consistency()
            ts.check_indices()
        except FormatError:
            raise
        except (KeyError, IndexError, TypeError, ValueError, AttributeError, OverflowError) as e:
            raise FormatError(f"malformed .vqt file: {str(e).splitlines()[0] if str(e) else type(e).__name__}") from None
        return ts

    def save(self, path) -> None:
        """Write atomically (temporary file in the same folder, then rename)."""
        data = self.to_bytes()
        folder = os.path.dirname(os.path.abspath(path))
        fd, tmp = tempfile.mkstemp(prefix=".vqt-", dir=folder)
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(data)
            os.replace(tmp, path)
        except BaseException:
            if os.path.exists(tmp):
                os.unlink(tmp)
            raise

    @classmethod
    def load(cls, path) -> "TextureSet":
        """Read a ``.vqt`` file. A missing or unreadable file also raises :class:`FormatError`."""
        try:
            with open(path, "rb") as f:
                data = f.read()
        except OSError as e:
            raise FormatError(f"cannot read {path}: {e.strerror}") from None
        return cls.from_bytes(data)

    def __eq__(self, other):
        if not isinstance(other, TextureSet):
            return NotImplemented
        return self.to_bytes() == other.to_bytes()


def default_index_bits(k: int) -> int:
    """ceil(log2 K), at least 1."""
    return max(1, math.ceil(math.log2(k)))
