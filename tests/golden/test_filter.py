"""golden.filter: the fixed-point footprint against the float formulas, mirror addressing, the
coordinate quantisation's exactness, bilinear sampling."""

import numpy as np
import pytest

from vqtex.golden import filter as fx
from vqtex.golden.render.sampling import Sampler, fold_coordinate

from tests.support import fragments

SHAPES = [[(16, 4), (8, 2), (4, 1), (2, 1), (1, 1)], [(1, 8), (1, 4), (1, 2), (1, 1)], [(32, 32)]]


def _float_reference(table, tex, s, t, lam, mode, a_s, a_t):
    """The footprint from the float coordinates (floor(s W 256) in float64), written independently of
    golden.filter's shifts: the formulas of docs/rendering.md."""
    m = len(tex)
    out_l, out_i, out_j, out_w = (np.zeros((m, 8), np.int64) for _ in range(4))
    for p in range(m):                       # a per-pixel loop: this is the slow reference
        k = tex[p]
        if mode[p] == 0:
            w0, h0 = 1 << table.log2w[k, 0], 1 << table.log2h[k, 0]
            i = int(np.floor(s[p] * w0))
            j = int(np.floor(t[p] * h0))
            taps = [(0, _addr(i, w0, a_s[p]), _addr(j, h0, a_t[p]), 1 << 24)]
        else:
            l0, f = lam[p] >> 8, lam[p] & 255
            if mode[p] == 1:
                f = 0
            l1 = min(l0 + 1, table.last[k])
            taps = []
            for lv, lw in ((l0, 256 - f), (l1, f)):
                w, h = 1 << table.log2w[k, lv], 1 << table.log2h[k, lv]
                u = int(np.floor(s[p] * w * 256)) - 128
                v = int(np.floor(t[p] * h * 256)) - 128
                fu, fv = u & 255, v & 255
                for di, dj, bw in ((0, 0, (256 - fu) * (256 - fv)), (1, 0, fu * (256 - fv)),
                                   (0, 1, (256 - fu) * fv), (1, 1, fu * fv)):
                    taps.append((lv, _addr((u >> 8) + di, w, a_s[p]), _addr((v >> 8) + dj, h, a_t[p]), bw * lw))
            taps = taps[:4] if mode[p] == 1 else taps
        taps += [(taps[0][0], taps[0][1], taps[0][2], 0)] * (8 - len(taps))
        for n, (lv, i, j, w) in enumerate(taps):
            out_l[p, n], out_i[p, n], out_j[p, n], out_w[p, n] = lv, i, j, w
    return out_l, out_i, out_j, out_w


def _addr(i, size, mode):
    if mode == 0:
        return i % size
    if mode == 1:
        return min(max(i, 0), size - 1)
    m = i % (2 * size)
    return m if m < size else 2 * size - 1 - m


