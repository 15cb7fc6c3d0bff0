"""All 2^24 (Y, U, V) inputs through the compiled RTL colour matrix equal golden's RGB, for every
matrix the project ships, the widest parameterisation the unit takes and a random one per run; golden
within its bound of float64 everywhere; the outputs clamp at both ends."""

import os
import time

import numpy as np
import pytest

from tests.support import need, shared_cache_dir
from vqtex.golden.color import DREAMCAST_YUV422, JFIF_BT601, ColorMatrix
from vqtex.sim.backends.color_sweep import extreme_matrix, golden_check, random_matrix, rtl_outputs

#: A new random parameterisation every run; VQTEX_SEED=N repeats one (the seed is in every message).
SEED = int(os.environ.get("VQTEX_SEED", time.time_ns() % 2**31))
MATRICES = {"jfif_bt601": lambda: JFIF_BT601, "dreamcast_yuv422": lambda: DREAMCAST_YUV422,
            "extreme": extreme_matrix, "random": lambda: random_matrix(SEED)}


@pytest.fixture(scope="module", autouse=True)
def cache():
    """The builds go to the suite's shared cache (kept between runs, like the unit's)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("VQTEX_CACHE", shared_cache_dir())
        yield


@pytest.mark.parametrize("name", list(MATRICES))
def test_rtl_colour_matrix_equals_golden_on_every_input(name):
    need("g++")
    matrix = MATRICES[name]()
    rtl, timing = rtl_outputs(matrix)
    rep = golden_check(matrix, rtl)
    assert timing["clocks"] >= rep["inputs"] == 1 << 24
    assert rep["mismatches"] == 0, f"seed {SEED}: {rep['mismatches']} inputs differ, first {rep['first_mismatch']}"
    assert rep["within_bound"], f"seed {SEED}: golden {rep['worst_error']} from float64, bound {rep['error_bound']}"
    if name != "random":        # these clamp at both ends in every channel
        assert min(rep["clamped_at_0"]) > 0 and min(rep["clamped_at_255"]) > 0


def test_the_sweep_sees_a_one_coefficient_change():
    """Negative control: golden with one coefficient off by one disagrees with the RTL somewhere."""
    need("g++")
    rtl, _ = rtl_outputs(JFIF_BT601)
    coeffs = np.array(JFIF_BT601.coeffs)
    coeffs[1, 2] += 1
    altered = ColorMatrix(coeffs=coeffs, offsets=JFIF_BT601.offsets, frac_bits=JFIF_BT601.frac_bits,
                          rounding=JFIF_BT601.rounding)
    assert golden_check(altered, rtl)["mismatches"] > 0


def test_random_parameterisations_are_all_valid():
    """random_matrix covers the unit's whole coefficient range and never draws an invalid matrix (a
    run's seed must never fail to build): seed 84157 drew -2^17, which golden once rejected."""
    drawn = [random_matrix(s) for s in (84157, *range(2000))]
    coeffs = np.array([m.coeffs for m in drawn])
    assert coeffs.min() == -(1 << 17) and coeffs.max() > (1 << 16)
    assert {m.frac_bits for m in drawn} == set(range(17)) and {m.rounding for m in drawn} == {False, True}
