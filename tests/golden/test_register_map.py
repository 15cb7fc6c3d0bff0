"""golden.register_map: the bus writes that load a texture set (every address mapped, once, in its
region; every descriptor field, index word, codebook byte, raw word and matrix coefficient decodes
back to the set), what answers on the bus (mapped), the Markdown and C header publications (the header
compiled by gcc and its values checked against the map), and the load's cycle count.

The register layout is written out here from the module's documentation, not read from its tables."""

from __future__ import annotations

import dataclasses
import functools
import re
import subprocess

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vqtex.golden.constants import COLORS, LAYOUTS, MAX_LEVELS
from vqtex.golden.geometry import BLOCK_SHAPES, PRESETS, Geometry, GeometryError
from vqtex.golden.register_map import (CONTROL, DESCRIPTOR_WORDS, ID_VALUE, REGIONS, LoadError, RegisterMap,
                                       c_header, expected_reads, load_cycles, load_writes, mapped, markdown)
from tests.support import get_set, need, texture_set


#: Region codes (the top three bits of a word address).
CODES = {"control": 0, "descriptors": 1, "index": 2, "codebook": 3, "raw": 4}
#: Descriptor row as four bus words: (field, word, lsb, register width).
LAYOUT = [("valid", 0, 0, 1), ("compressed", 0, 1, 1), ("layout", 0, 2, 1), ("sublevel", 0, 4, 2),
          ("color", 0, 8, 3), ("index_bits", 0, 12, 5), ("log2w", 0, 20, 4), ("log2h", 0, 24, 4),
          ("log2bw", 0, 28, 2), ("log2bh", 0, 30, 2), ("base", 1, 0, 24), ("cb_base", 2, 0, 24),
          ("texel_off", 3, 0, 10), ("u_off", 3, 10, 10), ("v_off", 3, 20, 10)]
#: Control registers: name -> (word offset, writable).
REGS = {"ID": (0x00, False), "VERSION": (0x01, False), "TEXTURES": (0x02, False), "INDEX_WORDS": (0x03, False),
        "WORD_BITS": (0x04, False), "CODEBOOK_ENTRIES": (0x05, False), "ENTRY_BYTES": (0x06, False),
        "RAW_WORDS": (0x07, False),
        "MATRIX_RY": (0x10, True), "MATRIX_RU": (0x11, True), "MATRIX_RV": (0x12, True),
        "MATRIX_GY": (0x13, True), "MATRIX_GU": (0x14, True), "MATRIX_GV": (0x15, True),
        "MATRIX_BY": (0x16, True), "MATRIX_BU": (0x17, True), "MATRIX_BV": (0x18, True),
        "MATRIX_OFFSET_Y": (0x19, True), "MATRIX_OFFSET_U": (0x1A, True), "MATRIX_OFFSET_V": (0x1B, True),
        "MATRIX_FRAC_BITS": (0x1C, True), "MATRIX_ROUNDING": (0x1D, True)}


def test_tables_as_documented():
    assert REGIONS == CODES
    assert {name: (off, "w" in acc) for name, (off, acc, _) in CONTROL.items()} == REGS
    assert [(f, w, lsb, width) for w, word in enumerate(DESCRIPTOR_WORDS) for f, lsb, width in word] == LAYOUT
    used = [0, 0, 0, 0]
    for _, w, lsb, width in LAYOUT:          # no two fields share a bit, every field inside its word
        bits = ((1 << width) - 1) << lsb
        assert not used[w] & bits and bits < 1 << 32
        used[w] |= bits
    assert ID_VALUE == int.from_bytes(b"VQTX", "big")


# -- the sets and the geometries they are loaded into ---------------------------------------------------


def wide(g):
    """A geometry larger than ``g`` in every depth (rows past the set, unused lanes and words)."""
    return dataclasses.replace(g, textures=g.textures + 3, index_words=2 * g.index_words + 1,
                               codebook_entries=2 * g.codebook_entries + 3, entry_bytes=g.entry_bytes + 5,
                               raw_words=2 * g.raw_words + 7)


def get_geometry(set_name, kind):
    ts = get_set(set_name)
    own = Geometry.of(ts)
    return {"own": own, "wide": wide(own)}.get(kind) or PRESETS[kind]


