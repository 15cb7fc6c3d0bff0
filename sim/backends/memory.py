"""The cached unit (textures in external memory, docs/memory.md) on every backend.

``run(ts, requests, config, backend, stall, seed) -> SimResult`` with ``memory`` filled in:

- ``golden``: responses from :func:`golden.fetch.fetch`, cycles from
  :func:`sim.backends.cycle_model.run_cached` (:mod:`golden.memory.timing`);
- ``pysim``: :class:`hw.memory.unit.CachedTexelFetch` in Amaranth's simulator, its AXI master
  answered by :class:`sim.backends.axi_memory.AxiMemory` from the same memory model; about 2e3
  cycles per second, for small traces;
- ``cxxrtl`` and ``verilator``: the same unit compiled (:func:`sim.backends.design.cached_design_info`,
  built by the backends' one ``build_design`` and run by their batch API), its AXI master answered by
  the drivers' slave (``drivers/axi_slave.h``) from the C++ twin of the same memory model
  (``drivers/memory_model.h``), for long streams and scene frames.

The loadable cached unit (``geometry``: :class:`hw.memory.unit.CachedTexelFetch` with
``loadable=True``) runs the same way after a load: :func:`run_phases` loads each set by the bus
writes of :func:`golden.register_map.load_writes` (descriptors, codebook, matrix, base registers) in
simulated cycles, puts ``layout.image(ts)`` behind the AXI master, then runs its requests; several
sets in one simulation (pysim) or one compiled library (cxxrtl, verilator).

Both report the same ``cycles``, ``stall_cycles`` (``output_backpressure``: ``o.valid & ~o.ready``;
``memory``: cycles the cache block's data read waited for a line fill, which the golden model splits
into ``miss`` and ``bandwidth`` in ``memory["stall_detail"]``), and ``memory``: ``bursts``,
``memory_bytes`` (index, raw), ``bytes_per_texel``, ``references``, ``misses`` and ``hit_rate`` per
cache.
"""

from __future__ import annotations

import numpy as np

from vqtex.golden.fetch import fetch
from vqtex.golden.memory.system import Layout
from vqtex.golden.memory.timing import FRONT_LATENCY, plan

from ..streams import ready_pattern
from .interface import GOLDEN_CHUNK, SimResult

__all__ = ["run", "run_pysim", "run_compiled", "run_phases", "build_cached", "BACKENDS"]

#: Backends that run the cached unit.
BACKENDS = ("golden", "pysim", "cxxrtl", "verilator")


def _memory_report(p, config, bursts_by_cache, n) -> dict:
    lines = (config.index_cache.line, config.raw_cache.line)
    mem_bytes = {"index": int(bursts_by_cache[0]) * lines[0], "raw": int(bursts_by_cache[1]) * lines[1]}
    refs = {"index": p.references[0], "raw": p.references[1]}
    return {
        "configuration": config.describe(),
        "bursts": int(sum(bursts_by_cache)),
        "memory_bytes": mem_bytes,
        "bytes_per_texel": (sum(mem_bytes.values()) / n) if n else 0.0,
        "references": refs,
        "misses": {k: int(bursts_by_cache[c]) for c, k in enumerate(("index", "raw"))},
        "hit_rate": {k: (1 - int(bursts_by_cache[c]) / refs[k]) if refs[k] else None
                     for c, k in enumerate(("index", "raw"))},
    }


