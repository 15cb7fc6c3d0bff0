"""TexelFetch: the whole texel-fetch pipeline of Beers, Agrawala and Chaddha (SIGGRAPH 1996).

A request (texture, level, i, j, tag) reads as a story through the blocks::

    request register -> descriptor table -> block address shifter -> index reader -> codebook ROM -> colour matrix
       (1 cycle)          (1 cycle)          (1 cycle)                (5 cycles)      (4 cycles)      (3 cycles)

and leaves as an RGBA8888 response with its tag, in request order, ``LATENCY`` = 15 cycles later.
The request is registered before the table is read (the table's address inputs, and in the
loadable unit the multiplexer between its LUT RAMs, start from flip-flops of the unit's own:
docs/area.md, "The descriptor stage").
Raw levels take the same path (the shifter computes the raw address, the codebook ROM stage reads
the raw memory, the colour matrix passes the word through), so the latency does not depend on the
request.

The unit is two halves wired back to back (:mod:`hw.pipeline`): the front end
(:class:`hw.front_end.FrontEnd`: request, descriptor, address, index reader and the pipeline control) and the
back end (:class:`hw.back_end.BackEnd`: codebook ROM, colour matrix, the skid register's data),
joined by one registered ``link``. Pipeline control is in one place (:class:`hw.front_end.FrontEnd`). Every register advances on
``advance``, a flip-flop: ``advance`` is high in a cycle when the output was not stalled in the
previous one (``o.valid & ~o.ready``); a response pushed out of the last stage in a stalled cycle
waits in the skid register, which the output shows first. With ``one_port`` the stages up to the
index reader's bit-address stage (``UPSTREAM_STAGES``) also wait while it ``hold``\\ s.
"""

from __future__ import annotations

from amaranth import *
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

from vqtex.golden.format import TextureSet
from vqtex.golden.geometry import Geometry
from vqtex.golden.register_map import LoadError, RegisterMap

from .back_end import BackEnd
from .banked_rom import BANK_DEPTH, LOADABLE_BANK_DEPTH
from .bus_port import BusPort, load_layout, wishbone_signature
from .features import Features
from .front_end import FrontEnd, index_port_members
from .pipeline import (FRONT_STAGES, LATENCY, REGISTERS, STAGES, UPSTREAM_STAGES, RequestLayout,
                       ResponseLayout, pack)

__all__ = ["TexelFetch", "RequestLayout", "ResponseLayout", "LATENCY", "STAGES", "REGISTERS",
           "UPSTREAM_STAGES", "FRONT_STAGES"]


