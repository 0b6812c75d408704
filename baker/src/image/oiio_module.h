#pragma once
// Internal to the image module: the interface of liblodbake_oiio, the shared module that holds every
// OpenImageIO call. Debian's libOpenImageIO pulls in hundreds of libraries (OpenCV, GDAL, OpenVDB,
// FFmpeg...) whose loading slows every process start; loading it with dlopen only when a texture
// is actually resized keeps that cost away from every bake without textures and from every test
// process. Module and library are built by the same toolchain, so C++ types cross the boundary.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace lodbake {
namespace oiio_module {

constexpr int kApiVersion = 1;

struct Api {
    int version;
    /// Image dimensions from the header; false with *error set on failure.
    bool (*probe)(const uint8_t* data, size_t size, uint32_t* width, uint32_t* height, std::string* error);
    /// Decodes once, filters every requested size (sizes[2*i], sizes[2*i+1] = width, height) and encodes
    /// each in the source format. false with *error set on failure. Never throws.
    bool (*resizeLevels)(const uint8_t* data, size_t size, const uint32_t* sizes, size_t size_count, bool is_srgb,
                         int jpeg_quality, const char* filter, std::vector<std::vector<uint8_t>>* out,
                         std::string* error);
};

} // namespace oiio_module
} // namespace lodbake

/// The module's only exported symbol.
extern "C" const lodbake::oiio_module::Api* lodbake_oiio_api();
