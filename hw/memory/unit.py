"""CachedTexelFetch: the texel-fetch unit with its index map and raw levels in external memory.

::

    i -> descriptor -> block address -> CachedReader (tag check, FIFO, AXI, data read)
                                              |  the request, its index words or raw word
                                              v
                           TexelFetch(index_port, raw_port): descriptor ... colour matrix -> o

The address stages (the unit's own :class:`hw.descriptor.DescriptorTable` and
:class:`hw.address.BlockAddress`, two stream registers) find the words a request reads (``w =
base + (k * b >> log2 W)`` and whether the index straddles, or the raw word); the
:class:`hw.memory.reader.CachedReader` reads them through the caches; the texel pipeline
(:class:`hw.texel_fetch.TexelFetch`, with its index reader and raw memory outside) takes the request
when it advances and, ``FRONT_STAGES`` (8) advancing cycles later, gets the index (extracted here from the carried
words) and the raw word on ``index_response`` and ``raw_in``. The codebook, the descriptor tables
and the colour matrix stay on chip (baked from ``texture_set``, or loaded: below).

Loadable (``loadable=True``, built from a ``geometry`` alone): the descriptor tables (the address
stages' and the pipeline's, one write reaching both), the codebook and the colour matrix are loaded
through the Wishbone slave ``bus`` of the loadable unit (:class:`hw.bus_port.BusPort`, the same
drain rule), and where the host put the set in external memory is two more control registers,
``INDEX_BASE`` and ``RAW_BASE`` (byte addresses; ``golden.register_map.RegisterMap(geometry,
external=True)``), added to the words' numbers in the address stage. The index and raw regions
are not on chip (an access is an error): the host writes ``Layout.image`` into the external
memory. Every accepted bus write empties the caches (the reader is reset in the cycle the write
reaches the unit; the drain rule has emptied it), so a stream after a load starts from empty
caches, as golden's cycle model does. The requests' timing is the baked unit's (below, with the
layout the base registers give); the bus's is the loadable unit's (:mod:`hw.bus_port`: a load of N
writes takes ``golden.register_map.load_cycles(N)``), and its drain rule counts the address
stages, the reader (its reference FIFO and output register) and the texel pipeline as in flight.

Timing: :func:`golden.memory.timing.run` (``address_stages`` 2, the texel pipeline as consumer),
cycle for cycle; with every reference a hit, ``LATENCY + 5`` cycles from ``i`` to ``o`` and one
request per cycle. A miss reaches the texel pipeline as cycles without a request, and ``i.ready``
falls when the address stages and the reference FIFO are full.

Arguments
---------
texture_set : TextureSet or None
    The baked contents (or a loadable unit's initial contents, its bases ``Layout.of``'s).
config : golden.memory.system.MemoryConfig
tag_width : int
geometry : golden.geometry.Geometry, optional
    What the unit serves (default ``Geometry.of(texture_set)``); required without a texture set.
loadable : bool
    Descriptors, codebook, matrix and base registers loaded over ``bus`` (above).

Members
-------
i : In(stream.Signature(hw.pipeline.RequestLayout))
o : Out(stream.Signature(hw.pipeline.ResponseLayout))
stall_memory : Out(1)
    Strobe: the cache block's data read waits for a line fill (:class:`hw.memory.reader.CachedReader`).
stall_output : Out(1)
    ``o.valid & ~o.ready``.
axi : Out(hw.memory.axi.axi4_read_signature(32, 8 * bus_bytes))
bus : In(hw.bus_port.wishbone_signature(RegisterMap(geometry, external=True).addr_bits))
    Only when loadable.
"""

from __future__ import annotations

from amaranth import *
from amaranth.lib import data, stream, wiring
from amaranth.lib.wiring import In, Out

from vqtex.golden.geometry import Geometry
from vqtex.golden.memory.system import Layout
from vqtex.golden.register_map import BASE_REGISTERS, REGIONS, RegisterMap, base_words

from ..address import BlockAddress
from ..banked_rom import addr_bits
from ..bus_port import ANSWER_LATENCY, BusPort, delayed, or_all, wishbone_signature
from ..descriptor import DescriptorTable
from ..features import Features
from ..pipeline import RequestLayout, ResponseLayout
from ..texel_fetch import FRONT_STAGES, LATENCY, TexelFetch
from .axi import axi4_read_signature
from .reader import CachedReader

