// Every (Y, U, V) through the colour-matrix stage alone (sim/backends/color_sweep.py).
//
//   design.cc -- CXXRTL's C++ of hw.color_matrix.ColorMatrix (ports samples, color, en, rgba)
//
// vq_color_sweep(out, color, latency) presents input c = Y | U << 8 | V << 16 for c = 0 .. 2^24-1,
// one per clock with en high, and writes the R, G, B the stage registers LATENCY clocks later to
// out[3c .. 3c+2]. Returns the number of clocks run.
#include <cstdint>
#include "design.cc"

#define VQ_EXPORT extern "C" __attribute__((visibility("default")))

VQ_EXPORT uint64_t vq_color_sweep(uint8_t *out, uint32_t color, uint32_t latency) {
    cxxrtl_design::p_top t;
    t.p_rst.set(1u); t.p_clk.set(0u); t.step(); t.p_clk.set(1u); t.step();
    t.p_clk.set(0u); t.p_rst.set(0u); t.step();
    t.p_en.set(1u);
    t.p_color.set(color);
    const uint64_t n = uint64_t(1) << 24;
    uint64_t clocks = 0;
    for (uint64_t c = 0; c < n + latency - 1; c++) {
        t.p_samples.set(uint32_t(c < n ? c : 0));
        t.p_clk.set(0u); t.step();
        t.p_clk.set(1u); t.step();
        clocks++;
        if (c + 1 >= latency) {                 // the item presented latency-1 clocks ago
            uint32_t rgba = t.p_rgba.get<uint32_t>();
            uint8_t *o = out + 3 * (c + 1 - latency);
            o[0] = uint8_t(rgba); o[1] = uint8_t(rgba >> 8); o[2] = uint8_t(rgba >> 16);
        }
    }
    return clocks;
}
