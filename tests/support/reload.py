"""A reload while requests are in flight, on pysim: the loadable cached unit's and the loadable
filter through memory's drain-rule tests share this bench (one loop, not one per unit)."""

from __future__ import annotations

from amaranth.sim import Simulator

from vqtex.golden.register_map import load_cycles
from vqtex.sim.backends import pysim


def reload_mid_stream(dut, slave, packed, first, second, *, tag_bits: int, limit: int) -> tuple[dict, int]:
    """Load ``first`` (bus writes, ``golden.register_map.load_writes``) into ``dut`` over its bus
    port, then stream the packed requests ``packed`` through ``dut.i`` with ``dut.o.ready`` high and
    ``slave`` (a ``sim.backends.axi_memory.AxiMemory``) answering ``dut.axi``; a second testbench
    starts writing ``second`` 20 cycles after the first load's own cycles, while requests are in
    flight. ``dut`` is a loadable cached unit or filter (``i``/``o`` streams whose output payload
    holds r, g, b, a and a tag of ``tag_bits`` counting responses, ``bus``, ``axi``).

    Checks the drain rule: the writes went in (some ``ack``), every request accepted before the
    first write left before it, and none was accepted until the last write's ``ack``; every
    response arrived in order (the tags), within ``limit`` cycles. Returns the log (``rgba``: one
    [r, g, b, a] per response; ``accept``, ``transfer``, ``ack``: cycles) and ``k``, the number of
    requests served from the first load."""
    n = len(packed)
    rlay = dut.o.p.shape()
    log = {"accept": [], "transfer": [], "rgba": [], "ack": []}

    async def bench(ctx):
        await pysim.load_over_bus(ctx, dut.bus, first)
        n_in = n_out = cycle = 0
        slave.start(ctx, dut.axi)
        ctx.set(dut.o.ready, 1)
        while n_out < n:
            assert cycle < limit, "hung"
            ctx.set(dut.i.valid, int(n_in < n))
            if n_in < n:
                ctx.set(dut.i.p.as_value(), packed[n_in])
            slave.step(ctx, dut.axi, cycle)
            if ctx.get(dut.o.valid):
                p = ctx.get(dut.o.p.as_value())
                assert (p >> rlay["tag"].offset) & ((1 << tag_bits) - 1) == n_out % (1 << tag_bits)
                log["rgba"].append([(p >> rlay[c].offset) & 255 for c in "rgba"])
                log["transfer"].append(cycle)
                n_out += 1
            if n_in < n and ctx.get(dut.i.ready):
                log["accept"].append(cycle)
                n_in += 1
            if ctx.get(dut.bus.ack):
                log["ack"].append(cycle)
            cycle += 1
            await ctx.tick()

    async def host(ctx):
        await ctx.tick().repeat(load_cycles(len(first)) + 20)
        await pysim.load_over_bus(ctx, dut.bus, second)

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.add_testbench(host)
    sim.run()
    assert log["ack"], "the reload never got in"
    first_ack = min(log["ack"])
    k = sum(t < first_ack for t in log["accept"])       # requests accepted before the writes
    assert 0 < k < n and len(log["rgba"]) == n
    assert max(log["transfer"][:k]) < first_ack         # drained first
    assert min(log["accept"][k:]) > max(log["ack"])     # none entered during the load
    return log, k
