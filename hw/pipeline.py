"""The texel-fetch pipeline's shared vocabulary: its stages, the request and response layouts, and the
*link* between its two halves.

:class:`hw.texel_fetch.TexelFetch` is two components wired back to back (see docs/hardware.md):

* the **front end** (:class:`hw.front_end.FrontEnd`): the request register, descriptor table,
  block address shifter, index reader (stages 1-8) and all the pipeline control (valid bits,
  ``advance``, the skid register's valid bit), and the request tags (with the tag part of the skid
  register);
* the **back end** (:class:`hw.back_end.BackEnd`): codebook ROM, colour matrix (stages 9-15) and the
  skid register's data.

Everything the back end needs from the front end in a cycle is one registered value, the ``link``
(:class:`LinkLayout`). Nothing flows back: the front end's next state depends on its inputs and its
own state only (the output's valid bit is the control's, not the data path's). That is what lets a
simulator run the two halves as two programs, the back end a few thousand cycles behind the front
end on another core, and still be exact (see docs/simulation.md).
"""

from __future__ import annotations

from amaranth import *
from amaranth.lib import data

from . import codebook_rom, color_matrix, index_reader
from .address import COORD_BITS
from .banked_rom import addr_bits  # noqa: F401 (the pipeline's address widths; re-exported)
from .descriptor import LEVEL_BITS, as_geometry
from .features import Features

__all__ = ["STAGES", "LATENCY", "UPSTREAM_STAGES", "REGISTERS", "FRONT_STAGES", "RequestLayout",
           "ResponseLayout", "RGBALayout", "SideLayout", "LinkLayout", "summed_index_bits", "pack", "addr_bits", "side_fields",
           "SIDE_DESCRIPTOR_FIELDS", "ADVANCE_COPIES", "advance_copies"]

#: Pipeline registers in order, one per cycle of latency; bit ``k`` of ``TexelFetch.valid`` is the
#: valid bit of ``STAGES[k]``.
STAGES = (
    "request",                                                          # the request registered
    "descriptor",                                                       # descriptor table
    "address",                                                          # block address shifter
    "index_bit", "index_word", "index_data", "index_pair", "index",     # index reader
    "codebook", "codebook_data", "texel_window", "texel",               # codebook ROM
    "color_offset", "color_product", "color",                           # colour matrix
)
#: Cycles from accepting a request to presenting its response (one per stage).
LATENCY = len(STAGES)
assert LATENCY == (2 + 1 + index_reader.LATENCY + codebook_rom.LATENCY + color_matrix.LATENCY)
#: The stages of the front end (the rest are the back end's).
FRONT_STAGES = 3 + index_reader.LATENCY
#: The first stages (request, descriptor, address, index_bit), which move on ``upstream``: with
#: ``one_port`` they and the input wait while the index reader's bit-address stage holds a
#: straddling index.
UPSTREAM_STAGES = STAGES.index("index_bit") + 1
#: Registers with a valid bit (bit ``k`` of the ``valid`` output is ``REGISTERS[k]``, and each has
#: an occupancy entry in the simulation reports): the stages, then the skid register in front of
#: the output.
REGISTERS = STAGES + ("skid",)


class RequestLayout(data.StructLayout):
    """A texel request: texture id, level, texel column ``i`` and row ``j`` inside the level, tag.

    Arguments
    ---------
    texture_bits : int
        Width of the texture id (``hw.descriptor.texture_bits(ts)``).
    tag_width : int
        Width of the tag (0 allowed).
    """

    def __init__(self, texture_bits: int, tag_width: int):
        super().__init__({
            "texture": unsigned(texture_bits),
            "level": unsigned(LEVEL_BITS),
            "i": unsigned(COORD_BITS),
            "j": unsigned(COORD_BITS),
            "tag": unsigned(tag_width),
        })


