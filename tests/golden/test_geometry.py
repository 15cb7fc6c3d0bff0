"""golden.geometry: Geometry.of (the smallest unit that holds a set), fits (one line per misfit),
the descriptor widths the hardware always had, union, the presets against the built-in scenes and
pvrtex's .dt files, and the TOML file form (round trips, and every way a file can be wrong)."""

from __future__ import annotations

import dataclasses
import os
import re
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vqtex.golden.constants import COLORS, LAYOUTS, PVR2_COLORS
from vqtex.golden.geometry import (BLOCK_SHAPES, MAX_DEPTH, PRESETS, Geometry, GeometryError, geometry_from,
                                   preset)
from vqtex.golden.pvr2.pvr_set import import_dt
from tests.support import CONFIGS, REPO, combined_set, get_set, pvr2_small_sets, scene_set, texture_set

PAPER_COLORS = ("rgb", "rgba", "intensity", "yuv411")


# -- the sets (tests.support.get_set) --------------------------------------------------------------

SET_NAMES = list(CONFIGS) + ["combined", "pvr2:rectangles_and_mip8", "pvr2:crate_argb4444_c_64_m"]


def _dt_dir():
    for d in (Path(REPO) / "tests" / "data" / "pvrtex" / "generated",
              Path(REPO).parent / "shared" / "vectors" / "pvrtex" / "generated"):
        if d.is_dir() and any(d.glob("*.dt")):
            return d
    return None


DT_DIR = _dt_dir()
DT_FILES = sorted(DT_DIR.glob("*.dt")) if DT_DIR else []


def _bits_for(n):
    """amaranth.utils.bits_for, written out."""
    return max(1, int(n).bit_length())


# -- Geometry.of -------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", SET_NAMES)
def test_of_depths_and_features(name):
    ts = get_set(name)
    g = Geometry.of(ts)
    d = ts.descriptors
    valid = d["valid"] != 0
    comp = valid & (d["compressed"] != 0)
    assert g.textures == ts.n_textures == len(ts.textures)
    assert g.word_bits == ts.word_bits
    assert g.index_words == len(ts.index_words)          # every set ends with its zero word: never 0
    assert g.codebook_entries == len(ts.codebook)
    assert g.raw_words == len(ts.raw_words)
    assert g.entry_bytes == ts.codebook.shape[1]
    if comp.any():
        assert g.colors == tuple(c for c in COLORS if COLORS.index(c) in set(d["color"][comp].tolist()))
        assert g.index_widths == tuple(sorted(set(d["index_bits"][comp].tolist())))
        assert g.blocks == tuple(sorted({tuple(int(v) for v in cb.block) for cb in ts.codebooks}))
        assert g.extended == bool((d["sublevel"][comp] > 0).any())
        span = d["log2w"].astype(int) - d["log2bw"] + d["log2h"] - d["log2bh"]
        assert g.k_bits == max(1, int(span[comp].max()))
    else:
        assert g.k_bits == 1 and not g.extended
    pvr2 = bool((d["layout"][valid] != 0).any() or (d["color"][valid] >= COLORS.index("argb1555")).any())
    assert g.pvr2 == pvr2
    assert g.layouts == (("pvr2",) if pvr2 else ("paper",))
    assert g.fits(ts) == []
    assert g.descriptor_rows == 16 * ts.n_textures


