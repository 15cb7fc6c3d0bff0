"""CachedReader: a request's index words or raw word, read through two caches and an AXI4 master.

The cache block of the cached unit (docs/memory.md), without the address stages in front of it and
the texel pipeline behind it::

    i (raw, word, straddle, tag) -> tag check -> reference FIFO (Q) -> data read -> o (words, tag)
                                       | AR (one burst per miss)          ^
                                       v                                  | R (line fills)
                                     AXI4 read master  <----------------  memory

Timing (cycle for cycle :mod:`golden.memory.timing` with ``address_stages=0`` and a stream sink as
consumer; with every reference a hit: one request per cycle, 2 cycles from ``i`` to ``o``):

* **Tag check** (the cycle ``i`` transfers): the request's references are looked up (an index
  request reads word ``w``, and ``w + 1`` when ``straddle``, a second lookup when it lies in the next
  line; a raw request one raw word). A miss allocates the LRU way at once (an empty way first) and
  queues its burst; the reference enters the FIFO. ``i.ready`` is low while the FIFO is full (and not
  read this cycle), while the second of two bursts of the previous request waits, or while a miss's
  victim line still has a reference in the FIFO.
* **AR**: the j-th burst of a request checked in cycle ``g`` is on AR in cycle ``g + 1 + j`` (when
  ``arready`` is high, as the golden memory assumes; otherwise it waits and holds the tag check).
  INCR, ``line / bus`` beats, ``araddr`` the line's byte address, never crossing 4 KB.
* **R**: beats fill lines in burst order (``rready`` is always high); a line is readable the cycle
  after its last beat.
* **Data read**: the FIFO's head is read when its lines are filled and ``o`` is empty or transferring;
  ``o`` shows it the next cycle and holds it until ``o.ready``.

Responses leave in request order, none lost or duplicated; a line is read from memory once while it
stays in the cache, however many references wait on it; a line is not replaced while a reference to
it waits.

Every cache field (tags, valid, LRU ages, filled bits, counts of waiting references) is a flip-flop:
fine for the small caches of simulation, where a synthesised cache would keep tags in LUT RAM (not
built yet).

Arguments
---------
config : golden.memory.system.MemoryConfig
    Cache shapes, FIFO depth (``prefetch``; 1 is blocking), bus width.
word_bits : int
    Index memory word (16, 32, 64).
raw_base : int
    Byte address of raw word 0 (``golden.memory.system.Layout.raw_base``); the index memory is at 0.
word_addr_bits : int
    Width of the request's word number.
tag_width : int
    Width of the request tag carried to ``o``.
addr_width : int
    AXI address width.

Members
-------
i : In(stream.Signature(RequestLayout))
    ``raw``, ``word`` (index word number, or raw word number), ``straddle``, ``tag``.
o : Out(stream.Signature(ResponseLayout))
    ``raw``, ``word0`` (the index word, or the raw word), ``word1`` (word ``w + 1``), ``tag``.
stall_fill : Out(1)
    Strobe: a cycle in which the FIFO's head could be read but for a line not yet filled (the
    memory's share of the stalls: ``miss + bandwidth`` of the golden model).
axi : Out(hw.memory.axi.axi4_read_signature(addr_width, 8 * bus_bytes))
"""

from __future__ import annotations

from amaranth import *
from amaranth.lib import data, memory, stream, wiring
from amaranth.lib.wiring import In, Out

from .axi import INCR, axi4_read_signature

__all__ = ["CachedReader"]


def _log2(v: int) -> int:
    return v.bit_length() - 1


class _Fields:
    """A struct's fields as separate signals (attributes by field name); ``value(layout)`` is their
    concatenation in the layout's bit order."""

    def __init__(self, signals: dict):
        self.__dict__.update(signals)
        self._signals = signals

    def value(self, layout):
        parts = sorted(((f.offset, self._signals[name]) for name, f in layout), key=lambda x: x[0])
        return Cat(*(sig for _, sig in parts))


