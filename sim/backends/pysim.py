"""The ``pysim`` backend: ``hw.texel_fetch.TexelFetch`` in Amaranth's own simulator.

One async testbench (:func:`run_stream`, which runs the texture filter too: :mod:`sim.backends.filter`)
drives the request stream back to back, drives ``o.ready`` from :func:`sim.streams.ready_pattern`,
collects the responses, checks their tags (in order, none lost or duplicated) and counts cycles,
the unit's strobes (stalls, straddles, ...) and per-stage valid bits, one loop iteration per clock
cycle (cycle 0 is the first cycle the first request is presented).

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

__all__ = ["run", "run_phases", "run_stream", "pack_rows", "bus_transfers", "load_over_bus", "SimulationError", "TAG_WIDTH"]

#: Tag width of the simulated unit: request n carries tag ``n mod 2**TAG_WIDTH``.
TAG_WIDTH = 8


class SimulationError(RuntimeError):
    """The RTL broke the stream contract (a response out of order, lost or duplicated)."""


def pack_rows(layout, columns, rows: np.ndarray, tag_width: int) -> list:
    """The request payloads (Python ints) of ``rows`` ((n, len(columns)) int: one column per request
    field named in ``columns``) in the request ``layout``; row n carries tag ``n mod 2**tag_width``."""
    rows = np.asarray(rows, np.int64).reshape(-1, len(columns))
    packed = np.zeros(len(rows), dtype=object)
    for col, name in enumerate(columns):
        f = layout[name]
        packed += (rows[:, col] & ((1 << f.width) - 1)).astype(object) << f.offset
    if tag_width:
        packed += (np.arange(len(rows), dtype=np.int64) & ((1 << tag_width) - 1)).astype(object) << layout["tag"].offset
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
    return _texel_fetch(dut, [(None, requests)], stall=stall, seed=seed, vcd=vcd)[0]


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
    return _texel_fetch(dut, program, stall=stall, seed=seed, vcd=vcd)


def _texel_fetch(dut: TexelFetch, program, *, stall: float, seed: int, vcd: str | None) -> list:
    phases = run_stream(dut, [(w, np.asarray(r, dtype=np.int64).reshape(-1, 4)) for w, r in program],
                        columns=("texture", "level", "i", "j"), tag_width=TAG_WIDTH,
                        strobes=("stall_output", "stall_one_port", "straddle"), valid=dut.valid,
                        stall=stall, seed=seed, vcd=vcd, name="texel_fetch")
    out = []
    for ph in phases:
        cycles, st = ph["cycles"], ph["strobes"]
        occupancy = ({name: float(c) / cycles for name, c in zip(REGISTERS, ph["occupancy"])} if cycles else None)
        out.append(SimResult(
            responses=ph["responses"], cycles=cycles, requests=len(ph["responses"]), latency=dut.latency,
            stall_cycles={"output_backpressure": st["stall_output"], "one_port_straddle": st["stall_one_port"]},
            straddles=st["straddle"], occupancy=occupancy, load_cycles=ph["load_cycles"]))
    return out


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



async def load_over_bus(ctx, bus, writes) -> int:
    """The host's load: ``writes`` ((N, 2) ints: word address, data, as
    ``golden.register_map.load_writes`` gives them) by :func:`bus_transfers`; returns the cycles
    spent. A write the unit answers with ``err`` raises :class:`SimulationError`."""
    ops = np.concatenate([writes, np.ones((len(writes), 1), writes.dtype)], axis=1)
    _, err, cycles = await bus_transfers(ctx, bus, ops)
    if any(err):
        raise SimulationError(f"bus write {err.index(True)} of the load answered with err")
    return cycles

def run_stream(dut, program, *, columns, tag_width: int, strobes, valid, stall: float, seed: int,
               vcd: str | None = None, name: str = "dut", step=None) -> list:
    """Run ``program`` on ``dut`` (a unit with ``i``/``o`` streams, ``i.payload`` holding the
    request fields ``columns`` and the tag, ``o.payload`` r, g, b, a and the tag, the 1-bit
    ``strobes`` as attributes, ``valid`` one bit per stage and, for bus phases, ``bus``) in one
    simulation: for each ``(bus writes or None, rows)``, the writes by :func:`bus_transfers`, then
    the request rows back to back. Returns a dict per phase: ``responses`` ((n, 4) uint8 RGBA),
    ``cycles``, ``strobes`` (name -> cycles high), ``occupancy`` (per-stage valid-bit sums, or None
    for no requests), ``load_cycles`` (None without writes). ``step(ctx, cycle)``, if given, is
    called in every cycle of a request phase before the clock edge (an AXI slave's
    :meth:`sim.backends.axi_memory.AxiMemory.step`), ``cycle`` counted from the phase's first."""
    nstages, nstrobes = len(valid), len(strobes)
    # Everything the testbench watches, gathered into one signal inside the simulated design so
    # that each cycle costs one signal read instead of an expression evaluation.
    watched = Cat(dut.i.ready, dut.o.valid, *(getattr(dut, n) for n in strobes), valid, dut.o.payload.as_value())
    observe = Signal(len(watched), name="observe")
    top = Module()
    top.submodules[name] = dut
    top.d.comb += observe.eq(watched)
    vshift = 2 + nstrobes
    pshift = vshift + nstages
    stage_mask = (1 << nstages) - 1
    rlayout = dut.o.payload.shape()
    fields = {name: rlayout[name].offset for name in ("r", "g", "b", "a")}
    tag_off, tag_mask = (rlayout["tag"].offset if tag_width else 0), (1 << tag_width) - 1
    i_payload, i_valid, o_ready = dut.i.payload.as_value(), dut.i.valid, dut.o.ready
    ilayout = dut.i.payload.shape()
    results = []

    async def requests_phase(ctx, req):
        n = len(req)
        out = np.zeros((n, 4), np.uint8)
        if n == 0:
            return out, {"cycles": 0, "strobes": dict.fromkeys(strobes, 0), "occupancy": None}
        packed = pack_rows(ilayout, columns, req, tag_width)
        ready = ready_pattern(seed, stall, pattern_length(n, stall, 2 * dut.latency))
        ready_list = ready.tolist()
        n_in = n_out = cycle = 0
        shown = -1               # request currently on i.payload
        last_ready = None
        occ = [0] * nstages
        sums = [0] * nstrobes
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
            if v & 2 and r:
                p = v >> pshift
                tag = (p >> tag_off) & tag_mask
                if tag != n_out & tag_mask:
                    raise SimulationError(f"cycle {cycle}: response tag {tag}, expected "
                                          f"{n_out & tag_mask} (response {n_out})")
                out[n_out] = [(p >> fields[c]) & 0xFF for c in "rgba"]
                n_out += 1
            if v >> 2 & ((1 << nstrobes) - 1):
                for k in range(nstrobes):
                    sums[k] += v >> (2 + k) & 1
            valids = (v >> vshift) & stage_mask
            if valids:
                for s in range(nstages):
                    if valids >> s & 1:
                        occ[s] += 1
            if v & 1 and n_in < n:
                n_in += 1
            if step is not None:
                step(ctx, cycle)
            cycle += 1
            await ctx.tick()
        ctx.set(i_valid, 0)
        ctx.set(o_ready, 0)
        return out, {"cycles": cycle, "strobes": dict(zip(strobes, sums)), "occupancy": np.array(occ)}

    async def bench(ctx):
        for writes, requests in program:
            load_cycles = None
            if writes is not None:
                load_cycles = await load_over_bus(ctx, dut.bus, writes)
            out, stats = await requests_phase(ctx, np.asarray(requests, dtype=np.int64).reshape(-1, len(columns)))
            results.append({"responses": out, "load_cycles": load_cycles, **stats})

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
