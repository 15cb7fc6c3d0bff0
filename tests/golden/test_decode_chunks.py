"""golden.fetch.decode works in bands of block rows (bounded memory, issue 26 item 5): it equals the
whole-array decode it replaced, on every configuration, PowerVR2 and pruned sets, at any band size;
the chunked index (un)packing equals the whole-array one."""

import dataclasses

import numpy as np
import pytest

from tests.support import CONFIGS, combined_set, levels, pvr2_small_sets, texture_set
from vqtex.golden import fetch as fetch_module
from vqtex.golden import format as fmt
from vqtex.golden.fetch import decode, decode_bands, expand_texels, fetch, random_requests
from vqtex.golden.format import COLOR_CODES, COLORS, LAYOUT_CODES, pack_indices, unpack_indices
from vqtex.golden.need.analysis import analyse
from vqtex.golden.need.prune import prune
from vqtex.golden.pvr2.pvr import decode_yuv422_blocks, twiddle_indices
from vqtex.sim.bench.robustness.decode_memory import big_set


def _unpack_whole(words, b, n, base=0, word_bits=32):
    """unpack_indices as it was: every bit of the map at once."""
    span = -(-(n * b) // word_bits)
    w = np.asarray(words[base: base + span]).astype(f"<u{word_bits // 8}")
    bits = np.unpackbits(w.view(np.uint8), bitorder="little")[: n * b]
    return (bits.reshape(n, b).astype(np.int64) << np.arange(b)).sum(axis=1)


def whole_decode(ts, tex, level=0):
    """golden.fetch.decode as it was before it worked in bands (whole index map, whole codebook
    rows as int64, whole level tiled at once): the reference the banded decode must equal."""
    d = ts.descriptor(tex, level)
    w, h = 1 << d["log2w"], 1 << d["log2h"]
    if not d["compressed"]:
        return ts.raw_words[d["base"]: d["base"] + w * h].astype("<u4").view(np.uint8).reshape(h, w, 4).copy()
    bw, bh = 1 << d["log2bw"], 1 << d["log2bh"]
    nbx, nby = w // bw, h // bh
    idx = _unpack_whole(ts.index_words, d["index_bits"], nbx * nby, d["base"], ts.word_bits)
    entries = ts.codebook[d["cb_base"] + idx].astype(np.int64)
    if d["layout"] == LAYOUT_CODES["pvr2"]:
        grid = idx[twiddle_indices(nbx, nby)]
        start = d["texel_off"]
        raw = ts.codebook[d["cb_base"] + grid.ravel(), start: start + 2 * bw * bh]
        texels = np.ascontiguousarray(raw).view("<u2").astype(np.int64)
        name = COLORS[d["color"]]
        if name == "yuv422":
            blocks = decode_yuv422_blocks(texels, matrix=ts.matrix)
        else:
            blocks = expand_texels(texels.ravel(), name).reshape(len(texels), bw * bh, 4)
        out = np.ascontiguousarray(blocks.reshape(nby, nbx, bw, bh, 4).transpose(0, 3, 1, 2, 4).reshape(h, w, 4))
        if ts.present_blocks is not None:
            k = twiddle_indices(nbx, nby).ravel()
            gone = ~ts.block_present(np.full(k.shape, tex), np.full(k.shape, level), k).reshape(nby, nbx)
            out[np.repeat(np.repeat(gone, bh, axis=0), bw, axis=1)] = 0
        return out

    def tile(plane, pw, ph, c):
        a = plane.reshape(nby, nbx, ph, pw, c)
        a = np.repeat(np.repeat(a, bh // ph, axis=2), bw // pw, axis=3)
        return a.transpose(0, 2, 1, 3, 4).reshape(h, w, c)

    color = d["color"]
    out = np.zeros((h, w, 4), np.uint8)
    t0 = d["texel_off"]
    if color == COLOR_CODES["yuv411"]:
        cw, ch = max(1, bw >> 1), max(1, bh >> 1)
        y = tile(entries[:, t0: t0 + bw * bh], bw, bh, 1)
        u = tile(entries[:, d["u_off"]: d["u_off"] + cw * ch], cw, ch, 1)
        v = tile(entries[:, d["v_off"]: d["v_off"] + cw * ch], cw, ch, 1)
        out[..., :3] = ts.matrix.apply(np.concatenate([y, u, v], axis=2))
    else:
        c = {COLOR_CODES["rgb"]: 3, COLOR_CODES["rgba"]: 4, COLOR_CODES["intensity"]: 1}[color]
        out[..., :c] = tile(entries[:, t0: t0 + bw * bh * c], bw, bh, c)
        if c == 1:
            out[..., 1] = out[..., 2] = out[..., 0]
    if color != COLOR_CODES["rgba"]:
        out[..., 3] = 255
    if ts.present_blocks is not None:
        k = np.arange(nbx * nby)
        gone = ~ts.block_present(np.full(k.shape, tex), np.full(k.shape, level), k).reshape(nby, nbx)
        out[np.repeat(np.repeat(gone, bh, axis=0), bw, axis=1)] = 0
    return out


def _pruned(ts, seed=0):
    """``ts`` pruned to the blocks of some random requests (blocks and levels absent)."""
    return prune(ts, analyse(ts, [random_requests(ts, 300, seed=seed)], per_frame=False))


def _blocks_dropped(ts, seed=0):
    """``ts`` with a random half of its compressed levels' blocks marked absent (``present_blocks``;
    ``prune`` itself re-packs indices, which a PowerVR2 set's fixed 8-bit maps do not allow)."""
    rows, offsets, nblocks = ts.present_rows()
    n = int((offsets + (nblocks + 7) // 8).max(initial=0))
    bits = np.random.default_rng(seed).integers(0, 256, n).astype(np.uint8)
    out = dataclasses.replace(ts, present_blocks=bits)
    out.validate()
    return out


def _sets():
    yield from ((name, lambda name=name: texture_set(name)) for name in sorted(CONFIGS))
    yield "combined", combined_set
    for name in sorted(pvr2_small_sets()):
        yield f"pvr2 {name}", lambda name=name: pvr2_small_sets()[name]
    yield "pruned combined", lambda: _pruned(combined_set())
    yield "pvr2 blocks dropped", lambda: _blocks_dropped(pvr2_small_sets()["rectangles_and_mip8"], seed=1)
    yield "blocks dropped yuv", lambda: _blocks_dropped(texture_set("yuv_2x4_b12_mip_w64"), seed=2)
    yield "1x1 blocks 1-bit 256x256, 48-byte entries", lambda: big_set(256, seed=3, entry_bytes=48)
    yield "1x1 blocks 1-bit yuv411 64x64", lambda: big_set(64, seed=4, color="yuv411")


SETS = dict(_sets())


@pytest.mark.parametrize("name", sorted(SETS))
def test_banded_decode_equals_the_whole_array_decode(name):
    ts = SETS[name]()
    stored = 0
    for t, L, w, h in levels(ts):
        if not ts.textures[t].stored(L):
            continue
        stored += 1
        want = whole_decode(ts, t, L)
        got = decode(ts, t, L)
        assert got.dtype == np.uint8 and got.shape == (h, w, 4)
        assert np.array_equal(got, want), (t, L)
        for texels in (1, 3 * w, 5 * w + 7):           # one block row a band, and bands of several
            bands = list(decode_bands(ts, t, L, texels))
            assert [j0 for j0, _ in bands] == sorted({j0 for j0, _ in bands}) and bands[0][0] == 0
            assert np.array_equal(np.concatenate([rows for _, rows in bands]), want), (t, L, texels)
    assert stored


def test_fetch_over_every_texel_equals_the_banded_decode():
    ts = big_set(128, seed=5, entry_bytes=48)
    j, i = np.mgrid[0:128, 0:128]
    zero = np.zeros(i.size, np.int64)
    assert np.array_equal(fetch(ts, zero, zero, i.ravel(), j.ravel()).reshape(128, 128, 4), decode(ts, 0, 0))


@pytest.mark.parametrize("b", [1, 3, 7, 12, 16])
@pytest.mark.parametrize("word_bits", [16, 32, 64])
def test_chunked_index_packing_equals_the_whole_array_packing(monkeypatch, b, word_bits):
    rng = np.random.default_rng(b * word_bits)
    n = 1000
    idx = rng.integers(0, 1 << b, n)
    whole = pack_indices(idx, b, word_bits)
    monkeypatch.setattr(fmt, "UNPACK_CHUNK", 64)          # many chunks, each a whole number of bytes
    words = pack_indices(idx, b, word_bits)
    assert words.dtype == whole.dtype and np.array_equal(words, whole)
    assert np.array_equal(unpack_indices(words, b, n, 0, word_bits), _unpack_whole(words, b, n, 0, word_bits))
    assert np.array_equal(unpack_indices(words, b, n, 0, word_bits), idx)
    for first in (0, 1, 63, 64, 333):                    # from any index on, at any bit offset
        assert np.array_equal(unpack_indices(words, b, n - first, 0, word_bits, first=first), idx[first:])


def test_twiddle_band_is_a_slice_of_the_grid():
    for gw, gh in ((8, 8), (16, 4), (2, 32), (1, 1)):
        full = twiddle_indices(gw, gh)
        for y0, y1 in ((0, gh), (1, gh), (0, 1), (gh // 2, gh)):
            assert np.array_equal(twiddle_indices(gw, gh, y0, y1), full[y0:y1])


@pytest.mark.parametrize("name", ["combined", "pvr2 rectangles_and_mip8", "1x1 blocks 1-bit 256x256, 48-byte entries"])
def test_fetch_in_chunks_equals_one_call(monkeypatch, name):
    ts = SETS[name]()
    req = random_requests(ts, 5000, seed=7)
    whole = fetch(ts, *req.T)
    monkeypatch.setattr(fetch_module, "FETCH_CHUNK", 333)        # many chunks, the last one short
    assert np.array_equal(fetch(ts, *req.T), whole)
