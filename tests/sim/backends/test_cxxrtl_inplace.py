"""The rewritten CXXRTL code (sim/cxxrtl_backend.rewrite, sim/cxxrtl_inplace.py) equals CXXRTL's own.

The texel-fetch unit's equality with golden is covered by test_backends.py (every stream there runs
through ``vq_cycle``); here a small design with the cases the unit lacks (registers that swap
values, so an order alone cannot work; a wide register; a memory read port on a memory shallower
than its address reaches, whose reads lose their bounds check; an enable) runs the
same random inputs through CXXRTL's generated code and through the rewritten code, and compares
the outputs every cycle.
"""

import os
import subprocess

import pytest
from amaranth import *
from amaranth.hdl import Fragment
from amaranth.lib import memory

from vqtex.sim.backends import cxxrtl as cb
from vqtex.sim.backends import design
from vqtex.sim.backends.cxxrtl_inplace import inplace_cycle
from vqtex.sim.backends.toolchain import CXX_PREFERENCE

from tests.support import need, texture_sets


class Toy(Elaboratable):
    def __init__(self):
        self.inp = Signal(8)
        self.en = Signal()
        self.out = Signal(64)
        self.out2 = Signal(64)

    def elaborate(self, platform):
        m = Module()
        a, b = Signal(8, init=1), Signal(8, init=2)
        wide = Signal(100, init=3)
        pipe = [Signal(12, name=f"pipe{k}") for k in range(3)]
        # 12 words, a 4-bit address: words 12..15 read as zero (CXXRTL's out-of-bounds read with
        # NDEBUG, as the library is built; the
        # rewrite pads the memory with zero rows instead of checking the address)
        m.submodules.mem = mem = memory.Memory(shape=40, depth=12, init=[k * 0x0123456789 for k in range(12)])
        rd = mem.read_port()
        with m.If(self.en):
            m.d.sync += [a.eq(b), b.eq(a ^ self.inp),                  # a cycle: a <- b <- a
                         wide.eq(Cat(wide[1:], wide[0] ^ a[0]) + self.inp)]
        m.d.sync += [pipe[0].eq(a + self.inp), pipe[1].eq(pipe[0]), pipe[2].eq(pipe[1] ^ pipe[0])]
        m.d.comb += [rd.addr.eq(wide[:4] ^ a[:4]), rd.en.eq(self.en),
                     self.out.eq(Cat(a, b, pipe[2], wide[90:100]) ^ rd.data ^ wide[:64]),
                     # shifts by a variable amount, 64-bit and 100-bit
                     self.out2.eq((wide[:64] >> a[:6]) ^ (b << a[:5]) ^ (wide << a[:3])[36:100]
                                  ^ (pipe[2] >> b[:4]))]
        return m


HARNESS = r"""
#include "vq_ops.h"
#include "design.cc"
#include <cstdio>
#include <random>
using namespace cxxrtl_design;
int main() {
    p_top t;
    t.p_rst.set(1u); t.p_clk.set(0u); t.step(); t.p_clk.set(1u); t.step();
    t.p_clk.set(0u); t.p_rst.set(0u); t.step();
    std::mt19937 rng(7);
    for (int c = 0; c < 3000; c++) {
        t.p_inp.set(unsigned(rng() & 0xff));
        t.p_en.set(unsigned(rng() % 4 != 0));
        unsigned long long out = 0, out2 = 0;
#ifdef FAST
        t.vq_cycle([&]() { out = t.p_out.get<unsigned long long>(); out2 = t.p_out2.get<unsigned long long>(); });
#else
        t.p_clk.set(0u); t.step();
        out = t.p_out.get<unsigned long long>(); out2 = t.p_out2.get<unsigned long long>();
        t.p_clk.set(1u); t.step();
#endif
        std::printf("%llx %llx\n", out, out2);
    }
    return 0;
}
"""


def _toy_source():
    top = Toy()
    frag = Fragment.get(top, None)
    ports = {name: (getattr(top, name), None) for name in ("inp", "en", "out", "out2")}  # directions inferred
    return cb.write_cxxrtl(frag, ports)


def _trace(folder, src, cxx, *defines):
    folder.mkdir()
    (folder / "design.cc").write_text(src)
    (folder / "main.cc").write_text(HARNESS)
    subprocess.run([cxx, "-std=c++17", "-O1", "-DNDEBUG", *defines, "-I", cb.cxxrtl_include_dir(), "-I", cb.DRIVER_DIR,
                    "-I", str(folder), str(folder / "main.cc"), "-o", str(folder / "toy")], check=True)
    return subprocess.run([str(folder / "toy")], capture_output=True, text=True, check=True).stdout


@pytest.mark.parametrize("compiler", CXX_PREFERENCE)
def test_rewritten_cycle_equals_cxxrtl_stepping(tmp_path, compiler):
    """CXXRTL's code as generated, stepped by eval()/commit() with the clock toggled, against the
    code after every rewrite (slices, aliases, padded memory, in-place cycle) run by vq_cycle; built by
    each compiler the backend may pick."""
    need(compiler)
    cxx = os.environ.get("CXX") if compiler == "g++" and os.environ.get("CXX") else compiler
    raw = _toy_source()
    fast, _, report = cb.rewrite(raw)
    assert "void p_top::vq_cycle" in fast
    assert "vq_old_" in fast                    # the swap needed its snapshot
    assert report["fast_slices"] > 0 and report["alias_locals"] == 0     # (the toy copies no register whole)
    assert "memory<40> memory_p_mem { 12u };" in raw and "memory<40> memory_p_mem { 16u };" in fast
    assert "out of bounds read" in raw and "out of bounds read" not in fast
    want = _trace(tmp_path / "cxxrtl", raw, cxx)
    got = _trace(tmp_path / "rewritten", fast, cxx, "-DFAST")
    assert len(want.splitlines()) == 3000
    assert got == want


def test_texel_fetch_uses_the_inplace_cycle():
    """Both halves' generated code has the shape the rewrite expects (else it would silently fall
    back to eval()/commit(), right but slower), in its own namespace."""
    src, header = cb.cxxrtl_program(design.design_info(texture_sets()["mixed"]))
    assert "#define VQ_FRONT_INPLACE 1" in header and "#define VQ_BACK_INPLACE 1" in header
    assert "namespace vq_front {" in src and "namespace vq_back {" in src
    assert "cxxrtl_design" not in src


@pytest.mark.parametrize("damage", [
    lambda s: s.replace("bool converged = true;", "bool converged = false;"),      # combinational loop
    lambda s: s.replace("\tif (posedge_p_clk) {", "\tif (posedge_p_clk && true) {", 1),  # another form
    lambda s: s.replace("bool eval(performer *performer = nullptr) override;", ""),
])
def test_unexpected_code_falls_back(damage):
    src = _toy_source()
    assert inplace_cycle(src) is not None
    assert inplace_cycle(damage(src)) is None

