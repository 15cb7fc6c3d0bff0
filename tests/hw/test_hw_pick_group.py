"""hw.pick.pick_group: the first half of a pick over two stages equals the whole pick for
every index (lists of any length, groups larger and smaller than the list, index wider than the
tree), simulated exhaustively."""

from __future__ import annotations

import pytest
from amaranth import *
from amaranth.sim import Simulator

from vqtex.hw.pick import pick, pick_group


@pytest.mark.parametrize("n", [1, 3, 5, 22, 85])
def test_pick_group_then_pick_is_pick(n):
    m = Module()
    cases = []
    for group in (1, 2, 4, 8):
        g = group.bit_length() - 1
        for width in range(max(1, (n - 1).bit_length()), (n - 1).bit_length() + 2):
            index = Signal(width, name=f"index_{group}_{width}")
            values = [C((v * 37 + 5) & 0xFFF, 12) for v in range(n)]
            whole, split = Signal(12, name=f"whole_{group}_{width}"), Signal(12, name=f"split_{group}_{width}")
            candidates = pick_group(values, index, group)
            assert len(candidates) == group
            m.d.comb += [whole.eq(pick(values, index)),
                         split.eq(pick(candidates, Cat(index, C(0, g))[:g]) if g else candidates[0])]
            cases.append((index, whole, split))

    async def bench(ctx):
        for index, whole, split in cases:
            for i in range(1 << len(index)):
                ctx.set(index, i)
                assert ctx.get(split) == ctx.get(whole), (len(index), i)
                assert ctx.get(whole) == (min(i % (1 << max(0, (n - 1).bit_length())), n - 1) * 37 + 5) & 0xFFF

    sim = Simulator(m)
    sim.add_testbench(bench)
    sim.run()


def test_pick_group_refuses_a_group_not_a_power_of_two():
    with pytest.raises(ValueError, match="not a power of two"):
        pick_group([C(0, 1)] * 4, Signal(2), 3)
