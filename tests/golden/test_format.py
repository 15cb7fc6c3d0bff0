"""golden.format: bit packing, descriptors, the .vqt container and its rejection of damaged files."""

import numpy as np
import pytest

from vqtex.golden.encode import encode
from vqtex.golden.format import (FormatError, TextureSet, entry_layout, pack_indices, sub_levels,
                           unpack_indices)


@pytest.mark.parametrize("word_bits", [16, 32, 64])
@pytest.mark.parametrize("b", range(1, 17))
def test_pack_every_width_every_straddle_position(b, word_bits):
    # Enough indices that index k starts at every bit offset 0..word_bits-1 (k*b mod W covers all
    # multiples of gcd(b, W)), with values exercising every bit.
    n = 2 * word_bits + 3
    rng = np.random.default_rng(b * 100 + word_bits)
    idx = rng.integers(0, 1 << b, n)
    idx[:2] = [(1 << b) - 1, 0]
    words = pack_indices(idx, b, word_bits)
    assert words.dtype == np.dtype(f"<u{word_bits // 8}")
    assert len(words) == -(-n * b // word_bits)
    # Reference: a Python big integer holding the little-endian bit stream.
    stream = sum(int(v) << (k * b) for k, v in enumerate(idx))
    assert int.from_bytes(words.tobytes(), "little") == stream
    assert (unpack_indices(words, b, n, 0, word_bits) == idx).all()
    # Every straddle position occurs: offsets seen are all multiples of gcd(b, W).
    offs = {(k * b) % word_bits for k in range(n)}
    g = np.gcd(b, word_bits)
    assert offs == set(range(0, word_bits, g))


def test_pack_rejects_too_wide_index():
    with pytest.raises(FormatError):
        pack_indices(np.array([256]), 8)
    with pytest.raises(FormatError):
        pack_indices(np.array([1]), 17)


def test_sub_levels_and_layout():
    assert sub_levels(4, 4) == 3 and sub_levels(2, 2) == 2 and sub_levels(4, 1) == 1
    assert sub_levels(8, 8) == 3 and sub_levels(4, 2) == 2
    lay = entry_layout("rgb", 4, 4, 3)
    assert lay.planes == ((0, 0, 0), (48, 0, 0), (60, 0, 0)) and lay.size == 63
    yuv = entry_layout("yuv411", 4, 4, 3)
    # 4x4: 16 Y + 4 U + 4 V; 2x2: 4 Y + 1 U + 1 V; 1x1: 1 Y + 1 U + 1 V
    assert yuv.planes == ((0, 16, 20), (24, 28, 29), (30, 31, 32)) and yuv.size == 33
    assert entry_layout("yuv411", 2, 2, 1).size == 6          # the paper's halving: 6 bytes vs 12


def _small_set():
    rng = np.random.default_rng(3)
    a = rng.integers(0, 256, (64, 64, 3), dtype=np.uint8)
    b = rng.integers(0, 256, (32, 64, 4), dtype=np.uint8)
    s1 = encode([a], codebook_size=16, mipmaps=True, raw_below=8, encoder="tsvq")
    s2 = encode([b], codebook_size=8, color="rgba", block=(2, 2), index_bits=5, encoder="tsvq")
    return TextureSet.combine([s1, s2])


def test_container_round_trip(tmp_path):
    ts = _small_set()
    path = tmp_path / "set.vqt"
    ts.save(path)
    back = TextureSet.load(path)
    assert back == ts
    assert back.to_bytes() == path.read_bytes()
    for name in ("index_words", "codebook", "raw_words", "descriptors"):
        assert np.array_equal(getattr(back, name), getattr(ts, name))
    assert [t.to_dict() for t in back.textures] == [t.to_dict() for t in ts.textures]
    assert back.matrix == ts.matrix


def test_container_rejects_damage(tmp_path):
    data = _small_set().to_bytes()
    cases = {
        "empty": b"",
        "truncated": data[: len(data) // 2],
        "one byte short": data[:-1],
        "foreign": b"\x89PNG\r\n\x1a\n" + data[8:],
        "bit flip in body": data[:100] + bytes([data[100] ^ 1]) + data[101:],
        "bit flip in checksum": data[:-1] + bytes([data[-1] ^ 0x80]),
        "future version": data[:8] + (99).to_bytes(4, "little") + data[12:],
    }
    for name, bad in cases.items():
        with pytest.raises(FormatError):
            TextureSet.from_bytes(bad)
        p = tmp_path / f"{name}.vqt"
        p.write_bytes(bad)
        with pytest.raises(FormatError):
            TextureSet.load(p)
    with pytest.raises(FormatError):
        TextureSet.load(tmp_path / "missing.vqt")


def test_container_rejects_inconsistent_descriptor():
    """A file whose checksum is right but whose descriptor points outside memory is rejected."""
    import json, struct, zlib
    from vqtex.golden.format import MAGIC
    ts = _small_set()
    ts.descriptors["base"][0, 0] = 10 ** 6
    body = ts.to_bytes()[:-4]
    with pytest.raises(FormatError, match="runs past"):
        TextureSet.from_bytes(body + struct.pack("<I", zlib.crc32(body)))


def test_paper_rates():
    """512x512 RGB, 4x4 blocks, 256 codewords: base 48:1, overall 27.4:1; 2x2 blocks: base 12:1."""
    rng = np.random.default_rng(0)
    img = rng.integers(0, 256, (512, 512, 3), dtype=np.uint8)
    ts = encode([img], block=(4, 4), codebook_size=256, encoder="tsvq")
    r = ts.rates(0)
    assert r["base"] == pytest.approx(48.0)
    assert round(r["overall"], 1) == 27.4
    ts2 = encode([img[:64, :64]], block=(2, 2), codebook_size=256, encoder="tsvq")
    assert ts2.rates(0)["base"] == pytest.approx(12.0)
    # 12-bit indices: 4x4 RGB at 32:1 base
    ts3 = encode([img[:64, :64]], codebook_size=256, index_bits=12, encoder="tsvq")
    assert ts3.rates(0)["base"] == pytest.approx(32.0)


def test_container_rejects_index_past_codebook():
    """Checksum right, descriptors in range, but an index names a codeword the codebook lacks."""
    import struct, zlib
    rng = np.random.default_rng(1)
    ts = encode([rng.integers(0, 256, (32, 32, 3), dtype=np.uint8)], codebook_size=8, index_bits=5,
                encoder="tsvq")
    TextureSet.from_bytes(ts.to_bytes())                        # fine as made
    ts.index_words[0] |= 31                                     # index 0 := 31 (codebook has 8)
    body = ts.to_bytes()[:-4]
    with pytest.raises(FormatError, match="past codebook"):
        TextureSet.from_bytes(body + struct.pack("<I", zlib.crc32(body)))
