"""What a texture set needs of the texel-fetch unit: the one place the unit is specialised.

:class:`Features` is computed from a :class:`golden.format.TextureSet` (``Features.of(ts)``) and
handed to every block of :class:`hw.texel_fetch.TexelFetch`; each optional piece of logic is guarded
by one of its fields, so that the unit elaborates only what the set's memories can ask of it:

============================  ===============================================================
field                         what it removes when the set does not need it
============================  ===============================================================
``compressed``                the index reader and the codebook memory (every level raw)
``raw``                       the raw memory, the raw address adder, the raw path of the select
``colors``                    the colour formats' texel selects and bypasses; without yuv411
                              or yuv422 the colour matrix (offsets, products, sums, clamps) and
                              the U, V selects of the codebook ROM; without PowerVR2's 16-bit
                              formats the texel expansion, without yuv422 its U, V pair select
``layouts``                   the PowerVR2 twiddle of the block address shifter (no level with a
                              twiddled map); without a paper (row-major) level, its multiplexer
``index_widths``              the ``k * b`` multiplier (one to three widths: shifts and adds),
                              the index mask (one width), index bits above the widest
``straddle``                  the odd bank and the word pair (no index crosses a word: every
                              width divides the word, or the maps are too short to cross)
``sublevels``                 (reported) no level reads a sub-level of an extended codeword:
                              the plane offset adder goes, ``texel_off`` being constant 0
``constants``                 every descriptor field that holds one value in every row that
                              reads it is a constant, not a column of the descriptor table nor a
                              register beside the index (cb_base, log2bw, colour, offsets, ...)
============================  ===============================================================

The colour matrix's products exist only for its non-zero coefficients, and a coefficient 0, +-1 or
+-2^n is a shift, not a multiplier (:class:`hw.color_matrix.ColorMatrix`).

``Features.full(ts)`` is the unit that serves any request of any set with these memory shapes:
every path present, every descriptor field stored (the unit as it was before specialisation). A
set holding PowerVR2 textures (:func:`pvr2_set`) makes it the PowerVR2 unit: every layout and all
eight colour formats; a set of the paper's textures the paper's unit (no PowerVR2 logic at all).
Both are bit-exact on every valid request; the specialised unit does not check requests (no unit
does: :func:`golden.fetch.check_requests` does).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from math import gcd

import numpy as np
from amaranth import C
from amaranth.utils import bits_for, ceil_log2

from vqtex.golden.format import (COLOR_CODES, COLORS, DESCRIPTOR_FIELDS, LAYOUT_CODES, MAX_LEVELS, PVR2_COLORS,
                                 TextureSet, log2)

__all__ = ["Features", "READ_BY", "ALL_WIDTHS", "Fields", "PAPER_COLORS", "pvr2_set"]

#: The descriptor fields the hardware reads, and in which rows: ``all`` (every level), ``compressed``
#: (compressed levels), ``yuv`` (compressed yuv411 and yuv422 levels), ``twiddled`` (compressed
#: levels with a PowerVR2 twiddled map: the twiddle needs the level's height). The table's other
#: fields (``valid``, ``sublevel``) are never read by the unit (requests are valid; the sub-level is
#: in the plane offsets and ``log2bw``). A block that comes to read another descriptor field must add it
#: here: a specialised table stores only these (a field missing here is neither stored nor a
#: constant, and reading it from ``DescriptorTable.fields()`` fails at elaboration).
READ_BY = {
    "compressed": "all", "base": "all", "log2w": "all",
    "log2bw": "compressed", "log2bh": "compressed", "index_bits": "compressed", "cb_base": "compressed",
    "color": "compressed", "texel_off": "compressed",
    "u_off": "yuv", "v_off": "yuv",
    "layout": "compressed", "log2h": "twiddled",
}
#: The paper's four colour formats (codes 0-3: what the colour matrix receives).
PAPER_COLORS = tuple(c for c in COLORS if c not in PVR2_COLORS)
_TWIDDLED = LAYOUT_CODES["pvr2"]


def pvr2_set(ts: TextureSet) -> bool:
    """``ts`` holds a PowerVR2 texture (a level with the twiddled layout or a PowerVR2 colour
    format): its descriptors have a 1-bit ``layout`` and a 3-bit ``color``
    (:func:`hw.descriptor.descriptor_widths`), and its full unit has the PowerVR2 paths."""
    d = ts.descriptors
    valid = d["valid"] != 0
    return bool((d["layout"][valid] != 0).any() or (d["color"][valid] >= len(PAPER_COLORS)).any())
#: Every index width the format allows.
ALL_WIDTHS = tuple(range(1, 17))


def _straddles(ts: TextureSet) -> bool:
    """Whether any index of any compressed level crosses a word boundary: index ``k`` of a map of
    ``b``-bit indices starts at bit ``k*b mod W`` of its word; the offsets repeat every ``W`` indices,
    so the first ``min(blocks, W)`` of each map decide (rows x W, vectorised)."""
    d = ts.descriptors[(ts.descriptors["valid"] != 0) & (ts.descriptors["compressed"] != 0)]
    if not len(d):
        return False
    W = ts.word_bits
    b = d["index_bits"].astype(np.int64)[:, None]
    span = (d["log2w"].astype(np.int64) - d["log2bw"] + d["log2h"] - d["log2bh"])[:, None]
    k = np.arange(W, dtype=np.int64)[None, :]
    present = k < (np.int64(1) << np.minimum(span, 30))
    return bool((present & ((k * b) % W + b > W)).any())


@dataclass(frozen=True)
class Features:
    """The parts of the texel-fetch unit a texture set needs (see the module docstring).

    Members
    -------
    specialised : bool
        False for :meth:`full` (every path, every descriptor field).
    compressed, raw : bool
        Some level is compressed / stored raw.
    colors : frozenset of str
        Colour formats of the compressed levels (``golden.format.COLORS`` names).
    index_widths : tuple of int
        Index widths ``b`` of the compressed levels, ascending.
    straddle : bool
        Some index crosses a word boundary of the index memory.
    sublevels : bool
        Some level reads a sub-level (> 0) of an extended codeword.
    constants : dict
        Descriptor field -> its value in every row that reads it (:data:`READ_BY`).
    level_bits, texture_bits : int
        Bits of the level and texture numbers the descriptor table decodes.
    layouts : frozenset of int
        Layout codes of the compressed levels (``golden.format.LAYOUT_CODES``): 0 the paper's
        row-major maps, 1 PowerVR2's twiddled ones.
    """
    specialised: bool
    compressed: bool
    raw: bool
    colors: frozenset
    index_widths: tuple
    straddle: bool
    sublevels: bool
    constants: dict = field(default_factory=dict, compare=True)
    level_bits: int = log2(MAX_LEVELS)
    texture_bits: int = 1
    layouts: frozenset = frozenset({0})

    # -- construction ---------------------------------------------------------------------------
    @classmethod
    def of(cls, ts: TextureSet) -> "Features":
        """What ``ts`` needs: the specialised unit."""
        d = ts.descriptors
        valid = d["valid"] != 0
        comp = valid & (d["compressed"] != 0)
        yuv = comp & ((d["color"] == COLOR_CODES["yuv411"]) | (d["color"] == COLOR_CODES["yuv422"]))
        twiddled = comp & (d["layout"] == _TWIDDLED)
        rows = {"all": valid, "compressed": comp, "yuv": yuv, "twiddled": twiddled}
        constants = {}
        for name, who in READ_BY.items():
            values = np.unique(d[name][rows[who]])
            if len(values) <= 1:            # one value, or no row reads it (then any value: 0)
                constants[name] = int(values[0]) if len(values) else 0
        levels = max(t.levels for t in ts.textures)
        return cls(
            specialised=True,
            compressed=bool(comp.any()),
            raw=bool((valid & ~comp).any()),
            colors=frozenset(COLORS[c] for c in np.unique(d["color"][comp]).tolist()),
            index_widths=tuple(int(b) for b in np.unique(d["index_bits"][comp])),
            straddle=_straddles(ts),
            sublevels=bool((d["sublevel"][comp] > 0).any()),
            constants=constants,
            level_bits=ceil_log2(levels),
            texture_bits=ceil_log2(ts.n_textures),
            layouts=frozenset(int(v) for v in np.unique(d["layout"][comp])),
        )

    @classmethod
    def full(cls, ts: TextureSet | None = None, *, pvr2: bool | None = None) -> "Features":
        """Every path and every descriptor field: the unspecialised unit (``ts`` sets the texture
        bits the descriptor table decodes, and whether it is the PowerVR2 unit: every layout and
        colour format, :func:`pvr2_set`; ``pvr2`` says so without a set; default the paper's unit)."""
        if pvr2 is None:
            pvr2 = ts is not None and pvr2_set(ts)
        return cls(specialised=False, compressed=True, raw=True,
                   colors=frozenset(COLORS if pvr2 else PAPER_COLORS),
                   index_widths=ALL_WIDTHS, straddle=True, sublevels=True, constants={},
                   level_bits=log2(MAX_LEVELS), texture_bits=bits_for(ts.n_textures - 1) if ts is not None else 1,
                   layouts=frozenset({0, _TWIDDLED} if pvr2 else {0}))

    @classmethod
    def of_geometry(cls, geometry) -> "Features":
        """What a loadable unit of ``geometry`` (:class:`golden.geometry.Geometry`) builds: every
        path its formats, index widths, layouts and memories can ask for, every descriptor field
        read from the table (none is a constant: the host may load any value)."""
        return cls(specialised=True, compressed=geometry.codebook_entries > 0, raw=geometry.raw_words > 0,
                   colors=frozenset(geometry.colors), index_widths=tuple(geometry.index_widths),
                   straddle=geometry.straddle, sublevels=geometry.extended, constants={},
                   level_bits=log2(MAX_LEVELS), texture_bits=geometry.texture_bits,
                   layouts=frozenset(LAYOUT_CODES[name] for name in geometry.layouts))

    @classmethod
    def for_set(cls, ts: TextureSet, specialise: bool) -> "Features":
        return cls.of(ts) if specialise else cls.full(ts)

    # -- derived ----------------------------------------------------------------------------------
    @property
    def matrix(self) -> bool:
        """The colour matrix is built (some level is yuv411 or yuv422), and the codebook ROM's U and
        V selects."""
        return bool({"yuv411", "yuv422"} & self.colors)

    @property
    def twiddled(self) -> bool:
        """The block address shifter's PowerVR2 twiddle is built (some level has a twiddled map)."""
        return _TWIDDLED in self.layouts

    @property
    def expand16(self) -> frozenset:
        """PowerVR2's 16-bit RGB formats present (the codebook ROM expands their texels)."""
        return self.colors & {"argb1555", "rgb565", "argb4444"}

    @property
    def color_codes(self) -> frozenset:
        """Colour codes of the compressed levels."""
        return frozenset(COLOR_CODES[c] for c in self.colors)

    @property
    def output_codes(self) -> frozenset:
        """Colour codes the colour matrix can receive: the compressed levels' paper formats, yuv411's
        for yuv422 (the codebook ROM sends Y, U, V), rgba for PowerVR2's 16-bit formats (expanded in
        the codebook ROM) and for raw levels."""
        codes = {COLOR_CODES[c] for c in self.colors if c in PAPER_COLORS}
        if "yuv422" in self.colors:
            codes.add(COLOR_CODES["yuv411"])
        if self.raw or self.expand16:
            codes.add(COLOR_CODES["rgba"])
        return frozenset(codes)

    @property
    def index_bits(self) -> int:
        """Width of an index out of the index reader: the widest index present (16 in the full unit)."""
        return max(self.index_widths) if self.index_widths else 1

    @property
    def index_unit(self) -> int:
        """Every index starts at a multiple of this many bits of its word (the greatest power of two
        dividing every width; 1 in the full unit): the extract selects among whole units."""
        g = 0
        for b in self.index_widths:
            g = gcd(g, b)
        return (g & -g) if g else 1

    @property
    def multiplier(self) -> bool:
        """``k * b`` needs a multiplier (more than three index widths); else shifts and adds."""
        return len(self.index_widths) > 3

    @property
    def stored_fields(self) -> tuple:
        """The descriptor table's columns: every field in the full unit; the fields the hardware reads
        that are not constants in the specialised one."""
        if not self.specialised:
            return tuple(DESCRIPTOR_FIELDS)
        return tuple(n for n in DESCRIPTOR_FIELDS if n in READ_BY and n not in self.constants)

    def variable(self, name: str) -> bool:
        """The descriptor field ``name`` differs between rows (it is not a constant)."""
        return name not in self.constants

    def to_dict(self) -> dict:
        """JSON-able summary (for reports)."""
        return {
            "specialised": self.specialised, "compressed": self.compressed, "raw": self.raw,
            "colors": sorted(self.colors, key=COLORS.index), "index_widths": list(self.index_widths),
            "straddle": self.straddle, "sublevels": self.sublevels, "color_matrix": self.matrix,
            "layouts": sorted(self.layouts), "twiddle": self.twiddled,
            "k_times_b": "multiplier" if self.multiplier else "shifts and adds",
            "constant_fields": dict(sorted(self.constants.items())),
            "descriptor_columns": list(self.stored_fields),
        }

    def describe(self) -> str:
        """One line for the command line."""
        if not self.specialised:
            return "full unit (every path, every descriptor field)"
        levels = {(True, True): "compressed+raw", (True, False): "compressed", (False, True): "raw"}
        parts = [levels[self.compressed, self.raw],
                 "/".join(sorted(self.colors, key=COLORS.index)) or "no codebook",
                 "b=" + ",".join(map(str, self.index_widths)) if self.index_widths else "no indices",
                 "straddling" if self.straddle else "no straddles",
                 "sub-levels" if self.sublevels else "no sub-levels",
                 "colour matrix" if self.matrix else "no colour matrix",
                 "twiddled" if self.twiddled else "",
                 f"{len(self.constants)} constant descriptor fields"]
        return "specialised: " + ", ".join(p for p in parts if p)


class Fields:
    """Named values of which some are constants: ``fields.name`` is the field of ``view`` (a
    ``data.View`` of a layout holding the variable fields) or, for a constant, ``C(value, width)``.

    Arguments
    ---------
    view : data.View or None
        The variable fields.
    constants : dict
        Field -> value, for the fields ``view`` does not hold.
    widths : dict
        Field -> width, for the constants.
    """

    def __init__(self, view, constants: dict, widths: dict):
        self._view = view
        self._constants = constants
        self._widths = widths

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        if name in self._constants:
            return C(self._constants[name], self._widths[name])
        return getattr(self._view, name)
