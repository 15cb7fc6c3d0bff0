// The Verilated model both Verilator drivers run (verilator_driver.cc: the texel-fetch unit;
// filter_verilator_driver.cc: the texture filter), --prefix Vtop, ports clk, rst, i_valid, o_ready:
// its context (2-state: anything uninitialised starts at 0), the reset, and one clock cycle
// (inputs settle with clk low, ``sample`` reads the outputs, then the rising edge).
#pragma once
#include <memory>
#include "Vtop.h"
#include "verilated.h"

double sc_time_stamp() { return 0; }

struct VerilatedTop {
    std::unique_ptr<VerilatedContext> ctx;
    std::unique_ptr<Vtop> top;
    VerilatedTop() : ctx(new VerilatedContext) {
        ctx->randReset(0);
        top.reset(new Vtop{ctx.get(), "top"});
        top->clk = 0; top->rst = 0; top->i_valid = 0; top->o_ready = 0;
        top->eval();
    }
    ~VerilatedTop() { top->final(); }
    void reset() {
        top->rst = 1; top->clk = 0; top->i_valid = 0; top->o_ready = 0; top->eval();
        top->clk = 1; top->eval();
        top->clk = 0; top->rst = 0; top->eval();
    }
    void settle() { top->clk = 0; top->eval(); }
    void posedge() { top->clk = 1; top->eval(); }
    template<class F> void cycle(F &&sample) { settle(); sample(); posedge(); }
};