def run(ts, requests, config, *, backend: str = "golden", stall: float = 0.0, seed: int = 0, geometry=None,
        layout: Layout | None = None) -> SimResult:
    """See the module docstring. With ``geometry``: the loadable cached unit of that geometry, ``ts``
    loaded over its bus first and placed in external memory by ``layout`` (default ``Layout.of``);
    ``load_cycles`` reports the load (golden: :func:`golden.register_map.load_cycles`). Raises
    ValueError for a backend that does not run the cached unit."""
    from vqtex.hw.texel_fetch import LATENCY
    from .cycle_model import straddle_flags
    req = np.asarray(requests, np.int64).reshape(-1, 4)
    n = len(req)
    if layout is not None and geometry is None:
        raise ValueError("the baked cached unit's set is at Layout.of(ts): a layout needs the loadable unit (geometry)")
    layout = layout or Layout.of(ts)
    p = plan(ts, req, config, layout=layout)
    load = None
    if geometry is not None:
        from vqtex.golden.register_map import load_cycles, load_writes
        load = load_cycles(len(load_writes(ts, geometry, layout)))
    straddles = int(straddle_flags(ts, req).sum())          # a property of the stream (both words read)
    if backend == "golden":
        from .cycle_model import run_cached
        model = run_cached(ts, req, config, stall=stall, seed=seed, layout=layout)
        responses = np.empty((n, 4), np.uint8)
        for s in range(0, n, GOLDEN_CHUNK):
            r = req[s:s + GOLDEN_CHUNK]
            responses[s:s + len(r)] = fetch(ts, r[:, 0], r[:, 1], r[:, 2], r[:, 3])
        sc = model["stall_cycles"]
        memory = _memory_report(p, config, np.bincount(p.cache, minlength=2), n)
        memory["stall_detail"] = {k: int(sc[k]) for k in ("miss", "bandwidth", "fifo_full", "victim")}
        memory["zero_latency_cycles"] = model["zero_latency_cycles"]
        memory["of_zero_latency"] = model["of_zero_latency"]
        return SimResult(responses, model["cycles"], n, LATENCY + FRONT_LATENCY,
                         {"output_backpressure": int(sc["output_backpressure"]),
                          "memory": int(sc["miss"] + sc["bandwidth"])}, straddles, memory=memory, load_cycles=load)
    if backend not in BACKENDS:
        raise ValueError(f"the cached unit (--memory external) runs on {', '.join(BACKENDS)}, not on {backend}")
    if geometry is not None:
        out = run_phases(geometry, config, [(ts, req, layout)], backend=backend, stall=stall, seed=seed)[0]
    elif backend == "pysim":
        out = run_pysim(ts, req, config, stall, seed)
    else:
        out = run_compiled(ts, req, config, backend, stall, seed)
    memory = _memory_report(p, config, out["bursts"], n)
    return SimResult(out["responses"], out["cycles"], n, LATENCY + FRONT_LATENCY,
                     {"output_backpressure": out["backpressure"], "memory": out["fill_waits"]}, straddles,
                     memory=memory, load_cycles=out.get("load_cycles"))


def run_pysim(ts, req, config, stall, seed) -> dict:
    """Run the cached unit on pysim; responses, cycles, measured stalls, bursts per cache, and the
    cycles of every input acceptance, AR and output transfer (tests compare them with the model)."""
    from vqtex.hw.memory.unit import CachedTexelFetch
    layout = Layout.of(ts)
    return _pysim(CachedTexelFetch(ts, config, tag_width=8), [(None, ts, req, layout)], config, stall, seed)[0]


