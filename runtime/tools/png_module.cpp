// loddump's image module: the PNG writer of --render and the decoder of the pack's textures it shades
// with, the only OpenImageIO calls of loddump, built as a module that loddump loads with dlopen when
// --render is given. libOpenImageIO pulls in some 250 libraries whose start-up costs seconds per
// process (baker/src/image/oiio_module.h), and loddump must stay a lodrt-only program otherwise. The
// interface is plain C so the module needs no C++ ABI agreement.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

namespace {

void setError(char* error, size_t error_size, std::string message) {
    for (char& c : message)
        if (c == '\n') c = ' '; // messages are one line
    if (error && error_size > 0) std::snprintf(error, error_size, "%s", message.c_str());
}

// A pack is untrusted: a texture whose header claims more pixels than this is not decoded.
constexpr uint64_t kMaxTexturePixels = uint64_t(1) << 26;

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

/// Decodes a PNG or JPEG held in data[0, size) to 8-bit RGBA, rows top to bottom (grey is spread to
/// RGB, a missing alpha is 255). Returns 0 with *pixels (width * height * 4 bytes, allocated with
/// malloc: release it with loddump_free), or -1 with a NUL-terminated message in error[0, error_size).
extern "C" __attribute__((visibility("default"))) int loddump_read_rgba8(const uint8_t* data, size_t size,
                                                                         uint8_t** pixels, uint32_t* width,
                                                                         uint32_t* height, char* error,
                                                                         size_t error_size) {
    *pixels = nullptr;
    const bool is_png = size >= 8 && data[0] == 0x89 && data[1] == 'P' && data[2] == 'N' && data[3] == 'G';
    const bool is_jpeg = size >= 3 && data[0] == 0xFF && data[1] == 0xD8 && data[2] == 0xFF;
    if (!is_png && !is_jpeg) {
        setError(error, error_size, "not a PNG or JPEG image");
        return -1;
    }
    try {
        OIIO::attribute("threads", 1);
        OIIO::Filesystem::IOMemReader reader(const_cast<uint8_t*>(data), size);
        OIIO::ImageSpec config;
        void* proxy = &reader;
        config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
        config.attribute("oiio:UnassociatedAlpha", 1); // as stored: no premultiplication by alpha
        std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(is_png ? "texture.png" : "texture.jpg", &config);
        if (!in) {
            setError(error, error_size, "cannot read the image header: " + OIIO::geterror());
            return -1;
        }
        const OIIO::ImageSpec& spec = in->spec();
        const int channels = spec.nchannels;
        if (spec.width <= 0 || spec.height <= 0 || channels < 1 || channels > 4 ||
            uint64_t(spec.width) * uint64_t(spec.height) > kMaxTexturePixels) {
            setError(error, error_size, "expected 1 to 4 channels and at most 2^26 pixels");
            return -1;
        }
        const size_t count = size_t(spec.width) * size_t(spec.height);
        std::vector<uint8_t> stored(count * size_t(channels));
        if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::UINT8, stored.data()) || in->has_error()) {
            setError(error, error_size, "cannot decode the image: " + in->geterror());
            return -1;
        }
        uint8_t* rgba = static_cast<uint8_t*>(std::malloc(count * 4));
        if (!rgba) {
            setError(error, error_size, "out of memory");
            return -1;
        }
        for (size_t i = 0; i < count; ++i) {
            const uint8_t* s = &stored[i * size_t(channels)];
            const bool has_colour = channels >= 3;
            for (int k = 0; k < 3; ++k) rgba[i * 4 + size_t(k)] = has_colour ? s[k] : s[0];
            rgba[i * 4 + 3] = channels == 2 ? s[1] : (channels == 4 ? s[3] : 255);
        }
        *pixels = rgba;
        *width = uint32_t(spec.width);
        *height = uint32_t(spec.height);
        return 0;
    } catch (const std::exception& e) {
        setError(error, error_size, std::string("OpenImageIO: ") + e.what());
        return -1;
    }
}

/// Releases what loddump_read_rgba8 allocated.
extern "C" __attribute__((visibility("default"))) void loddump_free(void* pointer) {
    std::free(pointer);
}
