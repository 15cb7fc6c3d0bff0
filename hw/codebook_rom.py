"""Codebook ROM: (codebook base + index, offset in the block) -> the texel's raw samples.

Twin of :func:`golden.fetch.read_codeword`, and of the raw-level read in :func:`golden.fetch.fetch`.
The codebook memory holds one wide entry per codeword (``entry_bytes * 8`` bits, byte ``n`` of the
entry in bits ``[8n, 8n+8)``); an extended (mipmap) codeword holds every sub-level, and the
descriptor's plane offsets say where this level's texels (or Y, U, V planes) start. Raw levels read a
32-bit RGBA word from the raw memory through the same four stages. Both memories are banked
(:class:`hw.banked_rom.BankedROM`: 512-entry block RAM banks, each read registered).
"""

from __future__ import annotations

import numpy as np
from amaranth import *
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from vqtex.golden.format import COLOR_CODES

from .banked_rom import BANK_DEPTH, BankedROM, pick
from .registers import enabled_register

__all__ = ["CodebookROM", "SamplesLayout", "LATENCY", "expand_texel"]

#: Cycles from the index to the samples.
LATENCY = 4

#: Four 8-bit samples: (R,G,B,A), (R,G,B,-), (I,-,-,-) or (Y,U,V,-) as in ``read_codeword``.
SamplesLayout = data.ArrayLayout(unsigned(8), 4)

_RGB, _RGBA, _YUV = (COLOR_CODES[c] for c in ("rgb", "rgba", "yuv411"))
_ARGB1555, _RGB565, _ARGB4444, _YUV422 = (COLOR_CODES[c] for c in ("argb1555", "rgb565", "argb4444", "yuv422"))


def _widen(field: Value) -> Value:
    """A 4-, 5- or 6-bit colour field widened to 8 bits by bit replication (``v << (8-n) | v >> (2n-8)``):
    wiring only."""
    n = len(field)
    return Cat(field, field)[2 * n - 8:] if n < 8 else field


def expand_texel(texel: Value, color: Value) -> Value:
    """The 16-bit PowerVR2 texel as R, G, B, A bytes (combinational; twin of
    :func:`golden.fetch.expand_texels`): argb1555 (A = bit 15 replicated), rgb565 (A = 255),
    argb4444."""
    t = texel
    argb1555 = Cat(_widen(t[10:15]), _widen(t[5:10]), _widen(t[0:5]), t[15].replicate(8))
    rgb565 = Cat(_widen(t[11:16]), _widen(t[5:11]), _widen(t[0:5]), C(255, 8))
    argb4444 = Cat(_widen(t[8:12]), _widen(t[4:8]), _widen(t[0:4]), _widen(t[12:16]))
    return Mux(color == _ARGB1555, argb1555, Mux(color == _RGB565, rgb565, argb4444))


def _entry_ints(codebook: np.ndarray) -> list:
    """Codebook rows -> little-endian integers (byte n in bits 8n..8n+7)."""
    return [int.from_bytes(bytes(row), "little") for row in np.asarray(codebook, dtype=np.uint8)]


