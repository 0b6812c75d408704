#pragma once
// The binary range decoder of docs/format/valence.md "Range coder" (the twin of
// baker/src/codec/range_encoder.h), shared by the valence decoder and the PFRep format 3 decoder.

#include <cstddef>
#include <cstdint>

#include "lodrt/detail/valence_model.h"
#include "lodrt/format.h"

namespace lodrt {
namespace detail {

// LZMA-style binary range decoder. Reading past the end yields zeros and is remembered, so a cut
// stream is reported instead of read out of bounds.
class RangeDecoder {
public:
    bool init(const uint8_t* data, size_t size) {
        p_ = data;
        end_ = data + size;
        if (size < 5 || data[0] != 0) return false;
        for (int i = 0; i < 5; ++i) code_ = (code_ << 8) | next();
        return true;
    }
    // Branch-free: the decoded bits of well-mixed contexts are unpredictable, so select with masks
    // instead of branching on them (a compiler turns a plain `?:` on the comparison into a branch).
    // (A mispredicted branch costs more than the selects: docs/format/valence.md, "Toward version 7".)
    inline uint32_t bit(uint32_t& prob) { return bitWith(rangeProb(prob), prob); }
    // bit() with the probability already computed from the model (p == rangeProb(prob)).
    inline uint32_t bitWith(uint32_t p, uint32_t& prob) {
        const uint32_t bound = (range_ >> format::kRangeProbBits) * p;
        // All ones when code >= bound (bit 1): the sign of the 64-bit difference.
        const uint32_t mask = uint32_t((uint64_t(code_) - bound) >> 63) - 1u;
        code_ -= bound & mask;
        range_ = bound ^ ((bound ^ (range_ - bound)) & mask);
        prob = rangeUpdateMasked(prob, mask);
        // The bounds on p leave range >= 2^16: at most one byte.
        renormalizeOnce();
        return mask & 1u;
    }
    // Multi-symbol decode (docs/format/valence.md "Range coder", `symbol`): one division finds the
    // slot, a branch-free count over the cumulative table the symbol.
    template <uint32_t N, uint32_t R> inline uint32_t symbol(CdfModel<N, R>& m) {
        constexpr uint32_t n = N;
        const uint32_t r = range_ >> format::kRangeCdfBits;
        const uint32_t slot = code_ / r;
        const uint32_t s = m.find(slot);
        const uint32_t low = r * m.cum[s];
        // cum[N] exists (2^15): the last symbol's high is the whole range instead (its rounding slack).
        const uint32_t last = 0u - uint32_t(s + 1 == n);
        const uint32_t high = (r * m.cum[s + 1] & ~last) | (range_ & last);
        code_ -= low;
        range_ = high - low;
        m.update(s);
        // A symbol is at least kRangeCdfMinFreq / 2^15 of a range >= 2^24: two bytes always suffice.
        renormalizeOnce();
        renormalizeOnce();
        return s;
    }
    inline uint32_t direct(uint32_t count) {
        uint32_t v = 0;
        for (uint32_t i = 0; i < count; ++i) {
            range_ >>= 1;
            const uint32_t b = code_ >= range_ ? 1u : 0u;
            code_ -= range_ & (0u - b);
            v = (v << 1) | b;
            if (range_ < format::kRangeTopValue) {
                range_ <<= 8;
                code_ = (code_ << 8) | next();
            }
        }
        return v;
    }
    // Same bits as a loop of bit(probs[m]), but both children's probabilities are computed before the
    // current bit is known, which takes the load and the mixing off the serial chain of decoded bits.
    inline uint32_t tree(uint32_t* probs, uint32_t bits) {
        uint32_t m = 1;
        uint32_t p = rangeProb(probs[1]);
        for (uint32_t i = 1; i < bits; ++i) {
            const uint32_t p0 = rangeProb(probs[2 * m]), p1 = rangeProb(probs[2 * m + 1]);
            const uint32_t b = bitWith(p, probs[m]);
            m = (m << 1) | b;
            p = b ? p1 : p0;
        }
        m = (m << 1) | bitWith(p, probs[m]);
        return m - (1u << bits);
    }
    // Bit-length class k of value+1 (6-bit tree), its top bit below the leading one modelled, the rest
    // direct. False for a class above 32 bits.
    bool uint(uint32_t* class_probs, uint32_t* top_probs, uint64_t* value) {
        const uint32_t k = tree(class_probs, format::kValenceClassTreeBits);
        if (k > 32) return false;
        uint64_t v = 1;
        if (k >= 1) v = (v << 1) | bit(top_probs[k]);
        if (k >= 2) v = (v << (k - 1)) | direct(k - 1);
        *value = v - 1;
        return true;
    }
    bool finishedExactly() const { return overrun_ == 0 && p_ == end_; }
    bool overrun() const { return overrun_ > 8; }

private:
    inline uint8_t next() {
        if (p_ < end_) return *p_++;
        ++overrun_;
        return 0;
    }
    // `if (range < 2^24) { range <<= 8; code = (code << 8) | next(); }` without branches: the byte
    // is loaded from a clamped address (a stream holds at least 5 bytes) and used only when due and
    // in bounds; past the end it reads as 0 and counts as an overrun, as next() does.
    inline void renormalizeOnce() {
        const uint32_t due = uint32_t(range_ < format::kRangeTopValue);
        const uint32_t in = uint32_t(p_ < end_);
        const uint8_t* at = in ? p_ : end_ - 1;
        const uint32_t byte = uint32_t(*at) & (0u - in);
        const uint32_t shift = due << 3;
        range_ <<= shift;
        code_ = (code_ << shift) | (byte & (0u - due));
        p_ += due & in;
        overrun_ += due & (in ^ 1u);
    }
    const uint8_t* p_ = nullptr;
    const uint8_t* end_ = nullptr;
    uint32_t range_ = 0xFFFFFFFFu;
    uint32_t code_ = 0;
    uint32_t overrun_ = 0;
};

} // namespace detail
} // namespace lodrt
