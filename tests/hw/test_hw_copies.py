"""hw.copies: copies of a register equal it every cycle (pysim), and survive Yosys's synth_ecp5 as
flip-flops of their own through ``vqtex report area``'s script (without its ``KEEP_REGISTERS`` step
Yosys merges them into one: the control)."""

import pytest
from amaranth import Elaboratable, Fragment, Module, Signal
from amaranth.back import rtlil
from amaranth.sim import Simulator

from vqtex.hw.copies import KEEP, register_copies
from vqtex.sim.reports.synth import tools
from vqtex.sim.reports.synth.target import HARNESS_NAME, UNIT_NAME
from tests.support import need_synth_tools

N = 4


class _Unit(Elaboratable):
    """Four copies of one enabled register, each the enable of a 4-bit register of its own."""

    def __init__(self):
        self.a = Signal()
        self.en = Signal()
        self.d = Signal(4 * N)
        self.o = Signal(4 * N)
        self.ref = Signal()

    def elaborate(self, platform):
        m = Module()
        self.copies = register_copies(m, self.a, N, name="a_copy", enable=self.en)
        with m.If(self.en):
            m.d.sync += self.ref.eq(self.a)
        for k, q in enumerate(self.copies):
            with m.If(q):
                m.d.sync += self.o[4 * k:4 * k + 4].eq(self.d[4 * k:4 * k + 4] ^ k)
        return m


class _Harness(Elaboratable):
    def __init__(self):
        self.unit = _Unit()

    def elaborate(self, platform):
        m = Module()
        m.submodules.unit = self.unit
        return m


def test_copies_equal_the_register_every_cycle():
    u = _Unit()
    sim = Simulator(u)
    sim.add_clock(1e-6)
    pattern = [(1, 1), (0, 0), (0, 1), (1, 0), (1, 1), (0, 1), (1, 1)]

    async def bench(ctx):
        for a, en in pattern:
            ctx.set(u.a, a)
            ctx.set(u.en, en)
            await ctx.tick()
            ref = ctx.get(u.ref)
            assert [ctx.get(q) for q in u.copies] == [ref] * N
    sim.add_testbench(bench)
    sim.run()
    assert all(q.attrs == KEEP for q in u.copies)
    m = Module()
    with pytest.raises(ValueError):
        register_copies(m, u.a, 0, name="none")
    Fragment.get(m, None)                       # used: no UnusedElaboratable warning


def _unit_ffs(tmp_path, monkeypatch, script):
    monkeypatch.setattr(tools, "yosys_script", script)
    h = _Harness()
    text = rtlil.convert(h, name=HARNESS_NAME, ports=[h.unit.a, h.unit.en, h.unit.d, h.unit.o])
    res = tools.run_yosys(text, str(tmp_path))
    return res["stat"][UNIT_NAME]["cells"].get("TRELLIS_FF", 0)


def test_copies_survive_synthesis(tmp_path, monkeypatch):
    need_synth_tools()
    script = tools.yosys_script
    assert tools.KEEP_REGISTERS in script()
    without = (lambda **kw: script(**kw).replace(tools.KEEP_REGISTERS + "\n", ""))
    for d in ("kept", "merged"):
        (tmp_path / d).mkdir()
    kept = _unit_ffs(tmp_path / "kept", monkeypatch, script)
    merged = _unit_ffs(tmp_path / "merged", monkeypatch, without)
    # 16 output bits and the copies (ref has no load and goes): four copies kept, one without the step
    assert kept == 4 * N + N
    assert merged == 4 * N + 1
