"""The elaborated texel-fetch unit as the simulators see it: ports, payload layouts, memories.

What every backend that runs the RTL outside Amaranth (CXXRTL, Verilator, Icarus) needs to know about
the design, in one place: the top-level port map (one port per signature member, named as Amaranth
names them), the Verilog top ``TexelFetchTop`` with one port per stream member, the payload field
offsets and widths, the observability strobes, the valid bits of the registers, the two halves of
the unit, the memories and their contents, and the packing of (texture, level, i, j) requests into
``i.payload`` words. The CXXRTL backend, the Verilator backend and the Icarus cross-check import it;
it imports none of them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from amaranth import Module
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .toolchain import ToolchainError

__all__ = ["TOP_NAME", "STROBES", "HALVES", "TexelFetchTop", "port_map", "request_ports", "response_ports",
           "MemoryImage", "DesignInfo", "design_info", "pack_requests"]

TOP_NAME = "texel_fetch"


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
        self._bus = []
        if geometry is not None:            # the slave's view (the unit's own signature members)
            for name, member in self._fetch.bus.signature.members.items():
                members[f"bus_{name}"] = (In if member.flow == In else Out)(member.shape)
                self._bus.append(name)
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
        for name in self._bus:
            member = f.bus.signature.members[name]
            if member.flow == In:           # driven by the initiator: an input of the top
                m.d.comb += getattr(f.bus, name).eq(getattr(self, f"bus_{name}"))
            else:
                m.d.comb += getattr(self, f"bus_{name}").eq(getattr(f.bus, name))
        return m


#: Observability strobes summed by the driver: port name -> counter slot name in batch.h.
STROBES = {"stall_output": "VQ_C_STALL_OUTPUT", "stall_one_port": "VQ_C_STALL_ONE_PORT",
           "straddle": "VQ_C_STRADDLES"}
#: The halves of the unit (hw.pipeline), each its own CXXRTL model (sim/cxxrtl/driver.cc).
HALVES = ("front", "back")


@dataclass
class MemoryImage:
    """One memory of the elaborated design: debug name (hierarchy joined by spaces), shape, contents."""
    name: str
    width: int
    depth: int
    init: list

    def rows(self) -> np.ndarray:
        """Contents as (depth, ceil(width/32)) uint32 little-endian chunks."""
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
    """The elaborated TexelFetch and what the drivers need to know about its ports and memories."""
    top: object
    fragment: object
    ports: dict                 # port name -> (value, direction) as rtlil.convert wants them
    request_fields: dict        # field -> (offset, width)
    response_fields: dict
    request_width: int
    response_width: int
    tag_width: int
    stages: list                # registers with a valid bit, bit k of the ``valid`` port (REGISTERS)
    strobes: list               # strobe ports present (keys of STROBES)
    memories: list = field(default_factory=list)
    latency: int = 0
    halves: dict = field(default_factory=dict)  # "front"/"back" -> (fragment, ports) of hw.pipeline's halves
    link_width: int = 0
    geometry: object = None     # the loadable unit's Geometry (None: the baked unit); no halves then


def _fields(layout) -> dict:
    return {name: (f.offset, f.width) for name, f in layout}


def design_info(ts, *, one_port: bool = False, tag_width: int = 8, specialise: bool = True,
                geometry=None) -> DesignInfo:
    """Elaborate ``TexelFetch(ts)`` (with ``geometry``: the loadable unit of that geometry, no
    contents: ``ts`` is loaded later, over the bus) and collect ports, payload layouts, stages and
    memory images."""
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
        halves=halves, link_width=len(halves["front"][1]["link"][0]) if halves else 0, geometry=geometry)
    for what, width in (("request", info.request_width), ("response", info.response_width)):
        if width > 64:
            raise ToolchainError(f"{what} payload of {width} bits: the compiled backends take at most 64")
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
