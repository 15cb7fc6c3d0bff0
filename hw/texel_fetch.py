"""TexelFetch: the whole texel-fetch pipeline of Beers, Agrawala and Chaddha (SIGGRAPH 1996).

A request (texture, level, i, j, tag) reads as a story through the blocks::

    descriptor table -> block address shifter -> index reader -> codebook ROM -> colour matrix
      (1 cycle)          (1 cycle)                (5 cycles)      (4 cycles)      (3 cycles)

and leaves as an RGBA8888 response with its tag, in request order, ``LATENCY`` = 14 cycles later.
Raw levels take the same path (the shifter computes the raw address, the codebook ROM stage reads
the raw memory, the colour matrix passes the word through), so the latency does not depend on the
request.

Pipeline control is in one place (:meth:`TexelFetch.elaborate`). Every register advances on
``advance``, a flip-flop: ``advance`` is high in a cycle when the output was not stalled in the
previous one (``o.valid & ~o.ready``); a response pushed out of the last stage in a stalled cycle
waits in the skid register, which the output shows first. With ``one_port`` the stages up to the
index reader's bit-address stage (``UPSTREAM_STAGES``) also wait while it ``hold``\\ s.
"""

from __future__ import annotations

from amaranth import *
from amaranth.lib import data, stream, wiring
from amaranth.lib.wiring import In, Out

from golden.format import TextureSet

from . import codebook_rom, color_matrix, index_reader
from .address import COORD_BITS, BlockAddress
from .banked_rom import BANK_DEPTH
from .codebook_rom import CodebookROM
from .color_matrix import ColorMatrix
from .descriptor import LEVEL_BITS, DescriptorTable, descriptor_widths, texture_bits
from .index_reader import IndexReader

__all__ = ["TexelFetch", "RequestLayout", "ResponseLayout", "LATENCY", "STAGES", "REGISTERS",
           "UPSTREAM_STAGES"]

#: Pipeline registers in order, one per cycle of latency; bit ``k`` of ``TexelFetch.valid`` is the
#: valid bit of ``STAGES[k]``.
STAGES = (
    "descriptor",                                                       # descriptor table
    "address",                                                          # block address shifter
    "index_bit", "index_word", "index_data", "index_pair", "index",     # index reader
    "codebook", "codebook_data", "texel_window", "texel",               # codebook ROM
    "color_offset", "color_product", "color",                           # colour matrix
)
#: Cycles from accepting a request to presenting its response (one per stage).
LATENCY = len(STAGES)
assert LATENCY == (1 + 1 + index_reader.LATENCY + codebook_rom.LATENCY + color_matrix.LATENCY)
#: The first stages (descriptor, address, index_bit), which move on ``upstream``: with ``one_port``
#: they and the input wait while the index reader's bit-address stage holds a straddling index.
UPSTREAM_STAGES = 3
#: Registers with a valid bit (bit ``k`` of the ``valid`` output is ``REGISTERS[k]``, and each has
#: an occupancy entry in the simulation reports): the stages, then the skid register in front of
#: the output.
REGISTERS = STAGES + ("skid",)


class RequestLayout(data.StructLayout):
    """A texel request: texture id, level, texel column ``i`` and row ``j`` inside the level, tag.

    Arguments
    ---------
    texture_bits : int
        Width of the texture id (``hw.descriptor.texture_bits(ts)``).
    tag_width : int
        Width of the tag (0 allowed).
    """

    def __init__(self, texture_bits: int, tag_width: int):
        super().__init__({
            "texture": unsigned(texture_bits),
            "level": unsigned(LEVEL_BITS),
            "i": unsigned(COORD_BITS),
            "j": unsigned(COORD_BITS),
            "tag": unsigned(tag_width),
        })


class ResponseLayout(data.StructLayout):
    """A texel response: RGBA8888 and the request's tag.

    Arguments
    ---------
    tag_width : int
        Width of the tag (0 allowed).
    """

    def __init__(self, tag_width: int):
        super().__init__({
            "r": unsigned(8), "g": unsigned(8), "b": unsigned(8), "a": unsigned(8),
            "tag": unsigned(tag_width),
        })


def _pack(layout: data.StructLayout, fields: dict) -> Value:
    """The bits of a ``layout`` value with these field values, as one concatenation: assigned in one
    piece, it is plain wiring (field-by-field assignments make simulators such as CXXRTL assemble
    the value with read-modify-writes every cycle)."""
    parts = []
    for name, field in sorted(layout, key=lambda item: item[1].offset):
        v = Value.cast(fields[name])
        parts.append(v[:field.width] if len(v) >= field.width else Cat(v, C(0, field.width - len(v))))
    return Cat(*parts)


def _bits(n: int) -> int:
    return max(1, int(n).bit_length())


def _addr_bits(depth: int) -> int:
    return max(1, (max(1, depth) - 1).bit_length())


