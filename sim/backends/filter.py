"""The texture filter's backends: ``simulate_filter(ts, pixels, ...) -> FilterResult``.

``pixels`` are the per-pixel inputs of :class:`hw.filter.TextureFilter`, a dict of equal-length
integer arrays ``texture``, ``s``, ``t`` (``frac`` fractional bits), ``lod``, ``mode``, ``address_s``,
``address_t`` (what :meth:`golden.render.sampling.Sampler.filter_inputs` returns).

Backends
--------
``golden``
    :func:`golden.filter.footprint`, the texels from :func:`golden.fetch.fetch`,
    :func:`golden.filter.blend`; no cycles.
``pysim``
    Amaranth's simulator running ``TextureFilter`` (:func:`run_pysim`, through the texel-fetch
    unit's testbench :func:`sim.backends.pysim.run_stream`): tiny cases.
``cxxrtl``, ``verilator``
    The compiled model, or the exported Verilog under Verilator (:func:`run_compiled`), built and run
    by the texel-fetch unit's backends from the filter's description
    (:func:`sim.backends.design.filter_design_info`): :func:`sim.backends.cxxrtl.build_design`,
    :func:`sim.backends.verilator.build_design`, :class:`sim.backends.cxxrtl.BatchLibrary`.

Every RTL backend presents the requests back to back from cycle 0, drives ``o.ready`` from
:func:`sim.streams.ready_pattern` and counts cycles up to and including the cycle the last colour
transfers; it checks every response's tag (in order, none lost or duplicated).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from vqtex.golden import filter as spec
from vqtex.golden.fetch import fetch
from vqtex.golden.format import TextureSet

from .design import FIELDS, FilterTop, filter_design_info     # (FilterTop: re-exported, its home is design.py)

__all__ = ["FilterResult", "simulate_filter", "golden_colors", "check_pixels", "FIELDS", "FILTER_BACKENDS",
           "FilterTop", "texel_slots", "run_pysim", "run_compiled", "compiled_build", "prepare_filter", "default_frac",
           "TAG_WIDTH"]

FILTER_BACKENDS = ("golden", "pysim", "cxxrtl", "verilator")
#: Tag width of the simulated filter: pixel n carries tag ``n mod 2**TAG_WIDTH``.
TAG_WIDTH = 16
#: Pixels the golden backend filters at a time (bounded temporaries).
GOLDEN_CHUNK = 1 << 16


@dataclass
class FilterResult:
    """What a filter run reports.

    Members
    -------
    colors : ndarray uint8 (M, 4)
        The filtered RGBA per pixel, in request order.
    cycles : int
        Cycles from the first cycle a request is presented to the cycle the last colour transfers
        (0 for the golden backend and for no pixels).
    pixels : int
    texels : int
        Texel slots fetched (1, 4 or 8 per pixel by mode, rounded up to whole groups of lanes).
    lanes : int
    latency : int
    stall_cycles : dict
        ``{"output_backpressure": cycles with o.valid & ~o.ready, "input_wait": cycles with
        i.valid & ~i.ready (the lanes busy with an earlier pixel's groups, or backpressure)}``.
    bank_conflicts : int
        Advancing cycles in which two lanes of a set needed different blocks of one index bank (the
        filter's ``bank_conflict`` strobe; 0 by construction, the count is the check; 0 without
        banks).
    """
    colors: np.ndarray
    cycles: int
    pixels: int
    texels: int
    lanes: int
    latency: int
    stall_cycles: dict
    bank_conflicts: int = 0
    #: Through the memory system (:mod:`sim.backends.filter_memory`): bursts, bytes, hit rates.
    memory: dict | None = None
    #: A loadable filter's load: the cycles of the bus writes before the pixels (None: baked).
    load_cycles: int | None = None

    @property
    def pixels_per_clock(self) -> float:
        return self.pixels / self.cycles if self.cycles else 0.0


def check_pixels(ts: TextureSet, pixels: dict, frac: int) -> dict:
    """The pixels as int64 arrays, checked: every field present and of one length, texture ids,
    levels of detail, mode and addressing codes in range, coordinates within ``frac + 3`` signed bits.

    Raises
    ------
    ValueError
        With one line naming the problem.
    """
    missing = [f for f in FIELDS if f not in pixels]
    if missing:
        raise ValueError(f"filter inputs lack {', '.join(missing)}")
    p = {f: np.asarray(pixels[f], dtype=np.int64).reshape(-1) for f in FIELDS}     # (no copy of int64)
    n = len(p["texture"])
    if any(len(v) != n for v in p.values()):
        raise ValueError("filter inputs of different lengths")
    if n == 0:
        return p
    table = spec.LevelTable([ts.level_shapes(t) for t in range(ts.n_textures)])
    if p["texture"].min() < 0 or p["texture"].max() >= ts.n_textures:
        raise ValueError("texture id out of range")
    half = 1 << (spec.coordinate_bits(frac) - 1)
    for f in ("s", "t"):
        if p[f].min() < -half or p[f].max() >= half:
            raise ValueError(f"{f} outside [-2, 2] at {frac} fractional bits")
    if p["lod"].min() < 0 or (p["lod"] > table.last[p["texture"]] << spec.FRAC_BITS).any():
        raise ValueError("level of detail outside [0, 256 last level]")
    for f, top in (("mode", 2), ("address_s", 2), ("address_t", 2)):
        if p[f].min() < 0 or p[f].max() > top:
            raise ValueError(f"unknown {f} code")
    return p


def golden_colors(ts: TextureSet, pixels: dict, frac: int) -> np.ndarray:
    """The filtered colours (M, 4) uint8 by the golden model: footprint, fetch, blend."""
    p = check_pixels(ts, pixels, frac)
    table = spec.LevelTable([ts.level_shapes(t) for t in range(ts.n_textures)])
    n = len(p["texture"])
    out = np.empty((n, 4), np.uint8)
    for a in range(0, n, GOLDEN_CHUNK):
        q = {f: v[a:a + GOLDEN_CHUNK] for f, v in p.items()}
        lv, i, j, w = spec.footprint(table, q["texture"], q["s"], q["t"], q["lod"], q["mode"], q["address_s"],
                                     q["address_t"], frac)
        tex = np.broadcast_to(q["texture"][:, None], lv.shape)
        texels = fetch(ts, tex.reshape(-1), lv.reshape(-1), i.reshape(-1), j.reshape(-1))
        out[a:a + len(lv)] = spec.blend(w, texels.reshape(len(lv), spec.SLOTS, 4))
    return out


def simulate_filter(ts: TextureSet, pixels: dict, *, backend: str = "golden", lanes: int = 1,
                    frac: int | None = None, stall: float = 0.0, seed: int = 0,
                    index_banks: str = "parity", geometry=None) -> FilterResult:
    """Filter ``pixels`` on ``backend`` (see the module docstring); ``frac`` defaults to the
    filter's (``golden.filter.coordinate_frac_bits`` of the set's largest level 0); ``index_banks``
    as for :class:`hw.filter.TextureFilter` (the golden backend counts the conflicts the banks would
    have, :func:`golden.index_banks.conflicts`). With ``geometry``, the loadable filter of that
    geometry (every lane its own copy of the memories: ``index_banks`` must be ``lane``), ``ts``
    loaded over its bus port first; its ``s`` and ``t`` have the fractional bits of the largest level
    it can address, so the pixels are widened to them (the same footprints).

    Raises
    ------
    ValueError
        Bad pixels, stall probability, lane count or backend name.
    """
    from vqtex.hw.filter import INDEX_BANKS, LANES, LATENCY
    if lanes not in LANES:
        raise ValueError(f"lanes must be one of {LANES}, not {lanes!r}")
    if index_banks not in INDEX_BANKS:
        raise ValueError(f"index_banks must be one of {INDEX_BANKS}, not {index_banks!r}")
    stall = float(stall)
    if not 0.0 <= stall < 1.0:
        raise ValueError(f"stall probability {stall} must be in [0, 1)")
    if frac is None:
        frac = default_frac(ts)
    p = check_pixels(ts, pixels, frac)
    load = None
    if geometry is not None:
        from vqtex.golden.register_map import load_cycles, load_writes
        if index_banks != "lane":
            raise ValueError("the loadable texture filter keeps a copy of the memories per lane: index_banks 'lane'")
        # (a set that does not fit is refused here, before any backend)
        load = load_cycles(len(load_writes(ts, geometry)))
    if backend == "golden":
        colors = golden_colors(ts, p, frac)
        return FilterResult(colors, 0, len(colors), int(texel_slots(p["mode"], lanes)), lanes, LATENCY,
                            {"output_backpressure": 0, "input_wait": 0},
                            golden_conflicts(ts, p, frac, lanes) if index_banks == "parity" else 0, load_cycles=load)
    if backend not in FILTER_BACKENDS:
        raise ValueError(f"unknown filter backend {backend!r} (known: {', '.join(FILTER_BACKENDS)})")
    if geometry is not None:                # the loadable filter's coordinates: widened, exactly
        unit_frac = _unit_frac(ts, frac, geometry)
        p = {**p, "s": p["s"] << (unit_frac - frac), "t": p["t"] << (unit_frac - frac)}
        frac = unit_frac
    if backend == "pysim":
        return run_pysim(ts, p, lanes=lanes, frac=frac, stall=stall, seed=seed, index_banks=index_banks,
                         geometry=geometry)
    return run_compiled(backend, ts, p, lanes=lanes, frac=frac, stall=stall, seed=seed, index_banks=index_banks,
                        geometry=geometry)


def default_frac(ts: TextureSet) -> int:
    """The filter's fractional bits of ``s`` and ``t`` for ``ts``: ``golden.filter.coordinate_frac_bits``
    of the set's largest level 0."""
    return spec.coordinate_frac_bits(spec.LevelTable([ts.level_shapes(t) for t in range(ts.n_textures)]).max_log2)


def _unit_frac(ts: TextureSet, frac: int | None, geometry) -> int:
    """The fractional bits the RTL filter is built with: ``frac`` (default :func:`default_frac`), or
    for the loadable filter those of the largest level it can address."""
    if geometry is not None:
        from vqtex.hw.address import COORD_BITS
        return spec.coordinate_frac_bits(COORD_BITS)
    return default_frac(ts) if frac is None else frac


def golden_conflicts(ts: TextureSet, pixels: dict, frac: int, lanes: int) -> int:
    """Groups of ``lanes`` texel slots in which two lanes of a set would need different blocks of one
    index bank (:func:`golden.index_banks.conflicts` of the pixels' footprints)."""
    from vqtex.golden.index_banks import conflicts
    table = spec.LevelTable([ts.level_shapes(t) for t in range(ts.n_textures)])
    level, i, j, _ = spec.footprint(table, pixels["texture"], pixels["s"], pixels["t"], pixels["lod"],
                                    pixels["mode"], pixels["address_s"], pixels["address_t"], frac)
    return conflicts(ts, pixels["texture"], level, i, j, lanes)


def texel_slots(mode: np.ndarray, lanes: int) -> int:
    """Texel slots the lanes fetch for these modes: per pixel ``ceil(used / lanes) * lanes``."""
    per_mode = np.bincount(np.asarray(mode, np.int64).reshape(-1), minlength=3)     # (a mode code past 2 fails below)
    used = np.array([1, 4, 8])
    return int((per_mode * (-(-used // lanes) * lanes)).sum())


def _result(info, pixels: dict, lanes: int, rgba, cycles: int, strobes: dict) -> FilterResult:
    return FilterResult(rgba, cycles, len(rgba), texel_slots(pixels["mode"], lanes), lanes, info.latency,
                        {"output_backpressure": strobes["stall_output"], "input_wait": strobes["busy"]},
                        strobes["bank_conflict"])


def run_pysim(ts, pixels: dict, *, lanes: int = 1, frac: int | None = None, stall: float = 0.0, seed: int = 0,
              bank_depth: int | None = None, vcd: str | None = None, index_banks: str = "parity",
              geometry=None) -> FilterResult:
    """Filter ``pixels`` (checked int64 arrays, :func:`check_pixels`) on ``TextureFilter(ts, lanes=lanes,
    frac=frac)`` in Amaranth's simulator (about 2e3 cycles per second; a trilinear pixel on one lane
    is 8 cycles): the texel-fetch unit's testbench, :func:`sim.backends.pysim.run_stream`.
    ``VQTEX_VCD=path.vcd`` writes a waveform.

    Raises
    ------
    sim.backends.pysim.SimulationError
        If a response's tag is not the next expected one.
    """
    from vqtex.hw.filter import TextureFilter

    from .pysim import run_stream
    unit = {} if bank_depth is None else {"bank_depth": bank_depth}
    writes = None
    if geometry is not None:                # the loadable filter: the set loaded over its bus first
        from vqtex.golden.register_map import load_writes
        unit.update(geometry=geometry, loadable=True)
        writes = load_writes(ts, geometry)
    dut = TextureFilter(None if geometry is not None else ts, lanes=lanes, tag_width=TAG_WIDTH, frac=frac,
                        index_banks=index_banks, **unit)
    rows = np.stack([np.asarray(pixels[f], np.int64) for f in FIELDS], 1)
    ph, = run_stream(dut, [(writes, rows)], columns=FIELDS, tag_width=TAG_WIDTH,
                     strobes=[n for n in dut.signature.members if n not in ("i", "o", "bus")], valid=dut.o.valid,
                     stall=stall, seed=seed, vcd=vcd, name="filter")
    res = _result(dut, pixels, lanes, ph["responses"], ph["cycles"], ph["strobes"])
    res.load_cycles = ph["load_cycles"]
    return res


def compiled_build(backend: str, ts, *, lanes: int = 1, frac: int | None = None, index_banks: str = "parity",
                   geometry=None):
    """The compiled library of the filter (``cxxrtl`` or ``verilator``): its description
    (:func:`sim.backends.design.filter_design_info`, elaborated once per process) built by that
    backend's ``build_design``, as the texel-fetch unit is, or found in the build cache. Returns the
    backend's ``Build`` (its ``info`` the description)."""
    from . import cxxrtl
    info = filter_design_info(ts, lanes=lanes, frac=frac, tag_width=TAG_WIDTH, index_banks=index_banks,
                              geometry=geometry)
    if backend == "cxxrtl":
        return cxxrtl.build_design(info)
    from . import verilator
    from .verilog import export_filter_verilog
    return verilator.build_design(info, lambda: export_filter_verilog(
        ts, lanes=lanes, tag_width=TAG_WIDTH, frac=frac, index_banks=index_banks, name=info.verilog_name,
        geometry=geometry)[0])


def prepare_filter(backend: str, ts, *, lanes: int = 1, frac: int | None = None, index_banks: str = "parity",
                   geometry=None) -> float:
    """Elaborate the filter and build its library (or find it in the cache) before a series of
    :func:`simulate_filter` calls with these arguments, so that each of them then costs its
    simulation and not the set-up (a renderer calls this once, before its first frame). Returns the
    seconds it took; nothing to do (0.0) for the golden and pysim backends."""
    if backend not in ("cxxrtl", "verilator"):
        return 0.0
    t0 = time.perf_counter()
    compiled_build(backend, ts, lanes=lanes, frac=_unit_frac(ts, frac, geometry), index_banks=index_banks,
                   geometry=geometry)
    return time.perf_counter() - t0


def run_compiled(backend: str, ts, pixels: dict, *, lanes: int = 1, frac: int | None = None, stall: float = 0.0,
                 seed: int = 0, index_banks: str = "parity", geometry=None) -> FilterResult:
    """Filter ``pixels`` (checked int64 arrays) on a compiled backend (``cxxrtl``, ``verilator``): the
    library of :func:`compiled_build`, run by :func:`sim.backends.cxxrtl.run_checked`."""
    from . import cxxrtl
    n = len(pixels["texture"])
    if n == 0:
        info = filter_design_info(ts, lanes=lanes, frac=frac, tag_width=TAG_WIDTH, index_banks=index_banks,
                                  geometry=geometry)
        return _result(info, pixels, lanes, np.zeros((0, 4), np.uint8), 0, dict.fromkeys(info.strobes, 0))
    lib, info, _ = cxxrtl.open_design(compiled_build(backend, ts, lanes=lanes, frac=frac, index_banks=index_banks,
                                                     geometry=geometry))
    load = None
    try:
        if geometry is not None:
            load = cxxrtl.load_set(lib, ts, geometry)
        rows = np.stack([np.asarray(pixels[f], np.int64) for f in FIELDS], 1)
        groups = int(texel_slots(pixels["mode"], lanes) // lanes)
        rgba, counters = cxxrtl.run_checked(lib, rows, cxxrtl.batch_layout(info), n=n, transfers=groups,
                                            latency=info.latency, worst=groups + info.latency + 64, stall=stall,
                                            seed=seed, tag_width=TAG_WIDTH, what="colour")
    finally:
        lib.close()
    res = _result(info, pixels, lanes, rgba, int(counters[cxxrtl.C_CYCLES]), cxxrtl.strobe_sums(info, counters))
    res.load_cycles = load
    return res
