"""CachedReader: a request's index words or raw word, read through two caches and an AXI4 master.

The cache block of the cached unit (docs/memory.md), without the address stages in front of it and
the texel pipeline behind it::

    i (raw, word, straddle, tag) -> buffer (3) -> lookup -> tag check -> reference FIFO (Q) -> data read -> o
                                                                 | AR (one burst per miss)      ^
                                                                 v                              | R (line fills)
                                                               AXI4 read master  <-----------  memory

Timing (cycle for cycle :mod:`golden.memory.timing` with ``address_stages=0`` and a stream sink as
consumer; with every reference a hit: one request per cycle, 4 cycles from ``i`` to ``o``):

* **Lookup** (the tag check's first cycle; ``i`` transfers in cycle ``b``, into the buffer): the request's sets
  and tags are computed, each bank's tag row (tags, LRU ages, valid bits) and counts (issued,
  retired) read from LUT RAM, the tags compared and whether each way has references waiting found,
  and all of it registered, what the check writes in that cycle forwarded. The lookup's registers
  load every cycle (no clock enable): the lookup walks the requests as if every check took its
  own, so while the check works on request n the lookup takes n + 1; when n is not taken, the kill
  acts from a register the next cycle (``lookup_kill``: what the lookup holds then is dropped) and
  n is looked up again the cycle after, so a check is tried every ``REPLAY`` = 3 cycles until it is
  taken, and ``take`` reaches neither the lookup's choice of request nor its multiplexers (it loads
  some 40 flip-flops: the kill, ``lookup_valid``, the buffer's, FIFO's and burst queue's pointers,
  the write registers' enables, the AR slots' valid bits). The requests accepted and not yet
  taken (at most three) wait in a three-entry buffer in front of the lookup, so ``i.ready`` is the
  registered ``count != 3``, i.e. ``b[n] >= g[n-3] + 1``; a request is looked up from the cycle after
  its acceptance (its sets and tags computed into the buffer when it is accepted). The sets and
  tags of the entry the lookup reads are chosen a cycle ahead into a register (``lookup_bundle``),
  so the lookup's reads start at flip-flops; its other fields are read from the buffer in the
  lookup's cycle.
* **Tag check** (first tried in cycle ``max(b + 2, g[n-1] + 1)``, from the lookup's registers): the
  request's references (an index request reads word ``w``, and ``w + 1`` when ``straddle``, a second
  lookup when it lies in the next line; a raw request one raw word) hit or miss. A miss allocates
  the LRU way at once (an empty way first) and queues its burst; the reference enters the FIFO. The
  check is not taken while the FIFO is full at the start of the cycle (its registered level; for
  ``Q = 1``, the blocking cache: full and not read this cycle), while the second of two bursts of
  the previous request waits, or while a miss's victim line still has a reference in the FIFO that
  was not read before the lookup's cycle (golden's ``VICTIM_READ``). The check's writes (tag rows,
  counts, the FIFO, the bursts in flight) land one cycle later from write registers, every read
  of them forwarding the pending write, so the decision ``take`` reaches flip-flops' data inputs
  and a few enables, no LUT RAM write enable.
* **AR**: the j-th burst of a request checked in cycle ``g`` is on AR in cycle ``g + 1 + j`` (when
  ``arready`` is high, as the golden memory assumes; otherwise it waits and holds the tag check).
  A free AR slot loads the check's burst address every cycle (valid only when the check takes its
  request); a slot waiting for ``arready`` holds its address.
  INCR, ``line / bus`` beats, ``araddr`` the line's byte address, never crossing 4 KB.
* **R**: beats fill lines in burst order (``rready`` is always high); a line is readable the cycle
  after its last beat.
* **Data read**: the FIFO's head is read when its lines are filled and ``o`` is empty or transferring;
  ``o`` shows it the next cycle and holds it until ``o.ready``. The head and the entry after it are
  registers (the FIFO's LUT RAM is read two entries after the head), and whether the head's lines
  are filled is a register, so the read's decision ``pop`` is a gate of flip-flops.

Responses leave in request order, none lost or duplicated; a line is read from memory once while it
stays in the cache, however many references wait on it; a line is not replaced while a reference to
it waits.

Storage: the caches' per-line state is in LUT RAM (``amaranth.lib.memory.Memory`` with asynchronous
read ports and ``ram_style = distributed``, one write port each: :class:`_Cache`), read and written
in the cycles the flip-flops of an earlier version were, so the timing above is unchanged: per set,
the ways' tags and LRU ages; the counts of waiting references as two counters mod ``2^n`` (checked
in, written by the tag check; read out, written by the data read); whether a line is filled as two
bits (one flipped by the fill, one set by the allocation to the other's complement). The index
cache's rows are banked by set parity (a straddling index's two lines lie in consecutive sets), so
every memory has one writer per cycle. The valid bits of a set's ways are in its row too, and count
only once the set's row has been written since reset: one flip-flop per set (``touched``, cleared by
reset, set through a decoder of the row's write address); an allocation rebases its line's count and
filled bit, so a reset, even with bursts in flight, leaves the caches empty and consistent. The
reference FIFO and the queue of bursts in flight are LUT RAM too; the lines are block RAM when large
enough (one row per bus beat, registered reads; the index lines in two banks, one read port each).

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

from ..bus_port import or_all
from .axi import INCR, axi4_read_signature

__all__ = ["CachedReader"]


def _log2(v: int) -> int:
    return v.bit_length() - 1


def _reg(m, nx, name):
    """A lookup register of ``nx`` (returned; the check reads it): loaded every cycle, no clock
    enable (a request the check does not take is killed and sent again: :class:`CachedReader`)."""
    nx = Value.cast(nx)
    r = Signal(len(nx), name=name)
    m.d.sync += r.eq(nx)
    return r


class _Fields:
    """A struct's fields as separate signals (attributes by field name); ``value(layout)`` is their
    concatenation in the layout's bit order."""

    def __init__(self, signals: dict):
        self.__dict__.update(signals)
        self._signals = signals

    def value(self, layout):
        parts = sorted(((f.offset, self._signals[name]) for name, f in layout), key=lambda x: x[0])
        return Cat(*(sig for _, sig in parts))


class _Behind:
    """A memory's write port written one cycle behind its writer, from a write register (address,
    data, enable: ``{name}_w_addr``, ``{name}_w_data``, ``{name}_w_en``) loaded every cycle, so the
    writer's decision reaches flip-flops' data inputs, not the LUT RAM's write enable. A reader of
    the memory sees the pending write through :meth:`pending` (the register's enable and address
    compared with its own, and the data), so to it the memory is written at the edge as without
    the register. ``write`` takes the data only when ``data_en`` (a gate: see ``CachedReader``'s
    ``new``)."""

    def __init__(self, m, port, addr_shape, data_shape, name):
        self.addr = Signal(addr_shape, name=f"{name}_w_addr")
        self.data = Signal(data_shape, name=f"{name}_w_data")
        self.en = Signal(name=f"{name}_w_en")
        m.d.comb += [port.addr.eq(self.addr), port.data.eq(self.data), port.en.eq(self.en)]

    def write(self, m, addr, data, en, data_en=None):
        """Write ``data`` at ``addr`` at the next edge but one when ``en``."""
        m.d.sync += [self.addr.eq(addr), self.en.eq(en)]
        if data_en is None:
            m.d.sync += self.data.eq(data)
        else:
            with m.If(data_en):
                m.d.sync += self.data.eq(data)

    def pending(self, addr=None):
        """Whether a write is pending (to ``addr``, when given), and its data."""
        return (self.en if addr is None else self.en & (self.addr == addr)), self.data


