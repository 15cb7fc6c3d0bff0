"""FrontEnd: request -> codebook index, and the pipeline control (stages 1-8 of TexelFetch).

request register -> descriptor table -> block address shifter -> index reader, with every valid
bit, the ``advance``
flip-flop, the skid register's valid bit and the request tags. Its ``link`` output
(:class:`hw.pipeline.LinkLayout`) is all that :class:`hw.back_end.BackEnd` needs from it; nothing
comes back (see :mod:`hw.pipeline`).
"""

from __future__ import annotations

from amaranth import *
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

from vqtex.golden.format import TextureSet
from vqtex.golden.geometry import Geometry

from . import index_reader
from .address import BlockAddress
from .banked_rom import BANK_DEPTH
from .bus_port import DATA_WIDTH, or_all
from .copies import register_copies
from .descriptor import DescriptorTable, as_geometry
from .features import Features
from .index_reader import IndexReader, IndexRequestLayout
from .registers import enabled_register
from .pipeline import (ADVANCE_COPIES, DATA_COPIES, INDEX_DATA_COPIES, STAGES, UPSTREAM_STAGES, REGISTERS, LinkLayout, RequestLayout, SideLayout,
                       addr_bits, advance_copies, pack)

__all__ = ["FrontEnd", "index_port_members"]


def k_bits(ts: TextureSet | Geometry) -> int:
    """Width of the block number ``k``: enough for the largest compressed level (of a set, or that a
    geometry addresses)."""
    return as_geometry(ts).k_bits


def index_port_members(ts: TextureSet | Geometry, features: Features) -> dict:
    """The members of a unit whose index reader is outside it (``index_port``): ``index_request``
    (:class:`hw.index_reader.IndexRequestLayout`) out, ``index_response`` (the index) in."""
    g = as_geometry(ts)
    return {"index_request": Out(IndexRequestLayout(g.k_bits, g.descriptor_widths()["base"])),
            "index_response": In(features.index_bits)}


class _NoIndex:
    """The index reader of a unit whose levels are all raw: nothing (no hold, no straddle, index 0)."""
    hold = straddle = C(0, 1)
    index = C(0, 1)


class _OutsideIndex:
    """The index reader outside the unit (``index_port``): its index comes in on ``index_response``;
    no hold (the outside reader has both word banks), straddles are the outside reader's to count."""
    hold = straddle = C(0, 1)

    def __init__(self, index):
        self.index = index