class TexelFetch(wiring.Component):
    """The texel-fetch unit holding the memories of one texture set.

    Latency: ``LATENCY`` = 14 cycles, a constant. A request accepted in cycle ``t`` (``i.valid`` and
    ``i.ready`` high) is presented on ``o`` (``o.valid`` high) in cycle ``t + 14`` when no
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

    Arguments
    ---------
    texture_set : TextureSet
        The memories: descriptor table, index memory, codebook memory, raw memory, colour matrix.
    one_port : bool
        Single-bank index memory (reproduces the paper's straddle penalty in cycle counts).
    tag_width : int
        Width of the request tag carried to the response.
    bank_depth : int
        Words per block RAM bank of the index, codebook and raw memories (a power of two; default
        512, one ECP5 DP16KD; see :class:`hw.banked_rom.BankedROM`).

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
        Valid bits of the registers, bit ``k`` for ``REGISTERS[k]`` (the 14 stages, then the skid
        register; ``o.valid`` is ``valid[13] | valid[14]``), for occupancy reports. One vector, so
        that a simulator samples every stage with one read.

    Raises
    ------
    TypeError
        If ``texture_set`` is not a TextureSet or ``tag_width`` is not a non-negative int.
    ValueError
        If ``bank_depth`` is not a power of two.
    golden.format.FormatError
        If the texture set's descriptors point outside its memories.
    """

    def __init__(self, texture_set: TextureSet, *, one_port: bool = False, tag_width: int = 8,
                 bank_depth: int = BANK_DEPTH):
        if not isinstance(texture_set, TextureSet):
            raise TypeError(f"texture_set must be a TextureSet, not {type(texture_set).__name__}")
        if not isinstance(tag_width, int) or tag_width < 0:
            raise TypeError(f"tag_width must be a non-negative integer, not {tag_width!r}")
        if not isinstance(bank_depth, int) or bank_depth < 1 or bank_depth & (bank_depth - 1):
            raise ValueError(f"bank_depth must be a power of two, not {bank_depth!r}")
        texture_set.validate()
        self._ts = texture_set
        self._one_port = bool(one_port)
        self._tag_width = tag_width
        self._bank_depth = bank_depth
        self._texture_bits = texture_bits(texture_set)
        members = {
            "i": In(stream.Signature(RequestLayout(self._texture_bits, tag_width))),
            "o": Out(stream.Signature(ResponseLayout(tag_width))),
            "straddle": Out(1),
            "stall_one_port": Out(1),
            "stall_output": Out(1),
        }
        members["valid"] = Out(len(REGISTERS))
        super().__init__(members)

    @property
    def latency(self) -> int:
        """Cycles from accepting a request to presenting its response: ``LATENCY`` (14)."""
        return LATENCY

    @property
    def one_port(self) -> bool:
        return self._one_port

    @property
    def texture_set(self) -> TextureSet:
        return self._ts

    @property
    def tag_width(self) -> int:
        return self._tag_width

    @property
    def bank_depth(self) -> int:
        return self._bank_depth

    @property
    def texture_bits(self) -> int:
        return self._texture_bits

    def _k_bits(self) -> int:
        d = self._ts.descriptors
        comp = (d["compressed"] != 0) & (d["valid"] != 0)
        if not comp.any():
            return 1
        span = (d["log2w"].astype(int) - d["log2bw"] + d["log2h"] - d["log2bh"])[comp]
        return max(1, int(span.max()))

    def elaborate(self, platform):
        m = Module()
        ts = self._ts
        widths = descriptor_widths(ts)

        m.submodules.descriptor = desc = DescriptorTable(ts)
        m.submodules.address = addr = BlockAddress(
            base_bits=widths["base"], k_bits=self._k_bits(), raw_bits=_addr_bits(len(ts.raw_words)))
        m.submodules.index_reader = idx = IndexReader(
            ts.index_words, word_bits=ts.word_bits, k_bits=self._k_bits(), base_bits=widths["base"],
            one_port=self._one_port, bank_depth=self._bank_depth)
        m.submodules.codebook_rom = rom = CodebookROM(
            ts.codebook, ts.raw_words, cb_bits=widths["cb_base"], raw_bits=_addr_bits(len(ts.raw_words)),
            off_bits=widths["texel_off"], bank_depth=self._bank_depth)
        m.submodules.color_matrix = cm = ColorMatrix(ts.matrix)

        # -- pipeline control, all in one place ---------------------------------------------------
        # The stages' valid bits, one register (a shift register: bit n is stage STAGES[n]).
        valid = Signal(len(STAGES), name="valid_stages")
        # ``advance`` and ``skid_valid`` are the same information (the output was stalled in the
        # previous cycle), in two flip-flops: ``advance`` drives the enables of the whole
        # pipeline, ``skid_valid`` (stored inverted, so that synthesis does not merge the two) the
        # output logic and the next state, away from that large net.
        advance = Signal(init=1)    # every register moves; a flip-flop: no output stall last cycle
        skid_valid = Signal()       # the skid register holds the response shown on ``o``
        upstream = Signal()         # the first UPSTREAM_STAGES registers and the input move
        skid = Signal(self.o.p.shape(), name="skid")    # the response pushed out in a stalled cycle
        response = Signal(self.o.p.shape())             # the last stage's response
        m.d.comb += [
            upstream.eq(advance & ~idx.hold),
            self.i.ready.eq(upstream),
            self.o.valid.eq(skid_valid | valid[-1]),
            self.o.p.eq(Mux(skid_valid, skid, response)),
            self.stall_output.eq(self.o.valid & ~self.o.ready),
            self.straddle.eq(idx.straddle & upstream),
            self.stall_one_port.eq(idx.hold & advance),
        ]
        m.d.sync += [advance.eq(~self.stall_output), skid_valid.eq(self.stall_output)]
        with m.If(advance):
            m.d.sync += skid.eq(response)
        m.d.comb += self.valid.eq(Cat(valid, skid_valid))
        # The first UPSTREAM_STAGES bits shift on ``upstream``, the rest on ``advance`` (a held
        # straddling index enters the index reader's word stage as a bubble). One assignment of the
        # whole register: simulators (CXXRTL) then update it with one statement, not one per bit.
        u = UPSTREAM_STAGES
        m.d.sync += valid.eq(Cat(
            Mux(upstream, Cat(self.i.valid, valid[:u - 1]), valid[:u]),
            Mux(advance, Cat(valid[u - 1] & ~idx.hold, valid[u:-1]), valid[u:])))

        # -- carried fields: registers beside the blocks' own, same enables ----------------------
        def carry(value, en, name):
            reg = Signal.like(value, name=name)
            with m.If(en):
                m.d.sync += reg.eq(value)
            return reg

        # Stage 1: descriptor.
        m.d.comb += [
            desc.texture.eq(self.i.p.texture),
            desc.level.eq(self.i.p.level),
            desc.en.eq(upstream),
        ]
        row = desc.row
        i1 = carry(self.i.p.i, upstream, "i_descriptor")
        j1 = carry(self.i.p.j, upstream, "j_descriptor")

        # Stage 2: block address.
        m.d.comb += [
            addr.i.eq(i1), addr.j.eq(j1),
            addr.log2w.eq(row.log2w), addr.log2bw.eq(row.log2bw), addr.log2bh.eq(row.log2bh),
            addr.base.eq(row.base),
            addr.en.eq(upstream),
        ]
        d2 = carry(row, upstream, "row_address")

        # Stages 3-7: index reader (stage 3 moves on upstream: the reader gates it with its hold).
        m.d.comb += [
            idx.valid.eq(valid[1] & d2.compressed),
            idx.k.eq(addr.k),
            idx.b.eq(d2.index_bits),
            idx.base.eq(d2.base),
            idx.en.eq(advance),
        ]
        side = Signal(data.StructLayout({
            "compressed": 1, "cb_base": len(d2.cb_base), "raw_addr": len(addr.raw_addr),
            "x": 3, "y": 3, "log2bw": 2, "color": 2,
            "texel_off": len(d2.texel_off), "u_off": len(d2.u_off), "v_off": len(d2.v_off),
        }))
        m.d.comb += side.eq(_pack(side.shape(), {
            "compressed": d2.compressed, "cb_base": d2.cb_base, "raw_addr": addr.raw_addr,
            "x": addr.x, "y": addr.y, "log2bw": d2.log2bw, "color": d2.color,
            "texel_off": d2.texel_off, "u_off": d2.u_off, "v_off": d2.v_off,
        }))
        index_stages = STAGES[2:2 + index_reader.LATENCY]
        for n, name in enumerate(index_stages):
            en = upstream if n + 2 < UPSTREAM_STAGES else advance
            side = carry(side, en, f"side_{name}")

        # Stages 8-11: codebook ROM (and raw memory).
        m.d.comb += [
            rom.index.eq(idx.index), rom.cb_base.eq(side.cb_base), rom.raw_addr.eq(side.raw_addr),
            rom.compressed.eq(side.compressed), rom.x.eq(side.x), rom.y.eq(side.y),
            rom.log2bw.eq(side.log2bw), rom.color.eq(side.color),
            rom.texel_off.eq(side.texel_off), rom.u_off.eq(side.u_off), rom.v_off.eq(side.v_off),
            rom.en.eq(advance),
        ]
        # Stages 12-14: colour matrix.
        m.d.comb += [
            cm.samples.eq(rom.samples), cm.color.eq(rom.color_out), cm.en.eq(advance),
        ]
        # The request's tag rides beside the stages: one shift register of a tag per stage, moving
        # like the valid bits (the first UPSTREAM_STAGES on ``upstream``, the rest on ``advance``),
        # assigned in one piece (one statement per cycle in CXXRTL instead of one per stage).
        tw = self._tag_width
        tags = Signal(len(STAGES) * tw, name="tag_stages")
        if tw:
            m.d.sync += tags.eq(Cat(
                Mux(upstream, Cat(self.i.p.tag, tags[:(u - 1) * tw]), tags[:u * tw]),
                Mux(advance, tags[(u - 1) * tw:-tw], tags[u * tw:])))

        m.d.comb += response.eq(_pack(response.shape(), {
            "r": cm.rgba[0], "g": cm.rgba[1], "b": cm.rgba[2], "a": cm.rgba[3],
            "tag": tags[-tw:] if tw else C(0, 0)}))
        return m