def test_of_exact_values():
    """A few geometries written out in full (the CONFIGS and the combined set as they encode today)."""
    g = Geometry.of(texture_set("rgba_2x2_b7_mip_w16"))
    assert (g.textures, g.word_bits, g.colors, g.index_widths, g.layouts, g.blocks, g.extended) == \
        (1, 16, ("rgba",), (7,), ("paper",), ((2, 2),), True)
    assert (g.index_words, g.codebook_entries, g.entry_bytes, g.raw_words, g.k_bits) == (120, 16, 20, 5, 8)
    g = Geometry.of(texture_set("i8_4x2_b5_w64"))
    assert (g.textures, g.word_bits, g.colors, g.index_widths, g.blocks, g.extended, g.raw_words) == \
        (1, 64, ("intensity",), (5,), ((4, 2),), False, 0)
    assert (g.index_words, g.codebook_entries, g.entry_bytes, g.k_bits) == (21, 12, 8, 8)
    g = Geometry.of(combined_set())
    assert g.textures == 6 and g.word_bits == 32
    assert g.colors == ("rgb", "rgba", "intensity", "yuv411")
    assert g.index_widths == (5, 7, 8, 12)
    assert g.blocks == ((2, 2), (2, 4), (4, 2), (4, 4))
    assert g.extended and g.layouts == ("paper",)
    g = Geometry.of(texture_set("raw_only_8x8_mip"))
    assert (g.codebook_entries, g.raw_words, g.index_words, g.k_bits, g.colors, g.extended) == \
        (0, 85, 1, 1, ("rgb",), False)
    g = Geometry.of(pvr2_small_sets()["rectangles_and_mip8"])
    assert g.colors == PVR2_COLORS and g.layouts == ("pvr2",) and g.blocks == ((2, 2),)
    assert (g.textures, g.entry_bytes, g.index_widths, g.extended, g.pvr2) == (4, 8, (8,), False, True)


@pytest.mark.parametrize("scene", ["topspin", "town"])
def test_scenes_fit_paper_and_dreamcast(scene):
    ts = scene_set(scene)
    g = Geometry.of(ts)
    assert g.fits(ts) == []
    assert PRESETS["paper"].fits(ts) == []
    assert PRESETS["dreamcast"].fits(ts) == []
    # the sizes the paper preset's comment quotes
    expected = {"topspin": (3, 4257, 768, 1365), "town": (22, 7409, 2048, 8528)}[scene]
    assert (g.textures, g.index_words, g.codebook_entries, g.raw_words) == expected
    # max has 512 codewords: neither scene fits it, and it says so in one line
    assert PRESETS["max"].fits(ts) == [f"codebook memory: {expected[2]} entries, the unit holds 512"]


@pytest.mark.skipif(not DT_FILES, reason="no pvrtex .dt vectors")
@pytest.mark.parametrize("path", DT_FILES, ids=lambda p: p.name)
def test_dt_fits_dreamcast_not_paper(path):
    ts = import_dt([path])
    g = Geometry.of(ts)
    assert g.fits(ts) == []
    assert PRESETS["dreamcast"].fits(ts) == []
    misfit = PRESETS["paper"].fits(ts)
    foreign = [c for c in g.colors if c not in PAPER_COLORS]
    assert foreign and set(foreign) <= set(PVR2_COLORS)
    fmt = [c for c in PVR2_COLORS if f"_{c}_" in path.name]
    assert not fmt or fmt[0] in foreign                       # crate_<format>_... names its format
    assert misfit == [f"colour format {', '.join(foreign)} not supported (the unit has rgb, rgba, intensity, yuv411)",
                      "layout pvr2 not supported (the unit has paper)"]


# -- fits: every misfit named ------------------------------------------------------------------------

def _with(g, **kw):
    return Geometry(**{**g.to_dict(), **kw})


