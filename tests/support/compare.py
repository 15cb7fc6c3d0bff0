"""Comparing a backend's run with golden's: every field of a SimResult, and the responses against
golden.fetch."""

from __future__ import annotations

import numpy as np

from vqtex.golden.fetch import fetch
from vqtex.hw.texel_fetch import LATENCY, REGISTERS
from vqtex.sim.backends import simulate


def assert_same(a, b, what=""):
    """Two SimResults agree on everything they hold (responses, cycles, stalls, straddles, occupancy)."""
    assert np.array_equal(a.responses, b.responses), f"{what}: responses differ"
    assert a.cycles == b.cycles, f"{what}: cycles {a.cycles} != {b.cycles}"
    assert a.requests == b.requests and a.latency == b.latency, what
    assert a.stall_cycles == b.stall_cycles, f"{what}: {a.stall_cycles} != {b.stall_cycles}"
    assert a.straddles == b.straddles, f"{what}: straddles {a.straddles} != {b.straddles}"
    if a.occupancy is not None and b.occupancy is not None:
        assert a.occupancy.keys() == b.occupancy.keys(), what
        for k in a.occupancy:
            assert abs(a.occupancy[k] - b.occupancy[k]) < 1e-12, f"{what}: occupancy {k}"


def compare_with_golden(ts, req, backend, **kw):
    """``backend`` and golden agree on everything a SimResult holds, the responses equal
    golden.fetch's texels, and every cycle is a transfer, a backpressure stall, a one-port bubble or
    one of the first LATENCY; returns the backend's result."""
    r = simulate(ts, req, backend=backend, **kw)
    g = simulate(ts, req, backend="golden", **kw)
    assert np.array_equal(r.responses, fetch(ts, req[:, 0], req[:, 1], req[:, 2], req[:, 3]))
    assert_same(r, g, backend)
    assert r.occupancy.keys() == g.occupancy.keys() == set(REGISTERS)
    assert r.cycles == len(req) + LATENCY + r.stall_cycles["output_backpressure"] + r.stall_cycles["one_port_straddle"]
    return r
