"""Descriptor table: (texture, level) -> the level's descriptor row.

Twin of :func:`golden.fetch.lookup_descriptor`. The table holds ``golden.format.TextureSet.descriptors``
(``MAX_LEVELS`` rows per texture, row address ``texture * MAX_LEVELS + level``), so one pipeline
serves every texture of a scene: a ROM (the baked unit), or four memories, one per 32-bit register
word of a row (:data:`golden.register_map.DESCRIPTOR_WORDS`), that the host writes over the bus port
(the loadable unit).

The widths of the fields come from a :class:`golden.geometry.Geometry`; every function here that
takes a geometry also takes a texture set (its smallest geometry, ``Geometry.of``).
"""

from __future__ import annotations

import numpy as np
from amaranth import *
from amaranth.lib import data, memory, wiring
from amaranth.lib.wiring import In, Out

from vqtex.golden.format import DESCRIPTOR_FIELDS, MAX_LEVELS, TextureSet, log2
from vqtex.golden.geometry import Geometry
from vqtex.golden.register_map import DESCRIPTOR_WORDS, REGIONS

from .bus_port import DATA_WIDTH, attach_memory, load_decode, or_all
from .features import READ_BY, Features, Fields

__all__ = ["DescriptorLayout", "DescriptorTable", "descriptor_widths", "texture_bits", "LEVEL_BITS", "as_geometry",
           "BLOCK_RAM_ROWS"]

#: Width of a level number (``MAX_LEVELS`` = 16 rows per texture).
LEVEL_BITS = log2(MAX_LEVELS)


def as_geometry(shape) -> Geometry:
    """``shape`` if it is a :class:`Geometry`, else the smallest geometry of the texture set ``shape``."""
    return shape if isinstance(shape, Geometry) else Geometry.of(shape)


def texture_bits(ts: TextureSet | Geometry) -> int:
    """Width of a texture id for this set or geometry (at least 1)."""
    return as_geometry(ts).texture_bits


def descriptor_widths(ts: TextureSet | Geometry) -> dict:
    """Width of every descriptor field for the memories of ``ts`` or a geometry (field name -> bits).

    ``base`` is wide enough for both the index memory and the raw memory, ``cb_base`` for the
    codebook memory, the plane offsets for a byte of the widest entry. ``color`` is 2 bits (the
    paper's four formats) unless the set holds a PowerVR2 texture (codes 4-7: 3 bits), and
    ``layout`` is 1 bit only then (else 0 bits): a set of the paper's textures elaborates exactly
    the paper's unit (:func:`hw.features.pvr2_set`; :class:`hw.features.Features` says which
    PowerVR2 paths the stages elaborate).
    """
    return as_geometry(ts).descriptor_widths()


class DescriptorLayout(data.StructLayout):
    """One descriptor row, the fields of :data:`golden.format.DESCRIPTOR_FIELDS` in that order (or
    only ``fields``, in that order: the columns a specialised table stores).

    Arguments
    ---------
    widths : dict
        Field name -> width, as returned by :func:`descriptor_widths`.
    fields : sequence of str, optional
        The fields held (default all).
    """

    def __init__(self, widths: dict, fields=None):
        fields = tuple(DESCRIPTOR_FIELDS) if fields is None else tuple(fields)
        missing = set(fields) - set(widths)
        if missing:
            raise ValueError(f"descriptor widths lack {sorted(missing)}")
        super().__init__({name: unsigned(widths[name]) for name in DESCRIPTOR_FIELDS if name in fields})


#: The fields a loadable table gives the pipeline (it stores every field, for the host to read back).
READ_BY_TABLE = frozenset(READ_BY)

#: A loadable, registered table (the texel pipeline's) of more rows than this is block RAM: port A
#: the pipeline's read (its address register the request stage), port B the bus's; the rows
#: registered once more behind it (the descriptor stage). Smaller tables stay in LUT RAM, read from
#: a registered address (docs/area.md, "Block by block").
BLOCK_RAM_ROWS = 256


