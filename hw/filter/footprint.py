"""Footprint: a filter request (texture, s, t, level of detail, mode, addressing) -> eight texel slots
(level, i, j) and their eight integer weights.

Twin of :func:`golden.filter.footprint` (the same shifts, the same 8-bit fractions, the same
products, the same unused slots), five pipeline stages:

1. *level*: ``L0 = lod >> 8``, ``f = lod & 255`` (0 unless trilinear), ``L1 = min(L0 + 1, last)``;
   the level table gives log2 of the width and height of L0, L1 and level 0. Registered.
2. *shift*: per level ``u = (s >> (frac - 8 - log2 W)) - 128`` (arithmetic shift) and the
   point texel's ``s >> (frac - log2 W0)`` (the same for t). Registered.
3. *coordinates*: ``i0 = u >> 8``, ``i1 = i0 + 1``, ``fu = u & 255`` and ``256 - fu`` (the same
   for t; level 0's fractions are 0 in point mode); every index through the addressing (wrap,
   clamp, mirror). Registered.
4. *bilinear*: ``(256-fu)(256-fv), fu(256-fv), (256-fu)fv, fu fv`` per level (9x9-bit products
   between registers; point: 2^16 in slot 0 and 0 elsewhere, from its zero fractions), the level
   weights ``256 - f`` and ``f`` (``f = 0`` unless trilinear), the slots in order (unused ones
   repeating slot 0). Registered.
5. *weights*: each slot's bilinear product times its level's weight (one 17x9-bit multiplier per
   slot, between registers). Registered: the output.

Loadable (a texture filter built from a geometry): the level table is a memory of one byte per
descriptor row (log2 width and height) and a valid bit per row, written as the host writes word 0
of each descriptor row over the bus port (the footprint watches the load command); a texture's last
level is its highest valid row. The same stages, latency and results.

Latency 5, throughput one request per cycle; a stream in and out with backpressure: the five stages
move together, whenever the output is empty or taken (``move = ~o.valid | o.ready``, one enable for
every register; ``i.ready = move``). A bubble in a stalled pipeline stays a bubble (the filter's
input is back to back in practice; the cycle counts of docs/filter.md hold either way); in exchange
no ready chain runs through the stages: ``o.ready`` reaches the registers' enables through one
gate (the multi-lane filter's critical path was that chain, 8.99 ns at 2 lanes).
"""

from __future__ import annotations

from amaranth import *
from amaranth.lib import data, memory, stream, wiring
from amaranth.lib.wiring import In, Out

from vqtex.golden import filter as spec

from ..address import COORD_BITS
from ..pick import pick
from ..descriptor import LEVEL_BITS

__all__ = ["Footprint", "FilterRequestLayout", "FootprintLayout", "TexelSlotLayout", "LATENCY",
           "LOD_BITS", "WEIGHT_WIDTH", "level_table", "address"]

#: Pipeline stages from a request to its footprint.
LATENCY = 5
#: Width of the level of detail: a level number and 8 fractional bits.
LOD_BITS = LEVEL_BITS + spec.FRAC_BITS
#: Width of a weight (up to 2^24 inclusive).
WEIGHT_WIDTH = spec.WEIGHT_BITS + 1

_MODE_POINT, _MODE_BILINEAR, _MODE_TRILINEAR = range(3)


class FilterRequestLayout(data.StructLayout):
    """A filter request: texture id, ``s`` and ``t`` (signed, ``frac`` fractional bits), the level of
    detail (8 fractional bits, at most 256 times the texture's last level), the mode (0 point,
    1 bilinear, 2 trilinear), the addressing of each axis (0 wrap, 1 clamp, 2 mirror) and a tag.

    Arguments
    ---------
    texture_bits, coord_bits, tag_width : int
        Widths of the texture id, of ``s`` and ``t`` (``golden.filter.coordinate_bits(frac)``), of the tag.
    """

    def __init__(self, texture_bits: int, coord_bits: int, tag_width: int):
        super().__init__({
            "texture": unsigned(texture_bits), "s": signed(coord_bits), "t": signed(coord_bits),
            "lod": unsigned(LOD_BITS), "mode": unsigned(2), "address_s": unsigned(2), "address_t": unsigned(2),
            "tag": unsigned(tag_width),
        })


