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

Result<std::vector<uint8_t>> encode(const OIIO::ImageBuf& linear, bool convert, const char* codec,
                                    const OIIO::TypeDesc& source_format, int channels, int jpeg_quality,
                                    const std::string& name) {
    const OIIO::ImageSpec& spec = linear.spec();
    OIIO::ImageBuf pixels_buf = linear;
    if (convert) {
        pixels_buf = OIIO::ImageBufAlgo::colorconvert(linear, "linear", "sRGB", true, "", "", nullptr, {}, 1);
        if (pixels_buf.has_error()) return internalError(name + ": colour conversion failed: " + pixels_buf.geterror());
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
    if (!output) return internalError(name + ": no encoder for " + codec);
    if (!output->set_ioproxy(&writer)) return internalError(name + ": the encoder cannot write to memory");
    std::vector<float> pixels(size_t(spec.width) * size_t(spec.height) * size_t(channels));
    const OIIO::ROI roi(0, spec.width, 0, spec.height, 0, 1, 0, channels);
    if (!pixels_buf.get_pixels(roi, OIIO::TypeDesc::FLOAT, pixels.data()))
        return internalError(name + ": reading resized pixels failed: " + pixels_buf.geterror());
    if (!output->open(codec, out_spec) || !output->write_image(OIIO::TypeDesc::FLOAT, pixels.data()) ||
        !output->close())
        return internalError(name + ": encoding failed: " + output->geterror());
    return std::vector<uint8_t>(out_bytes.begin(), out_bytes.end());
}

OIIO::ImageBuf resizeTo(const OIIO::ImageBuf& src, uint32_t width, uint32_t height, int channels,
                        const std::string& filter) {
    const OIIO::ROI roi(0, int(width), 0, int(height), 0, 1, 0, channels);
    return OIIO::ImageBufAlgo::resize(src, filter, 0.0f, roi, 1);
}

Result<std::vector<std::vector<uint8_t>>> levelsImpl(const std::vector<uint8_t>& encoded, const std::string& name,
                                                     const std::vector<ImageSize>& sizes,
                                                     const TextureResizeOptions& options) {
    const char* codec = codecName(encoded);
    if (!codec) return invalidInput(name + ": not a PNG or JPEG image");
    OIIO::Filesystem::IOMemReader reader(encoded.data(), encoded.size());
    OIIO::ImageBuf src(codec, 0, 0, nullptr, nullptr, &reader);
    if (!src.read(0, 0, true, OIIO::TypeDesc::FLOAT))
        return invalidInput(name + ": cannot decode the image: " + src.geterror());
    const OIIO::TypeDesc source_format = src.spec().format;
    const int channels = src.spec().nchannels;
    const uint32_t width = uint32_t(src.spec().width), height = uint32_t(src.spec().height);
    for (const ImageSize& s : sizes)
        if (s.width == 0 || s.height == 0 || s.width > width || s.height > height)
            return invalidInput(name + ": cannot make a " + std::to_string(s.width) + "x" + std::to_string(s.height) +
                                " level of a " + std::to_string(width) + "x" + std::to_string(height) + " image");
    const bool convert = options.is_srgb && channels >= 3;
    OIIO::ImageBuf current = src;
    if (convert) {
        current = OIIO::ImageBufAlgo::colorconvert(src, "sRGB", "linear", true, "", "", nullptr, {}, 1);
        if (current.has_error()) return internalError(name + ": colour conversion failed: " + current.geterror());
    }
    std::vector<std::vector<uint8_t>> out(sizes.size());
    std::vector<bool> done(sizes.size(), false);
    size_t remaining = sizes.size();
    uint32_t w = width, h = height;
    while (remaining > 0) {
        const uint32_t next_w = std::max<uint32_t>(1, (w + 1) / 2), next_h = std::max<uint32_t>(1, (h + 1) / 2);
        const bool last_step = w == 1 && h == 1;
        for (size_t i = 0; i < sizes.size(); ++i) {
            if (done[i]) continue;
            const bool exact = sizes[i].width == w && sizes[i].height == h;
            // Sizes between this step and the next come straight from this step.
            const bool between = sizes[i].width > next_w || sizes[i].height > next_h || last_step;
            if (!exact && !between) continue;
            OIIO::ImageBuf level = exact ? current : resizeTo(current, sizes[i].width, sizes[i].height, channels,
                                                              options.filter);
            if (level.has_error()) return internalError(name + ": resize failed: " + level.geterror());
            LODBAKE_ASSIGN_OR_RETURN(out[i], encode(level, convert, codec, source_format, channels,
                                                    options.jpeg_quality, name));
            done[i] = true;
            --remaining;
        }
        if (remaining == 0 || last_step) break;
        current = resizeTo(current, next_w, next_h, channels, options.filter);
        if (current.has_error()) return internalError(name + ": resize failed: " + current.geterror());
        w = next_w;
        h = next_h;
    }
    return out;
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

Result<std::vector<std::vector<uint8_t>>> resizeEncodedImageLevels(const std::vector<uint8_t>& encoded,
                                                                   const std::string& name,
                                                                   const std::vector<ImageSize>& sizes,
                                                                   const TextureResizeOptions& options) {
    try {
        return levelsImpl(encoded, name, sizes, options);
    } catch (const std::exception& e) {
        return internalError(name + ": image processing failed: " + e.what());
    }
}

Result<std::vector<uint8_t>> resizeEncodedImage(const std::vector<uint8_t>& encoded, const std::string& name,
                                                const TextureResizeOptions& options) {
    if (!codecName(encoded)) return invalidInput(name + ": not a PNG or JPEG image");
    if (options.size.width == 0 || options.size.height == 0) return invalidInput(name + ": output size is 0");
    LODBAKE_ASSIGN_OR_RETURN(std::vector<std::vector<uint8_t>> levels,
                             resizeEncodedImageLevels(encoded, name, {options.size}, options));
    return std::move(levels[0]);
}

} // namespace lodbake
