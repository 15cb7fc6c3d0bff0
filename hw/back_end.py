"""BackEnd: codebook index -> RGBA response (stages 9-15 of TexelFetch).

codebook ROM -> colour matrix -> the colour part of the skid register and the output multiplexer
(the tags are the front end's), every register
enabled by the front end's ``advance``. Its only input is the ``link`` of
:class:`hw.front_end.FrontEnd` (:class:`hw.pipeline.LinkLayout`).
"""

from __future__ import annotations

from amaranth import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

import numpy as np

from vqtex.golden.color import JFIF_BT601
from vqtex.golden.format import TextureSet
from vqtex.golden.geometry import Geometry

from .banked_rom import BANK_DEPTH
from .bus_port import DATA_WIDTH
from .codebook_rom import CodebookROM
from .color_matrix import ColorMatrix
from .descriptor import as_geometry
from .features import Features
from .pipeline import ADVANCE_COPIES, DATA_COPIES, LinkLayout, RGBALayout, addr_bits

__all__ = ["BackEnd"]

#: The codebook ROM's inputs from the side fields, in the order they are connected.
_ROM_INPUTS = ("cb_base", "raw_addr", "compressed", "x", "y", "log2bw", "color", "texel_off", "u_off", "v_off")


class BackEnd(wiring.Component):
    """Stages 9-12 (codebook ROM), 13-15 (colour matrix) and the colour part of the skid register.

    Latency: the colour for the index on ``link.index`` in cycle ``t`` is the last stage's in cycle
    ``t + 7`` when the pipeline advanced in between. Throughput: one per cycle. ``rgba`` shows the
    skid register when ``link.skid_valid``, else the last stage; the skid register takes the last
    stage's colour in every advancing cycle.

    Arguments
    ---------
    texture_set : TextureSet or None
        Codebook memory, raw memory, colour matrix (the contents; required unless loadable).
    geometry : Geometry, optional
        Memory depths and field widths (default ``Geometry.of(texture_set)``).
    load : data.StructLayout, optional
        The bus port's load command: the codebook and raw memories and the colour matrix are
        loadable; members ``load`` and ``load_data``.
    bank_depth
        As for :class:`hw.texel_fetch.TexelFetch`.
    features : hw.features.Features, optional
        What to build (default the full back end): the codebook and raw memories and selects, the
        colour formats and the colour matrix's products.
    summed : bool
        ``link.index`` is already ``cb_base + index`` (:class:`hw.pipeline.LinkLayout`): the
        codebook's block RAMs take it as their address, with no adder.

    Members
    -------
    link : In(LinkLayout)
        From the front end.
    rgba : Out(RGBALayout)
        The colour shown on the output (r, g, b, a).
    """

    def __init__(self, texture_set: TextureSet | None = None, *, bank_depth: int = BANK_DEPTH,
                 features: Features | None = None, geometry: Geometry | None = None, load=None,
                 raw_port: bool = False, summed: bool = False):
        self._ts = texture_set
        self._raw_port = bool(raw_port)
        self._geometry = geometry if geometry is not None else as_geometry(texture_set)
        self._load = load
        self._bank_depth = bank_depth
        self._features = features if features is not None else Features.full(texture_set)
        self._summed = bool(summed) and self._features.compressed
        super().__init__({
            "link": In(LinkLayout(self._geometry, self._features, summed=self._summed,
                                  copies=len(ADVANCE_COPIES) + DATA_COPIES if load is not None else 0)),
            "rgba": Out(RGBALayout),
            **({} if load is None else {"load": In(load), "load_data": Out(DATA_WIDTH)}),
            **({"raw_in": In(32)} if self._raw_port else {}),
        })

    def elaborate(self, platform):
        m = Module()
        ts = self._ts
        g = self._geometry
        feat = self._features
        load = self._load
        widths = g.descriptor_widths()
        link = self.link
        m.submodules.codebook_rom = rom = CodebookROM(
            ts.codebook if ts is not None else np.zeros((0, g.entry_bytes), np.uint8),
            ts.raw_words if ts is not None else (), cb_bits=widths["cb_base"], raw_bits=addr_bits(g.raw_words),
            off_bits=widths["texel_off"], bank_depth=self._bank_depth, features=feat,
            color_bits=widths["color"], entries=g.codebook_entries, entry_bytes=g.entry_bytes,
            raw_depth=g.raw_words, load=load, raw_port=self._raw_port,
            data_copies=DATA_COPIES if load is not None else 0,
            index_bits=len(link.index) if self._summed else None)
        if self._raw_port:
            m.d.comb += rom.raw_in.eq(self.raw_in)
        m.submodules.color_matrix = cm = ColorMatrix(
            ts.matrix if ts is not None else JFIF_BT601,
            colors=sorted(feat.output_codes) if feat.specialised else None, load=load)
        if load is not None:
            m.d.comb += [rom.load.eq(self.load), cm.load.eq(self.load),
                         self.load_data.eq(rom.load_data | cm.load_data)]

        # Stages 9-12: codebook ROM (and raw memory). The side fields a specialised unit does not
        # carry are constants the ROM knows from the features, or fields it does not use.
        carried = {name for name, _ in link.side.shape()}
        m.d.comb += rom.index.eq(link.index)
        m.d.comb += [getattr(rom, name).eq(getattr(link.side, name)) for name in _ROM_INPUTS
                     if name in carried and not (self._summed and name == "cb_base")]
        # The loadable unit's blocks each move on a copy of ``advance`` (hw.pipeline.advance_copies).
        en = ({name: link.copies[k] for k, name in enumerate(ADVANCE_COPIES)} if load is not None
              else dict.fromkeys(ADVANCE_COPIES, link.advance))
        m.d.comb += rom.en.eq(en["codebook_rom"])
        if load is not None:
            m.d.comb += rom.en_data.eq(link.copies[len(ADVANCE_COPIES):])
        # Stages 13-15: colour matrix.
        m.d.comb += [
            cm.samples.eq(rom.samples), cm.color.eq(rom.color_out), cm.en.eq(en["color_matrix"]),
        ]
        # The output: the skid register (the colour pushed out in a stalled cycle) or the last stage.
        skid = Signal(32, name="skid")
        with m.If(en["skid"]):
            m.d.sync += skid.eq(cm.rgba.as_value())
        m.d.comb += self.rgba.as_value().eq(Mux(link.skid_valid, skid, cm.rgba.as_value()))
        return m