#: A texel slot of a footprint: the level and the texel's column and row inside it.
TexelSlotLayout = data.StructLayout({"level": unsigned(LEVEL_BITS), "i": unsigned(COORD_BITS),
                                     "j": unsigned(COORD_BITS)})


class FootprintLayout(data.StructLayout):
    """A pixel's footprint: texture, tag, the number of slots used (1, 4 or 8), the eight texel slots
    and their weights (summing to 2^24)."""

    def __init__(self, texture_bits: int, tag_width: int):
        super().__init__({
            "texture": unsigned(texture_bits), "tag": unsigned(tag_width), "used": unsigned(4),
            "texels": data.ArrayLayout(TexelSlotLayout, spec.SLOTS),
            "weights": data.ArrayLayout(unsigned(WEIGHT_WIDTH), spec.SLOTS),
        })


def level_table(ts) -> spec.LevelTable:
    """The filter's level table of a TextureSet (log2 sizes per texture and level, last levels),
    the same object :class:`golden.render.sampling.Sampler` builds from the level shapes."""
    return spec.LevelTable([ts.level_shapes(t) for t in range(ts.n_textures)])


def address(m, i, log2size, mode, name: str):
    """The addressing of :func:`golden.filter.address` in logic: signed index ``i`` -> ``COORD_BITS``
    unsigned, combinational (wrap: mask; clamp: sign and high-bit tests; mirror: the mask XORed by
    bit ``log2size`` of ``i``)."""
    mask = Signal(COORD_BITS + 1, name=f"{name}_mask")
    low = Signal(COORD_BITS, name=f"{name}_low")
    above = Signal(name=f"{name}_above")
    out = Signal(COORD_BITS, name=name)
    m.d.comb += [
        mask.eq((C(1, COORD_BITS + 1) << log2size) - 1),
        low.eq(i[:COORD_BITS] & mask),
        above.eq((i >> log2size) != 0),
    ]
    with m.Switch(mode):
        with m.Case(0):
            m.d.comb += out.eq(low)
        with m.Case(1):
            m.d.comb += out.eq(Mux(i < 0, 0, Mux(above, mask, low)))
        with m.Default():
            m.d.comb += out.eq(low ^ Mux(i.bit_select(log2size, 1), mask, 0))
    return out


