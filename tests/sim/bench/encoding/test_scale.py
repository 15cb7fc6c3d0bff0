"""``sim/bench/encoding/scale.py``: the texture it encodes and the shape of its report (the figures
themselves are measured, never asserted)."""

import numpy as np

from vqtex.sim.bench.encoding import scale


def test_texture_is_seeded_and_covers_the_size():
    a, b = scale.texture(600, seed=1), scale.texture(600, seed=1)
    assert a.shape == (600, 600, 3) and a.dtype == np.uint8
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, scale.texture(600, seed=2))
    assert not np.array_equal(a[:88, :88], a[512:, 512:])  # tiles differ by the noise


def test_measure_reports_every_size_and_each_step():
    rep = scale.measure((32, 64), block="4x2", k=16)
    assert [r["size"] for r in rep["sizes"]] == [32, 64]
    assert [r["blocks"] for r in rep["sizes"]] == [32 * 32 // 8, 64 * 64 // 8]
    for r in rep["sizes"]:
        assert r["cpu_s"] > 0 and r["peak_mib"] > 10 and r["wall_s"] >= 0
    assert [(g["from"], g["to"]) for g in rep["growth"]] == [(32, 64)]
