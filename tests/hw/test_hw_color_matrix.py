"""hw.color_matrix.ColorMatrix against golden.color.ColorMatrix.apply and golden.fetch.convert_color."""

import numpy as np
import pytest

from vqtex.golden.color import DREAMCAST_YUV422, JFIF_BT601, ColorMatrix as Spec
from vqtex.golden.fetch import convert_color
from vqtex.golden.format import COLOR_CODES
from vqtex.hw.color_matrix import LATENCY, ColorMatrix
from tests.support import run_lockstep

#: A third matrix: floor, F = 0, odd offsets, big negative coefficients (exercises clamping both ways).
ODD = Spec(coeffs=((3, -2, 1), (-1, 1, 0), (0, 2, -3)), offsets=(17, 200, 0), frac_bits=0, rounding=False)
WIDE = Spec(coeffs=((131071, -131071, 5), (-65536, 1, 2), (7, 8, -9)), offsets=(255, 0, 128), frac_bits=16)


class _FakeSet:
    def __init__(self, matrix):
        self.matrix = matrix


def _inputs(rng, n):
    x = rng.integers(0, 256, (n, 4))
    corners = np.array([[a, b, c, d] for a in (0, 255) for b in (0, 128, 255) for c in (0, 127, 255) for d in (0, 255)])
    return np.concatenate([corners, x]).astype(np.uint8)


def _run(matrix, samples, colors, en_pattern=None):
    dut = ColorMatrix(matrix)
    packed = (samples.astype(np.int64) << (8 * np.arange(4))).sum(axis=1)
    res = run_lockstep(dut, {"samples": packed.tolist(), "color": colors.tolist()}, ["rgba"], LATENCY,
                       en_pattern=en_pattern)
    out = np.array(res["rgba"], dtype=np.int64)
    return ((out[:, None] >> (8 * np.arange(4))) & 0xFF).astype(np.uint8)


@pytest.mark.parametrize("matrix", [JFIF_BT601, DREAMCAST_YUV422, ODD, WIDE],
                         ids=["jfif_bt601", "dreamcast_yuv422", "odd_floor_f0", "wide_18bit"])
def test_matrix_bit_exact(matrix):
    rng = np.random.default_rng(1)
    s = _inputs(rng, 300)
    colors = np.full(len(s), COLOR_CODES["yuv411"])
    out = _run(matrix, s, colors)
    assert np.array_equal(out[:, :3], matrix.apply(s[:, :3]))
    assert (out[:, 3] == 255).all()


def test_bypass_and_mixed_formats_with_holds():
    """Every colour format interleaved, ``en`` dropped at random: convert_color bit for bit."""
    rng = np.random.default_rng(2)
    s = _inputs(rng, 200)
    colors = rng.integers(0, 4, len(s))
    en = rng.random(4 * len(s)) > 0.3
    out = _run(JFIF_BT601, s, colors, en_pattern=en)
    assert np.array_equal(out, convert_color(_FakeSet(JFIF_BT601), colors, s))



def _loadable(matrix):
    from vqtex.golden.geometry import PRESETS
    from vqtex.golden.register_map import RegisterMap
    from vqtex.hw.bus_port import load_layout
    return ColorMatrix(matrix, load=load_layout(RegisterMap(PRESETS["paper"])))


@pytest.mark.parametrize("matrix", [JFIF_BT601, DREAMCAST_YUV422, ODD, WIDE],
                         ids=["jfif_bt601", "dreamcast_yuv422", "odd_floor_f0", "wide_18bit"])
def test_loadable_matrix_initial_contents(matrix):
    """The loadable matrix (products first, K = bias - sum M * off precomputed) holding its initial
    matrix equals golden, with ``en`` dropped at random."""
    rng = np.random.default_rng(3)
    s = _inputs(rng, 150)
    colors = rng.integers(0, 4, len(s))
    packed = (s.astype(np.int64) << (8 * np.arange(4))).sum(axis=1)
    res = run_lockstep(_loadable(matrix), {"samples": packed.tolist(), "color": colors.tolist()}, ["rgba"],
                       LATENCY, en_pattern=rng.random(3 * len(s)) > 0.3)
    out = ((np.array(res["rgba"], dtype=np.int64)[:, None] >> (8 * np.arange(4))) & 0xFF).astype(np.uint8)
    assert np.array_equal(out, convert_color(_FakeSet(matrix), colors, s))