class Footprint(wiring.Component):
    """The footprint stage of the texture filter (see the module docstring).

    Arguments
    ---------
    table : golden.filter.LevelTable
        log2 sizes of every level of every texture, last levels (:func:`level_table`).
    texture_bits : int
        Width of the texture id.
    frac : int
        Fractional bits of ``s`` and ``t`` (at least ``golden.filter.coordinate_frac_bits(table.max_log2)``).
    tag_width : int
    load : data.StructLayout, optional
        The bus port's load command (:func:`hw.bus_port.load_layout`): the level table is loaded
        from the descriptor writes (``table``, if given, is its initial contents). Member ``load``.

    Members
    -------
    i : In(stream.Signature(FilterRequestLayout))
    o : Out(stream.Signature(FootprintLayout))
    load : In(load)
        Only when loadable.

    Raises
    ------
    ValueError
        If ``frac`` is too small for the table's textures, or a level is larger than 4096.
    """

    def __init__(self, table: spec.LevelTable, *, texture_bits: int, frac: int, tag_width: int = 8, load=None):
        if frac < spec.coordinate_frac_bits(table.max_log2):
            raise ValueError(f"{frac} fractional bits are too few for textures of 2^{table.max_log2} texels a side")
        if table.max_log2 > COORD_BITS:
            raise ValueError(f"levels up to 2^{COORD_BITS} texels a side, not 2^{table.max_log2}")
        if table.log2w.shape[1] > (1 << LEVEL_BITS):
            raise ValueError(f"at most {1 << LEVEL_BITS} levels")
        self._table = table
        self._frac = int(frac)
        self._texture_bits = texture_bits
        self._tag_width = tag_width
        self._load = load
        super().__init__({
            "i": In(stream.Signature(FilterRequestLayout(texture_bits, spec.coordinate_bits(frac), tag_width))),
            "o": Out(stream.Signature(FootprintLayout(texture_bits, tag_width))),
            **({} if load is None else {"load": In(load)}),
        })

    @property
    def latency(self) -> int:
        return LATENCY

    def _loaded_table(self, m, entries, tb):
        """The loadable level table (see the module docstring): ``(sizes, last_of)``, the
        functions the level stage reads it with (combinational)."""
        from vqtex.golden.register_map import DESCRIPTOR_WORDS, REGIONS
        fields = {name: lsb for name, lsb, _ in DESCRIPTOR_WORDS[0]}
        load = self.load
        rows = len(entries)
        table = memory.Memory(shape=8, depth=rows, init=[e.value for e in entries])
        m.submodules.level_table = table
        valid = Signal(rows, name="level_valid", init=sum(1 << r for r, e in enumerate(entries) if self._row_valid(r)),
                       reset_less=True)
        word = load.offset[:2]                  # the four words of a row: word 0 holds the sizes
        row = load.offset[2:]
        writes = Signal(name="level_write")
        m.d.comb += writes.eq(load.write & (load.region == REGIONS["descriptors"]) & (word == 0) & (row < rows))
        wp = table.write_port()
        m.d.comb += [wp.addr.eq(row), wp.en.eq(writes),
                     wp.data.eq(Cat(load.data[fields["log2w"]:fields["log2w"] + 4],
                                    load.data[fields["log2h"]:fields["log2h"] + 4]))]
        with m.If(writes):
            m.d.sync += valid.bit_select(row[:len(Const(rows - 1))], 1).eq(load.data[fields["valid"]])

        def sizes(texture, level):
            rp = table.read_port(domain="comb")
            m.d.comb += rp.addr.eq(Cat(level, texture))
            return rp.data[:4], rp.data[4:]

        def last_of(texture):
            bits = valid.word_select(texture, 1 << LEVEL_BITS)
            last = C(0, LEVEL_BITS)
            for lv in range(1, 1 << LEVEL_BITS):         # the highest valid level
                last = Mux(bits[lv], lv, last)
            return last
        return sizes, last_of

    def _row_valid(self, r: int) -> bool:
        """Row ``r`` (``texture * 16 + level``) of the initial table is a level of its texture."""
        t, lv = divmod(r, 1 << LEVEL_BITS)
        return t < len(self._table.last) and lv <= int(self._table.last[t])

    def elaborate(self, platform):
        m = Module()
        frac = self._frac
        tb = self._texture_bits
        table = self._table
        one = 1 << spec.FRAC_BITS

        # -- stream control: the stages move together when the output is empty or taken -----------
        names = ("level", "shift", "coords", "bilinear", "weights")
        valid = [Signal(name=f"valid_{n}") for n in names]
        move = Signal(name="move")
        m.d.comb += move.eq(~valid[-1] | self.o.ready)
        with m.If(move):
            m.d.sync += [valid[k].eq(self.i.valid if k == 0 else valid[k - 1]) for k in range(len(names))]
        m.d.comb += [self.i.ready.eq(move), self.o.valid.eq(valid[-1])]

        # -- the level table: (texture, level) -> log2 width, log2 height (constants, a mux tree) ---
        nlev = 1 << LEVEL_BITS
        entries = []
        for t in range(1 << tb):
            for lv in range(nlev):
                if t < table.log2w.shape[0]:
                    lvc = min(lv, table.log2w.shape[1] - 1)
                    entries.append(C(int(table.log2w[t, lvc]) | int(table.log2h[t, lvc]) << 4, 8))
                else:
                    entries.append(C(0, 8))
        lasts = [C(int(table.last[t]) if t < len(table.last) else 0, LEVEL_BITS) for t in range(1 << tb)]

        def sizes(texture, level):
            e = pick(entries, Cat(level, texture))
            return e[:4], e[4:]

        if self._load is not None:
            sizes, last_of = self._loaded_table(m, entries, tb)
        else:
            def last_of(texture):
                return pick(lasts, texture)

        # Stage 1: level.
        p = self.i.p
        r1 = Signal(data.StructLayout({
            "texture": tb, "s": len(p.s), "t": len(p.t), "mode": 2, "address_s": 2, "address_t": 2,
            "tag": self._tag_width, "l0": LEVEL_BITS, "l1": LEVEL_BITS, "f": 8,
            "lw0": 4, "lh0": 4, "lw1": 4, "lh1": 4, "lwp": 4, "lhp": 4}), name="level")
        l0 = Signal(LEVEL_BITS, name="l0")
        l1 = Signal(LEVEL_BITS, name="l1")
        last = Signal(LEVEL_BITS, name="last")
        m.d.comb += [
            l0.eq(p.lod[spec.FRAC_BITS:]),
            last.eq(last_of(p.texture)),
            l1.eq(Mux(l0 < last, l0 + 1, l0)),
        ]
        lw0, lh0 = sizes(p.texture, l0)
        lw1, lh1 = sizes(p.texture, l1)
        lwp, lhp = sizes(p.texture, C(0, LEVEL_BITS))
        with m.If(move):
            m.d.sync += [
                r1.texture.eq(p.texture), r1.s.eq(p.s), r1.t.eq(p.t), r1.mode.eq(p.mode),
                r1.address_s.eq(p.address_s), r1.address_t.eq(p.address_t), r1.tag.eq(p.tag),
                r1.l0.eq(l0), r1.l1.eq(l1),
                r1.f.eq(Mux(p.mode == _MODE_TRILINEAR, p.lod[:spec.FRAC_BITS], 0)),
                r1.lw0.eq(lw0), r1.lh0.eq(lh0), r1.lw1.eq(lw1), r1.lh1.eq(lh1), r1.lwp.eq(lwp), r1.lhp.eq(lhp),
            ]

        # Stage 2: the shifts, u = (s >> (frac - 8 - log2 W)) - 128 per level and axis, and the point
        # texel's s >> (frac - log2 W0).
        s, t = r1.s.as_signed(), r1.t.as_signed()
        ub = len(s) + 1
        rs = Signal(data.StructLayout({
            "texture": tb, "mode": 2, "address_s": 2, "address_t": 2, "tag": self._tag_width,
            "l0": LEVEL_BITS, "l1": LEVEL_BITS, "f": 8,
            "lw0": 4, "lh0": 4, "lw1": 4, "lh1": 4, "lwp": 4, "lhp": 4,
            "u": data.ArrayLayout(signed(ub), 4), "p": data.ArrayLayout(signed(len(s)), 2)}), name="shift")
        shifted = []
        for k, (lw, lh) in enumerate(((r1.lw0, r1.lh0), (r1.lw1, r1.lh1))):
            for axis, (c, lsz) in enumerate(((s, lw), (t, lh))):
                sh = Signal(range(frac + 1), name=f"shift{k}{'st'[axis]}")
                u = Signal(signed(ub), name=f"u{k}{'st'[axis]}")
                m.d.comb += [sh.eq(frac - spec.FRAC_BITS - lsz), u.eq((c >> sh) - (one >> 1))]
                shifted.append(u)
        points = []
        for axis, (c, lsz) in enumerate(((s, r1.lwp), (t, r1.lhp))):
            sh = Signal(range(frac + 1), name=f"shift_point_{'st'[axis]}")
            ip = Signal(signed(len(c)), name=f"point_{'st'[axis]}")
            m.d.comb += [sh.eq(frac - lsz), ip.eq(c >> sh)]
            points.append(ip)
        with m.If(move):
            m.d.sync += [getattr(rs, f).eq(getattr(r1, f)) for f in
                         ("texture", "mode", "address_s", "address_t", "tag", "l0", "l1", "f",
                          "lw0", "lh0", "lw1", "lh1", "lwp", "lhp")]
            m.d.sync += [rs.u[n].eq(v) for n, v in enumerate(shifted)]
            m.d.sync += [rs.p[n].eq(v) for n, v in enumerate(points)]

        # Stage 3: coordinates and addressing.
        r1 = rs
        r2 = Signal(data.StructLayout({
            "texture": tb, "mode": 2, "tag": self._tag_width, "l0": LEVEL_BITS, "l1": LEVEL_BITS, "f": 8,
            "idx": data.ArrayLayout(COORD_BITS, 8),     # per level: i0, i1, j0, j1
            "fr": data.ArrayLayout(9, 8),               # per level: 256 - fu, fu, 256 - fv, fv
            "ip": COORD_BITS, "jp": COORD_BITS}), name="coords")
        idx, fr = [], []
        for k, (lw, lh) in enumerate(((r1.lw0, r1.lh0), (r1.lw1, r1.lh1))):
            for axis, (lsz, mode) in enumerate(((lw, r1.address_s), (lh, r1.address_t))):
                u = r1.u[2 * k + axis].as_signed()
                i0 = Signal(signed(len(u) - spec.FRAC_BITS), name=f"i0_{k}{'st'[axis]}")
                i1 = Signal(signed(len(u) - spec.FRAC_BITS + 1), name=f"i1_{k}{'st'[axis]}")
                m.d.comb += [i0.eq(u >> spec.FRAC_BITS), i1.eq(i0 + 1)]
                idx += [address(m, i0, lsz, mode, f"a0_{k}{'st'[axis]}"), address(m, i1, lsz, mode, f"a1_{k}{'st'[axis]}")]
                frac_part = Signal(spec.FRAC_BITS, name=f"f{k}{'st'[axis]}")
                # point mode: level 0's fractions are 0, so its first bilinear product is 2^16 and
                # the others 0 (the multipliers of stage 3 then need no multiplexer behind them)
                m.d.comb += frac_part.eq(Mux((r1.mode == _MODE_POINT) & (k == 0), 0, u[:spec.FRAC_BITS]))
                fr += [C(one, 9) - frac_part, frac_part]
        pts = []
        for axis, (lsz, mode) in enumerate(((r1.lwp, r1.address_s), (r1.lhp, r1.address_t))):
            pts.append(address(m, r1.p[axis].as_signed(), lsz, mode, f"ap_{'st'[axis]}"))
        with m.If(move):
            m.d.sync += [
                r2.texture.eq(r1.texture), r2.mode.eq(r1.mode), r2.tag.eq(r1.tag), r2.l0.eq(r1.l0),
                r2.l1.eq(r1.l1), r2.f.eq(r1.f), r2.ip.eq(pts[0]), r2.jp.eq(pts[1]),
            ]
            m.d.sync += [r2.idx[n].eq(v) for n, v in enumerate(idx)]
            m.d.sync += [r2.fr[n].eq(v) for n, v in enumerate(fr)]

        # Stage 4: bilinear products per level, the slot order, the level weights.
        r3 = Signal(data.StructLayout({
            "texture": tb, "tag": self._tag_width, "used": 4,
            "slots": data.ArrayLayout(TexelSlotLayout, spec.SLOTS),
            "bil": data.ArrayLayout(17, spec.SLOTS),           # point: 2^16 in slot 0, 0 elsewhere
            "lw": data.ArrayLayout(9, 2)}), name="bilinear")  # 256 - f and f (f = 0 unless trilinear)
        slots = []
        for k, lv in enumerate((r2.l0, r2.l1)):
            i0, i1, j0, j1 = (r2.idx[4 * k + n] for n in range(4))
            slots += [Cat(lv, i0, j0), Cat(lv, i1, j0), Cat(lv, i0, j1), Cat(lv, i1, j1)]
        point = Cat(C(0, LEVEL_BITS), r2.ip, r2.jp)
        products = []
        for k in range(2):
            gu, fu, gv, fv = (r2.fr[4 * k + n] for n in range(4))
            products += [gu * gv, fu * gv, gu * fv, fu * fv]
        with m.If(move):
            m.d.sync += [r3.texture.eq(r2.texture), r3.tag.eq(r2.tag),
                         r3.lw[0].eq(C(one, 9) - r2.f), r3.lw[1].eq(r2.f)]
            m.d.sync += [r3.bil[n].eq(products[n]) for n in range(spec.SLOTS)]
            with m.Switch(r2.mode):
                with m.Case(_MODE_POINT):
                    m.d.sync += r3.used.eq(1)
                    m.d.sync += [r3.slots[n].eq(point) for n in range(spec.SLOTS)]
                with m.Case(_MODE_BILINEAR):
                    m.d.sync += r3.used.eq(4)
                    m.d.sync += [r3.slots[n].eq(slots[n if n < 4 else 0]) for n in range(spec.SLOTS)]
                with m.Default():
                    m.d.sync += r3.used.eq(8)
                    m.d.sync += [r3.slots[n].eq(slots[n]) for n in range(spec.SLOTS)]

        # Stage 5: the weights, bilinear product times level weight (one multiplier each, registered).
        out = self.o.p
        with m.If(move):
            m.d.sync += [out.texture.eq(r3.texture), out.tag.eq(r3.tag), out.used.eq(r3.used)]
            for n in range(spec.SLOTS):
                m.d.sync += [out.texels[n].eq(r3.slots[n]), out.weights[n].eq(r3.bil[n] * r3.lw[n // 4])]
        return m
