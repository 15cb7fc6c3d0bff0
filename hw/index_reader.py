"""Packed index reader: block number -> the block's b-bit index from the packed index map.

Twin of :func:`golden.fetch.read_index`. The bit address ``k * b`` splits into the word
``w = base + (k*b >> log2 W)`` and the bit offset ``off = k*b & (W - 1)``; the index is
``({word[w+1], word[w]} >> off) & (2**b - 1)``. An index *straddles* when ``off + b > W``.

The index memory is split into an EVEN bank (words 0, 2, 4, ...) and an ODD bank (words 1, 3, ...):
words ``w`` and ``w + 1`` always live in different banks, so both arrive in the same cycle and a
straddling index costs nothing (the paper's "specialized addressing logic"). With ``one_port`` the
memory is a single bank and a straddling index takes one extra cycle. Either memory is a
:class:`hw.banked_rom.BankedROM` (512-word block RAM banks, each read registered).

Specialised to the index widths ``widths`` a set holds (:class:`hw.features.Features`): ``k * b``
is shifts and adds for one to three widths (a multiplier for more), the index is as wide as the
widest, the mask exists only for several widths, the extract selects among the bit offsets an
index can start at (multiples of the greatest power of two dividing every width), and with
``straddle=False`` (no index crosses a word) the memory is one bank read at ``w`` and the pair is
one word. The latency stays 5: a stage with less to do is still a register.
"""

from __future__ import annotations

import numpy as np
from amaranth import *
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from vqtex.golden.geometry import index_lanes
from vqtex.golden.register_map import REGIONS

from .banked_rom import BANK_DEPTH, BankedROM
from .bus_port import DATA_WIDTH, LoadTarget, or_all
from .registers import enabled_register

__all__ = ["IndexReader", "IndexRequestLayout", "INDEX_BITS", "LATENCY"]

#: Width of an index (b is 1..16).
INDEX_BITS = 16
#: Cycles from the block number to the index.
LATENCY = 5


class IndexRequestLayout(data.StructLayout):
    """What a unit whose index reader is outside it (``TexelFetch(index_port=True)``, the lanes of
    :class:`hw.filter.texture_filter.TextureFilter`) asks of the reader each cycle: the reader's
    inputs (``valid``, ``k``, ``b``, ``base``, ``en``, as for :class:`IndexReader`) and the level's
    block grid, ``gw = log2w - log2bw``, ``gh = log2h - log2bh`` (``gh`` only for twiddled levels,
    else 0) and ``twiddled``, which a reader banked by block parity needs
    (:func:`golden.index_banks.bank_address`). The index comes back ``LATENCY`` advancing cycles later."""

    def __init__(self, k_bits: int, base_bits: int):
        super().__init__({
            "valid": 1, "k": k_bits, "b": 5, "base": base_bits, "en": 1,
            "gw": 4, "gh": 4, "twiddled": 1,
        })


