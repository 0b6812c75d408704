// Texture levels: the size rule and the pyramid's plan here, the filtering in texture_pyramid.cpp,
// decoding and encoding in liblodbake_oiio, which is loaded with dlopen on first use (oiio_module.h
// says why). Module search order: $LODBAKE_OIIO_MODULE,
// <executable dir>/../lib/lodbake/, <executable dir>/, then the build tree it was built in.
#include "lodbake/image/texture_resize.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <mutex>

#include "core/module_loader.h"
#include "core/parallel.h"
#include "image/oiio_module.h"
#include "image/texture_pyramid.h"

namespace lodbake {

namespace {

bool isPngOrJpeg(const std::vector<uint8_t>& b) {
    return (b.size() >= 8 && b[0] == 0x89 && b[1] == 'P' && b[2] == 'N' && b[3] == 'G') ||
           (b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF);
}

struct Loaded {
    const oiio_module::Api* api = nullptr;
    std::string error;
};

const Loaded& loadModule() {
    static Loaded loaded;
    static std::once_flag once;
    std::call_once(once, [] {
        const detail::ModuleSpec spec{"LODBAKE_OIIO_MODULE", LODBAKE_OIIO_MODULE_NAME, LODBAKE_OIIO_MODULE_BUILD_PATH,
                                      "lodbake_oiio_api", "OpenImageIO"};
        loaded.api = detail::openModule<oiio_module::Api>(spec, oiio_module::kApiVersion, &loaded.error);
    });
    return loaded;
}

} // namespace

bool looksLikePngOrJpeg(const std::vector<uint8_t>& encoded) {
    return isPngOrJpeg(encoded);
}

Result<ImageSize> probeImageSize(const std::vector<uint8_t>& encoded, const std::string& name) {
    if (!isPngOrJpeg(encoded)) return invalidInput(name + ": not a PNG or JPEG image");
    const Loaded& module = loadModule();
    if (!module.api) return unsupported(name + ": " + module.error);
    ImageSize size;
    std::string error;
    if (!module.api->probe(encoded.data(), encoded.size(), &size.width, &size.height, &error))
        return invalidInput(name + ": " + error);
    return size;
}

Result<DecodedImage> decodeImage(const std::vector<uint8_t>& encoded, const std::string& name, uint64_t max_pixels) {
    LODBAKE_ASSIGN_OR_RETURN(const ImageSize size, probeImageSize(encoded, name));
    if (uint64_t(size.width) * size.height > max_pixels)
        return resourceLimit(name + ": image header: " + std::to_string(size.width) + " x " +
                             std::to_string(size.height) + " pixels, expected at most " + std::to_string(max_pixels));
    const Loaded& module = loadModule();
    oiio_module::Pixels pixels;
    std::string error;
    if (!module.api->decode(encoded.data(), encoded.size(), &pixels, &error)) return invalidInput(name + ": " + error);
    DecodedImage out;
    out.width = pixels.width;
    out.height = pixels.height;
    out.channels = pixels.channels;
    out.bits = pixels.bits;
    out.samples = std::move(pixels.data);
    return out;
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

namespace {

// The halving steps a set of sizes needs: step 0 is the source, step k + 1 halves step k (rounding
// up), and size i comes from from_step[i], the smallest step at least as large on both axes.
struct StepPlan {
    std::vector<ImageSize> steps;
    std::vector<size_t> from_step;
    std::vector<bool> is_kept; // a step some size is taken from
};

StepPlan planSteps(ImageSize source, const std::vector<ImageSize>& sizes) {
    StepPlan plan;
    plan.steps.push_back(source);
    plan.from_step.assign(sizes.size(), 0);
    for (size_t i = 0; i < sizes.size(); ++i) {
        for (;;) {
            const ImageSize at = plan.steps[plan.from_step[i]];
            const ImageSize next{std::max<uint32_t>(1, (at.width + 1) / 2), std::max<uint32_t>(1, (at.height + 1) / 2)};
            const bool is_last = at.width == 1 && at.height == 1;
            if (is_last || sizes[i].width > next.width || sizes[i].height > next.height) break;
            if (plan.from_step[i] + 1 == plan.steps.size()) plan.steps.push_back(next);
            ++plan.from_step[i];
        }
    }
    plan.is_kept.assign(plan.steps.size(), false);
    for (size_t step : plan.from_step) plan.is_kept[step] = true;
    return plan;
}

} // namespace

Result<std::vector<std::vector<uint8_t>>> resizeEncodedImageLevels(const std::vector<uint8_t>& encoded,
                                                                   const std::string& name,
                                                                   const std::vector<ImageSize>& sizes,
                                                                   const TextureResizeOptions& options) {
    if (!isPngOrJpeg(encoded)) return invalidInput(name + ": not a PNG or JPEG image");
    const Loaded& module = loadModule();
    if (!module.api) return unsupported(name + ": " + module.error);
    // A few bytes of PNG or JPEG can claim gigapixels: refuse before the module decodes anything.
    LODBAKE_ASSIGN_OR_RETURN(const ImageSize source, probeImageSize(encoded, name));
    if (uint64_t(source.width) * source.height > options.max_source_pixels)
        return resourceLimit(name + ": image header: " + std::to_string(source.width) + " x " +
                             std::to_string(source.height) + " pixels, expected at most " +
                             std::to_string(options.max_source_pixels));
    oiio_module::Pixels decoded;
    std::string error;
    if (!module.api->decode(encoded.data(), encoded.size(), &decoded, &error)) return invalidInput(name + ": " + error);
    for (const ImageSize& s : sizes)
        if (s.width == 0 || s.height == 0 || s.width > decoded.width || s.height > decoded.height)
            return invalidInput(name + ": cannot make a " + std::to_string(s.width) + "x" + std::to_string(s.height) +
                                " level of a " + std::to_string(decoded.width) + "x" + std::to_string(decoded.height) +
                                " image");
    const StepPlan plan = planSteps({decoded.width, decoded.height}, sizes);
    // The pyramid: each step from the one before (the first from the decoded samples), parallel inside.
    std::vector<image_detail::LinearImage> steps(plan.steps.size());
    for (size_t k = 1; k < plan.steps.size(); ++k) {
        Result<image_detail::LinearImage> step =
            k == 1 ? image_detail::resampleDecoded(decoded, options.is_srgb, plan.steps[k].width, plan.steps[k].height)
                   : image_detail::resampleLinear(steps[k - 1], plan.steps[k].width, plan.steps[k].height);
        if (!step.ok()) return Status(step.status().code(), name + ": " + step.status().message());
        steps[k] = std::move(step).value();
        if (k >= 2 && !plan.is_kept[k - 1]) steps[k - 1] = {}; // no size needs it any more
    }
    // Every size from its step, filtered (when between steps), rounded and encoded side by side.
    const oiio_module::Codec codec = encoded[0] == 0x89 ? oiio_module::Codec::Png : oiio_module::Codec::Jpeg;
    std::vector<std::vector<uint8_t>> out(sizes.size());
    std::vector<Status> statuses(sizes.size(), Status::okStatus());
    LODBAKE_RETURN_IF_ERROR(parallelFor(sizes.size(), 1, [&](size_t i) {
        const size_t k = plan.from_step[i];
        const bool is_step = sizes[i].width == plan.steps[k].width && sizes[i].height == plan.steps[k].height;
        Result<oiio_module::Pixels> pixels = oiio_module::Pixels{};
        if (is_step && k == 0) {
            pixels = decoded;
        } else {
            // A size between two steps is filtered from the larger one; a step is rounded as it is.
            Result<image_detail::LinearImage> between = image_detail::LinearImage{};
            if (!is_step)
                between = k == 0 ? image_detail::resampleDecoded(decoded, options.is_srgb, sizes[i].width, sizes[i].height)
                                 : image_detail::resampleLinear(steps[k], sizes[i].width, sizes[i].height);
            if (!between.ok()) {
                statuses[i] = between.status();
                return;
            }
            const uint32_t bits = codec == oiio_module::Codec::Jpeg ? 8 : decoded.bits;
            pixels = image_detail::quantise(is_step ? steps[k] : *between, options.is_srgb, bits);
        }
        std::string encode_error;
        if (!pixels.ok())
            statuses[i] = pixels.status();
        else if (!module.api->encode(*pixels, codec, options.jpeg_quality, &out[i], &encode_error))
            statuses[i] = invalidInput(encode_error);
    }));
    for (const Status& s : statuses)
        if (!s.ok()) return Status(s.code(), name + ": " + s.message());
    return out;
}

Result<std::vector<uint8_t>> resizeEncodedImage(const std::vector<uint8_t>& encoded, const std::string& name,
                                                const TextureResizeOptions& options) {
    if (!isPngOrJpeg(encoded)) return invalidInput(name + ": not a PNG or JPEG image");
    if (options.size.width == 0 || options.size.height == 0) return invalidInput(name + ": output size is 0");
    LODBAKE_ASSIGN_OR_RETURN(std::vector<std::vector<uint8_t>> levels,
                             resizeEncodedImageLevels(encoded, name, {options.size}, options));
    return std::move(levels[0]);
}

} // namespace lodbake
