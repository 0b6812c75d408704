// liblodbake_oiio: every OpenImageIO call of the baker (loaded on demand, see oiio_module.h).
// sRGB images are converted to linear light before filtering and back afterwards, so averaging does
// not darken them; sizes are reached by repeated 2:1 halving (mipmap style) with a Lanczos-3 filter.
#include "image/oiio_module.h"

#include <algorithm>
#include <exception>
#include <memory>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

namespace {

// A file name whose extension makes OpenImageIO pick the right codec; the bytes come from memory.
const char* codecName(const uint8_t* b, size_t size) {
    if (size >= 8 && b[0] == 0x89 && b[1] == 'P' && b[2] == 'N' && b[3] == 'G') return "texture.png";
    if (size >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) return "texture.jpg";
    return nullptr;
}

bool fail(std::string* error, const std::string& message) {
    *error = message;
    return false;
}

// OpenImageIO works on the caller's thread only: the baker parallelises across textures itself, and no
// pool threads are left running when the process exits. Set once, when the module is first used.
void configureOnce() {
    static const bool configured = [] {
        OIIO::attribute("threads", 1);
        return true;
    }();
    (void)configured;
}

// An ImageInput reading the encoded bytes from memory (no file, no ImageCache).
bool openInput(const char* codec, OIIO::Filesystem::IOMemReader* reader, std::unique_ptr<OIIO::ImageInput>* input,
               std::string* error) {
    configureOnce();
    OIIO::ImageSpec config;
    void* proxy = reader;
    config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
    *input = OIIO::ImageInput::open(codec, &config);
    if (!*input) {
        std::string why = OIIO::geterror();
        std::replace(why.begin(), why.end(), '\n', ' '); // messages are one line
        return fail(error, "cannot read the image header: " + why);
    }
    return true;
}

bool encode(const OIIO::ImageBuf& linear, bool convert, const char* codec, const OIIO::TypeDesc& source_format,
            int channels, int jpeg_quality, std::vector<uint8_t>* out, std::string* error) {
    const OIIO::ImageSpec& spec = linear.spec();
    OIIO::ImageBuf pixels_buf = linear;
    if (convert) {
        pixels_buf = OIIO::ImageBufAlgo::colorconvert(linear, "linear", "sRGB", true, "", "", nullptr, {}, 1);
        if (pixels_buf.has_error()) return fail(error, "colour conversion failed: " + pixels_buf.geterror());
    }
    // Only the pixel layout is carried over: no timestamps or software tags (STYLE.md §7).
    const bool is_jpeg = codec[8] == 'j';
    OIIO::TypeDesc format = source_format;
    if (is_jpeg || format != OIIO::TypeDesc::UINT16) format = OIIO::TypeDesc::UINT8;
    OIIO::ImageSpec out_spec(spec.width, spec.height, channels, format);
    if (is_jpeg) out_spec.attribute("Compression", "jpeg:" + std::to_string(std::min(std::max(jpeg_quality, 1), 100)));
    std::vector<unsigned char> out_bytes;
    OIIO::Filesystem::IOVecOutput writer(out_bytes);
    auto output = OIIO::ImageOutput::create(codec);
    if (!output) return fail(error, std::string("no encoder for ") + codec);
    if (!output->set_ioproxy(&writer)) return fail(error, "the encoder cannot write to memory");
    std::vector<float> pixels(size_t(spec.width) * size_t(spec.height) * size_t(channels));
    const OIIO::ROI roi(0, spec.width, 0, spec.height, 0, 1, 0, channels);
    if (!pixels_buf.get_pixels(roi, OIIO::TypeDesc::FLOAT, pixels.data()))
        return fail(error, "reading resized pixels failed: " + pixels_buf.geterror());
    if (!output->open(codec, out_spec) || !output->write_image(OIIO::TypeDesc::FLOAT, pixels.data()) ||
        !output->close())
        return fail(error, "encoding failed: " + output->geterror());
    out->assign(out_bytes.begin(), out_bytes.end());
    return true;
}

OIIO::ImageBuf resizeTo(const OIIO::ImageBuf& src, uint32_t width, uint32_t height, int channels, const char* filter) {
    const OIIO::ROI roi(0, int(width), 0, int(height), 0, 1, 0, channels);
    return OIIO::ImageBufAlgo::resize(src, filter, 0.0f, roi, 1);
}

bool resizeLevelsImpl(const uint8_t* data, size_t size, const uint32_t* sizes, size_t count, bool is_srgb,
                      int jpeg_quality, const char* filter, std::vector<std::vector<uint8_t>>* out,
                      std::string* error) {
    const char* codec = codecName(data, size);
    if (!codec) return fail(error, "not a PNG or JPEG image");
    // Decoded through ImageInput into a buffer this call owns: an ImageBuf opened by name would go
    // through OpenImageIO's process-wide ImageCache, where every texture is "texture.png" and the
    // memory reader of an earlier call may be looked up after it is gone.
    OIIO::Filesystem::IOMemReader reader(const_cast<uint8_t*>(data), size);
    std::unique_ptr<OIIO::ImageInput> input;
    if (!openInput(codec, &reader, &input, error)) return false;
    OIIO::ImageSpec float_spec = input->spec();
    const OIIO::TypeDesc source_format = float_spec.format;
    float_spec.set_format(OIIO::TypeDesc::FLOAT);
    OIIO::ImageBuf src(float_spec, OIIO::InitializePixels::No);
    // libjpeg (and libpng for some damage) reports a truncated or corrupt stream as a warning and
    // fills the missing pixels with grey; OpenImageIO records the warning but read_image succeeds.
    // A damaged texture must fail the bake, not become a partly grey level, so any error counts.
    const bool is_read = input->read_image(0, 0, 0, float_spec.nchannels, OIIO::TypeDesc::FLOAT, src.localpixels());
    if (!is_read || input->has_error()) {
        std::string why = input->geterror();
        std::replace(why.begin(), why.end(), '\n', ' ');
        return fail(error, "cannot decode the image: " + (why.empty() ? std::string("read failed") : why));
    }
    input->close();
    input.reset();
    const int channels = src.spec().nchannels;
    const uint32_t width = uint32_t(src.spec().width), height = uint32_t(src.spec().height);
    for (size_t i = 0; i < count; ++i)
        if (sizes[2 * i] == 0 || sizes[2 * i + 1] == 0 || sizes[2 * i] > width || sizes[2 * i + 1] > height)
            return fail(error, "cannot make a " + std::to_string(sizes[2 * i]) + "x" + std::to_string(sizes[2 * i + 1]) +
                                   " level of a " + std::to_string(width) + "x" + std::to_string(height) + " image");
    const bool convert = is_srgb && channels >= 3;
    OIIO::ImageBuf current = src;
    if (convert) {
        current = OIIO::ImageBufAlgo::colorconvert(src, "sRGB", "linear", true, "", "", nullptr, {}, 1);
        if (current.has_error()) return fail(error, "colour conversion failed: " + current.geterror());
    }
    out->assign(count, {});
    std::vector<bool> done(count, false);
    size_t remaining = count;
    uint32_t w = width, h = height;
    while (remaining > 0) {
        const uint32_t next_w = std::max<uint32_t>(1, (w + 1) / 2), next_h = std::max<uint32_t>(1, (h + 1) / 2);
        const bool last_step = w == 1 && h == 1;
        for (size_t i = 0; i < count; ++i) {
            if (done[i]) continue;
            const uint32_t sw = sizes[2 * i], sh = sizes[2 * i + 1];
            const bool exact = sw == w && sh == h;
            // Sizes between this step and the next come straight from this step.
            const bool between = sw > next_w || sh > next_h || last_step;
            if (!exact && !between) continue;
            OIIO::ImageBuf level = exact ? current : resizeTo(current, sw, sh, channels, filter);
            if (level.has_error()) return fail(error, "resize failed: " + level.geterror());
            if (!encode(level, convert, codec, source_format, channels, jpeg_quality, &(*out)[i], error)) return false;
            done[i] = true;
            --remaining;
        }
        if (remaining == 0 || last_step) break;
        current = resizeTo(current, next_w, next_h, channels, filter);
        if (current.has_error()) return fail(error, "resize failed: " + current.geterror());
        w = next_w;
        h = next_h;
    }
    return true;
}

bool resizeLevels(const uint8_t* data, size_t size, const uint32_t* sizes, size_t count, bool is_srgb,
                  int jpeg_quality, const char* filter, std::vector<std::vector<uint8_t>>* out, std::string* error) {
    try {
        return resizeLevelsImpl(data, size, sizes, count, is_srgb, jpeg_quality, filter, out, error);
    } catch (const std::exception& e) {
        return fail(error, std::string("image processing failed: ") + e.what());
    }
}

bool probe(const uint8_t* data, size_t size, uint32_t* width, uint32_t* height, std::string* error) {
    const char* codec = codecName(data, size);
    if (!codec) return fail(error, "not a PNG or JPEG image");
    try {
        OIIO::Filesystem::IOMemReader reader(const_cast<uint8_t*>(data), size);
        std::unique_ptr<OIIO::ImageInput> input;
        if (!openInput(codec, &reader, &input, error)) return false;
        const OIIO::ImageSpec& spec = input->spec();
        if (spec.width <= 0 || spec.height <= 0) return fail(error, "image has no pixels");
        *width = uint32_t(spec.width);
        *height = uint32_t(spec.height);
        return true;
    } catch (const std::exception& e) {
        return fail(error, e.what());
    }
}

const lodbake::oiio_module::Api kApi{lodbake::oiio_module::kApiVersion, probe, resizeLevels};

} // namespace

extern "C" __attribute__((visibility("default"))) const lodbake::oiio_module::Api* lodbake_oiio_api() {
    return &kApi;
}
