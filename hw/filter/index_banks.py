"""IndexBanks: one index memory, banked by block parity, read by a set of texture-filter lanes in the
same cycle. Twin of :mod:`golden.index_banks` (the layout and the mapping).

The lanes are texel-fetch units built with ``index_port`` (:class:`hw.texel_fetch.TexelFetch`): each
sends its stage-3 index request (block number ``k``, width ``b``, base word ``base'``, the level's
block grid) here instead of to an index reader of its own. For each lane the *bank map* computes
``(bank, k')`` (:func:`golden.index_banks.bank_address`: the block's column and row parity, the
block's number in its bank); each bank, an :class:`hw.index_reader.IndexReader` over its image,
takes the request of the first lane that maps to it; each lane takes the index of its bank, the bank
number delayed beside the reader. In a set of two lanes (a horizontal pair) or four (a 2x2 footprint
of one level) two lanes that map to the same bank need the same block
(:mod:`golden.index_banks`), so one read serves them both: no bank conflicts, no stalls.
``conflict`` flags a cycle in which two lanes would need different blocks of one bank (it stays 0 on
every footprint; the tests drive it high with requests no footprint makes).

Latency: ``index_reader.LATENCY`` = 5 advancing cycles, as the lane's own reader (the bank map and the
crossbar are combinational in front of the readers' first register). Throughput: one request per
lane per cycle. Widths: ``k`` and ``k'`` ``k_bits``, ``base'`` ``base_bits``, the index the widest
index width present.
"""

from __future__ import annotations

from amaranth import *
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from vqtex.golden.index_banks import BankedIndex

from ..banked_rom import BANK_DEPTH
from ..pick import pick
from ..index_reader import LATENCY, IndexReader, IndexRequestLayout

__all__ = ["IndexBanks", "bank_map"]


def bank_map(m: Module, req, banks: int, twiddle: bool):
    """``(bank, k')`` of a lane's request, combinational (the twin of
    :func:`golden.index_banks.bank_address`); ``twiddle``: the set has PowerVR2 twiddled maps."""
    k, gw = req.k, req.gw
    kb = len(k)
    bx = Signal(kb)
    by = Signal(kb)
    hx = Signal(4)
    m.d.comb += [
        bx.eq(k & ~(C((1 << kb) - 1, kb) << gw)),
        by.eq(k >> gw),
        hx.eq(Mux(gw == 0, 0, gw - 1)),
    ]
    if banks == 4:
        bank = Cat(bx[0], by[0])
        kq = ((by >> 1) << hx) | (bx >> 1)
    else:
        bank = bx[0]
        kq = (by << hx) | (bx >> 1)
    if not twiddle:
        return bank, kq[:kb]
    gh = req.gh
    square = (gw != 0) & (gh != 0)
    x_strip = ~square & (gh == 0)
    if banks == 4:
        t_bank = Mux(square, Cat(k[1], k[0]), Mux(x_strip, Cat(k[0], C(0, 1)), Cat(C(0, 1), k[0])))
        t_kq = Mux(square, k >> 2, k >> 1)
    else:
        t_bank = Mux(square, k[1], Mux(x_strip, k[0], 0))
        t_kq = Mux(square, Cat(k[0], k >> 2), Mux(x_strip, k >> 1, k))
    return Mux(req.twiddled, t_bank, bank), Mux(req.twiddled, t_kq, kq)[:kb]


