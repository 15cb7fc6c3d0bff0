"""The texture filter through the memory system (docs/memory.md) on the backends:
``simulate_cached_filter(ts, pixels, config, backend=..., lanes=...) -> FilterResult`` with ``memory``.

- ``golden``: colours from :func:`sim.backends.filter.golden_colors`, cycles from the exact cycle
  model :func:`golden.memory.filter.run_pixels` (``stall``: output backpressure from
  :func:`sim.streams.ready_pattern`, the RTL backends' pattern);
- ``pysim``: :class:`hw.memory.filter.CachedTextureFilter` in Amaranth's simulator through the
  filter's test bench (:func:`sim.backends.pysim.run_stream`), its AXI master answered each cycle by
  :class:`sim.backends.axi_memory.AxiMemory` from the same memory model: tiny cases;
- ``cxxrtl``, ``verilator``: the same unit compiled (:func:`sim.backends.design.cached_filter_design_info`;
  Verilator from its exported Verilog, :class:`sim.backends.design.CachedFilterTop`), built by the
  backend's one ``build_design`` and run by its batch API, its AXI master answered by the drivers'
  slave (``drivers/axi_slave.h``) from the C++ twin of the same memory model: scene frames.

The loadable filter (``geometry``: :class:`hw.memory.filter.CachedTextureFilter` with ``loadable``)
runs the same way after a load, by the loadable cached unit's load path: :func:`run_phases` loads
each set by the bus writes of :func:`golden.register_map.load_writes` (descriptors, codebook,
matrix, base registers: ``layout``, default ``Layout.of``) in simulated cycles
(:func:`sim.backends.pysim.load_over_bus`; the compiled libraries' ``bus``, as
:func:`sim.backends.memory.run_phases`), puts ``layout.image(ts)`` behind the AXI master, then
filters its pixels; several sets in one simulation (pysim) or one compiled library. ``golden``
gives the cycle model with that layout and :func:`golden.register_map.load_cycles`. Every result's
``load_cycles`` is the load's (None for the baked filter).

``memory`` holds ``bursts``, ``memory_bytes`` (index, raw), ``bytes_per_pixel``, ``fill_waits`` (the
lanes' data reads waiting for fills, summed over the lanes: the model's ``miss + bandwidth``), and for
the RTL ``ar`` (every AR's cycle); for golden the model's hit rates, stall detail and the on-chip
filter's cycles on the same pixels.
"""

from __future__ import annotations

import numpy as np

from vqtex.golden.memory.system import Layout

from .filter import FIELDS, TAG_WIDTH, FilterResult, check_pixels, default_frac, golden_colors, texel_slots

__all__ = ["simulate_cached_filter", "run_pysim", "run_phases", "compiled_build", "BACKENDS"]

BACKENDS = ("golden", "pysim", "cxxrtl", "verilator")