def test_fits_names_each_misfit():
    ts = combined_set()
    g = Geometry.of(ts)
    n_idx, n_cb, n_raw, eb, k = len(ts.index_words), len(ts.codebook), len(ts.raw_words), ts.entry_bytes, g.k_bits
    assert (n_idx, n_cb, n_raw, eb, k) == (278, 52, 138, 63, 8)
    cases = [
        (dict(textures=5), "6 textures, the descriptor table holds 5"),
        (dict(index_words=n_idx - 1), f"index memory: {n_idx} words, the unit holds {n_idx - 1}"),
        (dict(codebook_entries=n_cb - 1), f"codebook memory: {n_cb} entries, the unit holds {n_cb - 1}"),
        (dict(entry_bytes=eb - 1), f"codebook entries of {eb} bytes, the unit's are {eb - 1}"),
        (dict(raw_words=n_raw - 1), f"raw memory: {n_raw} words, the unit holds {n_raw - 1}"),
        (dict(k_bits=k - 1), f"a level of 2^{k} blocks, the unit addresses 2^{k - 1}"),
        (dict(word_bits=16), "index words of 32 bits, the unit's are 16"),
        (dict(word_bits=64), "index words of 32 bits, the unit's are 64"),
        (dict(colors=["rgb", "rgba", "intensity"]),
         "colour format yuv411 not supported (the unit has rgb, rgba, intensity)"),
        (dict(colors=["rgb", "argb1555"]),
         "colour format rgba, intensity, yuv411 not supported (the unit has rgb, argb1555)"),
        (dict(index_widths=[5, 7, 8]), "index width 12 not supported (the unit has 5, 7, 8)"),
        (dict(blocks=["2x2", "4x2", "4x4"]), "block 2x4 not supported (the unit has 2x2, 4x2, 4x4)"),
        (dict(extended=False), "extended (mipmap) codewords not supported"),
    ]
    for change, line in cases:
        assert _with(g, **change).fits(ts) == [line], change
        assert dataclasses.replace(g, **change).fits(ts) == [line], change
    # a PowerVR2 set in a unit without the twiddled layout
    pts = pvr2_small_sets()["crate_argb4444_c_64_m"]
    pg = Geometry.of(pts)
    assert _with(pg, layouts=["paper"]).fits(pts) == ["layout pvr2 not supported (the unit has paper)"]
    assert _with(pg, colors=["rgb565"]).fits(pts) == ["colour format argb4444 not supported (the unit has rgb565)"]
    # several at once: one line each, in a fixed order
    small = _with(g, textures=1, codebook_entries=10, extended=False, index_widths=[8])
    assert small.fits(ts) == ["6 textures, the descriptor table holds 1",
                              f"codebook memory: {n_cb} entries, the unit holds 10",
                              "index width 5, 7, 12 not supported (the unit has 8)",
                              "extended (mipmap) codewords not supported"]


@pytest.mark.parametrize("name", SET_NAMES)
def test_of_is_smallest(name):
    """Geometry.of is the smallest: one less of any depth, or one feature fewer, is exactly one misfit."""
    ts = get_set(name)
    g = Geometry.of(ts)
    lower = {"textures": 1, "index_words": 1, "codebook_entries": 0, "entry_bytes": 1, "raw_words": 0, "k_bits": 1}
    shrunk = 0
    for key, lo in lower.items():
        v = getattr(g, key)
        if v <= lo or (key == "entry_bytes" and not len(ts.codebook)):
            continue
        misfit = dataclasses.replace(g, **{key: v - 1}).fits(ts)
        assert len(misfit) == 1 and str(v) in misfit[0], (key, misfit)
        shrunk += 1
    assert shrunk >= (2 if len(ts.codebook) else 1)
    if len(ts.codebook):
        for key in ("colors", "index_widths", "layouts", "blocks"):
            have = getattr(g, key)
            for v in have:
                if len(have) > 1:
                    rest = tuple(x for x in have if x != v)
                    misfit = dataclasses.replace(g, **{key: rest}).fits(ts)
                    assert len(misfit) == 1, (key, v, misfit)
        if g.extended:
            assert dataclasses.replace(g, extended=False).fits(ts) == ["extended (mipmap) codewords not supported"]


def test_raw_only_set_ignores_codebook_features():
    """A set without codewords fits whatever formats, widths and entry bytes the unit has."""
    ts = texture_set("raw_only_8x8_mip")
    g = _with(Geometry.of(ts), colors=["intensity"], index_widths=[3], blocks=["8x8"], extended=False,
              entry_bytes=1, codebook_entries=0)
    assert g.fits(ts) == []
    assert _with(g, raw_words=84).fits(ts) == ["raw memory: 85 words, the unit holds 84"]


# -- descriptor widths -------------------------------------------------------------------------------

