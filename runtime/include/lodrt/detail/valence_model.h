#pragma once
// Model state the .lbm encoder (baker/src/codec) and decoder (runtime/src/valence_decoder.cpp)
// must update identically, kept in one place so the two cannot drift apart (Draco's *_shared.h
// split). Not part of the runtime's API.

#include <cstddef>
#include <cstdint>

#include "lodrt/format.h"

namespace lodrt {
namespace detail {

/// Sets every adaptive binary probability to its initial value.
inline void initRangeProbs(uint16_t* probs, size_t n) {
    for (size_t i = 0; i < n; ++i) probs[i] = uint16_t(format::kRangeProbInit);
}

/// Ring of the N most recent values; at(0) is the newest. N is a power of two.
template <uint32_t N> struct Fifo {
    static_assert((N & (N - 1)) == 0, "Fifo size must be a power of two");
    uint32_t ring[N];
    uint32_t head = 0;
    uint32_t count = 0;
    uint32_t at(uint32_t i) const { return ring[(head - 1 - i) & (N - 1)]; }
    void push(uint32_t v) {
        ring[head & (N - 1)] = v;
        ++head;
        if (count < N) ++count;
    }
};

/// Move-to-front cache of recently referenced vertices.
template <uint32_t N> struct MoveToFront {
    uint32_t slot[N];
    uint32_t count = 0;
    int find(uint32_t v) const {
        for (uint32_t i = 0; i < count; ++i)
            if (slot[i] == v) return int(i);
        return -1;
    }
    void touch(uint32_t v) {
        int at = find(v);
        uint32_t i = at >= 0 ? uint32_t(at) : (count < N ? count++ : N - 1);
        for (; i > 0; --i) slot[i] = slot[i - 1];
        slot[0] = v;
    }
};

} // namespace detail
} // namespace lodrt