class _Rows:
    """One per-set field of a cache in LUT RAM: a row per set, in ``banks`` memories (2: by set
    parity, for the index cache, whose straddling index checks two consecutive sets in one cycle).
    Each memory has one write port (what a LUT RAM has) and one asynchronous (combinational) read
    port per party that reads it; a party works on each bank apart (its logic per bank), so no
    row-wide multiplexer sits between the banks.

    ``behind``: the writes land one cycle late, from a write register per bank (address, row and
    enable, loaded every cycle: the writer's decision reaches flip-flops' data inputs, not the LUT
    RAM's write enables); a read sees the pending write (``read`` forwards it), so to its readers
    the memory is written at the clock edge as without the register."""

    def __init__(self, m, name, shape, sets, banks, behind=False):
        self.shape = shape
        self.banks = banks
        self.mems = []
        self.behind = []        # with ``behind``, a _Behind per bank
        for b in range(banks):
            n = f"{name}{b}" if banks > 1 else name
            m.submodules[n] = mem = memory.Memory(
                shape=shape, depth=sets // banks, init=[], attrs={"ram_style": "distributed"})
            self.mems.append(mem)
            if behind:
                self.behind.append(_Behind(m, mem.write_port(), max(1, _log2(sets // banks)), shape, n))

    def row(self, s):
        """The row of set ``s`` in its bank."""
        return s >> _log2(self.banks)

    def forwarded(self, b, r):
        """Whether bank ``b``'s pending write (``behind``) is to row ``r``, and the row it writes."""
        return self.behind[b].pending(r)

    def read(self, m, b, s, name):
        """Bank ``b``'s row of set ``s`` (a set of that bank), combinational (with the pending write
        forwarded, ``behind``)."""
        port = self.mems[b].read_port(domain="comb")
        out = Signal(self.shape, name=name)
        m.d.comb += port.addr.eq(self.row(s))
        if self.behind:
            hit, d = self.forwarded(b, self.row(s))
            m.d.comb += out.eq(Mux(hit, d, port.data))
        else:
            m.d.comb += out.eq(port.data)
        return out

    def write(self, m, b, s, en, data):
        """Write bank ``b``'s row of set ``s`` at the clock edge when ``en`` (one call per bank); with
        ``behind``, into the write register, and from it into the memory at the next edge. Returns
        the address and enable of the memory's write."""
        if self.behind:
            w = self.behind[b]
            w.write(m, self.row(s), data, en)
            return w.addr, w.en
        port = self.mems[b].write_port()
        m.d.comb += [port.addr.eq(self.row(s)), port.en.eq(en), port.data.eq(data)]
        return port.addr, port.en


class _Cache:
    """One cache's per-line state, its tag check, its fills and its reads.

    In LUT RAM (:class:`_Rows`, a row per set, every way of the set in the row): ``lines`` (tag and
    LRU age of each way, and the ways' valid bits), ``issued`` and ``retired`` (counts mod
    ``2^count_bits`` of the references checked into the FIFO and read out of it: the waiting
    references are their difference, each count written by one side), ``alloc`` and ``fill`` (a bit
    per way: a line is filled when the two are equal; an allocation writes ``alloc = ~fill``, a fill
    toggles ``fill``). In flip-flops: ``touched``, a bit per set, cleared by reset (the cache starts
    empty at every reset), set when the set's row is written; a row's valid bits count only when its
    set is touched. The counts and the alloc bit are rebased at every allocation, so what a reset
    leaves in the memories is never read.

    Every party (tag check, data read, fill) reaches at most one set per bank in a cycle: with two
    banks, its two sets are consecutive (or the same, the second then unused)."""

    def __init__(self, m, name, shape, banks, count_bits, tag_bits):
        self.shape = shape
        self.sets, self.ways = shape.sets, shape.ways
        self.set_bits = _log2(self.sets)
        self.way_bits = _log2(self.ways)
        self.age_bits = max(1, self.way_bits)
        self.count_bits = count_bits
        self.tag_bits = tag_bits
        self.banks = banks
        self.name = name
        S, W = self.sets, self.ways
        self.touched = [Signal(S // banks, name=f"{name}_touched{b}" if banks > 1 else f"{name}_touched")
                        for b in range(banks)]
        way = data.StructLayout({"tag": tag_bits, "age": self.age_bits})
        self.lines = _Rows(m, f"{name}_tags", data.StructLayout({"way": data.ArrayLayout(way, W), "valid": W}),
                           S, banks, behind=True)
        self.issued = _Rows(m, f"{name}_issued", data.ArrayLayout(count_bits, W), S, banks, behind=True)
        self.retired = _Rows(m, f"{name}_retired", data.ArrayLayout(count_bits, W), S, banks, behind=True)
        self.alloc = _Rows(m, f"{name}_alloc", W, S, banks, behind=True)
        self.fill = _Rows(m, f"{name}_fill", W, S, banks)
        # what the tag check writes into each bank's tag row this cycle (for the lookup's forwarding):
        # the row, its address, and whether the bank's port is active (a request is being checked)
        rb = max(1, _log2(S // banks))
        self.w_addr = [Signal(rb, name=f"{name}_fwd_addr{b}") for b in range(banks)]
        self.w_act = [Signal(name=f"{name}_fwd_act{b}") for b in range(banks)]
        self.w_row = [Signal(self.lines.shape, name=f"{name}_fwd_row{b}") for b in range(banks)]
        # and the way it accesses (hit or allocated; one-hot) and the issued row it writes
        self.w_way = [Signal(self.ways, name=f"{name}_fwd_way{b}") for b in range(banks)]   # one-hot
        self.w_issued = [Signal(self.issued.shape, name=f"{name}_fwd_issued{b}") for b in range(banks)]

    def slot_bits(self):
        return max(1, _log2(self.sets * self.ways))

    def set_of(self, slot):
        return slot >> self.way_bits if self.set_bits else C(0, 1)

    def way_of(self, slot):
        return slot[:self.way_bits] if self.way_bits else C(0, 1)

    def _banked(self, m, items, name):
        """``items``: one tuple of values per port (1 port, or 2 whose sets differ in parity; the first
        value of each tuple its set). Returns one tuple per bank: the port's values that bank holds."""
        if self.banks == 1:
            return [items[0]]
        p = items[0][0][0]
        out = []
        for b in range(2):
            vals = []
            for j, (v0, v1) in enumerate(zip(*items)):
                sig = Signal(max(len(Value.cast(v0)), len(Value.cast(v1))), name=f"{self.name}_{name}{b}_{j}")
                m.d.comb += sig.eq(Mux(p == b, v0, v1))
                vals.append(sig)
            out.append(tuple(vals))
        return out

    def _unbank(self, m, s, per_bank):
        """The value of the bank holding set ``s`` (small signals: hit, way, ...)."""
        return per_bank[0] if self.banks == 1 else Mux(s[0], per_bank[1], per_bank[0])

    def derive(self, line):
        """The sets and tags a lookup of ``line`` needs (and of ``line + 1``: a second port, when the
        cache has two banks), combinational: ``set{k}``, ``tag{k}`` per port, and with two banks
        ``bset{b}``, ``btag{b}``: the set and tag each bank holds (the port whose set has the bank's
        parity). Computed when a request enters the lookup's buffer, so that the lookup starts
        from flip-flops."""
        d = {}
        for k in range(self.banks):
            ln = line if k == 0 else line + 1
            d[f"set{k}"] = (ln[:self.set_bits] if self.set_bits else C(0, 1), max(1, self.set_bits))
            d[f"tag{k}"] = ((ln >> self.set_bits)[:self.tag_bits], self.tag_bits)
        if self.banks == 2:
            for b in range(2):
                mine = d["set0"][0][0] == b
                d[f"bset{b}"] = (Mux(mine, d["set0"][0], d["set1"][0]), max(1, self.set_bits))
                d[f"btag{b}"] = (Mux(mine, d["tag0"][0], d["tag1"][0]), self.tag_bits)
        return d

    def lookup(self, m, d):
        """The tag check's first cycle: the lookup registers the sets and tags of :meth:`derive`
        (``d``: their values, from the lookup's buffer), and each bank's tag row for them, read
        from the LUT RAM, with its valid bits as the check counts them (cleared when the set is not
        touched: the check starts from them). The registers load every cycle (:func:`_reg`, no clock
        enable): what they hold is checked the next cycle, or killed there. A row the tag check
        writes in this same cycle (the request ahead, leaving the check) is forwarded: the register
        takes the written row and valid bits, not the memory's old ones (when the check does not
        take its request, the looked-up request is killed anyway). Only the tag check writes these
        rows, so no register holds a stale row."""
        nports = self.banks
        nsets = [d[f"set{k}"] for k in range(nports)]
        ntags = [d[f"tag{k}"] for k in range(nports)]
        self.rset = [_reg(m, nsets[k], f"{self.name}_set{k}") for k in range(nports)]
        self.rtag = [_reg(m, ntags[k], f"{self.name}_line_tag{k}") for k in range(nports)]
        self.rrow = [Signal(self.lines.shape, name=f"{self.name}{b}_row" if self.banks > 1 else f"{self.name}_row")
                     for b in range(self.banks)]
        # the row's valid bits, as the check counts them (none before its set is touched)
        self.rvalid = [Signal(self.ways, name=f"{self.name}{b}_row_valid" if self.banks > 1 else f"{self.name}_row_valid")
                       for b in range(self.banks)]
        nm = [f"{self.name}{b}" if self.banks > 1 else self.name for b in range(self.banks)]
        self.rmatch = [Signal(self.ways, name=f"{n}_match") for n in nm]
        self.rwaiting = [Signal(self.ways, name=f"{n}_waiting") for n in nm]
        self.rissued = [Signal(self.issued.shape, name=f"{n}_row_issued") for n in nm]
        self.rretired = [Signal(self.retired.shape, name=f"{n}_row_retired") for n in nm]
        self.rbank = []
        for b in range(self.banks):
            n = f"{self.name}{b}" if self.banks > 1 else self.name
            if self.banks == 1:
                s, t = nsets[0], ntags[0]
                self.rbank.append((self.rset[0], self.rtag[0]))
            else:
                # the bank's set and tag (of the port whose set has the bank's parity), registered
                s, t = d[f"bset{b}"], d[f"btag{b}"]
                self.rbank.append((_reg(m, s, f"{n}_set"), _reg(m, t, f"{n}_tag")))
            rd = self.lines.read(m, b, s, f"{n}_next_row")
            r = self.lines.row(s)
            touched = self.touched[b]
            here = touched.bit_select(r, 1) if len(touched) > 1 else touched
            fwd = Signal(name=f"{n}_fwd")
            m.d.comb += fwd.eq(self.w_act[b] & (self.w_addr[b] == r) if len(touched) > 1 else self.w_act[b])
            pend, _ = self.lines.forwarded(b, r)     # the check's write of the cycle before (rd has it)
            m.d.sync += [self.rrow[b].eq(Mux(fwd, self.w_row[b], rd)),
                         self.rvalid[b].eq(Mux(fwd, self.w_row[b].valid, Mux(here | pend, rd.valid, 0)))]
            # The tag compare, done here: each way's tag against the request's. When the check writes
            # this row (``fwd``) it changes one way's tag, the way it accesses, to its own tag (a
            # hit's is that tag already): that way compares the two requests' tags.
            cw = self.w_way[b]
            eq = Signal(self.ways, name=f"{n}_next_match")
            m.d.comb += eq.eq(Cat(*(Mux(fwd & cw[w], t == self.rbank[b][1], rd.way[w].tag == t)
                                    for w in range(self.ways))))
            m.d.sync += self.rmatch[b].eq(eq)
            # The counts: issued (only the check writes it: forwarded as the row), retired (the data
            # read writes it: what was read out before this cycle), and whether each way has
            # references waiting (the way the check accesses has at least its own).
            iss = self.issued.read(m, b, s, f"{n}_issued_row")
            ret = self.retired.read(m, b, s, f"{n}_retired_row")
            wt = Signal(self.ways, name=f"{n}_next_waiting")
            m.d.comb += wt.eq(Cat(*((fwd & cw[w]) | (iss[w] != ret[w]) for w in range(self.ways))))
            m.d.sync += [self.rissued[b].eq(Mux(fwd, self.w_issued[b], iss)), self.rretired[b].eq(ret),
                         self.rwaiting[b].eq(wt)]

    def check(self, m, actives, take):
        """The tag check's second cycle, on what :meth:`lookup` registered: ``actives`` is whether each
        port is looked up (the request is valid and reads that line), ``take`` whether the request
        leaves the check this cycle. Returns (set, hit, way, busy victim) per port, combinational;
        updates the state of the active ports' sets at the clock edge when ``take``."""
        S, W = self.sets, self.ways
        sets, tags = self.rset, self.rtag
        if self.banks == 1:
            banked = [(sets[0], tags[0], actives[0])]
        else:           # each bank's set and tag registered by the lookup; the ports' actives by parity
            banked = [(bs, bt, Mux(sets[0][0] == b, actives[0], actives[1])) for b, (bs, bt) in enumerate(self.rbank)]
        results = []
        for b, (s, t, act) in enumerate(banked):
            n = f"{self.name}{b}" if self.banks > 1 else self.name
            lines = self.rrow[b]
            issued, retired = self.rissued[b], self.rretired[b]
            alloc = self.alloc.read(m, b, s, f"{n}_alloc_check")
            fill = self.fill.read(m, b, s, f"{n}_fill_check")
            touched = self.touched[b]
            # the row's valid bits count once its set has been written since reset
            valid = Signal(W, name=f"{n}_valid")
            m.d.comb += valid.eq(self.rvalid[b])
            row = lines.way
            hits = [valid[w] & self.rmatch[b][w] for w in range(W)]
            hit = Signal(name=f"{n}_hit")
            way = Signal(max(1, self.way_bits), name=f"{n}_way")
            busy = Signal(name=f"{n}_busy")
            m.d.comb += hit.eq(Cat(*hits).any())
            # The way, one-hot (``sel``; ``way`` its number): the hit's; else the victim: the lowest
            # empty way, else the oldest (age W-1). The victim is found from the registered row alone,
            # beside the tag compare, and the row's update works on the one-hot way, its ages compared
            # pairwise beside it (no multiplexer by the way's number on the path to the new row).
            def lowest(x):
                return Cat(*(x[w] & ~x[:w].any() if w else x[0] for w in range(W)))
            oldest = Cat(*(valid[w] & (row[w].age == W - 1) for w in range(W)))
            vsel = Signal(W, name=f"{n}_victim_sel")
            sel = Signal(W, name=f"{n}_way_sel")
            m.d.comb += [vsel.eq(Mux(~valid.all(), lowest(~valid), Mux(oldest.any(), lowest(oldest), 1))),
                         sel.eq(Mux(hit, lowest(Cat(*hits)), vsel))]
            m.d.comb += way.eq(or_all(Mux(sel[w], w, 0) for w in range(W)))
            # a way's references wait when its counts differ (mod 2^n: equal is none waiting), found
            # for every way by the lookup (what was read out before its cycle), chosen by the victim
            m.d.comb += busy.eq(~hit & (valid & self.rwaiting[b] & vsel).any())
            # LRU: the accessed way becomes the youngest; younger valid ways age by one (every valid
            # way when the accessed one was empty). A miss puts the line's tag in the way, rebases its
            # count on what was read out, and clears its fill.
            acc_valid = Signal(name=f"{n}_acc_valid")
            m.d.comb += acc_valid.eq((valid & sel).any())
            new_row = Signal(self.lines.shape, name=f"{n}_new_row")
            new_issued = Signal(self.issued.shape, name=f"{n}_new_issued")
            new_alloc = Signal(W, name=f"{n}_new_alloc")
            ways, counts, allocs = [], [], []
            for w in range(W):
                here = sel[w]
                old_age = row[w].age
                younger = ~acc_valid | Cat(*(sel[v] & (old_age < row[v].age) for v in range(W) if v != w)).any()
                new_age = Mux(here, 0, Mux(valid[w] & younger, old_age + 1, old_age))
                ways.append(Cat(Mux(here & ~hit, t, row[w].tag)[:self.tag_bits], new_age[:self.age_bits]))
                counts.append((Mux(here, Mux(hit, issued[w], retired[w]) + 1, issued[w]))[:self.count_bits])
                allocs.append(Mux(here & ~hit, ~fill[w], alloc[w]))
            # each row assigned in one piece (CXXRTL would assemble a row written field by field)
            m.d.comb += [new_row.eq(Cat(Cat(*ways), valid | sel)), new_issued.eq(Cat(*counts)),
                         new_alloc.eq(Cat(*allocs))]
            addr, en = self.lines.write(m, b, s, act & take, new_row)
            self.issued.write(m, b, s, act & take, new_issued)
            self.alloc.write(m, b, s, act & take, new_alloc)
            m.d.comb += [self.w_addr[b].eq(self.lines.row(s)), self.w_act[b].eq(act), self.w_row[b].eq(new_row),
                         self.w_way[b].eq(sel), self.w_issued[b].eq(new_issued)]
            # a set is touched when its row is written (a decoder of the bank's write address)
            with m.If(en):
                m.d.sync += (touched.bit_select(addr, 1) if len(touched) > 1 else touched).eq(1)
            # a hit on a filled line (what the data read's register takes when this reference is
            # the next head: the fills of the cycles before this one)
            filled = Signal(name=f"{n}_hit_filled")
            # (at most one way hits: a set holds a line once)
            m.d.comb += filled.eq((Cat(*hits) & ~(alloc ^ fill)).any())
            results.append((hit, way, busy, filled))
        out = []
        for k, s in enumerate(sets):
            hit = Signal(name=f"{self.name}_hit{k}")
            way = Signal(max(1, self.way_bits), name=f"{self.name}_way{k}")
            busy = Signal(name=f"{self.name}_busy{k}")
            filled = Signal(name=f"{self.name}_hit_filled{k}")
            m.d.comb += [hit.eq(self._unbank(m, s, [r[0] for r in results])),
                         way.eq(self._unbank(m, s, [r[1] for r in results])),
                         busy.eq(self._unbank(m, s, [r[2] for r in results])),
                         filled.eq(self._unbank(m, s, [r[3] for r in results]))]
            out.append((s, hit, way, busy, filled))
        return out

    def filled(self, m, slots, name):
        """Whether each line of ``slots`` (one, or two in consecutive sets, or the same twice) is
        filled, combinational (the fills before this cycle)."""
        sets = [Signal(max(1, self.set_bits), name=f"{self.name}_{name}_set{k}") for k in range(len(slots))]
        m.d.comb += [s.eq(self.set_of(slot)) for s, slot in zip(sets, slots)]
        banked = self._banked(m, [(s, self.way_of(slot)) for s, slot in zip(sets, slots)], name)
        filled_b = []
        for b, (s, w) in enumerate(banked):
            n = f"{self.name}{b}" if self.banks > 1 else self.name
            alloc = self.alloc.read(m, b, s, f"{n}_alloc_{name}")
            fill = self.fill.read(m, b, s, f"{n}_fill_{name}")
            f = Signal(name=f"{n}_{name}_filled")
            m.d.comb += f.eq(alloc.bit_select(w, 1) == fill.bit_select(w, 1))
            filled_b.append(f)
        filled = Signal(len(slots), name=f"{self.name}_{name}_filled")
        m.d.comb += [filled[k].eq(self._unbank(m, s, filled_b)) for k, s in enumerate(sets)]
        return filled

    def retire(self, m, slots, retire):
        """The data read counts a reference read out of each line of ``slots`` at the clock edge
        (``retire``: one enable per slot; the second only when the slots differ)."""
        sets = [Signal(max(1, self.set_bits), name=f"{self.name}_head_set{k}") for k in range(len(slots))]
        m.d.comb += [s.eq(self.set_of(slot)) for s, slot in zip(sets, slots)]
        banked = self._banked(m, [(s, self.way_of(slot), en) for s, slot, en in zip(sets, slots, retire)], "head")
        for b, (s, w, en) in enumerate(banked):
            n = f"{self.name}{b}" if self.banks > 1 else self.name
            retired = self.retired.read(m, b, s, f"{n}_retired_head")
            new = Signal(self.retired.shape, name=f"{n}_new_retired")
            m.d.comb += new.eq(Cat(*(Mux(w == x, retired[x] + 1, retired[x])[:self.count_bits]
                                     for x in range(self.ways))))
            self.retired.write(m, b, s, en, new)

    def fill_line(self, m, slot, en):
        """A burst's last beat fills the line of ``slot`` at the clock edge (``en``)."""
        s = Signal(max(1, self.set_bits), name=f"{self.name}_fill_set")
        m.d.comb += s.eq(self.set_of(slot))
        w = self.way_of(slot)
        for b in range(self.banks):
            n = f"{self.name}{b}" if self.banks > 1 else self.name
            row = self.fill.read(m, b, s, f"{n}_fill_row")
            new = Signal(self.ways, name=f"{n}_new_fill")
            m.d.comb += new.eq(row ^ (C(1, self.ways) << w)[:self.ways])
            self.fill.write(m, b, s, en & (s[0] == b) if self.banks > 1 else en, new)


class CachedReader(wiring.Component):
    __doc__ = __doc__

    def __init__(self, config, *, word_bits: int = 32, raw_base: int = 0, word_addr_bits: int = 24,
                 tag_width: int = 8, addr_width: int = 32, joint: bool = False):
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
        self._joint = bool(joint)
        self.request_layout = data.StructLayout({
            "raw": 1, "word": word_addr_bits, "straddle": 1, "tag": tag_width})
        wide = max(word_bits, 32)
        self.response_layout = data.StructLayout({"raw": 1, "word0": wide, "word1": word_bits, "tag": tag_width})
        super().__init__({
            "i": In(stream.Signature(self.request_layout)),
            "o": Out(stream.Signature(self.response_layout)),
            "stall_fill": Out(1),
            "axi": Out(axi4_read_signature(addr_width, 8 * self._bus)),
            **({"check_ready": Out(1), "check_go": In(1)} if joint else {}),
        })

    #: Cycles from ``i`` to ``o`` when every reference hits: buffer, lookup, tag check, data read
    #: (golden's ``FRONT_LATENCY`` is the unit's address stages plus this).
    LATENCY = 4

    @property
    def latency(self) -> int:
        """Cycles from ``i`` to ``o`` when every reference hits (buffer, lookup, tag check, data read): 4."""
        return self.LATENCY

    def elaborate(self, platform):
        m = Module()
        cfg = self._config
        Q = cfg.prefetch
        bus = self._bus
        bus_bits = 8 * bus
        wb = self._word_bits // 8
        count_bits = max(1, Q.bit_length()) + 1
        aw = self._addr_width
        # The index cache's rows in two banks by set parity (a straddling index checks two
        # consecutive sets in one cycle); tags as wide as the AXI address leaves them.
        ic = _Cache(m, "index", cfg.index_cache, 2, count_bits,
                    max(1, aw - _log2(cfg.index_cache.line) - _log2(cfg.index_cache.sets)))
        rc = _Cache(m, "raw", cfg.raw_cache, 1, count_bits,
                    max(1, aw - _log2(cfg.raw_cache.line) - _log2(cfg.raw_cache.sets)))
        beats = [ic.shape.line // bus, rc.shape.line // bus]
        # -- the lookup's input: the requests accepted on i and not yet taken by the check (at most three) --
        # What the lookup needs of a request (its sets and tags in each cache, the FIFO entry's
        # fields) is computed from ``i`` when the request is accepted, into a three-entry buffer,
        # so the lookup starts from flip-flops. The lookup's registers load every cycle (no clock
        # enable, so the check's decision ``take`` reaches a handful of flip-flops, not the ~500 of
        # the lookup): the lookup walks the buffer as if every check took its request (its own
        # pointer ``lookup_pointer``), so while the check works on request n (``lv``) the lookup
        # takes n + 1. When the check does not take n, the kill acts from a register a cycle later
        # (``lookup_kill``): the request then behind n in the check (never valid: ``lv`` drops with
        # the try) and the one the lookup takes in that cycle are dropped, and the lookup's pointer
        # goes back to n, which is looked up again in the next cycle and checked in the one after:
        # a check not taken is tried again three cycles later (golden's ``REPLAY``), and ``take``
        # reaches neither the choice of the lookup's next request nor its ~100 multiplexers. The
        # buffer holds the requests accepted and not yet taken (n in the check, n + 1 in the lookup,
        # n + 2 arriving), so ``i.ready`` is the registered ``count != 3`` (``b[n] >= g[n-3] + 1``),
        # and a request accepted in cycle ``b`` is looked up from ``b + 1`` and checked from ``b +
        # 2`` (golden's ``LOOKUP_STAGES``).
        req = self.i.p
        a0 = Signal(self._addr_width + 8)
        a1 = Signal(self._addr_width + 8)
        ra = Signal(self._addr_width + 8)
        m.d.comb += [a0.eq(req.word * wb), a1.eq((req.word + 1) * wb), ra.eq(self._raw_base + req.word * 4)]
        il, rl = _log2(ic.shape.line), _log2(rc.shape.line)
        line0, line1, rline = a0 >> il, a1 >> il, ra >> rl
        nb = max(1, _log2(max(beats)))
        derived = [
            ("raw", req.raw, 1),
            ("two", ~req.raw & req.straddle & (line1 != line0), 1),
            ("tag", req.tag, max(1, self._tag_width)),
            ("beat0", Mux(req.raw, (ra & (rc.shape.line - 1)) >> _log2(bus), (a0 & (ic.shape.line - 1)) >> _log2(bus))[:nb], nb),
            ("beat1", ((a1 & (ic.shape.line - 1)) >> _log2(bus))[:nb], nb),
            ("off0", Mux(req.raw, (ra & (bus - 1)) >> 2, (a0 & (bus - 1)) >> _log2(wb))[:max(1, _log2(bus // min(wb, 4)) or 1)],
             max(1, _log2(bus // min(wb, 4)) or 1)),
            ("off1", ((a1 & (bus - 1)) >> _log2(wb))[:max(1, _log2(bus // wb) or 1)], max(1, _log2(bus // wb) or 1)),
        ]
        # the caches' sets and tags last: the fields the lookup's memory reads need, chosen a cycle
        # ahead (``lookup_bundle`` below); the ``now_bits`` before them are read in the lookup's cycle
        now_bits = sum(w for _, _, w in derived)
        for cache, line in ((ic, line0), (rc, rline)):
            derived += [(f"{cache.name}_{k}", v, w) for k, (v, w) in cache.derive(line).items()]
        width = sum(w for _, _, w in derived)
        bundle = Signal(width, name="lookup_bundle_in")
        # (a gate, not a plain wire: one packed wire holding bits of ``ra`` and bits computed from
        # them, Yosys makes it the driver of ``ra``'s bits and Verilator sees a cycle: see ``new``)
        with m.If(self.i.valid):
            m.d.comb += bundle.eq(Cat(*(Value.cast(v)[:w] if len(Value.cast(v)) >= w else v for _, v, w in derived)))
        buf = [Signal(width, name=f"lookup_buffer{j}") for j in range(3)]
        wp = Signal(3, name="lookup_buffer_write", init=1)      # one-hot
        rp = Signal(3, name="lookup_buffer_read", init=1)       # one-hot: the oldest request not taken
        count = Signal(range(4), name="lookup_buffer_count")
        lv = Signal(name="lookup_valid")
        take = Signal()
        accept = Signal()
        m.d.comb += accept.eq(self.i.valid & (count != 3))
        for j in range(3):
            with m.If(accept & wp[j]):
                m.d.sync += buf[j].eq(bundle)
        with m.If(accept):
            m.d.sync += wp.eq(wp.rotate_left(1))
        with m.If(take):
            m.d.sync += rp.eq(rp.rotate_left(1))
        m.d.sync += count.eq(count + accept - take)
        # The lookup's own pointer (``lp``, one-hot: the entry it reads this cycle) and how many
        # accepted requests lie at or after it (``ahead``; the lookup holds a request when it is not
        # 0). It advances every cycle the lookup holds a request, as if the check ahead took its
        # own; a kill (``lookup_kill``: the check did not take its request in the cycle before) sets
        # it back to the oldest request not taken (``rp``: the one not taken; no request is taken
        # in a kill's cycle, the check being empty then), with every request not taken ahead of it.
        lp = Signal(3, name="lookup_pointer", init=1)
        ahead = Signal(range(4), name="lookup_ahead")
        kill = Signal(name="lookup_kill")
        have = Signal(name="lookup_has_request")
        lp_next = Signal(3, name="lookup_pointer_next")
        m.d.comb += [have.eq(ahead != 0),
                     lp_next.eq(Mux(kill, rp, Mux(have, lp.rotate_left(1), lp)))]
        m.d.sync += [
            kill.eq(lv & ~take),
            lp.eq(lp_next),
            ahead.eq(Mux(kill, count + accept, ahead + accept - have)),
            # the check's request next cycle: the lookup's, unless a kill drops it (the one killed
            # now, or the one whose check fails now: ``lv & ~take`` is the kill of the next cycle)
            lv.eq(have & ~kill & ~(lv & ~take)),
        ]
        nbuf = [Mux(accept & wp[j], bundle, buf[j]) for j in range(3)]

        def pick(entries, sel):
            """The entry of the one-hot ``sel``."""
            return or_all(Mux(sel[j], entries[j], 0) for j in range(3))
        # Only the fields the lookup reads memories with (each cache's sets and tags: the last ones
        # of ``derived``) are chosen a cycle ahead, into ``lookup_bundle`` (the lookup's reads start
        # at flip-flops), from the buffer as it will be (a request accepted now is written into its
        # entry at this edge, so it is taken from ``bundle``) at the lookup's next pointer, which
        # no ``take`` reaches; the others (the FIFO entry's, ``raw``, ``two``), which the lookup only
        # registers for the check, are read from the buffer in the lookup's own cycle at ``lp``.
        src = Signal(width - now_bits, name="lookup_bundle")
        m.d.sync += src.eq(pick(nbuf, lp_next)[now_bits:])
        entry_now = Signal(now_bits, name="lookup_entry")
        m.d.comb += entry_now.eq(pick(buf, lp)[:now_bits])
        look = {}
        pos = 0
        for name, _, w in derived:
            sig = Signal(w, name=f"lookup_next_{name}")
            m.d.comb += sig.eq(entry_now[pos:pos + w] if pos < now_bits else src[pos - now_bits:pos - now_bits + w])
            look[name] = sig
            pos += w
        ic.lookup(m, {k[len("index_"):]: v for k, v in look.items() if k.startswith("index_")})
        rc.lookup(m, {k[len("raw_"):]: v for k, v in look.items() if k.startswith("raw_") and k != "raw"})

        def field(name):
            return _reg(m, look[name], f"lookup_{name}")
        l_raw = field("raw")
        l_two = field("two")
        l_tag = field("tag") if self._tag_width else C(0, 1)
        l_beat0, l_beat1, l_off0, l_off1 = field("beat0"), field("beat1"), field("off0"), field("off1")
        # the bursts' line addresses (line0, line0 + 1, raw) from the sets and tags the lookup
        # registered for the compare (not registered again: fewer flip-flops on ``take``'s enable)
        def line_addr(cache, k, sh):
            st, tg = cache.rset[k], cache.rtag[k]
            return (Cat(st[:cache.set_bits], tg) << sh)[:self._addr_width] if cache.set_bits else \
                (tg << sh)[:self._addr_width]
        l_addr = [line_addr(ic, 0, il), line_addr(ic, 1, il), line_addr(rc, 0, rl)]
        two = l_two
        # port 1 looks up the line after line0 (line1 when ``two``; unused otherwise)
        (s0, hit0, way0, busy0, fill0), (s1, hit1, way1, busy1, fill1) = ic.check(m, [lv & ~l_raw, lv & two], take)
        (sr, hitr, wayr, busyr, fillr), = rc.check(m, [lv & l_raw], take)
        new_filled = Signal(name="new_filled")       # the request's lines hit and are filled
        m.d.comb += new_filled.eq(Mux(l_raw, fillr, fill0 & (~two | fill1)))
        miss0 = ~l_raw & ~hit0
        miss1 = two & ~hit1
        missr = l_raw & ~hitr
        busy = Mux(l_raw, busyr, busy0 | (two & busy1))

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

        check_ready = self.check_ready if self._joint else Signal(name="check_ready")
        # -- the reference FIFO (Q entries) ------------------------------------------------------------
        islot = max(1, ic.slot_bits())
        rslot = max(1, rc.slot_bits())
        entry = data.StructLayout({
            "raw": 1, "slot0": max(islot, rslot), "slot1": islot, "beat0": max(1, _log2(max(beats))),
            "beat1": max(1, _log2(max(beats))), "off0": max(1, _log2(bus // min(wb, 4)) or 1),
            "off1": max(1, _log2(bus // wb) or 1), "tag": max(1, self._tag_width)})
        # in LUT RAM: written at the tail by the tag check, read at the head by the data read
        m.submodules.references = fifo = memory.Memory(shape=entry, depth=Q, init=[],
                                                       attrs={"ram_style": "distributed"})
        fifo_w, fifo_r = fifo.write_port(), fifo.read_port(domain="comb")   # fifo_r: two entries after the head
        level = Signal(range(Q + 1))
        # the address of the entry two after the head, a register of its own (no carry chain before
        # the FIFO's read multiplexers): ``head + 2`` mod Q
        head2 = Signal(range(max(Q, 2)), init=2 % Q, name="head_after_next")
        tail = Signal(range(max(Q, 2)))
        pop = Signal()
        o_free = Signal()
        m.d.comb += o_free.eq(~self.o.valid | self.o.ready)
        # The head entry and the entry after it in registers (so the data read starts from
        # flip-flops, not from the FIFO's LUT RAM read multiplexers, and whether the next head's lines
        # are filled is one LUT RAM read away from flip-flops): the head is loaded with the entry after
        # it when the head is read, or with the entry being written when that one becomes the head
        # (the FIFO empty, or about to be); the entry after the head (``head_next``, meaningful while
        # the FIFO holds two or more) with the entry two after the head when the head is read (in
        # the LUT RAM at ``head_after_next``, or in the write register, or being checked), or with the
        # entry being checked when that one becomes the second.
        headv = Signal(entry, name="head_entry")
        nextv = Signal(entry, name="head_next")
        m.d.comb += fifo_r.addr.eq(head2)
        # Whether the head's lines are filled, in a register (``head_filled``: the data read's
        # ``pop`` is then a gate of flip-flops): loaded each cycle for the entry that is the head in
        # the next one, from the fills before this cycle: the head's own lines when it stays, the
        # entry after it when it is read, or the entry being checked when that one becomes the head
        # (the check's hit on a filled line). So a line's fill is seen by the data read the second
        # cycle after its last beat (golden's ``FILL_READ``).
        # the FIFO's write register (below)
        fw = _Behind(m, fifo_w, tail.shape(), entry, "fifo")
        after_next = Signal(entry, name="head_after_next_entry")
        fw_en, fw_data = fw.pending()
        m.d.comb += after_next.eq(Mux(fw_en & (level == 3), fw_data, fifo_r.data))

        def lines_filled(v, name):
            i_f = ic.filled(m, [v.slot0[:islot], v.slot1], name)
            r_f = rc.filled(m, [v.slot0[:rslot]], name)
            return Mux(v.raw, r_f, i_f.all())
        head_now = lines_filled(headv, "head")
        next_now = lines_filled(nextv, "next")
        # ``head_filled`` chosen from three registers, each loaded every cycle (so that no read of
        # the ``alloc``/``fill`` LUT RAMs is shared between the head's and the next entry's lines
        # through a multiplexer on ``pop``, which Yosys's ``share`` would build: a loop from
        # ``pop`` through the read address back to ``head_filled``), by a fourth holding which
        # one applies: the head's lines (it stays), the next entry's (the head was read), the
        # check's hit (the entry being checked became the head).
        f_stay = Signal(name="head_filled_stay")
        f_next = Signal(name="head_filled_next")
        f_new = Signal(name="head_filled_new")
        f_from = Signal(2, name="head_filled_from")         # 0 stay, 1 next, 2 new
        m.d.sync += [f_stay.eq(head_now), f_next.eq(next_now), f_new.eq(new_filled)]
        head_filled = Signal(name="head_filled")
        m.d.comb += head_filled.eq(Mux(f_from[1], f_new, Mux(f_from[0], f_next, f_stay)))
        m.d.comb += pop.eq((level != 0) & head_filled & o_free)
        m.d.comb += self.stall_fill.eq((level != 0) & ~head_filled & o_free)
        # a read out of the index cache retires one reference per line
        ic.retire(m, [headv.slot0[:islot], headv.slot1],
                  [pop & ~headv.raw, pop & ~headv.raw & (headv.slot1 != headv.slot0[:islot])])
        rc.retire(m, [headv.slot0[:rslot]], [pop & headv.raw])

        # Room in the FIFO: from the registered level alone (``pop``, the end of the data read's
        # path through the fill LUT RAMs, stays off the check's ready and ``take``), so an entry freed
        # by a read is taken from the next cycle (golden's ``fifo_slack``); the blocking cache
        # (Q = 1) keeps the read's room in the same cycle (else every reference would take two).
        room = Signal(name="fifo_room")
        m.d.comb += room.eq((level != Q) | pop if Q == 1 else level != Q)
        m.d.comb += [
            check_ready.eq(~slot_v[1] & (~slot_v[0] | self.axi.arready) & room & ~busy),
            take.eq(lv & (self.check_go if self._joint else check_ready)),
            self.i.ready.eq(count != 3),
        ]
        # the entry of the request being checked
        # The entry's fields as separate signals, joined only where the FIFO stores them, and there
        # through a gate (the write data is driven only when ``take``): one packed wire would hold
        # both bits of ``a1`` (beat1, off1) and bits computed from them through the tag check
        # (slot1), Yosys makes such a wire the driver of ``a1``'s bits, and Verilator, which orders a
        # wire as a whole, would see a combinational cycle through it (UNOPTFLAT) where there is none.
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
            new.raw.eq(l_raw),
            new.slot0.eq(Mux(l_raw, slotr, slot0)),
            new.slot1.eq(slot1),
            new.beat0.eq(l_beat0), new.beat1.eq(l_beat1), new.off0.eq(l_off0), new.off1.eq(l_off1),
            new.tag.eq(l_tag),
        ]
        # The FIFO is written one cycle behind the check, from a write register loaded every cycle
        # (``take`` reaches its enable's data input, not the LUT RAM's write enables); the data read
        # takes a reference the cycle after its check from ``new`` (the FIFO empty) or from the
        # write register (below), so it sees no difference.
        fw.write(m, tail, new.value(entry), take, data_en=lv)    # (a gate, not a plain wire: see ``new`` above)
        with m.If(take):
            m.d.sync += tail.eq(Mux(tail == Q - 1, 0, tail + 1))
        with m.If(pop):
            m.d.sync += head2.eq(Mux(head2 == Q - 1, 0, head2 + 1))
        m.d.sync += level.eq(level + take - pop)
        with m.If(pop):
            # the entry after the head (level 2 or more), or the one being checked (level 1)
            m.d.sync += [headv.eq(Mux(level == 1, new.value(entry), nextv)), f_from.eq(Mux(level == 1, 2, 1))]
        with m.Elif(level == 0):
            m.d.sync += [headv.eq(new.value(entry)), f_from.eq(2)]
        with m.Else():
            m.d.sync += f_from.eq(0)
        # the entry after the head: when the head is read, the one two after it (being checked at
        # level 2; in the write register at level 3 with a write pending: the newest entry; else in
        # the LUT RAM); when not, the one being checked once it becomes the second (level 1)
        with m.If(pop):
            m.d.sync += nextv.eq(Mux(level == 2, new.value(entry), after_next))
        with m.Elif(level == 1):
            m.d.sync += nextv.eq(new.value(entry))

        # AR slots: shift on issue; a tag check with misses loads them (its first burst in slot 0).
        burst_addr = [Signal(self._addr_width, name=f"miss_addr{j}") for j in range(2)]
        burst_raw = [Signal(name=f"miss_raw{j}") for j in range(2)]
        nmiss = Signal(2)
        m.d.comb += nmiss.eq(Mux(l_raw, missr, miss0 + miss1))
        m.d.comb += [
            burst_addr[0].eq(Mux(l_raw, l_addr[2], Mux(miss0, l_addr[0], l_addr[1]))),
            burst_raw[0].eq(l_raw),
            burst_addr[1].eq(l_addr[1]), burst_raw[1].eq(0),
        ]
        # Only the valid bits follow ``take``; a free slot loads the check's burst every cycle
        # whether or not the check takes it (valid only when it does), so ``take`` reaches two
        # flip-flops here, not the ~70 enables of the slots' addresses. A slot's address moves only
        # while the slot is empty or issuing (AXI: ``araddr`` is held while ``arvalid & ~arready``).
        with m.If(take & (nmiss != 0)):
            m.d.sync += [slot_v[0].eq(1), slot_v[1].eq(nmiss == 2)]
        with m.Elif(ar_go):
            m.d.sync += [slot_v[0].eq(slot_v[1]), slot_v[1].eq(0)]
        with m.If(slot_v[1]):
            with m.If(ar_go):
                m.d.sync += [slot_addr[0].eq(slot_addr[1]), slot_raw[0].eq(slot_raw[1])]
        with m.Else():
            m.d.sync += [slot_addr[1].eq(burst_addr[1]), slot_raw[1].eq(burst_raw[1])]
            with m.If(~slot_v[0] | ar_go):
                m.d.sync += [slot_addr[0].eq(burst_addr[0]), slot_raw[0].eq(burst_raw[0])]

        # -- bursts in flight: which line each fills, in AR order ----------------------------------------
        depth = 1 << (2 * Q + 4).bit_length()
        f_head = Signal(range(depth))
        f_tail = Signal(range(depth))
        sw = max(islot, rslot)

        def fl(slot, raw):                          # a flight entry: the slot, zero-extended, then raw
            return Cat(slot, C(0, sw - len(slot)), C(raw, 1))
        # in LUT RAM, two banks by position parity (a tag check queues up to two bursts: one each)
        flight = []
        for b in range(2):
            m.submodules[f"flight{b}"] = mem = memory.Memory(shape=1 + sw, depth=depth // 2, init=[],
                                                             attrs={"ram_style": "distributed"})
            flight.append((mem.write_port(), mem.read_port(domain="comb")))
        # bursts are queued in tag-check order, the order they leave on AR and come back on R
        first = Signal(1 + sw)
        second = Signal(1 + sw)
        queue = take & (nmiss != 0)
        m.d.comb += [first.eq(Mux(l_raw, fl(slotr, 1), Mux(miss0, fl(slot0, 0), fl(slot1, 0)))),
                     second.eq(fl(slot1, 0))]
        # written one cycle behind the check, from a write register per bank (``take`` reaches no
        # write enable of the LUT RAM). The entry of the burst being filled is a register of its own
        # (``flight_head_entry``: the fill's row update and the line RAM's write address start from
        # flip-flops, not from the queue's LUT RAM read multiplexers), loaded every cycle with the
        # entry at the next cycle's ``f_head`` (``f_head + 1`` after a last beat): each bank reads
        # the one of ``f_head``, ``f_head + 1`` of its parity, the pending write forwarded. A burst's
        # AR leaves at least a cycle after its check, when its entry is in the write register, and
        # its first beat at least a cycle after that, when the register holds the entry.
        f_head1 = Signal(range(depth), init=1, name="flight_head_after")     # f_head + 1
        t1 = (f_tail + 1)[:len(f_tail)]
        ahead = []
        for b, (wp, rp) in enumerate(flight):
            mine = f_tail[0] == b
            w = _Behind(m, wp, len(f_tail) - 1, 1 + sw, f"flight{b}")
            w.write(m, Mux(mine, f_tail >> 1, t1 >> 1), Mux(mine, first, second), queue & (mine | (nmiss == 2)))
            row = Signal(len(f_tail) - 1, name=f"flight{b}_read_row")
            m.d.comb += [row.eq(Mux(f_head[0] == b, f_head >> 1, f_head1 >> 1)), rp.addr.eq(row)]
            pend, d = w.pending(row)
            ahead.append(Mux(pend, d, rp.data))
        with m.If(queue):
            m.d.sync += f_tail.eq(Mux(nmiss == 2, f_tail + 2, f_tail + 1))
        cur = Signal(1 + sw, name="flight_head_entry")
        last = self.axi.rvalid & self.axi.rlast
        m.d.sync += cur.eq(Mux(f_head[0] ^ last, ahead[1], ahead[0]))
        beat = Signal(range(max(beats) + 1))
        cur_raw = cur[-1]
        cur_slot = cur[:-1]
        with m.If(self.axi.rvalid):
            m.d.sync += beat.eq(Mux(self.axi.rlast, 0, beat + 1))
        with m.If(last):
            m.d.sync += [f_head.eq(f_head1), f_head1.eq(f_head1 + 1)]

        # -- line RAMs: a row per beat --------------------------------------------------------------------
        # The index lines in two banks, so that words w and w + 1 come from one read port each (a
        # block RAM has two ports: one writes, one reads): they lie in one row, or in consecutive
        # beats of a line, or in the last beat of a line and the first of the next set's: banks by
        # row parity, or by set parity when a line is one beat.
        kbit = 0 if beats[0] > 1 else _log2(ic.ways)
        ibank = []
        for b in range(2):
            m.submodules[f"index_lines{b}"] = mem = memory.Memory(
                shape=bus_bits, depth=ic.sets * ic.ways * beats[0] // 2, init=[])
            ibank.append((mem.write_port(), mem.read_port()))

        def split(row):                             # a row -> (its bank, its address in the bank)
            return row[kbit], Cat(row[:kbit], row[kbit + 1:])
        irow0, irow1, wrow = (Signal(islot + max(1, _log2(beats[0])), name=n) for n in ("irow0", "irow1", "wrow"))
        m.d.comb += [irow0.eq(headv.slot0[:islot] * beats[0] + headv.beat0),
                     irow1.eq(headv.slot1 * beats[0] + headv.beat1), wrow.eq(cur_slot[:islot] * beats[0] + beat)]
        (p0, a0_), (p1, a1_), (pw, aw_) = split(irow0), split(irow1), split(wrow)
        for b, (wp, rp) in enumerate(ibank):
            m.d.comb += [wp.addr.eq(aw_), wp.data.eq(self.axi.rdata), wp.en.eq(self.axi.rvalid & ~cur_raw & (pw == b)),
                         rp.addr.eq(Mux(p0 == b, a0_, a1_)), rp.en.eq(pop)]
        m.submodules.raw_lines = rram = memory.Memory(shape=bus_bits, depth=rc.sets * rc.ways * beats[1], init=[])
        rw, rr = rram.write_port(), rram.read_port()
        m.d.comb += [
            rw.addr.eq(cur_slot[:rslot] * beats[1] + beat), rw.data.eq(self.axi.rdata),
            rw.en.eq(self.axi.rvalid & cur_raw),
            rr.addr.eq(headv.slot0[:rslot] * beats[1] + headv.beat0), rr.en.eq(pop),
        ]

        # -- the fills: a burst's last beat makes its line readable from the next cycle ----------------
        ic.fill_line(m, cur_slot[:islot], last & ~cur_raw)
        rc.fill_line(m, cur_slot[:rslot], last & cur_raw)

        # -- the output register (the RAMs' read registers, and what goes with them) -------------------------
        o_raw = Signal()
        o_bank = Signal(2)                          # the index banks holding w and w + 1
        o_off0 = Signal.like(headv.off0)
        o_off1 = Signal.like(headv.off1)
        o_tag = Signal(max(1, self._tag_width))
        with m.If(pop):
            m.d.sync += [self.o.valid.eq(1), o_raw.eq(headv.raw), o_off0.eq(headv.off0), o_off1.eq(headv.off1),
                         o_tag.eq(headv.tag), o_bank.eq(Cat(p0, p1))]
        with m.Elif(self.o.ready):
            m.d.sync += self.o.valid.eq(0)
        wbits = self._word_bits
        ir0 = Mux(o_bank[0], ibank[1][1].data, ibank[0][1].data)
        ir1 = Mux(o_bank[1], ibank[1][1].data, ibank[0][1].data)
        m.d.comb += [
            self.o.p.raw.eq(o_raw),
            self.o.p.word0.eq(Mux(o_raw, rr.data.word_select(o_off0, 32),
                                  ir0.word_select(o_off0[:max(1, _log2(bus // wb))], wbits))),
            self.o.p.word1.eq(ir1.word_select(o_off1, wbits)),
        ]
        if self._tag_width:
            m.d.comb += self.o.p.tag.eq(o_tag)
        return m
