// The AXI4 read slave of the compiled drivers: what sim/backends/axi_memory.py is to pysim, for the
// cached unit (hw/memory/unit.py) on CXXRTL (driver.cc) and Verilator (verilator_driver.cc). It holds
// the external memory's bytes (golden.memory.system.Layout.image) and the C++ twin of a golden memory
// model (memory_model.h), and is called by batch.h's run loop twice per counted cycle c:
//
//   drive(c, a)   before the design settles: R carries the beat the model scheduled for cycle c
//                 (rvalid, rdata from the image, rlast), else rvalid = rlast = 0; arready is high;
//   sample(c, a)  after it settles: an AR offered in cycle c is accepted (arready is always high, as
//                 the golden models assume), the model gives its first beat's cycle f (>= c + 1),
//                 and beat k of the burst is driven in cycle f + k * beat_interval.
//
// It checks the master's side as it goes (INCR bursts of the bus width, never across 4 KB, never past
// the image, the model answering in order): the first violation is kept (error()) and stops the run.
// ``ar`` and ``addresses`` list every AR handshake's cycle and byte address, in order.
//
// The adapter A gives: axi_set_r(valid, const uint32_t *words, last), axi_set_arready(bool),
// axi_arvalid(), axi_araddr(), axi_arlen(), axi_arsize(), axi_arburst().
#pragma once
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <deque>
#include <string>
#include <vector>

#include "memory_model.h"

struct vq_axi_slave {
    std::vector<uint8_t> image;                 // the memory's bytes
    uint32_t data[32] = {};                     // the beat on R (little-endian 32-bit words)
    uint64_t bytes = 0, bus = 16;               // image size, bytes per beat
    int kind = -1;                              // 0 FixedMemory, 1 DramMemory (memory_model.cc's codes)
    std::vector<int64_t> params;
    vq::FixedMemory fixed{1, 1};
    vq::DramMemory dram{vq::DramTimings{}, 1, 1, 1, 0};
    int64_t beat_interval = 1;
    struct Burst { int64_t first; uint64_t address, beats; };
    std::deque<Burst> bursts;                   // scheduled, in order; the front one is being sent
    uint64_t beat = 0;                          // beats of the front burst already sent
    std::vector<uint64_t> ar, addresses;
    std::string error;

    // kind 0: params = latency, beat_interval; kind 1: memory_model.cc's fourteen. 0 ok, -1 refused.
    int configure(const uint8_t *img, uint64_t n, uint64_t bus_bytes, int k, const int64_t *p, int np) {
        if ((k != 0 || np != 2) && (k != 1 || np != 14))
            return -1;
        if (bus_bytes < 1 || bus_bytes > sizeof data || (bus_bytes & (bus_bytes - 1)))
            return -1;
        image.assign(img, img + n);
        bytes = n;
        bus = bus_bytes;
        kind = k;
        params.assign(p, p + np);
        return 0;
    }
    bool configured() const { return kind >= 0; }
    void reset() {
        if (kind == 0) {
            fixed = vq::FixedMemory(params[0], params[1]);
            beat_interval = params[1];
        } else if (kind == 1) {
            vq::DramTimings T{params[0], params[1], params[2], params[3], params[4], params[5], params[6],
                              params[7], params[8], params[9]};
            dram = vq::DramMemory(T, params[10], params[11], params[12], params[13]);
            beat_interval = params[12];
        }
        bursts.clear();
        beat = 0;
        ar.clear();
        addresses.clear();
        error.clear();
    }
    template<class A> void drive(uint64_t c, A &a) {
        a.axi_set_arready(true);
        if (!bursts.empty()) {
            const Burst &b = bursts.front();
            if (int64_t(c) == b.first + int64_t(beat) * beat_interval) {
                const bool last = beat + 1 == b.beats;
                std::memcpy(data, image.data() + b.address + beat * bus, bus);
                a.axi_set_r(true, data, last);
                if (last) {
                    bursts.pop_front();
                    beat = 0;
                } else {
                    beat++;
                }
                return;
            }
        }
        a.axi_set_r(false, data, false);              // (rdata is don't-care: the last beat's stays)
    }
    // false: the master broke the protocol (error() says how) and the run stops.
    template<class A> bool sample(uint64_t c, A &a) {
        if (!a.axi_arvalid())
            return true;
        const uint64_t addr = a.axi_araddr(), n = a.axi_arlen() + 1;
        char msg[160];
        if (a.axi_arburst() != 1 || (uint64_t(1) << a.axi_arsize()) != bus) {
            std::snprintf(msg, sizeof msg, "cycle %llu: only INCR bursts of %llu-byte beats are served",
                          (unsigned long long)c, (unsigned long long)bus);
            error = msg;
            return false;
        }
        if (addr / 4096 != (addr + n * bus - 1) / 4096) {
            std::snprintf(msg, sizeof msg, "cycle %llu: burst at %#llx of %llu beats crosses 4 KB",
                          (unsigned long long)c, (unsigned long long)addr, (unsigned long long)n);
            error = msg;
            return false;
        }
        if (addr % bus || addr + n * bus > bytes) {
            std::snprintf(msg, sizeof msg, "cycle %llu: burst at %#llx of %llu beats outside the memory",
                          (unsigned long long)c, (unsigned long long)addr, (unsigned long long)n);
            error = msg;
            return false;
        }
        const int64_t first = kind == 0 ? fixed.read(int64_t(c), int64_t(addr), int64_t(n))
                                        : dram.read(int64_t(c), int64_t(addr), int64_t(n));
        const int64_t prev = bursts.empty() ? -1 : bursts.back().first + int64_t(bursts.back().beats - 1) * beat_interval;
        if (first <= int64_t(c) || first <= prev) {
            std::snprintf(msg, sizeof msg, "cycle %llu: the memory model answered out of order", (unsigned long long)c);
            error = msg;
            return false;
        }
        bursts.push_back(Burst{first, addr, n});
        ar.push_back(c);
        addresses.push_back(addr);
        return true;
    }
};
