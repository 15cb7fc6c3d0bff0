"""Testbench helpers for Amaranth's simulator: a stream's put and get (async testbenches) and a
lockstep driver for the pipelined datapath stages."""

from __future__ import annotations

import numpy as np


async def stream_put(ctx, stream, payload):
    """Present ``payload`` on ``stream`` (valid high) until it transfers; returns after the transfer
    cycle's clock edge with ``valid`` low again."""
    ctx.set(stream.valid, 1)
    ctx.set(stream.payload, payload)
    await ctx.tick().until(stream.ready)
    ctx.set(stream.valid, 0)


async def stream_get(ctx, stream):
    """Raise ``ready`` until ``stream`` transfers; return the payload (lowers ``ready`` after)."""
    ctx.set(stream.ready, 1)
    payload, = await ctx.tick().sample(stream.payload).until(stream.valid)
    ctx.set(stream.ready, 0)
    return payload


def run_lockstep(dut, inputs: dict, outputs: list, latency: int, *, en: str = "en",
                 en_pattern=None, hold: str | None = None, seed: int = 0) -> dict:
    """Drive a pipelined datapath block (an ``en`` input, no valid/ready) with one input vector per
    enabled cycle and collect its outputs; for stage unit tests.

    ``inputs`` maps port names of ``dut`` to lists of ints (one per item); ``outputs`` names the
    ports to read. The item fed in the e-th cycle with ``en`` high appears on the outputs after
    ``latency`` enabled cycles. ``en_pattern`` (iterable of bools, default all high) drops ``en`` in
    some cycles: the inputs then carry another (random) item's values and the outputs must hold.
    ``hold`` names a combinational output (the one-port index reader's): while it is high in an
    enabled cycle, the block keeps the item it took in the previous enabled cycle in its first
    stage, a bubble goes down the pipeline ahead of that item, and the inputs are not taken (the
    same item is presented again).

    Returns ``{name: [int per item]}``.
    """
    from amaranth.sim import Simulator
    from amaranth.hdl import Value

    def port(name):
        p = getattr(dut, name)
        return p if isinstance(p, Value) else p.as_value()

    in_ports = {name: port(name) for name in inputs}
    out_ports = {name: port(name) for name in outputs}
    n = len(next(iter(inputs.values()))) if inputs else 0
    results = {name: [None] * n for name in outputs}
    rng = np.random.default_rng(seed)
    pattern = iter(en_pattern) if en_pattern is not None else None

    async def bench(ctx):
        item = 0              # next item to feed
        fed = []              # per enabled cycle: the item fed, or None (a bubble or held item)
        last = None           # position of item n-1 in ``fed``
        enabled = 0
        while n:
            if enabled >= latency:
                pos = enabled - latency
                if fed[pos] is not None:
                    for name, p in out_ports.items():
                        results[name][fed[pos]] = ctx.get(p)
                if last is not None and pos >= last:
                    break
            on = True if pattern is None else bool(next(pattern, True))
            src = item if (on and item < n) else int(rng.integers(0, n))
            for name, p in in_ports.items():
                ctx.set(p, int(inputs[name][src]))
            ctx.set(port(en), int(on))
            if on:
                held = hold is not None and ctx.get(port(hold))
                if held:                    # a bubble goes ahead of the item in the first stage
                    fed.insert(len(fed) - 1, None)
                    if last is not None:
                        last += 1
                elif item < n:
                    fed.append(item)
                    if item == n - 1:
                        last = len(fed) - 1
                    item += 1
                else:
                    fed.append(None)
                enabled += 1
            await ctx.tick()

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    return results