class DescriptorTable(wiring.Component):
    """The descriptor table: a ROM of a set's rows, or loaded over the bus port.

    Latency 1 (a synchronous read: the row for the ``texture`` and ``level`` presented in the cycle
    ``en`` is high appears on ``row`` in the next cycle and stays there while ``en`` is low).
    Throughput: one lookup per cycle.

    With ``registered`` (the texel pipeline's table: its stages ``request`` and ``descriptor``,
    :data:`hw.pipeline.STAGES`), latency 2: ``texture`` and ``level`` are registered when ``en`` is
    high (the request stage), then the table is read and ``row`` registered when ``row_en`` is high
    (the descriptor stage), so ``row`` holds the row of the address ``en`` took, from the cycle
    after ``row_en`` on. Nothing that drives ``texture`` and ``level`` reaches the memory's address
    inputs: a ROM registers the address itself (a block RAM's own address register; Yosys puts a
    ROM in logic behind registers of its own), and the loadable table has a register of the
    address per memory (:func:`hw.bus_port.attach_memory` with ``data_en``), so each group of LUT
    RAMs (``TRELLIS_DPR16X4``, 16 rows each) is read from a copy of its own and the multiplexer
    between them (by ``texture``) ends at the ``row`` register. Throughput: one lookup per cycle.

    Specialised (``features`` of a set, :class:`hw.features.Features`): the table stores only the
    fields the unit reads that differ between rows (``features.stored_fields``), decodes only
    ``features.level_bits`` bits of the level and ``features.texture_bits`` of the texture, and is
    no memory at all when every field is a constant; :meth:`fields` gives every field, a constant
    or a column of ``row``.

    Loadable (``load``): ``geometry.descriptor_rows`` rows in four memories, one per register word
    of a row (:data:`golden.register_map.DESCRIPTOR_WORDS`, each as wide as its fields), every
    field stored (the host reads back what it wrote), no constants; ``ts``, if given, is the
    initial contents.

    Arguments
    ---------
    ts : TextureSet, optional
        The texture set whose descriptors the table holds (required for a ROM).
    features : Features, optional
        Default ``Features.full(ts)``: every field, ``texture * 16 + level``.
    geometry : Geometry, optional
        The field widths and the rows (default ``Geometry.of(ts)``).
    load : data.StructLayout, optional
        The bus port's load command (:func:`hw.bus_port.load_layout`): the table is loadable.
    registered : bool
        Latency 2: the address registered in front of the table (above; member ``row_en``).

    Members
    -------
    texture : In(geometry.texture_bits)
        Texture id.
    level : In(4)
        Level inside the texture (0..15).
    en : In(1)
        Read enable (the pipeline's advance); with ``registered``, the address register's enable.
    row_en : In(1)
        Only with ``registered``: the ``row`` register's enable (the descriptor stage's).
    row : Out(DescriptorLayout)
        The descriptor row (the stored fields), registered.
    load : In(load), load_data : Out(32)
        Only when loadable: the load command and this table's read answer.
    """

    def __init__(self, ts: TextureSet | None = None, *, features: Features | None = None,
                 geometry: Geometry | None = None, load=None, registered: bool = False):
        if ts is None and (geometry is None or load is None):
            raise TypeError("a descriptor table without contents needs a geometry and a load port")
        self._ts = ts
        self._geometry = geometry if geometry is not None else as_geometry(ts)
        self._features = features if features is not None else Features.full(ts)
        self._widths = self._geometry.descriptor_widths()
        self._load = load
        self._registered = bool(registered)
        stored = [n for n in self._features.stored_fields if n in READ_BY_TABLE or load is None]
        self._layout = DescriptorLayout(self._widths, stored)
        super().__init__({
            "texture": In(self._geometry.texture_bits),
            "level": In(LEVEL_BITS),
            "en": In(1),
            **({"row_en": In(1)} if self._registered else {}),
            "row": Out(self._layout),
            **({} if load is None else {"load": In(load), "load_data": Out(DATA_WIDTH)}),
        })

    @property
    def layout(self) -> DescriptorLayout:
        return self._layout

    @property
    def latency(self) -> int:
        """Cycles from ``en`` taking an address to its row on ``row``: 2 with ``registered``, else 1."""
        return 2 if self._registered else 1

    @property
    def widths(self) -> dict:
        return dict(self._widths)

    def fields(self, view=None) -> Fields:
        """Every field the unit reads, from ``view`` (default ``row``; a register of it is a view of
        the same layout): the stored ones as its fields, the constant ones as constants."""
        return Fields(self.row if view is None else view, self._features.constants, self._widths)

    def _rows(self, lb: int, tb: int) -> np.ndarray:
        """The contents, ``1 << lb`` rows per texture, ``1 << (tb + lb)`` rows in all (zero rows past
        the set's)."""
        rows = self._ts.descriptors[:, :1 << lb]
        if rows.shape[1] < 1 << lb:         # the full table: 16 rows per texture
            pad = np.zeros((rows.shape[0], (1 << lb) - rows.shape[1]), rows.dtype)
            rows = np.concatenate([rows, pad], axis=1)
        rows = rows.reshape(-1)
        depth = 1 << (tb + lb)
        if len(rows) < depth:
            rows = np.concatenate([rows, np.zeros(depth - len(rows), rows.dtype)])
        return rows[:depth]

    def elaborate(self, platform):
        if self._load is not None:
            return self._elaborate_loadable()
        m = Module()
        names = [name for name, _ in self._layout]
        if not names:                       # every field a constant: nothing to store
            return m
        lb, tb = self._features.level_bits, self._features.texture_bits
        rows = self._rows(lb, tb)
        init = [{name: int(row[name]) for name in names} for row in rows]
        depth = 1 << (tb + lb)                                  # every address decodes
        # A set with PowerVR2 textures keeps the table in LUTs (as Yosys does for most paper sets):
        # its twiddle adds logic after the read, and a block RAM's clock-to-output (4.3 ns on the
        # ECP5-8) left too little of the cycle for it (89 MHz, docs/pvr2.md).
        attrs = {"rom_style": "logic"} if self._widths["layout"] else None
        m.submodules.table = table = memory.Memory(shape=self._layout, depth=depth, init=init, attrs=attrs)
        port = table.read_port(domain="sync")
        m.d.comb += [
            port.addr.eq(Cat(self.level[:lb], self.texture[:tb])),
            port.en.eq(self.en),
        ]
        if self._registered:                # the ROM's own address register, then the row's
            row = Signal.like(port.data, name="row_r")
            with m.If(self.row_en):
                m.d.sync += row.eq(port.data)
            m.d.comb += self.row.eq(row)
        else:
            m.d.comb += self.row.eq(port.data)
        return m

    def _elaborate_loadable(self):
        """Four memories, one per register word of a row, each as wide as the word's fields; the
        pipeline reads all four at ``texture * 16 + level``; the bus port writes and reads one."""
        m = Module()
        g = self._geometry
        widths = {name: min(self._widths[name], w) for word in DESCRIPTOR_WORDS for name, _, w in word}
        depth = g.descriptor_rows
        addr = Signal(range(max(2, depth)), name="row_address")
        m.d.comb += addr.eq(Cat(self.level, self.texture))
        row = {}
        answers = []
        hit, row_of, lane, command = load_decode(m, self.load, region=REGIONS["descriptors"],
                                                 lanes=len(DESCRIPTOR_WORDS), depth=depth, name="load")
        contents = self._rows(LEVEL_BITS, g.texture_bits)[:depth] if self._ts is not None else None
        block = self._registered and depth > BLOCK_RAM_ROWS
        for w, word in enumerate(DESCRIPTOR_WORDS):
            present = [(name, lsb) for name, lsb, _ in word if widths[name]]
            if not present:
                continue
            layout = data.StructLayout({name: unsigned(widths[name]) for name, _ in present})
            init = [] if contents is None else [{name: int(r[name]) & ((1 << widths[name]) - 1)
                                                  for name, _ in present} for r in contents]
            # In LUTs (distributed RAM), as the baked PowerVR2 table: a block RAM's clock-to-output
            # (4.3 ns on the ECP5-8) left too little of the cycle for the shifter behind it (town's
            # 512-row table: 104-112 MHz, docs/area.md). A registered table of more than
            # BLOCK_RAM_ROWS rows is block RAM (below).
            m.submodules[f"word{w}"] = mem = memory.Memory(
                shape=layout, depth=depth, init=init,
                attrs={"no_rw_check": 1, "ram_style": "block"} if block else {"ram_style": "distributed"})

            def pack(bus_word, present=present, layout=layout):     # noqa: E306
                return Cat(*(bus_word[lsb:lsb + layout.members[name].width] for name, lsb in present))

            def unpack(view, present=present):
                out = C(0, DATA_WIDTH)
                for name, lsb in present:
                    out = out | (Value.cast(getattr(view, name)) << lsb)
                return out[:DATA_WIDTH]

            # A block RAM's port A is the pipeline's (its address register is the request stage,
            # loaded on ``en``), port B the bus's (hw.bus_port.attach_memory with ``own_port``, as the
            # codebook's banks), its data registered on ``row_en`` below; LUT RAM reads from a
            # registered address (``data_en``).
            port, answer = attach_memory(
                m, mem, command, hit=hit, row=row_of, lane=lane, only_lane=w, pack=pack, unpack=unpack,
                name=f"word{w}_load", read_addr=addr, read_en=self.en,
                **({"own_port": True} if block else {"data_en": self.row_en if self._registered else None}))
            data_r = port.data
            if block:
                data_r = Signal.like(port.data, name=f"word{w}_row")
                with m.If(self.row_en):
                    m.d.sync += data_r.eq(port.data)
            answers.append(answer)
            for name, _ in present:
                row[name] = getattr(data_r, name)
        m.d.comb += self.load_data.eq(or_all(answers))
        # ``row`` assigned in one piece (plain wiring; field by field, CXXRTL would assemble it
        # with read-modify-writes every cycle, and its in-place cycle would not apply)
        parts = [row[name] if name in row else C(0, f.width)
                 for name, f in sorted(self._layout, key=lambda item: item[1].offset)]
        m.d.comb += self.row.eq(Cat(*parts))
        return m
