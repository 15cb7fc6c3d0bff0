"""Property tests (hypothesis) of the format's arithmetic: bit packing for every width, word width
and straddle; the container round trip; fetch equal to decode; request checks."""

import numpy as np
from hypothesis import given, settings, strategies as st

from vqtex.golden.encode import encode
from vqtex.golden.fetch import RequestError, check_requests, decode, fetch
from vqtex.golden.format import TextureSet, pack_indices, unpack_indices


@given(st.integers(1, 16), st.sampled_from([16, 32, 64]), st.integers(0, 200), st.integers(0, 2**32 - 1),
       st.integers(0, 40))
def test_pack_unpack_every_width_and_straddle(b, word_bits, n, seed, start):
    idx = np.random.default_rng(seed).integers(0, 1 << b, n)
    words = pack_indices(idx, b, word_bits)
    assert len(words) == -(-n * b // word_bits) and words.dtype.itemsize * 8 == word_bits
    assert np.array_equal(unpack_indices(words, b, n, 0, word_bits), idx)
    # a map that starts at any word: index k at bits [k b, k b + b) from that word
    padded = np.concatenate([np.full(start, 0xFFFF, words.dtype), words])
    assert np.array_equal(unpack_indices(padded, b, n, start, word_bits), idx)
    # every bit of the stream, read back one index at a time across word boundaries
    bits = np.unpackbits(words.view(np.uint8), bitorder="little")
    for k in range(min(n, 8)):
        assert int((bits[k * b:(k + 1) * b].astype(np.int64) << np.arange(b)).sum()) == idx[k]


def _small_set(seed, color, block, k, bits, word_bits, mip):
    rng = np.random.default_rng(seed)
    c = {"rgb": 3, "yuv411": 3, "rgba": 4, "intensity": 1}[color]
    img = rng.integers(0, 256, (32, 32, c)).astype(np.uint8)
    return encode([img], block=block, codebook_size=k, color=color, index_bits=bits, word_bits=word_bits,
                  mipmaps=mip, seed=seed, raw_below=4 if mip else 32)


_sets = st.builds(_small_set, st.integers(0, 1000), st.sampled_from(["rgb", "rgba", "intensity", "yuv411"]),
                  st.sampled_from([(2, 2), (4, 4), (4, 2)]), st.integers(2, 16), st.integers(4, 16),
                  st.sampled_from([16, 32, 64]), st.booleans())


@settings(max_examples=25)
@given(_sets)
def test_round_trip_and_fetch_equals_decode(ts):
    back = TextureSet.from_bytes(ts.to_bytes())
    assert back == ts
    for L, (w, h) in enumerate(back.level_shapes(0)):
        jj, ii = np.mgrid[0:h, 0:w]
        got = fetch(back, 0, L, ii.ravel(), jj.ravel()).reshape(h, w, 4)
        assert np.array_equal(got, decode(back, 0, L))


@settings(max_examples=25)
@given(_sets, st.lists(st.tuples(st.integers(-2, 2), st.integers(-2, 17), st.integers(-40, 40),
                                 st.integers(-40, 40)), min_size=1, max_size=20))
def test_check_requests_accepts_exactly_the_texels_inside(ts, reqs):
    req = np.array(reqs)
    shapes = {L: s for L, s in enumerate(ts.level_shapes(0))}
    inside = [t == 0 and L in shapes and 0 <= i < shapes[L][0] and 0 <= j < shapes[L][1] for t, L, i, j in reqs]
    try:
        check_requests(ts, req[:, 0], req[:, 1], req[:, 2], req[:, 3])
        accepted = True
    except RequestError as e:
        accepted = False
        assert "\n" not in str(e)
    assert accepted == all(inside)
