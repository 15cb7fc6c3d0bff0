// A C entry point to the C++ memory models (memory_model.h), for the test that holds them equal to
// the Python models: a sequence of bursts in, the first beat and the queued cycles of each out.
#include "memory_model.h"

extern "C" __attribute__((visibility("default")))
int vq_memory_reads(int kind, const int64_t *params, int64_t n, const int64_t *t, const int64_t *address,
                    const int64_t *beats, int64_t *first, int64_t *queued) {
    // kind 0: params = latency, beat_interval. kind 1: params = CL, tRCD, tRP, tRAS, tRC, tRFC, tREFI,
    // tRRD, tFAW, tRTP, banks, page_bytes, beat_interval, controller_cycles.
    if (kind == 0) {
        vq::FixedMemory m(params[0], params[1]);
        for (int64_t k = 0; k < n; k++) { first[k] = m.read(t[k], address[k], beats[k]); queued[k] = m.queued; }
        return 0;
    }
    if (kind == 1) {
        vq::DramTimings T{params[0], params[1], params[2], params[3], params[4], params[5], params[6], params[7],
                          params[8], params[9]};
        vq::DramMemory m(T, params[10], params[11], params[12], params[13]);
        for (int64_t k = 0; k < n; k++) { first[k] = m.read(t[k], address[k], beats[k]); queued[k] = m.queued; }
        return 0;
    }
    return -1;
}