__all__ = ["CachedTexelFetch", "ADDRESS_STAGES", "cached_lane", "base_registers"]

#: The unit's own address stages in front of the caches (descriptor, block address).
ADDRESS_STAGES = 2


class CachedTexelFetch(wiring.Component):
    __doc__ = __doc__

    def __init__(self, texture_set, config, *, tag_width: int = 8, geometry: Geometry | None = None,
                 loadable: bool = False):
        if texture_set is None and not (loadable and isinstance(geometry, Geometry)):
            raise TypeError("a CachedTexelFetch without a texture set must be loadable and given a Geometry")
        self._ts = texture_set
        self._config = config
        self._tag_width = tag_width
        self._loadable = bool(loadable)
        self._layout = Layout.of(texture_set) if texture_set is not None else None
        unit = {"geometry": geometry, "loadable": True, "bus_port": False} if self._loadable else {}
        if not self._loadable and geometry is not None:
            unit["geometry"] = geometry
        self._tf = TexelFetch(texture_set, tag_width=tag_width, index_port=True, raw_port=True, **unit)
        self._features = self._tf.features
        tb = self._tf.texture_bits
        members = {
            "i": In(stream.Signature(RequestLayout(tb, tag_width))),
            "o": Out(stream.Signature(ResponseLayout(tag_width))),
            "stall_memory": Out(1), "stall_output": Out(1),
            "axi": Out(axi4_read_signature(32, 8 * config.bus_bytes)),
        }
        if self._loadable:
            self._map = RegisterMap(self._tf.geometry, external=True)
            members["bus"] = In(wishbone_signature(self._map.addr_bits))
        super().__init__(members)

    @property
    def fetch(self) -> TexelFetch:
        """The texel pipeline behind the caches (its ``features``, ``geometry``)."""
        return self._tf

    @property
    def geometry(self) -> Geometry:
        return self._tf.geometry

    @property
    def loadable(self) -> bool:
        return self._loadable

    @property
    def register_map(self) -> RegisterMap | None:
        """The bus port's map (``RegisterMap(geometry, external=True)``; None for the baked unit)."""
        return self._map if self._loadable else None

    @property
    def latency(self) -> int:
        """Cycles from ``i`` to ``o`` when every reference hits: ``LATENCY + 5``."""
        return LATENCY + ADDRESS_STAGES + CachedReader.LATENCY

    def elaborate(self, platform):
        m = Module()
        m.submodules.texel = tf = self._tf
        en1, en2 = Signal(), Signal()
        lane = {}
        if self._loadable:
            m.submodules.bus_port = port = BusPort(self.geometry, external=True)
            wiring.connect(m, wiring.flipped(self.bus), port.bus)
            # the texel pipeline's load command (its map's offsets are wider: it has no index or raw
            # words here, but the same layout as a loadable unit's own)
            m.d.comb += [tf.load.write.eq(port.load.write), tf.load.read.eq(port.load.read),
                         tf.load.region.eq(port.load.region), tf.load.offset.eq(port.load.offset),
                         tf.load.data.eq(port.load.data)]
            bases, answer = base_registers(m, port.load, self._map, self._layout)
            m.d.comb += port.load_data.eq(or_all([tf.load_data, answer]))
            # any accepted write empties the caches (the drain rule has emptied the unit)
            lane = {"load": tf.load, "bases": bases, "flush": port.load.write}
        reader = cached_lane(m, "", self._ts, self._features, self._config, self._layout, tf, self.i.p, (en1, en2),
                             **lane)
        wiring.connect(m, reader.axi, wiring.flipped(self.axi))
        # -- the address stages: two stream registers, moving as a chain ----------------------------
        # (a loadable unit takes no request while the host holds the bus: the drain rule)
        v1, v2 = Signal(), Signal()
        taken = self.i.valid & ~port.pause if self._loadable else self.i.valid
        m.d.comb += [
            en2.eq(~v2 | reader.i.ready),
            en1.eq(~v1 | en2),
            self.i.ready.eq(en1 & ~port.pause if self._loadable else en1),
            reader.i.valid.eq(v2),
        ]
        with m.If(en1):
            m.d.sync += v1.eq(taken)
        with m.If(en2):
            m.d.sync += v2.eq(v1)
        # -- the texel pipeline takes the reader's output when it advances --------------------------
        m.d.comb += [tf.i.valid.eq(reader.o.valid), reader.o.ready.eq(tf.i.ready)]
        wiring.connect(m, tf.o, wiring.flipped(self.o))
        m.d.comb += [self.stall_memory.eq(reader.stall_fill), self.stall_output.eq(tf.stall_output)]
        if self._loadable:
            # the drain rule: nothing in the address stages, the reader (requests in minus out: its
            # FIFO and output register; no burst is in flight without a reference waiting on it) or
            # the texel pipeline
            held = Signal(range(self._config.prefetch + 8), name="reader_held")
            m.d.sync += held.eq(held + (reader.i.valid & reader.i.ready) - (reader.o.valid & reader.o.ready))
            m.d.comb += port.idle.eq(~v1 & ~v2 & (held == 0) & (tf.valid == 0))
        return m


