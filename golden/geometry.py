"""Geometry: what a texel-fetch unit can hold and do, apart from what it holds.

A :class:`Geometry` is the shape of a unit: the depths and widths of its memories (index, codebook,
raw), the rows of its descriptor table, the widths of the descriptor fields that follow from them,
and the features it supports (colour formats, index widths, block shapes, index-map layouts,
extended mipmap codewords). *Contents* are one texture set's memory images
(:class:`golden.format.TextureSet`). The hardware is built from a geometry; a texture set reaches it
as ROM initial values (the baked unit) or at run time over the bus port (the loadable unit,
:mod:`golden.register_map`).

- :meth:`Geometry.of` gives the smallest geometry that holds a set (exactly the shapes the baked
  unit has always had: its descriptor widths, memory depths and block-number width);
- :meth:`Geometry.fits` lists what of a set does not fit a geometry, one line per misfit;
- :data:`PRESETS` are named geometries (``paper``, ``dreamcast``, ``max``);
- :meth:`Geometry.load` / :meth:`Geometry.dumps` are the file form, TOML with the field names below.

Field widths (the descriptor table's columns) follow from the depths as they always did:
``base`` addresses the deeper of the index and raw memories, ``cb_base`` the codebook memory,
the plane offsets a byte of an entry, ``color`` is 3 bits and ``layout`` 1 bit when a PowerVR2
format or layout is supported (else 2 and 0).
"""

from __future__ import annotations

import tomllib
from dataclasses import MISSING, asdict, dataclass, fields

import numpy as np

from .constants import (COLOR_CODES, COLORS, LAYOUTS, MAX_LEVELS, PVR2_COLORS, WORD_BITS_ALLOWED)

__all__ = ["Geometry", "GeometryError", "PRESETS", "preset", "geometry_from", "BLOCK_SHAPES", "entry_lanes",
           "index_lanes"]

#: Block shapes (width, height) the format allows: 1, 2, 4 or 8 texels a side.
BLOCK_SHAPES = tuple((1 << a, 1 << b) for a in range(4) for b in range(4))
#: Most rows of a level's index map the hardware addresses (a 4096 x 4096 level of 1 x 1 blocks).
MAX_K_BITS = 24
#: The largest memory a geometry may name (words or entries): 2^24 - 1, so that a descriptor's
#: ``base`` and ``cb_base`` fit the register map's 24-bit fields (golden.register_map).
MAX_DEPTH = (1 << 24) - 1
#: The most 32-bit words a region of the register map may span (golden.register_map): 2^27, so that
#: the 3-bit region code and the offset make a word address of at most 30 bits, a byte address of 32.
MAX_REGION_WORDS = 1 << 27


class GeometryError(ValueError):
    """A geometry is malformed (a bad value in a geometry file, an unknown preset)."""


def _bits_for(n: int) -> int:
    """Bits of an unsigned value up to ``n`` (at least 1): ``amaranth.utils.bits_for`` without
    Amaranth (golden imports numpy only)."""
    return max(1, int(n).bit_length())