@pytest.mark.parametrize("name", SET_NAMES + ["scene:topspin"])
def test_descriptor_widths_as_before(name):
    """The widths the baked unit had before geometries (hw.descriptor.descriptor_widths(ts) and
    hw.front_end.k_bits(ts) of commit 8116282^), written out."""
    ts = get_set(name)
    d = ts.descriptors
    valid = d["valid"] != 0
    pvr2 = bool((d["layout"][valid] != 0).any() or (d["color"][valid] >= 4).any())
    off = _bits_for(ts.entry_bytes)
    before = {"valid": 1, "compressed": 1, "base": _bits_for(max(len(ts.index_words), len(ts.raw_words))),
              "log2w": 4, "log2h": 4, "log2bw": 2, "log2bh": 2, "index_bits": 5,
              "cb_base": _bits_for(len(ts.codebook)), "sublevel": 2, "color": 3 if pvr2 else 2,
              "texel_off": off, "u_off": off, "v_off": off, "layout": 1 if pvr2 else 0}
    g = Geometry.of(ts)
    assert g.descriptor_widths() == before
    comp = valid & (d["compressed"] != 0)
    span = (d["log2w"].astype(int) - d["log2bw"] + d["log2h"] - d["log2bh"])[comp]
    assert g.k_bits == (max(1, int(span.max())) if comp.any() else 1)
    assert g.texture_bits == _bits_for(ts.n_textures - 1)
    # every field value of the set fits its width
    for field, width in before.items():
        assert int(d[field].max()) < (1 << width) or (width == 0 and int(d[field].max()) == 0), field


def test_descriptor_widths_exact():
    w = Geometry.of(combined_set()).descriptor_widths()
    assert (w["base"], w["cb_base"], w["texel_off"], w["color"], w["layout"]) == (9, 6, 6, 2, 0)
    w = Geometry.of(pvr2_small_sets()["crate_argb4444_c_64_m"]).descriptor_widths()
    assert (w["base"], w["cb_base"], w["texel_off"], w["color"], w["layout"]) == (11, 7, 4, 3, 1)
    w = PRESETS["paper"].descriptor_widths()
    assert (w["base"], w["cb_base"], w["texel_off"], w["color"], w["layout"]) == (15, 12, 7, 2, 0)
    w = PRESETS["dreamcast"].descriptor_widths()
    assert (w["base"], w["cb_base"], w["texel_off"], w["color"], w["layout"]) == (15, 12, 7, 3, 1)
    w = PRESETS["max"].descriptor_widths()
    assert (w["base"], w["cb_base"], w["texel_off"], w["color"], w["layout"]) == (16, 10, 9, 3, 1)


# -- union -------------------------------------------------------------------------------------------

UNION_PAIRS = [("rgb_4x4_b8_mip", "yuv_8x2_b6"), ("combined", "pvr2:rectangles_and_mip8"),
               ("rgba_8x8_b9_mip", "raw_only_8x8_mip"), ("rgba_2x2_b7_mip_w16", "rgb_2x2_b16_w16"),
               ("i8_4x2_b5_w64", "yuv_2x4_b12_mip_w64"), ("scene:topspin", "pvr2:crate_argb4444_c_64_m")]


@pytest.mark.parametrize("a,b", UNION_PAIRS)
def test_union(a, b):
    ta, tb = get_set(a), get_set(b)
    ga, gb = Geometry.of(ta), Geometry.of(tb)
    u = ga.union(gb)
    assert u == gb.union(ga)
    assert u.union(u) == u and u.union(ga) == u
    assert u.fits(ta) == [] and u.fits(tb) == []
    for key in ("textures", "index_words", "codebook_entries", "entry_bytes", "raw_words", "k_bits"):
        assert getattr(u, key) == max(getattr(ga, key), getattr(gb, key)), key
    for key in ("colors", "index_widths", "layouts", "blocks"):
        assert set(getattr(u, key)) == set(getattr(ga, key)) | set(getattr(gb, key)), key
    assert u.extended == (ga.extended or gb.extended)
    assert u.word_bits == ga.word_bits
    assert u.colors == tuple(c for c in COLORS if c in u.colors)           # canonical order


