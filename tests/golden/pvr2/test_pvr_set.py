"""The PowerVR2 layout as a mode of the texture set (golden.pvr2.pvr_set, golden.fetch's twiddled path):
every texel of every level of every pvrtex file fetched from the imported set equals pvrtex's own
preview; the set survives the .vqt container and a hostile copy of it; .dt files written back are
pvrtex's bytes."""

from pathlib import Path

import numpy as np
import pytest

from vqtex.golden.pvr2 import pvr, pvr_set
from vqtex.golden.color import DREAMCAST_YUV422
from vqtex.golden.fetch import block_address, decode, fetch, random_requests, twiddled_block
from vqtex.golden.format import COLOR_CODES, DESCRIPTOR_FIELDS, FormatError, TextureSet
from vqtex.golden.render.imageio import read_image
from tests.support import PVRTEX_DATA, random_dt
from vqtex.sim.bench.robustness.fuzz import join_vqt, mutate_vqt, split_vqt, try_file

DATA = Path(PVRTEX_DATA)
GENERATED = sorted((DATA / "generated").glob("*.dt"))
APPROVED_VQ = DATA / "approved" / "texture_dt_-f_argb4444_-d_-c_64_-m_quality_-r_-R" / "texture.dt"


def _levels_by_fetch(ts: TextureSet, tex: int = 0) -> list:
    out = []
    for L, (w, h) in enumerate(ts.level_shapes(tex)):
        jj, ii = np.mgrid[0:h, 0:w]
        out.append(fetch(ts, tex, L, ii.ravel(), jj.ravel()).reshape(h, w, 4))
    return out


@pytest.mark.parametrize("path", GENERATED, ids=[p.stem for p in GENERATED])
def test_fetch_of_every_texel_equals_pvrtex_preview(path):
    ts = TextureSet.from_bytes(pvr_set.import_dt([path]).to_bytes())       # through the container too
    levels = _levels_by_fetch(ts)
    theirs = read_image(path.with_name(path.name[:-3] + ".preview.png"))
    assert np.array_equal(pvr.preview(levels), theirs)
    for L, lv in enumerate(levels):                                        # the independent whole-level path
        assert np.array_equal(decode(ts, 0, L), lv)
    info = ts.textures[0]
    hdr = pvr.read_dt(path, decode=False).header
    assert (info.color, info.block, info.index_bits, info.levels) == (
        pvr_set.PVR2_COLORS[hdr.pixel_format], (2, 2), 8, len(hdr.level_sizes))
    assert ts.codebooks[0].size == hdr.codebook_entries


@pytest.mark.parametrize("path", GENERATED + [APPROVED_VQ], ids=[p.stem for p in GENERATED] + ["approved"])
def test_written_dt_is_pvrtex_bytes(path):
    assert pvr_set.to_dt(pvr_set.import_dt([path])) == path.read_bytes()


def test_approved_texture_fetches_as_pvr_decodes():
    tex = pvr.read_dt(APPROVED_VQ)
    assert all(np.array_equal(a, b) for a, b in zip(_levels_by_fetch(pvr_set.import_dt([APPROVED_VQ])), tex.levels))


def test_one_by_one_level_descriptor():
    """The 1x1 level reads texel 3 of its block (byte 6), as rgb565 in a yuv422 texture."""
    ts = pvr_set.import_dt([DATA / "generated" / "crate_yuv422_c_m.dt"])
    d = ts.descriptor(0, 7)
    assert (d["log2w"], d["log2bw"], d["texel_off"], d["color"], d["layout"]) == (0, 0, 6, COLOR_CODES["rgb565"], 1)
    assert ts.descriptor(0, 6)["color"] == COLOR_CODES["yuv422"] and ts.matrix == DREAMCAST_YUV422


def test_small_codebook_is_rebased_and_written_back():
    path = DATA / "generated" / "crate_rgb565_c_small_m.dt"
    ts = pvr_set.import_dt([path])
    n = ts.codebooks[0].size
    assert n < 256 and len(ts.codebook) == n
    ts.check_indices()                                # every index inside the N stored entries
    assert pvr_set.to_dt(ts)[32 + 8 * n] >= 256 - n   # the file's bytes are 256-N..255 again


def test_several_files_make_one_set():
    paths = [DATA / "generated" / f"crate_{f}_c_64_m.dt" for f in ("rgb565", "yuv422", "argb4444")]
    ts = pvr_set.import_dt(paths)
    assert ts.n_textures == 3 and len(ts.codebooks) == 3 and ts.matrix == DREAMCAST_YUV422
    for t, path in enumerate(paths):
        assert all(np.array_equal(a, b) for a, b in zip(_levels_by_fetch(ts, t), pvr.read_dt(path).levels))
        assert pvr_set.to_dt(ts, t) == path.read_bytes()


def test_combined_with_a_paper_set():
    """A paper yuv411 set (JFIF matrix) and a PowerVR2 RGB set share one unit; a yuv422 set, which
    needs the Dreamcast matrix, cannot join the yuv411 one."""
    from tests.support import texture_set
    paper = texture_set("yuv_4x4_b12_mip")
    ts = TextureSet.combine([paper, pvr_set.import_dt([GENERATED[0]])])
    req = random_requests(ts, 4000, seed=2)
    for t, src in ((0, paper), (1, None)):
        sel = req[:, 0] == t
        if src is not None:
            assert np.array_equal(fetch(ts, *req[sel].T), fetch(paper, 0, *req[sel, 1:].T))
    assert np.array_equal(_levels_by_fetch(ts, 1)[0], pvr.read_dt(GENERATED[0]).levels[0])
    assert ts.matrix == paper.matrix
    with pytest.raises(FormatError, match="colour matrix"):
        TextureSet.combine([paper, pvr_set.import_dt([DATA / "generated" / "crate_yuv422_c.dt"])])


