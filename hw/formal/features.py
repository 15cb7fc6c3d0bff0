"""The specialised unit equals the full unit on every valid request (:mod:`hw.features`: the
specialisation is exact), by an equivalence miter.

Two units hold the same texture set, the specialised one (``TexelFetch(ts)``) and the full one
(``TexelFetch(ts, specialise=False)``); they are given the same request stream and the same output
``ready`` in every cycle. The requests are free but valid (:func:`valid_request`: the texture and
level exist and the texel is inside the level, what :func:`golden.fetch.check_requests` checks).
The claims: both have the same ``i.ready`` and ``o.valid`` in every cycle, and when ``o.valid`` is
high the same response (colour and tag).

With the output always ready the miter is proved by k-induction (the pipeline holds at most
``LATENCY`` requests, so ``LATENCY + 2`` cycles determine its whole state); under any
backpressure it is a bounded check (a stall can hold a difference out of sight for ever, which
k-induction cannot rule out without lemmas on the two units' different data paths).
"""

from __future__ import annotations

from amaranth import *
from amaranth.asserts import AnySeq

from vqtex.golden.format import TextureSet

from ..texel_fetch import TexelFetch
from .harness import Harness, SeededBug

__all__ = ["MiterHarness", "valid_request", "MATRIX_SHIFT_SHORT", "TEXEL_STRIDE_SHORT", "TWIDDLE_SQUARE_LARGER"]


def valid_request(ts: TextureSet, request) -> Value:
    """High when ``request`` (a :class:`hw.pipeline.RequestLayout` view) names a texture and level
    of ``ts`` and a texel inside that level."""
    terms = []
    for t in range(ts.n_textures):
        for level, (w, h) in enumerate(ts.level_shapes(t)):
            if ts.descriptors[t, level]["valid"]:
                terms.append((request.texture == t) & (request.level == level) & (request.i < w) & (request.j < h))
    return Cat(*terms).any()


class MiterHarness(Harness):
    """The specialised unit against the full unit (see the module docstring).

    Arguments
    ---------
    texture_set : callable
        Returns the set both units hold.
    backpressure : bool
        The output's ready is free (else held high).
    bug : SeededBug, optional
        Seeded in the specialised unit (design ``specialised``).
    """

    def __init__(self, texture_set, backpressure: bool, bug: SeededBug | None = None):
        super().__init__(bug)
        self._ts = texture_set
        self._backpressure = bool(backpressure)

    def build(self, m, platform):
        ts = self._ts()
        spec = TexelFetch(ts)
        full = TexelFetch(ts, specialise=False)
        self.design(m, "specialised", spec, platform)
        self.design(m, "full", full, platform)
        valid, payload = AnySeq(1), AnySeq(len(Value.cast(spec.i.payload)))
        ready = AnySeq(1) if self._backpressure else C(1, 1)
        for unit in (spec, full):
            m.d.comb += [unit.i.valid.eq(valid), unit.i.payload.eq(payload), unit.o.ready.eq(ready)]
        self.assume(m, ~valid | valid_request(ts, spec.i.payload))
        self.claim(m, spec.i.ready == full.i.ready, "same i.ready")
        self.claim(m, spec.o.valid == full.o.valid, "same o.valid")
        with m.If(spec.o.valid):
            self.claim(m, Value.cast(spec.o.payload) == Value.cast(full.o.payload), "same response")
        self.cover(m, spec.o.valid & (spec.o.payload.r != 0))


#: Negative control: the specialised colour matrix's product of a power-of-two coefficient (Y's
#: weight 2**12 in R) is shifted one bit short.
MATRIX_SHIFT_SHORT = SeededBug(
    "matrix_shift_short", "the specialised colour matrix shifts Y's weight in R one bit short",
    ("back", "color_matrix"), lambda s: [("sync", s("p_ry").eq(s("x0") << 11))], design="specialised")


#: Negative control of an rgb set: the specialised codebook ROM steps 2 bytes per rgb texel, not 3.
TEXEL_STRIDE_SHORT = SeededBug(
    "texel_stride_short", "the specialised codebook ROM's byte address of an rgb texel is 2 t, not 3 t",
    ("back", "codebook_rom"), lambda s: [("comb", s("tbt").eq(s("t") << 1))], design="specialised")

#: Negative control of a PowerVR2 set: the specialised unit's twiddle takes the twiddled squares'
#: side from the larger side of the block grid (wrong for a non-square texture).
TWIDDLE_SQUARE_LARGER = SeededBug(
    "twiddle_square_larger", "the specialised unit's twiddled squares take the larger side of the block grid",
    ("front", "address"), lambda s: [("comb", s("lm").eq(Mux(s("gw") < s("gh"), s("gh"), s("gw"))))],
    design="specialised")
