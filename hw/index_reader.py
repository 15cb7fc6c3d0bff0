"""Packed index reader: block number -> the block's b-bit index from the packed index map.

Twin of :func:`golden.fetch.read_index`. The bit address ``k * b`` splits into the word
``w = base + (k*b >> log2 W)`` and the bit offset ``off = k*b & (W - 1)``; the index is
``({word[w+1], word[w]} >> off) & (2**b - 1)``. An index *straddles* when ``off + b > W``.

The index memory is split into an EVEN bank (words 0, 2, 4, ...) and an ODD bank (words 1, 3, ...):
words ``w`` and ``w + 1`` always live in different banks, so both arrive in the same cycle and a
straddling index costs nothing (the paper's "specialized addressing logic"). With ``one_port`` the
memory is a single bank and a straddling index takes one extra cycle.
"""

from __future__ import annotations

import numpy as np
from amaranth import *
from amaranth.lib import memory, wiring
from amaranth.lib.wiring import In, Out

__all__ = ["IndexReader", "INDEX_BITS", "LATENCY"]

#: Width of an index (b is 1..16).
INDEX_BITS = 16
#: Cycles from the block number to the index.
LATENCY = 2


def _depth_bits(depth: int) -> int:
    return max(0, (depth - 1).bit_length())


class IndexReader(wiring.Component):
    """The packed index reader.

    Two internal stages, both advancing in cycles where ``en`` is high:

    1. *word address*: ``k * b``, word ``w``, offset ``off``; the banks are read (two-bank: even
       bank at ``(w + 1) >> 1``, odd bank at ``w >> 1``; one-port: the single bank at ``w``, then
       ``w + 1``).
    2. *extract*: the two words are ordered by the parity of ``w`` (or, one-port, the word saved
       from the first read and the second read), concatenated, shifted by ``off`` and masked.

    Latency 2. Throughput: one index per cycle; with ``one_port``, a straddling index occupies
    stage 1 for two advancing cycles: in the first, ``hold`` is high, the stages upstream must not
    advance and stage 2 receives a bubble.

    Arguments
    ---------
    words : ndarray
        The index memory image (``TextureSet.index_words``).
    word_bits : int
        ``W``: 16, 32 or 64.
    k_bits : int
        Width of the block number.
    base_bits : int
        Width of the level group's base word.
    one_port : bool
        One bank; a straddling index costs one extra cycle.

    Members
    -------
    valid : In(1)
        Stage 1 holds a request that reads an index (gates ``hold`` and ``straddle``).
    k : In(k_bits)
        Block number.
    b : In(5)
        Index width (1..16).
    base : In(base_bits)
        Index memory word where the level group's map starts.
    en : In(1)
        Pipeline advance.
    straddle : Out(1)
        Combinational: the index read in stage 1 straddles a word boundary (``valid`` and
        ``off + b > W``).
    hold : Out(1)
        Combinational, one-port only (else 0): stage 1 spends this cycle on the first of two reads.
    index : Out(16)
        The index, registered (latency 2).

    Raises
    ------
    ValueError
        If ``word_bits`` is not 16, 32 or 64.
    """

    def __init__(self, words, *, word_bits: int, k_bits: int, base_bits: int, one_port: bool = False):
        if word_bits not in (16, 32, 64):
            raise ValueError(f"index word width {word_bits} is not 16, 32 or 64")
        self._words = [int(w) for w in np.asarray(words).astype(np.uint64).tolist()] or [0]
        self._word_bits = word_bits
        self._k_bits = k_bits
        self._one_port = bool(one_port)
        super().__init__({
            "valid": In(1),
            "k": In(k_bits),
            "b": In(5),
            "base": In(base_bits),
            "en": In(1),
            "straddle": Out(1),
            "hold": Out(1),
            "index": Out(INDEX_BITS),
        })

    @property
    def latency(self) -> int:
        return LATENCY

    @property
    def one_port(self) -> bool:
        return self._one_port

    def elaborate(self, platform):
        m = Module()
        W = self._word_bits
        log2W = W.bit_length() - 1

        # Stage 1: bit address -> word and offset.
        bit = Signal(self._k_bits + 5)
        w = Signal(max(len(self.base), self._k_bits + 5 - log2W) + 1)
        off = Signal(log2W)
        m.d.comb += [
            bit.eq(self.k * self.b),
            w.eq(self.base + (bit >> log2W)),
            off.eq(bit[:log2W]),
            self.straddle.eq(self.valid & (off + self.b > W)),
        ]

        off_r = Signal(log2W)
        b_r = Signal(5)
        with m.If(self.en):
            m.d.sync += [off_r.eq(off), b_r.eq(self.b)]

        lo = Signal(W)
        hi = Signal(W)
        if not self._one_port:
            even_words = self._words[0::2] or [0]
            odd_words = self._words[1::2] or [0]
            m.submodules.even_bank = even = memory.Memory(shape=W, depth=len(even_words), init=even_words)
            m.submodules.odd_bank = odd = memory.Memory(shape=W, depth=len(odd_words), init=odd_words)
            even_rd = even.read_port(domain="sync")
            odd_rd = odd.read_port(domain="sync")
            parity_r = Signal()
            m.d.comb += [
                even_rd.addr.eq((w + 1) >> 1),
                odd_rd.addr.eq(w >> 1),
                even_rd.en.eq(self.en),
                odd_rd.en.eq(self.en),
            ]
            with m.If(self.en):
                m.d.sync += parity_r.eq(w[0])
            # Stage 2: order the two words: word[w] is in the odd bank when w is odd.
            m.d.comb += [
                lo.eq(Mux(parity_r, odd_rd.data, even_rd.data)),
                hi.eq(Mux(parity_r, even_rd.data, odd_rd.data)),
            ]
        else:
            m.submodules.bank = bank = memory.Memory(shape=W, depth=len(self._words), init=self._words)
            rd = bank.read_port(domain="sync")
            second = Signal()              # stage 1 is on the second read of a straddling index
            saved = Signal(W)              # word[w] from the first read
            straddled_r = Signal()
            m.d.comb += [
                self.hold.eq(self.straddle & ~second),
                rd.addr.eq(w + second),
                rd.en.eq(self.en),
            ]
            with m.If(self.en):
                m.d.sync += [second.eq(self.hold), straddled_r.eq(self.straddle)]
                with m.If(second):
                    m.d.sync += saved.eq(rd.data)
            m.d.comb += [
                lo.eq(Mux(straddled_r, saved, rd.data)),
                hi.eq(rd.data),
            ]

        # Stage 2: {hi, lo} >> off, masked to b bits.
        mask = Signal(INDEX_BITS)
        m.d.comb += mask.eq(~(C((1 << INDEX_BITS) - 1, INDEX_BITS) << b_r)[:INDEX_BITS])
        with m.If(self.en):
            m.d.sync += self.index.eq((Cat(lo, hi) >> off_r)[:INDEX_BITS] & mask)
        return m