def base_registers(m, load, rmap: RegisterMap, layout: Layout | None):
    """The base registers of the loadable cached unit (reset-less, as the other loaded contents):
    written and read by the load command ``load`` (registered, as :class:`hw.color_matrix.ColorMatrix`'s
    registers), read back ``ANSWER_LATENCY`` cycles after acceptance. Returns ``({"index": word
    number of index word 0, "raw": word number of raw word 0}, answer)``: the index base in index
    words, the raw base in 4-byte words. Initial values: ``layout``'s (the initial contents'), or 0."""
    low = rmap.base_bits()
    init = base_words(layout) if layout is not None else dict.fromkeys(BASE_REGISTERS, 0)
    regs = {name: Signal(32 - low[name], name=name.lower(), reset_less=True, init=init[name] >> low[name])
            for name in BASE_REGISTERS}
    answer = Signal(32, name="base_answer")
    m.d.sync += answer.eq(0)
    mine = load.region == REGIONS["control"]
    for name, reg in regs.items():
        here = mine & (load.offset == BASE_REGISTERS[name][0])
        with m.If(load.write & here):
            m.d.sync += reg.eq(load.data[low[name]:])
        with m.If(load.read & here):
            m.d.sync += answer.eq(reg << low[name])
    return ({"index": regs["INDEX_BASE"], "raw": regs["RAW_BASE"]},
            delayed(m, answer, ANSWER_LATENCY - 2, name="base_answer"))


