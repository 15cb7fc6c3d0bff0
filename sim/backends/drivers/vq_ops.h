// The operations the generated code is rewritten to call (sim/backends/cxxrtl.py: _fast_slices,
// _fast_shifts): the same bits as CXXRTL's own, with less work. Included before the generated
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

// vq_shl_uu / vq_shr_uu / vq_shift_uu<BitsY>(a, b): CXXRTL's shl_uu (a zero-extended to BitsY, then
// shifted left by b), shr_uu and shift_uu (a shifted right by b in its own width, then zero-extended
// or truncated to BitsY), as one 64-bit machine shift when every operand fits in 64 bits (CXXRTL
// shifts chunk by chunk with carries). Wider operands go to CXXRTL's own.
template<size_t Bits>
static inline __attribute__((always_inline)) cxxrtl::value<Bits> vq_from_u64(uint64_t x) {
    cxxrtl::value<Bits> r;
    r.template set<uint64_t>(Bits >= 64 ? x : x & ((uint64_t(1) << (Bits % 64)) - 1));
    return r;
}
template<size_t BitsY, size_t BitsA, size_t BitsB>
static inline __attribute__((always_inline)) cxxrtl::value<BitsY> vq_shl_uu(const cxxrtl::value<BitsA> &a, const cxxrtl::value<BitsB> &b) {
    if constexpr (BitsY <= 64 && BitsA <= 64 && BitsB <= 64) {
        uint64_t n = b.template get<uint64_t>();
        return vq_from_u64<BitsY>(n >= BitsY ? 0 : a.template get<uint64_t>() << n);
    } else {
        return cxxrtl_yosys::shl_uu<BitsY>(a, b);
    }
}
template<size_t BitsY, size_t BitsA, size_t BitsB>
static inline __attribute__((always_inline)) cxxrtl::value<BitsY> vq_shr_uu(const cxxrtl::value<BitsA> &a, const cxxrtl::value<BitsB> &b) {
    if constexpr (BitsY <= 64 && BitsA <= 64 && BitsB <= 64) {
        uint64_t n = b.template get<uint64_t>();
        return vq_from_u64<BitsY>(n >= BitsA ? 0 : a.template get<uint64_t>() >> n);
    } else {
        return cxxrtl_yosys::shr_uu<BitsY>(a, b);
    }
}
template<size_t BitsY, size_t BitsA, size_t BitsB>
static inline __attribute__((always_inline)) cxxrtl::value<BitsY> vq_shift_uu(const cxxrtl::value<BitsA> &a, const cxxrtl::value<BitsB> &b) {
    return vq_shr_uu<BitsY>(a, b);
}
