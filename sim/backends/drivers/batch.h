// The batch C API shared by the compiled backends (CXXRTL: driver.cc, Verilator: verilator_driver.cc).
//
// One call runs a whole request stream through the texel-fetch unit, so Python (ctypes + numpy)
// makes a handful of calls per simulation, never one per request or per cycle:
//
//   void*   vq_open(void);                      a simulator instance (memories as compiled)
//   void    vq_close(void *h);
//   int     vq_api_version(void);               VQ_API_VERSION
//   int     vq_runtime_memories(void);          1: vq_load_memory works (CXXRTL); 0: contents are
//                                               compiled in (Verilator runs the exported Verilog)
//   int     vq_stage_count(void);               per-stage valid bits sampled for occupancy
//   const char *vq_port_names(void);            "design;stage,stage,..." (for checks)
//   int     vq_load_memory(void *h, const char *name, const uint32_t *rows, uint64_t depth,
//                          uint32_t chunks_per_row);
//           replace a memory's contents (rows of 32-bit little-endian chunks), applied after every
//           reset; 0 ok, -1 unknown memory, -2 shape mismatch, -3 not supported by this backend
//   int     vq_run(void *h, uint64_t n, const int64_t *requests, const uint32_t *layout,
//                  const uint8_t *ready, uint64_t n_ready, uint64_t max_cycles, uint32_t *rgba,
//                  uint64_t *counters);
//
//   int64_t vq_bus(void *h, uint64_t n, const uint32_t *ops, uint32_t *answers, uint64_t max_cycles);
//           the loadable unit's Wishbone port: n transfers, ops[3k..3k+2] = (word address, data,
//           write), issued back to back in one bus cycle (golden.register_map.load_cycles); answers
//           [2k], [2k+1] = (dat_r, err) of transfer k. Returns the cycles taken, -1 if max_cycles
//           passed, -3 if the design has no bus port. The requests' side is idle meanwhile (i.valid
//           low, o.ready high); no reset: vq_run's reset clears the pipeline, not what was loaded.
//
// requests: n rows of (texture, level, i, j). layout[VQ_L_*]: the (offset, width) in i.payload of
// texture, level, i, j and the tag (request k carries tag k mod 2^width), then the (offset, width)
// of the tag in o.payload. vq_run packs each request into i.payload as it is presented.
//
// vq_run resets the design (rst high for one clock edge), then clocks it: in counted cycle c
// (c = 0 is the first cycle i.valid is high) it drives i.valid = (requests left), i.payload = the
// next request, o.ready = ready[c] (all ones when ready == NULL), lets the combinational logic
// settle, samples every port, counts the transfers and strobes, and clocks a rising edge. It stops
// after the cycle in which the n-th response transfers. Counting therefore runs from the first
// cycle i.valid is high up to and including the cycle the last response transfers (the
// TexelFetch docstring's definition). rgba[k] is bits 0..31 of the k-th response's o.payload
// (bytes r, g, b, a); its tag is checked against k.
//
// counters[VQ_C_*]: cycles, requests accepted, responses, output-backpressure cycles
// (stall_output strobe), one-port stall cycles (stall_one_port strobe), straddling index reads
// (straddle strobe), 1 + the number of the first response whose tag is not its request's (0: all
// right) and that tag, then from VQ_C_OCCUPANCY one sum of each stage's valid bit over the cycles.
// Return: 0 done; 1 the ready pattern ran out (call again with a longer one); 2 max_cycles passed.
#pragma once
#include <cstdint>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#define VQ_API_VERSION 3
#define VQ_EXPORT extern "C" __attribute__((visibility("default")))
enum {
    VQ_C_CYCLES = 0, VQ_C_ACCEPTED, VQ_C_RESPONSES, VQ_C_STALL_OUTPUT, VQ_C_STALL_ONE_PORT,
    VQ_C_STRADDLES, VQ_C_BAD_TAG, VQ_C_BAD_TAG_VALUE, VQ_C_OCCUPANCY
};
enum { VQ_L_TEXTURE = 0, VQ_L_LEVEL = 2, VQ_L_I = 4, VQ_L_J = 6, VQ_L_TAG = 8, VQ_L_RESPONSE_TAG = 10,
       VQ_L_SIZE = 12 };