def simulate_cached_filter(ts, pixels: dict, config, *, backend: str = "golden", lanes: int = 4,
                           frac: int | None = None, stall: float = 0.0, seed: int = 0, geometry=None,
                           layout: Layout | None = None) -> FilterResult:
    """See the module docstring. With ``geometry``: the loadable filter of that geometry, ``ts``
    loaded over its bus first and placed in external memory by ``layout`` (default ``Layout.of``).
    Raises ValueError for bad pixels, lanes, stall, backend or layout (one line);
    ``golden.register_map.LoadError`` (a ValueError) for a set that does not fit the geometry."""
    from vqtex.hw.filter import LANES
    from vqtex.hw.memory.filter import LATENCY
    if lanes not in LANES:
        raise ValueError(f"lanes must be one of {LANES}, not {lanes!r}")
    stall = float(stall)
    if not 0.0 <= stall < 1.0:
        raise ValueError(f"stall probability {stall} must be in [0, 1)")
    if layout is not None and geometry is None:
        raise ValueError("the baked filter's set is at Layout.of(ts): a layout needs the loadable filter (geometry)")
    frac = default_frac(ts) if frac is None else frac
    p = check_pixels(ts, pixels, frac)
    load = None
    if geometry is not None:                # (a set that does not fit is refused here, before any backend)
        from vqtex.golden.register_map import load_cycles, load_writes
        load = load_cycles(len(load_writes(ts, geometry, layout or Layout.of(ts))))
    if backend == "golden":
        from vqtex.golden.memory.filter import run_pixels
        from vqtex.hw.texel_fetch import LATENCY as FETCH_LATENCY
        from ..streams import ready_pattern
        pattern = (lambda m: ready_pattern(seed, stall, m)) if stall else None
        model = run_pixels(ts, p, config, lanes, frac, layout=layout, ready_pattern=pattern,
                           latency=FETCH_LATENCY)
        sc = model["stall_cycles"]
        memory = {k: model[k] for k in ("bursts", "memory_bytes", "bytes_per_pixel", "bytes_per_texel",
                                        "references", "hit_rate", "on_chip_cycles", "ar")}
        memory["fill_waits"] = int(sc["miss"] + sc["bandwidth"])
        memory["stall_detail"] = dict(sc)
        memory["configuration"] = config.describe()
        return FilterResult(golden_colors(ts, p, frac), model["cycles"], model["pixels"],
                            texel_slots(p["mode"], lanes), lanes, LATENCY,
                            {"output_backpressure": int(sc["output_backpressure"]), "memory": memory["fill_waits"]}, 0,
                            memory, load)
    if backend not in BACKENDS:
        raise ValueError(f"the filter through memory runs on {', '.join(BACKENDS)}, not on {backend}")
    if geometry is not None:
        return run_phases(geometry, config, [(ts, p, layout, frac)], backend=backend, lanes=lanes, stall=stall,
                          seed=seed)[0]
    if backend == "pysim":
        return run_pysim(ts, p, config, lanes=lanes, frac=frac, stall=stall, seed=seed)
    return run_compiled(ts, p, config, lanes=lanes, frac=frac, stall=stall, seed=seed, backend=backend)


def run_phases(geometry, config, phases, *, backend: str, lanes: int = 4, stall: float = 0.0,
               seed: int = 0) -> list:
    """One simulation of the loadable filter of ``geometry`` (one compiled library on cxxrtl and
    verilator) through ``phases``, each ``(ts, pixels, layout[, frac])`` (``pixels`` at ``frac``
    fractional bits, default :func:`sim.backends.filter.default_frac`; ``layout`` where the host
    puts the set in external memory, None: ``Layout.of(ts)``): ``ts`` is loaded by the bus writes of
    :func:`golden.register_map.load_writes`, the memory model holds ``layout.image(ts)``, then the
    pixels (widened to the filter's fractional bits: the same footprints) are filtered, the
    backpressure pattern restarting at each phase's first pixel. A :class:`FilterResult` per phase,
    with ``load_cycles`` and ``memory`` as the baked filter's."""
    from vqtex.golden.register_map import load_writes
    from vqtex.hw.address import COORD_BITS
    from vqtex.golden import filter as spec
    unit_frac = spec.coordinate_frac_bits(COORD_BITS)
    program = []
    for phase in phases:
        ts, px, layout = phase[:3]
        frac = phase[3] if len(phase) > 3 and phase[3] is not None else default_frac(ts)
        px = check_pixels(ts, px, frac)
        if not len(px["texture"]):
            raise ValueError("a phase of the loadable filter needs pixels")
        layout = layout or Layout.of(ts)
        rows = np.stack([px[f] << (unit_frac - frac if f in ("s", "t") else 0) for f in FIELDS], 1)
        program.append((load_writes(ts, geometry, layout).astype(np.int64), ts, rows, layout, px["mode"]))
    if backend == "pysim":
        from vqtex.hw.memory.filter import CachedTextureFilter
        dut = CachedTextureFilter(None, config, lanes=lanes, tag_width=TAG_WIDTH, geometry=geometry, loadable=True)
        return _pysim(dut, program, config, lanes, stall, seed)
    if backend not in ("cxxrtl", "verilator"):
        raise ValueError(f"the loadable filter through memory runs on pysim, cxxrtl and verilator, not on {backend}")
    from .cxxrtl import load_writes_over_bus, open_design
    lib, info, _ = open_design(compiled_build(None, config, lanes=lanes, frac=unit_frac, backend=backend,
                                              geometry=geometry))
    try:
        out = []
        for writes, ts, rows, layout, mode in program:
            load = load_writes_over_bus(lib, writes)
            res = _run_loaded(lib, info, ts, rows, mode, config, layout, lanes, stall, seed)
            res.load_cycles = load
            out.append(res)
        return out
    finally:
        lib.close()


