"""Comparing a backend's run with golden's: every field of a SimResult, and the responses against
golden.fetch."""

from __future__ import annotations

import numpy as np

from vqtex.golden.fetch import fetch, random_requests
from vqtex.golden.memory.timing import plan, run
from vqtex.hw.texel_fetch import LATENCY, REGISTERS
from vqtex.sim.backends import simulate
from vqtex.sim.streams import ready_pattern


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


def locality_stream(ts, n: int, seed: int) -> np.ndarray:
    """``n`` random requests with locality (runs of one request, 1-4 long): what a cache sees."""
    rng = np.random.default_rng(seed)
    req = random_requests(ts, n // 3, seed=seed)
    return np.repeat(req, rng.integers(1, 5, len(req)), axis=0)[:n]


def assert_cached_run(got: dict, ts, req, cfg, stall: float, seed: int, layout=None) -> dict:
    """A traced run of the cached unit (``sim.backends.memory``: ``trace=True``) equals golden in
    everything: responses (golden.fetch), every acceptance, every AR's cycle and address, every
    transfer, the cycles, backpressure and fill waits of ``golden.memory.timing.run`` under the
    same ready pattern. ``layout``: where the set sits (``Layout.of(ts)`` when None). Returns the
    model's dict."""
    assert (got["responses"] == fetch(ts, *np.asarray(req).T)).all()
    p = plan(ts, req, cfg, **({} if layout is None else {"layout": layout}))
    model = run(p, cfg, LATENCY, lambda m: ready_pattern(seed, stall, m))
    assert (got["accept"] == model["accept"]).all()
    ar = np.repeat(model["tag"], p.misses) + 1 + np.concatenate([np.arange(m) for m in p.misses.tolist()] or [[]])
    assert got["ar"] == ar.astype(np.int64).tolist()
    assert got["addresses"].tolist() == p.address.tolist()
    assert (got["transfer"] == model["transfer"]).all()
    assert got["cycles"] == model["cycles"]
    assert got["backpressure"] == model["stall_cycles"]["output_backpressure"]
    assert got["fill_waits"] == model["stall_cycles"]["miss"] + model["stall_cycles"]["bandwidth"]
    return model
