"""The specialised TexelFetch (hw.features): what each texture set needs, what the elaborated unit
then holds (and does not), and bit-exactness against golden on pysim for small cases, specialised
and full. The compiled backend runs every configuration in tests/sim/backends/test_specialised.py."""

import numpy as np
import pytest
from amaranth.back import rtlil

from tests import support
from tests.support import SPECIALISE_CASES, compare_with_golden
from vqtex.hw.features import READ_BY, Features
from vqtex.hw.memories import elaborate, memories
from vqtex.hw.texel_fetch import LATENCY, TexelFetch


def _requests(ts, n, seed):
    return np.concatenate([support.random_requests(ts, n, seed=seed), support.adversarial_requests(ts, seed=seed + 1)])


@pytest.mark.parametrize("name", SPECIALISE_CASES)
def test_features_of_each_configuration(name):
    make, want = SPECIALISE_CASES[name]
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
    ts = SPECIALISE_CASES[name][0]()
    req = _requests(ts, 120, seed=31)
    compare_with_golden(ts, req, "pysim", stall=0.3, seed=7)


@pytest.mark.parametrize("one_port", [False, True], ids=["two_bank", "one_port"])
@pytest.mark.parametrize("name", ["three_widths", "rgb8_mip"])
def test_pysim_full_and_specialised_agree_cycle_for_cycle(name, one_port):
    """Same responses and cycle counts (straddles, one-port bubbles, occupancy) from both units."""
    ts = SPECIALISE_CASES[name][0]()
    req = _requests(ts, 100, seed=41)
    full = compare_with_golden(ts, req, "pysim", stall=0.25, seed=9, one_port=one_port, specialise=False)
    spec = compare_with_golden(ts, req, "pysim", stall=0.25, seed=9, one_port=one_port)
    support.assert_same(spec, full, f"{name} specialised vs full")


def test_small_banks_specialised():
    """The specialised unit with many small banks (one index bank when nothing straddles)."""
    from vqtex.sim.backends import pysim as pysim_backend
    from vqtex.sim.backends.interface import simulate
    for name in ("two_widths_no_straddle", "three_widths"):
        ts = SPECIALISE_CASES[name][0]()
        req = _requests(ts, 100, seed=51)
        p = pysim_backend.run(ts, req, stall=0.3, seed=5, bank_depth=8)
        g = simulate(ts, req, backend="golden", stall=0.3, seed=5)
        support.assert_same(p, g, name)