class FrontEnd(wiring.Component):
    """Stages 1-8 (request, descriptor, address, the index reader's five) and the pipeline control.

    Latency: the index of a request accepted in cycle ``t`` is on ``link.index`` in cycle ``t + 8``
    (``FRONT_STAGES``) when the pipeline advanced in between. Throughput: one request per advancing cycle (one-port:
    a straddling index costs one more).

    Control (the rules of :class:`hw.texel_fetch.TexelFetch`): ``advance`` is a flip-flop set to
    ``~(o_valid & ~o_ready)``; ``skid_valid`` to ``o_valid & ~o_ready``; ``upstream = advance &
    ~hold`` moves the first ``UPSTREAM_STAGES`` registers and the input; ``o_valid`` is the last
    stage's valid bit or ``skid_valid``. All of it is here, so ``o_valid`` and ``i.ready`` depend on
    the front end's flip-flops and ``o_ready`` only.

    Arguments
    ---------
    texture_set : TextureSet or None
        Descriptor table and index memory contents (required unless loadable).
    geometry : Geometry, optional
        Memory depths and field widths (default ``Geometry.of(texture_set)``).
    load : data.StructLayout, optional
        The bus port's load command (:func:`hw.bus_port.load_layout`): the descriptor table and the
        index memory are loadable; members ``pause`` (no request is accepted while high),
        ``load`` and ``load_data`` (the OR of their read answers).
    one_port, tag_width, bank_depth
        As for :class:`hw.texel_fetch.TexelFetch`.
    features : hw.features.Features, optional
        What to build (default the full front end): the descriptor table's columns, the index
        reader's widths and straddle path (none without compressed levels), the raw address, the
        side fields carried.
    index_port : bool
        The index reader is outside the unit (a filter's lanes share banked readers,
        :mod:`hw.filter.index_banks`): the unit sends ``index_request`` and receives the index on
        ``index_response`` ``index_reader.LATENCY`` advancing cycles later; no ``one_port``.
    summed : bool
        ``link.index`` is the codebook address ``cb_base + index``, added in the index reader's
        extract stage (:class:`hw.pipeline.LinkLayout`; the loadable unit); not with ``index_port``.

    Members
    -------
    i : In(stream.Signature(RequestLayout))
        Requests.
    o_valid : Out(1)
        The response on the output (the back end's ``payload``) is valid.
    o_ready : In(1)
        The output's ready.
    straddle, stall_one_port, stall_output : Out(1)
        Strobes, as for ``TexelFetch``.
    valid : Out(len(REGISTERS))
        Valid bits of the registers, bit ``k`` for ``REGISTERS[k]``.
    o_tag : Out(tag_width)
        The tag of the response on the output: the skid register's tag when ``skid_valid``, else the
        last stage's (the tags never enter the back end).
    link : Out(LinkLayout)
        To the back end: ``advance``, ``skid_valid``, the index and its side fields.
    index_request : Out(hw.index_reader.IndexRequestLayout), index_response : In(index_bits)
        Only with ``index_port``: the index read the unit needs (stage 3's inputs) and its answer.
    """

    def __init__(self, texture_set: TextureSet | None = None, *, one_port: bool = False, tag_width: int = 8,
                 bank_depth: int = BANK_DEPTH, features: Features | None = None, index_port: bool = False,
                 geometry: Geometry | None = None, load=None, summed: bool = False):
        if index_port and one_port:
            raise ValueError("an index reader outside the unit has both word banks: no one_port")
        if index_port and summed:
            raise ValueError("an index reader outside the unit returns the index alone: no summed")
        self._ts = texture_set
        self._geometry = geometry if geometry is not None else as_geometry(texture_set)
        self._load = load
        self._one_port = bool(one_port)
        self._index_port = bool(index_port)
        self._tag_width = tag_width
        self._bank_depth = bank_depth
        self._features = features if features is not None else Features.full(texture_set)
        self._summed = bool(summed) and self._features.compressed
        g = self._geometry
        super().__init__({
            "i": In(stream.Signature(RequestLayout(g.texture_bits, tag_width))),
            "o_valid": Out(1),
            "o_ready": In(1),
            "straddle": Out(1),
            "stall_one_port": Out(1),
            "stall_output": Out(1),
            "valid": Out(len(REGISTERS)),
            "o_tag": Out(tag_width),
            "link": Out(LinkLayout(g, self._features, summed=self._summed,
                                   copies=len(ADVANCE_COPIES) + DATA_COPIES if load is not None else 0)),
            **(index_port_members(g, self._features) if self._index_port else {}),
            **({} if load is None else {"pause": In(1), "load": In(load), "load_data": Out(DATA_WIDTH)}),
        })

    def elaborate(self, platform):
        m = Module()
        ts = self._ts
        g = self._geometry
        feat = self._features
        load = self._load
        widths = g.descriptor_widths()
        kb = g.k_bits

        m.submodules.descriptor = desc = DescriptorTable(ts, features=feat, geometry=g, load=load, registered=True)
        m.submodules.address = addr = BlockAddress(
            base_bits=widths["base"], k_bits=kb, raw_bits=addr_bits(g.raw_words), raw=feat.raw,
            twiddle=feat.twiddled, linear=0 in feat.layouts, one_shifter=load is not None)
        if feat.compressed and self._index_port:
            idx = _OutsideIndex(self.index_response)
        elif feat.compressed:
            m.submodules.index_reader = idx = IndexReader(
                ts.index_words if ts is not None else (), word_bits=g.word_bits, k_bits=kb, base_bits=widths["base"],
                one_port=self._one_port, bank_depth=self._bank_depth,
                widths=feat.index_widths if feat.specialised else None, straddle=feat.straddle,
                depth=g.index_words, load=load, add_bits=widths["cb_base"] if self._summed else 0,
                data_copies=INDEX_DATA_COPIES if load is not None else 0)
        else:                               # every level raw: no index reader, the index is 0
            idx = _NoIndex()

        # -- pipeline control, all in one place ---------------------------------------------------
        # The stages' valid bits, one register (a shift register: bit n is stage STAGES[n]).
        valid = Signal(len(STAGES), name="valid_stages")
        # ``advance`` and ``skid_valid`` are the same information (the output was stalled in the
        # previous cycle), in two flip-flops: ``advance`` drives the enables of the whole
        # pipeline, ``skid_valid`` the output logic and the next state, away from that large net.
        advance = Signal(init=1)    # every register moves; a flip-flop: no output stall last cycle
        skid_valid = Signal()       # the skid register holds the response shown on ``o``
        upstream = Signal()         # the first UPSTREAM_STAGES registers and the input move
        # A loadable unit takes no request while the host holds the bus (hw.bus_port's drain rule).
        taken = self.i.valid if load is None else self.i.valid & ~self.pause
        m.d.comb += [
            upstream.eq(advance & ~idx.hold),
            self.i.ready.eq(upstream if load is None else upstream & ~self.pause),
            self.o_valid.eq(skid_valid | valid[-1]),
            self.stall_output.eq(self.o_valid & ~self.o_ready),
            self.straddle.eq(idx.straddle & upstream),
            self.stall_one_port.eq(idx.hold & advance),
        ]
        m.d.sync += [advance.eq(~self.stall_output), skid_valid.eq(self.stall_output)]
        # The loadable unit: the data registers' enables from copies of ``advance`` (one per block,
        # hw.pipeline.advance_copies), the valid bits, tags, control and stage 1 (the request: the
        # descriptor table's address registers and the request's i, j: they take the input, which
        # a copy's first cycle after a reset would miss) from ``advance`` itself.
        if load is not None:
            copies = dict(zip(ADVANCE_COPIES, advance_copies(m, self.stall_output, len(ADVANCE_COPIES))))
            # the codebook ROM's data registers' shares: equal to ``advance`` itself, kept apart by
            # ``keep``; on the link after the blocks' copies
            data_copies = register_copies(m, ~self.stall_output, DATA_COPIES, name="advance_data", init=1)
            en_desc = Signal(name="upstream_address")
            m.d.comb += en_desc.eq(copies["address"] & ~idx.hold)
            en_idx, en_side = copies["index_reader"], copies["side"]
        else:
            copies, data_copies = {}, []
            en_desc, en_idx, en_side = upstream, advance, advance
        m.d.comb += self.valid.eq(Cat(valid, skid_valid))
        # The first UPSTREAM_STAGES bits shift on ``upstream``, the rest on ``advance`` (a held
        # straddling index enters the index reader's word stage as a bubble). One assignment of the
        # whole register: simulators (CXXRTL) then update it with one statement, not one per bit.
        u = UPSTREAM_STAGES
        m.d.sync += valid.eq(Cat(
            Mux(upstream, Cat(taken, valid[:u - 1]), valid[:u]),
            Mux(advance, Cat(valid[u - 1] & ~idx.hold, valid[u:-1]), valid[u:])))

        # -- carried fields: registers beside the blocks' own, same enables ----------------------
        def carry(value, en, name):
            return enabled_register(m, en, value, name)

        # Stages 1 and 2: the request registered (the table's address registers: its own copies of
        # texture and level), then the table read.
        m.d.comb += [
            desc.texture.eq(self.i.p.texture),
            desc.level.eq(self.i.p.level),
            desc.en.eq(upstream),
            desc.row_en.eq(en_desc),
        ]
        row = desc.fields()
        i1 = carry(self.i.p.i, upstream, "i_request")
        j1 = carry(self.i.p.j, upstream, "j_request")
        i2 = carry(i1, en_desc, "i_descriptor")
        j2 = carry(j1, en_desc, "j_descriptor")

        # Stage 3: block address.
        m.d.comb += [
            addr.i.eq(i2), addr.j.eq(j2),
            addr.log2w.eq(row.log2w), addr.log2bw.eq(row.log2bw), addr.log2bh.eq(row.log2bh),
            addr.base.eq(row.base),
            addr.en.eq(en_desc),
        ]
        if addr.twiddle:                    # a level with a PowerVR2 twiddled map
            m.d.comb += [addr.layout.eq(row.layout), addr.log2h.eq(row.log2h)]
        d2 = desc.fields(carry(desc.row, en_desc, "row_address"))

        # Stages 4-8: index reader (stage 4 moves on upstream: the reader gates it with its hold).
        if feat.compressed and self._index_port:
            m.d.comb += [
                self.index_request.valid.eq(valid[STAGES.index("address")] & d2.compressed),
                self.index_request.k.eq(addr.k),
                self.index_request.b.eq(d2.index_bits),
                self.index_request.base.eq(d2.base),
                self.index_request.en.eq(advance),
                self.index_request.gw.eq(d2.log2w - d2.log2bw),
                self.index_request.twiddled.eq(d2.layout if feat.twiddled else 0),
            ]
            if feat.twiddled:
                m.d.comb += self.index_request.gh.eq(d2.log2h - d2.log2bh)
        elif feat.compressed:
            m.d.comb += [
                idx.valid.eq(valid[STAGES.index("address")] & d2.compressed),
                idx.k.eq(addr.k),
                idx.b.eq(d2.index_bits),
                idx.base.eq(d2.base),
                idx.en.eq(en_idx),
            ]
            if load is not None:            # the index memories' data registers on copies of their own
                m.d.comb += idx.en_data.eq(Cat(*register_copies(m, ~self.stall_output, INDEX_DATA_COPIES,
                                                                name="advance_index", init=1)))
        if load is not None:                # the read answers of the table and the index memory
            inside = feat.compressed and not self._index_port       # an index memory here
            m.d.comb += self.load_data.eq(or_all([desc.load_data] + ([idx.load_data] if inside else [])))
            m.d.comb += desc.load.eq(self.load)
            if inside:
                m.d.comb += idx.load.eq(self.load)
        side = Signal(SideLayout(g, feat))
        m.d.comb += side.eq(pack(side.shape(), {
            "compressed": d2.compressed, "cb_base": d2.cb_base, "raw_addr": addr.raw_addr,
            "x": addr.x, "y": addr.y, "log2bw": d2.log2bw, "color": d2.color,
            "texel_off": d2.texel_off, "u_off": d2.u_off, "v_off": d2.v_off,
        }))
        first = STAGES.index("index_bit")
        index_stages = STAGES[first:first + index_reader.LATENCY]
        for n, name in enumerate(index_stages):
            en = en_desc if n + first < UPSTREAM_STAGES else en_side
            if self._summed and n == len(index_stages) - 1:
                m.d.comb += idx.add.eq(side.cb_base)     # the item entering the extract stage
            side = carry(side, en, f"side_{name}")

        # The request's tag rides beside the stages: one shift register of a tag per stage, moving
        # like the valid bits (the first UPSTREAM_STAGES on ``upstream``, the rest on ``advance``),
        # assigned in one piece (one statement per cycle in CXXRTL instead of one per stage).
        tw = self._tag_width
        tags = Signal(len(STAGES) * tw, name="tag_stages")
        if tw:
            m.d.sync += tags.eq(Cat(
                Mux(upstream, Cat(self.i.p.tag, tags[:(u - 1) * tw]), tags[:u * tw]),
                Mux(advance, tags[(u - 1) * tw:-tw], tags[u * tw:])))

        if tw:
            skid_tag = Signal(tw, name="skid_tag")     # the tag part of the skid register
            with m.If(advance):
                m.d.sync += skid_tag.eq(tags[-tw:])
            m.d.comb += self.o_tag.eq(Mux(skid_valid, skid_tag, tags[-tw:]))

        m.d.comb += self.link.eq(pack(self.link.shape(), {
            "advance": advance, "skid_valid": skid_valid, "index": idx.index, "side": side,
            **({"copies": Cat(*copies.values(), *data_copies)} if copies else {})}))
        return m