def cached_lane(m, prefix: str, ts, feat, config, layout, tf, request, en, joint: bool = False, *, load=None,
                bases=None, flush=None):
    """One lane of the cached unit, built into ``m``: the address stages' datapath (descriptor and
    block address, loaded on ``en = (en1, en2)``, the enables of the two stream registers, which the
    caller drives and whose valid bits it keeps), a :class:`hw.memory.reader.CachedReader` (returned;
    the caller drives ``i.valid``, ``o.ready`` and connects ``axi``), and the texel pipeline ``tf``'s
    payload, ``index_response`` and ``raw_in`` (the words riding beside its first ``FRONT_STAGES``
    stages). The
    caller drives ``tf.i.valid``. ``request``: the payload entering the first address stage (a
    ``hw.pipeline.RequestLayout`` view). Submodules are named with ``prefix``. ``joint``: the
    reader's tag check waits for ``check_go`` (every lane's check together, driven by the caller).

    The loadable cached unit's lane: ``load``, the load command its descriptor table takes (the
    texel pipeline's, whose copy answers the bus's reads); ``bases``, the base registers (``index``
    in index words, ``raw`` in 4-byte words; without them, ``layout``'s constant bases); ``flush``,
    a strobe that resets the reader (its caches emptied)."""
    g = tf.geometry
    widths = g.descriptor_widths()
    W = g.word_bits
    en1, en2 = en
    req_bits = len(request.as_value())
    # what rides through the reader beside the words: the request, the bit offset and width
    ride = data.StructLayout({"request": req_bits, "off": max(1, (W - 1).bit_length()), "b": 5})
    reader = CachedReader(config, word_bits=W, raw_base=layout.raw_base if bases is None else 0, word_addr_bits=32,
                          tag_width=len(Signal(ride).as_value()), joint=joint)
    m.submodules[prefix + "reader"] = reader if flush is None else ResetInserter({"sync": flush})(reader)

    # -- the address stages' datapath ------------------------------------------------------------------
    m.submodules[prefix + "descriptor"] = desc = DescriptorTable(
        ts, features=feat, geometry=g, load=None if load is None else load.shape())
    if load is not None:
        m.d.comb += desc.load.eq(load)          # (its read answer is the texel pipeline's copy's)
    m.submodules[prefix + "address"] = addr = BlockAddress(
        base_bits=widths["base"], k_bits=g.k_bits, raw_bits=addr_bits(g.raw_words), raw=feat.raw,
        twiddle=feat.twiddled, linear=0 in feat.layouts, word_bits=W)
    req1 = Signal.like(request.as_value(), name=prefix + "request_descriptor")
    req2 = Signal.like(request.as_value(), name=prefix + "request_address")
    with m.If(en1):
        m.d.sync += req1.eq(request.as_value())
    with m.If(en2):
        m.d.sync += req2.eq(req1)
    p1 = request.shape()(req1)
    m.d.comb += [desc.texture.eq(request.texture), desc.level.eq(request.level), desc.en.eq(en1)]
    row = desc.fields()
    m.d.comb += [
        addr.i.eq(p1.i), addr.j.eq(p1.j),
        addr.log2w.eq(row.log2w), addr.log2bw.eq(row.log2bw), addr.log2bh.eq(row.log2bh),
        addr.base.eq(row.base), addr.en.eq(en2),
    ]
    if addr.twiddle:
        m.d.comb += [addr.layout.eq(row.layout), addr.log2h.eq(row.log2h)]
    m.d.comb += addr.index_bits.eq(row.index_bits)
    row2 = Signal.like(desc.row, name=prefix + "row_address")
    with m.If(en2):
        m.d.sync += row2.eq(desc.row)
    d2 = desc.fields(row2)
    # the words, registered by the address stage (w = base + (k * b >> log2 W), off = k * b mod
    # W, the straddle; so the tag check's cycle starts at registers); raw: the raw word
    word = Signal(32, name=prefix + "word")
    raw_word = addr.raw_addr if feat.raw else 0
    if bases is None:
        m.d.comb += word.eq(Mux(d2.compressed, addr.word, raw_word))
    else:                                   # where the host put the set (the base registers)
        m.d.comb += word.eq(Mux(d2.compressed, bases["index"] + addr.word, bases["raw"] + raw_word))
    r = Signal(ride, name=prefix + "ride")
    m.d.comb += [r.request.eq(req2), r.off.eq(addr.bit_offset), r.b.eq(d2.index_bits)]
    m.d.comb += [
        reader.i.p.raw.eq(~d2.compressed),
        reader.i.p.word.eq(word),
        reader.i.p.straddle.eq(d2.compressed & addr.straddle),
        reader.i.p.tag.eq(r.as_value()),
    ]

    # -- the texel pipeline's payload, and the words beside it -------------------------------------
    out = Signal(ride, name=prefix + "out")
    m.d.comb += out.eq(reader.o.p.tag)
    m.d.comb += tf.i.p.as_value().eq(out.request)
    # The words ride beside the texel pipeline's first FRONT_STAGES stages (its advance: no output stall
    # in the previous cycle), to arrive with the request at the index stage.
    advance = Signal(init=1, name=prefix + "advance")
    m.d.sync += advance.eq(~tf.stall_output)
    wide = len(reader.o.p.word0)
    carry = data.StructLayout({"pair": wide + W, "off": len(out.off), "b": 5, "raw": 32})
    shadow = [Signal(carry, name=f"{prefix}words_{n + 1}") for n in range(FRONT_STAGES)]
    first = Signal(carry, name=prefix + "words_0")
    m.d.comb += [first.pair.eq(Cat(reader.o.p.word0[:W], reader.o.p.word1)), first.off.eq(out.off),
                 first.b.eq(out.b), first.raw.eq(reader.o.p.word0[:32])]
    with m.If(advance):
        m.d.sync += shadow[0].eq(first)
        m.d.sync += [shadow[n].eq(shadow[n - 1]) for n in range(1, FRONT_STAGES)]
    last = shadow[-1]
    if "index_response" in tf.signature.members:
        ib = len(tf.index_response)
        mask = Signal(16, name=prefix + "mask")
        m.d.comb += mask.eq((1 << last.b) - 1)
        m.d.comb += tf.index_response.eq(((last.pair >> last.off) & mask)[:ib])
    if "raw_in" in tf.signature.members:
        m.d.comb += tf.raw_in.eq(last.raw)
    return reader
