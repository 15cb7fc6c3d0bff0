"""Codebook ROM: (codebook base + index, offset in the block) -> the texel's raw samples.

Twin of :func:`golden.fetch.read_codeword`, and of the raw-level read in :func:`golden.fetch.fetch`.
The codebook memory holds one wide entry per codeword (``entry_bytes * 8`` bits, byte ``n`` of the
entry in bits ``[8n, 8n+8)``); an extended (mipmap) codeword holds every sub-level, and the
descriptor's plane offsets say where this level's texels (or Y, U, V planes) start. Raw levels read a
32-bit RGBA word from the raw memory through the same two stages.
"""

from __future__ import annotations

import numpy as np
from amaranth import *
from amaranth.lib import data, memory, wiring
from amaranth.lib.wiring import In, Out

from golden.format import COLOR_CODES

__all__ = ["CodebookROM", "SamplesLayout", "LATENCY"]

#: Cycles from the index to the samples.
LATENCY = 2

#: Four 8-bit samples: (R,G,B,A), (R,G,B,-), (I,-,-,-) or (Y,U,V,-) as in ``read_codeword``.
SamplesLayout = data.ArrayLayout(unsigned(8), 4)

_YUV = COLOR_CODES["yuv411"]
_RGBA = COLOR_CODES["rgba"]


def _entry_ints(codebook: np.ndarray) -> list:
    """Codebook rows -> little-endian integers (byte n in bits 8n..8n+7)."""
    return [int.from_bytes(bytes(row), "little") for row in np.asarray(codebook, dtype=np.uint8)]


class CodebookROM(wiring.Component):
    """Codebook memory and raw memory, with the texel select.

    1. *read*: the codebook memory at ``cb_base + index`` and the raw memory at ``raw_addr``.
    2. *select*: texel ``t = (y << log2bw) | x``; the four bytes from ``texel_off + tb * t``
       (``tb`` = 3, 4, 1, 1 bytes per texel for rgb, rgba, intensity, yuv411; a byte past the entry
       reads the entry's last byte, as the golden model clamps); for yuv411, samples 1 and 2 are
       ``u_off + ct`` and ``v_off + ct`` with ``ct = ((y >> 1) << max(log2bw - 1, 0)) | (x >> 1)``.
       A raw level's samples are the raw word's bytes and its ``color_out`` is rgba.

    Latency 2 (both stages advance when ``en`` is high). Throughput: one texel per cycle.

    Arguments
    ---------
    codebook : ndarray uint8 (entries, entry_bytes)
        The codebook memory image.
    raw_words : ndarray uint32
        The raw memory image.
    cb_bits, raw_bits, off_bits : int
        Widths of the codebook base, the raw address and the plane offsets.

    Members
    -------
    index : In(16)
        The block's index.
    cb_base : In(cb_bits)
        Entry of codeword 0 of the texture's codebook.
    raw_addr : In(raw_bits)
        Raw memory word (raw levels).
    compressed : In(1)
        0: read the raw memory instead.
    x, y : In(3)
        Offset inside the block.
    log2bw : In(2)
        log2 of the block width at this level.
    color : In(2)
        Colour format code.
    texel_off, u_off, v_off : In(off_bits)
        Byte offsets of this sub-level's planes in the entry.
    en : In(1)
        Pipeline advance.
    samples : Out(SamplesLayout)
        Registered raw samples.
    color_out : Out(2)
        Registered colour format of the samples (rgba for raw levels).
    """

    def __init__(self, codebook, raw_words, *, cb_bits: int, raw_bits: int, off_bits: int):
        codebook = np.asarray(codebook, dtype=np.uint8)
        if codebook.ndim != 2:
            raise ValueError("codebook memory must be a 2-D uint8 array")
        self._entry_bytes = max(1, codebook.shape[1])
        self._entries = _entry_ints(codebook) or [0]
        self._raw = [int(v) for v in np.asarray(raw_words, dtype=np.uint32).tolist()] or [0]
        super().__init__({
            "index": In(16),
            "cb_base": In(cb_bits),
            "raw_addr": In(raw_bits),
            "compressed": In(1),
            "x": In(3),
            "y": In(3),
            "log2bw": In(2),
            "color": In(2),
            "texel_off": In(off_bits),
            "u_off": In(off_bits),
            "v_off": In(off_bits),
            "en": In(1),
            "samples": Out(SamplesLayout),
            "color_out": Out(2),
        })

    @property
    def latency(self) -> int:
        return LATENCY

    def elaborate(self, platform):
        m = Module()
        nbytes = self._entry_bytes
        m.submodules.codebook = codebook = memory.Memory(shape=nbytes * 8, depth=len(self._entries),
                                                         init=self._entries)
        m.submodules.raw = raw = memory.Memory(shape=32, depth=len(self._raw), init=self._raw)
        cb_rd = codebook.read_port(domain="sync")
        raw_rd = raw.read_port(domain="sync")
        m.d.comb += [
            cb_rd.addr.eq(self.cb_base + self.index),
            cb_rd.en.eq(self.en),
            raw_rd.addr.eq(self.raw_addr),
            raw_rd.en.eq(self.en),
        ]

        # Stage 1 registers beside the memories' own.
        fields = ("compressed", "x", "y", "log2bw", "color", "texel_off", "u_off", "v_off")
        r = {name: Signal.like(getattr(self, name), name=f"{name}_r") for name in fields}
        with m.If(self.en):
            m.d.sync += [r[name].eq(getattr(self, name)) for name in fields]

        # Stage 2: texel select. The entry is padded with three copies of its last byte so that
        # every byte address up to last + 3 reads what the golden model's clamp reads.
        entry = cb_rd.data
        last = entry[(nbytes - 1) * 8:]
        padded = Cat(entry, last, last, last)
        t = Signal(6)
        tb = Signal(3)
        start = Signal(len(r["texel_off"]) + 7)
        lcw = Signal(2)
        ct = Signal(6)
        m.d.comb += [
            t.eq((r["y"] << r["log2bw"]) | r["x"]),
            tb.eq(Array([C(3, 3), C(4, 3), C(1, 3), C(1, 3)])[r["color"]]),
            start.eq(r["texel_off"] + tb * t),
            lcw.eq(Mux(r["log2bw"] > 0, r["log2bw"] - 1, 0)),
            ct.eq(((r["y"] >> 1) << lcw) | (r["x"] >> 1)),
        ]
        texel = Signal(32)
        u = Signal(8)
        v = Signal(8)
        m.d.comb += [
            texel.eq(padded.bit_select(start << 3, 32)),
            u.eq(padded.bit_select((r["u_off"] + ct) << 3, 8)),
            v.eq(padded.bit_select((r["v_off"] + ct) << 3, 8)),
        ]
        out = Signal(32)
        with m.If(~r["compressed"]):
            m.d.comb += out.eq(raw_rd.data)
        with m.Elif(r["color"] == _YUV):
            m.d.comb += out.eq(Cat(texel[:8], u, v, texel[24:]))
        with m.Else():
            m.d.comb += out.eq(texel)
        with m.If(self.en):
            m.d.sync += [
                self.samples.as_value().eq(out),
                self.color_out.eq(Mux(r["compressed"], r["color"], _RGBA)),
            ]
        return m
