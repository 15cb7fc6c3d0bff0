"""The cached unit (textures in external memory, docs/memory.md) on the golden and pysim backends.

``run(ts, requests, config, backend, stall, seed) -> SimResult`` with ``memory`` filled in:

- ``golden``: responses from :func:`golden.fetch.fetch`, cycles from
  :func:`sim.backends.cycle_model.run_cached` (:mod:`golden.memory.timing`);
- ``pysim``: :class:`hw.memory.unit.CachedTexelFetch` in Amaranth's simulator, its AXI master
  answered by :class:`sim.backends.axi_memory.AxiMemory` from the same memory model; about 2e3
  cycles per second, for small traces.

Both report the same ``cycles``, ``stall_cycles`` (``output_backpressure``: ``o.valid & ~o.ready``;
``memory``: cycles the cache block's data read waited for a line fill, which the golden model splits
into ``miss`` and ``bandwidth`` in ``memory["stall_detail"]``), and ``memory``: ``bursts``,
``memory_bytes`` (index, raw), ``bytes_per_texel``, ``references``, ``misses`` and ``hit_rate`` per
cache. The
compiled backends do not run the cached unit yet.
"""

from __future__ import annotations

import numpy as np

from vqtex.golden.fetch import fetch
from vqtex.golden.memory.system import Layout
from vqtex.golden.memory.timing import plan

from ..streams import ready_pattern
from .interface import GOLDEN_CHUNK, SimResult

__all__ = ["run", "run_pysim", "BACKENDS"]

#: Backends that run the cached unit.
BACKENDS = ("golden", "pysim")


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


def run(ts, requests, config, *, backend: str = "golden", stall: float = 0.0, seed: int = 0) -> SimResult:
    """See the module docstring. Raises ValueError for a backend that does not run the cached unit."""
    from vqtex.hw.texel_fetch import LATENCY
    from .cycle_model import straddle_flags
    req = np.asarray(requests, np.int64).reshape(-1, 4)
    n = len(req)
    p = plan(ts, req, config)
    straddles = int(straddle_flags(ts, req).sum())          # a property of the stream (both words read)
    if backend == "golden":
        from .cycle_model import run_cached
        model = run_cached(ts, req, config, stall=stall, seed=seed)
        responses = np.empty((n, 4), np.uint8)
        for s in range(0, n, GOLDEN_CHUNK):
            r = req[s:s + GOLDEN_CHUNK]
            responses[s:s + len(r)] = fetch(ts, r[:, 0], r[:, 1], r[:, 2], r[:, 3])
        sc = model["stall_cycles"]
        memory = _memory_report(p, config, np.bincount(p.cache, minlength=2), n)
        memory["stall_detail"] = {k: int(sc[k]) for k in ("miss", "bandwidth", "fifo_full", "victim")}
        memory["zero_latency_cycles"] = model["zero_latency_cycles"]
        memory["of_zero_latency"] = model["of_zero_latency"]
        return SimResult(responses, model["cycles"], n, LATENCY + 4,
                         {"output_backpressure": int(sc["output_backpressure"]),
                          "memory": int(sc["miss"] + sc["bandwidth"])}, straddles, memory=memory)
    if backend != "pysim":
        raise ValueError(f"the cached unit (--memory external) runs on {' and '.join(BACKENDS)}, "
                         f"not yet on {backend}")
    out = run_pysim(ts, req, config, stall, seed)
    memory = _memory_report(p, config, out["bursts"], n)
    return SimResult(out["responses"], out["cycles"], n, LATENCY + 4,
                     {"output_backpressure": out["backpressure"], "memory": out["fill_waits"]}, straddles,
                     memory=memory)


def run_pysim(ts, req, config, stall, seed) -> dict:
    """Run the cached unit on pysim; responses, cycles, measured stalls, bursts per cache, and the
    cycles of every input acceptance, AR and output transfer (tests compare them with the model)."""
    from amaranth import Module
    from amaranth.sim import Simulator

    from vqtex.hw.memory.unit import CachedTexelFetch

    from .axi_memory import AxiMemory
    from .pysim import SimulationError, pack_rows

    dut = CachedTexelFetch(ts, config, tag_width=8)
    layout = Layout.of(ts)
    slave = AxiMemory(layout.image(ts), config.make_memory(), config.bus_bytes)
    n = len(req)
    packed = pack_rows(dut.i.p.shape(), ("texture", "level", "i", "j"), req, 8)
    rlay = dut.o.p.shape()
    got = {"accept": [], "transfer": [], "responses": np.zeros((n, 4), np.uint8), "backpressure": 0,
           "fill_waits": 0, "cycles": 0}
    top = Module()
    top.submodules.dut = dut

    async def bench(ctx):
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
        got["cycles"] = cycle

    sim = Simulator(top)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    got["ar"] = slave.ar
    raw_base = layout.raw_base
    got["bursts"] = np.bincount([int(a >= raw_base) for a in slave.addresses], minlength=2)
    return got