// The request packing and response tag of layout[] (see vq_run above).
struct vq_layout {
    uint32_t off[6];
    uint64_t mask[6];
    explicit vq_layout(const uint32_t *l) {
        for (int f = 0; f < 6; f++) {
            off[f] = l[2 * f];
            mask[f] = l[2 * f + 1] >= 64 ? ~uint64_t(0) : (uint64_t(1) << l[2 * f + 1]) - 1;
        }
    }
    uint64_t pack(const int64_t *row, uint64_t k) const {
        uint64_t p = (k & mask[4]) << off[4];
        for (int f = 0; f < 4; f++)
            p |= (uint64_t(row[f]) & mask[f]) << off[f];
        return p;
    }
    uint64_t tag(uint64_t payload) const { return (payload >> off[5]) & mask[5]; }
};

// Adapter: reset(), set_inputs(i_valid, i_payload, o_ready), cycle(sample), i_ready(), o_valid(),
// o_payload(), strobes(uint64_t *counters), valid() (the design's valid port: bit k is stage k,
// VQ_STAGE_COUNT bits). cycle(sample) settles the combinational logic, calls sample() (which reads
// the ports through the other methods), then clocks a rising edge.
// Per-stage occupancy sums, accumulated in byte lanes: stage k is byte k % 8 of lanes[k / 8], and
// one cycle adds vq_spread[8 valid bits] to each lane word (one table read and one add per 8 stages
// instead of one add per stage). A lane holds at most 255, so the lanes are emptied into the 64-bit
// sums every 255 cycles and at the end. Exact: the sums equal per-cycle per-stage counting.
struct vq_lane_table {
    uint64_t t[256];
    constexpr vq_lane_table() : t() {
        for (int v = 0; v < 256; v++) {
            uint64_t x = 0;
            for (int b = 0; b < 8; b++)
                if (v >> b & 1)
                    x |= uint64_t(1) << (8 * b);
            t[v] = x;
        }
    }
};
static constexpr vq_lane_table vq_spread{};

struct vq_occupancy {
    static constexpr int words = (VQ_STAGE_COUNT + 7) / 8;
    uint64_t lanes[words] = {};
    unsigned filled = 0;
    inline void add(uint32_t valid, uint64_t *sums) {
        for (int w = 0; w < words; w++)
            lanes[w] += vq_spread.t[(valid >> (8 * w)) & 0xff];
        if (++filled == 255)
            flush(sums);
    }
    void flush(uint64_t *sums) {
        for (int k = 0; k < VQ_STAGE_COUNT; k++)
            sums[k] += (lanes[k / 8] >> (8 * (k % 8))) & 0xff;
        for (int w = 0; w < words; w++)
            lanes[w] = 0;
        filled = 0;
    }
};

// What a driver's per-cycle hook reports: a response transferred (took) with o.payload (out), and
// whether the request on i.payload was accepted.
struct vq_cycle_out {
    bool took = false, accepted = false;
    uint64_t out = 0;
};

// The run loop of vq_run, resumable: state in the struct, ``run(limit, cycle, respond)`` advances
// up to ``limit`` counted cycles and can be called again. Every driver runs its design through it:
//   cycle(c, i_valid, payload, o_ready, strobes, occ, occ_sums) -> vq_cycle_out
//       drives the inputs, clocks the design once and samples the ports (adding the strobes to
//       strobes[] and the valid bits to occ); a template parameter, so it inlines into the loop;
//   respond(k, out): the k-th response transferred with o.payload ``out`` (its tag is checked here).
// AlwaysReady: ready == NULL, compiled as its own loop so that o.ready is a constant in it.
template<bool AlwaysReady>
struct alignas(64) vq_run_state {
    uint64_t n;
    const int64_t *req;
    const uint8_t *ready;
    uint64_t n_ready, max_cycles;
    vq_layout lay;
    uint64_t sums[VQ_C_OCCUPANCY + VQ_STAGE_COUNT] = {};
    uint64_t sent = 0, got = 0, c = 0, payload = 0, bad = 0, bad_tag = 0;
    vq_occupancy occ;
    int rc = -1;                        // -1 running, else vq_run's return code

