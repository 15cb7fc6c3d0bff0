"""The Verilator backend's build of the baked texel-fetch unit as its two halves
(``build_verilator(ts, halves=True)``: each half verilated as a model of its own from the fragment the
export instantiates, run by drivers/halves.h as the CXXRTL backend runs its halves) gives the whole
unit's responses, cycles, stall counts, straddles and occupancy, on one thread and on two, and builds
without a Verilator warning."""

import os

import numpy as np
import pytest

from tests.support import assert_same, need, random_requests, shared_cache, texture_sets
from vqtex.sim.backends.cxxrtl import run_batch
from vqtex.sim.backends.interface import simulate


@pytest.fixture(scope="module", autouse=True)
def cache():
    with shared_cache():
        yield


@pytest.fixture(scope="module")
def halves():
    """The mixed set's one-port unit (its front end stalls on straddles: the strobes the front end
    reports) as two Verilator models, and its DesignInfo and Build."""
    need("verilator")
    from vqtex.sim.backends.verilator import open_verilator
    ts = texture_sets()["mixed"]
    lib, info, build = open_verilator(ts, one_port=True, halves=True)
    yield ts, lib, info, build
    lib.close()


@pytest.mark.parametrize("threads", [1, 2])
def test_halves_equal_golden(halves, threads):
    """6000 requests (more than the ring of 4096 link records: the two threads take many turns of
    it) under 40% output backpressure, one thread and two."""
    ts, lib, info, _ = halves
    assert lib.set_threads(threads) == threads
    req = random_requests(ts, 6000, seed=9)
    gold = simulate(ts, req, backend="golden", stall=0.4, seed=4, one_port=True)
    assert gold.stall_cycles["output_backpressure"] > 2000 and gold.stall_cycles["one_port_straddle"] > 0
    assert_same(run_batch(lib, info, req, stall=0.4, seed=4), gold, f"verilator halves, {threads} thread(s)")


def test_halves_equal_whole_export(halves):
    """Back to back, no backpressure: the same as the exported Verilog whole under Verilator."""
    ts, lib, info, _ = halves
    lib.set_threads(1)
    req = random_requests(ts, 3000, seed=2)
    whole = simulate(ts, req, backend="verilator", one_port=True)
    assert_same(run_batch(lib, info, req), whole, "verilator halves against the whole export")
    assert np.array_equal(whole.responses, simulate(ts, req, backend="golden", one_port=True).responses)


def test_halves_build_has_no_warnings(halves):
    """Both models verilated, no warning (as the whole export's build: test_verilog.py); the front
    end's ports through the harness under their C++-friendly names."""
    build = halves[3]
    folder = os.path.dirname(build.library)
    with open(os.path.join(folder, "build.log")) as f:
        log = f.read()
    assert log.count("--prefix Vfront") == 1 and log.count("--prefix Vback") == 1
    assert "%Warning" not in log, [ln for ln in log.splitlines() if "%Warning" in ln][:5]
    with open(os.path.join(folder, "front_harness.v")) as f:
        harness = f.read()
    assert ".i__payload(i_payload)" in harness and "link <= unit_link;" in harness
