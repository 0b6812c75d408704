// Texture filtering in linear light: sRGB transfer tables, separable Lanczos-3 resampling (the filter
// widened by the scale factor, so a 2:1 step averages over 12 source texels per axis), and rounding
// back to stored samples. Rows are split across TBB tasks; each output sample is computed by the same
// sequence of operations whichever task computes it, so the bytes do not depend on the thread count.
#include "image/texture_pyramid.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

#include "core/parallel.h"

namespace lodbake {
namespace image_detail {

namespace {

using oiio_module::Pixels;

constexpr size_t kRowsPerTask = 8;

double srgbToLinear(double c) {
    return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

double linearToSrgb(double l) {
    return l <= 0.0031308 ? l * 12.92 : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
}

// Decoded sample -> linear value, for 8-bit samples (256 entries) and 16-bit ones (65536 entries).
struct DecodeTables {
    std::array<float, 256> srgb8{}, linear8{};
    std::vector<float> srgb16, linear16;
    // The linear value halfway between two consecutive 8-bit sRGB codes: a linear value rounds to the
    // number of thresholds at or below it, which is round(255 * linearToSrgb(value)).
    std::array<float, 255> srgb8_thresholds{};
    std::array<uint8_t, 4096> srgb8_guess{}; // code of linear value i / 4095
};

const DecodeTables& tables() {
    static const DecodeTables t = [] {
        DecodeTables d;
        for (int i = 0; i < 256; ++i) {
            d.srgb8[size_t(i)] = float(srgbToLinear(i / 255.0));
            d.linear8[size_t(i)] = float(i / 255.0);
        }
        for (int i = 0; i < 255; ++i) d.srgb8_thresholds[size_t(i)] = float(srgbToLinear((i + 0.5) / 255.0));
        for (int i = 0; i < 4096; ++i)
            d.srgb8_guess[size_t(i)] = uint8_t(std::upper_bound(d.srgb8_thresholds.begin(), d.srgb8_thresholds.end(),
                                                                float(i) / 4095.0f) -
                                               d.srgb8_thresholds.begin());
        d.srgb16.resize(65536);
        d.linear16.resize(65536);
        for (int i = 0; i < 65536; ++i) {
            d.srgb16[size_t(i)] = float(srgbToLinear(i / 65535.0));
            d.linear16[size_t(i)] = float(i / 65535.0);
        }
        return d;
    }();
    return t;
}

// round(255 * linearToSrgb(v)) for v in [0, 1]: the number of thresholds at or below v, found from a
// first guess (the code of v's bucket in a 4096-entry table) and a step or two along the thresholds.
uint8_t srgbCode(const DecodeTables& t, float v) {
    uint32_t code = t.srgb8_guess[size_t(v * 4095.0f)];
    while (code < 255 && t.srgb8_thresholds[code] <= v) ++code;
    while (code > 0 && t.srgb8_thresholds[code - 1] > v) --code;
    return uint8_t(code);
}

// The colour channels an sRGB transfer applies to: all but alpha (the last of 2 or 4 channels).
bool isColourChannel(uint32_t channel, uint32_t channels) {
    return !((channels == 2 || channels == 4) && channel == channels - 1);
}

double lanczos3(double x) {
    x = std::fabs(x);
    if (x < 1e-12) return 1.0;
    if (x >= 3.0) return 0.0;
    constexpr double kPi = 3.14159265358979323846;
    const double px = kPi * x;
    return 3.0 * std::sin(px) * std::sin(px / 3.0) / (px * px);
}

// For each output sample along one axis: `per_output` source indices (clamped at the edges) and
// normalised weights.
struct Taps {
    uint32_t per_output = 0;
    std::vector<uint32_t> index;
    std::vector<float> weight;
    std::vector<uint8_t> is_contiguous; // per output: index[k] == index[0] + k for every tap
};

void markContiguous(Taps& taps) {
    const size_t outputs = taps.per_output ? taps.index.size() / taps.per_output : 0;
    taps.is_contiguous.assign(outputs, 1);
    for (size_t i = 0; i < outputs; ++i)
        for (uint32_t k = 1; k < taps.per_output; ++k)
            if (taps.index[i * taps.per_output + k] != taps.index[i * taps.per_output] + k) taps.is_contiguous[i] = 0;
}

Taps lanczosTaps(uint32_t source, uint32_t target) {
    Taps taps;
    if (source == target) {
        taps.per_output = 1;
        for (uint32_t i = 0; i < target; ++i) taps.index.push_back(i);
        taps.weight.assign(target, 1.0f);
        markContiguous(taps);
        return taps;
    }
    const double scale = double(source) / double(target);
    const double support = 3.0 * std::max(scale, 1.0);
    auto range = [&](uint32_t i, int64_t* lo, int64_t* hi) {
        const double centre = (double(i) + 0.5) * scale;
        *lo = int64_t(std::ceil(centre - support - 0.5));
        *hi = int64_t(std::floor(centre + support - 0.5));
    };
    for (uint32_t i = 0; i < target; ++i) {
        int64_t lo = 0, hi = 0;
        range(i, &lo, &hi);
        taps.per_output = std::max(taps.per_output, uint32_t(std::max<int64_t>(hi - lo + 1, 1)));
    }
    taps.index.assign(size_t(target) * taps.per_output, 0);
    taps.weight.assign(size_t(target) * taps.per_output, 0.0f);
    std::vector<double> w(taps.per_output);
    for (uint32_t i = 0; i < target; ++i) {
        int64_t lo = 0, hi = 0;
        range(i, &lo, &hi);
        const double centre = (double(i) + 0.5) * scale;
        double sum = 0;
        for (uint32_t k = 0; k < taps.per_output; ++k) {
            const int64_t j = lo + int64_t(k);
            w[k] = j <= hi ? lanczos3((double(j) + 0.5 - centre) / std::max(scale, 1.0)) : 0.0;
            sum += w[k];
            taps.index[size_t(i) * taps.per_output + k] = uint32_t(std::clamp<int64_t>(j, 0, int64_t(source) - 1));
        }
        for (uint32_t k = 0; k < taps.per_output; ++k)
            taps.weight[size_t(i) * taps.per_output + k] = float(sum != 0 ? w[k] / sum : (k == 0 ? 1.0 : 0.0));
    }
    markContiguous(taps);
    return taps;
}

// Resamples rows [0, height) given by row(y, scratch) -> const float* (width * channels samples).
template <class RowFn>
Result<LinearImage> resampleRows(uint32_t width, uint32_t height, uint32_t channels, RowFn&& row,
                                 uint32_t out_width, uint32_t out_height) {
    if (out_width == 0 || out_height == 0 || out_width > width || out_height > height)
        return internalError("texture resample: " + std::to_string(out_width) + "x" + std::to_string(out_height) +
                             " from " + std::to_string(width) + "x" + std::to_string(height));
    const Taps across = lanczosTaps(width, out_width), down = lanczosTaps(height, out_height);
    const size_t c = channels, out_row = size_t(out_width) * c;
    // Horizontal pass over every source row.
    std::vector<float> narrow(size_t(height) * out_row);
    LODBAKE_RETURN_IF_ERROR(parallelForChunks(height, kRowsPerTask, [&](size_t, size_t first, size_t last) {
        std::vector<float> scratch;
        for (size_t y = first; y < last; ++y) {
            const float* in = row(uint32_t(y), scratch);
            float* out = &narrow[y * out_row];
            for (uint32_t x = 0; x < out_width; ++x) {
                const uint32_t* index = &across.index[size_t(x) * across.per_output];
                const float* weight = &across.weight[size_t(x) * across.per_output];
                float sum[4] = {0.0f, 0.0f, 0.0f, 0.0f};
                if (across.is_contiguous[x]) {
                    // Away from the edges the taps are consecutive texels: no index lookups.
                    const float* texel = in + size_t(index[0]) * c;
                    for (uint32_t k = 0; k < across.per_output; ++k, texel += c)
                        for (size_t ch = 0; ch < c; ++ch) sum[ch] += weight[k] * texel[ch];
                } else {
                    for (uint32_t k = 0; k < across.per_output; ++k)
                        for (size_t ch = 0; ch < c; ++ch) sum[ch] += weight[k] * in[size_t(index[k]) * c + ch];
                }
                for (size_t ch = 0; ch < c; ++ch) out[size_t(x) * c + ch] = sum[ch];
            }
        }
    }));
    // Vertical pass: each output row is a weighted sum of whole narrow rows, tap by tap.
    LinearImage out;
    out.width = out_width;
    out.height = out_height;
    out.channels = channels;
    out.samples.assign(size_t(out_height) * out_row, 0.0f);
    LODBAKE_RETURN_IF_ERROR(parallelForChunks(out_height, kRowsPerTask, [&](size_t, size_t first, size_t last) {
        for (size_t y = first; y < last; ++y) {
            float* dst = &out.samples[y * out_row];
            for (uint32_t k = 0; k < down.per_output; ++k) {
                const float w = down.weight[y * down.per_output + k];
                const float* src = &narrow[size_t(down.index[y * down.per_output + k]) * out_row];
                for (size_t i = 0; i < out_row; ++i) dst[i] += w * src[i];
            }
        }
    }));
    return out;
}

} // namespace

Result<LinearImage> resampleDecoded(const Pixels& source, bool is_srgb, uint32_t width, uint32_t height) {
    const DecodeTables& t = tables();
    const uint32_t c = source.channels;
    const size_t row_samples = size_t(source.width) * c;
    auto row = [&](uint32_t y, std::vector<float>& scratch) -> const float* {
        scratch.resize(row_samples);
        for (uint32_t ch = 0; ch < c; ++ch) {
            const bool colour = is_srgb && isColourChannel(ch, c);
            if (source.bits == 16) {
                const float* table = colour ? t.srgb16.data() : t.linear16.data();
                for (size_t i = ch; i < row_samples; i += c) {
                    uint16_t v;
                    std::memcpy(&v, &source.data[(size_t(y) * row_samples + i) * 2], 2);
                    scratch[i] = table[v];
                }
            } else {
                const float* table = colour ? t.srgb8.data() : t.linear8.data();
                const uint8_t* in = &source.data[size_t(y) * row_samples];
                for (size_t i = ch; i < row_samples; i += c) scratch[i] = table[in[i]];
            }
        }
        return scratch.data();
    };
    return resampleRows(source.width, source.height, c, row, width, height);
}

Result<LinearImage> resampleLinear(const LinearImage& source, uint32_t width, uint32_t height) {
    const size_t row_samples = size_t(source.width) * source.channels;
    auto row = [&](uint32_t y, std::vector<float>&) { return &source.samples[size_t(y) * row_samples]; };
    return resampleRows(source.width, source.height, source.channels, row, width, height);
}

Result<Pixels> quantise(const LinearImage& image, bool is_srgb, uint32_t bits) {
    const DecodeTables& t = tables();
    Pixels out;
    out.width = image.width;
    out.height = image.height;
    out.channels = image.channels;
    out.bits = bits == 16 ? 16 : 8;
    const uint32_t c = image.channels;
    const size_t row_samples = size_t(image.width) * c;
    out.data.assign(size_t(image.height) * row_samples * (out.bits / 8), 0);
    LODBAKE_RETURN_IF_ERROR(parallelForChunks(image.height, kRowsPerTask, [&](size_t, size_t first, size_t last) {
        for (size_t y = first; y < last; ++y)
            for (size_t i = 0; i < row_samples; ++i) {
                const float v = std::clamp(image.samples[y * row_samples + i], 0.0f, 1.0f);
                const bool colour = is_srgb && isColourChannel(uint32_t(i % c), c);
                const size_t at = y * row_samples + i;
                if (out.bits == 8) {
                    out.data[at] = colour ? srgbCode(t, v) : uint8_t(std::lround(double(v) * 255.0));
                } else {
                    const double encoded = colour ? linearToSrgb(double(v)) : double(v);
                    const uint16_t code = uint16_t(std::lround(std::clamp(encoded, 0.0, 1.0) * 65535.0));
                    std::memcpy(&out.data[at * 2], &code, 2);
                }
            }
    }));
    return out;
}

} // namespace image_detail
} // namespace lodbake
