"""BackEnd: codebook index -> RGBA response (stages 8-14 of TexelFetch).

codebook ROM -> colour matrix -> the skid register's data and the output multiplexer, every register
enabled by the front end's ``advance``. Its only input is the ``link`` of
:class:`hw.front_end.FrontEnd` (:class:`hw.pipeline.LinkLayout`).
"""

from __future__ import annotations

from amaranth import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from golden.format import TextureSet

from .banked_rom import BANK_DEPTH
from .codebook_rom import CodebookROM
from .color_matrix import ColorMatrix
from .descriptor import descriptor_widths
from .pipeline import LinkLayout, ResponseLayout, addr_bits, pack

__all__ = ["BackEnd"]


class BackEnd(wiring.Component):
    """Stages 8-11 (codebook ROM), 12-14 (colour matrix) and the skid register's data.

    Latency: the response to the index on ``link.index`` in cycle ``t`` is the last stage's
    response in cycle ``t + 7`` when the pipeline advanced in between. Throughput: one per cycle.
    ``payload`` shows the skid register when ``link.skid_valid``, else the last stage (with
    ``link.tag``); the skid register takes the last stage's response in every advancing cycle.

    Arguments
    ---------
    texture_set : TextureSet
        Codebook memory, raw memory, colour matrix.
    tag_width, bank_depth
        As for :class:`hw.texel_fetch.TexelFetch`.

    Members
    -------
    link : In(LinkLayout)
        From the front end.
    payload : Out(ResponseLayout)
        The response shown on the output.
    """

    def __init__(self, texture_set: TextureSet, *, tag_width: int = 8, bank_depth: int = BANK_DEPTH):
        self._ts = texture_set
        self._tag_width = tag_width
        self._bank_depth = bank_depth
        super().__init__({
            "link": In(LinkLayout(texture_set, tag_width)),
            "payload": Out(ResponseLayout(tag_width)),
        })

    def elaborate(self, platform):
        m = Module()
        ts = self._ts
        widths = descriptor_widths(ts)
        link = self.link
        side = link.side
        m.submodules.codebook_rom = rom = CodebookROM(
            ts.codebook, ts.raw_words, cb_bits=widths["cb_base"], raw_bits=addr_bits(len(ts.raw_words)),
            off_bits=widths["texel_off"], bank_depth=self._bank_depth)
        m.submodules.color_matrix = cm = ColorMatrix(ts.matrix)

        # Stages 8-11: codebook ROM (and raw memory).
        m.d.comb += [
            rom.index.eq(link.index), rom.cb_base.eq(side.cb_base), rom.raw_addr.eq(side.raw_addr),
            rom.compressed.eq(side.compressed), rom.x.eq(side.x), rom.y.eq(side.y),
            rom.log2bw.eq(side.log2bw), rom.color.eq(side.color),
            rom.texel_off.eq(side.texel_off), rom.u_off.eq(side.u_off), rom.v_off.eq(side.v_off),
            rom.en.eq(link.advance),
        ]
        # Stages 12-14: colour matrix.
        m.d.comb += [
            cm.samples.eq(rom.samples), cm.color.eq(rom.color_out), cm.en.eq(link.advance),
        ]
        # The output: the skid register (the response pushed out in a stalled cycle) or the last stage.
        response = Signal(self.payload.shape())
        skid = Signal(self.payload.shape(), name="skid")
        m.d.comb += response.eq(pack(response.shape(), {
            "r": cm.rgba[0], "g": cm.rgba[1], "b": cm.rgba[2], "a": cm.rgba[3], "tag": link.tag}))
        with m.If(link.advance):
            m.d.sync += skid.eq(response)
        m.d.comb += self.payload.eq(Mux(link.skid_valid, skid, response))
        return m
