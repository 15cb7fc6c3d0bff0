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
    Amaranth's simulator running ``TextureFilter`` (:mod:`sim.backends.filter_pysim`): tiny cases.
``cxxrtl``
    The compiled model (:mod:`sim.backends.filter_cxxrtl`).
``verilator``
    The exported Verilog under Verilator (:mod:`sim.backends.filter_verilator`).

Every RTL backend presents the requests back to back from cycle 0, drives ``o.ready`` from
:func:`sim.streams.ready_pattern` and counts cycles up to and including the cycle the last colour
transfers; it checks every response's tag (in order, none lost or duplicated).
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass

import numpy as np

from amaranth import Module
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from vqtex.golden import filter as spec
from vqtex.golden.fetch import fetch
from vqtex.golden.format import TextureSet

__all__ = ["FilterResult", "simulate_filter", "golden_colors", "check_pixels", "FIELDS", "FILTER_BACKENDS",
           "FilterTop", "texel_slots"]

#: The per-pixel input fields, in the order of the filter request.
FIELDS = ("texture", "s", "t", "lod", "mode", "address_s", "address_t")
FILTER_BACKENDS = ("golden", "pysim", "cxxrtl", "verilator")
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
    p = {f: np.asarray(pixels[f]).astype(np.int64).reshape(-1) for f in FIELDS}
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
                    index_banks: str = "parity") -> FilterResult:
    """Filter ``pixels`` on ``backend`` (see the module docstring); ``frac`` defaults to the
    filter's (``golden.filter.coordinate_frac_bits`` of the set's largest level 0); ``index_banks``
    as for :class:`hw.filter.TextureFilter` (the golden backend counts the conflicts the banks would
    have, :func:`golden.index_banks.conflicts`).

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
        table = spec.LevelTable([ts.level_shapes(t) for t in range(ts.n_textures)])
        frac = spec.coordinate_frac_bits(table.max_log2)
    p = check_pixels(ts, pixels, frac)
    if backend == "golden":
        colors = golden_colors(ts, p, frac)
        return FilterResult(colors, 0, len(colors), int(texel_slots(p["mode"], lanes)), lanes, LATENCY,
                            {"output_backpressure": 0, "input_wait": 0},
                            golden_conflicts(ts, p, frac, lanes) if index_banks == "parity" else 0)
    if backend not in FILTER_BACKENDS:
        raise ValueError(f"unknown filter backend {backend!r} (known: {', '.join(FILTER_BACKENDS)})")
    module = importlib.import_module(f"vqtex.sim.backends.filter_{backend}")
    return module.run(ts, p, lanes=lanes, frac=frac, stall=stall, seed=seed, index_banks=index_banks)


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
    used = np.asarray([1, 4, 8])[np.asarray(mode, np.int64)]
    return int((-(-used // lanes) * lanes).sum())


class FilterTop(wiring.Component):
    """``hw.filter.TextureFilter`` with one port per stream member (``i_valid``, ``i_ready``,
    ``i_payload``, ``o_valid``, ``o_ready``, ``o_payload``) and its strobes, for synthesis
    (:mod:`sim.reports.synth`'s harness) and Verilog.

    Arguments
    ---------
    texture_set : TextureSet
    lanes, tag_width, frac, index_banks
        As for :class:`hw.filter.TextureFilter`.
    """

    def __init__(self, texture_set, *, lanes: int = 1, tag_width: int = 8, frac: int | None = None,
                 index_banks: str = "parity"):
        from vqtex.hw.filter import TextureFilter
        self._filter = TextureFilter(texture_set, lanes=lanes, tag_width=tag_width, frac=frac,
                                     index_banks=index_banks)
        f = self._filter
        self._strobes = [n for n in f.signature.members if n not in ("i", "o")]    # stall_output, busy, ...
        super().__init__({
            "i_valid": In(1), "i_ready": Out(1), "i_payload": In(len(f.i.p.as_value())),
            "o_valid": Out(1), "o_ready": In(1), "o_payload": Out(len(f.o.p.as_value())),
            **{n: Out(len(getattr(f, n))) for n in self._strobes},
        })

    @property
    def filter(self):
        return self._filter

    @property
    def latency(self) -> int:
        return self._filter.latency

    def elaborate(self, platform):
        m = Module()
        m.submodules.filter = f = self._filter
        m.d.comb += [
            f.i.valid.eq(self.i_valid), self.i_ready.eq(f.i.ready), f.i.p.eq(self.i_payload),
            self.o_valid.eq(f.o.valid), f.o.ready.eq(self.o_ready), self.o_payload.eq(f.o.p),
        ]
        m.d.comb += [getattr(self, n).eq(getattr(f, n)) for n in self._strobes]
        return m
