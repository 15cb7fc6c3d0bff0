"""The loadable unit's register map, and the bus writes that load a texture set (the host's side).

A loadable texel-fetch unit (``hw.texel_fetch.TexelFetch(geometry, loadable=True)``) has a
Wishbone B4 pipelined slave port (``hw.bus_port``): 32-bit data, *word* addresses on ``adr`` (a
CPU's byte address is ``4 * adr``). The address is a 3-bit region and a word offset inside it::

    adr = region << offset_bits | offset

=========  ====  ============================================================================
region     code  contents (one 32-bit bus word at each offset)
=========  ====  ============================================================================
control    0     ID, version, the geometry (read only); the colour matrix (read/write)
descriptors 1    four words per descriptor row, row ``texture * 16 + level`` (:data:`DESCRIPTOR_WORDS`)
index      2     index memory word ``w`` (``word_bits`` 64: two bus words, low half first)
codebook   3     codebook entry ``e``: ``entry_lanes`` words from ``e * entry_lanes``, bytes
                 ``4l .. 4l+3`` of the entry in word ``l`` (little-endian)
raw        4     raw memory word ``w`` (RGBA8888, R in bits 0..7)
=========  ====  ============================================================================

An address outside what the geometry holds (a region 5-7, an offset past a memory's depth, a lane
past an entry's bytes, a control word that does not exist) and a write to a read-only register get
Wishbone's error response (``err`` instead of ``ack``). Bits of a word beyond a field's width are
dropped on write and read back as 0.

The loadable cached unit (``hw.memory.unit.CachedTexelFetch(geometry=..., loadable=True)``: the
index and raw memories in external memory behind caches) has the map ``RegisterMap(geometry,
external=True)``: the index and raw regions hold no words (every access is an error: the host
writes those memories into external memory, ``golden.memory.system.Layout.image``) and the control
region has two more registers, :data:`BASE_REGISTERS` (``INDEX_BASE``, ``RAW_BASE``: where they are).

:func:`load_writes` is what a CPU driver does to load a set: one write per descriptor word of every
row of the geometry (rows the set does not use are written 0, not valid, so nothing of a previous
set stays visible), then the index, codebook and raw memories and the colour matrix. :func:`markdown`
and :func:`c_header` publish the map the way SoC generators publish CSR maps.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .constants import DESCRIPTOR_FIELDS, MAX_LEVELS
from .geometry import Geometry, entry_lanes, index_lanes

__all__ = ["RegisterMap", "REGIONS", "DESCRIPTOR_WORDS", "CONTROL", "BASE_REGISTERS", "base_words", "ID_VALUE", "VERSION", "load_writes",
           "descriptor_words", "memory_words", "markdown", "c_header", "LoadError", "load_cycles", "expected_reads",
           "mapped", "mapped_words"]

#: Region name -> code (the top three bits of a word address).
REGIONS = {"control": 0, "descriptors": 1, "index": 2, "codebook": 3, "raw": 4}
#: Bits of the region code.
REGION_BITS = 3
#: The value of the ID register: "VQTX".
ID_VALUE = 0x56515458
#: Register map version (the VERSION register).
VERSION = 1

#: The descriptor row as four bus words: word -> [(field, lsb, width or None for the geometry's)].
#: Widths are the format's (4-bit log2 sizes, 5-bit index width, ...); ``base``, ``cb_base`` and the
#: plane offsets are as wide as the geometry makes them (``Geometry.descriptor_widths``), at most 24
#: and 10 bits.
DESCRIPTOR_WORDS = (
    (("valid", 0, 1), ("compressed", 1, 1), ("layout", 2, 1), ("sublevel", 4, 2), ("color", 8, 3),
     ("index_bits", 12, 5), ("log2w", 20, 4), ("log2h", 24, 4), ("log2bw", 28, 2), ("log2bh", 30, 2)),
    (("base", 0, 24),),
    (("cb_base", 0, 24),),
    (("texel_off", 0, 10), ("u_off", 10, 10), ("v_off", 20, 10)),
)
assert {f for word in DESCRIPTOR_WORDS for f, _, _ in word} == set(DESCRIPTOR_FIELDS)

#: The control region: register -> (offset, access, description). Matrix coefficients are 18-bit
#: two's complement (sign-extended when read), offsets 8 bits, frac_bits 0..16, rounding 1 bit.
CONTROL = {
    "ID": (0x00, "r", "0x56515458, 'VQTX'"),
    "VERSION": (0x01, "r", "register map version"),
    "TEXTURES": (0x02, "r", "geometry: textures (16 descriptor rows each)"),
    "INDEX_WORDS": (0x03, "r", "geometry: index memory words"),
    "WORD_BITS": (0x04, "r", "geometry: bits of an index memory word"),
    "CODEBOOK_ENTRIES": (0x05, "r", "geometry: codebook entries"),
    "ENTRY_BYTES": (0x06, "r", "geometry: bytes of a codebook entry"),
    "RAW_WORDS": (0x07, "r", "geometry: raw memory words"),
    **{f"MATRIX_{'RGB'[c]}{'YUV'[k]}": (0x10 + 3 * c + k, "rw", f"colour matrix M[{c}][{k}], 18-bit signed")
       for c in range(3) for k in range(3)},
    **{f"MATRIX_OFFSET_{'YUV'[k]}": (0x19 + k, "rw", f"colour matrix input offset {k}, 0..255") for k in range(3)},
    "MATRIX_FRAC_BITS": (0x1C, "rw", "colour matrix fractional bits F, 0..16 (5 bits)"),
    "MATRIX_ROUNDING": (0x1D, "rw", "1: bias 2^(F-1), round to nearest; 0: floor"),
}
#: The loadable cached unit's extra control registers (``RegisterMap(g, external=True)``): where the
#: host put the set in external memory (byte addresses, :class:`golden.memory.system.Layout`). The
#: index base keeps bits ``log2(word_bits / 8)`` and up, the raw base bits 2 and up (the low bits
#: read back as 0). A write to either (any accepted write) empties the unit's caches.
BASE_REGISTERS = {
    "INDEX_BASE": (0x1E, "rw", "external memory: byte address of index word 0 (a multiple of the word's bytes)"),
    "RAW_BASE": (0x1F, "rw", "external memory: byte address of raw word 0 (a multiple of 4)"),
}
#: Control-region words: the first one past the last register.
CONTROL_WORDS = 0x20
#: Width of a matrix coefficient register.
COEFF_BITS = 18


class LoadError(ValueError):
    """A texture set does not fit the geometry it is to be loaded into."""


@dataclass(frozen=True)
class RegisterMap:
    """The address map of a geometry's loadable unit.

    Members
    -------
    geometry : Geometry
    external : bool
        The loadable cached unit's map (:class:`hw.memory.unit.CachedTexelFetch`): the index and raw
        memories are in external memory (the host writes them there, ``Layout.image``), so their
        regions hold no words (every access is an error), and the control region has the base
        registers :data:`BASE_REGISTERS`.
    """
    geometry: Geometry
    external: bool = False

    @property
    def control(self) -> dict:
        """The control registers of this map: :data:`CONTROL`, and :data:`BASE_REGISTERS` when external."""
        return {**CONTROL, **BASE_REGISTERS} if self.external else CONTROL

    def base_bits(self) -> dict:
        """Base register -> its lowest stored bit (external maps only)."""
        return {"INDEX_BASE": (self.geometry.word_bits // 8).bit_length() - 1, "RAW_BASE": 2}

    @property
    def index_lanes(self) -> int:
        """Bus words per index memory word (2 for 64-bit words, else 1)."""
        return index_lanes(self.geometry.word_bits)

    @property
    def entry_lanes(self) -> int:
        """Bus words per codebook entry: ``ceil(entry_bytes / 4)`` rounded up to a power of two."""
        return entry_lanes(self.geometry.entry_bytes)

    @property
    def used_entry_lanes(self) -> int:
        """The lanes of an entry that hold bytes (the rest answer with an error)."""
        return -(-self.geometry.entry_bytes // 4)

    def region_words(self) -> dict:
        """Region -> the words it spans (its offsets that answer)."""
        g = self.geometry
        ext = not self.external
        return {"control": CONTROL_WORDS, "descriptors": g.descriptor_rows * len(DESCRIPTOR_WORDS),
                "index": g.index_words * self.index_lanes * ext, "codebook": g.codebook_entries * self.entry_lanes,
                "raw": g.raw_words * ext}

    @property
    def offset_bits(self) -> int:
        """Bits of the offset inside a region (enough for the largest)."""
        return max(1, max(int(n - 1).bit_length() for n in self.region_words().values()))

    @property
    def addr_bits(self) -> int:
        """Width of the Wishbone ``adr`` (word address)."""
        return REGION_BITS + self.offset_bits

    def address(self, region: str, offset) -> np.ndarray:
        """Word addresses of ``offset`` (array) in ``region``."""
        return (np.uint64(REGIONS[region]) << np.uint64(self.offset_bits)) | np.asarray(offset, np.uint64)

    def field_widths(self) -> dict:
        """Descriptor field -> the bits the unit stores (the geometry's widths, capped by the register's)."""
        widths = self.geometry.descriptor_widths()
        return {name: min(width, widths[name]) for word in DESCRIPTOR_WORDS for name, _, width in word}


def descriptor_words(ts, rmap: RegisterMap) -> np.ndarray:
    """(geometry rows, 4) uint32: every descriptor row of the geometry as its four bus words (rows
    past the set's textures are zero: not valid). Fields are masked to the unit's widths."""
    g = rmap.geometry
    out = np.zeros((g.descriptor_rows, len(DESCRIPTOR_WORDS)), np.uint64)
    rows = ts.descriptors.reshape(-1)
    widths = rmap.field_widths()
    for w, word in enumerate(DESCRIPTOR_WORDS):
        acc = np.zeros(len(rows), np.uint64)
        for name, lsb, _ in word:
            mask = np.uint64((1 << widths[name]) - 1)
            acc |= (rows[name].astype(np.uint64) & mask) << np.uint64(lsb)
        out[:len(rows), w] = acc
    return out.astype(np.uint32)


def memory_words(ts, rmap: RegisterMap) -> dict:
    """Region -> (offsets, data) uint32 arrays: the index, codebook and raw memories of ``ts`` as bus
    words (the codebook's unused lanes and bytes are not written)."""
    out = {}
    words = np.asarray(ts.index_words)
    if rmap.geometry.word_bits == 64:
        w64 = words.astype(np.uint64)
        data = np.stack([w64 & np.uint64(0xFFFFFFFF), w64 >> np.uint64(32)], axis=1).reshape(-1)
    else:
        data = words.astype(np.uint64)
    out["index"] = (np.arange(len(data), dtype=np.uint64), data.astype(np.uint32))
    cb = np.asarray(ts.codebook, np.uint8)
    lanes, used = rmap.entry_lanes, -(-cb.shape[1] // 4) if cb.size else 0
    if cb.size:
        padded = np.zeros((cb.shape[0], used * 4), np.uint8)
        padded[:, :cb.shape[1]] = cb
        data = padded.view("<u4").reshape(cb.shape[0], used)
        offsets = (np.arange(cb.shape[0], dtype=np.uint64)[:, None] * np.uint64(lanes)
                   + np.arange(used, dtype=np.uint64)[None, :])
        out["codebook"] = (offsets.reshape(-1), data.reshape(-1).astype(np.uint32))
    else:
        out["codebook"] = (np.zeros(0, np.uint64), np.zeros(0, np.uint32))
    raw = np.asarray(ts.raw_words, np.uint32)
    out["raw"] = (np.arange(len(raw), dtype=np.uint64), raw)
    return out


def matrix_words(matrix) -> dict:
    """Control register -> value for the colour matrix ``matrix`` (golden.color.ColorMatrix)."""
    regs = {}
    for c in range(3):
        for k in range(3):
            # two's complement in 32 bits: the unit keeps 18 and reads them back sign-extended
            regs[f"MATRIX_{'RGB'[c]}{'YUV'[k]}"] = int(matrix.coeffs[c][k]) & 0xFFFFFFFF
    for k in range(3):
        regs[f"MATRIX_OFFSET_{'YUV'[k]}"] = int(matrix.offsets[k])
    regs["MATRIX_FRAC_BITS"] = int(matrix.frac_bits)
    regs["MATRIX_ROUNDING"] = int(matrix.rounding)
    return regs


def geometry_words(g: Geometry) -> dict:
    """The read-only control registers' values."""
    return {"ID": ID_VALUE, "VERSION": VERSION, "TEXTURES": g.textures, "INDEX_WORDS": g.index_words,
            "WORD_BITS": g.word_bits, "CODEBOOK_ENTRIES": g.codebook_entries, "ENTRY_BYTES": g.entry_bytes,
            "RAW_WORDS": g.raw_words}


def base_words(layout) -> dict:
    """Base register -> value for a set placed by ``layout`` (:class:`golden.memory.system.Layout`)."""
    return {"INDEX_BASE": int(layout.index_base), "RAW_BASE": int(layout.raw_base)}


def load_writes(ts, geometry: Geometry, layout=None) -> np.ndarray:
    """The bus writes that load ``ts`` into a unit of ``geometry``: an (N, 2) uint32 array of (word
    address, data), in the order a driver issues them: the colour matrix, every descriptor row of the
    geometry, then the index, codebook and raw memories.

    With ``layout`` (:class:`golden.memory.system.Layout`), the loadable cached unit's load
    (``RegisterMap(geometry, external=True)``): the colour matrix, the base registers (``INDEX_BASE``,
    ``RAW_BASE``: where the host put the set's index and raw memories in external memory, whose bytes
    are ``layout.image(ts)``), every descriptor row, then the codebook; no index or raw words.

    Raises
    ------
    LoadError
        If the set does not fit (the message lists what does not, ``Geometry.fits``).
    """
    misfit = geometry.fits(ts)
    if misfit:
        raise LoadError("the texture set does not fit the unit's geometry: " + "; ".join(misfit))
    rmap = RegisterMap(geometry, external=layout is not None)
    parts = []
    regs = matrix_words(ts.matrix)
    if layout is not None:
        if layout.word_bytes * 8 != geometry.word_bits:
            raise LoadError(f"the layout's {8 * layout.word_bytes}-bit index words are not the unit's "
                            f"{geometry.word_bits}-bit words")
        regs.update(base_words(layout))
    control = rmap.control
    parts.append((rmap.address("control", [control[n][0] for n in regs]),
                  np.array(list(regs.values()), np.uint32)))
    desc = descriptor_words(ts, rmap)
    parts.append((rmap.address("descriptors", np.arange(desc.size, dtype=np.uint64)), desc.reshape(-1)))
    for region, (offsets, data) in memory_words(ts, rmap).items():
        if rmap.region_words()[region]:
            parts.append((rmap.address(region, offsets), data))
    addr = np.concatenate([a.astype(np.uint64) for a, _ in parts])
    data = np.concatenate([d.astype(np.uint32) for _, d in parts])
    return np.stack([addr.astype(np.uint32), data], axis=1)


def expected_reads(ts, geometry: Geometry, addresses, layout=None) -> tuple:
    """What reads of ``addresses`` return from a unit loaded with ``ts`` (:func:`load_writes`, with
    ``layout`` the loadable cached unit's): (data uint32, err bool) per address. Only the words the
    load wrote, the read-only registers and unmapped addresses are known (any other word reads as 0
    here: ask only known ones)."""
    rmap = RegisterMap(geometry, external=layout is not None)
    regs = {**geometry_words(geometry), **matrix_words(ts.matrix)}
    if layout is not None:
        low = rmap.base_bits()
        regs.update({n: v >> low[n] << low[n] for n, v in base_words(layout).items()})
    writes = load_writes(ts, geometry, layout)
    control = rmap.control
    # every known word, once (the load's control writes are those registers' values again, first)
    known_addr = np.concatenate([rmap.address("control", [control[n][0] for n in regs]),
                                 writes[:, 0].astype(np.uint64)])
    known_data = np.concatenate([np.array(list(regs.values()), np.uint64), writes[:, 1].astype(np.uint64)])
    known_addr, first = np.unique(known_addr, return_index=True)
    known_data = known_data[first]
    addrs = np.asarray(addresses, np.uint64).reshape(-1)
    at = np.minimum(np.searchsorted(known_addr, addrs), max(len(known_addr) - 1, 0))
    hit = known_addr[at] == addrs if len(known_addr) else np.zeros(len(addrs), bool)
    data = np.where(hit, known_data[at] if len(known_addr) else 0, 0).astype(np.uint32)
    return data, ~hit & ~mapped_words(rmap, addrs)


def mapped_words(rmap: RegisterMap, addresses, write: bool = False) -> np.ndarray:
    """Whether each word address answers with ``ack`` (else ``err``), for reads or writes (bool array)."""
    a = np.asarray(addresses, np.uint64).reshape(-1)
    region = (a >> np.uint64(rmap.offset_bits)).astype(np.int64)
    offset = (a & np.uint64((1 << rmap.offset_bits) - 1)).astype(np.int64)
    words = rmap.region_words()
    ok = np.zeros(len(a), bool)
    inside = (a >> np.uint64(rmap.addr_bits)) == 0
    for name, code in REGIONS.items():
        here = inside & (region == code) & (offset < words[name])
        if name == "control":
            allowed = [off for off, acc, _ in rmap.control.values() if not write or "w" in acc]
            here &= np.isin(offset, allowed)
        elif name == "codebook":
            here &= offset % rmap.entry_lanes < rmap.used_entry_lanes
        ok |= here
    return ok


def mapped(rmap: RegisterMap, address: int, write: bool = False) -> bool:
    """Whether word ``address`` answers with ``ack`` (else ``err``), for a read or a write."""
    if not 0 <= int(address) < 1 << 64:
        return False
    return bool(mapped_words(rmap, [int(address)], write)[0])


def markdown(geometry: Geometry, external: bool = False) -> str:
    """The register map as a Markdown document (what ``vqtex export --unit loadable`` writes; with
    ``external``, the loadable cached unit's: ``--memory external``)."""
    rmap = RegisterMap(geometry, external)
    ob = rmap.offset_bits
    lines = ["# vqtex loadable unit: register map", "",
             f"Geometry: {geometry.describe()}.", "",
             f"Wishbone B4 pipelined slave, 32-bit data, word addresses of {rmap.addr_bits} bits "
             f"(`adr = region << {ob} | offset`; a CPU's byte address is `4 * adr`). Out-of-range "
             "addresses and writes to read-only registers answer with `err`. Writes and reads wait "
             "(`stall`) until the texel requests in flight have left the pipeline; no request is "
             "accepted while `cyc` is high.", "",
             *(["External memory (the loadable cached unit): the host writes the index and raw memories "
                "into the memory behind the unit's AXI4 read master (`Layout.image`) and their byte "
                "addresses into `INDEX_BASE` and `RAW_BASE`; the index and raw regions hold no words here. "
                "Any accepted write empties the unit's caches.", ""] if external else []),
             "| region | code | word address | words | contents |", "|---|---|---|---|---|"]
    words = rmap.region_words()
    contents = {"control": "registers below",
                "descriptors": f"row `texture * {MAX_LEVELS} + level`, 4 words a row",
                "index": f"index memory words of {geometry.word_bits} bits"
                         + (", two bus words each (low half first)" if rmap.index_lanes == 2 else ""),
                "codebook": f"entry `e`: {rmap.entry_lanes} words from `e * {rmap.entry_lanes}` "
                            f"({rmap.used_entry_lanes} hold bytes, little-endian)",
                "raw": "RGBA8888 words, R in bits 0..7"}
    for name, code in REGIONS.items():
        lines.append(f"| {name} | {code} | 0x{code << ob:08x} | {words[name]} | {contents[name]} |")
    lines += ["", "## Control registers", "", "| register | word offset | access | meaning |", "|---|---|---|---|"]
    for name, (off, acc, what) in rmap.control.items():
        lines.append(f"| {name} | 0x{off:02x} | {acc} | {what} |")
    widths = rmap.field_widths()
    lines += ["", "## Descriptor row (4 words)", "", "| word | field | bits | meaning |", "|---|---|---|---|"]
    for w, word in enumerate(DESCRIPTOR_WORDS):
        for name, lsb, _ in word:
            width = widths[name]
            bits = f"{lsb + width - 1}:{lsb}" if width > 1 else f"{lsb}" if width == 1 else "(not stored)"
            lines.append(f"| {w} | {name} | {bits} | {DESCRIPTOR_FIELDS[name]} |")
    return "\n".join(lines) + "\n"


def c_header(geometry: Geometry, prefix: str = "VQTEX", external: bool = False) -> str:
    """The register map as a C header: byte offsets of the regions (``VQTEX_<REGION>_BASE``) and of
    the control registers (``VQTEX_REG_<NAME>``), descriptor word addresses
    (``VQTEX_DESCRIPTOR(texture, level, word)``) and field shifts and masks (``VQTEX_D_<FIELD>_...``),
    the geometry (``VQTEX_GEOMETRY_...``): what a CPU driver includes. ``external``: the loadable
    cached unit's map (the base registers ``VQTEX_REG_INDEX_BASE``, ``VQTEX_REG_RAW_BASE``)."""
    rmap = RegisterMap(geometry, external)
    ob = rmap.offset_bits
    p = prefix
    lines = ["/* Generated by vqtex (golden/register_map.py): register map of the loadable texel-fetch unit.",
             f" * Geometry: {geometry.describe()}.",
             " * Byte offsets from the unit's base address (word address * 4); 32-bit accesses only. */",
             f"#ifndef {p}_REGS_H", f"#define {p}_REGS_H", "",
             f"#define {p}_ADDR_BITS {rmap.addr_bits}u /* word address bits on the bus */",
             f"#define {p}_OFFSET_BITS {ob}u"]
    for name, code in REGIONS.items():
        lines.append(f"#define {p}_{name.upper()}_BASE 0x{(code << ob) * 4:08x}u")
    for name, words in rmap.region_words().items():
        lines.append(f"#define {p}_{name.upper()}_WORDS {words}u")
    lines.append(f"#define {p}_ENTRY_LANES {rmap.entry_lanes}u /* bus words per codebook entry */")
    lines.append(f"#define {p}_INDEX_LANES {rmap.index_lanes}u /* bus words per index memory word */")
    lines.append("")
    for name, (off, acc, what) in rmap.control.items():
        lines.append(f"#define {p}_REG_{name} ({p}_CONTROL_BASE + 0x{off * 4:03x}u) /* {acc}: {what} */")
    lines.append("")
    lines.append(f"#define {p}_DESCRIPTOR(texture, level, word) ({p}_DESCRIPTORS_BASE + "
                 f"((((texture) * {MAX_LEVELS}u + (level)) * 4u + (word)) * 4u))")
    widths = rmap.field_widths()
    for w, word in enumerate(DESCRIPTOR_WORDS):
        for name, lsb, _ in word:
            lines.append(f"#define {p}_D_{name.upper()}_WORD {w}u")
            lines.append(f"#define {p}_D_{name.upper()}_SHIFT {lsb}u")
            lines.append(f"#define {p}_D_{name.upper()}_MASK 0x{(1 << widths[name]) - 1:x}u")
    g = geometry
    lines += ["", f"#define {p}_GEOMETRY_TEXTURES {g.textures}u", f"#define {p}_GEOMETRY_WORD_BITS {g.word_bits}u",
              f"#define {p}_GEOMETRY_ENTRY_BYTES {g.entry_bytes}u", "", f"#endif /* {p}_REGS_H */"]
    return "\n".join(lines) + "\n"


def load_cycles(n_transfers: int) -> int:
    """Cycles a load of ``n_transfers`` writes takes on an idle unit, as every simulator's Wishbone
    master issues them (one bus cycle, back to back): the first cycle (``cyc`` rises; the unit's
    ``pause`` flip-flop is not yet set, so ``stall`` is high), one cycle per write, the last write's
    ``ack``, and one cycle after ``cyc`` drops for ``pause`` to clear: ``n + 3`` (0 for none)."""
    return int(n_transfers) + 3 if n_transfers else 0
