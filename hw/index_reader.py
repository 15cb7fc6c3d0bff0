"""Packed index reader: block number -> the block's b-bit index from the packed index map.

Twin of :func:`golden.fetch.read_index`. The bit address ``k * b`` splits into the word
``w = base + (k*b >> log2 W)`` and the bit offset ``off = k*b & (W - 1)``; the index is
``({word[w+1], word[w]} >> off) & (2**b - 1)``. An index *straddles* when ``off + b > W``.

The index memory is split into an EVEN bank (words 0, 2, 4, ...) and an ODD bank (words 1, 3, ...):
words ``w`` and ``w + 1`` always live in different banks, so both arrive in the same cycle and a
straddling index costs nothing (the paper's "specialized addressing logic"). With ``one_port`` the
memory is a single bank and a straddling index takes one extra cycle. Either memory is a
:class:`hw.banked_rom.BankedROM` (512-word block RAM banks, each read registered).
"""

from __future__ import annotations

import numpy as np
from amaranth import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .banked_rom import BANK_DEPTH, BankedROM
from .registers import enabled_register

__all__ = ["IndexReader", "INDEX_BITS", "LATENCY"]

#: Width of an index (b is 1..16).
INDEX_BITS = 16
#: Cycles from the block number to the index.
LATENCY = 5


class IndexReader(wiring.Component):
    """The packed index reader.

    Five internal stages, each a register:

    1. *bit address*: ``k * b`` (a multiplier, registered), with ``base``, ``b`` and ``valid``.
    2. *word*: ``w = base + (k*b >> log2 W)`` and ``off``; the memory is read (two-bank: even bank
       at ``(w + 1) >> 1``, odd bank at ``w >> 1``; one-port: the single bank at ``w``, then
       ``w + 1``) into the block RAMs' read registers.
    3. *data*: the read data, registered per 512-word bank.
    4. *pair*: the bank's word selected and the two words ordered by the parity of ``w`` (one-port:
       the word of the first read, kept from the previous item, and the second read), registered as
       the pair ``{word[w+1], word[w]}``.
    5. *extract*: the pair shifted right by ``off`` and masked to ``b`` bits, registered.

    Latency 5; stages 2..5 advance when ``en`` is high, stage 1 when ``en & ~hold``. Throughput: one
    index per cycle. With ``one_port``, a straddling index stays in stage 1 for two advancing
    cycles: in the first, ``hold`` is high, stage 1 keeps its item and does not take the inputs (the
    stages upstream must not advance either) and stage 2 receives a bubble (ahead of the item).

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
    bank_depth : int
        Words per block RAM bank of each memory (:class:`hw.banked_rom.BankedROM`).

    Members
    -------
    valid : In(1)
        The inputs are a request that reads an index (registered into stage 1; gates ``hold`` and
        ``straddle``).
    k : In(k_bits)
        Block number.
    b : In(5)
        Index width (1..16).
    base : In(base_bits)
        Index memory word where the level group's map starts.
    en : In(1)
        Pipeline advance.
    straddle : Out(1)
        Combinational: the index read of the item in stage 1 straddles a word boundary (its
        ``valid`` and ``off + b > W``).
    hold : Out(1)
        Combinational, one-port only (else 0): stage 1 spends this cycle on the first of two reads.
    index : Out(16)
        The index, registered (latency 5).

    Raises
    ------
    ValueError
        If ``word_bits`` is not 16, 32 or 64.
    """

    def __init__(self, words, *, word_bits: int, k_bits: int, base_bits: int, one_port: bool = False,
                 bank_depth: int = BANK_DEPTH):
        if word_bits not in (16, 32, 64):
            raise ValueError(f"index word width {word_bits} is not 16, 32 or 64")
        self._words = [int(w) for w in np.asarray(words).astype(np.uint64).tolist()] or [0]
        self._word_bits = word_bits
        self._k_bits = k_bits
        self._one_port = bool(one_port)
        self._bank_depth = bank_depth
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

        # Stage 1: the bit address k*b, registered (a multiplier's output goes straight to flops).
        # The fields beside it are one register (one update per cycle in a simulator), as are the
        # fields carried through each later stage.
        bit = Signal(self._k_bits + 5, name="bit")
        fields1 = Signal(len(self.base) + 6, name="fields_bit")
        base1, b1, valid1 = fields1[:len(self.base)], fields1[len(self.base):-1], fields1[-1]
        with m.If(self.en & ~self.hold):
            m.d.sync += [bit.eq(self.k * self.b), fields1.eq(Cat(self.base, self.b, self.valid))]

        # Stage 2: word and offset; the memory read.
        w = Signal(max(len(self.base), self._k_bits + 5 - log2W) + 1)
        off = Signal(log2W)
        m.d.comb += [
            w.eq(base1 + (bit >> log2W)),
            off.eq(bit[:log2W]),
            self.straddle.eq(valid1 & (off + b1 > W)),
        ]

        def reg(value, name):
            return enabled_register(m, self.en, value, name)

        lo = Signal(W, name="lo")           # stage 4: word[w]
        hi = Signal(W, name="hi")           # stage 4: word[w + 1]
        if not self._one_port:
            m.submodules.even_bank = even = BankedROM(self._words[0::2] or [0], width=W, bank_depth=self._bank_depth)
            m.submodules.odd_bank = odd = BankedROM(self._words[1::2] or [0], width=W, bank_depth=self._bank_depth)
            m.d.comb += [
                even.addr.eq((w + 1) >> 1), even.en.eq(self.en),
                odd.addr.eq(w >> 1), odd.en.eq(self.en),
            ]
            fields3 = reg(reg(Cat(off, b1, w[0]), "fields_word"), "fields_data")
            parity = fields3[-1]
            # Stage 4: word[w] is in the odd bank when w is odd.
            with m.If(self.en):
                m.d.sync += [
                    lo.eq(Mux(parity, odd.word, even.word)),
                    hi.eq(Mux(parity, even.word, odd.word)),
                ]
        else:
            m.submodules.memory = mem = BankedROM(self._words, width=W, bank_depth=self._bank_depth)
            second = Signal()               # stage 1 is on the second read of a straddling index
            m.d.comb += [
                self.hold.eq(self.straddle & ~second),
                mem.addr.eq(w + second),
                mem.en.eq(self.en),
            ]
            with m.If(self.en):
                m.d.sync += second.eq(self.hold)
            fields3 = reg(reg(Cat(off, b1, self.straddle), "fields_word"), "fields_data")
            straddled = fields3[-1]
            # Stage 4: the first read (word w) went down the pipeline one item ahead, as the bubble;
            # ``hi`` still holds it when the straddler's second read (word w + 1) arrives.
            with m.If(self.en):
                m.d.sync += [hi.eq(mem.word), lo.eq(Mux(straddled, hi, mem.word))]

        # Stage 5: {hi, lo} >> off, masked to b bits.
        fields4 = reg(fields3[:-1], "fields_pair")
        off4, b4 = fields4[:log2W], fields4[log2W:]
        mask = Signal(INDEX_BITS)
        m.d.comb += mask.eq(~(C((1 << INDEX_BITS) - 1, INDEX_BITS) << b4)[:INDEX_BITS])
        with m.If(self.en):
            m.d.sync += self.index.eq((Cat(lo, hi) >> off4)[:INDEX_BITS] & mask)
        return m
