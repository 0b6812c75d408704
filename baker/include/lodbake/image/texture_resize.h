#pragma once
// Texture levels: decode an encoded image (PNG or JPEG) once, filter it down in linear light step by
// step (a pyramid, built on TBB) and encode the requested sizes again in the source's format.
// OpenImageIO stays inside this module (STYLE.md §2).

#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/core/status.h"

namespace lodbake {

struct ImageSize {
    uint32_t width = 0;
    uint32_t height = 0;
};

/// True when the bytes start with the PNG signature or a JPEG SOI marker (what the module decodes).
bool looksLikePngOrJpeg(const std::vector<uint8_t>& encoded);

/// Reads the dimensions from the header of an encoded PNG or JPEG. `name` prefixes messages.
Result<ImageSize> probeImageSize(const std::vector<uint8_t>& encoded, const std::string& name);

/// Decoded samples of an encoded PNG or JPEG, as stored: rows top to bottom, channels interleaved.
struct DecodedImage {
    uint32_t width = 0;
    uint32_t height = 0;
    uint32_t channels = 0;        // 1 grey, 2 grey + alpha, 3 RGB, 4 RGBA
    uint32_t bits = 8;            // 8 or 16 per sample
    std::vector<uint8_t> samples; // 16-bit samples as native uint16_t
};

/// Decodes a whole PNG or JPEG (a decoder warning is an error). `name` prefixes messages. A header
/// claiming more than max_pixels pixels is refused before decoding (ResourceLimit).
Result<DecodedImage> decodeImage(const std::vector<uint8_t>& encoded, const std::string& name,
                                 uint64_t max_pixels = uint64_t(1) << 28);

/// The size of a level texture whose larger side should be about `target_px` texels: the target is
/// rounded up to a power of two and clamped to [min_px, max_px]; both sides scale by the same
/// power-of-two factor (so power-of-two sources stay power-of-two, aspect ratios are kept). Never
/// larger than the source; each side at least 1.
ImageSize levelTextureSize(ImageSize source, double target_px, uint32_t min_px, uint32_t max_px);

struct TextureResizeOptions {
    ImageSize size;                  // output size (use levelTextureSize)
    bool is_srgb = true;             // colour data (base colour, emissive): filter in linear light, store sRGB again
    int jpeg_quality = 92;           // JPEG output quality, 1..100
    uint64_t max_source_pixels = uint64_t(1) << 28; // refuse sources with more pixels (16384 x 16384) before decoding
};

/// Several sizes of one image at once (texture levels): decodes once, then halves repeatedly in linear
/// light (each step a Lanczos-3 filter over (w + 1) / 2 x (h + 1) / 2, like mipmap generation), taking
/// every requested size from the nearest larger step; the steps are filtered and the sizes encoded in
/// parallel, with the same bytes at any thread count. A size equal to the source's is the decoded
/// image encoded again. Returns one encoded image per entry of `sizes`, in order; options.size is
/// ignored. Sizes larger than the source are an error, and so is a source whose header claims more
/// than options.max_source_pixels pixels (ResourceLimit, checked before anything is decoded).
Result<std::vector<std::vector<uint8_t>>> resizeEncodedImageLevels(const std::vector<uint8_t>& encoded,
                                                                   const std::string& name,
                                                                   const std::vector<ImageSize>& sizes,
                                                                   const TextureResizeOptions& options);

/// Resizes `encoded` (PNG or JPEG, detected from the bytes) and encodes the result in the same
/// format, channel count and bit depth. Deterministic (at any thread count; no metadata copied).
/// Errors: unknown or undecodable image, or a size of 0.
Result<std::vector<uint8_t>> resizeEncodedImage(const std::vector<uint8_t>& encoded, const std::string& name,
                                                const TextureResizeOptions& options);

} // namespace lodbake
