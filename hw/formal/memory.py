"""Proofs about the cache block of the cached unit (:class:`hw.memory.reader.CachedReader`): a word
the reader hands to the texel pipeline is the word the memory holds at the request's address, and
no line is read from memory twice while its burst is in flight.

Everything is stated at the reader's ports (the request stream ``i``, the word stream ``o``, the
AXI4 AR and R channels), none of it on the caches' internal state, so the property does not depend
on how the tags, valid bits and ages are held (flip-flops or LUT RAM).

**The memory** is an abstract AXI4 read slave written in the harness, constrained by ``Assume``
only where the property needs it:

* ``arready`` is free in every cycle (the slave may stall the master on AR as it likes), except that
  the slave takes no more than :data:`OUTSTANDING` bursts at a time (its own queue: the bursts it has
  accepted and not answered, in order);
* R answers the oldest accepted burst, ``arlen + 1`` beats, ``rlast`` on the last, ``rvalid`` free in
  every cycle (any gap between beats, any latency), ``rresp`` OKAY;
* ``rdata`` is free in every beat, with one constraint: the solver picks, once and for all, one
  bus-word address ``A`` and one value ``V`` (``AnyConst``), and every beat that carries bus word
  ``A`` carries ``V``. Nothing else is assumed of the memory: the other addresses may even answer
  differently from one burst to the next.

The claim is then about ``A``: whenever the reader offers a word on ``o`` whose address lies in bus
word ``A``, the word is the lane of ``V`` at that address. Because ``A`` and ``V`` are free, this is
the claim for every address and every content: a reader that served a word from another line,
another lane, a stale line (replaced, or not yet filled) or a burst it mixed up would be caught with
the address it got wrong as ``A``. (This is the usual way of proving a cache with a free memory:
one watched address stands for all of them.)

**Which request a response answers**: the harness drives the request's tag with the request itself
(``raw``, ``word``, ``straddle``), so every response names the address its words must come from.
That is the reader's own tag path, which the texel pipeline relies on; the order of the responses
is the texel-fetch unit's order proof (and the cached unit's cycle-for-cycle tests against the golden
model), not this one.

Requests are free in every cycle (any word of the index map or of the raw memory, straddling or not,
valid or not, held or not) and so is the output's ``ready``: the claims hold under every request
stream and every backpressure. The only assumption on the requests is the address range the
harness's memory serves: index words (and ``w + 1`` of a straddling one) below :data:`INDEX_WORDS`,
raw words below :data:`RAW_WORDS` (more lines than the caches hold; the index map lies below the raw
memory at :data:`RAW_BASE`).

Claims:

* ``o`` (index): ``word0`` is the memory's word ``w``, and ``word1`` the word ``w + 1`` when the
  request straddles; ``o`` (raw): ``word0`` is the raw word; ``o.raw`` is the request's;
* AR: a burst is never issued for a line whose earlier burst is still in flight (nothing is read
  twice while it is in flight: the references that wait on a line all wait for its one fill, the
  prefetching cache's rule); every burst is INCR of the bus width, line-aligned and inside 4 KB, and
  AR keeps its address and length until ``arready`` (the AXI rule).

Method: bounded (BMC). k-induction would need invariants on the caches' internal state (a line's
RAM rows hold the memory's words once its filled bit is set, the burst queue matches the slots
waiting for it, the counts of waiting references match the FIFO), which would name the internal
signals the property is written to avoid. The depth of each property is chosen from the covers:
within it a line is replaced, read again and one of its words served from the second fill, and a
straddling index is served from two lines (docs/verification.md has the steps and times).
"""

from __future__ import annotations

from amaranth import *
from amaranth.asserts import AnyConst, AnySeq

from ...golden.memory.cache import CacheShape
from ...golden.memory.system import MemoryConfig
from ..memory.axi import INCR
from ..memory.reader import CachedReader
from .harness import Harness, SeededBug

__all__ = ["ReaderHarness", "reader_config", "INDEX_WORDS", "RAW_WORDS", "OUTSTANDING", "RAW_BASE",
           "DATA_READ_EARLY", "wrong_lane"]

#: Index words and raw words the requests may name: more lines than either cache holds (so lines are
#: replaced), few enough to keep the state small.
INDEX_WORDS = 16
RAW_WORDS = 4
#: The raw memory's byte address (4 KB aligned, as ``golden.memory.system.Layout`` places it).
RAW_BASE = 4096
#: Bursts the abstract slave holds at a time (accepted on AR, not fully answered on R).
OUTSTANDING = 2
ADDR_WIDTH = 13


def reader_config(prefetch: int) -> MemoryConfig:
    """The small reader of the proofs: a 32-bit bus; an index cache of 2 sets x 2 ways of 4-byte
    lines (one beat each), a raw cache of one 4-byte line; a reference FIFO of ``prefetch`` entries
    (1: the blocking cache)."""
    return MemoryConfig(index_cache=CacheShape(16, 4, 2), raw_cache=CacheShape(4, 4, 1), prefetch=prefetch,
                        bus_bytes=4)


