"""The texture filter through the memory system (docs/memory.md) on the backends:
``simulate_cached_filter(ts, pixels, config, backend=..., lanes=...) -> FilterResult`` with ``memory``.

- ``golden``: colours from :func:`sim.backends.filter.golden_colors`, cycles from the exact cycle
  model :func:`golden.memory.filter.run_pixels` (``stall`` must be 0: output backpressure is not
  modelled);
- ``pysim``: :class:`hw.memory.filter.CachedTextureFilter` in Amaranth's simulator through the
  filter's test bench (:func:`sim.backends.pysim.run_stream`), its AXI master answered each cycle by
  :class:`sim.backends.axi_memory.AxiMemory` from the same memory model: tiny cases;
- ``cxxrtl``, ``verilator``: the same unit compiled (:func:`sim.backends.design.cached_filter_design_info`;
  Verilator from its exported Verilog, :class:`sim.backends.design.CachedFilterTop`), built by the
  backend's one ``build_design`` and run by its batch API, its AXI master answered by the drivers'
  slave (``drivers/axi_slave.h``) from the C++ twin of the same memory model: scene frames.

``memory`` holds ``bursts``, ``memory_bytes`` (index, raw), ``bytes_per_pixel``, ``fill_waits`` (the
lanes' data reads waiting for fills, summed over the lanes: the model's ``miss + bandwidth``), and for
the RTL ``ar`` (every AR's cycle); for golden the model's hit rates, stall detail and the on-chip
filter's cycles on the same pixels.
"""

from __future__ import annotations

import numpy as np

from vqtex.golden.memory.system import Layout

from .filter import FIELDS, TAG_WIDTH, FilterResult, check_pixels, default_frac, golden_colors, texel_slots

__all__ = ["simulate_cached_filter", "run_pysim", "BACKENDS"]

BACKENDS = ("golden", "pysim", "cxxrtl", "verilator")


def simulate_cached_filter(ts, pixels: dict, config, *, backend: str = "golden", lanes: int = 4,
                           frac: int | None = None, stall: float = 0.0, seed: int = 0) -> FilterResult:
    """See the module docstring. Raises ValueError for bad pixels, lanes, stall or backend (one line)."""
    from vqtex.hw.filter import LANES
    from vqtex.hw.memory.filter import LATENCY
    if lanes not in LANES:
        raise ValueError(f"lanes must be one of {LANES}, not {lanes!r}")
    stall = float(stall)
    if not 0.0 <= stall < 1.0:
        raise ValueError(f"stall probability {stall} must be in [0, 1)")
    frac = default_frac(ts) if frac is None else frac
    p = check_pixels(ts, pixels, frac)
    if backend == "golden":
        if stall:
            raise ValueError("the filter's cycle model through memory has no output backpressure: stall 0")
        from vqtex.golden.memory.filter import run_pixels
        model = run_pixels(ts, p, config, lanes, frac)
        sc = model["stall_cycles"]
        memory = {k: model[k] for k in ("bursts", "memory_bytes", "bytes_per_pixel", "bytes_per_texel",
                                        "references", "hit_rate", "on_chip_cycles", "ar")}
        memory["fill_waits"] = int(sc["miss"] + sc["bandwidth"])
        memory["stall_detail"] = dict(sc)
        memory["configuration"] = config.describe()
        return FilterResult(golden_colors(ts, p, frac), model["cycles"], model["pixels"],
                            texel_slots(p["mode"], lanes), lanes, LATENCY,
                            {"output_backpressure": 0, "memory": memory["fill_waits"]}, 0, memory)
    if backend == "pysim":
        return run_pysim(ts, p, config, lanes=lanes, frac=frac, stall=stall, seed=seed)
    if backend in ("cxxrtl", "verilator"):
        return run_compiled(ts, p, config, lanes=lanes, frac=frac, stall=stall, seed=seed, backend=backend)
    raise ValueError(f"the filter through memory runs on {', '.join(BACKENDS)}, not on {backend}")


def run_pysim(ts, pixels: dict, config, *, lanes: int = 4, frac: int | None = None, stall: float = 0.0,
              seed: int = 0) -> FilterResult:
    """``CachedTextureFilter`` on pysim (about 2e3 cycles per second): the filter's test bench with
    the AXI slave stepped every cycle. Raises ``sim.backends.pysim.SimulationError`` on a colour out
    of order, ``sim.backends.axi_memory.AxiError`` on a protocol error, AssertionError if the
    arbiter's queue overflowed."""
    from vqtex.hw.memory.filter import CachedTextureFilter

    from .axi_memory import AxiMemory
    from .pysim import run_stream
    dut = CachedTextureFilter(ts, config, lanes=lanes, tag_width=TAG_WIDTH, frac=frac)
    layout = Layout.of(ts)
    slave = AxiMemory(layout.image(ts), config.make_memory(), config.bus_bytes)

    def step(ctx, cycle):
        if cycle == 0:
            slave.start(ctx, dut.axi)
        slave.step(ctx, dut.axi, cycle)

    strobes = ["stall_output", "overflow"] + [f"stall_memory{k}" for k in range(lanes)]
    rows = np.stack([np.asarray(pixels[f], np.int64) for f in FIELDS], 1)
    ph, = run_stream(dut, [(None, rows)], columns=FIELDS, tag_width=TAG_WIDTH, strobes=strobes,
                     valid=dut.o.valid, stall=stall, seed=seed, name="filter", step=step)
    st = ph["strobes"]
    assert st["overflow"] == 0, "the arbiter's queue overflowed"
    bursts = np.bincount([int(a >= layout.raw_base) for a in slave.addresses], minlength=2)
    line = (config.index_cache.line, config.raw_cache.line)
    mem_bytes = {"index": int(bursts[0]) * line[0], "raw": int(bursts[1]) * line[1]}
    n = len(rows)
    fill = sum(st[f"stall_memory{k}"] for k in range(lanes))
    memory = {"bursts": int(bursts.sum()), "memory_bytes": mem_bytes,
              "bytes_per_pixel": sum(mem_bytes.values()) / n if n else 0.0, "fill_waits": int(fill),
              "ar": np.array(slave.ar, np.int64), "configuration": config.describe()}
    return FilterResult(ph["responses"], ph["cycles"], n, texel_slots(pixels["mode"], lanes), lanes, dut.latency,
                        {"output_backpressure": st["stall_output"], "memory": int(fill)}, 0, memory)


