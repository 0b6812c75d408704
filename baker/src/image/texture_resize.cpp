// Texture downscaling with OpenImageIO. sRGB images are converted to linear light before filtering
// and back afterwards, so averaging does not darken them (the filtering happens on physical
// intensities; see e.g. OpenImageIO's ImageBufAlgo::colorconvert documentation).
#include "lodbake/image/texture_resize.h"

#include <algorithm>
#include <cmath>
#include <exception>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

namespace lodbake {

namespace {

// A file name whose extension makes OpenImageIO pick the right codec; the bytes come from memory.
const char* codecName(const std::vector<uint8_t>& b) {
    if (b.size() >= 8 && b[0] == 0x89 && b[1] == 'P' && b[2] == 'N' && b[3] == 'G') return "texture.png";
    if (b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) return "texture.jpg";
    return nullptr;
}

Result<std::vector<uint8_t>> resizeImpl(const std::vector<uint8_t>& encoded, const std::string& name,
                                        const TextureResizeOptions& options) {
    const char* codec = codecName(encoded);
    if (!codec) return invalidInput(name + ": not a PNG or JPEG image");
    if (options.size.width == 0 || options.size.height == 0) return invalidInput(name + ": output size is 0");
    OIIO::Filesystem::IOMemReader reader(encoded.data(), encoded.size());
    OIIO::ImageBuf src(codec, 0, 0, nullptr, nullptr, &reader);
    if (!src.read(0, 0, true, OIIO::TypeDesc::FLOAT))
        return invalidInput(name + ": cannot decode the image: " + src.geterror());
    const OIIO::ImageSpec& in_spec = src.spec();
    const int channels = in_spec.nchannels;
    OIIO::ImageBuf work = src;
    const bool convert = options.is_srgb && channels >= 3;
    if (convert) {
        work = OIIO::ImageBufAlgo::colorconvert(src, "sRGB", "linear", true, "", "", nullptr, {}, 1);
        if (work.has_error()) return internalError(name + ": colour conversion failed: " + work.geterror());
    }
    const OIIO::ROI roi(0, int(options.size.width), 0, int(options.size.height), 0, 1, 0, channels);
    OIIO::ImageBuf resized = OIIO::ImageBufAlgo::resize(work, options.filter, 0.0f, roi, 1);
    if (resized.has_error()) return internalError(name + ": resize failed: " + resized.geterror());
    if (convert) {
        resized = OIIO::ImageBufAlgo::colorconvert(resized, "linear", "sRGB", true, "", "", nullptr, {}, 1);
        if (resized.has_error()) return internalError(name + ": colour conversion failed: " + resized.geterror());
    }
    // Only the pixel layout is carried over: no timestamps or software tags (STYLE.md §7).
    const bool is_jpeg = codec[8] == 'j';
    OIIO::TypeDesc format = in_spec.format;
    if (is_jpeg || (format != OIIO::TypeDesc::UINT16)) format = OIIO::TypeDesc::UINT8;
    OIIO::ImageSpec out_spec(int(options.size.width), int(options.size.height), channels, format);
    if (is_jpeg)
        out_spec.attribute("Compression", "jpeg:" + std::to_string(std::min(std::max(options.jpeg_quality, 1), 100)));
    std::vector<unsigned char> out_bytes;
    OIIO::Filesystem::IOVecOutput writer(out_bytes);
    auto output = OIIO::ImageOutput::create(codec);
    if (!output) return internalError(name + ": no encoder for " + codec);
    if (!output->set_ioproxy(&writer)) return internalError(name + ": the encoder cannot write to memory");
    std::vector<float> pixels(size_t(options.size.width) * options.size.height * size_t(channels));
    if (!resized.get_pixels(roi, OIIO::TypeDesc::FLOAT, pixels.data()))
        return internalError(name + ": reading resized pixels failed: " + resized.geterror());
    if (!output->open(codec, out_spec) || !output->write_image(OIIO::TypeDesc::FLOAT, pixels.data()) ||
        !output->close())
        return internalError(name + ": encoding failed: " + output->geterror());
    return std::vector<uint8_t>(out_bytes.begin(), out_bytes.end());
}

} // namespace

Result<ImageSize> probeImageSize(const std::vector<uint8_t>& encoded, const std::string& name) {
    const char* codec = codecName(encoded);
    if (!codec) return invalidInput(name + ": not a PNG or JPEG image");
    try {
        OIIO::Filesystem::IOMemReader reader(encoded.data(), encoded.size());
        OIIO::ImageSpec config;
        void* proxy = &reader;
        config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
        auto input = OIIO::ImageInput::open(codec, &config);
        if (!input) return invalidInput(name + ": cannot read the image header: " + OIIO::geterror());
        const OIIO::ImageSpec& spec = input->spec();
        if (spec.width <= 0 || spec.height <= 0) return invalidInput(name + ": image has no pixels");
        return ImageSize{uint32_t(spec.width), uint32_t(spec.height)};
    } catch (const std::exception& e) {
        return internalError(name + ": " + e.what());
    }
}

ImageSize levelTextureSize(ImageSize source, double target_px, uint32_t min_px, uint32_t max_px) {
    const uint32_t largest = std::max(source.width, source.height);
    if (largest == 0) return source;
    uint64_t target = 1;
    const double wanted = std::isfinite(target_px) ? std::max(target_px, 1.0) : double(max_px);
    while (double(target) < wanted && target < (uint64_t(1) << 20)) target <<= 1;
    target = std::min<uint64_t>(std::max<uint64_t>(target, min_px), max_px);
    // Halve until the larger side fits: keeps the aspect ratio and power-of-two sides.
    ImageSize out = source;
    while (std::max(out.width, out.height) > target && std::max(out.width, out.height) > 1) {
        out.width = std::max<uint32_t>(1, (out.width + 1) / 2);
        out.height = std::max<uint32_t>(1, (out.height + 1) / 2);
    }
    return out;
}

Result<std::vector<uint8_t>> resizeEncodedImage(const std::vector<uint8_t>& encoded, const std::string& name,
                                                const TextureResizeOptions& options) {
    try {
        return resizeImpl(encoded, name, options);
    } catch (const std::exception& e) {
        return internalError(name + ": image processing failed: " + e.what());
    }
}

} // namespace lodbake