class ResponseLayout(data.StructLayout):
    """A texel response: RGBA8888 and the request's tag.

    Arguments
    ---------
    tag_width : int
        Width of the tag (0 allowed).
    """

    def __init__(self, tag_width: int):
        super().__init__({
            "r": unsigned(8), "g": unsigned(8), "b": unsigned(8), "a": unsigned(8),
            "tag": unsigned(tag_width),
        })


#: A colour: the r, g, b, a bytes of a response.
RGBALayout = data.StructLayout({"r": unsigned(8), "g": unsigned(8), "b": unsigned(8), "a": unsigned(8)})


#: The side fields that are descriptor fields (the rest come from the block address shifter).
SIDE_DESCRIPTOR_FIELDS = ("compressed", "cb_base", "log2bw", "color", "texel_off", "u_off", "v_off")


def side_fields(ts, features: Features | None = None) -> dict:
    """The side fields a unit carries (name -> width): all of them in the full unit; in a
    specialised one, not the constant descriptor fields, ``raw_addr`` only with raw levels, ``x``
    and ``y`` only with compressed levels, the U and V plane offsets only with yuv411 or yuv422."""
    g = as_geometry(ts)
    w = g.descriptor_widths()
    fields = {
        "compressed": 1, "cb_base": w["cb_base"], "raw_addr": addr_bits(g.raw_words),
        "x": 3, "y": 3, "log2bw": 2, "color": w["color"],
        "texel_off": w["texel_off"], "u_off": w["u_off"], "v_off": w["v_off"],
    }
    if features is None or not features.specialised:
        return fields
    drop = {name for name in SIDE_DESCRIPTOR_FIELDS if not features.variable(name)}
    if not features.raw:
        drop.add("raw_addr")
    if not features.compressed:
        drop |= {"x", "y"}
    return {name: width for name, width in fields.items() if name not in drop}


class SideLayout(data.StructLayout):
    """The fields the codebook ROM needs beside the index, carried through the index reader's
    stages: the descriptor's codebook base, format and plane offsets, and the block address
    shifter's offset in the block and raw address (:func:`side_fields`: a specialised unit carries
    only the ones that vary).

    Arguments
    ---------
    ts : TextureSet
        Sets the widths (``hw.descriptor.descriptor_widths``, the raw memory's address).
    features : Features, optional
        Default: the full unit's fields.
    """

    def __init__(self, ts, features: Features | None = None):
        super().__init__(side_fields(ts, features))


class LinkLayout(data.StructLayout):
    """What the front end gives the back end in every cycle, all of it flip-flops of the front end:

    * ``advance``: the pipeline moves this cycle (the enable of every back-end register);
    * ``copies`` (the loadable unit only, ``copies`` > 0): copies of ``advance`` in flip-flops of
      their own (:func:`advance_copies`), each the enable of one block's registers, so that no
      single net drives the clock enables of the whole unit;
    * ``skid_valid``: the skid register holds the response that ``o`` shows;
    * ``index``: the index reader's output (stage 7);
    * ``side``: the fields beside it (:class:`SideLayout`).

    The request tags stay in the front end (with the tag part of the skid register): the back end
    computes the colour only.

    Arguments
    ---------
    ts : TextureSet
    features : Features, optional
        Default: the full unit (a 16-bit index and every side field).
    summed : bool
        ``index`` is the codebook address ``cb_base + index`` (:func:`summed_index_bits` wide), added
        by the index reader's extract stage (the loadable unit: no adder between the link and the
        codebook's block RAMs); ``side.cb_base`` is then not read.
    copies : int
        Width of the ``copies`` field (0: no field).
    """

    def __init__(self, ts, features: Features | None = None, *, summed: bool = False, copies: int = 0):
        index = index_reader.INDEX_BITS if features is None or not features.specialised else features.index_bits
        if summed:
            index = summed_index_bits(ts, features)
        super().__init__({
            "advance": 1, **({"copies": copies} if copies else {}), "skid_valid": 1, "index": index,
            "side": SideLayout(ts, features),
        })