def test_union_of_presets_and_word_bits():
    p, d = PRESETS["paper"], PRESETS["dreamcast"]
    assert p.union(d) == d.union(p)
    assert p.union(d).colors == COLORS and p.union(d).layouts == LAYOUTS
    g16 = Geometry.of(texture_set("rgba_2x2_b7_mip_w16"))
    g64 = Geometry.of(texture_set("i8_4x2_b5_w64"))
    for a, b in ((p, g16), (g16, p), (g16, g64), (g64, p)):
        with pytest.raises(GeometryError, match=f"{a.word_bits} and {b.word_bits} bits"):
            a.union(b)


# -- TOML file form ----------------------------------------------------------------------------------

@pytest.mark.parametrize("name", list(PRESETS))
def test_preset_round_trip(name, tmp_path):
    g = PRESETS[name]
    text = g.dumps()
    assert Geometry.loads(text) == g
    assert Geometry.loads(text).dumps() == text
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    assert Geometry.load(path) == g
    assert geometry_from(str(path)) == g
    assert geometry_from(name) is g
    assert preset(name) is g
    assert Geometry(**g.to_dict()) == g


def test_preset_values():
    p = PRESETS["paper"]
    assert (p.textures, p.index_words, p.codebook_entries, p.raw_words, p.k_bits, p.word_bits) == \
        (32, 8192, 2048, 16384, 14, 32)
    assert p.colors == PAPER_COLORS and p.index_widths == (8, 12) and p.layouts == ("paper",)
    assert p.blocks == ((2, 2), (4, 4)) and p.extended and p.entry_bytes == 84   # 4x4 rgba with 3 sub-levels
    d = PRESETS["dreamcast"]
    assert d.index_words == 16384 and d.k_bits == 18 and d.colors == COLORS and d.layouts == LAYOUTS and d.pvr2
    m = PRESETS["max"]
    assert m.blocks == BLOCK_SHAPES and m.index_widths == tuple(range(1, 17)) and m.entry_bytes == 336
    assert (m.textures, m.index_words, m.codebook_entries) == (64, 32768, 512)
    assert 'colors = ["rgb", "rgba", "intensity", "yuv411"]' in p.dumps()
    assert 'blocks = ["2x2", "4x4"]' in p.dumps() and "extended = true" in p.dumps()


@pytest.mark.parametrize("name", SET_NAMES + ["scene:town"])
def test_of_round_trip(name):
    g = Geometry.of(get_set(name))
    assert Geometry.loads(g.dumps()) == g
    assert Geometry(**g.to_dict()) == g


def _paper_text(**changes):
    """The paper preset's TOML with keys replaced (value: TOML text) or removed (None)."""
    lines = []
    for line in PRESETS["paper"].dumps().splitlines():
        key = line.split(" = ")[0]
        if key in changes:
            if changes[key] is not None:
                lines.append(f"{key} = {changes[key]}")
        else:
            lines.append(line)
    return "\n".join(lines) + "\n"


BAD_VALUES = [
    # (key, TOML value, what the message says besides the key)
    ("textures", '"32"', "'32'"), ("textures", "true", "True"), ("textures", "32.0", "32.0"),
    ("textures", "0", "not 0"), ("textures", "4097", "4097"), ("textures", "[32]", "[32]"),
    ("index_words", "-1", "-1"), ("index_words", str(MAX_DEPTH + 1), str(MAX_DEPTH + 1)),
    ("index_words", "0", "not 0"), ("codebook_entries", '"many"', "many"),
    ("entry_bytes", "100000", "100000"), ("entry_bytes", "0", "not 0"), ("raw_words", "false", "False"),
    ("k_bits", "25", "25"), ("k_bits", "0", "not 0"),
    ("word_bits", "24", "24"), ("word_bits", '"32"', "'32'"), ("word_bits", "[32]", "[32]"),
    ("word_bits", "true", "True"),
    ("colors", '["cmyk"]', "cmyk"), ("colors", "[]", "[]"), ("colors", '"rgb"', "must be a list"),
    ("colors", "[1]", "[1]"), ("colors", "{ a = 1 }", "must be a list"),
    ("index_widths", "[17]", "17"), ("index_widths", "[0]", "[0]"), ("index_widths", "[8.0]", "8.0"),
    ("index_widths", "[true]", "True"), ("index_widths", "8", "must be a list"),
    ("index_widths", '["8"]', "'8'"),
    ("layouts", '["morton"]', "morton"), ("layouts", '"paper"', "must be a list"), ("layouts", "[]", "[]"),
    ("blocks", '["3x3"]', "(3, 3)"), ("blocks", '["16x16"]', "(16, 16)"), ("blocks", '["4x"]', "4x"),
    ("blocks", '["4x4x4"]', "4x4x4"), ("blocks", "[]", "at least one"), ("blocks", '"4x4"', "must be a list"),
    ("blocks", "[[3, 3]]", "(3, 3)"),
]