#: The loadable reader's stage 4 shifts the word pair by whole ``2**COARSE_SHIFT``-bit steps of the
#: index's offset, stage 5 by the rest (``_elaborate_specialised``).
COARSE_SHIFT = 3


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
    widths : sequence of int, optional
        The index widths ``b`` the reader must serve (default: every width 1..16, the full reader:
        a multiplier, a 16-bit index, the mask and a bit-granular shift). Given, the reader is
        specialised to them (``b`` is ignored when there is one).
    straddle : bool
        Some index can cross a word boundary (default). False: one bank, no word pair, ``hold`` and
        ``straddle`` constant 0.
    add_bits : int
        0 (default), or the width of an input ``add`` that the extract stage adds to the index
        before its register (``index`` is then ``index + add``, ``max(index bits, add_bits) + 1``
        wide): the loadable unit adds the codebook base of the item in the extract stage here, so
        that the register drives the codebook's block RAM addresses with no adder behind it.

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
    index : Out(index_bits)
        The index, registered (latency 5): 16 bits, or the widest of ``widths`` (with ``add_bits``:
        the index plus ``add``, one bit wider than the wider of the two).
    add : In(add_bits)
        Only with ``add_bits``: added to the index in the extract stage (the value for the item
        entering that stage, i.e. moving in the same cycle as stage 4's register).
    en_data : In(data_copies)
        Only with ``data_copies`` ``n`` > 0: copies of ``en`` (the loadable front end gives copies of
        ``advance``, equal to ``en`` but in a reset's first cycle, when every stage is empty), the
        enables of the index memories' data registers (:class:`hw.banked_rom.BankedROM`
        ``data_copies``; two banks: half each), so that ``en`` is not the clock enable of them all
        (1,241 loads on ``max``, docs/area.md "The paths between blocks").

    Raises
    ------
    ValueError
        If ``word_bits`` is not 16, 32 or 64, or a width is outside 1..16.
    """

    def __init__(self, words=(), *, word_bits: int, k_bits: int, base_bits: int, one_port: bool = False,
                 bank_depth: int = BANK_DEPTH, widths=None, straddle: bool = True, depth: int | None = None,
                 load=None, add_bits: int = 0, data_copies: int = 0):
        if word_bits not in (16, 32, 64):
            raise ValueError(f"index word width {word_bits} is not 16, 32 or 64")
        if widths is not None:
            widths = tuple(sorted({int(b) for b in widths}))
            if not widths or widths[0] < 1 or widths[-1] > INDEX_BITS:
                raise ValueError(f"index widths {widths} must be in 1..{INDEX_BITS}")
        self._words = [int(w) for w in np.asarray(words).astype(np.uint64).tolist()] or [0]
        self._depth = max(1, len(self._words) if depth is None else int(depth))
        self._load = load
        self._word_bits = word_bits
        self._k_bits = k_bits
        self._one_port = bool(one_port)
        self._bank_depth = bank_depth
        self._widths = widths
        self._straddle = bool(straddle)
        self._add_bits = int(add_bits)
        self._data_copies = int(data_copies)
        self._copies_used = 0
        index_bits = INDEX_BITS if widths is None else widths[-1]
        super().__init__({
            "valid": In(1),
            "k": In(k_bits),
            "b": In(5),
            "base": In(base_bits),
            "en": In(1),
            "straddle": Out(1),
            "hold": Out(1),
            "index": Out(max(index_bits, self._add_bits) + 1 if self._add_bits else index_bits),
            **({"add": In(self._add_bits)} if self._add_bits else {}),
            **({} if load is None else {"load": In(load), "load_data": Out(DATA_WIDTH)}),
            **({"en_data": In(self._data_copies)} if self._data_copies else {}),
        })

    @property
    def latency(self) -> int:
        return LATENCY

    @property
    def one_port(self) -> bool:
        return self._one_port

    @property
    def specialised(self) -> bool:
        return self._widths is not None

    def elaborate(self, platform):
        self._answers = []                  # the loadable memories' read answers (``_memory``)
        m = self._elaborate_specialised() if self._widths is not None else self._elaborate_full()
        if self._load is not None:
            m.d.comb += self.load_data.eq(or_all(self._answers))
        return m

    def _elaborate_full(self):
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

        lo, hi, fields3 = self._read_words(m, w, Cat(off, b1), straddle=True,
                                           w_next=self._next_word(m, self.en & ~self.hold, bit >> log2W, len(w)))

        # Stage 5: {hi, lo} >> off, masked to b bits.
        fields4 = enabled_register(m, self.en, fields3, "fields_pair")
        off4, b4 = fields4[:log2W], fields4[log2W:]
        mask = Signal(INDEX_BITS)
        m.d.comb += mask.eq(~(C((1 << INDEX_BITS) - 1, INDEX_BITS) << b4)[:INDEX_BITS])
        with m.If(self.en):
            m.d.sync += self.index.eq(self._added((Cat(lo, hi) >> off4)[:INDEX_BITS] & mask))
        return m

    def _added(self, index):
        """The value the extract stage registers: the index, plus ``add`` with ``add_bits``."""
        return index + self.add if self._add_bits else index

    def _memory(self, m, name: str, stride: int = 1, phase: int = 0) -> BankedROM:
        """The index memory, or its even (``phase`` 0) or odd bank (``stride`` 2), as submodule
        ``name``: a ROM of the words, or loadable (region ``index``) with ``load``."""
        words = self._words[phase::stride] or [0]
        depth = None if self._depth == len(self._words) and self._load is None else \
            max(1, (self._depth - phase + stride - 1) // stride)
        target = None if self._load is None else LoadTarget(
            self._load, REGIONS["index"], lanes=index_lanes(self._word_bits), stride=stride, phase=phase)
        n = self._data_copies
        share = (n if stride == 1 else (n + 1 - phase) // 2) if n else 0     # two banks: half each
        copies = {"data_copies": share} if share else {}
        m.submodules[name] = mem = BankedROM(words, width=self._word_bits,
                                             bank_depth=self._bank_depth, depth=depth, load=target, **copies)
        if share:
            first = 0 if stride == 1 else phase * ((n + 1) // 2)
            m.d.comb += mem.en_data.eq(self.en_data[first:first + share])
        if target is not None:
            m.d.comb += mem.load.eq(self.load)
            self._answers.append(mem.load_data)
        return mem

    def _next_word(self, m, en, words, width: int):
        """``w + 1`` (``w = base + words``) for the even bank's address, as one sum: the loadable
        reader registers ``base + 1`` in stage 1 beside ``base`` (enable ``en``), so that stage 2
        has one carry chain in front of the block RAMs' address, not ``w`` and then ``w + 1`` (the
        index reader's own critical path out of context at ``max``, docs/area.md "Block by block").
        None for a baked reader (its RTLIL as before)."""
        if self._load is None:
            return None
        base_next = Signal(len(self.base) + 1, name="base_next")
        with m.If(en):
            m.d.sync += base_next.eq(self.base + 1)
        w_next = Signal(width + 1, name="w_next")           # as wide as w + 1
        m.d.comb += w_next.eq(base_next + words)
        return w_next

    def _read_words(self, m, w, carried, *, straddle: bool, w_next=None, pre=None):
        """Stages 2-4, the memory organisation both readers share: the read of word ``w`` (and
        ``w + 1`` with ``straddle``), and ``carried`` (the fields stage 5 needs) registered twice
        beside it. Returns ``(lo, hi, fields)``: ``lo`` = word[w] and ``hi`` = word[w + 1]
        registered in stage 4 (``hi`` a 0-bit constant without ``straddle``), ``fields`` the carried
        value after stage 3. Two banks (even and odd words, read together); with ``one_port`` one
        bank read twice for a straddling index (``hold`` high for the first); without ``straddle``
        one bank, one word. ``w_next``, when given, is ``w + 1`` (:meth:`_next_word`).
        ``pre``, with two banks: stage 4 registers ``pre(word pair, fields)`` as ``lo`` instead
        (``hi`` then a 0-bit constant), the pair ``Cat(word[w], word[w + 1])`` and ``fields`` the
        carried value in stage 4."""
        W = self._word_bits

        def reg(value, name):
            return enabled_register(m, self.en, value, name)

        lo = Signal(W, name="lo")                       # stage 4: word[w]
        if not straddle:                                # no index crosses a word: one bank, one word
            mem = self._memory(m, "memory")
            m.d.comb += [mem.addr.eq(w), mem.en.eq(self.en)]
            fields3 = reg(reg(carried, "fields_word"), "fields_data")
            with m.If(self.en):
                m.d.sync += lo.eq(mem.word)
            return lo, C(0, 0), fields3
        hi = Signal(W, name="hi")                       # stage 4: word[w + 1]
        if not self._one_port:
            even = self._memory(m, "even_bank", 2, 0)
            odd = self._memory(m, "odd_bank", 2, 1)
            m.d.comb += [
                even.addr.eq((w + 1 if w_next is None else w_next) >> 1), even.en.eq(self.en),
                odd.addr.eq(w >> 1), odd.en.eq(self.en),
            ]
            fields3 = reg(reg(Cat(carried, w[0]), "fields_word"), "fields_data")
            parity = fields3[-1]
            # Stage 4: word[w] is in the odd bank when w is odd.
            if pre is not None:
                pair = pre(Cat(Mux(parity, odd.word, even.word), Mux(parity, even.word, odd.word)), fields3[:-1])
                lo = Signal(len(pair), name="pair")
                with m.If(self.en):
                    m.d.sync += lo.eq(pair)
                return lo, C(0, 0), fields3[:-1]
            with m.If(self.en):
                m.d.sync += [
                    lo.eq(Mux(parity, odd.word, even.word)),
                    hi.eq(Mux(parity, even.word, odd.word)),
                ]
        else:
            mem = self._memory(m, "memory")
            second = Signal()               # stage 1 is on the second read of a straddling index
            m.d.comb += [
                self.hold.eq(self.straddle & ~second),
                mem.addr.eq(w + second),
                mem.en.eq(self.en),
            ]
            with m.If(self.en):
                m.d.sync += second.eq(self.hold)
            fields3 = reg(reg(Cat(carried, self.straddle), "fields_word"), "fields_data")
            straddled = fields3[-1]
            # Stage 4: the first read (word w) went down the pipeline one item ahead, as the bubble;
            # ``hi`` still holds it when the straddler's second read (word w + 1) arrives.
            with m.If(self.en):
                m.d.sync += [hi.eq(mem.word), lo.eq(Mux(straddled, hi, mem.word))]
        return lo, hi, fields3[:-1]

    def _elaborate_specialised(self):
        """The reader for the widths ``self._widths`` (see the class docstring): the same five
        registers, the same memory organisation when indices straddle (even/odd banks, or one
        bank and ``hold`` with ``one_port``), one bank when none does."""
        m = Module()
        W = self._word_bits
        log2W = W.bit_length() - 1
        widths = self._widths
        ib = widths[-1]                                 # index bits: the widest present
        several = len(widths) > 1
        g = 0
        for b in widths:
            g = np.gcd(g, b)
        unit = int(g & -g)                              # every index starts at a multiple of this
        log2u = unit.bit_length() - 1
        straddle = self._straddle

        # Stage 1: the bit address k*b: for each width, shifts and adds of k (a width's set bits),
        # selected by b; a multiplier beyond three widths.
        def times(b):
            terms = [self.k << n for n in range(5) if b >> n & 1]
            out = terms[0]
            for t in terms[1:]:
                out = out + t
            return out

        bit = Signal(self._k_bits + ib.bit_length(), name="bit")
        bw_bits = len(self.b) if several else 0
        fields1 = Signal(len(self.base) + bw_bits + 1, name="fields_bit")
        base1, b1, valid1 = fields1[:len(self.base)], fields1[len(self.base):-1], fields1[-1]
        with m.If(self.en & ~self.hold):
            m.d.sync += fields1.eq(Cat(self.base, self.b if several else C(0, 0), self.valid))
            if len(widths) > 3:
                m.d.sync += bit.eq(self.k * self.b)
            elif several:
                with m.Switch(self.b):
                    for b in widths[:-1]:
                        with m.Case(b):
                            m.d.sync += bit.eq(times(b))
                    with m.Default():
                        m.d.sync += bit.eq(times(widths[-1]))
            else:
                m.d.sync += bit.eq(times(widths[0]))
        b1 = b1 if several else C(widths[0], 5)

        # Stage 2: word and offset (in units); the memory read.
        w = Signal(max(len(self.base), len(bit) - log2W) + 1)
        off = Signal(max(1, log2W - log2u))               # the offset in units of ``unit`` bits
        m.d.comb += [w.eq(base1 + (bit >> log2W)), off.eq(bit[log2u:log2W])]
        if straddle:
            m.d.comb += self.straddle.eq(valid1 & ((off << log2u) + b1 > W))

        # The loadable reader with two banks: the shift by whole units split over stages 4 and 5,
        # by whole bytes (``COARSE_SHIFT``) beside the bank select, within the byte in stage 5 (max's
        # 32-position shift, mask and ``+ cb_base`` in one cycle: docs/area.md "Block by block").
        F = COARSE_SHIFT
        coarse = self._load is not None and straddle and not self._one_port and W > unit and log2u < F
        keep = ib + (1 << F) - 1                       # what stage 5 can still need of the pair

        def pre(pair, fields):
            at = Cat(C(0, log2u), fields[:len(off)])
            pair = Cat(pair, C(0, max(0, W + keep - len(pair))))
            return (pair >> Cat(C(0, F), at[F:]))[:keep]

        lo, hi, fields3 = self._read_words(m, w, Cat(off, b1[:bw_bits]), straddle=straddle,
                                           w_next=self._next_word(m, self.en & ~self.hold, bit >> log2W, len(w)),
                                           pre=pre if coarse else None)

        # Stage 5: the index at offset ``off`` units of the word (pair): a right shift by whole units
        # (``off`` with log2(unit) zeros below it), masked to b bits when there are several widths.
        # The fabric builds the same 2:1 multiplexers as a tree of selects (the zero low bits of the
        # amount need none); a simulator shifts once where it branched on ``off`` (random per
        # texel: Verilator's model 5 ns a cycle faster, docs/simulation.md).
        fields4 = enabled_register(m, self.en, fields3, "fields_pair")
        off4, b4 = fields4[:len(off)], fields4[len(off):]
        data = Cat(lo, hi)
        pad = max(0, W - unit + ib - len(data))      # past the word (pair) the index reads zeros
        data = Cat(data, C(0, pad)) if pad else data
        if coarse:                                      # the pair already shifted by whole bytes
            value = (data >> Cat(C(0, log2u), off4)[:F])[:ib]
        else:
            value = (data >> Cat(C(0, log2u), off4))[:ib] if W > unit else data[:ib]
        if several:
            mask = Signal(ib)
            m.d.comb += mask.eq(~(C((1 << ib) - 1, ib) << b4)[:ib])
            value = value & mask
        with m.If(self.en):
            m.d.sync += self.index.eq(self._added(value))
        return m
