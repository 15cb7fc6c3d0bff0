"""The specialised TexelFetch (hw.features): what each texture set needs, what the elaborated unit
then holds (and does not), and bit-exactness against golden on pysim for small cases, specialised
and full. The compiled backend runs every configuration in tests/sim/backends/test_specialised.py."""

import functools

import numpy as np
import pytest
from amaranth.back import rtlil

from tests import support
from tests.support import compare_with_golden, image
from vqtex.golden.encode import encode
from vqtex.golden.format import TextureSet
from vqtex.hw.features import READ_BY, Features
from vqtex.hw.memories import elaborate, memories
from vqtex.hw.texel_fetch import LATENCY, TexelFetch


@functools.lru_cache(maxsize=None)
def three_widths() -> TextureSet:
    """rgb 8-bit (mipmapped), intensity 12-bit, rgba 6-bit, 32-bit words: three index widths (k*b as
    shifts and adds selected by b), straddles, raw levels, three colour formats, no yuv411."""
    return TextureSet.combine([
        encode([image((64, 64), 20, 3)], block=(4, 4), codebook_size=16, color="rgb", index_bits=8,
               mipmaps=True, raw_below=4, seed=1),
        encode([image((32, 32), 21, 1)], block=(2, 2), codebook_size=12, color="intensity", index_bits=12, seed=2),
        encode([image((32, 32), 22, 4)], block=(4, 2), codebook_size=8, color="rgba", index_bits=6, seed=3),
    ])


@functools.lru_cache(maxsize=None)
def two_widths_no_straddle() -> TextureSet:
    """rgb 8-bit and rgb 16-bit indices in 32-bit words, no mipmaps: two widths that both divide the
    word (one bank, the mask), one colour, no raw levels."""
    return TextureSet.combine([
        encode([image((32, 32), 23, 3)], block=(4, 4), codebook_size=16, color="rgb", index_bits=8, seed=4),
        encode([image((64, 32), 24, 3)], block=(2, 2), codebook_size=16, color="rgb", index_bits=16, seed=5),
    ])


#: name -> (texture set, what the specialised unit must be): the configurations of the issue (rgb-only
#: 8-bit, intensity, yuv411, rgba, 12-bit straddling, mixed raw/compressed, no mipmaps, mipmaps).
CASES = {
    "rgb8_no_mip": (lambda: support.texture_set("rgb_4x4_b8_k256"),
                    dict(colors={"rgb"}, widths=(8,), straddle=False, raw=False, matrix=False, sublevels=False)),
    "rgb8_mip": (lambda: support.texture_set("rgb_4x4_b8_mip"),
                 dict(colors={"rgb"}, widths=(8,), straddle=False, raw=True, matrix=False, sublevels=True)),
    "intensity_b5_w64": (lambda: support.texture_set("i8_4x2_b5_w64"),
                         dict(colors={"intensity"}, widths=(5,), straddle=True, raw=False, matrix=False)),
    "yuv_dreamcast_b12_mip": (lambda: support.texture_set("yuv_dreamcast_4x4_b12_mip"),
                              dict(colors={"yuv411"}, widths=(12,), straddle=True, raw=True, matrix=True)),
    "yuv_jfif_b12_mip": (lambda: support.texture_set("yuv_4x4_b12_mip"),
                         dict(colors={"yuv411"}, widths=(12,), straddle=True, raw=True, matrix=True)),
    "rgba_b7_mip_w16": (lambda: support.texture_set("rgba_2x2_b7_mip_w16"),
                        dict(colors={"rgba"}, widths=(7,), straddle=True, raw=True, matrix=False)),
    "rgb12_w16": (lambda: support.texture_set("rgb_4x4_b12_w16"),
                  dict(colors={"rgb"}, widths=(12,), straddle=True, raw=False, matrix=False)),
    "raw_only": (lambda: support.texture_set("raw_only_8x8_mip"),
                 dict(colors=set(), widths=(), straddle=False, raw=True, matrix=False, compressed=False)),
    "three_widths": (three_widths, dict(colors={"rgb", "intensity", "rgba"}, widths=(6, 8, 12), straddle=True,
                                        raw=True, matrix=False)),
    "two_widths_no_straddle": (two_widths_no_straddle, dict(colors={"rgb"}, widths=(8, 16), straddle=False,
                                                            raw=False, matrix=False)),
    "combined": (support.combined_set, dict(colors={"rgb", "rgba", "intensity", "yuv411"}, widths=(5, 7, 8, 12),
                                            straddle=True, raw=True, matrix=True)),
}


def _requests(ts, n, seed):
    return np.concatenate([support.random_requests(ts, n, seed=seed), support.adversarial_requests(ts, seed=seed + 1)])


@pytest.mark.parametrize("name", CASES)
def test_features_of_each_configuration(name):
    make, want = CASES[name]
    f = Features.of(make())
    assert f.specialised and f.colors == frozenset(want["colors"]) and f.index_widths == want["widths"]
    assert (f.straddle, f.raw, f.matrix) == (want["straddle"], want["raw"], want["matrix"])
    assert f.compressed == want.get("compressed", True)
    if "sublevels" in want:
        assert f.sublevels == want["sublevels"]
    # every field the hardware reads is a constant or a stored column, never both
    assert set(f.stored_fields).isdisjoint(f.constants) and set(f.stored_fields) | set(f.constants) == set(READ_BY)