#: The copies of ``advance`` the loadable unit keeps (:func:`advance_copies`): the front end's
#: descriptor and address stages (and the index reader's first, which moves with them), its index
#: reader, its side-field carries; the back end's codebook ROM, colour matrix and skid register.
#: Stage 1 (the request) moves on ``advance`` itself: it takes the input. Never more than
#: ``len(_COPY_KINDS)``.
ADVANCE_COPIES = ("address", "index_reader", "side", "codebook_rom", "color_matrix", "skid")
#: Further copies of ``advance`` in the loadable unit, each the enable of a share of the codebook
#: ROM's memories' data registers (:class:`hw.codebook_rom.CodebookROM` ``data_copies``): made by
#: :func:`hw.copies.register_copies` (marked ``keep``, equal to ``advance`` in every cycle), carried
#: after :data:`ADVANCE_COPIES` in the link's ``copies``. One copy of ``advance`` was the clock
#: enable of 2,243 (``paper``) to 3,847 (``max``) flip-flops and block RAM ports (docs/area.md,
#: "The paths between blocks").
DATA_COPIES = 8
#: Copies of ``advance`` in the loadable front end for the index memories' data registers
#: (:class:`hw.index_reader.IndexReader` ``data_copies``), made and used in the front end.
INDEX_DATA_COPIES = 4

# (reset value, reset-less, inverted) of each copy: no two alike, and none like ``advance`` itself
# (reset value 1, reset, not inverted) or ``skid_valid`` (its complement: reset value 0, reset,
# inverted), or Yosys's opt_merge makes them one flip-flop again (it merges flip-flops with the
# same input and the same reset, whatever ``keep`` their wires have).
_COPY_KINDS = ((0, False, False), (1, True, False), (0, True, False),
               (1, False, True), (1, True, True), (0, True, True))


def advance_copies(m: Module, stall: Value, n: int) -> list:
    """``n`` flip-flops in ``m`` that each equal ``advance`` (``~stall`` of the previous cycle)
    from the second cycle after a reset on; returns their values (each already the enable, not
    inverted).

    They differ in their reset value and in whether they store ``advance`` or its complement, so
    that synthesis keeps them apart (``_COPY_KINDS``); in the first cycle after a reset (or, for
    the reset-less ones, after a reset that followed a stalled cycle) a copy may read 0 where
    ``advance`` reads 1. Every stage is empty then (the valid bits reset to 0), so whether stage 2
    or a later one loads in that cycle changes no response (it would load its empty predecessor);
    the registers a copy enables hold data, never a valid bit (those move on ``advance``), and
    never stage 1's (it takes the request accepted in that cycle).
    """
    if n > len(_COPY_KINDS):
        raise ValueError(f"at most {len(_COPY_KINDS)} copies of advance, not {n}")
    out = []
    for k, (init, reset_less, inverted) in enumerate(_COPY_KINDS[:n]):
        q = Signal(init=init, reset_less=reset_less, name=f"advance_copy{k}")
        m.d.sync += q.eq(stall if inverted else ~stall)
        out.append(~q if inverted else q)
    return out


def summed_index_bits(ts, features: Features | None = None) -> int:
    """Width of ``cb_base + index`` (:class:`LinkLayout` with ``summed``): one bit more than the
    wider of the two."""
    index = index_reader.INDEX_BITS if features is None or not features.specialised else features.index_bits
    return max(index, as_geometry(ts).descriptor_widths()["cb_base"]) + 1


def pack(layout: data.StructLayout, fields: dict) -> Value:
    """The bits of a ``layout`` value with these field values, as one concatenation: assigned in one
    piece, it is plain wiring (field-by-field assignments make simulators such as CXXRTL assemble
    the value with read-modify-writes every cycle)."""
    parts = []
    for name, field in sorted(layout, key=lambda item: item[1].offset):
        v = Value.cast(fields[name])
        parts.append(v[:field.width] if len(v) >= field.width else Cat(v, C(0, field.width - len(v))))
    return Cat(*parts)