    vq_run_state(uint64_t n, const int64_t *req, const uint32_t *layout, const uint8_t *ready,
                 uint64_t n_ready, uint64_t max_cycles)
        : n(n), req(req), ready(ready), n_ready(n_ready), max_cycles(max_cycles), lay(layout) {
        payload = n ? lay.pack(req, 0) : 0;
        if (n == 0)
            rc = 0;
    }
    // Up to ``limit`` more cycles (fewer when the run ends); returns the cycle count so far. The
    // loop works on local copies of the state (written back at the end): the model's stores could
    // alias members, which would make the compiler reload and store them every cycle.
    template<class Cycle, class Respond>
    uint64_t run(uint64_t limit, Cycle &&cycle, Respond &&respond) {
        const vq_layout lay = this->lay;
        uint64_t sent = this->sent, got = this->got, c = this->c, payload = this->payload;
        uint64_t bad = this->bad, bad_tag = this->bad_tag;
        uint64_t strobes[VQ_C_OCCUPANCY] = {};
        vq_occupancy occ = this->occ;
        uint64_t *occ_sums = sums + VQ_C_OCCUPANCY;
        for (uint64_t end = c + limit; c < end; c++) {
            if (got >= n) { rc = 0; break; }
            if (c >= max_cycles) { rc = 2; break; }
            bool o_ready = true;
            if (!AlwaysReady) {
                if (c >= n_ready) { rc = 1; break; }
                o_ready = ready[c] != 0;
            }
            bool i_valid = sent < n;
            const vq_cycle_out r = cycle(c, i_valid, payload, o_ready, strobes, occ, occ_sums);
            if (r.took) {
                uint64_t tag = lay.tag(r.out);
                if (tag != (got & lay.mask[5]) && !bad) {
                    bad = got + 1;
                    bad_tag = tag;
                }
                respond(got, r.out);
                got++;
            }
            if (r.accepted) {
                sent++;
                payload = sent < n ? lay.pack(req + 4 * sent, sent) : 0;
            }
        }
        if (rc < 0 && got >= n)
            rc = 0;
        for (int k = 0; k < VQ_C_OCCUPANCY; k++)
            sums[k] += strobes[k];
        this->sent = sent; this->got = got; this->c = c; this->payload = payload;
        this->bad = bad; this->bad_tag = bad_tag;
        this->occ = occ;
        return c;
    }
    // counters[] as vq_run returns them (``responses``: the responses stored); returns rc.
    int finish(uint64_t *counters, uint64_t responses) {
        occ.flush(sums + VQ_C_OCCUPANCY);
        sums[VQ_C_CYCLES] = c;
        sums[VQ_C_ACCEPTED] = sent;
        sums[VQ_C_RESPONSES] = responses;
        sums[VQ_C_BAD_TAG] = bad;
        sums[VQ_C_BAD_TAG_VALUE] = bad_tag;
        std::memcpy(counters, sums, sizeof(sums));
        return rc;
    }
};

// One design in one loop (an adapter A with reset, set_inputs, cycle(sample), the port reads).
template<bool AlwaysReady, class A>
static int vq_run_loop(A &a, uint64_t n, const int64_t *req, const uint32_t *layout, const uint8_t *ready,
                       uint64_t n_ready, uint64_t max_cycles, uint32_t *rgba, uint64_t *counters) {
    vq_run_state<AlwaysReady> s(n, req, layout, ready, n_ready, max_cycles);
    a.reset();
    s.run(max_cycles + 1,
          [&](uint64_t, bool i_valid, uint64_t payload, bool o_ready, uint64_t *strobes, vq_occupancy &occ,
              uint64_t *occ_sums) {
              a.set_inputs(i_valid, payload, o_ready);
              // sample() reads the ports into locals; the response is stored after the clock edge.
              vq_cycle_out r;
              a.cycle([&]() {
                  r.took = a.o_valid() && o_ready;
                  r.out = a.o_payload();
                  r.accepted = i_valid && a.i_ready();
                  a.strobes(strobes);
                  occ.add(a.valid(), occ_sums);
              });
              return r;
          },
          [&](uint64_t k, uint64_t out) { rgba[k] = uint32_t(out); });
    return s.finish(counters, s.got);
}