@pytest.mark.parametrize("bw, bh", [(1, 1), (2, 2), (8, 8), (4, 1), (1, 4), (16, 2), (2, 16), (64, 8), (8, 512)])
def test_twiddled_block_agrees_with_pvr_twiddle(bw, bh):
    by, bx = np.mgrid[0:bh, 0:bw]
    k = twiddled_block(bx.ravel(), by.ravel(), int(bw).bit_length() - 1, int(bh).bit_length() - 1)
    assert np.array_equal(k.reshape(bh, bw), pvr.twiddle_indices(bw, bh))


@pytest.mark.parametrize("width, height, fmt, n", [(64, 8, 1, 256), (8, 32, 3, 17), (16, 16, 0, 1),
                                                   (1024, 8, 2, 100), (8, 8, 3, 256)])
def test_rectangular_textures_fetch_as_pvr_decodes(width, height, fmt, n):
    """Rectangles are twiddled in min-side squares; random texels of every format."""
    data = random_dt(width, height, fmt, n, seed=width + height)
    ts = pvr_set.from_dt(pvr.parse_dt(data, decode=False))
    assert np.array_equal(_levels_by_fetch(ts)[0], pvr.parse_dt(data).levels[0])
    assert np.array_equal(decode(ts, 0, 0), pvr.parse_dt(data).levels[0])
    assert pvr.parse_dt(pvr_set.to_dt(ts)).levels[0].tobytes() == pvr.parse_dt(data).levels[0].tobytes()


def test_block_address_transposes_offsets_only_for_pvr2():
    ts = pvr_set.import_dt([GENERATED[0]])
    d = ts.descriptors[[0, 0], [0, 0]]
    k, x, y = block_address(d, [3, 2], [0, 1])
    assert k.tolist() == [2, 2] and x.tolist() == [0, 1] and y.tolist() == [1, 0]


def test_layout_is_a_descriptor_field():
    assert list(DESCRIPTOR_FIELDS)[-1] == "layout"


def test_legacy_vqt_without_layout_field_loads():
    """A .vqt written before the layout field existed reads with layout 0 (the paper's)."""
    import json
    from tests.support import texture_set
    ts = texture_set("rgb_4x4_b8_mip")
    prefix, header, body = split_vqt(ts.to_bytes())
    h = json.loads(header)
    h["descriptor_fields"] = [f for f in h["descriptor_fields"] if f != "layout"]
    desc = h["arrays"]["descriptors"]
    from vqtex.golden.constants import LEGACY_DESCRIPTOR_DTYPE
    old = np.zeros(ts.descriptors.shape, LEGACY_DESCRIPTOR_DTYPE)
    for name in LEGACY_DESCRIPTOR_DTYPE.names:
        old[name] = ts.descriptors[name]
    raw = old.tobytes()
    start = desc["offset"]
    new_body = body[:start] + raw + body[start + desc["nbytes"]:]
    shift = len(raw) - desc["nbytes"]
    desc["nbytes"] = len(raw)
    for name, spec in h["arrays"].items():
        if spec["offset"] > start:
            spec["offset"] += shift
    loaded = TextureSet.from_bytes(join_vqt(prefix, json.dumps(h).encode(), new_body))
    assert loaded == ts


def _tampered(field: str, value: int, level: int = 0) -> bytes:
    ts = pvr_set.import_dt([DATA / "generated" / "crate_yuv422_c_64_m.dt"])
    ts.descriptors[0, level][field] = value
    return ts.to_bytes()


@pytest.mark.parametrize("field, value, level", [
    ("layout", 0, 0), ("layout", 2, 0), ("texel_off", 0, 7), ("color", COLOR_CODES["yuv422"], 7),
    ("color", COLOR_CODES["rgb"], 0), ("v_off", 2, 3), ("log2bw", 0, 2), ("sublevel", 1, 1),
    ("index_bits", 12, 0), ("log2bw", 1, 7),
])
def test_tampered_pvr2_descriptor_is_refused(field, value, level):
    with pytest.raises(FormatError) as e:
        TextureSet.from_bytes(_tampered(field, value, level))
    assert "\n" not in str(e.value)


def test_paper_layout_with_pvr2_flag_is_refused():
    from tests.support import texture_set
    ts = TextureSet.from_bytes(texture_set("rgb_4x4_b8_mip").to_bytes())     # a copy: the set is cached
    ts.descriptors[0, 0]["layout"] = 1
    with pytest.raises(FormatError, match="layout"):
        TextureSet.from_bytes(ts.to_bytes())


def test_mutated_pvr2_vqt_only_format_errors():
    """Mutations of a PowerVR2 .vqt (bytes and JSON, checksum recomputed): accepted and usable, or
    one FormatError."""
    seed = pvr_set.import_dt([DATA / "generated" / "crate_argb1555_c_small_m.dt"]).to_bytes()
    rng = np.random.default_rng(15)
    outcomes = {}
    for _ in range(300):
        outcome, detail = try_file(mutate_vqt(seed, rng))
        outcomes[outcome] = outcomes.get(outcome, 0) + 1
        assert outcome in ("accepted", "rejected"), detail
    assert outcomes.get("rejected", 0) > 100