@pytest.mark.parametrize("key,value,says", BAD_VALUES, ids=[f"{k}={v}" for k, v, _ in BAD_VALUES])
def test_loads_refuses_bad_values(key, value, says):
    with pytest.raises(GeometryError) as e:
        Geometry.loads(_paper_text(**{key: value}), "unit.toml")
    msg = str(e.value)
    assert msg.startswith("unit.toml: "), msg
    # the key (the block shape message names it "block")
    assert (key if key != "blocks" else "block") in msg, msg
    assert says in msg, msg
    assert "\n" not in msg


def test_loads_refuses_structure():
    with pytest.raises(GeometryError, match=r"^g\.toml: not TOML"):
        Geometry.loads("textures = = 3", "g.toml")
    with pytest.raises(GeometryError, match="not TOML"):
        Geometry.loads(_paper_text() + "textures = 3\n")                  # a key twice
    with pytest.raises(GeometryError, match="not TOML"):
        Geometry.loads("\x00")
    with pytest.raises(GeometryError, match=r"unknown key 'depth' \(keys: textures, index_words"):
        Geometry.loads(_paper_text() + "depth = 3\n")
    with pytest.raises(GeometryError, match=r"unknown key 'geometry'"):
        Geometry.loads("[geometry]\n" + _paper_text())                   # everything inside a table
    for key in ("textures", "index_words", "codebook_entries", "entry_bytes", "raw_words", "k_bits", "colors",
                "index_widths"):
        with pytest.raises(GeometryError, match=f"^<geometry>: missing key '{key}'$"):
            Geometry.loads(_paper_text(**{key: None}))
    with pytest.raises(GeometryError, match="missing key 'textures'"):
        Geometry.loads("")
    # the keys with defaults may be left out
    g = Geometry.loads(_paper_text(layouts=None, blocks=None, extended=None, word_bits=None))
    assert (g.layouts, g.blocks, g.extended, g.word_bits) == (("paper",), ((4, 4),), True, 32)


@pytest.mark.parametrize("value", ['"false"', "0", "[]", '"no"'])
def test_loads_refuses_non_bool_extended(value):
    with pytest.raises(GeometryError, match="extended"):
        Geometry.loads(_paper_text(extended=value))


def test_loads_refuses_float_word_bits():
    with pytest.raises(GeometryError, match="word_bits"):
        Geometry.loads(_paper_text(word_bits="32.0"))


def test_block_of_unicode_digits_names_the_key():
    with pytest.raises(GeometryError, match="block"):
        Geometry.loads(_paper_text(blocks='["²x²"]'))


def test_loads_accepts_equivalent_spellings():
    g = Geometry.loads(_paper_text(colors='["yuv411", "rgb", "rgb", "intensity", "rgba"]',
                                   index_widths="[12, 8, 12]", blocks='["4X4", [2, 2]]'))
    assert g == PRESETS["paper"]


