"""sim/cxxrtl_inplace.py: the in-place clock cycle equals CXXRTL's own eval()/commit() stepping.

The texel-fetch unit's equality with golden is covered by test_backends.py (every stream there runs
through ``vq_cycle``); here a small design with the cases the unit lacks (registers that swap
values, so an order alone cannot work; a wide register; a memory read port; an enable) runs the
same random inputs through both ways of stepping and compares the ports every cycle.
"""

import os
import subprocess

import pytest
from amaranth import *
from amaranth.hdl import _ir
from amaranth.lib import memory

from sim import cxxrtl_backend as cb
from sim.cxxrtl_inplace import inplace_cycle

from backend_fixtures import need, texture_sets


class Toy(Elaboratable):
    def __init__(self):
        self.inp = Signal(8)
        self.en = Signal()
        self.out = Signal(64)

    def elaborate(self, platform):
        m = Module()
        a, b = Signal(8, init=1), Signal(8, init=2)
        wide = Signal(100, init=3)
        pipe = [Signal(12, name=f"pipe{k}") for k in range(3)]
        m.submodules.mem = mem = memory.Memory(shape=40, depth=16, init=[k * 0x0123456789 for k in range(16)])
        rd = mem.read_port()
        with m.If(self.en):
            m.d.sync += [a.eq(b), b.eq(a ^ self.inp),                  # a cycle: a <- b <- a
                         wide.eq(Cat(wide[1:], wide[0] ^ a[0]) + self.inp)]
        m.d.sync += [pipe[0].eq(a + self.inp), pipe[1].eq(pipe[0]), pipe[2].eq(pipe[1] ^ pipe[0])]
        m.d.comb += [rd.addr.eq(wide[:4] ^ a[:4]), rd.en.eq(self.en),
                     self.out.eq(Cat(a, b, pipe[2], wide[90:100]) ^ rd.data ^ wide[:64])]
        return m


HARNESS = r"""
#include "vq_slice.h"
#include "design.cc"
#include <cstdio>
#include <random>
using namespace cxxrtl_design;
static void reset(p_top &t) {
    t.p_rst.set(1u); t.p_clk.set(0u); t.step(); t.p_clk.set(1u); t.step();
    t.p_clk.set(0u); t.p_rst.set(0u); t.step();
}
int main() {
    p_top ref, fast;
    reset(ref); reset(fast);
    std::mt19937 rng(7);
    for (int c = 0; c < 5000; c++) {
        unsigned x = rng() & 0xff, en = (rng() % 4) != 0;
        for (p_top *t : {&ref, &fast}) { t->p_inp.set(x); t->p_en.set(en); }
        ref.p_clk.set(0u); ref.step();
        unsigned long long want = ref.p_out.get<unsigned long long>(), got = 0;
        ref.p_clk.set(1u); ref.step();
        fast.vq_cycle([&]() { got = fast.p_out.get<unsigned long long>(); });
        if (want != got) { std::printf("cycle %d: %llx != %llx\n", c, want, got); return 1; }
    }
    std::puts("equal");
    return 0;
}
"""


def _toy_source():
    top = Toy()
    frag = _ir.Fragment.get(top, None)
    i, o = _ir.PortDirection.Input, _ir.PortDirection.Output
    ports = {"inp": (top.inp, i), "en": (top.en, i), "out": (top.out, o)}
    return cb.write_cxxrtl(frag, ports)


def test_inplace_cycle_equals_eval_commit(tmp_path):
    need("g++")
    src, _ = cb.rewrite(_toy_source())
    assert "void p_top::vq_cycle" in src
    assert "vq_old_" in src                     # the swap needed its snapshot
    (tmp_path / "design.cc").write_text(src)
    (tmp_path / "main.cc").write_text(HARNESS)
    cxx = os.environ.get("CXX", "g++")
    subprocess.run([cxx, "-std=c++17", "-O1", "-I", cb.cxxrtl_include_dir(), "-I", cb.DRIVER_DIR,
                    "-I", str(tmp_path), str(tmp_path / "main.cc"), "-o", str(tmp_path / "toy")], check=True)
    out = subprocess.run([str(tmp_path / "toy")], capture_output=True, text=True)
    assert out.returncode == 0, out.stdout
    assert out.stdout.strip() == "equal"


def test_texel_fetch_uses_the_inplace_cycle():
    """The unit's generated code has the shape the rewrite expects (else it would silently fall
    back to eval()/commit(), right but slower)."""
    _, header = cb.cxxrtl_program(cb.design_info(texture_sets()["mixed"]))
    assert "#define VQ_INPLACE 1" in header


@pytest.mark.parametrize("damage", [
    lambda s: s.replace("bool converged = true;", "bool converged = false;"),      # combinational loop
    lambda s: s.replace("\tif (posedge_p_clk) {", "\tif (posedge_p_clk && true) {", 1),  # another form
    lambda s: s.replace("bool eval(performer *performer = nullptr) override;", ""),
])
def test_unexpected_code_falls_back(damage):
    src = _toy_source()
    assert inplace_cycle(src) is not None
    assert inplace_cycle(damage(src)) is None