def _memory(config, layout, addresses, fill: int, n: int, ar) -> dict:
    """The ``memory`` of an RTL run: bursts and bytes per cache from the bursts' byte ``addresses``."""
    bursts = np.bincount(layout.raw_bursts(addresses).astype(np.int64), minlength=2)
    line = (config.index_cache.line, config.raw_cache.line)
    mem_bytes = {"index": int(bursts[0]) * line[0], "raw": int(bursts[1]) * line[1]}
    return {"bursts": int(bursts.sum()), "memory_bytes": mem_bytes,
            "bytes_per_pixel": sum(mem_bytes.values()) / n if n else 0.0, "fill_waits": int(fill),
            "ar": np.asarray(ar, np.int64), "configuration": config.describe()}


def run_pysim(ts, pixels: dict, config, *, lanes: int = 4, frac: int | None = None, stall: float = 0.0,
              seed: int = 0) -> FilterResult:
    """``CachedTextureFilter`` on pysim (about 2e3 cycles per second): the filter's test bench with
    the AXI slave stepped every cycle. Raises ``sim.backends.pysim.SimulationError`` on a colour out
    of order, ``sim.backends.axi_memory.AxiError`` on a protocol error, AssertionError if the
    arbiter's queue overflowed."""
    from vqtex.hw.memory.filter import CachedTextureFilter
    dut = CachedTextureFilter(ts, config, lanes=lanes, tag_width=TAG_WIDTH, frac=frac)
    rows = np.stack([np.asarray(pixels[f], np.int64) for f in FIELDS], 1)
    return _pysim(dut, [(None, ts, rows, Layout.of(ts), pixels["mode"])], config, lanes, stall, seed)[0]


def _pysim(dut, program, config, lanes: int, stall: float, seed: int) -> list:
    """``dut`` (a :class:`hw.memory.filter.CachedTextureFilter`) in one pysim simulation through
    ``program``, each ``(bus writes or None, ts, rows, layout, mode)``: the writes by
    :func:`sim.backends.pysim.load_over_bus` (in :func:`sim.backends.pysim.run_stream`), then the
    pixel rows with a fresh memory model holding ``layout.image(ts)``. A FilterResult per phase."""
    from .axi_memory import AxiMemory
    from .pysim import run_stream
    slaves = [AxiMemory(layout.image(ts), config.make_memory(), config.bus_bytes) for _, ts, _, layout, _ in program]
    current = iter(slaves)
    state = {}

    def step(ctx, cycle):
        if cycle == 0:                      # a phase's first pixel: its own external memory
            state["slave"] = next(current)
            state["slave"].start(ctx, dut.axi)
        state["slave"].step(ctx, dut.axi, cycle)

    strobes = ["stall_output", "overflow"] + [f"stall_memory{k}" for k in range(lanes)]
    phases = run_stream(dut, [(writes, rows) for writes, _, rows, _, _ in program], columns=FIELDS,
                        tag_width=TAG_WIDTH, strobes=strobes, valid=dut.o.valid, stall=stall, seed=seed,
                        name="filter", step=step)
    out = []
    for ph, slave, (_, ts, rows, layout, mode) in zip(phases, slaves, program):
        st = ph["strobes"]
        assert st["overflow"] == 0, "the arbiter's queue overflowed"
        n = len(rows)
        fill = sum(st[f"stall_memory{k}"] for k in range(lanes))
        out.append(FilterResult(ph["responses"], ph["cycles"], n, texel_slots(mode, lanes), lanes, dut.latency,
                                {"output_backpressure": st["stall_output"], "memory": int(fill)}, 0,
                                _memory(config, layout, slave.addresses, fill, n, slave.ar), ph["load_cycles"]))
    return out