class IndexBanks(wiring.Component):
    """``lanes`` lanes' index requests served by ``banked.banks`` banked index readers.

    Arguments
    ---------
    banked : golden.index_banks.BankedIndex
        The banks' images and ``base'`` (``banked.banks`` 2 or 4 banks, as many as ``lanes``).
    k_bits, base_bits : int
        Widths of the lanes' block numbers and base words.
    widths : tuple of int
        Index widths present (each reader specialised to them, as a lane's own reader).
    straddle : bool
        Some index crosses a word (each reader has its odd word bank).
    twiddle : bool
        The set has PowerVR2 twiddled maps (the bank map's twiddled path).
    bank_depth : int
        Words per block RAM bank of each reader's memories.

    Members
    -------
    requests : In(ArrayLayout(IndexRequestLayout(k_bits, base_bits), lanes))
        Each lane's request (all lanes advance together: lane 0's ``en`` moves every reader).
    index : Out(ArrayLayout(max(widths), lanes))
        Each lane's index, ``LATENCY`` advancing cycles after its request.
    conflict : Out(1)
        Combinational: in an advancing cycle, two valid lanes map to one bank with different blocks.
    """

    def __init__(self, banked: BankedIndex, *, k_bits: int, base_bits: int, widths: tuple, straddle: bool,
                 twiddle: bool = False, bank_depth: int = BANK_DEPTH):
        if banked.banks not in (2, 4):
            raise ValueError(f"IndexBanks serves 2 or 4 banks, not {banked.banks}")
        self._banked = banked
        self._k_bits = k_bits
        self._base_bits = base_bits
        self._widths = tuple(widths)
        self._straddle = bool(straddle)
        self._twiddle = bool(twiddle)
        self._bank_depth = bank_depth
        lanes = banked.banks
        super().__init__({
            "requests": In(data.ArrayLayout(IndexRequestLayout(k_bits, base_bits), lanes)),
            "index": Out(data.ArrayLayout(max(self._widths), lanes)),
            "conflict": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        banks = self._banked.banks
        lanes = banks
        reqs = [self.requests[n] for n in range(lanes)]
        en = reqs[0].en
        maps = [bank_map(m, r, banks, self._twiddle) for r in reqs]
        bank = [Signal(range(banks), name=f"bank_lane{n}") for n in range(lanes)]
        kq = [Signal(self._k_bits, name=f"kq_lane{n}") for n in range(lanes)]
        for n, (b, q) in enumerate(maps):
            m.d.comb += [bank[n].eq(b), kq[n].eq(q)]

        readers = []
        for p in range(banks):
            r = IndexReader(self._banked.words[p], word_bits=self._banked.word_bits, k_bits=self._k_bits,
                            base_bits=self._base_bits, bank_depth=self._bank_depth, widths=self._widths,
                            straddle=self._straddle)
            m.submodules[f"bank{p}"] = r
            readers.append(r)
            # the first lane that maps to bank p (any of them: they need the same block)
            hit = [reqs[n].valid & (bank[n] == p) for n in range(lanes)]
            sel_k, sel_b, sel_base = C(0, self._k_bits), C(0, 5), C(0, self._base_bits)
            for n in reversed(range(lanes)):
                sel_k = Mux(hit[n], kq[n], sel_k)
                sel_b = Mux(hit[n], reqs[n].b, sel_b)
                sel_base = Mux(hit[n], reqs[n].base, sel_base)
            m.d.comb += [
                r.valid.eq(Cat(*hit).any()), r.k.eq(sel_k), r.b.eq(sel_b), r.base.eq(sel_base), r.en.eq(en),
            ]

        # each lane's bank number, delayed beside the readers (their LATENCY stages move on ``en``)
        for n in range(lanes):
            delayed = bank[n]
            for s in range(LATENCY):
                reg = Signal(range(banks), name=f"bank_lane{n}_stage{s + 1}")
                with m.If(en):
                    m.d.sync += reg.eq(delayed)
                delayed = reg
            m.d.comb += self.index[n].eq(pick([r.index for r in readers], delayed))

        clash = []
        for a in range(lanes):
            for b in range(a + 1, lanes):
                clash.append(reqs[a].valid & reqs[b].valid & (bank[a] == bank[b])
                             & ((kq[a] != kq[b]) | (reqs[a].base != reqs[b].base)))
        m.d.comb += self.conflict.eq(en & Cat(*clash).any())
        return m
