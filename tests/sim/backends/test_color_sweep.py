"""All 2^24 (Y, U, V) inputs through the compiled RTL colour matrix equal golden's RGB, for every
matrix the project ships and a random one per run; golden within its bound of float64 everywhere."""

import os
import time

import numpy as np
import pytest

from tests.support import need
from vqtex.golden.color import DREAMCAST_YUV422, JFIF_BT601, ColorMatrix
from vqtex.sim.backends.color_sweep import golden_check, random_matrix, rtl_outputs

#: A new random parameterisation every run; VQTEX_SEED=N repeats one (the seed is in every message).
SEED = int(os.environ.get("VQTEX_SEED", time.time_ns() % 2**31))


@pytest.mark.parametrize("name", ["jfif_bt601", "dreamcast_yuv422", "random"])
def test_rtl_colour_matrix_equals_golden_on_every_input(name):
    need("g++")
    matrix = {"jfif_bt601": JFIF_BT601, "dreamcast_yuv422": DREAMCAST_YUV422}.get(name) or random_matrix(SEED)
    rtl, timing = rtl_outputs(matrix)
    rep = golden_check(matrix, rtl)
    assert timing["clocks"] >= rep["inputs"]
    assert rep["mismatches"] == 0, f"seed {SEED}: {rep['mismatches']} inputs differ, first {rep['first_mismatch']}"
    assert rep["within_bound"], f"seed {SEED}: golden {rep['worst_error']} from float64, bound {rep['error_bound']}"
    if name != "random":        # the shipped matrices clamp at both ends in every channel
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