def compiled_build(ts, config, *, lanes: int = 4, frac: int | None = None, backend: str = "cxxrtl"):
    """The compiled library of the cached filter on ``backend`` (``cxxrtl``, or ``verilator`` from
    its exported Verilog), built or from the build cache (one build per lanes, cache shapes, FIFO
    depth, bus width and set; the memory model is the driver's, set per run)."""
    from .design import cached_filter_design_info
    info = cached_filter_design_info(ts, config, lanes=lanes, frac=frac, tag_width=TAG_WIDTH)
    if backend == "cxxrtl":
        import os
        from .cxxrtl import CXXFLAGS, build_design
        from .toolchain import find_cxx
        flags = list(CXXFLAGS)
        if "clang" in os.path.basename(find_cxx()):
            # the arbiter's queues (lanes * (2 Q + 2) entries, 256 at 4 lanes and Q = 16) are read
            # through multiplexers CXXRTL writes as nested expressions, deeper than clang's default
            # of 256 brackets (a compile error)
            flags.append("-fbracket-depth=4096")
        return build_design(info, cxxflags=flags)
    from . import verilator
    from .verilog import export_cached_filter_verilog
    return verilator.build_design(info, lambda: export_cached_filter_verilog(
        ts, config, lanes=lanes, tag_width=TAG_WIDTH, frac=frac, name=info.verilog_name))


def run_compiled(ts, pixels: dict, config, *, lanes: int = 4, frac: int | None = None, stall: float = 0.0,
                 seed: int = 0, backend: str = "cxxrtl") -> FilterResult:
    """The cached filter on CXXRTL or Verilator: :func:`compiled_build`'s library, the external memory configured
    (``Layout.image``, the memory model's parameters), run by :func:`sim.backends.cxxrtl.run_checked`.
    Raises ``sim.backends.toolchain.ToolchainError`` on an AXI protocol error or a hang."""
    from .cxxrtl import C_CYCLES, open_design, run_checked, strobe_sums
    from .cxxrtl import batch_layout
    from .memory_model_cxx import model_params
    n = len(pixels["texture"])
    lib, info, _ = open_design(compiled_build(ts, config, lanes=lanes, frac=frac, backend=backend))
    try:
        layout = Layout.of(ts)
        kind, params = model_params(config.make_memory())
        lib.configure_axi(layout.image(ts), config.bus_bytes, kind, params)
        rows = np.stack([np.asarray(pixels[f], np.int64) for f in FIELDS], 1)
        groups = int(texel_slots(pixels["mode"], lanes) // lanes)
        mem = config.make_memory()
        access = (config.latency if config.kind == "fixed" else 4096) + 256 * mem.beat_interval
        worst = (groups + 64) * (2 * lanes * access + 64)
        rgba, counters = run_checked(lib, rows, batch_layout(info), n=n, transfers=n, latency=info.latency,
                                     worst=worst, stall=stall, seed=seed, tag_width=TAG_WIDTH, what="colour")
        st = strobe_sums(info, counters)
        ar, addresses = lib.axi_bursts()
    finally:
        lib.close()
    assert st["overflow"] == 0, "the arbiter's queue overflowed"
    addresses = np.asarray(addresses, np.int64)
    bursts = np.bincount((addresses >= layout.raw_base).astype(np.int64), minlength=2)
    line = (config.index_cache.line, config.raw_cache.line)
    mem_bytes = {"index": int(bursts[0]) * line[0], "raw": int(bursts[1]) * line[1]}
    fill = sum(st[f"stall_memory{k}"] for k in range(lanes))
    memory = {"bursts": int(bursts.sum()), "memory_bytes": mem_bytes,
              "bytes_per_pixel": sum(mem_bytes.values()) / n if n else 0.0, "fill_waits": int(fill),
              "ar": np.asarray(ar, np.int64), "configuration": config.describe()}
    return FilterResult(rgba.copy(), int(counters[C_CYCLES]), n, texel_slots(pixels["mode"], lanes), lanes,
                        info.latency, {"output_backpressure": st["stall_output"], "memory": int(fill)}, 0, memory)
