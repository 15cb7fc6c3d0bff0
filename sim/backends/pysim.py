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
from vqtex.hw.texel_fetch import REGISTERS, TexelFetch

from .interface import SimResult
from ..streams import pattern_length, ready_pattern

__all__ = ["run", "run_phases", "bus_transfers", "TAG_WIDTH"]

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
        specialise: bool = True, geometry=None) -> SimResult:
    """Simulate ``requests`` ((N, 4) int) on ``TexelFetch(ts, one_port=one_port, specialise=specialise)``
    (with ``bank_depth``, if given: small banks put the bank select to work on small texture sets).
    With ``geometry`` (a :class:`golden.geometry.Geometry`), the loadable unit of that geometry: the
    set is loaded by bus writes first (:func:`run_phases`), and ``load_cycles`` reports them.

    Raises
    ------
    SimulationError
        If a response's tag is not the next expected one.
    """
    if geometry is not None:
        return run_phases(geometry, [(ts, requests)], stall=stall, seed=seed, one_port=one_port, vcd=vcd,
                          bank_depth=bank_depth)[0]
    unit = {} if bank_depth is None else {"bank_depth": bank_depth}
    dut = TexelFetch(ts, one_port=one_port, tag_width=TAG_WIDTH, specialise=specialise, **unit)
    return _simulate(dut, [(None, requests)], stall=stall, seed=seed, vcd=vcd)[0]


def run_phases(geometry, phases, *, stall: float = 0.0, seed: int = 0, one_port: bool = False,
               vcd: str | None = None, bank_depth: int | None = None) -> list:
    """One simulation of the loadable unit of ``geometry`` through ``phases``: for each ``(ts,
    requests)``, ``ts`` is loaded by the bus writes of :func:`golden.register_map.load_writes` (no
    load when ``ts`` is None), then the requests run (as :func:`run` runs them, the backpressure
    pattern restarting at each phase's first request). Returns a :class:`SimResult` per phase, with
    ``load_cycles``."""
    from vqtex.golden.register_map import load_writes
    unit = {} if bank_depth is None else {"bank_depth": bank_depth}
    dut = TexelFetch(geometry=geometry, loadable=True, one_port=one_port, tag_width=TAG_WIDTH, **unit)
    program = [(None if ts is None else load_writes(ts, geometry), req) for ts, req in phases]
    return _simulate(dut, program, stall=stall, seed=seed, vcd=vcd)


async def bus_transfers(ctx, bus, ops) -> tuple:
    """The Wishbone master of the simulations: ``ops`` ((N, 3) ints: word address, data, write)
    issued back to back in one bus cycle (``cyc`` high throughout, ``stb`` while transfers remain,
    the next presented when ``stall`` is low), until every one is answered; then ``cyc`` drops and
    one more cycle lets the unit's ``pause`` clear. Returns (data, err) per transfer and the
    cycles spent (``golden.register_map.load_cycles`` of N on an idle unit)."""
    ops = [tuple(int(v) for v in op) for op in ops]
    n = len(ops)
    data, err = [0] * n, [False] * n
    sent = got = cycles = 0
    ctx.set(bus.cyc, 1)
    ctx.set(bus.sel, 1)
    shown = -1
    while got < n:
        if sent != shown:
            if sent < n:
                a, d, we = ops[sent]
                ctx.set(bus.adr, a)
                ctx.set(bus.dat_w, d)
                ctx.set(bus.we, we)
                ctx.set(bus.stb, 1)
            else:
                ctx.set(bus.stb, 0)
            shown = sent
        if ctx.get(bus.ack) or ctx.get(bus.err):
            data[got], err[got] = ctx.get(bus.dat_r), bool(ctx.get(bus.err))
            got += 1
        if sent < n and not ctx.get(bus.stall):
            sent += 1
        cycles += 1
        await ctx.tick()
    ctx.set(bus.cyc, 0)
    ctx.set(bus.stb, 0)
    await ctx.tick()
    return data, err, cycles + 1


def _simulate(dut: TexelFetch, program, *, stall: float, seed: int, vcd: str | None) -> list:
    """Run ``program`` (a list of (bus writes or None, requests)) on ``dut`` in one simulation."""
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
    rlayout = dut.o.payload.shape()
    fields = {name: rlayout[name].offset for name in ("r", "g", "b", "a", "tag")}
    i_payload, i_valid, o_ready = dut.i.payload.as_value(), dut.i.valid, dut.o.ready
    results = []

    async def requests_phase(ctx, req):
        n = len(req)
        out = np.zeros((n, 4), np.uint8)
        if n == 0:
            return out, {"cycles": 0, "backpressure": 0, "one_port": 0, "straddles": 0, "occupancy": None}
        packed = _pack_requests(dut, req)
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
        ctx.set(i_valid, 0)
        ctx.set(o_ready, 0)
        return out, {"cycles": cycle, "backpressure": backpressure, "one_port": one_port_stalls,
                     "straddles": straddles, "occupancy": np.array(occ)}

    async def bench(ctx):
        for writes, requests in program:
            load_cycles = None
            if writes is not None:
                ops = np.concatenate([writes, np.ones((len(writes), 1), writes.dtype)], axis=1)
                _, err, load_cycles = await bus_transfers(ctx, dut.bus, ops)
                if any(err):
                    raise SimulationError(f"bus write {err.index(True)} of the load answered with err")
            req = np.asarray(requests, dtype=np.int64).reshape(-1, 4)
            out, stats = await requests_phase(ctx, req)
            cycles = stats["cycles"]
            occupancy = ({name: float(c) / cycles for name, c in zip(REGISTERS, stats["occupancy"])}
                         if cycles else None)
            results.append(SimResult(
                responses=out, cycles=cycles, requests=len(req), latency=dut.latency,
                stall_cycles={"output_backpressure": stats["backpressure"], "one_port_straddle": stats["one_port"]},
                straddles=stats["straddles"], occupancy=occupancy, load_cycles=load_cycles))

    sim = Simulator(top)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    vcd = vcd or os.environ.get("VQTEX_VCD")
    if vcd:
        with sim.write_vcd(vcd):
            sim.run()
    else:
        sim.run()
    return results
