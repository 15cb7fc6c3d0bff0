"""hw.memory.arbiter.AxiArbiter on pysim, alone, against golden.memory.arbiter's rule: random offers
from 1 to 4 ports (3: banks rounded up to 4), random ``axi.arready``, small queues that wrap many
times (the queues are LUT RAM in banks by position): every AR leaves in (cycle, port) order, in the
cycle the rule gives (with ``arready`` high the rule is ``golden.memory.arbiter.Arbiter``'s exactly),
never lost or duplicated, and every R beat reaches the port that issued its burst; ``overflow`` stays
low. The filter's tests check it inside the filter, cycle for cycle against the cycle model."""

import numpy as np
import pytest
from amaranth.sim import Simulator

from vqtex.golden.memory.arbiter import Arbiter
from vqtex.hw.memory.arbiter import AxiArbiter


def run(ports, depth, cycles, seed, arready_p):
    rng = np.random.default_rng(seed)
    dut = AxiArbiter(ports, addr_width=16, data_width=8, depth=depth)
    got = {"issued": [], "beats": [[] for _ in range(ports)], "overflow": 0}
    offers = []                                 # (cycle, port, addr, len) in (cycle, port) order

    async def bench(ctx):
        waiting = 0                             # offers taken but not yet issued (the rule's queue)
        bursts = []                             # issued bursts waiting for their R beats: [addr, beats left]
        delay = 0
        for cycle in range(cycles):
            # offers: at most what the queues still hold (the caller sizes them to the bursts in
            # flight: queued, or issued and not yet returned)
            room = depth - waiting - len(bursts)
            valid = [bool(rng.random() < 0.45) for _ in range(ports)]
            while sum(valid) > room:
                valid[valid.index(True)] = False
            for k, p in enumerate(dut.ports):
                addr, n = int(rng.integers(0, 1 << 16)), int(rng.integers(0, 3))
                ctx.set(p.arvalid, int(valid[k]))
                ctx.set(p.araddr, addr)
                ctx.set(p.arlen, n)
                if valid[k]:
                    offers.append((cycle, k, addr, n))
            ready = bool(rng.random() < arready_p)
            ctx.set(dut.axi.arready, int(ready))
            # R: one beat per cycle of the oldest issued burst, after a random gap
            beat = bool(bursts) and delay == 0
            ctx.set(dut.axi.rvalid, int(beat))
            if beat:
                ctx.set(dut.axi.rdata, bursts[0][0] & 0xFF)
                ctx.set(dut.axi.rlast, int(bursts[0][1] == 1))
            else:
                delay = max(0, delay - 1)
            assert ctx.get(dut.axi.rready) == 1
            if beat:
                to = [k for k, p in enumerate(dut.ports) if ctx.get(p.rvalid)]
                assert len(to) == 1
                got["beats"][to[0]].append((bursts[0][0], ctx.get(dut.ports[to[0]].rlast)))
                bursts[0][1] -= 1
                if bursts[0][1] == 0:
                    bursts.pop(0)
                    delay = int(rng.integers(0, 3))
            got["overflow"] |= ctx.get(dut.overflow)
            if ctx.get(dut.axi.arvalid) and ready:
                a = (cycle, ctx.get(dut.axi.araddr), ctx.get(dut.axi.arlen))
                got["issued"].append(a)
                bursts.append([a[1], a[2] + 1])
            waiting += sum(valid) - (1 if ctx.get(dut.axi.arvalid) and ready else 0)
            await ctx.tick()
        for p in dut.ports:
            ctx.set(p.arvalid, 0)

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    return offers, got


@pytest.mark.parametrize("ports,depth,arready_p,seed", [
    (1, 2, 0.5, 1),
    (3, 4, 0.6, 2),
    (4, 8, 0.7, 3),
    (4, 8, 1.0, 4),
])
def test_arbiter_issues_by_the_rule_and_routes_every_beat(ports, depth, arready_p, seed):
    offers, got = run(ports, depth, 300, seed, arready_p)
    assert got["overflow"] == 0
    issued = got["issued"]
    assert len(issued) > 3 * depth              # the queues wrapped several times
    # the order: (cycle, port), every offer once
    assert [(a, n) for _, a, n in issued] == [(a, n) for _, _, a, n in offers[:len(issued)]]
    # the cycles: issue[b] = the first cycle >= max(offer[b], issue[b-1] + 1) with arready high
    if arready_p == 1.0:
        rule = Arbiter()
        assert [c for c, _, _ in issued] == [rule.issue(c) for c, _, _, _ in offers[:len(issued)]]
    else:
        last = -1
        for (c, _, _), (o, _, _, _) in zip(issued, offers):
            assert c >= max(o, last + 1)
            last = c
    # every R beat reached the port of its burst, each burst's beats in order, rlast on its last
    per_port = [[] for _ in range(ports)]
    for (_, k, a, n) in offers[:len(issued)]:
        per_port[k].extend([(a & 0xFF, 0)] * n + [(a & 0xFF, 1)])
    for k in range(ports):
        beats = got["beats"][k]
        assert [(a & 0xFF, last) for a, last in beats] == per_port[k][:len(beats)]
    # and every burst but the last few in flight came back
    assert sum(last for b in got["beats"] for _, last in b) >= len(issued) - depth


def test_arbiter_refuses_a_queue_below_its_banks():
    with pytest.raises(ValueError, match="queue depth 2"):
        AxiArbiter(3, depth=2)
