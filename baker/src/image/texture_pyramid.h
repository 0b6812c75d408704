#pragma once
// Internal to the image module: the filtering half of texture levels. A decoded image is turned into
// linear light (colour channels of sRGB textures; alpha and data textures are linear already) and
// halved step by step with a separable Lanczos-3 filter. Every output sample is one fixed sum over
// fixed taps, and the work is split by rows only, so the result is the same at any thread count.

#include <cstdint>
#include <vector>

#include "image/oiio_module.h"
#include "lodbake/core/status.h"

namespace lodbake {
namespace image_detail {

/// Linear-light samples, rows top to bottom, channels interleaved.
struct LinearImage {
    uint32_t width = 0;
    uint32_t height = 0;
    uint32_t channels = 0;
    std::vector<float> samples;
};

/// `source` (decoded samples; sRGB colour channels when is_srgb) resampled to width x height in linear
/// light. Sizes at most the source's; an axis of equal size is copied, not filtered.
Result<LinearImage> resampleDecoded(const oiio_module::Pixels& source, bool is_srgb, uint32_t width, uint32_t height);

/// `source` resampled to width x height (at most the source's size).
Result<LinearImage> resampleLinear(const LinearImage& source, uint32_t width, uint32_t height);

/// Back to stored samples of `bits` (8 or 16), sRGB-encoding the colour channels when is_srgb; values are
/// clamped to [0, 1] (the filter's lobes overshoot at edges) and rounded to the nearest code.
Result<oiio_module::Pixels> quantise(const LinearImage& image, bool is_srgb, uint32_t bits);

} // namespace image_detail
} // namespace lodbake