@pytest.mark.parametrize("frac_bits", [1, 3, 8, 11, 15])
def test_loadable_matrix_every_shift(frac_bits):
    """The loaded matrix's stage 3 takes the 8 bits at ``F`` by a window select and the clamp from
    the sign and a mask of the bits at or above ``F + 8``: random coefficients of that scale (sums
    that clamp both ways and land in range), equal to golden."""
    rng = np.random.default_rng(frac_bits)
    scale = 1 << frac_bits
    coeffs = rng.integers(-2 * scale, 2 * scale + 1, (3, 3))
    matrix = Spec(coeffs=tuple(map(tuple, coeffs.tolist())), offsets=tuple(rng.integers(0, 256, 3).tolist()),
                  frac_bits=frac_bits, rounding=bool(frac_bits % 2))
    s = _inputs(rng, 100)
    colors = np.full(len(s), COLOR_CODES["yuv411"])
    packed = (s.astype(np.int64) << (8 * np.arange(4))).sum(axis=1)
    res = run_lockstep(_loadable(matrix), {"samples": packed.tolist(), "color": colors.tolist()}, ["rgba"], LATENCY)
    out = ((np.array(res["rgba"], dtype=np.int64)[:, None] >> (8 * np.arange(4))) & 0xFF).astype(np.uint8)
    want = convert_color(_FakeSet(matrix), colors, s)
    assert np.array_equal(out, want)
    assert {0, 255} <= set(np.unique(want[:, :3])) and len(np.unique(want[:, :3])) > 20


@pytest.mark.parametrize("before,after", [(JFIF_BT601, WIDE), (WIDE, ODD), (ODD, DREAMCAST_YUV422)],
                         ids=["jfif_to_wide", "wide_to_odd", "odd_to_dreamcast"])
def test_loadable_matrix_reloaded(before, after):
    """Every matrix register written through the load command (as the bus port issues it), then 3
    idle cycles (K's pipeline), then a stream: the new matrix's results, bit for bit; read-back of
    every register equals what was written."""
    from amaranth.sim import Simulator
    from vqtex.golden.register_map import CONTROL, REGIONS
    from vqtex.hw.bus_port import ANSWER_LATENCY
    dut = _loadable(before)
    writes = []
    for c in range(3):
        for k in range(3):
            writes.append((CONTROL[f"MATRIX_{'RGB'[c]}{'YUV'[k]}"][0], after.coeffs[c][k] & 0xFFFFFFFF))
    writes += [(CONTROL[f"MATRIX_OFFSET_{'YUV'[k]}"][0], after.offsets[k]) for k in range(3)]
    writes += [(CONTROL["MATRIX_FRAC_BITS"][0], after.frac_bits), (CONTROL["MATRIX_ROUNDING"][0], int(after.rounding))]
    rng = np.random.default_rng(4)
    s = _inputs(rng, 100)
    packed = (s.astype(np.int64) << (8 * np.arange(4))).sum(axis=1)
    out, readback = [], []

    async def bench(ctx):
        ctx.set(dut.load.region, REGIONS["control"])
        for off, value in writes:
            ctx.set(dut.load.write, 1)
            ctx.set(dut.load.offset, off)
            ctx.set(dut.load.data, value)
            await ctx.tick()
        ctx.set(dut.load.write, 0)
        for off, _ in writes:               # the answer is on load_data ANSWER_LATENCY - 1 cycles after the command
            ctx.set(dut.load.read, 1)
            ctx.set(dut.load.offset, off)
            await ctx.tick()
            ctx.set(dut.load.read, 0)
            await ctx.tick().repeat(ANSWER_LATENCY - 2)
            readback.append(ctx.get(dut.load_data) & 0xFFFFFFFF)
        await ctx.tick().repeat(3)
        ctx.set(dut.en, 1)
        ctx.set(dut.color, COLOR_CODES["yuv411"])
        for e in range(len(s) + LATENCY):
            ctx.set(dut.samples.as_value(), int(packed[min(e, len(s) - 1)]))
            await ctx.tick()
            if e + 1 >= LATENCY:
                out.append(ctx.get(dut.rgba.as_value()))

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    got = ((np.array(out[:len(s)], dtype=np.int64)[:, None] >> (8 * np.arange(3))) & 0xFF).astype(np.uint8)
    assert np.array_equal(got, after.apply(s[:, :3]))
    assert readback == [v for _, v in writes]
