"""CachedTextureFilter: the texture filter with its index map and raw levels in external memory.

Twin of :mod:`golden.memory.filter` (its exact cycle model); the design: docs/memory.md, "The texture
filter through the memory system"::

    i -> Footprint -> sequencer -> lane k: address stages -> CachedReader k --join--> TexelFetch k -> Blend -> o
                                                                  | AR/R
                                       AxiArbiter (lanes -> one master, lane order) -> axi

* the footprint, the sequencer and the blend are the on-chip filter's
  (:mod:`hw.filter.texture_filter`: :class:`Footprint`, :func:`sequencer`, :func:`gather`,
  :class:`Blend`);
* each lane is one lane of the cached unit (:func:`hw.memory.unit.cached_lane`: descriptor and block
  address stages, a :class:`hw.memory.reader.CachedReader` with its own index and raw caches, the
  texel pipeline :class:`hw.texel_fetch.TexelFetch` with its index and raw words from outside). The
  lanes' address stages move together (one valid chain); a group enters every lane's tag check in
  the same cycle, when every reader is ready (the fork); the texel pipelines take a group when
  every reader's output holds it (the join) and run in lock step;
* the readers' AXI masters share one through :class:`hw.memory.arbiter.AxiArbiter`.

Loadable (``loadable=True``, built from a ``geometry`` alone): the filter in the loadable cached
unit's configuration (:class:`hw.memory.unit.CachedTexelFetch` with ``loadable``). One Wishbone
slave ``bus`` (:class:`hw.bus_port.BusPort`, the map ``RegisterMap(geometry, external=True)``)
loads every lane's descriptor tables (the address stages' and the texel pipeline's), codebook and
colour matrix, the footprint's level table (from the descriptor writes, as the on-chip loadable
filter's) and the two base registers ``INDEX_BASE`` and ``RAW_BASE`` (one pair for all lanes); lane
0 answers reads. The index map and raw levels are in external memory where the bases say
(``golden.memory.system.Layout.at``). The drain rule is the on-chip loadable filter's, counted in
pixels: while ``cyc`` is high no pixel is accepted, and a transfer waits until every accepted
pixel's colour has left (then every reference has been read and every burst has completed).
Every accepted write empties every lane's caches (each reader reset as the write reaches the
unit). The pixels' timing is the baked filter's (:func:`golden.memory.filter.run` with the
bases' layout); a load of N writes takes ``golden.register_map.load_cycles(N)``.

Timing: :func:`golden.memory.filter.run` (with output backpressure too), cycle for cycle; with every reference a
hit, one group of ``lanes`` texel slots per clock (a bilinear pixel per clock with 4 lanes) and
``LATENCY`` = 29 cycles from a one-group pixel's acceptance to its colour (the on-chip filter's 24,
plus the address stages, the tag check and the data read). A miss in any lane holds the group
(the pixel) until its line is filled; the hits behind it keep being checked, up to each reader's
FIFO depth (``config.prefetch``; 1 is blocking). Colours leave in order, with stream backpressure
throughout (the cycle model's ``ready_pattern``).

Arguments
---------
texture_set : TextureSet or None
    The baked contents (or a loadable filter's initial contents, its bases ``Layout.of``'s).
config : golden.memory.system.MemoryConfig
    Every lane's cache shapes and FIFO depth, the bus width.
lanes : int
    1, 2, 4 or 8.
tag_width : int
frac : int or None
    As for :class:`hw.filter.TextureFilter` (a loadable filter's default: the largest level it can
    address, ``golden.filter.coordinate_frac_bits(COORD_BITS)``).
geometry : golden.geometry.Geometry, optional
    What a loadable filter serves (required with ``loadable``).
loadable : bool
    Descriptors, codebook, matrix, level table and base registers loaded over ``bus`` (above).

Members
-------
i, o : as :class:`hw.filter.TextureFilter`'s
axi : Out(hw.memory.axi.axi4_read_signature(32, 8 * bus_bytes))
stall_output : Out(1)
    ``o.valid & ~o.ready``.
stall_memory0 .. stall_memory{lanes-1} : Out(1)
    Lane k's data read waits for a line fill (its reader's ``stall_fill``).
overflow : Out(1)
    The arbiter's queue overflowed (never: sized to the bursts that can be in flight).
bus : In(hw.bus_port.wishbone_signature(RegisterMap(geometry, external=True).addr_bits))
    Only when loadable.
"""

from __future__ import annotations

from amaranth import *
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

from vqtex.golden import filter as spec
from vqtex.golden.format import TextureSet
from vqtex.golden.geometry import Geometry
from vqtex.golden.memory.system import Layout
from vqtex.golden.register_map import RegisterMap

