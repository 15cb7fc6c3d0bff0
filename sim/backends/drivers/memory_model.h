// The golden memory models in C++ (golden/memory/external.py, golden/memory/dram.py): the same
// rules, integer for integer, for the compiled simulators' AXI slave. A model answers one burst at a
// time, in issue order: read(t, address, beats) is the cycle of the burst's first R beat; beat k
// follows k * beat_interval cycles later; `queued` is the last burst's wait behind earlier ones.
// tests/sim/backends/test_memory_model_cxx.py checks both against the Python models.
#pragma once
#include <algorithm>
#include <cstdint>
#include <vector>

namespace vq {

struct FixedMemory {
    int64_t latency, beat_interval;
    int64_t free_ = 0, queued = 0;
    FixedMemory(int64_t latency, int64_t beat_interval) : latency(latency), beat_interval(beat_interval) {}
    int64_t read(int64_t t, int64_t /*address*/, int64_t beats) {
        int64_t ready = t + latency;
        int64_t first = std::max(ready, free_);
        queued = first - ready;
        free_ = first + beats * beat_interval;
        return first;
    }
};

// Timings in controller cycles, as DramMemory.timings gives them (golden/memory/dram.py).
struct DramTimings {
    int64_t CL, tRCD, tRP, tRAS, tRC, tRFC, tREFI, tRRD, tFAW, tRTP;
};

struct DramMemory {
    DramTimings T;
    int64_t banks, page_bytes, beat_interval, controller_cycles;
    std::vector<int64_t> open, act, rd;
    int64_t acts[4];
    int64_t next_cmd = 0, data_free = 0, next_ref, queued = 0, refreshes = 0;
    static constexpr int64_t never = -(int64_t(1) << 40);

    DramMemory(DramTimings T, int64_t banks, int64_t page_bytes, int64_t beat_interval, int64_t controller_cycles)
        : T(T), banks(banks), page_bytes(page_bytes), beat_interval(beat_interval),
          controller_cycles(controller_cycles), open(banks, -1), act(banks, never), rd(banks, never),
          next_ref(T.tREFI) {
        for (auto &a : acts) a = never;
    }

    int64_t read(int64_t t, int64_t address, int64_t beats) {
        int64_t bank = (address / page_bytes) % banks;
        int64_t row = address / (page_bytes * banks);
        int64_t start = std::max(t, next_cmd);
        int64_t q = start - t;
        while (next_ref <= start) {             // refreshes that fell due: done before this burst
            int64_t at = std::max(next_ref, next_cmd);
            bool any = false;
            int64_t pre = at;
            for (int64_t b = 0; b < banks; b++)
                if (open[b] >= 0) {
                    any = true;
                    pre = std::max({pre, act[b] + T.tRAS, rd[b] + T.tRTP});
                }
            if (any) at = pre + T.tRP;
            int64_t done = at + T.tRFC;
            std::fill(open.begin(), open.end(), -1);
            refreshes++;
            next_ref += T.tREFI;
            start = std::max(start, done);
        }
        int64_t column;
        if (open[bank] == row) {
            column = start;
        } else {
            int64_t a = start;
            if (open[bank] >= 0) a = std::max({start, act[bank] + T.tRAS, rd[bank] + T.tRTP}) + T.tRP;
            a = std::max({a, act[bank] + T.tRC, acts[3] + T.tRRD, acts[0] + T.tFAW});
            acts[0] = acts[1]; acts[1] = acts[2]; acts[2] = acts[3]; acts[3] = a;
            act[bank] = a;
            open[bank] = row;
            column = a + T.tRCD;
        }
        if (column < data_free) {
            q += data_free - column;
            column = data_free;
        }
        int64_t data = beats * beat_interval;
        data_free = column + data;
        rd[bank] = column + data - 1;
        next_cmd = column + 1;
        queued = q;
        return column + T.CL + controller_cycles;
    }
};

}  // namespace vq
