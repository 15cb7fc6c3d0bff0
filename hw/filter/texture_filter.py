"""TextureFilter: the texture sampler in the RTL. A filter request (texture, s, t, level of detail,
mode, addressing, tag) goes in; the filtered RGBA8888 colour comes out with its tag, in order::

    footprint (5 cycles) -> sequencer -> texel-fetch lanes (15 cycles) -> blend (4 cycles)

* :class:`hw.filter.footprint.Footprint` computes the pixel's texel slots and weights (the twin of
  :func:`golden.filter.footprint`);
* the *sequencer* issues them to the ``lanes`` texel-fetch lanes, ``lanes`` slots per cycle, in
  ``ceil(used / lanes)`` groups (a point pixel is 1 slot, bilinear 4, trilinear 8); a slot's weight
  and the pixel's ``first``/``last`` marks and tag ride through the lane as its request tag;
* each lane is the paper's unit, :class:`hw.texel_fetch.TexelFetch` (the lanes run in lock step:
  same ``valid``, same ``ready``). With ``index_banks="parity"`` (the default) the lanes share one
  index memory banked by block parity (:mod:`hw.filter.index_banks`: 2 banks for 2 lanes, 4 per set
  of 4 lanes; each lane is built with ``index_port`` and its descriptor table holds the banks' base
  words); each lane keeps its own codebook and raw memory (a DP16KD's two ports are 18 bits wide
  each, so reading a 512-deep codebook through both costs as many block RAMs as a second copy:
  docs/filter.md). With ``index_banks="lane"`` every lane has its own copy of every memory;
* :class:`hw.filter.blend.Blend` weighs each group and accumulates the pixel's colour (the twin of
  :func:`golden.filter.blend`).

Throughput: one group per cycle, so with ``lanes`` = 1 a point pixel per clock, a bilinear pixel every
4 and a trilinear pixel every 8; with 4 lanes a bilinear pixel per clock and a trilinear pixel every 2;
with 8 lanes (the second set) a trilinear pixel per clock. Latency (``LATENCY``): a pixel accepted in
cycle ``t`` whose slots go out in ``g`` groups without stalls is on ``o`` in cycle
``t + LATENCY + g - 1`` with ``LATENCY = 5 + 15 + 4 = 24``.

Loadable (``loadable=True``, from a ``geometry``): every lane is the loadable texel-fetch unit
with its own copy of the memories (``index_banks="lane"``), the footprint's level table is loaded
from the descriptor writes, and the filter has one Wishbone port (:mod:`hw.bus_port`) whose load
commands reach every lane (each writes its copy; lane 0 answers reads). The drain rule is the
texel-fetch unit's, counted in pixels: while ``cyc`` is high no pixel is accepted, and a transfer
waits until every accepted pixel's colour has left. The register map and the host's writes are the
texel-fetch unit's (:mod:`golden.register_map`).

Stream backpressure throughout: ``i`` and ``o`` are ``amaranth.lib.stream`` streams; a stalled output
holds the blend, which holds the lanes (their own skid registers), which hold the sequencer and the
footprint; nothing is lost, duplicated or reordered.
"""

from __future__ import annotations

from amaranth import *
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

from vqtex.golden import filter as spec
from vqtex.golden.format import TextureSet
from vqtex.golden.index_banks import banked_index, lane_banks

from vqtex.golden.geometry import Geometry
from vqtex.golden.register_map import RegisterMap

from ..address import COORD_BITS
from ..banked_rom import BANK_DEPTH
from ..pick import pick
from ..bus_port import BusPort, wishbone_signature
from ..descriptor import descriptor_widths, texture_bits
from ..features import Features
from ..front_end import k_bits
from ..pipeline import LATENCY as FETCH_LATENCY
from ..pipeline import ResponseLayout
from ..texel_fetch import TexelFetch
from . import blend, footprint
from .blend import Blend
from .index_banks import IndexBanks
from .footprint import WEIGHT_WIDTH, FilterRequestLayout, Footprint, TexelSlotLayout, level_table

__all__ = ["TextureFilter", "LATENCY", "LANES", "INDEX_BANKS"]

