// The operation the generated code is rewritten to call (sim/backends/cxxrtl.py: _fast_slices):
// the same bits as CXXRTL's own, with less work. Included before the generated
// design.cc by sim/backends/drivers/driver.cc and by the tests.
#pragma once
#include <cxxrtl/cxxrtl.h>

// vq_slice<Stop, Start>(v): the bits Stop..Start of v, as v.slice<Stop, Start>().val() (the generated
// code is rewritten to call this, see sim/backends/cxxrtl.py: _fast_slices). CXXRTL's own slice
// copies and shifts the whole operand first (rtrunc, then trunc): for a 504-bit register that is
// 16 chunks per slice; this reads only the chunks the result needs.
template<size_t Stop, size_t Start, size_t N>
static inline __attribute__((always_inline)) cxxrtl::value<Stop - Start + 1> vq_slice(const cxxrtl::value<N> &v) {
    static_assert(Stop >= Start && Stop < N, "vq_slice out of range");
    using cxxrtl::value;
    constexpr size_t bits = Stop - Start + 1, base = Start / 32, sh = Start % 32;
    value<bits> r;
    for (size_t i = 0; i < value<bits>::chunks; i++) {
        uint32_t x = v.data[base + i] >> sh;
        if (sh != 0 && base + i + 1 < value<N>::chunks)
            x |= v.data[base + i + 1] << ((32 - sh) % 32);
        r.data[i] = x;
    }
    r.data[value<bits>::chunks - 1] &= value<bits>::msb_mask;
    return r;
}
template<size_t Bit, size_t N>
static inline __attribute__((always_inline)) cxxrtl::value<1> vq_slice(const cxxrtl::value<N> &v) {
    return vq_slice<Bit, Bit>(v);
}
