"""The hardware units as the simulators see them: ports, payload layouts, strobes, memories.

What every backend that runs the RTL outside Amaranth (CXXRTL, Verilator, Icarus) needs to know about
a unit, in one place, as one :class:`DesignInfo` per unit: the top-level port map (one port per
signature member, named as Amaranth names them), the payload field offsets and widths and the
columns of a request row packed into them, the observability strobes (summed in the batch API's
counter slots, in order), the valid bits of the registers, the memories and their contents, the
ports of the unit's Verilog top, and what names a build in the cache. Three units:

- the texel-fetch unit (:func:`design_info`; its Verilog top :class:`TexelFetchTop`, one port per
  stream member), with the two halves the CXXRTL backend runs on two threads;
- the texture filter (:func:`filter_design_info`; its Verilog top :class:`FilterTop`, the payloads
  whole), one model;
- the cached unit, textures in external memory (:func:`cached_design_info`; its Verilog top
  :class:`CachedTexelFetchTop`), one model with an AXI4 read master the drivers answer.

The CXXRTL backend, the Verilator backend, the filter's backends and the Icarus cross-check import
it; it imports none of them.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np
from amaranth import Module
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .toolchain import ToolchainError, texture_set_digest

__all__ = ["TOP_NAME", "FILTER_TOP_NAME", "STROBES", "HALVES", "COLUMNS", "FIELDS", "TexelFetchTop", "FilterTop", "CachedTexelFetchTop",
           "port_map", "request_ports", "response_ports", "MemoryImage", "DesignInfo", "design_info",
           "filter_design_info", "cached_design_info", "CACHED_STROBES", "pack_requests", "MAX_PAYLOAD_WORDS"]

TOP_NAME = "texel_fetch"
FILTER_TOP_NAME = "texture_filter"
#: The columns of a texel-fetch request row (the request fields the batch API packs from it).
COLUMNS = ("texture", "level", "i", "j")
#: The filter's per-pixel input fields, the columns of a filter request row, in the request's order.
FIELDS = ("texture", "s", "t", "lod", "mode", "address_s", "address_t")
#: The widest request payload the compiled backends take, in 64-bit words.
MAX_PAYLOAD_WORDS = 4


def port_map(top) -> dict:
    """Top-level ports of a component for Amaranth's RTLIL/CXXRTL converters: ``name -> (value,
    None)``, one per signature member, named ``stream__member`` as Amaranth names them. The direction
    is left for Amaranth to infer from the design (inputs are what the design reads and does not
    drive), which gives the same RTLIL as naming it."""
    from amaranth.hdl import ValueCastable
    ports = {}
    for path, _, value in top.signature.flatten(top):
        if isinstance(value, ValueCastable):
            value = value.as_value()
        ports["__".join(map(str, path))] = (value, None)
    return ports


def request_ports(fetch) -> dict:
    """Request payload field -> width (fields of width 0 are dropped)."""
    return {name: f.width for name, f in fetch.i.p.shape() if f.width}


def response_ports(fetch) -> dict:
    return {name: f.width for name, f in fetch.o.p.shape() if f.width}


class TexelFetchTop(wiring.Component):
    """``TexelFetch`` with one port per stream member (see the module docstring).

    The loadable unit (``geometry``) has its Wishbone port as ``bus_adr``, ``bus_dat_w``,
    ``bus_dat_r``, ``bus_sel``, ``bus_cyc``, ``bus_stb``, ``bus_we``, ``bus_ack``, ``bus_err``,
    ``bus_stall`` (amaranth-soc's names, ``bus_`` before each).

    Arguments
    ---------
    texture_set : TextureSet or None
    one_port : bool
    tag_width : int
    specialise : bool
        As for :class:`hw.texel_fetch.TexelFetch`.
    geometry : Geometry, optional
        The loadable unit of this geometry (``texture_set``, if given, its initial contents).
    """

    def __init__(self, texture_set, *, one_port: bool = False, tag_width: int = 8, specialise: bool = True,
                 geometry=None):
        from vqtex.hw.texel_fetch import TexelFetch
        unit = {} if geometry is None else {"geometry": geometry, "loadable": True}
        self._fetch = TexelFetch(texture_set, one_port=one_port, tag_width=tag_width, specialise=specialise, **unit)
        members = {"i_valid": In(1), "i_ready": Out(1)}
        members.update({f"i_{n}": In(w) for n, w in request_ports(self._fetch).items()})
        members.update({"o_valid": Out(1), "o_ready": In(1)})
        members.update({f"o_{n}": Out(w) for n, w in response_ports(self._fetch).items()})
        self._extra = [n for n in self._fetch.signature.members if n not in ("i", "o", "bus")]
        members.update({n: Out(len(getattr(self._fetch, n))) for n in self._extra})
        members.update(bus_members(self._fetch))
        super().__init__(members)

    @property
    def fetch(self):
        return self._fetch

    @property
    def latency(self) -> int:
        return self._fetch.latency

    def elaborate(self, platform):
        m = Module()
        m.submodules.fetch = f = self._fetch
        m.d.comb += [f.i.valid.eq(self.i_valid), self.i_ready.eq(f.i.ready),
                     self.o_valid.eq(f.o.valid), f.o.ready.eq(self.o_ready)]
        m.d.comb += [getattr(f.i.p, n).eq(getattr(self, f"i_{n}")) for n in request_ports(f)]
        m.d.comb += [getattr(self, f"o_{n}").eq(getattr(f.o.p, n)) for n in response_ports(f)]
        m.d.comb += [getattr(self, n).eq(getattr(f, n)) for n in self._extra]
        connect_bus(m, self, f)
        return m


def bus_members(unit) -> dict:
    """A loadable unit's Wishbone port as top-level members ``bus_adr``, ``bus_dat_w``, ... (the
    slave's view: the unit's own signature members); none for a unit without ``bus``."""
    if "bus" not in unit.signature.members:
        return {}
    return {f"bus_{name}": (In if member.flow == In else Out)(member.shape)
            for name, member in unit.bus.signature.members.items()}


def connect_bus(m, top, unit) -> None:
    """Wire ``top``'s ``bus_*`` members (:func:`bus_members`) to ``unit.bus``."""
    if "bus" not in unit.signature.members:
        return
    for name, member in unit.bus.signature.members.items():
        if member.flow == In:               # driven by the initiator: an input of the top
            m.d.comb += getattr(unit.bus, name).eq(getattr(top, f"bus_{name}"))
        else:
            m.d.comb += getattr(top, f"bus_{name}").eq(getattr(unit.bus, name))


