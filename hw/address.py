"""Block address shifter: texel (i, j) -> block number and offset inside the block.

Twin of :func:`golden.fetch.block_address` (and of the raw-level address in
:func:`golden.fetch.fetch`). Only shifts, masks and one add: block sides are powers of two.
"""

from __future__ import annotations

from amaranth import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

__all__ = ["BlockAddress", "COORD_BITS", "OFFSET_BITS"]

#: Width of a texel coordinate (levels up to 4096x4096).
COORD_BITS = 12
#: Width of an offset inside a block (blocks up to 8x8).
OFFSET_BITS = 3


class BlockAddress(wiring.Component):
    """The block address shifter.

    ``k = ((j >> log2bh) << (log2w - log2bw)) | (i >> log2bw)``, ``x = i & (bw - 1)``,
    ``y = j & (bh - 1)`` and, for raw levels, ``raw_addr = base + (j << log2w) + i``.

    With ``twiddle`` (a set holding PowerVR2 textures) and ``layout`` high, ``k`` is instead the
    twiddled (Morton) block number of :func:`golden.fetch.twiddled_block` and the offsets are
    transposed (``x = j & (bh - 1)``, ``y = i & (bw - 1)``: a PowerVR2 codeword lists its texels
    column by column), as :func:`golden.fetch.block_address` says.

    Latency 1 (outputs registered, updated in cycles where ``en`` is high). Throughput: one per cycle.

    Arguments
    ---------
    base_bits : int
        Width of the descriptor's ``base`` field.
    k_bits : int
        Width of a block number (at most 24: a 4096x4096 level of 1x1 blocks).
    raw_bits : int
        Width of a raw memory address.
    twiddle : bool
        Elaborate the PowerVR2 twiddled path (default False: the paper's shifter only).
    linear : bool
        With ``twiddle``: some level has the paper's row-major map (default): ``layout`` selects
        between the two; False: every level that reads ``k``, ``x``, ``y`` is twiddled (``layout``
        is ignored, no multiplexer).
    raw : bool
        The set has raw levels (default): compute ``raw_addr`` (an adder); else leave it 0.
    word_bits : int or None
        With an index word width (16, 32, 64), also register the index words a request reads (the
        cached unit, :class:`hw.memory.unit.CachedTexelFetch`, whose tag check follows this stage
        in the next cycle): ``bit = k * index_bits``, ``word = base + (bit >> log2 word_bits)``,
        ``bit_offset = bit mod word_bits`` and ``straddle = bit_offset + index_bits > word_bits``
        (the on-chip unit's index reader does this in stages of its own). Default None: not built.
    one_shifter : bool
        With ``twiddle``: the twiddled number as one shifter and a per-bit choice (:meth:`_twiddled`;
        the loadable unit's, whose ``max`` preset it took from 10.5 logic levels to 7); default
        False, the shift right and left of the formula (the baked units, their netlists as before).

    Members
    -------
    i, j : In(12)
        Texel column and row inside the level.
    log2w : In(4)
        log2 of the level's width.
    log2h : In(4)
        log2 of the level's height (``twiddle`` only).
    layout : In(1)
        The descriptor's layout: 1 for a PowerVR2 twiddled index map (``twiddle`` only).
    log2bw, log2bh : In(2)
        log2 of the block's width and height at this level.
    base : In(base_bits)
        Raw memory word of texel (0, 0) (raw levels; ignored by the block path).
    en : In(1)
        Pipeline advance.
    k : Out(k_bits)
        Block number, row-major in the level group's index map.
    x, y : Out(3)
        Offset inside the block.
    raw_addr : Out(raw_bits)
        Raw memory word of texel (i, j) (0 when ``raw`` is false).
    index_bits : In(5)
        ``word_bits`` only: the level's index width.
    word, bit_offset, straddle : Out
        ``word_bits`` only: the request's first index word, its index's bit offset in it, and whether
        the index straddles into the next word.
    """

    def __init__(self, *, base_bits: int, k_bits: int, raw_bits: int, twiddle: bool = False,
                 raw: bool = True, linear: bool = True, word_bits: int | None = None, one_shifter: bool = False):
        for name, v in (("base_bits", base_bits), ("k_bits", k_bits), ("raw_bits", raw_bits)):
            if not isinstance(v, int) or v < 1:
                raise TypeError(f"{name} must be a positive integer, not {v!r}")
        if k_bits > 2 * COORD_BITS:
            raise ValueError(f"k_bits {k_bits} exceeds {2 * COORD_BITS}")
        self._k_bits = k_bits
        self._twiddle = bool(twiddle)
        self._linear = bool(linear) or not self._twiddle
        self._raw = bool(raw)
        self._one_shifter = bool(one_shifter)
        if word_bits not in (None, 16, 32, 64):
            raise ValueError(f"word_bits {word_bits!r}: 16, 32 or 64 (or None)")
        self._word_bits = word_bits
        twiddle_ports = {"layout": In(1), "log2h": In(4)} if self._twiddle else {}
        lw = (word_bits or 1).bit_length() - 1
        word_ports = {"index_bits": In(5), "word": Out(max(base_bits, k_bits + 5 - lw) + 1),
                      "bit_offset": Out(max(1, lw)), "straddle": Out(1)} if word_bits else {}
        super().__init__({
            **twiddle_ports,
            **word_ports,
            "i": In(COORD_BITS),
            "j": In(COORD_BITS),
            "log2w": In(4),
            "log2bw": In(2),
            "log2bh": In(2),
            "base": In(base_bits),
            "en": In(1),
            "k": Out(k_bits),
            "x": Out(OFFSET_BITS),
            "y": Out(OFFSET_BITS),
            "raw_addr": Out(raw_bits),
        })

    @property
    def twiddle(self) -> bool:
        """The PowerVR2 twiddled path is elaborated (``layout`` and ``log2h`` ports exist)."""
        return self._twiddle

    def elaborate(self, platform):
        m = Module()
        bx = Signal(COORD_BITS)
        by = Signal(COORD_BITS)
        row_shift = Signal(4)               # log2(blocks per row) = log2w - log2bw
        m.d.comb += [
            bx.eq(self.i >> self.log2bw),
            by.eq(self.j >> self.log2bh),
            row_shift.eq(self.log2w - self.log2bw),
        ]
        k = (by << row_shift) | bx
        x = self.i & ~(C((1 << COORD_BITS) - 1, COORD_BITS) << self.log2bw)
        y = self.j & ~(C((1 << COORD_BITS) - 1, COORD_BITS) << self.log2bh)
        k_out, x_out, y_out = k, x, y
        if self._twiddle:
            k_out, x_out, y_out = self._twiddled(m, bx, by, k, x, y)
        with m.If(self.en):
            m.d.sync += [
                self.k.eq(k_out[:self._k_bits]),
                self.x.eq(x_out),
                self.y.eq(y_out),
            ]
            if self._raw:
                m.d.sync += self.raw_addr.eq(self.base + (self.j << self.log2w) + self.i)
            if self._word_bits:
                W = self._word_bits
                lw = W.bit_length() - 1
                bit = Signal(self._k_bits + 5)
                m.d.comb += bit.eq(k_out[:self._k_bits] * self.index_bits)
                m.d.sync += [self.word.eq(self.base + (bit >> lw)), self.bit_offset.eq(bit[:lw]),
                             self.straddle.eq((bit[:lw] + self.index_bits) > W)]
        return m

    def _twiddled(self, m, bx, by, k, x, y):
        """The PowerVR2 layout (``layout`` high): the twiddled (Morton) block number
        ``((bx | by) >> lm) << 2 lm | interleave(bx mod 2**lm, by mod 2**lm)`` (``by`` bit n at bit
        2n, ``bx`` bit n at bit 2n + 1; ``lm`` the log2 of the smaller side of the block grid) and
        the offsets transposed.

        With ``one_shifter``, one shifter: bit ``p`` of the number is bit ``p`` of the full
        interleave of ``bx`` and ``by`` below ``2 lm`` (wiring) and bit ``p`` of ``(bx | by) << lm``
        from ``2 lm`` up
        (``(square << 2 lm)[p] = (bx | by)[p - lm]``), a per-bit choice by a thermometer of ``lm``:
        the same value as the shift right then left of the formula, one shifter fewer in the cycle
        (docs/area.md, "The paths between blocks")."""
        gw = Signal(4)
        gh = Signal(4)
        lm = Signal(4)                      # log2 of the twiddled squares' side, in blocks
        m.d.comb += [
            gw.eq(self.log2w - self.log2bw),
            gh.eq(self.log2h - self.log2bh),
            lm.eq(Mux(gw < gh, gw, gh)),
        ]
        if self._one_shifter:
            k_tw = Signal(2 * COORD_BITS)
            interleave = Cat(*(Cat(by[n], bx[n]) for n in range(COORD_BITS)))
            squares = Signal(2 * COORD_BITS)    # (bx | by) << lm: the square's number in place
            m.d.comb += squares.eq((bx | by) << lm)
            m.d.comb += k_tw.eq(Cat(*(Mux(lm > (p >> 1), interleave[p], squares[p])
                                      for p in range(2 * COORD_BITS))))
        else:
            low = ~(C((1 << COORD_BITS) - 1, COORD_BITS) << lm)
            sx = Signal(COORD_BITS)
            sy = Signal(COORD_BITS)
            square = Signal(COORD_BITS)         # which square along the longer side
            m.d.comb += [sx.eq(bx & low), sy.eq(by & low), square.eq((bx | by) >> lm)]
            morton = Cat(*(Cat(sy[n], sx[n]) for n in range(COORD_BITS)))
            k_tw = Signal(2 * COORD_BITS)
            m.d.comb += k_tw.eq((square << (lm << 1)) | morton)
        if not self._linear:                # every compressed level twiddled: no multiplexer
            return k_tw, y, x
        return (Mux(self.layout, k_tw, k), Mux(self.layout, y, x), Mux(self.layout, x, y))
