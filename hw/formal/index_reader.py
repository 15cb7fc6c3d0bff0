"""The packed index reader (:class:`hw.index_reader.IndexReader`) equals its golden formula
(:func:`golden.fetch.read_index`) for every block number, index width and base of an index inside
the memory.

The reference is golden's arithmetic: ``bit = k * b``, ``w = base + bit // W``, ``off = bit % W``,
and the index is ``((word[w + 1] : word[w]) >> off) & (2**b - 1)`` (``word`` read from the harness's
own copy of the image, a constant table; golden's shift of the concatenated pair, where the hardware
selects among the offsets an index can start at). The reader's memory is a seeded random image of
12 words (every bit pattern likely somewhere) in banks of 4 words, so that the proof also covers the
bank select of :class:`hw.banked_rom.BankedROM` and, with two banks, the even/odd word pair.

Domain: ``k``, ``b`` (1..16, or the widths a specialised reader serves) and ``base`` free in every
cycle, with the index's bits inside the memory (``base * W + (k + 1) * b <= 12 * W``); ``valid``
free. The reader's enable is held high: a stage that does not advance holds its registers (the
stream proofs of the whole unit cover the stalls).
"""

from __future__ import annotations

import random

import numpy as np
from amaranth import *
from amaranth.asserts import AnySeq

from ..index_reader import INDEX_BITS, LATENCY, IndexReader
from .harness import Harness, SeededBug

__all__ = ["IndexReaderHarness", "image", "MASK_ONE_BIT_WIDE", "PAIR_NOT_ORDERED"]

DEPTH = 12
BANK_DEPTH = 4


def image(word_bits: int, seed: int = 0) -> list:
    """The memory image of the proofs: ``DEPTH`` seeded random words of ``word_bits`` bits."""
    rng = random.Random(seed)
    return [rng.getrandbits(word_bits) for _ in range(DEPTH)]


class IndexReaderHarness(Harness):
    """The reader against the golden formula (see the module docstring).

    Arguments
    ---------
    word_bits : int
        ``W``: 16, 32 or 64.
    widths : tuple of int, optional
        A specialised reader's widths (default: the full reader, 1..16).
    bug : SeededBug, optional
    """

    def __init__(self, word_bits: int, widths=None, bug: SeededBug | None = None):
        super().__init__(bug)
        self._word_bits = word_bits
        self._widths = None if widths is None else tuple(widths)

    def build(self, m, platform):
        W = self._word_bits
        words = image(W)
        k_bits = (DEPTH * W).bit_length()
        base_bits = DEPTH.bit_length()
        # (a uint64 array: ``np.asarray`` of Python ints above 2**63 mixed with smaller ones is float64)
        dut = IndexReader(np.array(words, dtype=np.uint64), word_bits=W, k_bits=k_bits, base_bits=base_bits, bank_depth=BANK_DEPTH,
                          widths=self._widths)
        self.design(m, "dut", dut, platform)
        k, b, base, valid = AnySeq(k_bits), AnySeq(5), AnySeq(base_bits), AnySeq(1)
        m.d.comb += [dut.k.eq(k), dut.b.eq(b), dut.base.eq(base), dut.valid.eq(valid), dut.en.eq(1)]
        widths = self._widths or tuple(range(1, INDEX_BITS + 1))
        self.assume(m, Cat(*(b == v for v in widths)).any())
        self.assume(m, base * W + (k + 1) * b <= DEPTH * W)

        # The inputs, LATENCY cycles later; ``ready`` once the first inputs are there.
        stages = [Cat(k, b, base)]
        for n in range(LATENCY):
            r = Signal(len(stages[0]), name=f"inputs_{n + 1}")
            m.d.sync += r.eq(stages[-1])
            stages.append(r)
        k_d, b_d, base_d = stages[-1][:k_bits], stages[-1][k_bits:k_bits + 5], stages[-1][k_bits + 5:]
        ready = Signal(range(LATENCY + 1))
        with m.If(ready < LATENCY):
            m.d.sync += ready.eq(ready + 1)

        # Golden's formula on the delayed inputs.
        bit = Signal(k_bits + 5)
        w = Signal(base_bits + k_bits + 1)
        off = Signal(range(W))
        m.d.comb += [bit.eq(k_d * b_d), w.eq(base_d + bit // W), off.eq(bit % W)]
        table = Array(C(v, W) for v in words + [0])
        lo = Signal(W)
        hi = Signal(W)
        m.d.comb += [lo.eq(table[Mux(w < DEPTH, w, DEPTH)]), hi.eq(table[Mux(w + 1 < DEPTH, w + 1, DEPTH)])]
        pair = Signal(2 * W)
        index = Signal(INDEX_BITS)
        m.d.comb += [pair.eq(Cat(lo, hi)), index.eq((pair >> off) & ((C(1, 17) << b_d) - 1))]
        with m.If(ready == LATENCY):
            self.claim(m, dut.index == index, "index = ((word[w+1] : word[w]) >> off) & (2**b - 1)")
        self.cover(m, (ready == LATENCY) & (off + b_d > W))


#: Negative control of the full reader: the mask keeps one bit above the index.
MASK_ONE_BIT_WIDE = SeededBug(
    "mask_one_bit_wide", "the index mask keeps b + 1 bits", (),
    lambda s: [("comb", s("mask").eq(
        ~(C((1 << INDEX_BITS) - 1, INDEX_BITS) << (s("fields_pair")[len(s("off")):] + 1))[:INDEX_BITS]))])


def _pair_not_ordered(s):
    parity = s("fields_data")[-1]
    even, odd = s("word", "even_bank"), s("word", "odd_bank")
    return [("sync", s("lo").eq(Mux(parity, even, odd))), ("sync", s("hi").eq(Mux(parity, odd, even)))]


#: Negative control of the two-bank reader: the pair ``{word[w+1], word[w]}`` is ordered the wrong
#: way round (the even bank's word taken as ``word[w]`` when ``w`` is odd).
PAIR_NOT_ORDERED = SeededBug(
    "pair_not_ordered", "the word pair ordered by the wrong parity of w", (), _pair_not_ordered)
