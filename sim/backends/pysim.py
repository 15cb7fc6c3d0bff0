"""The ``pysim`` backend: ``hw.texel_fetch.TexelFetch`` in Amaranth's own simulator.

One async testbench drives the request stream back to back, drives ``o.ready`` from
:func:`sim.streams.ready_pattern`, collects the responses, checks their tags (in order, none lost or
duplicated) and counts cycles, stall strobes, straddles and per-stage valid bits, one loop iteration
per clock cycle (cycle 0 is the first cycle the first request is presented).

About 1e4 cycles per second: for unit tests and small traces. Set ``VQTEX_VCD=path.vcd`` to write a
waveform (large memories make large files).
"""

from __future__ import annotations

import os

import numpy as np
from amaranth import Cat, Module, Signal
from amaranth.sim import Simulator

from vqtex.golden.format import TextureSet
from vqtex.hw.texel_fetch import LATENCY, REGISTERS, TexelFetch

from .interface import SimResult
from ..streams import pattern_length, ready_pattern

__all__ = ["run", "TAG_WIDTH"]

#: Tag width of the simulated unit: request n carries tag ``n mod 2**TAG_WIDTH``.
TAG_WIDTH = 8


class SimulationError(RuntimeError):
    """The RTL broke the stream contract (a response out of order, lost or duplicated)."""


def _pack_requests(dut: TexelFetch, req: np.ndarray) -> list:
    layout = dut.i.payload.shape()
    tags = np.arange(len(req), dtype=np.int64) & ((1 << TAG_WIDTH) - 1)
    packed = np.zeros(len(req), dtype=object)
    for col, name in enumerate(("texture", "level", "i", "j")):
        packed += req[:, col].astype(object) << layout[name].offset
    packed += tags.astype(object) << layout["tag"].offset
    return packed.tolist()


def run(ts: TextureSet, requests: np.ndarray, *, stall: float = 0.0, seed: int = 0,
        one_port: bool = False, vcd: str | None = None, bank_depth: int | None = None,
        specialise: bool = True) -> SimResult:
    """Simulate ``requests`` ((N, 4) int) on ``TexelFetch(ts, one_port=one_port, specialise=specialise)``
    (with ``bank_depth``, if given: small banks put the bank select to work on small texture sets).

    Raises
    ------
    SimulationError
        If a response's tag is not the next expected one.
    """
    req = np.asarray(requests, dtype=np.int64).reshape(-1, 4)
    n = len(req)
    if n == 0:
        return SimResult(responses=np.zeros((0, 4), np.uint8), cycles=0, requests=0, latency=LATENCY,
                         stall_cycles={"output_backpressure": 0, "one_port_straddle": 0}, straddles=0,
                         occupancy=None)
    unit = {} if bank_depth is None else {"bank_depth": bank_depth}
    dut = TexelFetch(ts, one_port=one_port, tag_width=TAG_WIDTH, specialise=specialise, **unit)
    packed = _pack_requests(dut, req)
    rlayout = dut.o.payload.shape()
    fields = {name: rlayout[name].offset for name in ("r", "g", "b", "a", "tag")}
    nstages = len(REGISTERS)
    # Everything the testbench watches, gathered into one signal inside the simulated design so
    # that each cycle costs one signal read instead of an expression evaluation.
    watched = Cat(dut.i.ready, dut.o.valid, dut.straddle, dut.stall_one_port,
                  dut.valid, dut.o.payload.as_value())
    observe = Signal(len(watched), name="observe")
    top = Module()
    top.submodules.texel_fetch = dut
    top.d.comb += observe.eq(watched)
    pshift = 4 + nstages
    stage_mask = (1 << nstages) - 1

    out = np.zeros((n, 4), np.uint8)
    stats = {"cycles": 0, "backpressure": 0, "one_port": 0, "straddles": 0,
             "occupancy": np.zeros(nstages, np.int64)}

    i_payload, i_valid, o_ready = dut.i.payload.as_value(), dut.i.valid, dut.o.ready

    async def bench(ctx):
        ready = ready_pattern(seed, stall, pattern_length(n, stall, 2 * dut.latency))
        ready_list = ready.tolist()
        n_in = n_out = cycle = 0
        shown = -1               # request currently on i.payload
        last_ready = None
        occ = [0] * nstages
        backpressure = one_port_stalls = straddles = 0
        while n_out < n:
            if n_in != shown:
                if n_in < n:
                    ctx.set(i_payload, packed[n_in])
                    ctx.set(i_valid, 1)
                else:
                    ctx.set(i_valid, 0)
                shown = n_in
            if cycle >= len(ready_list):
                ready_list = ready_pattern(seed, stall, 2 * len(ready_list)).tolist()
            r = ready_list[cycle]
            if r != last_ready:
                ctx.set(o_ready, r)
                last_ready = r
            v = ctx.get(observe)
            if v & 2:
                if r:
                    p = v >> pshift
                    tag = (p >> fields["tag"]) & ((1 << TAG_WIDTH) - 1)
                    if tag != n_out & ((1 << TAG_WIDTH) - 1):
                        raise SimulationError(f"cycle {cycle}: response tag {tag}, expected "
                                              f"{n_out & ((1 << TAG_WIDTH) - 1)} (response {n_out})")
                    out[n_out] = [(p >> fields[c]) & 0xFF for c in "rgba"]
                    n_out += 1
                else:
                    backpressure += 1
            if v & 4:
                straddles += 1
            if v & 8:
                one_port_stalls += 1
            valids = (v >> 4) & stage_mask
            if valids:
                for s in range(nstages):
                    if valids >> s & 1:
                        occ[s] += 1
            if v & 1 and n_in < n:
                n_in += 1
            cycle += 1
            await ctx.tick()
        stats.update(cycles=cycle, backpressure=backpressure, one_port=one_port_stalls,
                     straddles=straddles, occupancy=np.array(occ))

    sim = Simulator(top)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    vcd = vcd or os.environ.get("VQTEX_VCD")
    if vcd:
        with sim.write_vcd(vcd):
            sim.run()
    else:
        sim.run()
    cycles = stats["cycles"]
    occupancy = ({name: float(c) / cycles for name, c in zip(REGISTERS, stats["occupancy"])}
                 if cycles else None)
    return SimResult(
        responses=out, cycles=cycles, requests=n, latency=dut.latency,
        stall_cycles={"output_backpressure": stats["backpressure"], "one_port_straddle": stats["one_port"]},
        straddles=stats["straddles"], occupancy=occupancy,
    )
