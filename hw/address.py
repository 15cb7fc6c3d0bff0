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

    Latency 1 (outputs registered, updated in cycles where ``en`` is high). Throughput: one per cycle.

    Arguments
    ---------
    base_bits : int
        Width of the descriptor's ``base`` field.
    k_bits : int
        Width of a block number (at most 24: a 4096x4096 level of 1x1 blocks).
    raw_bits : int
        Width of a raw memory address.

    Members
    -------
    i, j : In(12)
        Texel column and row inside the level.
    log2w : In(4)
        log2 of the level's width.
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

    Arguments
    ---------
    base_bits, k_bits, raw_bits : int
        As above.
    raw : bool
        The set has raw levels (default): compute ``raw_addr`` (an adder); else leave it 0.
    """

    def __init__(self, *, base_bits: int, k_bits: int, raw_bits: int, raw: bool = True):
        for name, v in (("base_bits", base_bits), ("k_bits", k_bits), ("raw_bits", raw_bits)):
            if not isinstance(v, int) or v < 1:
                raise TypeError(f"{name} must be a positive integer, not {v!r}")
        if k_bits > 2 * COORD_BITS:
            raise ValueError(f"k_bits {k_bits} exceeds {2 * COORD_BITS}")
        self._k_bits = k_bits
        self._raw = bool(raw)
        super().__init__({
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
        with m.If(self.en):
            m.d.sync += [
                self.k.eq(((by << row_shift) | bx)[:self._k_bits]),
                self.x.eq(self.i & ~(C((1 << COORD_BITS) - 1, COORD_BITS) << self.log2bw)),
                self.y.eq(self.j & ~(C((1 << COORD_BITS) - 1, COORD_BITS) << self.log2bh)),
            ]
            if self._raw:
                m.d.sync += self.raw_addr.eq(self.base + (self.j << self.log2w) + self.i)
        return m
