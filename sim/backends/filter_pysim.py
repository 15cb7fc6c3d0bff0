"""The texture filter (``hw.filter.TextureFilter``) in Amaranth's own simulator: tiny cases only
(about 2e3 cycles per second; a trilinear pixel on one lane is 8 cycles).

One async testbench presents the requests back to back, drives ``o.ready`` from
:func:`sim.streams.ready_pattern`, checks every response's tag and counts the cycles and stalls.
``VQTEX_VCD=path.vcd`` writes a waveform.
"""

from __future__ import annotations

import os

import numpy as np
from amaranth import Cat, Module, Signal
from amaranth.sim import Simulator

from vqtex.hw.filter import TextureFilter

from ..streams import pattern_length, ready_pattern
from .filter import FIELDS, FilterResult, texel_slots

__all__ = ["run", "pack_pixels", "TAG_WIDTH"]

#: Tag width of the simulated filter: pixel n carries tag ``n mod 2**TAG_WIDTH``.
TAG_WIDTH = 8


class SimulationError(RuntimeError):
    """The RTL broke the stream contract (a colour out of order, lost or duplicated)."""


def pack_pixels(layout, pixels: dict, tag_width: int) -> list:
    """The request payloads (Python ints) of the pixels in the filter's request ``layout``; pixel n
    carries tag ``n mod 2**tag_width``."""
    n = len(pixels["texture"])
    packed = np.zeros(n, dtype=object)
    for name in FIELDS:
        f = layout[name]
        packed += (np.asarray(pixels[name], np.int64) & ((1 << f.width) - 1)).astype(object) << f.offset
    if tag_width:
        packed += (np.arange(n, dtype=np.int64) & ((1 << tag_width) - 1)).astype(object) << layout["tag"].offset
    return packed.tolist()


def run(ts, pixels: dict, *, lanes: int = 1, frac: int | None = None, stall: float = 0.0, seed: int = 0,
        bank_depth: int | None = None, vcd: str | None = None, index_banks: str = "parity") -> FilterResult:
    """Filter ``pixels`` (checked int64 arrays, :func:`sim.backends.filter.check_pixels`) on
    ``TextureFilter(ts, lanes=lanes, frac=frac)``.

    Raises
    ------
    SimulationError
        If a response's tag is not the next expected one.
    """
    n = len(pixels["texture"])
    unit = {} if bank_depth is None else {"bank_depth": bank_depth}
    dut = TextureFilter(ts, lanes=lanes, tag_width=TAG_WIDTH, frac=frac, index_banks=index_banks, **unit)
    stalls = {"output_backpressure": 0, "input_wait": 0}
    if n == 0:
        return FilterResult(np.zeros((0, 4), np.uint8), 0, 0, 0, lanes, dut.latency, stalls)
    packed = pack_pixels(dut.i.p.shape(), pixels, TAG_WIDTH)
    rl = dut.o.p.shape()
    offs = {c: rl[c].offset for c in ("r", "g", "b", "a", "tag")}
    watched = Cat(dut.i.ready, dut.o.valid, dut.bank_conflict, dut.o.p.as_value())
    observe = Signal(len(watched), name="observe")
    top = Module()
    top.submodules.filter = dut
    top.d.comb += observe.eq(watched)
    out = np.zeros((n, 4), np.uint8)
    stats = {}
    mask = (1 << TAG_WIDTH) - 1

    async def bench(ctx):
        ready = ready_pattern(seed, stall, pattern_length(8 * n, stall, 2 * dut.latency)).tolist()
        n_in = n_out = cycle = 0
        shown = -1
        last_ready = None
        backpressure = waits = conflicts = 0
        while n_out < n:
            if n_in != shown:
                if n_in < n:
                    ctx.set(dut.i.p.as_value(), packed[n_in])
                    ctx.set(dut.i.valid, 1)
                else:
                    ctx.set(dut.i.valid, 0)
                shown = n_in
            if cycle >= len(ready):
                ready = ready_pattern(seed, stall, 2 * len(ready)).tolist()
            r = ready[cycle]
            if r != last_ready:
                ctx.set(dut.o.ready, r)
                last_ready = r
            v = ctx.get(observe)
            if v & 2:
                if r:
                    p = v >> 3
                    tag = (p >> offs["tag"]) & mask
                    if tag != n_out & mask:
                        raise SimulationError(f"cycle {cycle}: colour tag {tag}, expected {n_out & mask} "
                                              f"(pixel {n_out})")
                    out[n_out] = [(p >> offs[c]) & 0xFF for c in "rgba"]
                    n_out += 1
                else:
                    backpressure += 1
            conflicts += (v >> 2) & 1
            if n_in < n:
                if v & 1:
                    n_in += 1
                else:
                    waits += 1
            cycle += 1
            await ctx.tick()
        stats.update(cycles=cycle, backpressure=backpressure, waits=waits, conflicts=conflicts)

    sim = Simulator(top)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    vcd = vcd or os.environ.get("VQTEX_VCD")
    if vcd:
        with sim.write_vcd(vcd):
            sim.run()
    else:
        sim.run()
    return FilterResult(out, stats["cycles"], n, texel_slots(pixels["mode"], lanes), lanes, dut.latency,
                        {"output_backpressure": stats["backpressure"], "input_wait": stats["waits"]},
                        stats["conflicts"])