class _Cache:
    """One cache's state and its tag check: ``ports`` lookups per cycle into different sets."""

    def __init__(self, m, name, shape, ports, count_bits):
        self.shape = shape
        self.sets, self.ways = shape.sets, shape.ways
        self.set_bits = _log2(self.sets)
        self.age_bits = max(1, _log2(self.ways))
        S, W = self.sets, self.ways
        self.tag = [[Signal(32, name=f"{name}_tag_{s}_{w}") for w in range(W)] for s in range(S)]
        self.valid = [[Signal(name=f"{name}_valid_{s}_{w}") for w in range(W)] for s in range(S)]
        self.age = [[Signal(self.age_bits + 1, name=f"{name}_age_{s}_{w}") for w in range(W)] for s in range(S)]
        self.filled = [[Signal(name=f"{name}_filled_{s}_{w}") for w in range(W)] for s in range(S)]
        self.count = [[Signal(count_bits, name=f"{name}_count_{s}_{w}") for w in range(W)] for s in range(S)]
        self.name = name
        self.ports = ports

    def slot_bits(self):
        return max(1, _log2(self.sets * self.ways))

    def lookup(self, m, line, k):
        """Combinational lookup of ``line`` on port ``k``: (set, hit, way, busy victim)."""
        S, W = self.sets, self.ways
        s = Signal(max(1, self.set_bits), name=f"{self.name}_set{k}")
        t = Signal(32, name=f"{self.name}_line_tag{k}")
        m.d.comb += [s.eq(line[:self.set_bits] if self.set_bits else 0), t.eq(line >> self.set_bits)]
        hit = Signal(name=f"{self.name}_hit{k}")
        way = Signal(max(1, _log2(W)), name=f"{self.name}_way{k}")
        busy = Signal(name=f"{self.name}_busy{k}")
        ways = []
        for w in range(W):
            tw = Array(self.tag[x][w] for x in range(S))[s]
            vw = Array(self.valid[x][w] for x in range(S))[s]
            aw = Array(self.age[x][w] for x in range(S))[s]
            cw = Array(self.count[x][w] for x in range(S))[s]
            ways.append((tw, vw, aw, cw))
        hits = [vw & (tw == t) for tw, vw, aw, cw in ways]
        m.d.comb += hit.eq(Cat(*hits).any())
        # The way: the hit's; else the lowest empty way; else the oldest (age W-1).
        with m.If(hit):
            for w in reversed(range(W)):
                with m.If(hits[w]):
                    m.d.comb += way.eq(w)
        with m.Else():
            for w in reversed(range(W)):
                tw, vw, aw, cw = ways[w]
                with m.If(vw & (aw == W - 1)):
                    m.d.comb += way.eq(w)
            for w in reversed(range(W)):
                tw, vw, aw, cw = ways[w]
                with m.If(~vw):
                    m.d.comb += way.eq(w)
        vway = Array(v for _, v, _, _ in ways)[way]
        cway = Array(c for _, _, _, c in ways)[way]
        m.d.comb += busy.eq(~hit & vway & (cway != 0))
        return s, t, hit, way, busy

    def filled_at(self, slot):
        return Array(self.filled[x][w] for x in range(self.sets) for w in range(self.ways))[slot]


