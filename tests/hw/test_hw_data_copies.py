"""``data_copies`` of :class:`hw.banked_rom.BankedROM` (the loadable codebook ROM's data registers
on copies of ``advance``, docs/area.md "The paths between blocks"): every bit of the banks' data
registers is enabled by exactly one copy, the shares contiguous. Each copy is driven on its own
(random, apart from the others) and every bit is checked against the copy its share names."""

from __future__ import annotations

import numpy as np
import pytest
from amaranth.sim import Simulator

from vqtex.hw.banked_rom import BankedROM


@pytest.mark.parametrize("width, depth, bank_depth, n", [(40, 32, 8, 3), (32, 32, 16, 8), (9, 8, 8, 2)])
def test_each_share_on_its_own_copy(width, depth, bank_depth, n):
    rng = np.random.default_rng(width + n)
    init = [int(v) for v in rng.integers(0, 1 << width, depth, dtype=np.uint64)]
    dut = BankedROM(init, width=width, bank_depth=bank_depth, data_copies=n)
    banks, total = dut.banks, dut.banks * width
    share = [next(s for s in range(n) if s * total // n <= b < (s + 1) * total // n) for b in range(total)]
    assert sorted(set(share)) == list(range(n))
    cycles = 60
    addr = rng.integers(0, depth, cycles)
    en_data = rng.integers(0, 1 << n, cycles)
    seen = []

    async def bench(ctx):
        for t in range(cycles):
            ctx.set(dut.addr, int(addr[t]))
            ctx.set(dut.en, 1)
            ctx.set(dut.en_data, int(en_data[t]))
            await ctx.tick()
            seen.append(ctx.get(dut.data.as_value()))

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    # the model: the memory's read register follows ``en`` (always 1), each data bit its share's copy
    reg = [0] * total
    for t in range(1, cycles):
        a = int(addr[t - 1])                # read at t - 1, on the port at t, into the data register
        for b in range(total):
            k, i = divmod(b, width)
            if en_data[t] >> share[b] & 1:
                word = init[k * bank_depth + a % bank_depth]
                reg[b] = word >> i & 1
        got = seen[t]
        assert [got >> b & 1 for b in range(total)] == reg, t
