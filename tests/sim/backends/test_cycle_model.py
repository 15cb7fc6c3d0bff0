"""sim.backends.cycle_model (vectorised) against a cycle-by-cycle replay of TexelFetch's pipeline control.

The replay is the RTL's control written out per cycle (the registered advance = no output stall in
the previous cycle, the skid register, the one-port hold of the bit-address stage); the pysim tests
tie both to the RTL itself on shorter traces."""

import numpy as np
import pytest

from vqtex.hw.texel_fetch import LATENCY, REGISTERS, UPSTREAM_STAGES
from vqtex.sim.backends.cycle_model import run_flags
from vqtex.sim.streams import ready_pattern


def replay(strad, *, stall, seed, one_port):
    n = len(strad)
    h = UPSTREAM_STAGES
    ready = ready_pattern(seed, stall, 64 + 4 * (n + LATENCY) + int(20 * n * stall / (1 - stall)))
    stage = [None] * LATENCY           # item id per register R1..R14, None = bubble
    skid = None                        # the skid register's item
    advance = True                     # the registered advance
    second = False
    n_in = n_out = cycle = 0
    backpressure = holds = 0
    transfers = []
    occ = np.zeros(len(REGISTERS), np.int64)
    while n_out < n:
        assert advance == (skid is None)
        r = bool(ready[cycle])
        shown = skid if skid is not None else stage[-1]
        ov = shown is not None
        occ += [s is not None for s in stage] + [skid is not None]
        hold = one_port and stage[h - 1] is not None and bool(strad[stage[h - 1]]) and not second
        if ov and r:
            assert shown == n_out          # in order, none lost or duplicated
            transfers.append(cycle)
            n_out += 1
        if ov and not r:
            backpressure += 1
        if advance:
            skid = stage[-1] if not r else None
            holds += hold
            stage[h + 1:] = stage[h:-1]
            stage[h] = None if hold else stage[h - 1]
            if not hold:
                stage[1:h] = stage[:h - 1]
                stage[0] = n_in if n_in < n else None
                n_in += n_in < n
            second = hold
        elif r:
            skid = None
        advance = not (ov and not r)
        cycle += 1
    return cycle, backpressure, holds, occ / max(1, cycle), transfers


@pytest.mark.parametrize("one_port", [False, True])
@pytest.mark.parametrize("stall", [0.0, 0.2, 0.6])
def test_model_equals_cycle_by_cycle_replay(stall, one_port):
    rng = np.random.default_rng(int(stall * 10) + one_port)
    for trial in range(25):
        n = int(rng.integers(0, 300))
        strad = rng.random(n) < rng.random()
        seed = int(rng.integers(0, 1 << 30))
        m = run_flags(strad, stall=stall, seed=seed, one_port=one_port)
        cycles, bp, holds, occ, transfers = replay(strad, stall=stall, seed=seed, one_port=one_port)
        assert m["cycles"] == cycles
        assert m["stall_cycles"] == {"output_backpressure": bp, "one_port_straddle": holds}
        assert m["straddles"] == int(strad.sum())
        assert m["transfer"].tolist() == transfers
        # every cycle is one of the first LATENCY, a transfer, a backpressure stall or a one-port bubble
        assert cycles == (n + LATENCY + bp + holds if n else 0)
        if n:
            assert [m["occupancy"][s] for s in REGISTERS] == pytest.approx(occ.tolist(), abs=1e-12)
            assert m["transfer"][-1] == cycles - 1


def test_ready_pattern_is_one_sequence():
    a = ready_pattern(5, 0.4, 100)
    b = ready_pattern(5, 0.4, 1000)
    assert np.array_equal(a, b[:100])
    assert ready_pattern(5, 0.0, 10).all()
    with pytest.raises(ValueError):
        ready_pattern(0, 1.0, 10)


def test_no_backpressure_closed_form():
    strad = np.random.default_rng(0).random(1000) < 0.4
    assert run_flags(strad)["cycles"] == 1000 + LATENCY
    assert run_flags(strad, one_port=True)["cycles"] == 1000 + LATENCY + int(strad.sum())
