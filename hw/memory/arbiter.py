"""AxiArbiter: several AXI4 read masters (the texture filter's lanes' caches) onto one.

Twin of :mod:`golden.memory.arbiter` (the rule, docs/memory.md "The texture filter through the memory
system")::

    ports[0..N-1] (AR, R) --> queue of ARs in (cycle, lane) order --> axi (one AR per cycle)
                         <-- R beats routed by a queue of lane numbers <--

* **AR**: every port's ``arready`` is high (an offered AR is taken in the cycle it is offered, so each
  cache's timing is its own). When the queue is empty, the lowest-numbered offering port's AR goes
  straight to the master in the same cycle; every other offer of the cycle is queued in port order,
  and the queue's head is offered to the master, one per cycle. So ``issue[b] = max(offer[b],
  issue[b-1] + 1)`` over the offers in (cycle, port) order, with ``axi.arready`` high; a low
  ``axi.arready`` holds the head (and queues every offer).
* **R**: one ID, bursts come back in issue order; the port of every issued AR is queued, and each R
  beat goes to the port at the head of that queue (``rvalid`` to it alone; data, ``rlast`` and
  ``rresp`` to all), which is popped at ``rlast``. ``axi.rready`` is high (every cache takes its beats
  as they come).

Storage: both queues are LUT RAM (``amaranth.lib.memory.Memory``, ``ram_style`` distributed, one write
port and one asynchronous read port each, as a LUT RAM has), not flip-flops: the AR queue in ``nb``
banks (``nb``: ``ports`` rounded up to a power of two) by position mod ``nb``, so the up to ``ports``
offers a cycle pushes, at consecutive positions, land in different banks; the head is read from its
bank. (In flip-flops the 4-lane filter's 2,048-entry queues at a FIFO of 128 ran Yosys out of memory.)

Latency: none (a combinational path from a port's AR to the master's when nothing waits).
Throughput: one AR per cycle. ``depth``: entries of each queue (a power of two); the caller sizes it to
the bursts that can be in flight (a :class:`hw.memory.reader.CachedReader` has at most two per FIFO
entry and two in its AR slots); ``overflow`` is a strobe that must stay low.

Members
-------
ports : list of In(axi4_read_signature(addr_width, data_width))
axi : Out(axi4_read_signature(addr_width, data_width))
overflow : Out(1)
"""

from __future__ import annotations

from amaranth import *
from amaranth.lib import data, memory, wiring
from amaranth.lib.wiring import In, Out

from .axi import axi4_read_signature

__all__ = ["AxiArbiter"]


