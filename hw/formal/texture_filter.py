"""The texture filter's streams (:class:`hw.filter.texture_filter.TextureFilter`) keep the stream
rules: its output, and inside it the footprint's output, the sequencer's requests to each texel-fetch
lane, and each lane's output into the blend.

Every filter request and the output's ``ready`` are free in every cycle (no assumption: the
requests need not be valid). Each internal stream's producer must hold ``valid`` and the payload
until its consumer's ``ready``, whatever the consumer does; the claims are
:func:`hw.formal.stream.stream_rules`, one set per stream. With several lanes, lemmas say that the
lanes run in lock step (the same valid bits and the same ``advance``), which k-induction needs: from
an arbitrary state the lanes could otherwise disagree.
"""

from __future__ import annotations

from amaranth import *
from amaranth.asserts import AnySeq

from ..filter.texture_filter import TextureFilter
from .harness import Harness, SeededBug, component, internal
from .stream import stream_rules

__all__ = ["FilterStreamHarness", "BLEND_IGNORES_READY"]


class FilterStreamHarness(Harness):
    """Every stream of the texture filter keeps the rules (see the module docstring).

    Arguments
    ---------
    texture_set : callable
        Returns the set the filter holds.
    lanes : int
        Texel-fetch lanes (with 2 or more the lanes share the index memory's parity banks).
    bug : SeededBug, optional
    """

    def __init__(self, texture_set, lanes: int = 1, bug: SeededBug | None = None):
        super().__init__(bug)
        self._ts = texture_set
        self._lanes = lanes

    def build(self, m, platform):
        dut = TextureFilter(self._ts(), lanes=self._lanes)
        frag = self.design(m, "dut", dut, platform)
        m.d.comb += [dut.i.valid.eq(AnySeq(1)), dut.i.payload.eq(AnySeq(len(Value.cast(dut.i.payload)))),
                     dut.o.ready.eq(AnySeq(1))]
        stream_rules(self, m, dut.o, "o")
        stream_rules(self, m, component(frag, "footprint").o, "footprint.o")
        for k in range(self._lanes):
            lane = component(frag, f"lane{k}")
            stream_rules(self, m, lane.i, f"lane{k}.i")
            stream_rules(self, m, lane.o, f"lane{k}.o")
            if k:                       # the lanes run in lock step: the same control state
                self.lemma(m, lane.valid == component(frag, "lane0").valid, f"lane{k}'s valid bits are lane0's")
                self.lemma(m, internal(frag, f"lane{k}", "front", "advance") == internal(frag, "lane0", "front", "advance"),
                           f"lane{k}'s advance is lane0's")
        self.cover(m, dut.o.valid & ~dut.o.ready)


#: Negative control: the blend's last stage takes a group while its output is stalled (it ignores
#: ``o.ready``), overwriting the colour on the output.
BLEND_IGNORES_READY = SeededBug(
    "blend_ignores_ready", "the blend's output stage ignores o.ready", ("blend",),
    lambda s: [("comb", s("take").eq(s("w_valid")))])