def entry_lanes(entry_bytes: int) -> int:
    """Bus words (32 bits) a codebook entry of ``entry_bytes`` spans in the register map: its 32-bit
    words rounded up to a power of two (golden.register_map; hw.codebook_rom's loadable banks)."""
    return 1 << max(0, (-(-int(entry_bytes) // 4) - 1).bit_length())


def index_lanes(word_bits: int) -> int:
    """Bus words an index memory word of ``word_bits`` spans in the register map (2 for 64 bits)."""
    return max(1, int(word_bits) // 32)


def _block_name(shape) -> str:
    return f"{shape[0]}x{shape[1]}"


@dataclass(frozen=True)
class Geometry:
    """The shape of a texel-fetch unit (see the module docstring).

    Members
    -------
    textures : int
        Textures the descriptor table describes (``MAX_LEVELS`` = 16 rows each).
    word_bits : int
        Index memory word width: 16, 32 or 64.
    index_words : int
        Index memory depth in words (the packed index maps and the zero word after the last).
    codebook_entries, entry_bytes : int
        Codebook memory depth (codewords) and width (bytes per entry).
    raw_words : int
        Raw memory depth (32-bit RGBA words; 0: no raw levels).
    k_bits : int
        Width of a block number: log2 of the blocks of the largest compressed level.
    colors : tuple of str
        Colour formats of compressed levels (``golden.format.COLORS`` names).
    index_widths : tuple of int
        Index widths ``b`` (1..16).
    layouts : tuple of str
        Index-map layouts: ``paper`` (row-major), ``pvr2`` (twiddled).
    blocks : tuple of (int, int)
        Block shapes (width, height) of the codebooks.
    extended : bool
        Extended (mipmap) codewords: levels that read a sub-level of a codeword.
    """
    textures: int
    index_words: int
    codebook_entries: int
    entry_bytes: int
    raw_words: int
    k_bits: int
    colors: tuple
    index_widths: tuple
    layouts: tuple = ("paper",)
    blocks: tuple = ((4, 4),)
    extended: bool = True
    word_bits: int = 32

    def __post_init__(self):
        def count(name, lo, hi):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not lo <= v <= hi:
                raise GeometryError(f"geometry {name} must be an integer in {lo}..{hi}, not {v!r}")
            object.__setattr__(self, name, int(v))
        count("textures", 1, 1 << 12)
        count("index_words", 1, MAX_DEPTH)
        count("codebook_entries", 0, MAX_DEPTH)
        count("entry_bytes", 1, 512)
        count("raw_words", 0, MAX_DEPTH)
        count("k_bits", 1, MAX_K_BITS)
        if (isinstance(self.word_bits, bool) or not isinstance(self.word_bits, (int, np.integer))
                or self.word_bits not in WORD_BITS_ALLOWED):
            raise GeometryError(f"geometry word_bits must be one of {WORD_BITS_ALLOWED}, not {self.word_bits!r}")
        object.__setattr__(self, "word_bits", int(self.word_bits))
        colors = tuple(self.colors)
        if not colors or any(c not in COLORS for c in colors):
            raise GeometryError(f"geometry colors must be a non-empty list of {', '.join(COLORS)}; got {list(colors)}")
        object.__setattr__(self, "colors", tuple(sorted(set(colors), key=COLORS.index)))
        widths = tuple(self.index_widths)
        if not widths or any(isinstance(b, bool) or not isinstance(b, (int, np.integer)) or not 1 <= b <= 16
                             for b in widths):
            raise GeometryError(f"geometry index_widths must be a non-empty list of integers in 1..16; got {list(widths)}")
        object.__setattr__(self, "index_widths", tuple(sorted({int(b) for b in widths})))
        layouts = tuple(self.layouts)
        if not layouts or any(v not in LAYOUTS for v in layouts):
            raise GeometryError(f"geometry layouts must be a non-empty list of {', '.join(LAYOUTS)}; got {list(layouts)}")
        object.__setattr__(self, "layouts", tuple(sorted(set(layouts), key=LAYOUTS.index)))
        blocks = []
        for shape in self.blocks:
            if isinstance(shape, str):
                parts = shape.lower().split("x")
                shape = (tuple(int(p) for p in parts)
                         if len(parts) == 2 and all(p.isascii() and p.isdigit() for p in parts) else shape)
            shape = tuple(shape) if not isinstance(shape, str) else shape
            if shape not in BLOCK_SHAPES:
                raise GeometryError(f"geometry block {shape!r} is not WxH with sides 1, 2, 4 or 8")
            blocks.append(shape)
        if not blocks:
            raise GeometryError("geometry blocks must name at least one block shape")
        object.__setattr__(self, "blocks", tuple(sorted(set(blocks))))
        if not isinstance(self.extended, (bool, np.bool_)):
            raise GeometryError(f"geometry extended must be true or false, not {self.extended!r}")
        object.__setattr__(self, "extended", bool(self.extended))
        words = max(self.codebook_entries * entry_lanes(self.entry_bytes),
                    self.index_words * index_lanes(self.word_bits), self.raw_words, self.textures * MAX_LEVELS * 4)
        if words > MAX_REGION_WORDS:
            raise GeometryError(f"geometry too large for the bus: a region of {words} words (at most "
                                f"{MAX_REGION_WORDS}, so that a CPU's byte address fits 32 bits)")

    # -- derived ---------------------------------------------------------------------------------
    @property
    def pvr2(self) -> bool:
        """A PowerVR2 format or layout is supported: a 3-bit ``color`` and a 1-bit ``layout`` field."""
        return "pvr2" in self.layouts or bool(set(self.colors) & set(PVR2_COLORS))

    @property
    def texture_bits(self) -> int:
        """Width of a texture id (at least 1)."""
        return _bits_for(self.textures - 1)

    @property
    def descriptor_rows(self) -> int:
        """Rows of the descriptor table: ``MAX_LEVELS`` per texture."""
        return self.textures * MAX_LEVELS

    def descriptor_widths(self) -> dict:
        """Width of every descriptor field (field name -> bits; see the module docstring)."""
        off = _bits_for(self.entry_bytes)
        return {
            "valid": 1, "compressed": 1,
            "base": _bits_for(max(self.index_words, self.raw_words)),
            "log2w": 4, "log2h": 4, "log2bw": 2, "log2bh": 2, "index_bits": 5,
            "cb_base": _bits_for(self.codebook_entries),
            "sublevel": 2,
            "color": 3 if self.pvr2 else 2,
            "texel_off": off, "u_off": off, "v_off": off,
            "layout": 1 if self.pvr2 else 0,
        }

    @property
    def straddle(self) -> bool:
        """Some supported index width can cross a word boundary (it does not divide the word)."""
        return any(self.word_bits % b for b in self.index_widths)

    @property
    def memory_bits(self) -> dict:
        """Bits of each memory (what a loadable unit holds in block RAM)."""
        return {"index": self.index_words * self.word_bits, "codebook": self.codebook_entries * self.entry_bytes * 8,
                "raw": self.raw_words * 32, "descriptors": self.descriptor_rows * 128}

    # -- construction ------------------------------------------------------------------------------
    @classmethod
    def of(cls, ts) -> "Geometry":
        """The smallest geometry that holds texture set ``ts``: its memories' depths and widths, its
        largest compressed level's block count, and the features its levels use."""
        d = ts.descriptors
        valid = d["valid"] != 0
        comp = valid & (d["compressed"] != 0)
        span = (d["log2w"].astype(np.int64) - d["log2bw"] + d["log2h"] - d["log2bh"])[comp]
        colors = [COLORS[c] for c in np.unique(d["color"][comp]).tolist()]
        # a set without compressed levels still names a format (its codebook memory is empty)
        colors = colors or [ts.textures[0].color if ts.textures[0].color in COLORS else "rgba"]
        pvr2 = bool((d["layout"][valid] != 0).any() or (d["color"][valid] >= COLOR_CODES["argb1555"]).any())
        layouts = [LAYOUTS[v] for v in np.unique(d["layout"][comp]).tolist()] or ["paper"]
        if pvr2 and "pvr2" not in layouts:      # the widths of a PowerVR2 set (hw.features.pvr2_set)
            layouts.append("pvr2")
        blocks = sorted({tuple(int(v) for v in cb.block) for cb in ts.codebooks}) or [(4, 4)]
        return cls(
            textures=ts.n_textures, word_bits=int(ts.word_bits),
            index_words=max(1, len(ts.index_words)), codebook_entries=len(ts.codebook),
            entry_bytes=max(1, ts.entry_bytes), raw_words=len(ts.raw_words),
            k_bits=max(1, int(span.max())) if comp.any() else 1,
            colors=tuple(colors), index_widths=tuple(np.unique(d["index_bits"][comp]).tolist()) or (8,),
            layouts=tuple(layouts), blocks=tuple(blocks),
            extended=bool((d["sublevel"][comp] > 0).any()))

    def fits(self, ts) -> list:
        """What of ``ts`` does not fit this geometry: one line per misfit (empty: it fits)."""
        need = Geometry.of(ts)
        out = []
        if need.textures > self.textures:
            out.append(f"{need.textures} textures, the descriptor table holds {self.textures}")
        if need.word_bits != self.word_bits:
            out.append(f"index words of {need.word_bits} bits, the unit's are {self.word_bits}")
        for what, unit, have, cap in (("index memory", "words", len(ts.index_words), self.index_words),
                                      ("codebook memory", "entries", len(ts.codebook), self.codebook_entries),
                                      ("raw memory", "words", len(ts.raw_words), self.raw_words)):
            if have > cap:
                out.append(f"{what}: {have} {unit}, the unit holds {cap}")
        if len(ts.codebook) and ts.entry_bytes > self.entry_bytes:
            out.append(f"codebook entries of {ts.entry_bytes} bytes, the unit's are {self.entry_bytes}")
        if need.k_bits > self.k_bits:
            out.append(f"a level of 2^{need.k_bits} blocks, the unit addresses 2^{self.k_bits}")
        if len(ts.codebook):
            for name, have, cap in (("colour format", need.colors, self.colors),
                                    ("index width", need.index_widths, self.index_widths),
                                    ("layout", need.layouts, self.layouts)):
                extra = [str(v) for v in have if v not in cap]
                if extra:
                    out.append(f"{name} {', '.join(extra)} not supported (the unit has {', '.join(map(str, cap))})")
            extra = [_block_name(b) for b in need.blocks if b not in self.blocks]
            if extra:
                out.append(f"block {', '.join(extra)} not supported (the unit has "
                           f"{', '.join(_block_name(b) for b in self.blocks)})")
            if need.extended and not self.extended:
                out.append("extended (mipmap) codewords not supported")
        elif need.pvr2 and not self.pvr2:
            out.append("PowerVR2 descriptors (a 3-bit colour field) not supported")
        return out

    def union(self, other: "Geometry") -> "Geometry":
        """The smallest geometry that holds what either holds (same word width required)."""
        if other.word_bits != self.word_bits:
            raise GeometryError(f"index words of {self.word_bits} and {other.word_bits} bits cannot share a unit")
        return Geometry(
            textures=max(self.textures, other.textures), word_bits=self.word_bits,
            index_words=max(self.index_words, other.index_words),
            codebook_entries=max(self.codebook_entries, other.codebook_entries),
            entry_bytes=max(self.entry_bytes, other.entry_bytes), raw_words=max(self.raw_words, other.raw_words),
            k_bits=max(self.k_bits, other.k_bits), colors=self.colors + other.colors,
            index_widths=self.index_widths + other.index_widths, layouts=self.layouts + other.layouts,
            blocks=self.blocks + other.blocks, extended=self.extended or other.extended)

    # -- file form ---------------------------------------------------------------------------------
    def to_dict(self) -> dict:
        d = asdict(self)
        d["colors"], d["index_widths"], d["layouts"] = list(self.colors), list(self.index_widths), list(self.layouts)
        d["blocks"] = [_block_name(b) for b in self.blocks]
        return d

    def dumps(self) -> str:
        """The TOML file form (what :meth:`loads` reads)."""
        lines = ["# vqtex unit geometry (docs/hardware.md, 'Geometry')"]
        for name, v in self.to_dict().items():
            if isinstance(v, bool):
                lines.append(f"{name} = {'true' if v else 'false'}")
            elif isinstance(v, list):
                lines.append(f"{name} = [{', '.join(repr(x) if isinstance(x, str) else str(x) for x in v)}]".replace("'", '"'))
            else:
                lines.append(f"{name} = {v}")
        return "\n".join(lines) + "\n"

    @classmethod
    def loads(cls, text: str, where: str = "<geometry>") -> "Geometry":
        """A geometry from its TOML form; unknown or missing keys and bad values raise
        :class:`GeometryError` naming the file and the key."""
        try:
            doc = tomllib.loads(text)
        except tomllib.TOMLDecodeError as e:
            raise GeometryError(f"{where}: not TOML ({e})") from None
        names = [f.name for f in fields(cls)]
        unknown = sorted(set(doc) - set(names))
        if unknown:
            raise GeometryError(f"{where}: unknown key {unknown[0]!r} (keys: {', '.join(names)})")
        required = [f.name for f in fields(cls) if f.default is MISSING]
        missing = [n for n in required if n not in doc]
        if missing:
            raise GeometryError(f"{where}: missing key {missing[0]!r}")
        for key in ("colors", "index_widths", "layouts", "blocks"):
            if key in doc and not isinstance(doc[key], list):
                raise GeometryError(f"{where}: {key} must be a list")
        try:
            return cls(**doc)
        except GeometryError as e:
            raise GeometryError(f"{where}: {e}") from None
        except (TypeError, ValueError) as e:
            raise GeometryError(f"{where}: {e}") from None

    @classmethod
    def load(cls, path) -> "Geometry":
        try:
            with open(path, "rb") as f:
                data = f.read((1 << 16) + 1)
        except (OSError, ValueError) as e:          # ValueError: a NUL byte in the path
            raise GeometryError(f"{path!s}: {getattr(e, 'strerror', None) or e}") from None
        if len(data) > 1 << 16:
            raise GeometryError(f"{path}: larger than 64 KiB, not a geometry file")
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError:
            raise GeometryError(f"{path}: not UTF-8 text") from None
        return cls.loads(text, str(path))

    def describe(self) -> str:
        """One line for the command line."""
        kib = sum(self.memory_bits.values()) / 8192
        return (f"{self.textures} textures, index {self.index_words} x {self.word_bits} b, codebook "
                f"{self.codebook_entries} x {self.entry_bytes} B, raw {self.raw_words} words ({kib:.0f} KiB); "
                f"{'/'.join(self.colors)}; b={','.join(map(str, self.index_widths))}; "
                f"{'/'.join(self.layouts)}; blocks {','.join(_block_name(b) for b in self.blocks)}"
                f"{'; extended codewords' if self.extended else ''}")


def _entry_bytes(colors, blocks, extended: bool) -> int:
    """The widest codebook entry of these formats and block shapes (golden.format.entry_layout)."""
    from .format import entry_layout, sub_levels
    return max(entry_layout(c, bw, bh, sub_levels(bw, bh) if extended else 1).size
               for c in colors for bw, bh in blocks)


def _preset(textures, index_words, codebook_entries, raw_words, k_bits, colors, index_widths, layouts, blocks,
            extended=True) -> Geometry:
    return Geometry(textures=textures, index_words=index_words, codebook_entries=codebook_entries,
                    entry_bytes=_entry_bytes(colors, blocks, extended), raw_words=raw_words, k_bits=k_bits,
                    colors=colors, index_widths=index_widths, layouts=layouts, blocks=blocks, extended=extended)


_PAPER = ("rgb", "rgba", "intensity", "yuv411")
#: Named geometries (``--geometry NAME``), each sized to fit the block RAM of a Lattice ECP5-85
#: (208 DP16KD, 3.7 Mbit) beside the pipeline:
#:
#: - ``paper``: the paper's scenes as vqtex builds them (topspin: 3 textures, 4,257 index words, 768
#:   codewords, 1,365 raw words; town: 22 textures, 7,409 index words, 2,048 codewords, 8,528 raw
#:   words): 32 textures (512 descriptor rows), 8 Ki index words, 2 Ki codewords, 16 Ki raw words, the
#:   paper's four formats, 8- and 12-bit indices, 2x2 and 4x4 blocks, extended codewords;
#: - ``dreamcast``: the paper's unit grown into a PowerVR2 texture unit: every PowerVR2 format and
#:   the twiddled layout as well (pvrtex's .dt files), 16 Ki index words (a 1024 x 1024 texture's
#:   8-bit index map is 64 Ki words; a Dreamcast's 8 MB of video memory does not fit on chip);
#: - ``max``: everything the format allows (every format, index width 1..16, both layouts, every
#:   block shape up to 8 x 8, extended codewords) at memories that still fit: 64 textures, 32 Ki
#:   index words, 512 codewords of up to 336 bytes, 16 Ki raw words.
#:
#: The paper-sized scenes (topspin-paper, town-paper: up to 50,881 index words and 34,457 raw words)
#: need more block RAM than an ECP5-85 has; ``Geometry.of`` of their sets (or a geometry file) makes
#: a simulation-only unit for them.
PRESETS = {
    "paper": _preset(32, 1 << 13, 1 << 11, 1 << 14, 14, _PAPER, (8, 12), ("paper",), ((2, 2), (4, 4))),
    "dreamcast": _preset(32, 1 << 14, 1 << 11, 1 << 14, 18, _PAPER + PVR2_COLORS, (8, 12), ("paper", "pvr2"),
                         ((2, 2), (4, 4))),
    "max": _preset(64, 1 << 15, 1 << 9, 1 << 14, 20, COLORS, tuple(range(1, 17)), LAYOUTS, BLOCK_SHAPES),
}


def preset(name: str) -> Geometry:
    """The named geometry (:data:`PRESETS`)."""
    try:
        return PRESETS[name]
    except KeyError:
        raise GeometryError(f"unknown geometry {name!r} (presets: {', '.join(PRESETS)}; or a .toml file)") from None


def geometry_from(name_or_path: str) -> Geometry:
    """A preset by name, or a geometry file (any name that is not a preset)."""
    if name_or_path in PRESETS:
        return PRESETS[name_or_path]
    if not str(name_or_path).endswith(".toml"):
        preset(name_or_path)                # the one-line error naming the presets
    return Geometry.load(name_or_path)
