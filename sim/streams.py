"""Stream helpers shared by the simulation backends: the backpressure pattern and pysim testbench
helpers for ``amaranth.lib.stream`` interfaces.

The backpressure pattern
------------------------
``o.ready`` in cycle ``t`` (cycle 0 is the first cycle the first request is presented) is
``ready_pattern(seed, stall, n)[t]`` = ``numpy.random.default_rng(seed).random(n)[t] >= stall``.
numpy's generator draws its doubles in sequence, so the pattern is one infinite sequence per
``(seed, stall)`` and any two lengths agree on their common prefix: a backend that runs out of
pattern asks for a longer one. ``stall = 0`` is "always ready". Every backend (golden cycle model,
pysim, cxxrtl, verilator) is fed this same array.
"""

from __future__ import annotations

import numpy as np

__all__ = ["ready_pattern", "pattern_length", "stream_put", "stream_get", "stream_get_with_backpressure",
           "run_lockstep"]


def ready_pattern(seed: int, stall: float, ncycles: int) -> np.ndarray:
    """``o.ready`` for cycles ``0 .. ncycles-1``: bool array, ``rng.random(n) >= stall``.

    Raises
    ------
    ValueError
        If ``stall`` is not in [0, 1) or ``ncycles`` is negative.
    """
    stall = float(stall)
    if not 0.0 <= stall < 1.0:
        raise ValueError(f"stall probability {stall} must be in [0, 1)")
    if ncycles < 0:
        raise ValueError("ncycles must be non-negative")
    if stall == 0.0:
        return np.ones(int(ncycles), dtype=bool)
    return np.random.default_rng(seed).random(int(ncycles)) >= stall


def pattern_length(n_requests: int, stall: float, slack: int) -> int:
    """A first guess at the pattern length that lets ``n_requests`` transfer (a backend doubles it
    while it is too short): the expected cycles with 25% margin plus ``slack``."""
    return int(n_requests / (1.0 - stall) * 1.25) + int(slack) + 64


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


async def stream_get_with_backpressure(ctx, stream, ready):
    """Receive payloads from ``stream`` forever, driving ``ready`` from the iterable ``ready`` one
    value per cycle; an async generator of the payloads in order."""
    for r in ready:
        ctx.set(stream.ready, int(bool(r)))
        _, _, valid, payload = await ctx.tick().sample(stream.valid, stream.payload)
        if r and valid:
            yield payload


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