class TexelFetch(wiring.Component):
    """The texel-fetch unit holding the memories of one texture set.

    Latency: ``LATENCY`` = 15 cycles, a constant. A request accepted in cycle ``t`` (``i.valid`` and
    ``i.ready`` high) is presented on ``o`` (``o.valid`` high) in cycle ``t + 15`` when no
    backpressure or one-port stall intervened.

    Throughput: one request per cycle whenever the output is not stalled, whatever the index width
    (the index memory's even and odd banks deliver both words of a straddling index together).
    With ``one_port``, every straddling index read costs exactly one extra cycle.

    Cycle count: with requests presented back to back from cycle 0 and ``o.ready`` always high,
    N requests transfer their last response in cycle ``N - 1 + LATENCY``, i.e. in ``N + LATENCY``
    cycles counted from the first cycle ``i.valid`` is high up to and including the cycle the last
    response transfers (``+ straddles`` with ``one_port``). In general every cycle is one of the
    first ``LATENCY``, a transfer, a cycle of output backpressure or a one-port bubble at the output.

    Backpressure: every pipeline register (including the memories' read registers) advances on
    ``advance``, a register set to ``~(o.valid & ~o.ready)`` in every cycle: the cycle after an
    output stall, the pipeline waits. The response that left the last stage in the stalled cycle is
    kept in a skid register, which drives ``o`` until it transfers; so no response is lost,
    duplicated or reordered. ``i.ready = advance & ~hold`` and ``o.valid`` depend on flip-flops
    only, not combinationally on ``o.ready``.

    Loadable (``loadable=True``): the unit is built from a ``geometry`` alone
    (:class:`golden.geometry.Geometry`: memory depths, field widths, the formats, index widths and
    layouts it serves); its memories and colour matrix are loaded at run time through the Wishbone
    slave ``bus`` (:mod:`hw.bus_port`; register map :mod:`golden.register_map`). While the host
    holds a bus cycle no request is accepted, and a transfer waits until no request is in flight
    (the drain rule). ``texture_set``, if given, is the initial contents. Same latency,
    throughput and cycle counts as the baked unit.

    Arguments
    ---------
    texture_set : TextureSet, optional
        The memories: descriptor table, index memory, codebook memory, raw memory, colour matrix
        (the ROMs of the baked unit; the initial contents of a loadable one).
    geometry : Geometry, optional
        What the unit holds and serves (default: ``Geometry.of(texture_set)``, the smallest that
        holds the set). Required for a loadable unit without contents.
    loadable : bool
        Memories loaded over the bus port (see above); ``specialise`` is then ignored: the unit
        serves every set the geometry holds.
    bus_port : bool
        Loadable only: the unit has its own Wishbone port (default). False: the port is its
        parent's (the texture filter's lanes share one): members ``load`` (the port's load
        command) and ``load_data`` (this unit's read answer) instead of ``bus``, and the parent
        keeps requests away while its host holds the bus.
    one_port : bool
        Single-bank index memory (reproduces the paper's straddle penalty in cycle counts).
    tag_width : int
        Width of the request tag carried to the response.
    bank_depth : int, optional
        Words per block RAM bank of the index, codebook and raw memories (a power of two; default
        512 for the baked unit, one ECP5 DP16KD at 36 bits, and 1024 for a loadable one, one
        DP16KD at 18 bits per port in true dual-port mode; see :class:`hw.banked_rom.BankedROM`).
    specialise : bool
        Build only what the texture set needs (default; :class:`hw.features.Features`: no colour
        matrix without yuv411, no multipliers where shifts do, no raw path without raw levels, no
        odd index bank when no index straddles, constant descriptor fields as constants). False:
        the full unit, every path present (what any texture set with memories of these shapes
        needs). Both are bit-exact against the golden model on valid requests, with the same
        latency, throughput and cycle counts.
    raw_port : bool
        The raw memory is outside the unit (external memory, :mod:`hw.memory`): member ``raw_in``,
        the raw word of the request whose index the front end hands the back end in this cycle
        (the request at stage 7, as ``index_response`` is); ignored without raw levels.
    index_port : bool
        The index reader is outside the unit (the lanes of a texture filter share index memories
        banked by block parity, :mod:`hw.filter.index_banks`; the cached unit's index words come
        from external memory): members ``index_request`` and ``index_response`` (see
        :class:`hw.front_end.FrontEnd`); ignored when every level is raw. A loadable unit takes it
        only without its own bus port (``bus_port=False``: the loadable cached unit, whose index
        memory is not on chip, :class:`hw.memory.unit.CachedTexelFetch`).

    Members
    -------
    i : In(stream.Signature(RequestLayout(texture_bits, tag_width)))
        Requests. Requests must be valid (texture and level exist, texel inside the level); the
        unit does not check (see :func:`golden.fetch.check_requests`).
    o : Out(stream.Signature(ResponseLayout(tag_width)))
        Responses, in request order.
    straddle : Out(1)
        Strobe: an index read that straddles a word boundary advances to the extract stage
        (once per straddling request, in both modes).
    stall_one_port : Out(1)
        Strobe: a cycle spent on the extra read of a straddling index (one-port only).
    stall_output : Out(1)
        ``o.valid & ~o.ready``: a cycle of output backpressure.
    valid : Out(len(REGISTERS))
        Valid bits of the registers, bit ``k`` for ``REGISTERS[k]`` (the 15 stages, then the skid
        register; ``o.valid`` is ``valid[14] | valid[15]``), for occupancy reports. One vector, so
        that a simulator samples every stage with one read.

    bus : In(hw.bus_port.wishbone_signature(...))
        Only when loadable: the Wishbone B4 pipelined slave port.

    Raises
    ------
    TypeError
        If ``texture_set`` is not a TextureSet or ``tag_width`` is not a non-negative int.
    golden.register_map.LoadError
        If a loadable unit's initial contents do not fit its geometry.
    ValueError
        If ``bank_depth`` is not a power of two.
    golden.format.FormatError
        If the texture set's descriptors point outside its memories.
    """

    def __init__(self, texture_set: TextureSet | None = None, *, one_port: bool = False, tag_width: int = 8,
                 bank_depth: int | None = None, specialise: bool = True, index_port: bool = False,
                 geometry: Geometry | None = None, loadable: bool = False, bus_port: bool = True,
                 raw_port: bool = False):
        if texture_set is not None and not isinstance(texture_set, TextureSet):
            raise TypeError(f"texture_set must be a TextureSet, not {type(texture_set).__name__}")
        if texture_set is None and not (loadable and isinstance(geometry, Geometry)):
            raise TypeError("a TexelFetch without a texture set must be loadable and given a Geometry")
        if geometry is not None and not isinstance(geometry, Geometry):
            raise TypeError(f"geometry must be a Geometry, not {type(geometry).__name__}")
        if not isinstance(tag_width, int) or tag_width < 0:
            raise TypeError(f"tag_width must be a non-negative integer, not {tag_width!r}")
        if bank_depth is None:
            bank_depth = LOADABLE_BANK_DEPTH if loadable else BANK_DEPTH
        if not isinstance(bank_depth, int) or bank_depth < 1 or bank_depth & (bank_depth - 1):
            raise ValueError(f"bank_depth must be a power of two, not {bank_depth!r}")
        if texture_set is not None:
            texture_set.validate()
        self._ts = texture_set
        self._geometry = geometry if geometry is not None else Geometry.of(texture_set)
        if index_port and one_port:
            raise ValueError("an index reader outside the unit has both word banks: no one_port")
        self._loadable = bool(loadable)
        if self._loadable and index_port and bus_port:
            raise ValueError("a loadable unit with its own bus port keeps its index reader (no index_port)")
        if texture_set is not None and geometry is not None:
            misfit = self._geometry.fits(texture_set)
            if misfit:
                raise LoadError("the texture set does not fit the unit's geometry: " + "; ".join(misfit))
        self._one_port = bool(one_port)
        self._tag_width = tag_width
        self._bank_depth = bank_depth
        self._features = (Features.of_geometry(self._geometry) if self._loadable
                          else Features.for_set(texture_set, bool(specialise)))
        self._index_port = bool(index_port) and self._features.compressed
        self._texture_bits = self._geometry.texture_bits
        self._load = load_layout(RegisterMap(self._geometry)) if self._loadable else None
        members = {
            "i": In(stream.Signature(RequestLayout(self._texture_bits, tag_width))),
            "o": Out(stream.Signature(ResponseLayout(tag_width))),
            "straddle": Out(1),
            "stall_one_port": Out(1),
            "stall_output": Out(1),
        }
        members["valid"] = Out(len(REGISTERS))
        if self._index_port:
            members.update(index_port_members(self._geometry, self._features))
        self._raw_port = bool(raw_port) and self._features.raw
        if self._raw_port:
            members["raw_in"] = In(32)
        self._bus_port = self._loadable and bool(bus_port)
        if self._bus_port:
            members["bus"] = In(wishbone_signature(RegisterMap(self._geometry).addr_bits))
        elif self._loadable:
            members.update(load=In(self._load), load_data=Out(32))
        super().__init__(members)

    @property
    def latency(self) -> int:
        """Cycles from accepting a request to presenting its response: ``LATENCY`` (15)."""
        return LATENCY

    @property
    def one_port(self) -> bool:
        return self._one_port

    @property
    def texture_set(self) -> TextureSet | None:
        """The contents (the ROMs, or a loadable unit's initial contents; None: none)."""
        return self._ts

    @property
    def geometry(self) -> Geometry:
        return self._geometry

    @property
    def loadable(self) -> bool:
        return self._loadable

    @property
    def load_layout(self):
        """The load command's layout (:func:`hw.bus_port.load_layout`; None for the baked unit)."""
        return self._load

    @property
    def tag_width(self) -> int:
        return self._tag_width

    @property
    def bank_depth(self) -> int:
        return self._bank_depth

    @property
    def texture_bits(self) -> int:
        return self._texture_bits

    @property
    def specialised(self) -> bool:
        return self._features.specialised

    @property
    def features(self) -> Features:
        """What the unit was built with (:class:`hw.features.Features`)."""
        return self._features

    def elaborate(self, platform):
        m = Module()
        load = self._load
        # The loadable unit adds the codebook address cb_base + index in its index reader's last
        # stage; with the index reader outside (the cached unit's index_port) the codebook adds it.
        summed = self._loadable and not self._index_port
        m.submodules.front = front = FrontEnd(self._ts, one_port=self._one_port, tag_width=self._tag_width,
                                              bank_depth=self._bank_depth, features=self._features,
                                              index_port=self._index_port, geometry=self._geometry, load=load,
                                              summed=summed)
        if self._index_port:
            m.d.comb += [self.index_request.eq(front.index_request), front.index_response.eq(self.index_response)]
        m.submodules.back = back = BackEnd(self._ts, bank_depth=self._bank_depth, features=self._features,
                                           geometry=self._geometry, load=load, raw_port=self._raw_port,
                                           summed=summed)
        if self._raw_port:
            m.d.comb += back.raw_in.eq(self.raw_in)
        if load is not None and not self._bus_port:     # the parent's port (a filter's lanes)
            m.d.comb += [front.pause.eq(0), front.load.eq(self.load), back.load.eq(self.load),
                         self.load_data.eq(front.load_data | back.load_data)]
        elif load is not None:              # the bus port and the drain rule (hw.bus_port)
            m.submodules.bus_port = port = BusPort(self._geometry)
            wiring.connect(m, wiring.flipped(self.bus), port.bus)
            m.d.comb += [
                port.idle.eq(front.valid == 0),
                front.pause.eq(port.pause),
                front.load.eq(port.load), back.load.eq(port.load),
                port.load_data.eq(front.load_data | back.load_data),
            ]
        wiring.connect(m, wiring.flipped(self.i), front.i)          # the request stream, forwarded
        m.d.comb += [
            self.o.valid.eq(front.o_valid), front.o_ready.eq(self.o.ready),
            self.o.p.eq(pack(self.o.p.shape(), {
                "r": back.rgba.r, "g": back.rgba.g, "b": back.rgba.b, "a": back.rgba.a, "tag": front.o_tag})),
            back.link.eq(front.link),
            self.straddle.eq(front.straddle), self.stall_one_port.eq(front.stall_one_port),
            self.stall_output.eq(front.stall_output), self.valid.eq(front.valid),
        ]
        return m