def _pysim(dut, phases, config, stall, seed) -> list:
    """``dut`` (a :class:`hw.memory.unit.CachedTexelFetch`) in one pysim simulation through ``phases``,
    each ``(bus writes or None, ts, requests, layout)``: the writes by
    :func:`sim.backends.pysim.load_over_bus`, then the requests with a fresh memory model holding
    ``layout.image(ts)`` (cycles counted from the phase's first request, as golden's model counts
    them). One dict per phase, as :func:`run_pysim`'s, with ``load_cycles``."""
    from amaranth import Module
    from amaranth.sim import Simulator

    from .axi_memory import AxiMemory
    from .pysim import SimulationError, load_over_bus, pack_rows

    rlay = dut.o.p.shape()
    top = Module()
    top.submodules.dut = dut
    results = []

    async def phase(ctx, ts, req, layout):
        n = len(req)
        packed = pack_rows(dut.i.p.shape(), ("texture", "level", "i", "j"), req, 8)
        slave = AxiMemory(layout.image(ts), config.make_memory(), config.bus_bytes)
        got = {"accept": [], "transfer": [], "responses": np.zeros((n, 4), np.uint8), "backpressure": 0,
               "fill_waits": 0, "cycles": 0}
        ready = ready_pattern(seed, stall, 4 * n + 1024).tolist()
        n_in = n_out = cycle = 0
        slave.start(ctx, dut.axi)
        while n_out < n:
            if cycle >= len(ready):
                ready = ready_pattern(seed, stall, 2 * len(ready)).tolist()
            ctx.set(dut.i.valid, int(n_in < n))
            if n_in < n:
                ctx.set(dut.i.p.as_value(), packed[n_in])
            r = ready[cycle]
            ctx.set(dut.o.ready, r)
            slave.step(ctx, dut.axi, cycle)
            got["fill_waits"] += ctx.get(dut.stall_memory)
            if ctx.get(dut.o.valid):
                if r:
                    p = ctx.get(dut.o.p.as_value())
                    if (p >> rlay["tag"].offset) & 255 != n_out & 255:
                        raise SimulationError(f"cycle {cycle}: response out of order (expected {n_out})")
                    got["responses"][n_out] = [(p >> rlay[c].offset) & 255 for c in "rgba"]
                    got["transfer"].append(cycle)
                    n_out += 1
                else:
                    got["backpressure"] += 1
            if n_in < n and ctx.get(dut.i.ready):
                got["accept"].append(cycle)
                n_in += 1
            cycle += 1
            await ctx.tick()
        ctx.set(dut.i.valid, 0)
        ctx.set(dut.o.ready, 0)
        got["cycles"] = cycle
        got["ar"] = slave.ar
        got["addresses"] = slave.addresses
        got["bursts"] = np.bincount(layout.raw_bursts(slave.addresses).astype(np.int64), minlength=2)
        return got

    async def bench(ctx):
        for writes, ts, req, layout in phases:
            load = None
            if writes is not None:
                load = await load_over_bus(ctx, dut.bus, writes)
            got = await phase(ctx, ts, np.asarray(req, np.int64).reshape(-1, 4), layout)
            got["load_cycles"] = load
            results.append(got)

    sim = Simulator(top)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    return results


def run_phases(geometry, config, phases, *, backend: str, stall: float = 0.0, seed: int = 0,
               trace: bool = False) -> list:
    """One simulation of the loadable cached unit of ``geometry`` (one compiled library on cxxrtl and
    verilator) through ``phases``, each ``(ts, requests, layout)`` (``layout``: where the host puts
    the set in external memory; None: ``Layout.of(ts)``): ``ts`` is loaded by the bus writes of
    :func:`golden.register_map.load_writes` (matrix, base registers, descriptors, codebook), the
    memory model holds ``layout.image(ts)``, then the requests run. One dict per phase:
    ``responses``, ``cycles`` (from the phase's first request, as golden's model), ``load_cycles``,
    ``backpressure``, ``fill_waits``, ``bursts`` (per cache), ``ar`` (cycles) and ``addresses``; on
    pysim, and with ``trace`` on the compiled backends, ``accept`` and ``transfer`` (every input
    acceptance's and response transfer's cycle)."""
    from vqtex.golden.register_map import load_writes
    program = []
    for ts, req, layout in phases:
        layout = layout or Layout.of(ts)
        program.append((load_writes(ts, geometry, layout).astype(np.int64), ts,
                        np.asarray(req, np.int64).reshape(-1, 4), layout))
    if backend == "pysim":
        from vqtex.hw.memory.unit import CachedTexelFetch
        dut = CachedTexelFetch(None, config, tag_width=8, geometry=geometry, loadable=True)
        return _pysim(dut, program, config, stall, seed)
    if backend not in ("cxxrtl", "verilator"):
        raise ValueError(f"the loadable cached unit runs on pysim, cxxrtl and verilator, not on {backend}")
    from .cxxrtl import load_writes_over_bus, open_design
    lib, info, _ = open_design(build_cached(None, config, backend, geometry=geometry))
    try:
        out = []
        for writes, ts, req, layout in program:
            load = load_writes_over_bus(lib, writes)
            got = _run_loaded(lib, info, ts, req, config, layout, stall, seed, trace=trace)
            got["load_cycles"] = load
            out.append(got)
        return out
    finally:
        lib.close()