class CodebookROM(wiring.Component):
    """Codebook memory and raw memory, with the texel select.

    The texel's bytes start at ``start = texel_off + tb * t`` with ``t = (y << log2bw) | x`` and
    ``tb`` = 3, 4, 1, 1 bytes per texel for rgb, rgba, intensity, yuv411 (a byte past the entry
    reads the entry's last byte, as the golden model clamps); for yuv411, samples 1 and 2 are the
    bytes at ``u_off + ct`` and ``v_off + ct`` with ``ct = ((y >> 1) << max(log2bw - 1, 0)) | (x >> 1)``.
    A raw level's samples are the raw word's bytes and its ``color_out`` is rgba. Four stages:

    1. *read*: the codebook memory at ``cb_base + index`` and the raw memory at ``raw_addr``; the
       byte addresses ``start``, ``u_off + ct``, ``v_off + ct`` (``tb * t`` as shifts and an add),
       registered beside the block RAMs' read registers.
    2. *data*: the read data, registered per 512-entry bank.
    3. *window*: in every codebook bank, the two 4-byte-aligned words of the entry that hold the
       texel's bytes (a 64-bit window) and the words holding U and V; the raw word of the selected
       raw bank. Registered.
    4. *select*: the bank's windows selected, then the bytes inside them; registered as ``samples``.

    Latency 4 (every stage advances when ``en`` is high). Throughput: one texel per cycle.

    Arguments
    ---------
    codebook : ndarray uint8 (entries, entry_bytes)
        The codebook memory image.
    raw_words : ndarray uint32
        The raw memory image.
    cb_bits, raw_bits, off_bits : int
        Widths of the codebook base, the raw address and the plane offsets.
    bank_depth : int
        Entries per block RAM bank of each memory (:class:`hw.banked_rom.BankedROM`).

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

    def __init__(self, codebook, raw_words, *, cb_bits: int, raw_bits: int, off_bits: int,
                 bank_depth: int = BANK_DEPTH, color_bits: int = 2):
        codebook = np.asarray(codebook, dtype=np.uint8)
        if codebook.ndim != 2:
            raise ValueError("codebook memory must be a 2-D uint8 array")
        self._entry_bytes = max(1, codebook.shape[1])
        self._entries = _entry_ints(codebook) or [0]
        self._raw = [int(v) for v in np.asarray(raw_words, dtype=np.uint32).tolist()] or [0]
        self._bank_depth = bank_depth
        if color_bits not in (2, 3):
            raise ValueError(f"color_bits must be 2 (the paper's formats) or 3 (with PowerVR2's), not {color_bits!r}")
        self._pvr2 = color_bits == 3
        super().__init__({
            "index": In(16),
            "cb_base": In(cb_bits),
            "raw_addr": In(raw_bits),
            "compressed": In(1),
            "x": In(3),
            "y": In(3),
            "log2bw": In(2),
            "color": In(color_bits),
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
        m.submodules.codebook = codebook = BankedROM(self._entries, width=nbytes * 8, bank_depth=self._bank_depth)
        m.submodules.raw = raw = BankedROM(self._raw, width=32, bank_depth=self._bank_depth)
        m.d.comb += [
            codebook.addr.eq(self.cb_base + self.index), codebook.en.eq(self.en),
            raw.addr.eq(self.raw_addr), raw.en.eq(self.en),
        ]

        def reg(value, name):
            return enabled_register(m, self.en, value, name)

        # Stage 1: byte addresses of the texel and of its U and V, beside the memory reads.
        t = Signal(6)
        tbt = Signal(8)                     # tb * t
        lcw = Signal(2)
        ct = Signal(6)
        m.d.comb += [
            t.eq((self.y << self.log2bw) | self.x),
            lcw.eq(Mux(self.log2bw > 0, self.log2bw - 1, 0)),
            ct.eq(((self.y >> 1) << lcw) | (self.x >> 1)),
        ]
        with m.Switch(self.color):
            with m.Case(_RGB):
                m.d.comb += tbt.eq((t << 1) + t)
            with m.Case(_RGBA):
                m.d.comb += tbt.eq(t << 2)
            if self._pvr2:
                with m.Case(_ARGB1555, _RGB565, _ARGB4444, _YUV422):
                    m.d.comb += tbt.eq(t << 1)          # 16-bit texels
            with m.Default():
                m.d.comb += tbt.eq(t)
        if self._pvr2:
            # yuv422: U and V are the low bytes of the row's left and right texels, at u_off + 2x
            # and v_off + 2x (``x`` is the row: PowerVR2 offsets come transposed)
            ct_pair = Signal(6)
            m.d.comb += ct_pair.eq(Mux(self.color == _YUV422, self.x << 1, ct))
            ct = ct_pair
        nwords = -(-(nbytes + 3) // 4) + 1     # 4-byte words of the padded entry (see stage 3)
        addr_bits = (4 * nwords - 1).bit_length()
        # The fields that ride beside the memories, one register per stage (assigned in one piece:
        # one register update per stage in a simulator instead of five).
        cbits = len(self.color)
        carried = data.StructLayout({"start": addr_bits, "ustart": addr_bits, "vstart": addr_bits,
                                     "compressed": 1, "color": cbits})
        f1 = Signal(carried, name="fields_read")
        with m.If(self.en):
            m.d.sync += f1.eq(Cat((self.texel_off + tbt)[:addr_bits], (self.u_off + ct)[:addr_bits],
                                  (self.v_off + ct)[:addr_bits], self.compressed, self.color))

        # Stage 2: the banks' data registers (in BankedROM); the fields follow.
        f2 = reg(f1, "fields_data")
        start, ustart, vstart = f2.start, f2.ustart, f2.vstart

        # Stage 3: per codebook bank, the 4-byte words holding the texel (two: a 64-bit window) and
        # U and V, each picked from a list of words by the word number (a multiplexer of whole
        # words; no shifter). The entry is padded with three copies of its last byte, so that every
        # byte address up to last + 3 reads what the golden model's clamp reads, then with zeros.
        windows, u_words, v_words = [], [], []
        for k in range(codebook.banks):
            entry = codebook.data[k]
            last = entry[(nbytes - 1) * 8:]
            padded = Cat(entry, last, last, last)
            words = [Cat(padded[32 * n:32 * n + 32], C(0, max(0, 32 * n + 32 - len(padded))))
                     for n in range(nwords - 1)] + [C(0, 32)]
            windows.append(reg(pick([Cat(words[n], words[n + 1]) for n in range(nwords - 1)], start[2:]),
                               f"window{k}"))
            u_words.append(reg(pick(words, ustart[2:]), f"u_word{k}"))
            v_words.append(reg(pick(words, vstart[2:]), f"v_word{k}"))
        bank = reg(codebook.bank, "bank_window")
        raw_word = reg(raw.word, "raw_window")
        f3 = reg(Cat(start[:2], ustart[:2], vstart[:2], f2.compressed, f2.color), "fields_window")
        start, ustart, vstart, compressed, color = f3[0:2], f3[2:4], f3[4:6], f3[6], f3[7:7 + cbits]

        # Stage 4: the bank's words, then the bytes.
        window = pick(windows, bank)
        texel = Signal(32)
        u = Signal(8)
        v = Signal(8)
        m.d.comb += [
            texel.eq(window.bit_select(start << 3, 32)),
            u.eq(pick(u_words, bank).bit_select(ustart << 3, 8)),
            v.eq(pick(v_words, bank).bit_select(vstart << 3, 8)),
        ]
        out = Signal(32)
        if not self._pvr2:                  # the paper's formats only
            with m.If(~compressed):
                m.d.comb += out.eq(raw_word)
            with m.Elif(color == _YUV):
                m.d.comb += out.eq(Cat(texel[:8], u, v, texel[24:]))
            with m.Else():
                m.d.comb += out.eq(texel)
            with m.If(self.en):
                m.d.sync += [
                    self.samples.as_value().eq(out),
                    self.color_out.eq(Mux(compressed, color, _RGBA)),
                ]
            return m
        # With PowerVR2 formats: 16-bit texels expanded here (then rgba to the colour matrix); yuv422
        # as (Y, U, V) with Y the texel's high byte (then yuv411's code: through the matrix).
        color_out = Signal(2)               # what the colour matrix is told: the paper's codes only
        m.d.comb += color_out.eq(Mux(compressed, color[:2], _RGBA))
        with m.If(~compressed):
            m.d.comb += out.eq(raw_word)
        with m.Elif(color == _YUV):
            m.d.comb += out.eq(Cat(texel[:8], u, v, texel[24:]))
        with m.Elif(color == _YUV422):
            m.d.comb += [out.eq(Cat(texel[8:16], u, v, texel[24:])), color_out.eq(_YUV)]
        with m.Elif(color[2]):
            m.d.comb += [out.eq(expand_texel(texel[:16], color)), color_out.eq(_RGBA)]
        with m.Else():
            m.d.comb += out.eq(texel)
        with m.If(self.en):
            m.d.sync += [
                self.samples.as_value().eq(out),
                self.color_out.eq(color_out),
            ]
        return m