class AxiArbiter(wiring.Component):
    __doc__ = __doc__

    def __new__(cls, ports: int, *, depth: int = 64, **kwargs):
        # checked before the instance exists (a rejected one is never reported as unused)
        if ports < 1:
            raise ValueError(f"an arbiter of {ports} ports")
        if depth < 2 or depth & (depth - 1):
            raise ValueError(f"queue depth {depth} must be a power of two, at least 2")
        if depth < 1 << (ports - 1).bit_length():
            raise ValueError(f"queue depth {depth} is below the {ports} ports rounded up to a power of two")
        return super().__new__(cls)

    def __init__(self, ports: int, *, addr_width: int = 32, data_width: int = 128, depth: int = 64):
        self._n = ports
        self._depth = depth
        self._aw = addr_width
        sig = axi4_read_signature(addr_width, data_width)
        super().__init__({
            **{f"port{k}": In(sig) for k in range(ports)},
            "axi": Out(sig),
            "overflow": Out(1),
        })

    @property
    def ports(self) -> list:
        return [getattr(self, f"port{k}") for k in range(self._n)]

    def elaborate(self, platform):
        m = Module()
        n, depth = self._n, self._depth
        ports = self.ports
        lane_bits = max(1, (n - 1).bit_length())
        entry = data.StructLayout({"addr": self._aw, "len": 8, "size": 3, "burst": 2, "lane": lane_bits})
        # The AR queue in LUT RAM, in ``nb`` banks by position (position mod nb): a cycle pushes at
        # most ``n <= nb`` offers, at consecutive positions, so each bank takes at most one (one write
        # port, what a LUT RAM has); the head is read asynchronously from its bank.
        nb = 1 << (n - 1).bit_length()
        sb = (nb - 1).bit_length()                  # position bits that name the bank
        banks = []
        for b in range(nb):
            mem = memory.Memory(shape=entry, depth=depth // nb, init=[], attrs={"ram_style": "distributed"})
            m.submodules[f"ar_queue{b}" if nb > 1 else "ar_queue"] = mem
            banks.append((mem.write_port(), mem.read_port(domain="comb")))
        head = Signal(range(depth))
        tail = Signal(range(depth))
        count = Signal(range(depth + 1))
        empty = Signal()
        m.d.comb += empty.eq(count == 0)

        offer = [Signal(entry, name=f"offer{k}") for k in range(n)]
        for k, p in enumerate(ports):
            m.d.comb += [p.arready.eq(1), offer[k].addr.eq(p.araddr), offer[k].len.eq(p.arlen),
                         offer[k].size.eq(p.arsize), offer[k].burst.eq(p.arburst), offer[k].lane.eq(k)]
        # the lowest offering port (passed through when the queue is empty)
        first = Signal(entry)
        any_offer = Signal()
        m.d.comb += any_offer.eq(Cat(*(p.arvalid for p in ports)).any())
        for k in reversed(range(n)):
            with m.If(ports[k].arvalid):
                m.d.comb += first.eq(offer[k])
        q_head = Signal(entry, name="ar_queue_head")
        for b, (_, rp) in enumerate(banks):
            m.d.comb += rp.addr.eq(head >> sb)
        if nb > 1:
            m.d.comb += q_head.eq(Array(rp.data for _, rp in banks)[head[:sb]])
        else:
            m.d.comb += q_head.eq(banks[0][1].data)
        out = Signal(entry)
        m.d.comb += [
            out.eq(Mux(empty, first, q_head)),
            self.axi.arvalid.eq(~empty | any_offer),
            self.axi.araddr.eq(out.addr), self.axi.arlen.eq(out.len), self.axi.arsize.eq(out.size),
            self.axi.arburst.eq(out.burst),
        ]
        go = Signal()
        m.d.comb += go.eq(self.axi.arvalid & self.axi.arready)
        bypass = Signal()
        m.d.comb += bypass.eq(empty & go)
        # push the offers in port order, less the one passed through: the j-th pushed offer of the
        # cycle goes to position tail + j, in bank (tail + j) mod nb
        pushed = C(0, range(n + 1))
        seen = C(0, 1)                  # an earlier port offered (so this one is not the first)
        push, rank = [], []
        for k, p in enumerate(ports):
            push.append(Signal(name=f"push{k}"))
            rank.append(Signal(range(n + 1), name=f"rank{k}"))
            m.d.comb += [push[k].eq(p.arvalid & ~(bypass & ~seen)), rank[k].eq(pushed)]
            pushed = pushed + push[k]
            seen = seen | p.arvalid
        npush = Signal(range(n + 1))
        m.d.comb += npush.eq(pushed)
        for b, (wp, _) in enumerate(banks):
            j = Signal(range(nb), name=f"ar_queue{b}_rank")     # which pushed offer lands in bank b
            pos = Signal(range(depth), name=f"ar_queue{b}_pos")
            m.d.comb += [j.eq((b - tail[:sb]) if nb > 1 else 0), pos.eq(tail + j)]
            m.d.comb += [wp.addr.eq(pos >> sb), wp.en.eq(npush > j)]
            for k in range(n):
                with m.If(push[k] & (rank[k] == j)):
                    m.d.comb += wp.data.eq(offer[k])
        pop = Signal()
        m.d.comb += pop.eq(~empty & go)
        m.d.sync += [tail.eq(tail + npush), head.eq(head + pop), count.eq(count + npush - pop)]
        m.d.comb += self.overflow.eq(count + npush - pop > depth)

        # -- R: the port of every issued burst, in order (LUT RAM: one write, one asynchronous read) ---
        m.submodules.r_lanes = rmem = memory.Memory(shape=lane_bits, depth=depth, init=[],
                                                    attrs={"ram_style": "distributed"})
        rw, rr = rmem.write_port(), rmem.read_port(domain="comb")
        rh = Signal(range(depth))
        rt = Signal(range(depth))
        m.d.comb += [rw.addr.eq(rt), rw.data.eq(out.lane), rw.en.eq(go)]
        with m.If(go):
            m.d.sync += rt.eq(rt + 1)
        rlane = Signal(lane_bits)
        m.d.comb += [rr.addr.eq(rh), rlane.eq(rr.data)]
        with m.If(self.axi.rvalid & self.axi.rlast):
            m.d.sync += rh.eq(rh + 1)
        m.d.comb += self.axi.rready.eq(1)
        for k, p in enumerate(ports):
            m.d.comb += [p.rvalid.eq(self.axi.rvalid & (rlane == k)), p.rdata.eq(self.axi.rdata),
                         p.rlast.eq(self.axi.rlast), p.rresp.eq(self.axi.rresp)]
        return m