def build_cached(ts, config, backend: str, *, tag_width: int = 8, geometry=None):
    """The compiled library (``sim.backends.cxxrtl.Build``) of the cached unit on ``backend``
    (``cxxrtl`` or ``verilator``), built or from the cache: one build per cache shape, FIFO depth,
    bus width and texture set (the memory model is the driver's, chosen per run); with
    ``geometry``, the loadable cached unit's: one build per geometry and cache configuration."""
    from .design import cached_design_info
    info = cached_design_info(ts, config, tag_width=tag_width, geometry=geometry)
    if backend == "cxxrtl":
        from .cxxrtl import build_design
        return build_design(info)
    if backend == "verilator":
        from .verilator import build_design
        from .verilog import export_cached_verilog
        return build_design(info, lambda: export_cached_verilog(ts, config, tag_width=tag_width,
                                                                geometry=geometry)[0])
    raise ValueError(f"no compiled backend {backend!r} (cxxrtl, verilator)")


def _worst_cycles(n: int, config) -> int:
    """A bound on the cycles of ``n`` requests without backpressure (a hang detector, not a
    figure): every request two bursts, each waiting a whole memory access."""
    mem = config.make_memory()
    access = (config.latency if config.kind == "fixed" else 4096) + 256 * mem.beat_interval
    return (n + 64) * (2 * access + 64)


def run_compiled(ts, req, config, backend: str, stall: float, seed: int, *, trace: bool = False) -> dict:
    """Run the cached unit on a compiled backend (see the module docstring): the dict of
    :func:`run_pysim` (responses, cycles, ``backpressure``, ``fill_waits``, bursts per cache, and
    ``ar``, the cycle of every AR, with its byte ``addresses``); with ``trace`` also ``accept`` and
    ``transfer``, the cycle of every input acceptance and response transfer (int64 arrays)."""
    from .cxxrtl import open_design
    lib, info, _ = open_design(build_cached(ts, config, backend))
    try:
        return _run_loaded(lib, info, ts, req, config, Layout.of(ts), stall, seed, trace=trace)
    finally:
        lib.close()


def _run_loaded(lib, info, ts, req, config, layout, stall, seed, *, trace: bool) -> dict:
    """One run of the cached unit's library ``lib`` (contents baked or loaded): the memory model of
    ``config`` holding ``layout.image(ts)``, then the requests; the dict of :func:`run_compiled`."""
    from .cxxrtl import batch_layout, run_checked, strobe_sums, C_CYCLES
    from .memory_model_cxx import model_params
    req = np.asarray(req, np.int64).reshape(-1, 4)
    n = len(req)
    kind, params = model_params(config.make_memory())
    lib.configure_axi(layout.image(ts), config.bus_bytes, kind, params)
    accept = transfer = None
    if trace:
        accept, transfer = np.zeros(n, np.uint64), np.zeros(n, np.uint64)
    lib.set_trace(accept, transfer)
    if n == 0:
        return {"responses": np.zeros((0, 4), np.uint8), "cycles": 0, "backpressure": 0, "fill_waits": 0,
                "bursts": np.zeros(2, np.int64), "ar": [], "addresses": np.zeros(0, np.int64),
                **({"accept": np.zeros(0, np.int64), "transfer": np.zeros(0, np.int64)} if trace else {})}
    rgba, counters = run_checked(lib, req, batch_layout(info), n=n, transfers=n, latency=info.latency,
                                 worst=_worst_cycles(n, config), stall=stall, seed=seed,
                                 tag_width=info.tag_width)
    lib.set_trace(None, None)
    strobes = strobe_sums(info, counters)
    ar, addresses = lib.axi_bursts()
    addresses = addresses.astype(np.int64)
    out = {"responses": rgba.copy(), "cycles": int(counters[C_CYCLES]),
           "backpressure": strobes["stall_output"], "fill_waits": strobes["stall_memory"],
           "bursts": np.bincount(layout.raw_bursts(addresses).astype(np.int64), minlength=2),
           "ar": ar.astype(np.int64).tolist(), "addresses": addresses}
    if trace:
        out["accept"], out["transfer"] = accept.astype(np.int64), transfer.astype(np.int64)
    return out
