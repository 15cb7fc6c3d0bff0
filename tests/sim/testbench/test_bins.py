"""The testbench's coverage model (sim/testbench/bins.py) against a brute-force count: every texel of
every stored level of the three sets the cocotb tests run (8-bit, 12-bit straddling yuv411,
PowerVR2) and a combined set, through ``request_bins``; ``candidates`` must find exactly those bins,
and every candidate request must be in its bin."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support import combined_set, levels, pvr2_small_sets, texture_set
from vqtex.sim.testbench.bins import bin_name, candidates, reachable, request_bins

SETS = {"rgb8": lambda: texture_set("rgb_4x4_b8_mip"), "yuv12": lambda: texture_set("yuv_4x4_b12_mip"),
        "pvr2": lambda: pvr2_small_sets()["rectangles_and_mip8"], "combined": combined_set,
        "w64": lambda: texture_set("yuv_2x4_b12_mip_w64")}


def _every_texel(ts) -> np.ndarray:
    parts = []
    for t, L, w, h in levels(ts):
        jj, ii = np.mgrid[0:h, 0:w]
        parts.append(np.stack([np.full(w * h, t), np.full(w * h, L), ii.ravel(), jj.ravel()], 1))
    return np.concatenate(parts).astype(np.int64)


@pytest.mark.parametrize("name", sorted(SETS))
def test_candidates_are_exactly_the_bins_of_every_texel(name):
    ts = SETS[name]()
    every = set(request_bins(ts, _every_texel(ts)))
    cands = candidates(ts)
    assert set(cands) == every
    for key, req in cands.items():
        assert set(request_bins(ts, req)) == {key}, key
    assert reachable(ts) == {(*k, s) for k in every for s in (False, True)}


def test_the_bins_name_the_paths():
    """The 12-bit set straddles (and has aligned indices too), three sub-levels and raw levels; the
    8-bit one never straddles a 32-bit word; PowerVR2 formats are their own colour bins."""
    y12 = set(candidates(texture_set("yuv_4x4_b12_mip")))
    assert {k[2] for k in y12 if k[0] == "yuv411"} == {False, True}
    assert {k[3] for k in y12} == {"sub0", "sub1", "sub2", "raw"}
    assert ("raw", 0, False, "raw") in y12
    b8 = set(candidates(texture_set("rgb_4x4_b8_mip")))
    assert not any(k[2] for k in b8) and {k[1] for k in b8} == {0, 8}
    pvr = set(candidates(pvr2_small_sets()["rectangles_and_mip8"]))
    assert {k[0] for k in pvr} == {"argb1555", "rgb565", "argb4444", "yuv422"}
    assert bin_name(("yuv411", 12, True, "sub0", True)) == "yuv411/b12/straddle/sub0/stall"
