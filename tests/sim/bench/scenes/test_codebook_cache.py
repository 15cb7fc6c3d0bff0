"""sim.bench.scenes.codebook_cache: the codebook entries and bytes a frame reads, and the codebook
cache's misses, on a small scene."""

import numpy as np

from vqtex.golden.fetch import block_address, lookup_descriptor, random_requests, read_codeword, read_index
from vqtex.golden.format import COLORS, texel_bytes
from vqtex.golden.render.scene import build_texture_set, parse_scene
from vqtex.sim.bench.scenes.codebook_cache import codebook_cache, codebook_references, texel_lines

from tests.support import NEED_SCENE as SMALL
from tests.support.sets import combined_set, levels


def _set():
    return build_texture_set(parse_scene(SMALL, "small.toml"))


def test_entries_are_the_compressed_requests_codebook_rows():
    ts = _set()
    req = random_requests(ts, 3000, seed=4)
    d = lookup_descriptor(ts, req[:, 0], req[:, 1])
    comp = d["compressed"].astype(bool)
    assert 0 < comp.sum() < len(req) or comp.all()
    e = codebook_references(ts, req)
    assert len(e) == comp.sum()
    lo = d["cb_base"][comp].astype(np.int64)
    k, _, _ = block_address(d[comp], req[comp, 2], req[comp, 3])
    assert (e - lo == read_index(ts, d[comp], k)).all()
    assert (e >= 0).all() and (e < len(ts.codebook)).all()


def _every_texel(ts):
    """A request for every texel of every level of every texture."""
    parts = []
    for t, level, w, h in levels(ts):
        j, i = np.mgrid[0:h, 0:w]
        parts.append(np.stack([np.full(w * h, t), np.full(w * h, level), i.ravel(), j.ravel()], 1))
    return np.concatenate(parts)


def test_texel_lines_address_the_bytes_read_codeword_reads():
    """With 1-byte lines a texel's first line is its first byte in the codebook memory as one byte
    array: the byte read_codeword returns first (rgb, rgba, intensity, yuv411's Y); a texel of
    more than one byte also references its last byte's line, right after."""
    ts = combined_set()             # noisy images: neighbouring sub-levels' bytes differ
    req = _every_texel(ts)
    d = lookup_descriptor(ts, req[:, 0], req[:, 1])
    comp = d["compressed"].astype(bool)
    dc, rc = d[comp], req[comp]
    k, x, y = block_address(dc, rc[:, 2], rc[:, 3])
    lines = texel_lines(ts, req, 1)
    tb = np.array([texel_bytes(c) for c in COLORS])[dc["color"].astype(np.int64)]
    count = 1 + (tb > 1)
    first = np.cumsum(count) - count                # each request's first reference
    assert len(lines) == count.sum()
    assert (lines[first[tb > 1] + 1] == lines[first[tb > 1]] + tb[tb > 1] - 1).all()
    flat = ts.codebook.ravel()
    samples = read_codeword(ts, dc, read_index(ts, dc, k), x, y)
    plain = dc["color"].astype(np.int64) <= 3      # rgb, rgba, intensity, yuv411: sample 0 is the first byte
    assert (dc["texel_off"][plain] > 0).any()       # sub-levels of extended mipmap codewords among them
    assert (flat[lines[first]][plain] == samples[plain, 0]).all()
    assert (texel_lines(ts, req, 1 << 20) == 0).all()   # everything in the first megabyte line


def test_a_cache_holding_every_entry_misses_once_per_entry():
    """At a size whose sets x ways cover the codebook memory, entries e and e + sets never meet in
    one set beyond its ways, so the only misses are the first reads: one per distinct entry."""
    scene = parse_scene(SMALL, "small.toml")
    r = codebook_cache(scene, frame=1, sizes=(1, 64))
    big = r["rows"][1]
    assert r["codebook_entries"] * big["codebook_line"] <= 64 * 1024
    assert np.isclose(big["codebook_bytes_per_pixel"] * r["pixels"], r["distinct_entries"] * big["codebook_line"])
    small = r["rows"][0]
    assert small["codebook_hit_rate"] <= big["codebook_hit_rate"] <= 1
    assert big["index_raw_bytes_per_pixel"] > 0 and big["codebook_adds"] > 0
