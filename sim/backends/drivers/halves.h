// The baked texel-fetch unit run as its two halves, for every compiled backend (CXXRTL: driver.cc,
// Verilator: verilator_driver.cc). The front end (descriptor, address, index reader, all pipeline
// control) and the back end (codebook ROM, colour matrix, skid data) are joined by one registered
// ``link`` with nothing flowing back (hw/pipeline.py), so the front end can run ahead: in cycle c it
// records link(c) and whether a response transfers; the back end replays cycle c from that record.
// Both halves see exactly the inputs the whole unit gives them in the same cycle, so the result is
// the whole unit's, clock for clock, bit for bit. With one thread the two alternate every VQ_CHUNK
// cycles; with two the back end runs on a second core, at most VQ_RING cycles behind, through a
// ring of records.
//
// A driver supplies its halves as a class H (its batch adapter):
//   typename H::Record          { <the link, as the front end's model holds it> link; uint32_t took; }
//   std::vector<Record> ring    VQ_RING records
//   int threads                 1 or 2 (vq_set_threads)
//   vq_trace trace
//   void reset()                both halves
//   vq_cycle_out front_cycle(bool i_valid, const vq_payload &p, bool o_ready, uint64_t *strobes,
//                            vq_occupancy &occ, uint64_t *occ_sums, Record &rec)
//       drives the front end's inputs, clocks it once, samples its ports (took, accepted and the
//       tag where o.payload holds it in ``out``; the strobes and valid bits) and writes rec.link
//   uint32_t back_cycle(const Record &rec)
//       clocks the back end once with rec.link as its input; returns the rgba it showed that cycle
#pragma once
#include <atomic>
#include <thread>
#include <vector>

#include "batch.h"

//: Cycles per chunk of records, chunks in the ring.
constexpr uint64_t VQ_CHUNK = 512, VQ_RING_CHUNKS = 8, VQ_RING = VQ_CHUNK * VQ_RING_CHUNKS;

// Spin briefly, then give the core away until ready() holds.
template<class P> static inline void vq_wait(P &&ready) {
    for (unsigned k = 0; !ready(); k++) {
        if (k < 256) {
#if defined(__x86_64__) || defined(__i386__)
            __builtin_ia32_pause();
#endif
        } else {
            std::this_thread::yield();
        }
    }
}

// The front end's run: batch.h's run loop with a cycle that drives and clocks the front half and
// records, for the back end, the link and whether a response transfers (the back end reads the
// response's colour itself).
template<class H, bool AlwaysReady>
struct vq_front_run : vq_run_state<AlwaysReady> {
    H &s;
    vq_front_run(H &s, uint64_t n, const int64_t *req, const uint32_t *layout, const uint8_t *ready,
                 uint64_t n_ready, uint64_t max_cycles)
        : vq_run_state<AlwaysReady>(n, req, layout, ready, n_ready, max_cycles, s.trace), s(s) {}
    uint64_t run(uint64_t limit) {
        // Locals captured by the hook (the model's stores could alias members, not these).
        H &h = s;
        typename H::Record *const ring = s.ring.data();
        auto cycle = [&h, ring](uint64_t c, bool i_valid, const vq_payload &payload, bool o_ready,
                                uint64_t *strobes, vq_occupancy &occ, uint64_t *occ_sums) {
            typename H::Record &rec = ring[c % VQ_RING];
            const vq_cycle_out r = h.front_cycle(i_valid, payload, o_ready, strobes, occ, occ_sums, rec);
            rec.took = r.took;
            return r;
        };
        return vq_run_state<AlwaysReady>::run(limit, cycle, [](uint64_t, uint64_t) {});
    }
};

// The back end's run: replays the recorded cycles and stores the colours of the responses.
template<class H>
struct alignas(64) vq_back_run {
    H &s;
    uint32_t *rgba;
    uint64_t c = 0, got = 0;

    vq_back_run(H &s, uint32_t *rgba) : s(s), rgba(rgba) {}
    void run(uint64_t upto) {
        // Locals, not members, in the loop: the compiler keeps them in registers (the model's
        // stores may alias members), and the other thread's state stays off this cache line.
        H &h = s;
        uint64_t c = this->c, got = this->got;
        const typename H::Record *ring = s.ring.data();
        for (; c < upto; c++) {
            const typename H::Record &r = ring[c % VQ_RING];
            const uint32_t out = h.back_cycle(r);
            if (r.took)
                rgba[got++] = out;
        }
        this->c = c;
        this->got = got;
    }
};

template<bool AlwaysReady, class H>
static int vq_run_halves(H &s, uint64_t n, const int64_t *req, const uint32_t *layout, const uint8_t *ready,
                         uint64_t n_ready, uint64_t max_cycles, uint32_t *rgba, uint64_t *counters) {
    s.reset();
    vq_front_run<H, AlwaysReady> f(s, n, req, layout, ready, n_ready, max_cycles);
    vq_back_run<H> b(s, rgba);
    if (s.threads < 2 || n < VQ_RING) {
        // One thread: a chunk of the front end, then the same cycles of the back end.
        while (f.rc < 0)
            b.run(f.run(VQ_CHUNK));
        b.run(f.c);
    } else {
        // Two threads: the front end here, the back end on another, at most VQ_RING cycles behind.
        alignas(64) std::atomic<uint64_t> produced{0};
        alignas(64) std::atomic<uint64_t> consumed{0};
        alignas(64) std::atomic<bool> finished{false};
        std::thread back([&]() {
            for (;;) {
                uint64_t upto = 0;
                bool last = false;
                vq_wait([&]() {
                    last = finished.load(std::memory_order_acquire);
                    upto = produced.load(std::memory_order_acquire);
                    return last || upto > b.c;
                });
                b.run(upto);
                consumed.store(b.c, std::memory_order_release);
                if (last && b.c == upto)
                    break;
            }
        });
        while (f.rc < 0) {
            vq_wait([&]() { return f.c + VQ_CHUNK <= consumed.load(std::memory_order_acquire) + VQ_RING; });
            produced.store(f.run(VQ_CHUNK), std::memory_order_release);
        }
        finished.store(true, std::memory_order_release);
        back.join();
    }
    return f.finish(counters, b.got);
}

// batch.h's vq_run_batch for a halves adapter (VQ_BATCH_EXPORTS(H, ...) finds it by overload).
template<class H>
static int vq_run_halves_batch(H &s, uint64_t n, const int64_t *req, const uint32_t *layout, const uint8_t *ready,
                               uint64_t n_ready, uint64_t max_cycles, uint32_t *rgba, uint64_t *counters) {
    if (ready == nullptr)
        return vq_run_halves<true>(s, n, req, layout, ready, n_ready, max_cycles, rgba, counters);
    return vq_run_halves<false>(s, n, req, layout, ready, n_ready, max_cycles, rgba, counters);
}

// vq_set_threads for a halves adapter: 1 (the halves alternate) or 2 (the back end on a second
// thread); returns the number in use.
#define VQ_HALVES_EXPORTS(H)                                                                        \
    VQ_EXPORT int vq_set_threads(void *h, int threads) {                                            \
        H *s = static_cast<H *>(h);                                                                 \
        s->threads = threads >= 2 ? 2 : 1;                                                          \
        return s->threads;                                                                          \
    }