def _random_inputs(rng, table, n):
    tex = rng.integers(0, len(table.last), n)
    a_s = rng.integers(0, 3, n)
    a_t = rng.integers(0, 3, n)
    mode = rng.integers(0, 3, n)
    # coordinates on and near texel edges and centres, plus anything in range
    raw = np.concatenate([rng.uniform(-3, 3, n // 2),
                          rng.integers(-512, 512, n - n // 2) / 128 + rng.choice([0, 1e-9, -1e-9], n - n // 2)])
    s = rng.permutation(raw)
    t = rng.permutation(raw)
    sf = fold_coordinate(s, a_s == 0, a_s == 2)
    tf = fold_coordinate(t, a_t == 0, a_t == 2)
    last = table.last[tex]
    lam = np.where(rng.random(n) < 0.3, (rng.integers(0, 8, n) * 256) % (last * 256 + 1),
                   rng.integers(0, 1 << 16, n) % (last * 256 + 1))
    return tex, sf, tf, lam, mode, a_s, a_t


@pytest.mark.parametrize("extra_frac", [0, 3, 12])
def test_footprint_matches_the_float_formulas(extra_frac):
    rng = np.random.default_rng(extra_frac)
    table = fx.LevelTable(SHAPES)
    tex, sf, tf, lam, mode, a_s, a_t = _random_inputs(rng, table, 3000)
    frac = fx.coordinate_frac_bits(table.max_log2) + extra_frac
    got = fx.footprint(table, tex, fx.quantize_coordinate(sf, frac), fx.quantize_coordinate(tf, frac),
                       lam, mode, a_s, a_t, frac)
    want = _float_reference(table, tex, sf, tf, lam, mode, a_s, a_t)
    for g, w, what in zip(got, want, ("level", "i", "j", "weight")):
        assert (g == w).all(), what
    assert (got[3].sum(1) == 1 << 24).all()
    # every slot inside its level
    lw = table.log2w[tex[:, None], got[0]]
    lh = table.log2h[tex[:, None], got[0]]
    assert (got[1] >= 0).all() and (got[1] < (1 << lw)).all() and (got[2] >= 0).all() and (got[2] < (1 << lh)).all()
    # the quantised coordinates fit coordinate_bits signed bits
    q = fx.quantize_coordinate(np.array([-1.0, 2.0, -1.9999, 1.9999]), frac)
    bits = fx.coordinate_bits(frac)
    assert (q >= -(1 << (bits - 1))).all() and (q < (1 << (bits - 1))).all()


def test_mirror_address_is_a_reflection():
    i = np.arange(-40, 40)
    for lg in range(5):
        got = fx.address(i, lg, 2)
        assert [int(v) for v in got] == [_addr(int(v), 1 << lg, 2) for v in i]
    # 0..W-1, W-1..0, 0..W-1 ...
    assert fx.address(np.arange(12), 2, 2).tolist() == [0, 1, 2, 3, 3, 2, 1, 0, 0, 1, 2, 3]
    assert fx.address(np.array([-1, -4, -5]), 2, 2).tolist() == [0, 3, 3]


def test_mirror_fold_keeps_the_texels():
    """A mirrored coordinate and the same plus any multiple of 2 sample the same texels."""
    rng = np.random.default_rng(5)
    s = rng.uniform(-1.99, 1.99, 200)
    shapes = [[(8, 4), (4, 2), (2, 1), (1, 1)]]
    base = Sampler(shapes, ["mirror"], "trilinear")
    d = (0.05, 0.0, 0.0, 0.05)
    ref = base.requests(fragments(s, s[::-1], d=d))
    for k in (1, -3, 1e6):
        got = base.requests(fragments(s + 2 * k, s[::-1] - 2 * k, d=d))
        assert (got == ref).all()
    for bad in (np.inf, -np.inf):
        r = base.requests(fragments([bad], [0.25], d=d))
        assert (r == base.requests(fragments([0.0], [0.25], d=d))).all()
    with pytest.raises(ValueError, match="NaN"):                # a NaN coordinate names no texel
        base.requests(fragments([np.nan], [0.25], d=d))


def test_bilinear_is_trilinear_level_zero_when_magnified():
    rng = np.random.default_rng(2)
    shapes = [[(8, 8), (4, 4), (2, 2), (1, 1)]]
    f = fragments(rng.uniform(-2, 3, 64), rng.uniform(-2, 3, 64), w=8, d=(0.01, 0, 0, 0.01))
    tex = rng.integers(0, 256, (8 * 8 + 16 + 4 + 1, 4), dtype=np.uint8)
    for addr in ("wrap", "clamp", "mirror"):
        tri = Sampler(shapes, [addr], "trilinear", stream="fixed")
        bil = Sampler(shapes, [addr], "bilinear", stream="fixed")
        rt, rb = tri.requests(f).reshape(-1, 8, 4), bil.requests(f).reshape(-1, 4, 4)
        assert bil.requests_per_pixel == 4
        assert (rt[:, :4] == rb).all()

        def texels(r):
            lw = np.array([8, 4, 2, 1])
            base = np.array([0, 64, 80, 84])
            return tex[base[r[:, 1]] + r[:, 3] * lw[r[:, 1]] + r[:, 2]]
        frame = tri.resolve(texels(rt.reshape(-1, 4)))
        assert (frame == bil.resolve(texels(rb.reshape(-1, 4)))).all()
        # the sparse streams (the default) of both modes: the same frame from fewer requests
        for mode in ("bilinear", "trilinear"):
            sp = Sampler(shapes, [addr], mode)
            rs = sp.requests(f)
            assert len(rs) <= len(f.s) * sp.requests_per_pixel
            assert (sp.resolve(texels(rs)) == frame).all()


def test_filter_inputs_and_place_give_the_frame():
    """The RTL's per-pixel inputs through golden.filter (footprint, then blend), placed, are the
    frame requests() + resolve() make, at any number of fractional bits."""
    rng = np.random.default_rng(3)
    shapes = [[(16, 4), (8, 2), (4, 1), (2, 1), (1, 1)]]
    f = fragments(rng.uniform(-3, 3, 40), rng.uniform(-3, 3, 40), w=8, d=(0.3, 0.1, 0.0, 0.2))
    pyr = rng.integers(0, 256, (64 + 16 + 4 + 2 + 1, 4), dtype=np.uint8)
    base = np.array([0, 64, 80, 84, 86])
    widths = np.array([16, 8, 4, 2, 1])
    for mode in fx.MODES:
        for addr in (("wrap", "mirror"), ("clamp", "wrap"), ("mirror", "clamp")):
            sm = Sampler(shapes, [addr], mode)
            r = sm.requests(f)
            frame = sm.resolve(pyr[base[r[:, 1]] + r[:, 3] * widths[r[:, 1]] + r[:, 2]])
            for frac in (sm.frac, 20):
                p = sm.filter_inputs(f, frac)
                lv, i, j, w = fx.footprint(sm.levels, p["texture"], p["s"], p["t"], p["lod"], p["mode"],
                                           p["address_s"], p["address_t"], frac)
                colors = fx.blend(w, pyr[base[lv] + j * widths[lv] + i])
                assert (sm.place(colors) == frame).all()
    with pytest.raises(ValueError):
        sm.filter_inputs(f, sm.frac - 1)


def test_footprint_rejects_bad_inputs():
    table = fx.LevelTable([[(4, 4), (2, 2), (1, 1)]])
    ok = dict(tex=[0], s_q=[0], t_q=[0], lam=[512], mode=[2], address_s=[0], address_t=[0], frac=10)
    fx.footprint(table, **ok)
    for k, v in (("lam", [513]), ("lam", [-1]), ("mode", [3]), ("address_t", [3]), ("frac", 9)):
        with pytest.raises(ValueError):
            fx.footprint(table, **{**ok, k: v})
