"""Blend: weighted texels -> the filtered RGBA8888 colour of a pixel.

Twin of :func:`golden.filter.blend`: per channel ``(sum_k w_k texel_k + 2^23) >> 24`` over the
pixel's slots, which arrive in *groups* of ``lanes`` texels (one group per cycle; a pixel is one
group or several in a row, marked ``first`` and ``last``). Four stages:

1. *group*: the lanes' texels and weights, registered (nothing but wires behind the lanes' outputs).
2. *weigh*: per lane and channel ``w_k texel_k`` as two partial products, ``w_k[0:17] texel_k`` and
   ``w_k[17:25] texel_k`` (each one MULT18X18D, no adder behind it), registered with ``first``,
   ``last`` and the tag.
3. *sum*: per channel the group's ``sum_k (lo_k + (hi_k << 17))``, registered.
4. *accumulate*: ``acc = (0 if first else acc) + sum``; on the ``last`` group the rounded colour
   ``(acc + 2^23) >> 24`` is the output register (the stream's payload).

Latency 4 (the last group of a pixel in cycle ``t``, its colour on ``o`` in cycle ``t + 4``);
throughput one group per cycle. Stream backpressure: each stage loads when it is empty or its
content moves on, the last when ``~o.valid | o.ready`` (``i.ready`` is combinational on
``o.ready``); all sums stay below 2^32 because the weights of a pixel sum to 2^24.
"""

from __future__ import annotations

from amaranth import *
from amaranth.lib import data, stream, wiring
from amaranth.lib.wiring import In, Out

from vqtex.golden import filter as spec

from ..pipeline import ResponseLayout
from .footprint import WEIGHT_WIDTH

__all__ = ["Blend", "GroupLayout", "LATENCY"]

#: Cycles from a pixel's last group to its colour.
LATENCY = 4
_ACC = 32
#: The weight's bits in the low partial product (an unsigned 17-bit operand of an 18x18 multiplier).
_LOW = 17


class GroupLayout(data.StructLayout):
    """One group of weighted texels: per lane the texel (r, g, b, a bytes, bits 0..31) and its weight;
    ``first`` and ``last`` group of the pixel; the pixel's tag."""

    def __init__(self, lanes: int, tag_width: int):
        super().__init__({
            "rgba": data.ArrayLayout(32, lanes), "weight": data.ArrayLayout(WEIGHT_WIDTH, lanes),
            "first": 1, "last": 1, "tag": unsigned(tag_width),
        })


class Blend(wiring.Component):
    """The blend stage of the texture filter (see the module docstring).

    Arguments
    ---------
    lanes : int
        Texels per group.
    tag_width : int

    Members
    -------
    i : In(stream.Signature(GroupLayout(lanes, tag_width)))
    o : Out(stream.Signature(hw.pipeline.ResponseLayout(tag_width)))
    """

    def __init__(self, lanes: int, tag_width: int = 8):
        self._lanes = lanes
        self._tag_width = tag_width
        super().__init__({
            "i": In(stream.Signature(GroupLayout(lanes, tag_width))),
            "o": Out(stream.Signature(ResponseLayout(tag_width))),
        })

    @property
    def latency(self) -> int:
        return LATENCY

    def elaborate(self, platform):
        m = Module()
        lanes = self._lanes
        half = 1 << (spec.WEIGHT_BITS - 1)

        # Stage 1: the group, registered (the lanes' outputs come through their skid multiplexers).
        g_valid = Signal()
        g = Signal.like(self.i.p, name="group")
        # Stage 2: weigh (the products, registered: each multiplier between registers).
        p_valid = Signal()
        lo = [[Signal(_LOW + 8, name=f"product{k}_{'rgba'[c]}_lo") for c in range(4)] for k in range(lanes)]
        hi = [[Signal(WEIGHT_WIDTH - _LOW + 8, name=f"product{k}_{'rgba'[c]}_hi") for c in range(4)]
              for k in range(lanes)]
        p_first, p_last = Signal(), Signal()
        p_tag = Signal(self._tag_width)
        # Stage 3: sum (the lanes' products added, registered).
        w_valid = Signal()
        w_sum = [Signal(_ACC, name=f"sum_{'rgba'[c]}") for c in range(4)]
        w_first, w_last = Signal(), Signal()
        w_tag = Signal(self._tag_width)
        take = Signal()                              # stage 4 takes stage 3's group this cycle
        load_w = Signal()                            # stage 3 loads (it is empty or its group moves on)
        load_p = Signal()                            # stage 2 loads
        load_g = Signal()                            # stage 1 loads
        m.d.comb += [
            take.eq(w_valid & (~self.o.valid | self.o.ready)),
            load_w.eq(~w_valid | take),
            load_p.eq(~p_valid | load_w),
            load_g.eq(~g_valid | load_p),
            self.i.ready.eq(load_g),
        ]
        with m.If(load_g):
            m.d.sync += [g_valid.eq(self.i.valid), g.eq(self.i.p)]
        with m.If(load_p):
            m.d.sync += [p_valid.eq(g_valid), p_first.eq(g.first), p_last.eq(g.last), p_tag.eq(g.tag)]
            for k in range(lanes):
                for c in range(4):
                    texel = g.rgba[k][8 * c:8 * c + 8]
                    m.d.sync += [lo[k][c].eq(g.weight[k][:_LOW] * texel), hi[k][c].eq(g.weight[k][_LOW:] * texel)]
        with m.If(load_w):
            m.d.sync += [w_valid.eq(p_valid), w_first.eq(p_first), w_last.eq(p_last), w_tag.eq(p_tag)]
            for c in range(4):
                total = lo[0][c] + (hi[0][c] << _LOW)
                for k in range(1, lanes):
                    total = total + lo[k][c] + (hi[k][c] << _LOW)
                m.d.sync += w_sum[c].eq(total)

        # Stage 4: accumulate, round, output register.
        acc = [Signal(_ACC, name=f"acc_{'rgba'[c]}") for c in range(4)]
        new = [Signal(_ACC, name=f"new_{'rgba'[c]}") for c in range(4)]
        rounded = [Signal(_ACC + 1, name=f"rounded_{'rgba'[c]}") for c in range(4)]
        for c in range(4):
            m.d.comb += [new[c].eq(Mux(w_first, 0, acc[c]) + w_sum[c]), rounded[c].eq(new[c] + half)]
        with m.If(self.o.ready):
            m.d.sync += self.o.valid.eq(0)
        with m.If(take):
            m.d.sync += [acc[c].eq(new[c]) for c in range(4)]
            with m.If(w_last):
                m.d.sync += [self.o.valid.eq(1), self.o.p.tag.eq(w_tag)]
                m.d.sync += [getattr(self.o.p, "rgba"[c]).eq(rounded[c][spec.WEIGHT_BITS:spec.WEIGHT_BITS + 8])
                             for c in range(4)]
        return m
