"""Descriptor table: (texture, level) -> the level's descriptor row.

Twin of :func:`golden.fetch.lookup_descriptor`. The table is a ROM holding
``golden.format.TextureSet.descriptors`` (``MAX_LEVELS`` rows per texture, row address
``texture * MAX_LEVELS + level``), so one pipeline serves every texture of a scene.
"""

from __future__ import annotations

import numpy as np
from amaranth import *
from amaranth.lib import data, memory, wiring
from amaranth.lib.wiring import In, Out
from amaranth.utils import bits_for

from vqtex.golden.format import DESCRIPTOR_FIELDS, MAX_LEVELS, TextureSet, log2

from .features import Features, Fields, pvr2_set

__all__ = ["DescriptorLayout", "DescriptorTable", "descriptor_widths", "texture_bits", "LEVEL_BITS"]

#: Width of a level number (``MAX_LEVELS`` = 16 rows per texture).
LEVEL_BITS = log2(MAX_LEVELS)


def texture_bits(ts: TextureSet) -> int:
    """Width of a texture id for this set (at least 1)."""
    return bits_for(ts.n_textures - 1)


def descriptor_widths(ts: TextureSet) -> dict:
    """Width of every descriptor field for the memories of ``ts`` (field name -> bits).

    ``base`` is wide enough for both the index memory and the raw memory, ``cb_base`` for the
    codebook memory, the plane offsets for a byte of the widest entry. ``color`` is 2 bits (the
    paper's four formats) unless the set holds a PowerVR2 texture (codes 4-7: 3 bits), and
    ``layout`` is 1 bit only then (else 0 bits): a set of the paper's textures elaborates exactly
    the paper's unit (:func:`hw.features.pvr2_set`; :class:`hw.features.Features` says which
    PowerVR2 paths the stages elaborate).
    """
    base_bits = bits_for(max(len(ts.index_words), len(ts.raw_words)))
    pvr2 = pvr2_set(ts)
    return {
        "valid": 1,
        "compressed": 1,
        "base": base_bits,
        "log2w": 4,
        "log2h": 4,
        "log2bw": 2,
        "log2bh": 2,
        "index_bits": 5,
        "cb_base": bits_for(len(ts.codebook)),
        "sublevel": 2,
        "color": 3 if pvr2 else 2,
        "texel_off": bits_for(ts.entry_bytes),
        "u_off": bits_for(ts.entry_bytes),
        "v_off": bits_for(ts.entry_bytes),
        "layout": 1 if pvr2 else 0,
    }


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


class DescriptorTable(wiring.Component):
    """The descriptor table ROM.

    Latency 1 (a synchronous read: the row for the ``texture`` and ``level`` presented in the cycle
    ``en`` is high appears on ``row`` in the next cycle and stays there while ``en`` is low).
    Throughput: one lookup per cycle.

    Specialised (``features`` of a set, :class:`hw.features.Features`): the table stores only the
    fields the unit reads that differ between rows (``features.stored_fields``), decodes only
    ``features.level_bits`` bits of the level and ``features.texture_bits`` of the texture, and is
    no memory at all when every field is a constant; :meth:`fields` gives every field, a constant
    or a column of ``row``.

    Arguments
    ---------
    ts : TextureSet
        The texture set whose descriptors the ROM holds.
    features : Features, optional
        Default ``Features.full(ts)``: every field, ``texture * 16 + level``.

    Members
    -------
    texture : In(texture_bits(ts))
        Texture id.
    level : In(4)
        Level inside the texture (0..15).
    en : In(1)
        Read enable (the pipeline's advance).
    row : Out(DescriptorLayout)
        The descriptor row (the stored fields), registered.
    """

    def __init__(self, ts: TextureSet, *, features: Features | None = None):
        self._ts = ts
        self._features = features if features is not None else Features.full(ts)
        self._widths = descriptor_widths(ts)
        self._layout = DescriptorLayout(self._widths, self._features.stored_fields)
        super().__init__({
            "texture": In(texture_bits(ts)),
            "level": In(LEVEL_BITS),
            "en": In(1),
            "row": Out(self._layout),
        })

    @property
    def layout(self) -> DescriptorLayout:
        return self._layout

    @property
    def widths(self) -> dict:
        return dict(self._widths)

    def fields(self, view=None) -> Fields:
        """Every field the unit reads, from ``view`` (default ``row``; a register of it is a view of
        the same layout): the stored ones as its fields, the constant ones as constants."""
        return Fields(self.row if view is None else view, self._features.constants, self._widths)

    def elaborate(self, platform):
        m = Module()
        names = [name for name, _ in self._layout]
        if not names:                       # every field a constant: nothing to store
            return m
        lb, tb = self._features.level_bits, self._features.texture_bits
        rows = self._ts.descriptors[:, :1 << lb]
        if rows.shape[1] < 1 << lb:         # the full table: 16 rows per texture
            pad = np.zeros((rows.shape[0], (1 << lb) - rows.shape[1]), rows.dtype)
            rows = np.concatenate([rows, pad], axis=1)
        init = [{name: int(row[name]) for name in names} for row in rows.reshape(-1)]
        depth = 1 << (tb + lb)                                  # every address decodes
        init += [{name: 0 for name in names}] * (depth - len(init))
        # A set with PowerVR2 textures keeps the table in LUTs (as Yosys does for most paper sets):
        # its twiddle adds logic after the read, and a block RAM's clock-to-output (4.3 ns on the
        # ECP5-8) left too little of the cycle for it (89 MHz, docs/pvr2.md).
        attrs = {"rom_style": "logic"} if self._widths["layout"] else None
        m.submodules.table = table = memory.Memory(shape=self._layout, depth=depth, init=init, attrs=attrs)
        port = table.read_port(domain="sync")
        m.d.comb += [
            port.addr.eq(Cat(self.level[:lb], self.texture[:tb])),
            port.en.eq(self.en),
            self.row.eq(port.data),
        ]
        return m