class CachedReader(wiring.Component):
    __doc__ = __doc__

    def __init__(self, config, *, word_bits: int = 32, raw_base: int = 0, word_addr_bits: int = 24,
                 tag_width: int = 8, addr_width: int = 32):
        if word_bits not in (16, 32, 64):
            raise ValueError(f"index word of {word_bits} bits: 16, 32 or 64")
        if config.index_cache.sets < 2:
            raise ValueError("the index cache needs at least two sets (the two lines of a straddling index)")
        if raw_base % 4096:
            raise ValueError(f"raw_base {raw_base:#x} must be 4 KB aligned")
        self._config = config
        self._word_bits = word_bits
        self._raw_base = raw_base
        self._tag_width = tag_width
        self._addr_width = addr_width
        self._bus = config.bus_bytes
        self.request_layout = data.StructLayout({
            "raw": 1, "word": word_addr_bits, "straddle": 1, "tag": tag_width})
        wide = max(word_bits, 32)
        self.response_layout = data.StructLayout({"raw": 1, "word0": wide, "word1": word_bits, "tag": tag_width})
        super().__init__({
            "i": In(stream.Signature(self.request_layout)),
            "o": Out(stream.Signature(self.response_layout)),
            "stall_fill": Out(1),
            "axi": Out(axi4_read_signature(addr_width, 8 * self._bus)),
        })

    @property
    def latency(self) -> int:
        """Cycles from ``i`` to ``o`` when every reference hits (tag check, data read): 2."""
        return 2

    def elaborate(self, platform):
        m = Module()
        cfg = self._config
        Q = cfg.prefetch
        bus = self._bus
        bus_bits = 8 * bus
        wb = self._word_bits // 8
        count_bits = max(1, Q.bit_length()) + 1
        caches = []
        for c, (name, shape) in enumerate((("index", cfg.index_cache), ("raw", cfg.raw_cache))):
            caches.append(_Cache(m, name, shape, 2 if c == 0 else 1, count_bits))
        ic, rc = caches
        beats = [ic.shape.line // bus, rc.shape.line // bus]
        req = self.i.p

        # -- the references of the request on i -----------------------------------------------------
        a0 = Signal(self._addr_width + 8)
        a1 = Signal(self._addr_width + 8)
        ra = Signal(self._addr_width + 8)
        m.d.comb += [a0.eq(req.word * wb), a1.eq((req.word + 1) * wb), ra.eq(self._raw_base + req.word * 4)]
        il, rl = _log2(ic.shape.line), _log2(rc.shape.line)
        line0, line1, rline = a0 >> il, a1 >> il, ra >> rl
        two = Signal()
        m.d.comb += two.eq(~req.raw & req.straddle & (line1 != line0))
        s0, t0, hit0, way0, busy0 = ic.lookup(m, line0, 0)
        s1, t1, hit1, way1, busy1 = ic.lookup(m, line1, 1)
        sr, tr, hitr, wayr, busyr = rc.lookup(m, rline, 0)
        miss0 = ~req.raw & ~hit0
        miss1 = two & ~hit1
        missr = req.raw & ~hitr
        busy = Mux(req.raw, busyr, busy0 | (two & busy1))

        # -- AR: two issue slots, loaded by the tag check ----------------------------------------------
        slot_v = [Signal(name=f"ar_valid{j}") for j in range(2)]
        slot_addr = [Signal(self._addr_width, name=f"ar_addr{j}") for j in range(2)]
        slot_raw = [Signal(name=f"ar_raw{j}") for j in range(2)]
        ar_go = Signal()
        m.d.comb += [
            self.axi.arvalid.eq(slot_v[0]), self.axi.araddr.eq(slot_addr[0]),
            self.axi.arlen.eq(Mux(slot_raw[0], beats[1] - 1, beats[0] - 1)),
            self.axi.arsize.eq(_log2(bus)), self.axi.arburst.eq(INCR),
            ar_go.eq(slot_v[0] & self.axi.arready),
            self.axi.rready.eq(1),
        ]

        # -- the reference FIFO (Q entries) ------------------------------------------------------------
        islot = max(1, ic.slot_bits())
        rslot = max(1, rc.slot_bits())
        entry = data.StructLayout({
            "raw": 1, "slot0": max(islot, rslot), "slot1": islot, "beat0": max(1, _log2(max(beats))),
            "beat1": max(1, _log2(max(beats))), "off0": max(1, _log2(bus // min(wb, 4)) or 1),
            "off1": max(1, _log2(bus // wb) or 1), "tag": max(1, self._tag_width)})
        fifo = [Signal(entry, name=f"ref_{q}") for q in range(Q)]
        level = Signal(range(Q + 1))
        head = Signal(range(max(Q, 2)))
        tail = Signal(range(max(Q, 2)))
        pop = Signal()
        o_free = Signal()
        m.d.comb += o_free.eq(~self.o.valid | self.o.ready)
        headv = Signal(entry)
        m.d.comb += headv.eq(Array(fifo)[head] if Q > 1 else fifo[0])
        head_filled = Mux(headv.raw, rc.filled_at(headv.slot0[:rslot]),
                          ic.filled_at(headv.slot0[:islot]) & ic.filled_at(headv.slot1))
        m.d.comb += pop.eq((level != 0) & head_filled & o_free)
        m.d.comb += self.stall_fill.eq((level != 0) & ~head_filled & o_free)

        take = Signal()
        m.d.comb += [
            self.i.ready.eq(~slot_v[1] & (~slot_v[0] | self.axi.arready) & ((level != Q) | pop) & ~busy),
            take.eq(self.i.valid & self.i.ready),
        ]
        # the entry of the request being checked
        # The entry's fields as separate signals, joined only where the FIFO stores them: one packed
        # ``new`` wire would hold both bits of ``a1`` (beat1, off1) and bits computed from them through
        # the tag check (slot1), and Verilator, which orders a wire as a whole, would see a
        # combinational cycle through it (UNOPTFLAT) where there is none.
        new = _Fields({name: Signal(f.shape, name=f"new_{name}") for name, f in entry})
        slot0 = Signal(islot)
        slot1 = Signal(islot)
        slotr = Signal(rslot)
        m.d.comb += [
            slot0.eq((s0 << _log2(ic.ways)) | way0 if ic.ways > 1 else s0),
            slot1.eq(Mux(two, (s1 << _log2(ic.ways)) | way1 if ic.ways > 1 else s1, slot0)),
            slotr.eq((sr << _log2(rc.ways)) | wayr if rc.ways > 1 else sr),
        ]
        m.d.comb += [
            new.raw.eq(req.raw),
            new.slot0.eq(Mux(req.raw, slotr, slot0)),
            new.slot1.eq(slot1),
            new.beat0.eq(Mux(req.raw, (ra & (rc.shape.line - 1)) >> _log2(bus), (a0 & (ic.shape.line - 1)) >> _log2(bus))),
            new.beat1.eq((a1 & (ic.shape.line - 1)) >> _log2(bus)),
            new.off0.eq(Mux(req.raw, (ra & (bus - 1)) >> 2, (a0 & (bus - 1)) >> _log2(wb))),
            new.off1.eq((a1 & (bus - 1)) >> _log2(wb)),
            new.tag.eq(req.tag),
        ]
        with m.If(take):
            m.d.sync += Array(fifo)[tail].eq(new.value(entry)) if Q > 1 else fifo[0].eq(new.value(entry))
            m.d.sync += tail.eq(Mux(tail == Q - 1, 0, tail + 1))
        with m.If(pop):
            m.d.sync += head.eq(Mux(head == Q - 1, 0, head + 1))
        m.d.sync += level.eq(level + take - pop)

        # AR slots: shift on issue; a tag check with misses loads them (its first burst in slot 0).
        burst_addr = [Signal(self._addr_width, name=f"miss_addr{j}") for j in range(2)]
        burst_raw = [Signal(name=f"miss_raw{j}") for j in range(2)]
        nmiss = Signal(2)
        m.d.comb += nmiss.eq(Mux(req.raw, missr, miss0 + miss1))
        m.d.comb += [
            burst_addr[0].eq(Mux(req.raw, rline << rl, Mux(miss0, line0 << il, line1 << il))),
            burst_raw[0].eq(req.raw),
            burst_addr[1].eq(line1 << il), burst_raw[1].eq(0),
        ]
        with m.If(take & (nmiss != 0)):
            m.d.sync += [slot_v[0].eq(1), slot_addr[0].eq(burst_addr[0]), slot_raw[0].eq(burst_raw[0]),
                         slot_v[1].eq(nmiss == 2), slot_addr[1].eq(burst_addr[1]), slot_raw[1].eq(burst_raw[1])]
        with m.Elif(ar_go):
            m.d.sync += [slot_v[0].eq(slot_v[1]), slot_addr[0].eq(slot_addr[1]), slot_raw[0].eq(slot_raw[1]),
                         slot_v[1].eq(0)]

        # -- bursts in flight: which line each fills, in AR order ----------------------------------------
        depth = 1 << (2 * Q + 4).bit_length()
        flight = [Signal(1 + max(islot, rslot), name=f"flight_{q}") for q in range(depth)]
        f_head = Signal(range(depth))
        f_tail = Signal(range(depth))
        # bursts are queued in tag-check order, the order they leave on AR and come back on R
        with m.If(take & (nmiss != 0)):
            sw = max(islot, rslot)

            def fl(slot, raw):                      # a flight entry: the slot, zero-extended, then raw
                return Cat(slot, C(0, sw - len(slot)), C(raw, 1))
            first_slot = Mux(req.raw, fl(slotr, 1), Mux(miss0, fl(slot0, 0), fl(slot1, 0)))
            m.d.sync += Array(flight)[f_tail].eq(first_slot)
            with m.If(nmiss == 2):
                m.d.sync += Array(flight)[(f_tail + 1)[:len(f_tail)]].eq(fl(slot1, 0))
                m.d.sync += f_tail.eq(f_tail + 2)
            with m.Else():
                m.d.sync += f_tail.eq(f_tail + 1)
        cur = Signal(1 + max(islot, rslot))
        m.d.comb += cur.eq(Array(flight)[f_head])
        beat = Signal(range(max(beats) + 1))
        cur_raw = cur[-1]
        cur_slot = cur[:-1]
        last = self.axi.rvalid & self.axi.rlast
        with m.If(self.axi.rvalid):
            m.d.sync += beat.eq(Mux(self.axi.rlast, 0, beat + 1))
        with m.If(last):
            m.d.sync += f_head.eq(f_head + 1)

        # -- line RAMs: a row per beat --------------------------------------------------------------------
        m.submodules.index_lines = iram = memory.Memory(shape=bus_bits, depth=ic.sets * ic.ways * beats[0], init=[])
        m.submodules.raw_lines = rram = memory.Memory(shape=bus_bits, depth=rc.sets * rc.ways * beats[1], init=[])
        iw, rw = iram.write_port(), rram.write_port()
        ir0, ir1, rr = iram.read_port(), iram.read_port(), rram.read_port()
        m.d.comb += [
            iw.addr.eq(cur_slot[:islot] * beats[0] + beat), iw.data.eq(self.axi.rdata),
            iw.en.eq(self.axi.rvalid & ~cur_raw),
            rw.addr.eq(cur_slot[:rslot] * beats[1] + beat), rw.data.eq(self.axi.rdata),
            rw.en.eq(self.axi.rvalid & cur_raw),
            ir0.addr.eq(headv.slot0[:islot] * beats[0] + headv.beat0), ir0.en.eq(pop),
            ir1.addr.eq(headv.slot1 * beats[0] + headv.beat1), ir1.en.eq(pop),
            rr.addr.eq(headv.slot0[:rslot] * beats[1] + headv.beat0), rr.en.eq(pop),
        ]

        # -- cache state: tag check updates, fills, reads ---------------------------------------------------
        def update(cache, ports, fill_hit, read_dec):
            """ports: (set, tag, hit, way, active) per port checked in this cycle."""
            S, W = cache.sets, cache.ways
            for s in range(S):
                for w in range(W):
                    inc = []
                    for (ps, pt, ph, pw, act) in ports:
                        here = act & (ps == s) & (pw == w)
                        inc.append(here)
                        with m.If(act & (ps == s)):
                            # LRU: the accessed way becomes the youngest; younger valid ways age by one
                            acc_age = Signal(cache.age_bits + 1, name=f"{cache.name}_acc_{s}_{w}_{len(inc)}")
                            aw = Array(cache.age[s][x] for x in range(W))[pw]
                            vw = Array(cache.valid[s][x] for x in range(W))[pw]
                            m.d.comb += acc_age.eq(Mux(vw, aw, W))
                            with m.If(pw == w):
                                m.d.sync += cache.age[s][w].eq(0)
                                with m.If(~ph):
                                    m.d.sync += [cache.tag[s][w].eq(pt), cache.valid[s][w].eq(1),
                                                 cache.filled[s][w].eq(0)]
                            with m.Elif(cache.valid[s][w] & (cache.age[s][w] < acc_age)):
                                m.d.sync += cache.age[s][w].eq(cache.age[s][w] + 1)
                    slot = s * W + w
                    fill = fill_hit(slot)
                    with m.If(fill):
                        m.d.sync += cache.filled[s][w].eq(1)
                    dec = read_dec(slot)
                    m.d.sync += cache.count[s][w].eq(cache.count[s][w] + sum(inc) - dec)

        update(ic, [(s0, t0, hit0, way0, take & ~req.raw), (s1, t1, hit1, way1, take & two)],
               lambda slot: last & ~cur_raw & (cur_slot[:islot] == slot),
               lambda slot: pop & ~headv.raw & ((headv.slot0[:islot] == slot)
                                                 + ((headv.slot1 == slot) & (headv.slot1 != headv.slot0[:islot]))))
        update(rc, [(sr, tr, hitr, wayr, take & req.raw)],
               lambda slot: last & cur_raw & (cur_slot[:rslot] == slot),
               lambda slot: pop & headv.raw & (headv.slot0[:rslot] == slot))

        # -- the output register (the RAMs' read registers, and what goes with them) -------------------------
        o_raw = Signal()
        o_off0 = Signal.like(headv.off0)
        o_off1 = Signal.like(headv.off1)
        o_tag = Signal(max(1, self._tag_width))
        with m.If(pop):
            m.d.sync += [self.o.valid.eq(1), o_raw.eq(headv.raw), o_off0.eq(headv.off0), o_off1.eq(headv.off1),
                         o_tag.eq(headv.tag)]
        with m.Elif(self.o.ready):
            m.d.sync += self.o.valid.eq(0)
        wbits = self._word_bits
        m.d.comb += [
            self.o.p.raw.eq(o_raw),
            self.o.p.word0.eq(Mux(o_raw, rr.data.word_select(o_off0, 32),
                                  ir0.data.word_select(o_off0[:max(1, _log2(bus // wb))], wbits))),
            self.o.p.word1.eq(ir1.data.word_select(o_off1, wbits)),
        ]
        if self._tag_width:
            m.d.comb += self.o.p.tag.eq(o_tag)
        return m