def test_features_straddle_is_exact():
    """Straddling decided per map: 12-bit indices straddle in 32-bit words once a map has 3 indices,
    16-bit ones never do in 16-bit words, 5-bit ones do in 64-bit words."""
    assert Features.of(support.texture_set("rgb_4x4_b12_w16")).straddle
    assert not Features.of(support.texture_set("rgb_2x2_b16_w16")).straddle
    assert not Features.of(support.texture_set("i8_4x4_b1_mip")).straddle
    full = Features.full(support.combined_set())
    assert not full.specialised and full.straddle and full.matrix and full.index_widths == tuple(range(1, 17))
    assert full.stored_fields == tuple(support.combined_set().descriptors.dtype.names)


def _cells(top, kind):
    return rtlil.convert(top, emit_src=False).count(f"cell ${kind} ")


def _memory_names(top):
    return {" ".join(m.path) for m in memories(elaborate(top))}


def test_rgb8_unit_has_no_multiplier_no_odd_bank_no_raw_memory():
    ts = support.texture_set("rgb_4x4_b8_k256")
    spec, full = TexelFetch(ts), TexelFetch(ts, specialise=False)
    assert _cells(spec, "mul") == 0 and _cells(full, "mul") == 10       # k*b and nine colour products
    names = _memory_names(TexelFetch(ts))
    assert not any("odd_bank" in n or "even_bank" in n for n in names)  # one index bank
    assert not any("raw" in n for n in names)
    assert not any("descriptor" in n for n in names)                    # every descriptor field constant
    assert any(n.startswith("front index_reader memory") for n in names)
    assert {"front index_reader even_bank bank0", "back codebook_rom raw bank0",
            "front descriptor table"} <= _memory_names(TexelFetch(ts, specialise=False))
    assert spec.latency == full.latency == LATENCY


def test_matrix_products_only_for_nonzero_coefficients_and_no_multiplier_for_powers_of_two():
    """Dreamcast YUV422: 64 (three times, a shift), 0 (twice, nothing), 88, -22, -44, 110 (four
    products); and k*b with b = 12 as shifts and adds: four multipliers in all."""
    ts = support.texture_set("yuv_dreamcast_4x4_b12_mip")
    assert _cells(TexelFetch(ts), "mul") == 4
    jfif = support.texture_set("yuv_4x4_b12_mip")           # 4096 x3, 0 x2, four others
    assert _cells(TexelFetch(jfif), "mul") == 4
    assert _cells(TexelFetch(support.combined_set()), "mul") == 5   # four widths: k*b is a multiplier


def test_link_and_descriptor_narrower_when_specialised():
    from vqtex.hw.pipeline import LinkLayout
    ts = support.texture_set("rgb_4x4_b8_mip")
    spec, full = Features.of(ts), Features.full(ts)
    assert LinkLayout(ts, spec).size < LinkLayout(ts, full).size
    assert LinkLayout(ts).size == LinkLayout(ts, full).size
    assert spec.index_bits == 8 and full.index_bits == 16


@pytest.mark.parametrize("name", ["rgb8_no_mip", "rgb8_mip", "intensity_b5_w64", "yuv_dreamcast_b12_mip",
                                  "rgba_b7_mip_w16", "raw_only", "three_widths", "two_widths_no_straddle"])
def test_pysim_specialised_bit_exact_with_backpressure(name):
    ts = CASES[name][0]()
    req = _requests(ts, 120, seed=31)
    compare_with_golden(ts, req, "pysim", stall=0.3, seed=7)


@pytest.mark.parametrize("one_port", [False, True], ids=["two_bank", "one_port"])
@pytest.mark.parametrize("name", ["three_widths", "rgb8_mip"])
def test_pysim_full_and_specialised_agree_cycle_for_cycle(name, one_port):
    """Same responses and cycle counts (straddles, one-port bubbles, occupancy) from both units."""
    ts = CASES[name][0]()
    req = _requests(ts, 100, seed=41)
    full = compare_with_golden(ts, req, "pysim", stall=0.25, seed=9, one_port=one_port, specialise=False)
    spec = compare_with_golden(ts, req, "pysim", stall=0.25, seed=9, one_port=one_port)
    support.assert_same(spec, full, f"{name} specialised vs full")


def test_small_banks_specialised():
    """The specialised unit with many small banks (one index bank when nothing straddles)."""
    from vqtex.sim.backends import pysim as pysim_backend
    from vqtex.sim.backends.interface import simulate
    for name in ("two_widths_no_straddle", "three_widths"):
        ts = CASES[name][0]()
        req = _requests(ts, 100, seed=51)
        p = pysim_backend.run(ts, req, stall=0.3, seed=5, bank_depth=8)
        g = simulate(ts, req, backend="golden", stall=0.3, seed=5)
        support.assert_same(p, g, name)
