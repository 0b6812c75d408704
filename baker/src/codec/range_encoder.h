#pragma once
// LZMA-style binary range encoder (and the raw bit writer beside it), the twin of RangeDecoder in runtime/src/valence_decoder.cpp
// (docs/format/valence.md "Range coder"). Adaptive 11-bit probabilities, 32-bit range, carry via a
// cached byte.

#include <cstdint>
#include <vector>

#include "lodrt/detail/valence_model.h"
#include "lodrt/format.h"

namespace lodbake::codec {

class RangeEncoder {
public:
    void bit(uint32_t& prob, uint32_t b) {
        using namespace lodrt::format;
        uint32_t bound = (range_ >> kRangeProbBits) * lodrt::detail::rangeProb(prob);
        if (b == 0) {
            range_ = bound;
        } else {
            low_ += bound;
            range_ -= bound;
        }
        prob = lodrt::detail::rangeUpdate(prob, b);
        while (range_ < kRangeTopValue) {
            range_ <<= 8;
            shiftLow();
        }
    }
    /// Multi-symbol adaptive coding of s < N (docs/format/valence.md "Range coder").
    template <uint32_t N, uint32_t R> void symbol(lodrt::detail::CdfModel<N, R>& m, uint32_t s) {
        using namespace lodrt::format;
        constexpr uint32_t n = N;
        const uint32_t r = range_ >> kRangeCdfBits;
        const uint32_t low = r * m.cum[s];
        const uint32_t high = s + 1 < n ? r * m.cum[s + 1] : range_;
        low_ += low;
        range_ = high - low;
        m.update(s);
        while (range_ < kRangeTopValue) {
            range_ <<= 8;
            shiftLow();
        }
    }
    void direct(uint32_t value, uint32_t count) {
        for (uint32_t i = count; i-- > 0;) {
            range_ >>= 1;
            if ((value >> i) & 1u) low_ += range_;
            while (range_ < lodrt::format::kRangeTopValue) {
                range_ <<= 8;
                shiftLow();
            }
        }
    }
    void tree(uint32_t* probs, uint32_t bits, uint32_t value) {
        uint32_t m = 1;
        for (uint32_t i = bits; i-- > 0;) {
            uint32_t b = (value >> i) & 1u;
            bit(probs[m], b);
            m = (m << 1) | b;
        }
    }
    /// Bit-length class of value+1, then its bits below the leading one (first modelled, rest direct).
    /// Returns the class.
    uint32_t uint(uint32_t* class_probs, uint32_t* top_probs, uint64_t value) {
        uint64_t v = value + 1;
        uint32_t k = 0;
        while ((v >> (k + 1)) != 0) ++k;
        tree(class_probs, lodrt::format::kValenceClassTreeBits, k);
        if (k >= 1) bit(top_probs[k], uint32_t((v >> (k - 1)) & 1u));
        if (k >= 2) direct(uint32_t(v & ((uint64_t(1) << (k - 1)) - 1)), k - 1);
        return k;
    }
    /// Residual r of component j in context ctx (docs/format/valence.md "Residuals"); returns the bit
    /// length of |r|.
    template <class Model, class Raw>
    uint32_t residual(Model& m, Raw& raw, int j, uint32_t ctx, int32_t r, uint32_t sign_ctx = 0) {
        const uint32_t mag = uint32_t(r < 0 ? -r : r);
        uint32_t k = 0;
        while ((mag >> k) != 0) ++k;
        symbol(m.length[j][ctx], k);
        if (k == 0) return 0;
        bit(m.sign[j][sign_ctx], r < 0 ? 1u : 0u);
        if (k >= 2) bit(m.top[j][k], (mag >> (k - 2)) & 1u);
        if (k >= 3) bit(m.second[j][2 * k + ((mag >> (k - 2)) & 1u)], (mag >> (k - 3)) & 1u);
        if (k >= 4) raw.write(mag & ((1u << (k - 3)) - 1), k - 3);
        return k;
    }
    /// Bytes written so far plus the ones held back for a carry (the size so far, to within 5 bytes).
    size_t bytesSoFar() const { return out_.size() + size_t(cache_size_); }
    std::vector<uint8_t> finish() {
        for (int i = 0; i < 5; ++i) shiftLow();
        return std::move(out_);
    }

private:
    void shiftLow() {
        if (uint32_t(low_) < 0xFF000000u || (low_ >> 32) != 0) {
            uint8_t carry = uint8_t(low_ >> 32);
            uint8_t temp = cache_;
            do {
                out_.push_back(uint8_t(temp + carry));
                temp = 0xFF;
            } while (--cache_size_ != 0);
            cache_ = uint8_t(low_ >> 24);
        }
        ++cache_size_;
        low_ = (low_ & 0x00FFFFFFu) << 8;
    }
    uint64_t low_ = 0;
    uint32_t range_ = 0xFFFFFFFFu;
    uint8_t cache_ = 0;
    uint64_t cache_size_ = 1;
    std::vector<uint8_t> out_;
};

/// Raw bit part of an attribute stream (docs/format/valence.md "Raw bits"): bits packed least
/// significant first, the last byte padded with zeros; the twin of BitReader in the decoder.
class BitWriter {
public:
    void write(uint32_t value, uint32_t count) {
        window_ |= uint64_t(value) << avail_;
        avail_ += count;
        while (avail_ >= 8) {
            out_.push_back(uint8_t(window_));
            window_ >>= 8;
            avail_ -= 8;
        }
    }
    /// Whole bytes written so far.
    size_t bytesSoFar() const { return out_.size(); }
    std::vector<uint8_t> finish() {
        if (avail_ > 0) out_.push_back(uint8_t(window_));
        window_ = 0;
        avail_ = 0;
        return std::move(out_);
    }

private:
    uint64_t window_ = 0;
    uint32_t avail_ = 0;
    std::vector<uint8_t> out_;
};

} // namespace lodbake::codec