def compiled_build(ts, config, *, lanes: int = 4, frac: int | None = None, backend: str = "cxxrtl", geometry=None):
    """The compiled library of the cached filter on ``backend`` (``cxxrtl``, or ``verilator`` from
    its exported Verilog), built or from the build cache (one build per lanes, cache shapes, FIFO
    depth, bus width and set; the memory model is the driver's, set per run). With ``geometry``:
    the loadable filter's, one build per geometry and cache configuration for every set it holds
    (``ts`` unused, ``frac`` the filter's own: None)."""
    from .design import cached_filter_design_info
    if geometry is not None:
        ts, frac = None, None
    info = cached_filter_design_info(ts, config, lanes=lanes, frac=frac, tag_width=TAG_WIDTH, geometry=geometry)
    if backend == "cxxrtl":
        import os
        from .cxxrtl import CXXFLAGS, build_design
        from .toolchain import find_cxx
        flags = list(CXXFLAGS)
        if "clang" in os.path.basename(find_cxx()):
            # the arbiter's queues in flip-flops (lanes * (2 Q + 2) entries, 256 at 4 lanes and Q = 16)
            # were read through multiplexers CXXRTL wrote as nested expressions, deeper than clang's
            # default of 256 brackets (a compile error); they are LUT RAM now, the flag is kept (not
            # re-measured without it)
            flags.append("-fbracket-depth=4096")
        return build_design(info, cxxflags=flags)
    from . import verilator
    from .verilog import export_cached_filter_verilog
    return verilator.build_design(info, lambda: export_cached_filter_verilog(
        ts, config, lanes=lanes, tag_width=TAG_WIDTH, frac=frac, name=info.verilog_name, geometry=geometry))


def run_compiled(ts, pixels: dict, config, *, lanes: int = 4, frac: int | None = None, stall: float = 0.0,
                 seed: int = 0, backend: str = "cxxrtl") -> FilterResult:
    """The cached filter on CXXRTL or Verilator: :func:`compiled_build`'s library, the external memory configured
    (``Layout.image``, the memory model's parameters), run by :func:`sim.backends.cxxrtl.run_checked`.
    Raises ``sim.backends.toolchain.ToolchainError`` on an AXI protocol error or a hang."""
    from .cxxrtl import open_design
    lib, info, _ = open_design(compiled_build(ts, config, lanes=lanes, frac=frac, backend=backend))
    try:
        rows = np.stack([np.asarray(pixels[f], np.int64) for f in FIELDS], 1)
        return _run_loaded(lib, info, ts, rows, pixels["mode"], config, Layout.of(ts), lanes, stall, seed)
    finally:
        lib.close()


def _run_loaded(lib, info, ts, rows, mode, config, layout, lanes, stall, seed) -> FilterResult:
    """One run of the cached filter's library ``lib`` (contents baked or loaded): the memory model of
    ``config`` holding ``layout.image(ts)``, then the pixel ``rows`` (the filter's request columns)."""
    from .cxxrtl import C_CYCLES, batch_layout, run_checked, strobe_sums
    from .memory_model_cxx import model_params
    n = len(rows)
    kind, params = model_params(config.make_memory())
    lib.configure_axi(layout.image(ts), config.bus_bytes, kind, params)
    groups = int(texel_slots(mode, lanes) // lanes)
    mem = config.make_memory()
    access = (config.latency if config.kind == "fixed" else 4096) + 256 * mem.beat_interval
    worst = (groups + 64) * (2 * lanes * access + 64)
    rgba, counters = run_checked(lib, rows, batch_layout(info), n=n, transfers=n, latency=info.latency,
                                 worst=worst, stall=stall, seed=seed, tag_width=TAG_WIDTH, what="colour")
    st = strobe_sums(info, counters)
    ar, addresses = lib.axi_bursts()
    assert st["overflow"] == 0, "the arbiter's queue overflowed"
    fill = sum(st[f"stall_memory{k}"] for k in range(lanes))
    return FilterResult(rgba.copy(), int(counters[C_CYCLES]), n, texel_slots(mode, lanes), lanes, info.latency,
                        {"output_backpressure": st["stall_output"], "memory": int(fill)}, 0,
                        _memory(config, layout, np.asarray(addresses, np.int64), fill, n, ar))
