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
when it advances and, seven advancing cycles later, gets the index (extracted here from the carried
words) and the raw word on ``index_response`` and ``raw_in``. The codebook, the descriptor tables
and the colour matrix stay on chip (baked from ``texture_set``).

Timing: :func:`golden.memory.timing.run` (``address_stages`` 2, the texel pipeline as consumer),
cycle for cycle; with every reference a hit, ``LATENCY + 5`` cycles from ``i`` to ``o`` and one
request per cycle. A miss reaches the texel pipeline as cycles without a request, and ``i.ready``
falls when the address stages and the reference FIFO are full.

Arguments
---------
texture_set : TextureSet
config : golden.memory.system.MemoryConfig
tag_width : int

Members
-------
i : In(stream.Signature(hw.pipeline.RequestLayout))
o : Out(stream.Signature(hw.pipeline.ResponseLayout))
stall_memory : Out(1)
    Strobe: the cache block's data read waits for a line fill (:class:`hw.memory.reader.CachedReader`).
stall_output : Out(1)
    ``o.valid & ~o.ready``.
axi : Out(hw.memory.axi.axi4_read_signature(32, 8 * bus_bytes))
"""

from __future__ import annotations

from amaranth import *
from amaranth.lib import data, stream, wiring
from amaranth.lib.wiring import In, Out

from vqtex.golden.memory.system import Layout

from ..address import BlockAddress
from ..banked_rom import addr_bits
from ..descriptor import DescriptorTable
from ..features import Features
from ..pipeline import RequestLayout, ResponseLayout
from ..texel_fetch import LATENCY, TexelFetch
from .axi import axi4_read_signature
from .reader import CachedReader

__all__ = ["CachedTexelFetch", "ADDRESS_STAGES", "cached_lane"]

#: The unit's own address stages in front of the caches (descriptor, block address).
ADDRESS_STAGES = 2


class CachedTexelFetch(wiring.Component):
    __doc__ = __doc__

    def __init__(self, texture_set, config, *, tag_width: int = 8):
        self._ts = texture_set
        self._config = config
        self._tag_width = tag_width
        self._layout = Layout.of(texture_set)
        self._features = Features.for_set(texture_set, True)
        self._tf = TexelFetch(texture_set, tag_width=tag_width, index_port=True, raw_port=True)
        self._reader_latency = 3                # CachedReader.latency: lookup, tag check, data read
        tb = self._tf.texture_bits
        super().__init__({
            "i": In(stream.Signature(RequestLayout(tb, tag_width))),
            "o": Out(stream.Signature(ResponseLayout(tag_width))),
            "stall_memory": Out(1), "stall_output": Out(1),
            "axi": Out(axi4_read_signature(32, 8 * config.bus_bytes)),
        })

    @property
    def fetch(self) -> TexelFetch:
        """The texel pipeline behind the caches (its ``features``, ``geometry``)."""
        return self._tf

    @property
    def latency(self) -> int:
        """Cycles from ``i`` to ``o`` when every reference hits: ``LATENCY + 5``."""
        return LATENCY + ADDRESS_STAGES + self._reader_latency

    def elaborate(self, platform):
        m = Module()
        m.submodules.texel = tf = self._tf
        en1, en2 = Signal(), Signal()
        reader = cached_lane(m, "", self._ts, self._features, self._config, self._layout, tf, self.i.p, (en1, en2))
        wiring.connect(m, reader.axi, wiring.flipped(self.axi))
        # -- the address stages: two stream registers, moving as a chain ----------------------------
        v1, v2 = Signal(), Signal()
        m.d.comb += [
            en2.eq(~v2 | reader.i.ready),
            en1.eq(~v1 | en2),
            self.i.ready.eq(en1),
            reader.i.valid.eq(v2),
        ]
        with m.If(en1):
            m.d.sync += v1.eq(self.i.valid)
        with m.If(en2):
            m.d.sync += v2.eq(v1)
        # -- the texel pipeline takes the reader's output when it advances --------------------------
        m.d.comb += [tf.i.valid.eq(reader.o.valid), reader.o.ready.eq(tf.i.ready)]
        wiring.connect(m, tf.o, wiring.flipped(self.o))
        m.d.comb += [self.stall_memory.eq(reader.stall_fill), self.stall_output.eq(tf.stall_output)]
        return m


def cached_lane(m, prefix: str, ts, feat, config, layout, tf, request, en, joint: bool = False):
    """One lane of the cached unit, built into ``m``: the address stages' datapath (descriptor and
    block address, loaded on ``en = (en1, en2)``, the enables of the two stream registers, which the
    caller drives and whose valid bits it keeps), a :class:`hw.memory.reader.CachedReader` (returned;
    the caller drives ``i.valid``, ``o.ready`` and connects ``axi``), and the texel pipeline ``tf``'s
    payload, ``index_response`` and ``raw_in`` (the words riding beside its first seven stages). The
    caller drives ``tf.i.valid``. ``request``: the payload entering the first address stage (a
    ``hw.pipeline.RequestLayout`` view). Submodules are named with ``prefix``. ``joint``: the
    reader's tag check waits for ``check_go`` (every lane's check together, driven by the caller)."""
    g = tf.geometry
    widths = g.descriptor_widths()
    W = ts.word_bits
    en1, en2 = en
    req_bits = len(request.as_value())
    # what rides through the reader beside the words: the request, the bit offset and width
    ride = data.StructLayout({"request": req_bits, "off": max(1, (W - 1).bit_length()), "b": 5})
    m.submodules[prefix + "reader"] = reader = CachedReader(
        config, word_bits=W, raw_base=layout.raw_base, word_addr_bits=32,
        tag_width=len(Signal(ride).as_value()), joint=joint)

    # -- the address stages' datapath ------------------------------------------------------------------
    m.submodules[prefix + "descriptor"] = desc = DescriptorTable(ts, features=feat, geometry=g)
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
    m.d.comb += word.eq(Mux(d2.compressed, addr.word, addr.raw_addr if feat.raw else 0))
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
    # The words ride beside the texel pipeline's first seven stages (its advance: no output stall
    # in the previous cycle), to arrive with the request at the index stage.
    advance = Signal(init=1, name=prefix + "advance")
    m.d.sync += advance.eq(~tf.stall_output)
    wide = len(reader.o.p.word0)
    carry = data.StructLayout({"pair": wide + W, "off": len(out.off), "b": 5, "raw": 32})
    shadow = [Signal(carry, name=f"{prefix}words_{n + 1}") for n in range(7)]
    first = Signal(carry, name=prefix + "words_0")
    m.d.comb += [first.pair.eq(Cat(reader.o.p.word0[:W], reader.o.p.word1)), first.off.eq(out.off),
                 first.b.eq(out.b), first.raw.eq(reader.o.p.word0[:32])]
    with m.If(advance):
        m.d.sync += shadow[0].eq(first)
        m.d.sync += [shadow[n].eq(shadow[n - 1]) for n in range(1, 7)]
    last = shadow[-1]
    if "index_response" in tf.signature.members:
        ib = len(tf.index_response)
        mask = Signal(16, name=prefix + "mask")
        m.d.comb += mask.eq((1 << last.b) - 1)
        m.d.comb += tf.index_response.eq(((last.pair >> last.off) & mask)[:ib])
    if "raw_in" in tf.signature.members:
        m.d.comb += tf.raw_in.eq(last.raw)
    return reader
