// loddump's PNG writer: the only OpenImageIO call of loddump, built as a module that loddump loads
// with dlopen when --render is given. libOpenImageIO pulls in some 250 libraries whose start-up costs
// seconds per process (baker/src/image/oiio_module.h), and loddump must stay a lodrt-only program
// otherwise. The interface is plain C so the module needs no C++ ABI agreement.
#include <cstdint>
#include <cstdio>
#include <exception>
#include <memory>
#include <string>

#include <OpenImageIO/imageio.h>

namespace {

void setError(char* error, size_t error_size, const std::string& message) {
    if (error && error_size > 0) std::snprintf(error, error_size, "%s", message.c_str());
}

} // namespace

/// Writes an 8-bit RGB image (rows top to bottom, tightly packed) to `path` in the format its
/// extension names. Returns 0 on success, -1 with a NUL-terminated message in error[0, error_size).
extern "C" __attribute__((visibility("default"))) int loddump_write_rgb8(const char* path, const uint8_t* rgb,
                                                                         uint32_t width, uint32_t height, char* error,
                                                                         size_t error_size) {
    try {
        std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(path);
        if (!out) {
            setError(error, error_size, "no image writer for this file name: " + OIIO::geterror());
            return -1;
        }
        OIIO::ImageSpec spec(int(width), int(height), 3, OIIO::TypeDesc::UINT8);
        if (!out->open(path, spec)) {
            setError(error, error_size, out->geterror());
            return -1;
        }
        if (!out->write_image(OIIO::TypeDesc::UINT8, rgb)) {
            setError(error, error_size, out->geterror());
            out->close();
            return -1;
        }
        if (!out->close()) {
            setError(error, error_size, out->geterror());
            return -1;
        }
        return 0;
    } catch (const std::exception& e) {
        setError(error, error_size, std::string("OpenImageIO: ") + e.what());
        return -1;
    }
}
