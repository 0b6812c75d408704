#pragma once
// Internal to the image module: the interface of liblodbake_oiio, the shared module that holds every
// OpenImageIO call. Debian's libOpenImageIO pulls in hundreds of libraries (OpenCV, GDAL, OpenVDB,
// FFmpeg...) whose loading slows every process start; loading it with dlopen only when a texture
// is actually resized keeps that cost away from every bake without textures and from every test
// process. Module and library are built by the same toolchain, so C++ types cross the boundary.
//
// The module only decodes and encodes; filtering happens in the library (texture_pyramid.cpp), where
// it runs on TBB and its result does not depend on the thread count.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace lodbake {
namespace oiio_module {

constexpr int kApiVersion = 2;

/// Decoded pixels as the file stores them: rows top to bottom, channels interleaved.
struct Pixels {
    uint32_t width = 0;
    uint32_t height = 0;
    uint32_t channels = 0;     // 1 grey, 2 grey + alpha, 3 RGB, 4 RGBA
    uint32_t bits = 8;         // 8 or 16 bits per sample
    std::vector<uint8_t> data; // width * height * channels samples; 16-bit samples as native uint16_t
};

/// Which encoder writes a level: the source's own format.
enum class Codec { Png, Jpeg };

struct Api {
    int version;
    /// Image dimensions from the header; false with *error set on failure.
    bool (*probe)(const uint8_t* data, size_t size, uint32_t* width, uint32_t* height, std::string* error);
    /// Decodes a whole PNG or JPEG. Any decoder warning (libjpeg fills a truncated stream with grey and
    /// calls it a warning) is a failure. false with *error set on failure. Never throws.
    bool (*decode)(const uint8_t* data, size_t size, Pixels* out, std::string* error);
    /// Encodes `pixels` (JPEG: 8 bits, 1 or 3 channels) with no metadata. Never throws.
    bool (*encode)(const Pixels& pixels, Codec codec, int jpeg_quality, std::vector<uint8_t>* out,
                   std::string* error);
};

} // namespace oiio_module
} // namespace lodbake

/// The module's only exported symbol.
extern "C" const lodbake::oiio_module::Api* lodbake_oiio_api();
