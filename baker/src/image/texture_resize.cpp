// Texture levels: the size rule here; decoding, filtering and encoding in liblodbake_oiio, which is
// loaded with dlopen on first use (oiio_module.h says why). Module search order: $LODBAKE_OIIO_MODULE,
// <executable dir>/../lib/lodbake/, <executable dir>/, then the build tree it was built in.
#include "lodbake/image/texture_resize.h"

#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <mutex>

#include "image/oiio_module.h"

namespace lodbake {

namespace {

bool isPngOrJpeg(const std::vector<uint8_t>& b) {
    return (b.size() >= 8 && b[0] == 0x89 && b[1] == 'P' && b[2] == 'N' && b[3] == 'G') ||
           (b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF);
}

std::string executableDir() {
    char buf[PATH_MAX];
    const ssize_t n = readlink("/proc/self/exe", buf, sizeof(buf) - 1);
    if (n <= 0) return "";
    std::string path(buf, size_t(n));
    const size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? "" : path.substr(0, slash);
}

struct Loaded {
    const oiio_module::Api* api = nullptr;
    std::string error;
};

const Loaded& loadModule() {
    static Loaded loaded;
    static std::once_flag once;
    std::call_once(once, [] {
        std::vector<std::string> candidates;
        if (const char* env = std::getenv("LODBAKE_OIIO_MODULE")) candidates.push_back(env);
        const std::string dir = executableDir();
        if (!dir.empty()) {
            candidates.push_back(dir + "/../lib/lodbake/" LODBAKE_OIIO_MODULE_NAME);
            candidates.push_back(dir + "/" LODBAKE_OIIO_MODULE_NAME);
        }
        candidates.push_back(LODBAKE_OIIO_MODULE_BUILD_PATH);
        std::string tried;
        for (const std::string& path : candidates) {
            void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
            if (!handle) {
                tried += (tried.empty() ? "" : "; ") + std::string(dlerror());
                continue;
            }
            using Entry = const oiio_module::Api* (*)();
            auto entry = reinterpret_cast<Entry>(dlsym(handle, "lodbake_oiio_api"));
            const oiio_module::Api* api = entry ? entry() : nullptr;
            if (api && api->version == oiio_module::kApiVersion) {
                loaded.api = api; // stays loaded for the life of the process
                return;
            }
            tried += (tried.empty() ? "" : "; ") + path + ": not a compatible lodbake OpenImageIO module";
            dlclose(handle);
        }
        loaded.error = "cannot load the OpenImageIO module (" + tried + ")";
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
    if (!isPngOrJpeg(encoded)) return invalidInput(name + ": not a PNG or JPEG image");
    const Loaded& module = loadModule();
    if (!module.api) return unsupported(name + ": " + module.error);
    // A few bytes of PNG or JPEG can claim gigapixels: refuse before the module decodes anything.
    LODBAKE_ASSIGN_OR_RETURN(const ImageSize source, probeImageSize(encoded, name));
    if (uint64_t(source.width) * source.height > options.max_source_pixels)
        return resourceLimit(name + ": image header: " + std::to_string(source.width) + " x " +
                             std::to_string(source.height) + " pixels, expected at most " +
                             std::to_string(options.max_source_pixels));
    std::vector<uint32_t> flat;
    for (const ImageSize& s : sizes) {
        flat.push_back(s.width);
        flat.push_back(s.height);
    }
    std::vector<std::vector<uint8_t>> out;
    std::string error;
    if (!module.api->resizeLevels(encoded.data(), encoded.size(), flat.data(), sizes.size(), options.is_srgb,
                                  options.jpeg_quality, options.filter.c_str(), &out, &error))
        return invalidInput(name + ": " + error);
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
