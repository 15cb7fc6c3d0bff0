"""The block address shifter (:class:`hw.address.BlockAddress`) equals its golden formula
(:func:`golden.fetch.block_address`, :func:`golden.fetch.twiddled_block`) for every input of a valid
request.

The reference is written as golden writes it, with arithmetic where the hardware has shifts and
masks: ``bx = i // bw``, ``by = j // bh``, ``k = by * (w // bw) + bx``, ``x = i % bw``,
``y = j % bh``, ``raw_addr = base + j * w + i``; for a PowerVR2 twiddled level
``k = square * m * m + sum(bit n of by mod m * 4**n + bit n of bx mod m * 2 * 4**n)`` with
``m = 2**min(log2 gw, log2 gh)`` and ``square = (bx | by) // m``, the offsets transposed.

Every input is free in every cycle (the enable too), restricted to what a valid request of any
texture set can present: a level of at most 4096x4096 texels (``log2w``, ``log2h`` at most 12),
blocks of 1..8 texels a side no larger than the level, ``i < w``, ``j < h``, and for the raw address
a level that fits the raw memory (``base + w * h`` within ``raw_bits``). The block number has the
widest ``k_bits`` (24), the descriptor's ``base`` 16 bits and the raw address 20.
"""

from __future__ import annotations

from amaranth import *
from amaranth.asserts import AnySeq

from ..address import BlockAddress
from .harness import Harness, SeededBug

__all__ = ["AddressHarness", "ROW_SHIFT_USES_HEIGHT", "TWIDDLE_LARGER_SIDE"]

K_BITS, BASE_BITS, RAW_BITS = 24, 16, 20
MAX_LOG2 = 12


class AddressHarness(Harness):
    """The shifter against the golden formula (see the module docstring).

    Arguments
    ---------
    twiddle : bool
        The PowerVR2 shifter (``layout`` free: both maps), else the paper's.
    bug : SeededBug, optional
    """

    def __init__(self, twiddle: bool = False, bug: SeededBug | None = None):
        super().__init__(bug)
        self._twiddle = bool(twiddle)

    def build(self, m, platform):
        dut = BlockAddress(base_bits=BASE_BITS, k_bits=K_BITS, raw_bits=RAW_BITS, twiddle=self._twiddle)
        self.design(m, "dut", dut, platform)
        i, j, log2w, log2h = AnySeq(12), AnySeq(12), AnySeq(4), AnySeq(4)
        log2bw, log2bh, base, en = AnySeq(2), AnySeq(2), AnySeq(BASE_BITS), AnySeq(1)
        layout = AnySeq(1) if self._twiddle else C(0, 1)
        m.d.comb += [dut.i.eq(i), dut.j.eq(j), dut.log2w.eq(log2w), dut.log2bw.eq(log2bw),
                     dut.log2bh.eq(log2bh), dut.base.eq(base), dut.en.eq(en)]
        if self._twiddle:
            m.d.comb += [dut.log2h.eq(log2h), dut.layout.eq(layout)]
        w = Signal(13)
        h = Signal(13)
        bw = Signal(4)
        bh = Signal(4)
        m.d.comb += [w.eq(C(1, 13) << log2w), h.eq(C(1, 13) << log2h), bw.eq(C(1, 4) << log2bw), bh.eq(C(1, 4) << log2bh)]
        raw = Signal(BASE_BITS + 25)
        m.d.comb += raw.eq(base + j * w + i)
        # A valid request (the domain of the claim).
        self.assume(m, (log2w <= MAX_LOG2) & (log2h <= MAX_LOG2) & (log2bw <= log2w) & (log2bh <= log2h))
        self.assume(m, (i < w) & (j < h))
        self.assume(m, base + w * h <= (1 << RAW_BITS))

        # The golden formula, arithmetic.
        bx = Signal(12)
        by = Signal(12)
        m.d.comb += [bx.eq(i // bw), by.eq(j // bh)]
        k = Signal(K_BITS + 1)
        x = Signal(3)
        y = Signal(3)
        m.d.comb += [k.eq(by * (w // bw) + bx), x.eq(i % bw), y.eq(j % bh)]
        if self._twiddle:
            gw = Signal(4)
            gh = Signal(4)
            lm = Signal(4)
            side = Signal(13)
            m.d.comb += [gw.eq(log2w - log2bw), gh.eq(log2h - log2bh), lm.eq(Mux(gw < gh, gw, gh)),
                         side.eq(C(1, 13) << lm)]
            sx = Signal(12)
            sy = Signal(12)
            m.d.comb += [sx.eq(bx % side), sy.eq(by % side)]
            morton = sum((sy[n] * (4 ** n) + sx[n] * (2 * 4 ** n) for n in range(12)), C(0, K_BITS))
            k_tw = Signal(K_BITS + 1)
            m.d.comb += k_tw.eq(((bx | by) // side) * side * side + morton)
            k, x, y = Mux(layout, k_tw, k), Mux(layout, y, x), Mux(layout, x, y)

        # One register stage: the shifter's outputs against the formula of the inputs it took.
        want = {"k": Signal(K_BITS + 1), "x": Signal(3), "y": Signal(3), "raw_addr": Signal(RAW_BITS)}
        with m.If(en):
            m.d.sync += [want["k"].eq(k), want["x"].eq(x), want["y"].eq(y), want["raw_addr"].eq(raw)]
        self.claim(m, dut.k == want["k"], "k = (j // bh) * (w // bw) + i // bw (twiddled: the Morton number)")
        self.claim(m, dut.x == want["x"], "x = i % bw (twiddled: j % bh)")
        self.claim(m, dut.y == want["y"], "y = j % bh (twiddled: i % bw)")
        self.claim(m, dut.raw_addr == want["raw_addr"], "raw_addr = base + j * w + i")
        self.cover(m, en & (log2bw != log2bh) & (bx != 0) & (by != 0) & (layout if self._twiddle else 1))


#: Negative control of the paper's shifter: the row shift subtracts the block's height, not its
#: width (the blocks per row of a non-square block are wrong).
ROW_SHIFT_USES_HEIGHT = SeededBug(
    "row_shift_uses_height", "blocks per row computed as log2w - log2bh", (),
    lambda s: [("comb", s("row_shift").eq(s("log2w") - s("log2bh")))])

#: Negative control of the twiddled shifter: the twiddled squares' side is the larger side of the
#: block grid, not the smaller.
TWIDDLE_LARGER_SIDE = SeededBug(
    "twiddle_larger_side", "the twiddled squares' side taken from the larger side of the block grid", (),
    lambda s: [("comb", s("lm").eq(Mux(s("gw") < s("gh"), s("gh"), s("gw"))))])