CASES = [("rgb_4x4_b8_mip", "own"), ("rgb_4x4_b8_mip", "paper"), ("rgb_4x4_b8_mip", "wide"),
         ("rgba_2x2_b7_mip_w16", "own"), ("rgba_2x2_b7_mip_w16", "wide"), ("rgb_2x2_b16_w16", "own"),
         ("i8_4x2_b5_w64", "own"), ("i8_4x2_b5_w64", "wide"), ("yuv_2x4_b12_mip_w64", "own"),
         ("yuv_2x4_b12_mip_w64", "wide"), ("rgba_8x8_b9_mip", "own"), ("rgba_8x8_b9_mip", "max"),
         ("raw_only_8x8_mip", "own"), ("raw_only_8x8_mip", "paper"), ("yuv_dreamcast_4x4_b12_mip", "own"),
         ("yuv_dreamcast_4x4_b12_mip", "dreamcast"), ("combined", "own"), ("combined", "max"),
         ("pvr2:rectangles_and_mip8", "own"), ("pvr2:rectangles_and_mip8", "dreamcast"),
         ("pvr2:crate_argb4444_c_64_m", "dreamcast"), ("scene:topspin", "paper")]
IDS = [f"{s}@{k}" for s, k in CASES]


@functools.lru_cache(maxsize=None)
def loaded(set_name, kind):
    """(ts, geometry, register map, writes, {region: (offsets, data)} in write order)."""
    ts, g = get_set(set_name), get_geometry(set_name, kind)
    w = load_writes(ts, g)
    rmap = RegisterMap(g)
    addr = w[:, 0].astype(np.int64)
    region = addr >> rmap.offset_bits
    offset = addr & ((1 << rmap.offset_bits) - 1)
    parts = {name: (offset[region == code], w[region == code, 1]) for name, code in CODES.items()}
    return ts, g, rmap, w, region, parts