class ReaderHarness(Harness):
    """A word on ``o`` is the memory's word at its request's address (see the module docstring).

    Arguments
    ---------
    prefetch : int
        The reference FIFO's depth (1: blocking).
    word_bits : int
        The index memory's word (16 or 32: two or four words in a bus word, so the lane select is
        in the proof).
    bug : SeededBug, optional
    """

    def __init__(self, prefetch: int, word_bits: int, bug: SeededBug | None = None):
        super().__init__(bug)
        self._prefetch = prefetch
        self._word_bits = word_bits

    def build(self, m, platform):
        cfg = reader_config(self._prefetch)
        bus = cfg.bus_bytes
        bus_log = bus.bit_length() - 1
        wb = self._word_bits // 8
        word_addr_bits = max(INDEX_WORDS, RAW_WORDS).bit_length()
        tag_width = 2 + word_addr_bits
        dut = CachedReader(cfg, word_bits=self._word_bits, raw_base=RAW_BASE, word_addr_bits=word_addr_bits,
                           tag_width=tag_width, addr_width=ADDR_WIDTH)
        self.design(m, "dut", dut, platform)
        axi = dut.axi

        # -- requests: free, in range; the tag is the request itself ---------------------------------
        raw, word, straddle = AnySeq(1), AnySeq(word_addr_bits), AnySeq(1)
        m.d.comb += [dut.i.valid.eq(AnySeq(1)), dut.i.p.raw.eq(raw), dut.i.p.word.eq(word),
                     dut.i.p.straddle.eq(straddle), dut.i.p.tag.eq(Cat(raw, straddle, word)),
                     dut.o.ready.eq(AnySeq(1))]
        self.assume(m, Mux(raw, word < RAW_WORDS, word + straddle < INDEX_WORDS))

        # -- the abstract slave: its queue of accepted bursts, in order ----------------------------------
        wa = AnyConst(ADDR_WIDTH - bus_log)                 # the watched bus word
        wv = AnyConst(8 * bus)                              # what it holds
        q_addr = [Signal(ADDR_WIDTH - bus_log, name=f"slave_addr{n}") for n in range(OUTSTANDING)]
        q_len = [Signal(8, name=f"slave_len{n}") for n in range(OUTSTANDING)]
        q_valid = [Signal(name=f"slave_valid{n}") for n in range(OUTSTANDING)]
        beat = Signal(8)
        ar_go = Signal()
        r_go = Signal()
        r_last = Signal()
        full = Signal()
        m.d.comb += [full.eq(Cat(*q_valid).all()),
                     axi.arready.eq(AnySeq(1) & ~full),
                     ar_go.eq(axi.arvalid & axi.arready),
                     axi.rvalid.eq(AnySeq(1) & q_valid[0]),
                     r_go.eq(axi.rvalid),                   # the master's rready is its own claim below
                     r_last.eq(beat == q_len[0]),
                     axi.rlast.eq(r_last), axi.rresp.eq(0),
                     axi.rdata.eq(AnySeq(8 * bus))]
        with m.If(axi.rvalid & (q_addr[0] + beat == wa)):
            self.assume(m, axi.rdata == wv)
        # the queue: the head leaves after its last beat, a new burst enters at the first free place
        after = [Signal.like(q_valid[n], name=f"slave_valid_after{n}") for n in range(OUTSTANDING)]
        a_after = [Signal.like(q_addr[n], name=f"slave_addr_after{n}") for n in range(OUTSTANDING)]
        l_after = [Signal.like(q_len[n], name=f"slave_len_after{n}") for n in range(OUTSTANDING)]
        pop = r_go & r_last
        for n in range(OUTSTANDING):
            nxt = n + 1
            m.d.comb += [after[n].eq(Mux(pop, q_valid[nxt] if nxt < OUTSTANDING else 0, q_valid[n])),
                         a_after[n].eq(Mux(pop, q_addr[nxt] if nxt < OUTSTANDING else 0, q_addr[n])),
                         l_after[n].eq(Mux(pop, q_len[nxt] if nxt < OUTSTANDING else 0, q_len[n]))]
        placed = C(0, 1)
        for n in range(OUTSTANDING):
            here = ar_go & ~after[n] & ~placed
            m.d.sync += [q_valid[n].eq(after[n] | here),
                         q_addr[n].eq(Mux(here, axi.araddr >> bus_log, a_after[n])),
                         q_len[n].eq(Mux(here, axi.arlen, l_after[n]))]
            placed = placed | ~after[n]
        with m.If(r_go):
            m.d.sync += beat.eq(Mux(r_last, 0, beat + 1))

        # -- claims: the words on o -----------------------------------------------------------------------
        o_raw, o_straddle, o_word = dut.o.p.tag[0], dut.o.p.tag[1], dut.o.p.tag[2:]
        lanes = bus // wb
        with m.If(dut.o.valid):
            self.claim(m, dut.o.p.raw == o_raw, "o: raw is the request's")
            with m.If(o_raw):
                addr = Signal(ADDR_WIDTH, name="o_raw_addr")
                m.d.comb += addr.eq(RAW_BASE + o_word * 4)
                with m.If((addr >> bus_log) == wa):
                    lane = addr[2:bus_log] if bus > 4 else C(0, 1)
                    self.claim(m, dut.o.p.word0[:32] == wv.word_select(lane, 32),
                               "o: a raw word is the memory's word at its address")
            with m.Else():
                for k, (port, name) in enumerate(((dut.o.p.word0, "word0"), (dut.o.p.word1, "word1"))):
                    addr = Signal(ADDR_WIDTH, name=f"o_index_addr{k}")
                    m.d.comb += addr.eq((o_word + k) * wb)
                    lane = addr[wb.bit_length() - 1:bus_log] if lanes > 1 else C(0, 1)
                    with m.If(((addr >> bus_log) == wa) & ((k == 0) | o_straddle)):
                        self.claim(m, port[:self._word_bits] == wv.word_select(lane, self._word_bits),
                                   f"o: {name} is the memory's index word {'w' if k == 0 else 'w + 1'}")

        # -- claims: AR --------------------------------------------------------------------------------
        line_of = Signal(ADDR_WIDTH - bus_log, name="ar_bus_word")
        m.d.comb += line_of.eq(axi.araddr >> bus_log)
        with m.If(ar_go):
            for n in range(OUTSTANDING):
                # the slave's queue holds exactly the bursts in flight (accepted, last beat not yet given)
                self.claim(m, ~q_valid[n] | (q_addr[n] != line_of) | (pop & (n == 0)),
                           "AR: no burst for a line whose burst is in flight")
        with m.If(axi.arvalid):
            self.claim(m, axi.arburst == INCR, "AR: INCR bursts")
            self.claim(m, axi.arsize == bus_log, "AR: beats of the bus width")
            self.claim(m, (axi.araddr & ((axi.arlen + 1) * bus - 1)) == 0, "AR: a burst starts on its line")
            self.claim(m, (axi.araddr >> 12) == ((axi.araddr + (axi.arlen + 1) * bus - 1) >> 12),
                       "AR: a burst stays inside 4 KB")
        self.claim(m, axi.rready, "R: rready high (a burst's room is reserved when it is issued)")
        held = Signal(name="ar_stalled")
        held_addr = Signal.like(axi.araddr, name="ar_held_addr")
        held_len = Signal.like(axi.arlen, name="ar_held_len")
        m.d.sync += [held.eq(axi.arvalid & ~axi.arready), held_addr.eq(axi.araddr), held_len.eq(axi.arlen)]
        with m.If(held):
            self.claim(m, axi.arvalid & (axi.araddr == held_addr) & (axi.arlen == held_len),
                       "AR: valid, address and length held until arready")

        # -- covers: a word of a line read twice (replaced, then read again), a straddle across lines ----
        refetched = Signal(2, name="cover_reads_of_watched_line")
        with m.If(ar_go & (line_of == wa) & (refetched != 3)):
            m.d.sync += refetched.eq(refetched + 1)
        a0 = Signal(ADDR_WIDTH - bus_log, name="cover_o_bus_word0")
        a1 = Signal(ADDR_WIDTH - bus_log, name="cover_o_bus_word1")
        m.d.comb += [a0.eq((o_word * wb) >> bus_log), a1.eq(((o_word + 1) * wb) >> bus_log)]
        self.cover(m, dut.o.valid & ~o_raw & (a0 == wa) & (refetched == 2))
        self.cover(m, dut.o.valid & ~o_raw & o_straddle & (a1 == wa) & (a1 != a0))


def _data_read_early(s):
    """The data read does not wait for its line: ``pop`` whenever the FIFO holds a reference and
    the output register is free."""
    return [("comb", s("pop").eq((s("level") != 0) & s("o_free")))]


#: Negative control: the FIFO's head is read before its line is filled (a stale or empty line served).
DATA_READ_EARLY = SeededBug("data_read_early", "the data read does not wait for its line's fill", (),
                            _data_read_early)


def wrong_lane(bus: int, word_bits: int) -> SeededBug:
    """Negative control: the tag check stores, for an index word, the neighbouring lane of its bus
    word (``off0`` with its low bit flipped), so ``word0`` is another word of the same line."""
    def assign(s):
        # the FIFO entry's lane, as the lookup registered it, with its low bit flipped (index words)
        lane = s("lookup_off0")
        return [("comb", s("new_off0").eq(Mux(s("new_raw"), lane, lane ^ 1)))]
    return SeededBug("wrong_lane", "word0 taken from the neighbouring lane of its bus word", (), assign)