#: Cycles from accepting a request to its colour on the output (a one-group pixel, no stalls).
LATENCY = footprint.LATENCY + FETCH_LATENCY + blend.LATENCY
#: Lane counts the filter can be built with (they divide the eight slots of a footprint).
LANES = (1, 2, 4, 8)
#: How the lanes hold the index memory: ``parity`` one memory banked by block parity, shared;
#: ``lane`` a copy per lane.
INDEX_BANKS = ("parity", "lane")


class TextureFilter(wiring.Component):
    """The texture filter holding the memories of one texture set (see the module docstring).

    Arguments
    ---------
    texture_set : TextureSet
    lanes : int
        Texel-fetch lanes, 1, 2, 4 or 8: texels fetched per cycle.
    tag_width : int
        Width of the pixel tag.
    frac : int or None
        Fractional bits of ``s`` and ``t`` (default ``golden.filter.coordinate_frac_bits`` of the
        set's largest level 0; at least that).
    bank_depth : int
        As for :class:`hw.texel_fetch.TexelFetch`.
    index_banks : str
        ``"parity"`` (default): the lanes share the index memory, banked by block parity
        (``golden.index_banks.lane_banks(lanes)`` banks per set of lanes; one lane: its own reader);
        ``"lane"``: each lane has its own index memory. Same pixels, cycles and latency.

    Members
    -------
    i : In(stream.Signature(FilterRequestLayout(texture_bits, frac + 3, tag_width)))
        Filter requests (see :class:`hw.filter.footprint.FilterRequestLayout`; the level of detail at
        most 256 times the texture's last level, ``s`` and ``t`` in [-2, 2]).
    o : Out(stream.Signature(hw.pipeline.ResponseLayout(tag_width)))
        Filtered colours with their tags, in request order.
    stall_output : Out(1)
        ``o.valid & ~o.ready``: a cycle of output backpressure.
    busy : Out(1)
        ``i.valid & ~i.ready``: a request waits (the lanes are on an earlier pixel's groups, or
        backpressure reached the input).
    bank_conflict : Out(1)
        Two lanes of a set needed different blocks of one index bank in an advancing cycle (never on
        the footprint's groups; 0 without banks).

    Raises
    ------
    TypeError, ValueError
        On a bad texture set, lane count or fractional bits.
    """

    def __new__(cls, texture_set: TextureSet | None = None, *, lanes: int = 1, tag_width: int = 8,
                frac: int | None = None, index_banks: str = "parity", geometry=None, loadable: bool = False,
                **kwargs):
        # Parameters are checked before the instance exists (a rejected one is never reported by
        # Amaranth as an elaboratable that was not used).
        if loadable:
            if not isinstance(geometry, Geometry):
                raise TypeError("a loadable texture filter needs a Geometry")
            if index_banks != "lane":
                raise ValueError("a loadable texture filter keeps a copy of the memories per lane: index_banks='lane'")
        if not (loadable and texture_set is None) and not isinstance(texture_set, TextureSet):
            raise TypeError(f"texture_set must be a TextureSet, not {type(texture_set).__name__}")
        if lanes not in LANES:
            raise ValueError(f"lanes must be one of {LANES}, not {lanes!r}")
        if index_banks not in INDEX_BANKS:
            raise ValueError(f"index_banks must be one of {INDEX_BANKS}, not {index_banks!r}")
        if not isinstance(tag_width, int) or tag_width < 0:
            raise TypeError(f"tag_width must be a non-negative integer, not {tag_width!r}")
        minimum = spec.coordinate_frac_bits(COORD_BITS if loadable else level_table(texture_set).max_log2)
        if frac is not None and frac < minimum:
            raise ValueError(f"frac {frac} is below {minimum} for this texture set")
        return super().__new__(cls)

    def __init__(self, texture_set: TextureSet | None = None, *, lanes: int = 1, tag_width: int = 8,
                 frac: int | None = None, bank_depth: int | None = None, index_banks: str = "parity",
                 geometry=None, loadable: bool = False):
        self._loadable = bool(loadable)
        self._geometry = geometry
        self._contents = texture_set
        self._ts = texture_set
        # a loadable filter without contents starts from a level table of 1x1 textures (the host
        # loads the real one with the descriptors)
        self._table = level_table(texture_set) if texture_set is not None else spec.LevelTable([[(1, 1)]])
        # a loadable filter serves every level size the coordinates can address
        minimum = spec.coordinate_frac_bits(COORD_BITS if self._loadable else self._table.max_log2)
        self._frac = minimum if frac is None else int(frac)
        self._lanes = lanes
        self._tag_width = tag_width
        self._bank_depth = bank_depth
        self._texture_bits = geometry.texture_bits if self._loadable else texture_bits(texture_set)
        self._features = Features.of_geometry(geometry) if self._loadable else Features.of(texture_set)
        # one lane reads its own memory; so does a set without compressed levels
        self._banks = lane_banks(lanes) if index_banks == "parity" and self._features.compressed else 1
        self._index_banks = index_banks
        members = {
            "i": In(stream.Signature(FilterRequestLayout(self._texture_bits, spec.coordinate_bits(self._frac),
                                                         tag_width))),
            "o": Out(stream.Signature(ResponseLayout(tag_width))),
            "stall_output": Out(1),
            "busy": Out(1),
            "bank_conflict": Out(1),
        }
        if self._loadable:
            members["bus"] = In(wishbone_signature(RegisterMap(geometry).addr_bits))
        super().__init__(members)

    @property
    def latency(self) -> int:
        return LATENCY

    @property
    def lanes(self) -> int:
        return self._lanes

    @property
    def index_banks(self) -> str:
        """``"parity"`` or ``"lane"``, as built."""
        return self._index_banks

    @property
    def banks(self) -> int:
        """Index banks per set of lanes: 1 (each lane reads its own memory), 2 or 4."""
        return self._banks

    @property
    def frac(self) -> int:
        return self._frac

    @property
    def texture_set(self) -> TextureSet | None:
        """The contents (a loadable filter's initial contents; None: none)."""
        return self._contents

    @property
    def loadable(self) -> bool:
        return self._loadable

    @property
    def geometry(self):
        return self._geometry

    def elaborate(self, platform):
        m = Module()
        lanes = self._lanes
        tw = self._tag_width
        # Lane 0's tag is its slot's weight, the pixel's first and last marks and the pixel tag; the
        # other lanes run in lock step with it and carry their weight only (the blend reads the
        # marks and the tag from lane 0).
        lane_tag = [WEIGHT_WIDTH + 2 + tw if k == 0 else WEIGHT_WIDTH for k in range(lanes)]

        loadable = self._loadable
        if loadable:
            m.submodules.bus_port = port = BusPort(self._geometry)
            wiring.connect(m, wiring.flipped(self.bus), port.bus)
        m.submodules.footprint = fp = Footprint(self._table, texture_bits=self._texture_bits, frac=self._frac,
                                                tag_width=tw, load=port.load.shape() if loadable else None)
        m.submodules.blend = bl = Blend(lanes, tw)
        fetch = []
        banked = self._banks > 1
        banked_image = banked_index(self._ts, self._banks) if banked else None
        lane_set = banked_image.view(self._ts) if banked else self._ts
        for k in range(lanes):
            if loadable:                    # the filter's port loads every lane's copy
                f = TexelFetch(self._contents, tag_width=lane_tag[k], bank_depth=self._bank_depth, geometry=self._geometry,
                               loadable=True, bus_port=False)
            else:
                f = TexelFetch(lane_set, tag_width=lane_tag[k], bank_depth=self._bank_depth, index_port=banked)
            m.submodules[f"lane{k}"] = f
            fetch.append(f)
        if loadable:
            m.d.comb += [f.load.eq(port.load) for f in fetch]
            m.d.comb += [fp.load.eq(port.load), port.load_data.eq(fetch[0].load_data)]
        conflicts = []
        if banked:                      # sets of ``banks`` lanes, each with its banks
            feat = self._features
            for s in range(lanes // self._banks):
                ib = IndexBanks(banked_image, k_bits=k_bits(self._ts),
                                base_bits=descriptor_widths(lane_set)["base"], widths=feat.index_widths,
                                straddle=feat.straddle, twiddle=feat.twiddled,
                                bank_depth=BANK_DEPTH if self._bank_depth is None else self._bank_depth)
                m.submodules[f"index_banks{s}"] = ib
                for n in range(self._banks):
                    f = fetch[s * self._banks + n]
                    m.d.comb += [ib.requests[n].eq(f.index_request), f.index_response.eq(ib.index[n])]
                conflicts.append(ib.conflict)
        m.d.comb += self.bank_conflict.eq(Cat(*conflicts).any() if conflicts else 0)
        if loadable:
            pixel_drain(m, self.i, fp.i, self.o, port, 1 << 10)
        else:
            wiring.connect(m, wiring.flipped(self.i), fp.i)
        wiring.connect(m, bl.o, wiring.flipped(self.o))
        m.d.comb += [
            self.stall_output.eq(self.o.valid & ~self.o.ready),
            self.busy.eq(self.i.valid & ~self.i.ready),
        ]

        sequencer(m, fp, lanes, fetch[0].i.ready, [(f.i.valid, f.i.p) for f in fetch], tw)
        gather(m, bl, [f.o for f in fetch])
        return m


def sequencer(m, fp, lanes: int, ready, targets, tag_width: int):
    """The sequencer, built into ``m``: the footprint ``fp``'s slots, ``lanes`` per cycle, in
    ``ceil(used / lanes)`` groups, onto ``targets`` (per lane ``(valid, payload)``, the payload a
    ``hw.pipeline.RequestLayout`` view whose tag is the slot's weight, and for lane 0 also the
    pixel's first and last marks and tag); the lanes take a group when ``ready`` is high (all
    together)."""
    groups = spec.SLOTS // lanes
    group = Signal(range(max(groups, 2)), name="group")
    last = Signal(name="last_group")
    issue = Signal(name="issue")                 # the lanes take a group this cycle
    fpp = fp.o.p
    m.d.comb += [
        last.eq((group + 1) * lanes >= fpp.used),
        issue.eq(fp.o.valid & ready),
        fp.o.ready.eq(ready & last),
    ]
    with m.If(issue):
        m.d.sync += group.eq(Mux(last, 0, group + 1))
    for k, (valid, p) in enumerate(targets):
        slots = [k + lanes * g for g in range(groups)]
        texel = TexelSlotLayout(pick([fpp.texels[n].as_value() for n in slots], group))
        weight = pick([fpp.weights[n] for n in slots], group)
        m.d.comb += [
            valid.eq(fp.o.valid),
            p.texture.eq(fpp.texture),
            p.level.eq(texel.level),
            p.i.eq(texel.i),
            p.j.eq(texel.j),
            p.tag.eq(Cat(weight, group == 0, last, fpp.tag) if k == 0 else weight),
        ]


def pixel_drain(m, i, inner, o, port, most: int) -> None:
    """The loadable filters' drain rule, in pixels: the input stream ``i`` reaches ``inner`` except
    while the host holds the bus (``port.pause``), and a bus transfer happens only when every pixel
    accepted has left through ``o`` (``port.idle``: a count of the pixels in flight, below ``most``).
    Zero latency; the count is one register."""
    taken, given = Signal(), Signal()
    in_flight = Signal(range(most), name="pixels_in_flight")
    m.d.comb += [
        inner.valid.eq(i.valid & ~port.pause), i.ready.eq(inner.ready & ~port.pause), inner.p.eq(i.p),
        taken.eq(i.valid & i.ready), given.eq(o.valid & o.ready),
        port.idle.eq(in_flight == 0),
    ]
    m.d.sync += in_flight.eq(in_flight + taken - given)


def gather(m, bl, outs):
    """The lanes' responses (``outs``, their ``o`` streams, in lock step), one group per cycle, into
    the blend ``bl`` (marks and pixel tag from lane 0's tag)."""
    head = outs[0].p.tag
    m.d.comb += [
        bl.i.valid.eq(outs[0].valid),
        bl.i.p.first.eq(head[WEIGHT_WIDTH]),
        bl.i.p.last.eq(head[WEIGHT_WIDTH + 1]),
        bl.i.p.tag.eq(head[WEIGHT_WIDTH + 2:]),
    ]
    for k, o in enumerate(outs):
        m.d.comb += [
            o.ready.eq(bl.i.ready),
            bl.i.p.rgba[k].eq(Cat(o.p.r, o.p.g, o.p.b, o.p.a)),
            bl.i.p.weight[k].eq(o.p.tag[:WEIGHT_WIDTH]),
        ]