def _lanes(entry_bytes):
    words = -(-entry_bytes // 4)
    return 1 << (words - 1).bit_length(), words


@pytest.mark.parametrize("set_name,kind", CASES, ids=IDS)
def test_load_addresses(set_name, kind):
    ts, g, rmap, w, region, parts = loaded(set_name, kind)
    assert w.dtype == np.uint32 and w.ndim == 2 and w.shape[1] == 2
    addr = w[:, 0].tolist()
    assert len(set(addr)) == len(addr), "an address written twice"
    assert all(mapped(rmap, a, write=True) for a in addr)
    assert all(a < 1 << rmap.addr_bits for a in addr)
    assert np.all(np.diff(region) >= 0), "not in region order control, descriptors, index, codebook, raw"
    lanes, used = _lanes(ts.entry_bytes)
    counts = {"control": 14, "descriptors": g.textures * MAX_LEVELS * 4,
              "index": len(ts.index_words) * (2 if g.word_bits == 64 else 1),
              "codebook": len(ts.codebook) * used, "raw": len(ts.raw_words)}
    assert {name: len(parts[name][0]) for name in CODES} == counts
    assert len(w) == sum(counts.values())
    # offset_bits: every region fits, and no fewer bits would do
    sizes = {"control": 32, "descriptors": g.textures * 64, "index": g.index_words * (2 if g.word_bits == 64 else 1),
             "codebook": g.codebook_entries * _lanes(g.entry_bytes)[0], "raw": g.raw_words}
    assert rmap.region_words() == sizes
    assert all(n <= 1 << rmap.offset_bits for n in sizes.values())
    assert max(sizes.values()) > 1 << (rmap.offset_bits - 1)
    assert rmap.addr_bits == rmap.offset_bits + 3


def _decode(words):
    """(rows, 4) uint32 bus words -> field -> (rows,) int64, with the documented layout."""
    words = words.astype(np.int64)
    return {f: (words[:, w] >> lsb) & ((1 << width) - 1) for f, w, lsb, width in LAYOUT}


@pytest.mark.parametrize("set_name,kind", CASES, ids=IDS)
def test_load_descriptors(set_name, kind):
    ts, g, rmap, w, region, parts = loaded(set_name, kind)
    off, data = parts["descriptors"]
    assert np.array_equal(off, np.arange(g.descriptor_rows * 4))
    fields = _decode(data.reshape(-1, 4))
    rows = ts.descriptors.reshape(-1)
    n = len(rows)
    assert n == ts.n_textures * MAX_LEVELS
    for f, *_ in LAYOUT:
        assert np.array_equal(fields[f][:n], rows[f].astype(np.int64)), f
        assert not fields[f][n:].any(), f"{f}: rows past the set are not 0"
    # the words themselves: nothing outside the fields
    masks = [0, 0, 0, 0]
    for _, word, lsb, width in LAYOUT:
        masks[word] |= ((1 << width) - 1) << lsb
    assert masks == [0xFFF1F737, 0xFFFFFF, 0xFFFFFF, 0x3FFFFFFF]
    assert not (data.reshape(-1, 4) & ~np.array(masks, np.uint32)).any()
    # a valid row is really there (the test is not vacuous)
    assert fields["valid"][:n].sum() == int((ts.descriptors["valid"] != 0).sum()) > 0


@pytest.mark.parametrize("set_name,kind", CASES, ids=IDS)
def test_load_memories(set_name, kind):
    ts, g, rmap, w, region, parts = loaded(set_name, kind)
    # index memory: one bus word per 16/32-bit word, two (low half first) per 64-bit word
    off, data = parts["index"]
    assert np.array_equal(off, np.arange(len(off)))
    words = np.asarray(ts.index_words)
    assert words.dtype.itemsize * 8 == ts.word_bits
    if ts.word_bits == 64:
        pairs = data.astype(np.uint64).reshape(-1, 2)
        back = pairs[:, 0] | (pairs[:, 1] << np.uint64(32))
    else:
        back = data
        assert ts.word_bits == 32 or not (data >> 16).any()
    assert np.array_equal(back.astype(np.uint64), words.astype(np.uint64))
    # codebook: entry e's bytes 4l..4l+3 little-endian in lane l at offset e * lanes + l
    off, data = parts["codebook"]
    lanes, _ = _lanes(g.entry_bytes)
    _, used = _lanes(ts.entry_bytes)
    cb = np.asarray(ts.codebook, np.uint8)
    assert len(off) == cb.shape[0] * used
    e, lane = off // lanes, off % lanes
    assert np.all(lane < used) and np.all(e < max(1, len(cb)))
    got = np.zeros((cb.shape[0], used * 4), np.uint8)
    for b in range(4):
        got[e, 4 * lane + b] = (data >> np.uint32(8 * b)) & np.uint32(0xFF)
    assert np.array_equal(got[:, :cb.shape[1]], cb)
    assert not got[:, cb.shape[1]:].any(), "padding bytes of the last lane are not 0"
    # raw memory
    off, data = parts["raw"]
    assert np.array_equal(off, np.arange(len(ts.raw_words)))
    assert np.array_equal(data, np.asarray(ts.raw_words, np.uint32))


@pytest.mark.parametrize("set_name,kind", CASES, ids=IDS)
def test_load_matrix(set_name, kind):
    ts, g, rmap, w, region, parts = loaded(set_name, kind)
    off, data = parts["control"]
    got = dict(zip(off.tolist(), data.tolist()))
    m = ts.matrix
    expected = {}
    for c in range(3):
        for k in range(3):
            expected[0x10 + 3 * c + k] = m.coeffs[c][k] % (1 << 32)       # two's complement, 32 bits
    for k in range(3):
        expected[0x19 + k] = m.offsets[k]
    expected[0x1C], expected[0x1D] = m.frac_bits, int(bool(m.rounding))
    assert got == expected
    assert [v for v in got.values() if v >= 1 << 31], "no negative coefficient (vacuous sign test)"


def test_matrix_words_exact():
    """The JFIF and Dreamcast matrices as bus words (negative coefficients as 32-bit two's complement)."""
    _, _, _, _, _, parts = loaded("rgb_4x4_b8_mip", "own")
    got = dict(zip(*(a.tolist() for a in parts["control"])))
    assert got[0x10] == 4096 and got[0x12] == 5743 and got[0x14] == 0xFFFFFA7E and got[0x15] == 2**32 - 2925
    assert (got[0x19], got[0x1A], got[0x1B], got[0x1C], got[0x1D]) == (0, 128, 128, 12, 1)
    ts = get_set("yuv_dreamcast_4x4_b12_mip")
    _, _, _, _, _, parts = loaded("yuv_dreamcast_4x4_b12_mip", "own")
    got = dict(zip(*(a.tolist() for a in parts["control"])))
    assert ts.matrix.coeffs != get_set("rgb_4x4_b8_mip").matrix.coeffs
    assert got[0x13] == ts.matrix.coeffs[1][0] % 2**32


def test_load_pvr2_fields_survive():
    """The 3-bit colour and the layout bit reach the bus in a PowerVR2 geometry; a paper geometry keeps
    2 colour bits and no layout bit."""
    _, g, _, _, _, parts = loaded("pvr2:rectangles_and_mip8", "dreamcast")
    f = _decode(parts["descriptors"][1].reshape(-1, 4))
    valid = f["valid"] == 1
    assert set(f["color"][valid].tolist()) == {4, 5, 6, 7} and set(f["layout"][valid].tolist()) == {1}
    assert RegisterMap(PRESETS["paper"]).field_widths()["layout"] == 0
    assert RegisterMap(PRESETS["paper"]).field_widths()["color"] == 2
    assert RegisterMap(PRESETS["dreamcast"]).field_widths()["color"] == 3
    assert RegisterMap(PRESETS["max"]).field_widths() == {
        "valid": 1, "compressed": 1, "layout": 1, "sublevel": 2, "color": 3, "index_bits": 5, "log2w": 4,
        "log2h": 4, "log2bw": 2, "log2bh": 2, "base": 16, "cb_base": 10, "texel_off": 9, "u_off": 9, "v_off": 9}


def test_load_refuses_misfits():
    ts = get_set("scene:topspin")
    with pytest.raises(LoadError, match="codebook memory: 768 entries, the unit holds 512"):
        load_writes(ts, PRESETS["max"])
    pts = get_set("pvr2:crate_argb4444_c_64_m")
    with pytest.raises(LoadError) as e:
        load_writes(pts, PRESETS["paper"])
    assert str(e.value) == ("the texture set does not fit the unit's geometry: colour format argb4444 not "
                            "supported (the unit has rgb, rgba, intensity, yuv411); layout pvr2 not supported "
                            "(the unit has paper)")
    w16 = get_set("rgba_2x2_b7_mip_w16")
    with pytest.raises(LoadError, match="index words of 16 bits, the unit's are 32"):
        load_writes(w16, PRESETS["max"])
    g = Geometry.of(get_set("combined"))
    with pytest.raises(LoadError, match="6 textures, the descriptor table holds 5"):
        load_writes(get_set("combined"), dataclasses.replace(g, textures=5))
    with pytest.raises(LoadError, match="raw memory: 138 words, the unit holds 137"):
        load_writes(get_set("combined"), dataclasses.replace(g, raw_words=137))


def test_load_into_wide_address_geometry():
    ts = get_set("rgb_4x4_b8_mip")
    try:
        # 2^23 entries of 512 bytes (128 lanes): a 2^30-word codebook region, 33-bit word addresses
        g = dataclasses.replace(Geometry.of(ts), codebook_entries=1 << 23, entry_bytes=512)
        rmap = RegisterMap(g)
        w = load_writes(ts, g)
    except (LoadError, GeometryError):
        return                      # refusing the geometry (or the load) is a fix too
    assert rmap.addr_bits == 33
    assert all(mapped(rmap, a, write=True) for a in w[:, 0].tolist())


# -- mapped ------------------------------------------------------------------------------------------

MAP_GEOMETRIES = {"paper": PRESETS["paper"], "dreamcast": PRESETS["dreamcast"], "max": PRESETS["max"],
                  "w64": Geometry.of(texture_set("i8_4x2_b5_w64")),             # no raw memory
                  "raw_only": Geometry.of(texture_set("raw_only_8x8_mip")),       # no codebook memory
                  "w16": Geometry.of(texture_set("rgba_2x2_b7_mip_w16"))}


@pytest.mark.parametrize("gname", list(MAP_GEOMETRIES))
def test_mapped(gname):
    g = MAP_GEOMETRIES[gname]
    rmap = RegisterMap(g)
    ob = rmap.offset_bits

    def at(region, offset):
        assert 0 <= offset < 1 << ob
        return (CODES[region] << ob) | offset

    # control registers: every one reads, the matrix ones write, nothing else answers
    for name, (off, writable) in REGS.items():
        assert mapped(rmap, at("control", off)), name
        assert mapped(rmap, at("control", off), write=True) == writable, name
    for off in set(range(0x20)) - {off for off, _ in REGS.values()}:
        assert not mapped(rmap, at("control", off)) and not mapped(rmap, at("control", off), write=True), off
    assert not mapped(rmap, at("control", 0x20))
    # regions 5-7 and addresses past the bus
    for code in (5, 6, 7):
        for off in (0, 1, (1 << ob) - 1):
            assert not mapped(rmap, (code << ob) | off) and not mapped(rmap, (code << ob) | off, write=True)
    assert not mapped(rmap, 1 << rmap.addr_bits)
    assert not mapped(rmap, (1 << rmap.addr_bits) | at("control", 0))
    # the last offset of each region answers, the next does not
    lanes, used = _lanes(g.entry_bytes)
    last = {"descriptors": g.textures * 64 - 1,
            "index": g.index_words * (2 if g.word_bits == 64 else 1) - 1,
            "codebook": (g.codebook_entries - 1) * lanes + used - 1 if g.codebook_entries else -1,
            "raw": g.raw_words - 1}
    for region, off in last.items():
        if off >= 0:
            for write in (False, True):
                assert mapped(rmap, at(region, off), write=write), (region, off)
                assert mapped(rmap, at(region, 0), write=write), region
        nxt = off + 1 if region != "codebook" else g.codebook_entries * lanes
        if nxt < 1 << ob:
            assert not mapped(rmap, at(region, nxt)) and not mapped(rmap, at(region, nxt), write=True), region
        else:
            assert nxt == 1 << ob                       # the region fills its offsets
    if g.codebook_entries == 0:
        assert not mapped(rmap, at("codebook", 0))
    if g.raw_words == 0:
        assert not mapped(rmap, at("raw", 0))
    # codebook padding lanes: used ones answer, the rest of the power-of-two stride do not
    if g.codebook_entries:
        for e in (0, g.codebook_entries - 1):
            for lane in range(lanes):
                assert mapped(rmap, at("codebook", e * lanes + lane)) == (lane < used), (e, lane)
    # the last codebook entry's padding lane is unmapped in the presets that have padding
    if gname == "paper":
        assert (lanes, used) == (32, 21) and not mapped(rmap, at("codebook", 2047 * 32 + 21))
        assert (ob, rmap.addr_bits) == (16, 19)


_geometries = st.builds(
    Geometry,
    textures=st.integers(1, 300), index_words=st.integers(1, 5000), codebook_entries=st.integers(0, 700),
    entry_bytes=st.integers(1, 512), raw_words=st.integers(0, 5000), k_bits=st.integers(1, 24),
    colors=st.lists(st.sampled_from(COLORS), min_size=1, max_size=3),
    index_widths=st.lists(st.integers(1, 16), min_size=1, max_size=3),
    layouts=st.lists(st.sampled_from(LAYOUTS), min_size=1, max_size=2),
    blocks=st.lists(st.sampled_from(BLOCK_SHAPES), min_size=1, max_size=3), extended=st.booleans(),
    word_bits=st.sampled_from((16, 32, 64)))


@settings(max_examples=80)
@given(_geometries, st.lists(st.integers(0, (1 << 24) - 1), min_size=20, max_size=20), st.booleans())
def test_mapped_property(g, raw_addresses, write):
    """mapped() against the documented map, at random addresses (biased to each region's end)."""
    rmap = RegisterMap(g)
    ob = rmap.offset_bits
    lanes, used = _lanes(g.entry_bytes)
    sizes = {0: 32, 1: g.textures * 64, 2: g.index_words * (2 if g.word_bits == 64 else 1),
             3: g.codebook_entries * lanes, 4: g.raw_words}
    addrs = [a % (1 << (rmap.addr_bits + 1)) for a in raw_addresses]
    addrs += [(code << ob) | min(n + d, (1 << ob) - 1) for code, n in sizes.items() for d in (-1, 0) if n + d >= 0]
    for a in addrs:
        code, off = a >> ob, a & ((1 << ob) - 1)
        if code == 0:
            regs = {o: wr for o, wr in REGS.values()}
            want = off in regs and (regs[off] or not write)
        elif code in (1, 2, 4):
            want = off < sizes[code]
        elif code == 3:
            want = off // lanes < g.codebook_entries and off % lanes < used
        else:
            want = False
        assert mapped(rmap, a, write=write) == want, (a, code, off)


# -- expected reads ----------------------------------------------------------------------------------

def test_expected_reads():
    ts, g, rmap, w, _, _ = loaded("combined", "wide")
    ctl = lambda off: (CODES["control"] << rmap.offset_bits) | off          # noqa: E731
    at = lambda region, off: (CODES[region] << rmap.offset_bits) | off     # noqa: E731
    addrs = [ctl(o) for o in range(8)] + [ctl(0x12), ctl(0x14), ctl(0x08), ctl(0x1E),
                                          at("descriptors", 0), at("descriptors", g.textures * 64 - 1),
                                          at("index", len(ts.index_words) - 1), at("index", len(ts.index_words)),
                                          at("raw", len(ts.raw_words)), at("raw", g.raw_words),
                                          (5 << rmap.offset_bits)]
    data, err = expected_reads(ts, g, addrs)
    assert data.dtype == np.uint32 and err.dtype == bool
    assert data[:8].tolist() == [ID_VALUE, 1, g.textures, g.index_words, g.word_bits, g.codebook_entries,
                                 g.entry_bytes, g.raw_words]
    assert data[8] == 5743 and data[9] == 2**32 - 1410
    assert err.tolist() == [False] * 10 + [True, True] + [False] * 5 + [True, True]
    writes = dict(map(tuple, w.tolist()))
    assert data[12] == writes[at("descriptors", 0)] and data[12] & 1
    assert data[14] == ts.index_words[-1]
    assert data[13] == 0                               # a row past the set: written 0
    assert data[15] == 0 and data[16] == 0             # mapped, not written (the wide geometry's spare words)
    assert len(ts.raw_words) < g.raw_words and len(ts.index_words) < g.index_words


# -- Markdown and C header ---------------------------------------------------------------------------

@pytest.mark.parametrize("gname", ["paper", "dreamcast", "max", "w64"])
def test_markdown(gname):
    g = MAP_GEOMETRIES[gname]
    rmap = RegisterMap(g)
    text = markdown(g)
    ob = rmap.offset_bits
    assert f"word addresses of {rmap.addr_bits} bits" in text and f"`adr = region << {ob} | offset`" in text
    for name, code in CODES.items():
        assert re.search(rf"^\| {name} \| {code} \| 0x{code << ob:08x} \| {rmap.region_words()[name]} \|", text,
                         re.M), name
    for name, (off, writable) in REGS.items():
        assert re.search(rf"^\| {name} \| 0x{off:02x} \| {'rw' if writable else 'r'} \|", text, re.M), name
    widths = g.descriptor_widths()
    for f, w, lsb, width in LAYOUT:
        width = min(width, widths[f])
        bits = f"{lsb + width - 1}:{lsb}" if width > 1 else f"{lsb}" if width == 1 else "(not stored)"
        assert re.search(rf"^\| {w} \| {f} \| {re.escape(bits)} \|", text, re.M), f
    assert sum(line.startswith("| ") for line in text.splitlines()) == 3 + len(CODES) + len(REGS) + len(LAYOUT)


def _defines(header):
    """#define NAME VALUE (no parameters) -> [(name, value text)] in order."""
    return re.findall(r"^#define (\w+)(?:[ \t]+([^/\n]*?))?[ \t]*(?:/\*.*\*/)?$", header, re.M)


def _value(text, known):
    text = text.strip()
    m = re.fullmatch(r"\((\w+) \+ (0x[0-9a-f]+)u\)", text)
    if m:
        return known[m.group(1)] + int(m.group(2), 16)
    m = re.fullmatch(r"(0x[0-9a-f]+|\d+)u", text)
    assert m, text
    return int(m.group(1), 0)


def _expected_macros(g):
    rmap = RegisterMap(g)
    ob = rmap.offset_bits
    out = {"ADDR_BITS": rmap.addr_bits, "OFFSET_BITS": ob,
           "ENTRY_LANES": _lanes(g.entry_bytes)[0], "INDEX_LANES": 2 if g.word_bits == 64 else 1}
    for name, code in CODES.items():
        out[f"{name.upper()}_BASE"] = (code << ob) * 4
    for name, n in rmap.region_words().items():
        out[f"{name.upper()}_WORDS"] = n
    for name, (off, _) in REGS.items():
        out[f"REG_{name}"] = off * 4
    out["GEOMETRY_TEXTURES"], out["GEOMETRY_WORD_BITS"] = g.textures, g.word_bits
    out["GEOMETRY_ENTRY_BYTES"] = g.entry_bytes
    widths = g.descriptor_widths()
    for f, w, lsb, width in LAYOUT:
        out[f"D_{f.upper()}_WORD"], out[f"D_{f.upper()}_SHIFT"] = w, lsb
        out[f"D_{f.upper()}_MASK"] = (1 << min(width, widths[f])) - 1
    return out


C_CASES = [("scene:topspin", "paper"), ("rgb_4x4_b8_mip", "own"), ("yuv_2x4_b12_mip_w64", "wide"),
           ("pvr2:rectangles_and_mip8", "dreamcast"), ("rgba_8x8_b9_mip", "max")]


def _gcc(tmp_path, source, *flags):
    src = tmp_path / "use.c"
    src.write_text(source)
    return subprocess.run(["gcc", "-fsyntax-only", "-std=c11", "-Wall", "-Wextra", *flags, "-x", "c", str(src)],
                          capture_output=True, text=True, timeout=60)


def _use_program(ts, g, rows_words):
    """A C file that includes the header and checks, at compile time, descriptor addresses, the ID
    register and one descriptor row built from the masks against load_writes' words."""
    rmap = RegisterMap(g)
    lines = ['#include <stdint.h>', '#include "vqtex_regs.h"', "",
             "static inline uint32_t rd(uintptr_t base, uint32_t off)",
             "{ return *(volatile uint32_t *)(base + off); }",
             "static inline void wr(uintptr_t base, uint32_t off, uint32_t v)",
             "{ *(volatile uint32_t *)(base + off) = v; }",
             "int probe(uintptr_t base) {",
             "    wr(base, VQTEX_REG_MATRIX_FRAC_BITS, 12u);",
             "    return rd(base, VQTEX_REG_ID) == 0x56515458u",
             "        && rd(base, VQTEX_REG_TEXTURES) == VQTEX_GEOMETRY_TEXTURES;",
             "}",
             "#define FIELD(name, v) (((uint32_t)(v) & VQTEX_D_##name##_MASK) << VQTEX_D_##name##_SHIFT)"]
    t, lev = g.textures - 1, MAX_LEVELS - 1
    for word in range(4):
        addr = ((CODES["descriptors"] << rmap.offset_bits) | ((t * MAX_LEVELS + lev) * 4 + word)) * 4
        lines.append(f"_Static_assert(VQTEX_DESCRIPTOR({t}u, {lev}u, {word}u) == {addr}ull, \"descriptor address\");")
    lines.append("_Static_assert(VQTEX_DESCRIPTOR(0u, 0u, 0u) == VQTEX_DESCRIPTORS_BASE, \"descriptor 0\");")
    lines.append("_Static_assert(VQTEX_REG_ID == VQTEX_CONTROL_BASE && VQTEX_CONTROL_BASE == 0u, \"ID\");")
    # the first valid row of the set, built from the header's masks and shifts
    row = ts.descriptors.reshape(-1)[0]
    for word in range(4):
        parts = [f"FIELD({f.upper()}, {int(row[f])}u)" for f, w, _, _ in LAYOUT if w == word]
        lines.append(f"_Static_assert(({' | '.join(parts)}) == {int(rows_words[0, word])}u, \"row 0 word {word}\");")
    for f, w, _, _ in LAYOUT:
        lines.append(f"_Static_assert(VQTEX_D_{f.upper()}_WORD == {w}u, \"{f} word\");")
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("set_name,kind", C_CASES, ids=[f"{s}@{k}" for s, k in C_CASES])
def test_c_header(set_name, kind, tmp_path):
    need("gcc")
    ts, g, rmap, w, region, parts = loaded(set_name, kind)
    header = c_header(g)
    (tmp_path / "vqtex_regs.h").write_text(header)
    # the defines, parsed: every expected one there with the map's value
    defs = _defines(header)
    names = [n for n, _ in defs]
    assert names[:2] == ["VQTEX_REGS_H", "VQTEX_ADDR_BITS"]
    known = {}
    for name, text in defs[1:]:
        if name.startswith("VQTEX_") and text:
            known[name] = _value(text, known)
    expected = _expected_macros(g)
    for name, value in expected.items():
        assert names.count(f"VQTEX_{name}") == 1, name
        assert known[f"VQTEX_{name}"] == value, (name, known[f"VQTEX_{name}"], value)
    assert "#define VQTEX_DESCRIPTOR(texture, level, word)" in header
    assert known["VQTEX_REG_ID"] == 0 and known["VQTEX_REG_MATRIX_ROUNDING"] == 0x1D * 4
    # every #define once (no macro means two things), and nothing the map does not explain
    assert len(names) == len(set(names)), sorted(n for n in set(names) if names.count(n) > 1)
    assert set(names) == {"VQTEX_REGS_H"} | {f"VQTEX_{n}" for n in expected}
    # gcc: the header alone, and a driver that uses it (values checked by _Static_assert)
    r = _gcc(tmp_path, '#include "vqtex_regs.h"\n#include "vqtex_regs.h"\n', "-Werror")
    assert r.returncode == 0 and not r.stderr, r.stderr
    r = _gcc(tmp_path, _use_program(ts, g, parts["descriptors"][1].reshape(-1, 4)), "-Werror")
    assert r.returncode == 0 and not r.stderr, r.stderr
    # a wrong _Static_assert does fail (the checks above are not vacuous)
    r = _gcc(tmp_path, '#include "vqtex_regs.h"\n_Static_assert(VQTEX_REG_ID == 4u, "x");\n')
    assert r.returncode != 0


# -- load cycles -------------------------------------------------------------------------------------

def test_load_cycles():
    assert load_cycles(0) == 0
    for n in (1, 2, 3, 12, 1000, 123457):
        assert load_cycles(n) == n + 3
    ts, g, _, w, _, _ = loaded("combined", "own")
    assert load_cycles(len(w)) == len(w) + 3 == 14 + g.descriptor_rows * 4 + len(ts.index_words) + \
        len(ts.codebook) * 16 + len(ts.raw_words) + 3


def test_external_map_of_the_loadable_cached_unit():
    """RegisterMap(g, external=True): the base registers at 0x1E and 0x1F (rw), no index or raw words;
    load_writes with a Layout writes the matrix, the bases, every descriptor row and the codebook, and
    nothing else; the publications name the bases only for this map."""
    from vqtex.golden.memory.system import Layout
    ts = texture_set("yuv_4x4_b12_mip")
    g = Geometry.of(ts)
    layout = Layout.at(ts, 0x2000, 0x8000)
    rmap = RegisterMap(g, external=True)
    assert rmap.region_words()["index"] == rmap.region_words()["raw"] == 0
    assert rmap.control["INDEX_BASE"] == (0x1E, "rw", rmap.control["INDEX_BASE"][2])
    assert rmap.control["RAW_BASE"][:2] == (0x1F, "rw") and "INDEX_BASE" not in RegisterMap(g).control
    writes = load_writes(ts, g, layout)
    region = writes[:, 0].astype(np.int64) >> rmap.offset_bits
    assert set(region.tolist()) == {CODES["control"], CODES["descriptors"], CODES["codebook"]}
    control = dict(zip((writes[region == 0, 0] & ((1 << rmap.offset_bits) - 1)).tolist(), writes[region == 0, 1].tolist()))
    assert control[0x1E] == 0x2000 and control[0x1F] == 0x8000 and len(control) == 16
    on_chip = load_writes(ts, g)
    assert len(writes) == len(on_chip) + 2 - len(ts.index_words) - len(ts.raw_words)
    assert mapped(rmap, int(rmap.address("control", 0x1E)), True) and not mapped(RegisterMap(g), int(
        RegisterMap(g).address("control", 0x1E)), False)
    assert not mapped(rmap, int(rmap.address("index", 0))) and not mapped(rmap, int(rmap.address("raw", 0)))
    assert "INDEX_BASE" in markdown(g, external=True) and "INDEX_BASE" not in markdown(g)
    assert "VQTEX_REG_RAW_BASE" in c_header(g, external=True) and "RAW_BASE" not in c_header(g).replace(
        "VQTEX_RAW_BASE", "")
    data, err = expected_reads(ts, g, [int(rmap.address("control", 0x1E))], layout)
    assert data.tolist() == [0x2000] and not err.any()
    with pytest.raises(LoadError, match="16-bit index words"):
        load_writes(ts, g, Layout(0, 0x1000, 2, 0x2000))