def axi_members(unit) -> dict:
    """A cached unit's AXI4 read master as top-level members ``axi_araddr``, ..., ``axi_rready`` (the
    master's view: the unit's own signature members), plus ``axi_arid`` (an output, tied to 0 by
    :func:`connect_axi`) and ``axi_rid`` (an input, ignored): one ID."""
    members = {"axi_arid": Out(1), "axi_rid": In(1)}
    for name, member in unit.axi.signature.members.items():
        members[f"axi_{name}"] = Out(member.shape) if member.flow == wiring.Out else In(member.shape)
    return members


def connect_axi(m, top, unit) -> None:
    """Wire ``top``'s ``axi_*`` members (:func:`axi_members`) to ``unit.axi``; ``axi_arid`` is 0."""
    m.d.comb += top.axi_arid.eq(0)
    for name, member in unit.axi.signature.members.items():
        if member.flow == wiring.Out:
            m.d.comb += getattr(top, f"axi_{name}").eq(getattr(unit.axi, name))
        else:
            m.d.comb += getattr(unit.axi, name).eq(getattr(top, f"axi_{name}"))


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
                 index_banks: str = "parity", geometry=None):
        from vqtex.hw.filter import TextureFilter
        unit = {} if geometry is None else {"geometry": geometry, "loadable": True}
        self._filter = TextureFilter(texture_set, lanes=lanes, tag_width=tag_width, frac=frac,
                                     index_banks=index_banks, **unit)
        f = self._filter
        self._strobes = [n for n in f.signature.members if n not in ("i", "o", "bus")]  # stall_output, busy, ...
        super().__init__({
            "i_valid": In(1), "i_ready": Out(1), "i_payload": In(len(f.i.p.as_value())),
            "o_valid": Out(1), "o_ready": In(1), "o_payload": Out(len(f.o.p.as_value())),
            **{n: Out(len(getattr(f, n))) for n in self._strobes},
            **bus_members(f),
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
        connect_bus(m, self, f)
        return m


#: The texel-fetch unit's observability strobes, in the order of their counter slots (batch.h's
#: VQ_C_STROBES + k).
STROBES = ("stall_output", "stall_one_port", "straddle")
#: The halves of the unit (hw.pipeline), each its own CXXRTL model (sim/cxxrtl/driver.cc).
HALVES = ("front", "back")


@dataclass
class MemoryImage:
    """One memory of the elaborated design: debug name (hierarchy joined by spaces), shape, contents."""
    name: str
    width: int
    depth: int
    init: list
    _rows: np.ndarray | None = field(default=None, init=False, repr=False, compare=False)

    def rows(self) -> np.ndarray:
        """Contents as (depth, ceil(width/32)) uint32 little-endian chunks (made once, read-only: a
        library opened for every frame loads the same rows)."""
        if self._rows is None:
            self._rows = self._make_rows()
            self._rows.flags.writeable = False
        return self._rows

    def _make_rows(self) -> np.ndarray:
        cpr = max(1, -(-self.width // 32))
        vals = list(self.init) + [0] * (self.depth - len(self.init))
        if self.width <= 64:
            a = np.array(vals, dtype=np.uint64)
            out = np.empty((self.depth, 2), np.uint32)
            out[:, 0] = (a & 0xFFFFFFFF).astype(np.uint32)
            out[:, 1] = (a >> np.uint64(32)).astype(np.uint32)
            return np.ascontiguousarray(out[:, :cpr])
        raw = b"".join(int(v).to_bytes(cpr * 4, "little") for v in vals)
        return np.frombuffer(raw, dtype="<u4").reshape(self.depth, cpr).copy()


@dataclass
class DesignInfo:
    """One elaborated unit and what the backends and their drivers need to know about it: the
    description every compiled backend (one CXXRTL build, one Verilator build, one ctypes library
    class) works from, whichever the unit."""
    top: object
    fragment: object
    ports: dict                 # port name -> (value, direction) as rtlil.convert wants them
    request_fields: dict        # field -> (offset, width)
    response_fields: dict
    request_width: int
    response_width: int
    tag_width: int
    stages: list                # registers with a valid bit, bit k of the ``valid`` port (REGISTERS)
    strobes: list               # strobe ports, in the order of their counter slots
    memories: list = field(default_factory=list)
    latency: int = 0
    halves: dict = field(default_factory=dict)  # "front"/"back" -> (fragment, ports) of hw.pipeline's halves
    link_width: int = 0
    geometry: object = None     # the loadable unit's Geometry (None: the baked unit); no halves then
    unit: str = "texel_fetch"   # which unit (names it in cache keys and messages)
    columns: tuple = COLUMNS    # request row columns, each a request field the batch API packs
    valid: str = "valid"        # the port of the stages' valid bits (a port_map name)
    verilog_name: str = TOP_NAME            # the Verilog top's module name
    verilog_request: list = field(default_factory=list)     # (Verilog top port, offset in i.payload, width)
    verilog_response: list = field(default_factory=list)    # (Verilog top port, offset in o.payload, width)
    options: tuple = ()         # what, besides the sources, names the build (the quick key): options, contents
    axi_bytes: int = 0          # the AXI4 read master's data bytes (``axi__*`` ports; 0: none)

    @property
    def payload_words(self) -> int:
        """64-bit words of ``i.payload`` (the batch API's VQ_PAYLOAD_WORDS)."""
        return max(1, -(-self.request_width // 64))

    @property
    def bus(self) -> bool:
        """Whether the unit has the loadable unit's Wishbone port (``bus__*`` ports)."""
        return "bus__adr" in self.ports


def _fields(layout) -> dict:
    return {name: (f.offset, f.width) for name, f in layout}


#: How many elaborated units :func:`design_info` and :func:`filter_design_info` keep (least recently
#: used first out): a texel-fetch unit's description is about 1.5 MB, a four-lane filter's about 6 MB.
DESIGNS_KEPT = 8
_designs: OrderedDict = OrderedDict()
_designs_lock = threading.Lock()


def _memoised(key: tuple, make) -> DesignInfo:
    """The unit of ``key`` elaborated once per process (``make()``), then the same :class:`DesignInfo`.
    ``key`` holds everything the elaboration depends on: the unit, its options and its contents'
    digest (:func:`sim.backends.toolchain.texture_set_digest`, as the build cache's quick key), or
    the loadable unit's geometry. Elaborating is most of what a repeated run of a cached build costs
    (0.45 s for the four-lane filter of ``topspin``, 3.5x the simulation of one of its frames), and
    a renderer asks for the same unit every frame."""
    with _designs_lock:
        info = _designs.get(key)
        if info is not None:
            _designs.move_to_end(key)
            return info
    info = make()                           # (two threads may both elaborate one unit: the same result)
    with _designs_lock:
        info = _designs.setdefault(key, info)
        _designs.move_to_end(key)
        while len(_designs) > DESIGNS_KEPT:
            _designs.popitem(last=False)
    return info


def _contents(ts, geometry):
    return texture_set_digest(ts) if geometry is None else ("loadable", geometry.dumps())


def design_info(ts, *, one_port: bool = False, tag_width: int = 8, specialise: bool = True,
                geometry=None) -> DesignInfo:
    """Elaborate ``TexelFetch(ts)`` (with ``geometry``: the loadable unit of that geometry, no
    contents: ``ts`` is loaded later, over the bus) and collect ports, payload layouts, stages and
    memory images. Elaborated once per process for the same options and contents (the same
    :class:`DesignInfo` is returned again: treat it as read-only)."""
    key = ("texel_fetch", one_port, tag_width, specialise or geometry is not None, _contents(ts, geometry))
    return _memoised(key, lambda: _design_info(ts, one_port=one_port, tag_width=tag_width, specialise=specialise,
                                               geometry=geometry, contents=key[-1]))


def _design_info(ts, *, one_port, tag_width, specialise, geometry, contents) -> DesignInfo:
    from vqtex.hw.memories import elaborate, memories
    from vqtex.hw.texel_fetch import REGISTERS, TexelFetch

    if geometry is not None:
        top = TexelFetch(geometry=geometry, loadable=True, one_port=one_port, tag_width=tag_width)
    else:
        top = TexelFetch(ts, one_port=one_port, tag_width=tag_width, specialise=specialise)
    ports = port_map(top)
    whole_ports = ports
    frag = elaborate(top)
    images = [MemoryImage(" ".join(mem.path), mem.width, mem.depth, mem.words) for mem in memories(frag)]
    halves = {}
    for sub, name, _ in frag.subfragments:      # FrontEnd and BackEnd, each converted as its own model
        if str(name) in HALVES and geometry is None:
            ports = {k: v for k, v in port_map(sub.origins[0]).items() if len(v[0])}  # (no 0-bit tag)
            halves[str(name)] = (sub, ports)
    ports = whole_ports
    if geometry is None and set(halves) != set(HALVES):
        raise ToolchainError("TexelFetch is not made of the front and back halves this backend runs")
    req = top.i.p.shape()
    resp = top.o.p.shape()
    names = list(top.signature.members.keys())
    info = DesignInfo(
        top=top, fragment=frag, ports=ports,
        request_fields=_fields(req), response_fields=_fields(resp),
        request_width=req.size, response_width=resp.size, tag_width=tag_width,
        stages=list(REGISTERS),
        strobes=[n for n in STROBES if n in names], memories=images, latency=int(top.latency),
        halves=halves, link_width=len(halves["front"][1]["link"][0]) if halves else 0, geometry=geometry,
        verilog_request=[(f"i_{n}", off, w) for n, (off, w) in _fields(req).items() if w],
        verilog_response=[(f"o_{n}", off, w) for n, (off, w) in _fields(resp).items() if w],
        options=(one_port, tag_width, contents, *(() if specialise or geometry is not None else ("full unit",))))
    return _checked(info)


def filter_design_info(ts, *, lanes: int = 1, frac: int | None = None, tag_width: int = 16,
                       index_banks: str = "parity", bank_depth: int | None = None, geometry=None) -> DesignInfo:
    """Elaborate ``hw.filter.TextureFilter(ts, ...)`` and describe it as :func:`design_info` does the
    texel-fetch unit: one model (no halves), a request row is the pixel's :data:`FIELDS`, the
    strobes (``stall_output``, ``busy``, ``bank_conflict``) in the filter's signature order, and
    ``o.valid`` as its one stage's valid bit ("output"). With ``geometry``, the loadable filter of
    that geometry (no contents: ``ts`` is loaded over its bus). Elaborated once per process, as
    :func:`design_info`."""
    key = ("filter", lanes, frac, tag_width, index_banks, bank_depth, _contents(ts, geometry))
    return _memoised(key, lambda: _filter_design_info(ts, lanes=lanes, frac=frac, tag_width=tag_width,
                                                      index_banks=index_banks, bank_depth=bank_depth,
                                                      geometry=geometry, contents=key[-1]))


def _filter_design_info(ts, *, lanes, frac, tag_width, index_banks, bank_depth, geometry, contents) -> DesignInfo:
    from vqtex.hw.filter import TextureFilter
    from vqtex.hw.memories import elaborate, memories
    unit = {} if bank_depth is None else {"bank_depth": bank_depth}
    if geometry is not None:
        unit.update(geometry=geometry, loadable=True)
        ts = None
    top = TextureFilter(ts, lanes=lanes, tag_width=tag_width, frac=frac, index_banks=index_banks, **unit)
    frag = elaborate(top)
    req, resp = top.i.p.shape(), top.o.p.shape()
    info = DesignInfo(
        top=top, fragment=frag, ports=port_map(top),
        request_fields=_fields(req), response_fields=_fields(resp),
        request_width=req.size, response_width=resp.size, tag_width=tag_width,
        stages=["output"], strobes=[n for n in top.signature.members if n not in ("i", "o", "bus")],
        memories=[MemoryImage(" ".join(m.path), m.width, m.depth, m.words) for m in memories(frag)],
        latency=int(top.latency), unit="filter", columns=FIELDS, valid="o__valid",
        verilog_name=FILTER_TOP_NAME,
        verilog_request=[("i_payload", 0, req.size)], verilog_response=[("o_payload", 0, resp.size)],
        geometry=geometry,
        options=(lanes, index_banks, top.frac, tag_width, bank_depth, contents))
    return _checked(info)


#: The cached unit's strobes, in the order of their counter slots.
CACHED_STROBES = ("stall_memory", "stall_output")


def cached_design_info(ts, config, *, tag_width: int = 8, geometry=None) -> DesignInfo:
    """Elaborate :class:`hw.memory.unit.CachedTexelFetch` (``ts`` baked; its index map and raw
    levels in the external memory of ``config``, :class:`golden.memory.system.MemoryConfig`) and
    describe it as :func:`design_info` does the texel-fetch unit: one model (no halves), a request
    row is (texture, level, i, j), the strobes :data:`CACHED_STROBES`, ``o.valid`` as its one
    stage's valid bit ("output"), and the AXI4 read master as ``axi__*`` (``axi_bytes``; the
    drivers answer it, drivers/axi_slave.h). Its Verilog top is :class:`CachedTexelFetchTop`. What
    names the build: the cache shapes, the FIFO depth and the bus width (the RTL's structure) and
    the set's contents; the memory model is the driver's, set per run. With ``geometry``: the
    loadable cached unit of that geometry (no contents; ``ts`` is loaded over its bus, the ``bus__*``
    ports), one build per geometry and cache configuration for every set it holds."""
    contents = texture_set_digest(ts) if geometry is None else ("loadable", geometry.dumps())
    key = ("cached_texel_fetch", tag_width, config.index_cache, config.raw_cache, config.prefetch, config.bus_bytes,
           contents)
    return _memoised(key, lambda: _cached_design_info(ts, config, tag_width, geometry, contents))


def _cached_design_info(ts, config, tag_width: int, geometry=None, contents=None) -> DesignInfo:
    from vqtex.hw.memories import elaborate, memories
    from vqtex.hw.memory.unit import CachedTexelFetch
    if geometry is not None:
        top = CachedTexelFetch(None, config, tag_width=tag_width, geometry=geometry, loadable=True)
    else:
        top = CachedTexelFetch(ts, config, tag_width=tag_width)
    frag = elaborate(top)
    req, resp = top.i.p.shape(), top.o.p.shape()
    info = DesignInfo(
        top=top, fragment=frag, ports=port_map(top),
        request_fields=_fields(req), response_fields=_fields(resp),
        request_width=req.size, response_width=resp.size, tag_width=tag_width,
        stages=["output"], strobes=list(CACHED_STROBES),
        memories=[MemoryImage(" ".join(m.path), m.width, m.depth, m.words) for m in memories(frag)],
        latency=int(top.latency), unit="cached_texel_fetch", valid="o__valid", verilog_name="cached_texel_fetch",
        verilog_request=[(f"i_{n}", off, w) for n, (off, w) in _fields(req).items() if w],
        verilog_response=[(f"o_{n}", off, w) for n, (off, w) in _fields(resp).items() if w],
        options=(tag_width, config.index_cache, config.raw_cache, config.prefetch, config.bus_bytes, contents),
        axi_bytes=config.bus_bytes, geometry=geometry)
    return _checked(info)


def cached_filter_design_info(ts, config, *, lanes: int = 4, frac: int | None = None,
                              tag_width: int = 16, geometry=None) -> DesignInfo:
    """Elaborate :class:`hw.memory.filter.CachedTextureFilter` and describe it as
    :func:`filter_design_info` does the filter (a request row is the pixel's :data:`FIELDS`) with the
    AXI4 read master as ``axi__*`` (``axi_bytes``, as :func:`cached_design_info`) and the strobes in
    the unit's signature order (``stall_output``, ``stall_memory0`` .. , ``overflow``). What names
    the build: lanes, frac, tag width, cache shapes, FIFO depth, bus width and the set's contents.
    With ``geometry``: the loadable filter of that geometry (no contents; ``ts`` is loaded over its
    bus, the ``bus__*`` ports), one build per geometry and cache configuration for every set."""
    key = ("cached_filter", lanes, frac, tag_width, config.index_cache, config.raw_cache, config.prefetch,
           config.bus_bytes, _contents(ts, geometry))
    return _memoised(key, lambda: _cached_filter_design_info(ts, config, lanes, frac, tag_width, key, geometry))


def _cached_filter_design_info(ts, config, lanes, frac, tag_width, key, geometry=None) -> DesignInfo:
    from vqtex.hw.memories import elaborate, memories
    from vqtex.hw.memory.filter import CachedTextureFilter
    unit = {} if geometry is None else {"geometry": geometry, "loadable": True}
    top = CachedTextureFilter(None if geometry is not None else ts, config, lanes=lanes, tag_width=tag_width,
                              frac=frac, **unit)
    frag = elaborate(top)
    req, resp = top.i.p.shape(), top.o.p.shape()
    info = DesignInfo(
        top=top, fragment=frag, ports=port_map(top),
        request_fields=_fields(req), response_fields=_fields(resp),
        request_width=req.size, response_width=resp.size, tag_width=tag_width,
        stages=["output"], strobes=[n for n in top.signature.members if n not in ("i", "o", "axi", "bus")],
        memories=[MemoryImage(" ".join(m.path), m.width, m.depth, m.words) for m in memories(frag)],
        latency=int(top.latency), unit="cached_filter", columns=FIELDS, valid="o__valid",
        verilog_name="cached_texture_filter",
        verilog_request=[("i_payload", 0, req.size)], verilog_response=[("o_payload", 0, resp.size)],
        options=key[1:], axi_bytes=config.bus_bytes, geometry=geometry)
    return _checked(info)


def _checked(info: DesignInfo) -> DesignInfo:
    if info.request_width > 64 * MAX_PAYLOAD_WORDS:
        raise ToolchainError(f"request payload of {info.request_width} bits: the compiled backends take at most "
                             f"{64 * MAX_PAYLOAD_WORDS}")
    if info.response_width > 64:
        raise ToolchainError(f"response payload of {info.response_width} bits: the compiled backends take at most 64")
    return info


def pack_requests(info: DesignInfo, requests: np.ndarray, *, block: int = 1 << 15) -> np.ndarray:
    """The ``i.payload`` words of (texture, level, i, j) requests, tag = request number. Packed in
    blocks of ``block`` requests so that the temporaries stay in the cache (half the time of
    whole-array passes on 4e6 requests)."""
    req = np.ascontiguousarray(np.asarray(requests).reshape(-1, 4))
    # the same bits as unsigned (two's complement; every field is masked below): a view, no copy
    req = (req if req.dtype in (np.int64, np.uint64) else req.astype(np.int64)).view(np.uint64)
    n = len(req)
    out = np.zeros(n, np.uint64)
    tmp = np.empty(min(n, block), np.uint64)
    columns = {"texture": 0, "level": 1, "i": 2, "j": 3}
    fields = [(columns.get(name), np.uint64(off), np.uint64((1 << width) - 1))
              for name, (off, width) in info.request_fields.items()
              if width and (name in columns or (name == "tag" and info.tag_width))]
    for s in range(0, n, block):
        e = min(n, s + block)
        o, t = out[s:e], tmp[:e - s]
        for col, off, mask in fields:
            np.bitwise_and(req[s:e, col] if col is not None else np.arange(s, e, dtype=np.uint64), mask, out=t)
            if off:
                np.left_shift(t, off, out=t)
            np.bitwise_or(o, t, out=o)
    return out


class CachedTexelFetchTop(wiring.Component):
    """:class:`hw.memory.unit.CachedTexelFetch` with one port per stream member, as
    :class:`TexelFetchTop` (``i_valid``, ``i_ready``, ``i_texture``, ..., ``o_r``, ..., ``o_tag``), the
    strobes ``stall_memory`` and ``stall_output``, and the AXI4 read master as ``axi_araddr``,
    ``axi_arlen``, ..., ``axi_rready`` (AMBA's names after ``axi_``, what bus models such as
    cocotbext-axi find by prefix), with ``axi_arid`` tied to 0 and ``axi_rid`` ignored (one ID).

    The loadable cached unit (``geometry``) has its Wishbone port as ``bus_adr``, ..., ``bus_stall``,
    as :class:`TexelFetchTop`.

    Arguments
    ---------
    texture_set : TextureSet or None
    config : golden.memory.system.MemoryConfig
    tag_width : int
    geometry : Geometry, optional
        The loadable cached unit of this geometry (``texture_set``, if given, its initial contents).
    """

    def __init__(self, texture_set, config, *, tag_width: int = 8, geometry=None):
        from vqtex.hw.memory.unit import CachedTexelFetch
        unit = {} if geometry is None else {"geometry": geometry, "loadable": True}
        self._unit = CachedTexelFetch(texture_set, config, tag_width=tag_width, **unit)
        u = self._unit
        members = {"i_valid": In(1), "i_ready": Out(1), "o_valid": Out(1), "o_ready": In(1),
                   "stall_memory": Out(1), "stall_output": Out(1)}
        members.update({f"i_{n}": In(f.width) for n, f in u.i.p.shape() if f.width})
        members.update({f"o_{n}": Out(f.width) for n, f in u.o.p.shape() if f.width})
        members.update(axi_members(u))
        members.update(bus_members(u))
        super().__init__(members)

    @property
    def unit(self):
        return self._unit

    def elaborate(self, platform):
        m = Module()
        m.submodules.unit = u = self._unit
        m.d.comb += [u.i.valid.eq(self.i_valid), self.i_ready.eq(u.i.ready),
                     self.o_valid.eq(u.o.valid), u.o.ready.eq(self.o_ready),
                     self.stall_memory.eq(u.stall_memory), self.stall_output.eq(u.stall_output)]
        m.d.comb += [getattr(u.i.p, n).eq(getattr(self, f"i_{n}")) for n, f in u.i.p.shape() if f.width]
        m.d.comb += [getattr(self, f"o_{n}").eq(getattr(u.o.p, n)) for n, f in u.o.p.shape() if f.width]
        connect_axi(m, self, u)
        connect_bus(m, self, u)
        return m


class CachedFilterTop(wiring.Component):
    """:class:`hw.memory.filter.CachedTextureFilter` with one port per stream member as
    :class:`FilterTop` (``i_valid``, ``i_ready``, ``i_payload``, ``o_valid``, ``o_ready``,
    ``o_payload``), its strobes, and the AXI4 read master as ``axi_*`` as :class:`CachedTexelFetchTop`
    (``axi_arid`` tied to 0, ``axi_rid`` ignored). The loadable filter (``geometry``) has its
    Wishbone port as ``bus_adr``, ..., ``bus_stall``, as :class:`TexelFetchTop`.

    Arguments
    ---------
    texture_set, config, lanes, tag_width, frac
        As for :class:`hw.memory.filter.CachedTextureFilter`.
    geometry : Geometry, optional
        The loadable filter of this geometry (``texture_set``, if given, its initial contents).
    """

    def __init__(self, texture_set, config, *, lanes: int = 4, tag_width: int = 16, frac: int | None = None,
                 geometry=None):
        from vqtex.hw.memory.filter import CachedTextureFilter
        unit = {} if geometry is None else {"geometry": geometry, "loadable": True}
        self._unit = u = CachedTextureFilter(texture_set, config, lanes=lanes, tag_width=tag_width, frac=frac,
                                             **unit)
        self._strobes = [n for n in u.signature.members if n not in ("i", "o", "axi", "bus")]
        members = {"i_valid": In(1), "i_ready": Out(1), "i_payload": In(len(u.i.p.as_value())),
                   "o_valid": Out(1), "o_ready": In(1), "o_payload": Out(len(u.o.p.as_value())),
                   **{n: Out(1) for n in self._strobes}}
        members.update(axi_members(u))
        members.update(bus_members(u))
        super().__init__(members)

    @property
    def unit(self):
        return self._unit

    @property
    def latency(self) -> int:
        return self._unit.latency

    def elaborate(self, platform):
        m = Module()
        m.submodules.unit = u = self._unit
        m.d.comb += [u.i.valid.eq(self.i_valid), self.i_ready.eq(u.i.ready), u.i.p.eq(self.i_payload),
                     self.o_valid.eq(u.o.valid), u.o.ready.eq(self.o_ready), self.o_payload.eq(u.o.p)]
        m.d.comb += [getattr(self, n).eq(getattr(u, n)) for n in self._strobes]
        connect_axi(m, self, u)
        connect_bus(m, self, u)
        return m