from ..address import COORD_BITS
from ..bus_port import BusPort, or_all, wishbone_signature
from ..descriptor import texture_bits
from ..features import Features
from ..filter import blend, footprint
from ..filter.blend import Blend
from ..filter.footprint import WEIGHT_WIDTH, FilterRequestLayout, Footprint, level_table
from ..filter.texture_filter import LANES, gather, pixel_drain, sequencer
from ..pipeline import RequestLayout, ResponseLayout
from ..texel_fetch import LATENCY as FETCH_LATENCY
from ..texel_fetch import TexelFetch
from .arbiter import AxiArbiter
from .axi import axi4_read_signature
from .unit import ADDRESS_STAGES, base_registers, cached_lane

__all__ = ["CachedTextureFilter", "LATENCY"]

#: Cycles from a one-group pixel's acceptance to its colour when every reference hits.
LATENCY = footprint.LATENCY + ADDRESS_STAGES + 3 + FETCH_LATENCY + blend.LATENCY


class CachedTextureFilter(wiring.Component):
    __doc__ = __doc__

    def __new__(cls, texture_set=None, config=None, *, lanes: int = 4, geometry=None, loadable: bool = False,
                **kwargs):
        # checked before the instance exists (a rejected one is never reported as unused)
        if loadable and not isinstance(geometry, Geometry):
            raise TypeError("a loadable CachedTextureFilter needs a Geometry")
        if not (loadable and texture_set is None) and not isinstance(texture_set, TextureSet):
            raise TypeError(f"texture_set must be a TextureSet, not {type(texture_set).__name__}")
        if lanes not in LANES:
            raise ValueError(f"lanes must be one of {LANES}, not {lanes!r}")
        return super().__new__(cls)

    def __init__(self, texture_set, config, *, lanes: int = 4, tag_width: int = 8, frac: int | None = None,
                 geometry: Geometry | None = None, loadable: bool = False):
        self._ts = texture_set
        self._config = config
        self._lanes = lanes
        self._tag_width = tag_width
        self._loadable = bool(loadable)
        # a loadable filter without contents starts from a level table of 1x1 textures (the host
        # loads the real one with the descriptors) and serves every level size it can address
        self._table = level_table(texture_set) if texture_set is not None else spec.LevelTable([[(1, 1)]])
        minimum = spec.coordinate_frac_bits(COORD_BITS if self._loadable else self._table.max_log2)
        if frac is not None and frac < minimum:
            raise ValueError(f"frac {frac} is below {minimum} for this texture set")
        self._frac = minimum if frac is None else int(frac)
        # lane 0 carries the weight, the pixel's marks and its tag; the others their weight
        self._lane_tag = [WEIGHT_WIDTH + 2 + tag_width if k == 0 else WEIGHT_WIDTH for k in range(lanes)]
        if self._loadable:
            self._tf = [TexelFetch(texture_set, tag_width=self._lane_tag[k], index_port=True, raw_port=True,
                                   geometry=geometry, loadable=True, bus_port=False) for k in range(lanes)]
            self._texture_bits = self._tf[0].texture_bits
            self._features = self._tf[0].features
            self._map = RegisterMap(self._tf[0].geometry, external=True)
        else:
            self._texture_bits = texture_bits(texture_set)
            self._features = Features.for_set(texture_set, True)
            self._tf = [TexelFetch(texture_set, tag_width=self._lane_tag[k], index_port=True, raw_port=True)
                        for k in range(lanes)]
        super().__init__({
            "i": In(stream.Signature(FilterRequestLayout(self._texture_bits, spec.coordinate_bits(self._frac),
                                                         tag_width))),
            "o": Out(stream.Signature(ResponseLayout(tag_width))),
            "axi": Out(axi4_read_signature(32, 8 * config.bus_bytes)),
            "stall_output": Out(1),
            **{f"stall_memory{k}": Out(1) for k in range(lanes)},
            "overflow": Out(1),
            **({"bus": In(wishbone_signature(self._map.addr_bits))} if self._loadable else {}),
        })

    @property
    def latency(self) -> int:
        return LATENCY

    @property
    def lanes(self) -> int:
        return self._lanes

    @property
    def frac(self) -> int:
        return self._frac

    @property
    def loadable(self) -> bool:
        return self._loadable

    @property
    def features(self) -> Features:
        """What every lane's texel pipeline is built for (``hw.features``)."""
        return self._features

    @property
    def geometry(self) -> Geometry:
        return self._tf[0].geometry

    @property
    def register_map(self) -> RegisterMap | None:
        """The bus port's map (``RegisterMap(geometry, external=True)``; None for the baked filter)."""
        return self._map if self._loadable else None

    def arbiter_depth(self) -> int:
        """The arbiter's queues: every lane's bursts in flight (two per FIFO entry, two in its AR
        slots), rounded up to a power of two."""
        need = self._lanes * (2 * self._config.prefetch + 2)
        return 1 << max(1, (need - 1).bit_length())

    def elaborate(self, platform):
        m = Module()
        lanes, tw, ts = self._lanes, self._tag_width, self._ts
        layout = Layout.of(ts) if ts is not None else None
        lane_kw = [{} for _ in range(lanes)]
        if self._loadable:
            m.submodules.bus_port = port = BusPort(self.geometry, external=True)
            wiring.connect(m, wiring.flipped(self.bus), port.bus)
            # the load command as the texel pipelines take it (their map's offsets are wider: the
            # same layout as a loadable unit's own), to every lane and the footprint
            load = Signal(self._tf[0].load.shape(), name="load")
            m.d.comb += [load.write.eq(port.load.write), load.read.eq(port.load.read),
                         load.region.eq(port.load.region), load.offset.eq(port.load.offset),
                         load.data.eq(port.load.data)]
            m.d.comb += [tf.load.eq(load) for tf in self._tf]
            bases, answer = base_registers(m, port.load, self._map, layout)
            m.d.comb += port.load_data.eq(or_all([self._tf[0].load_data, answer]))
            # any accepted write empties every lane's caches (the drain rule has emptied the filter)
            lane_kw = [{"load": tf.load, "bases": bases, "flush": port.load.write} for tf in self._tf]
        m.submodules.footprint = fp = Footprint(self._table, texture_bits=self._texture_bits, frac=self._frac,
                                                tag_width=tw, load=load.shape() if self._loadable else None)
        if self._loadable:
            m.d.comb += fp.load.eq(load)
        m.submodules.blend = bl = Blend(lanes, tw)
        m.submodules.arbiter = arb = AxiArbiter(lanes, addr_width=32, data_width=8 * self._config.bus_bytes,
                                                depth=self.arbiter_depth())
        wiring.connect(m, arb.axi, wiring.flipped(self.axi))
        en1, en2 = Signal(name="address_en1"), Signal(name="address_en2")
        v1, v2 = Signal(name="address_valid1"), Signal(name="address_valid2")
        front = [Signal(RequestLayout(self._texture_bits, self._lane_tag[k]), name=f"lane{k}_request")
                 for k in range(lanes)]
        readers = []
        for k in range(lanes):
            tf = self._tf[k]
            m.submodules[f"lane{k}"] = tf
            r = cached_lane(m, f"lane{k}_", ts, self._features, self._config, layout, tf, front[k], (en1, en2),
                            joint=True, **lane_kw[k])
            wiring.connect(m, r.axi, arb.ports[k])
            readers.append(r)
        # -- the fork: one valid chain for every lane's address stages; every tag check together ---------
        all_in = Signal(name="readers_ready")
        m.d.comb += [
            all_in.eq(Cat(*(r.i.ready for r in readers)).all()),
            en2.eq(~v2 | all_in),
            en1.eq(~v1 | en2),
        ]
        front_valid = Signal(name="front_valid")
        with m.If(en1):
            m.d.sync += v1.eq(front_valid)
        with m.If(en2):
            m.d.sync += v2.eq(v1)
        # every lane's tag check takes its request in the same cycle: when every lane's check can
        # (the lookups load together, so they hold the same group)
        all_check = Signal(name="readers_check_ready")
        m.d.comb += all_check.eq(Cat(*(r.check_ready for r in readers)).all())
        for r in readers:
            m.d.comb += [r.i.valid.eq(v2 & all_in), r.check_go.eq(all_check)]
        sequencer(m, fp, lanes, en1, [(front_valid if k == 0 else Signal(name=f"lane{k}_valid"), front[k])
                                      for k in range(lanes)], tw)
        # -- the join: the texel pipelines take a group when every reader holds it ------------------------
        all_out = Signal(name="readers_valid")
        m.d.comb += all_out.eq(Cat(*(r.o.valid for r in readers)).all())
        for k, r in enumerate(readers):
            m.d.comb += [self._tf[k].i.valid.eq(all_out), r.o.ready.eq(self._tf[0].i.ready & all_out),
                         getattr(self, f"stall_memory{k}").eq(r.stall_fill)]
        gather(m, bl, [tf.o for tf in self._tf])
        if self._loadable:
            # The drain rule in pixels, the on-chip loadable filter's
            most = footprint.LATENCY + ADDRESS_STAGES + 4 * self._config.prefetch + FETCH_LATENCY + 64
            pixel_drain(m, self.i, fp.i, self.o, port, most)
        else:
            wiring.connect(m, wiring.flipped(self.i), fp.i)
        wiring.connect(m, bl.o, wiring.flipped(self.o))
        m.d.comb += [self.stall_output.eq(self.o.valid & ~self.o.ready), self.overflow.eq(arb.overflow)]
        return m