def test_load_file_errors(tmp_path):
    with pytest.raises(GeometryError, match="No such file"):
        Geometry.load(tmp_path / "missing.toml")
    with pytest.raises(GeometryError, match="directory"):
        Geometry.load(tmp_path)
    big = tmp_path / "big.toml"
    big.write_text(PRESETS["paper"].dumps() + "#" * (1 << 16))
    with pytest.raises(GeometryError, match="larger than 64 KiB"):
        Geometry.load(big)
    exact = tmp_path / "exact.toml"                         # exactly 64 KiB is still a file
    text = PRESETS["paper"].dumps()
    exact.write_text(text + "#" * ((1 << 16) - len(text) - 1) + "\n")
    assert os.path.getsize(exact) == 1 << 16 and Geometry.load(exact) == PRESETS["paper"]
    latin = tmp_path / "latin.toml"
    latin.write_bytes(PRESETS["paper"].dumps().encode() + b"# caf\xe9\n")
    with pytest.raises(GeometryError, match="not UTF-8"):
        Geometry.load(latin)
    binary = tmp_path / "binary.toml"
    binary.write_bytes(bytes(range(256)))
    with pytest.raises(GeometryError):
        Geometry.load(binary)
    bad = tmp_path / "bad.toml"
    bad.write_text(_paper_text(textures="0"))
    with pytest.raises(GeometryError, match="^" + re.escape(str(bad)) + ": geometry textures"):
        Geometry.load(bad)
    with pytest.raises(GeometryError, match="^" + re.escape(str(bad)) + ": geometry textures"):
        geometry_from(str(bad))
    with pytest.raises(GeometryError, match="No such file"):
        geometry_from(str(tmp_path / "nosuch.toml"))


def test_load_nul_path():
    with pytest.raises(GeometryError):
        Geometry.load("paper\x00.toml")


def test_geometry_from_names():
    assert geometry_from("paper") is PRESETS["paper"]
    assert geometry_from("dreamcast") is PRESETS["dreamcast"]
    for name in ("nosuch", "Paper", "", "paper.tom"):
        with pytest.raises(GeometryError) as e:
            geometry_from(name)
        assert str(e.value) == f"unknown geometry {name!r} (presets: paper, dreamcast, max; or a .toml file)"
    with pytest.raises(GeometryError, match="presets: paper, dreamcast, max"):
        preset("nosuch")


# -- property: random valid geometries round-trip -------------------------------------------------------

_blocks = st.sampled_from(BLOCK_SHAPES).flatmap(
    lambda s: st.sampled_from([s, list(s), f"{s[0]}x{s[1]}", f"{s[0]}X{s[1]}"]))

geometries = st.builds(
    Geometry,
    textures=st.integers(1, 1 << 12), index_words=st.integers(1, MAX_DEPTH),
    codebook_entries=st.integers(0, 1 << 20), entry_bytes=st.integers(1, 512), raw_words=st.integers(0, MAX_DEPTH),
    k_bits=st.integers(1, 24), colors=st.lists(st.sampled_from(COLORS), min_size=1, max_size=10),
    index_widths=st.lists(st.integers(1, 16), min_size=1, max_size=20),
    layouts=st.lists(st.sampled_from(LAYOUTS), min_size=1, max_size=3),
    blocks=st.lists(_blocks, min_size=1, max_size=8), extended=st.booleans(),
    word_bits=st.sampled_from((16, 32, 64)))


@settings(max_examples=150)
@given(geometries)
def test_random_geometries_round_trip(g):
    text = g.dumps()
    back = Geometry.loads(text)
    assert back == g
    assert back.dumps() == text
    assert Geometry(**g.to_dict()) == g
    assert back.descriptor_widths() == g.descriptor_widths()
    # canonical: sorted, no repeats
    assert list(g.colors) == sorted(set(g.colors), key=COLORS.index)
    assert list(g.index_widths) == sorted(set(g.index_widths))
    assert list(g.blocks) == sorted(set(g.blocks)) and all(b in BLOCK_SHAPES for b in g.blocks)
    assert g.union(g) == g


@settings(max_examples=60)
@given(geometries, geometries)
def test_random_union(a, b):
    b = dataclasses.replace(b, word_bits=a.word_bits)
    u = a.union(b)
    assert u == b.union(a)
    assert u.union(a) == u and u.union(b) == u
    assert Geometry.loads(u.dumps()) == u