template<class A>
static int vq_run_batch(A &a, uint64_t n, const int64_t *req, const uint32_t *layout, const uint8_t *ready,
                        uint64_t n_ready, uint64_t max_cycles, uint32_t *rgba, uint64_t *counters) {
    if (ready == nullptr)
        return vq_run_loop<true>(a, n, req, layout, ready, n_ready, max_cycles, rgba, counters);
    return vq_run_loop<false>(a, n, req, layout, ready, n_ready, max_cycles, rgba, counters);
}

// The Wishbone master of vq_bus (the one sim/backends/pysim.py's bus_transfers is): an adapter A
// with set_inputs (the requests' side), set_bus(cyc, stb, we, adr, dat_w), cycle(sample) and the
// reads bus_ack(), bus_err(), bus_stall(), bus_dat_r().
template<class A>
static int64_t vq_bus_loop(A &a, uint64_t n, const uint32_t *ops, uint32_t *answers, uint64_t max_cycles) {
    uint64_t sent = 0, got = 0, c = 0;
    a.set_inputs(false, 0, true);
    while (got < n) {
        if (c >= max_cycles)
            return -1;
        const bool stb = sent < n;
        const uint32_t *op = ops + 3 * (stb ? sent : 0);
        a.set_bus(true, stb, stb && op[2], stb ? op[0] : 0, stb ? op[1] : 0);
        bool took = false, err = false, accepted = false;
        uint32_t data = 0;
        a.cycle([&]() {
            err = a.bus_err();
            took = a.bus_ack() || err;
            data = a.bus_dat_r();
            accepted = stb && !a.bus_stall();
        });
        if (took) {
            answers[2 * got] = data;
            answers[2 * got + 1] = err;
            got++;
        }
        if (accepted)
            sent++;
        c++;
    }
    a.set_bus(false, false, false, 0, 0);
    a.cycle([]() {});
    return int64_t(c + 1);
}

#ifdef VQ_BUS
#define VQ_BUS_EXPORT(A)                                                                            \
    VQ_EXPORT int64_t vq_bus(void *h, uint64_t n, const uint32_t *ops, uint32_t *answers, uint64_t max_cycles) { \
        return vq_bus_loop(*static_cast<A *>(h), n, ops, answers, max_cycles);                     \
    }
#else
#define VQ_BUS_EXPORT(A)                                                                            \
    VQ_EXPORT int64_t vq_bus(void *, uint64_t, const uint32_t *, uint32_t *, uint64_t) { return -3; }
#endif

// The exports both drivers share, for an adapter class A (one simulator instance per handle);
// each driver defines vq_load_memory itself. RUNTIME_MEMORIES: what vq_runtime_memories() returns.
#define VQ_BATCH_EXPORTS(A, RUNTIME_MEMORIES)                                                       \
    VQ_EXPORT void *vq_open(void) { return new A(); }                                               \
    VQ_EXPORT void vq_close(void *h) { delete static_cast<A *>(h); }                                \
    VQ_EXPORT int vq_api_version(void) { return VQ_API_VERSION; }                                   \
    VQ_EXPORT int vq_runtime_memories(void) { return RUNTIME_MEMORIES; }                            \
    VQ_EXPORT int vq_stage_count(void) { return VQ_STAGE_COUNT; }                                   \
    VQ_EXPORT const char *vq_port_names(void) { return VQ_PORT_NAMES; }                             \
    VQ_EXPORT int vq_run(void *h, uint64_t n, const int64_t *req, const uint32_t *layout,            \
                         const uint8_t *ready, uint64_t n_ready, uint64_t max_cycles, uint32_t *rgba, \
                         uint64_t *counters) {                                                      \
        return vq_run_batch(*static_cast<A *>(h), n, req, layout, ready, n_ready, max_cycles, rgba, \
                            counters);                                                              \
    }                                                                                               \
    VQ_BUS_EXPORT(A)
