// The bake's texture stage: the size rule applied to every level (LOD0 included, so no level ships a
// texture above the preset's cap), the handling of unreadable images, and one decode-and-pyramid job
// per texture (the image module filters and encodes inside it in parallel).
#include "bake/texture_levels.h"

#include <algorithm>
#include <cctype>
#include <limits>

#include "core/parallel.h"
#include "lodbake/cleanup/tangents.h"

namespace lodbake {
namespace bake_detail {

namespace {

// Textures sampled as colour (base colour, emissive) are sRGB; the rest hold linear data.
std::vector<bool> srgbTextures(const Mesh& mesh) {
    std::vector<bool> srgb(mesh.textures.size(), false);
    for (const Material& m : mesh.materials)
        for (const TextureSlot* slot : {&m.base_color_texture, &m.emissive_texture})
            if (slot->isSet() && size_t(slot->texture) < srgb.size()) srgb[size_t(slot->texture)] = true;
    return srgb;
}

// What the bake says of an image it cannot read, when it fails.
std::string unreadableHint() {
    return "; expected a PNG or JPEG file that decodes (textures.keep_unreadable_images ships it byte for byte)";
}

std::string keptMessage(const std::string& why) {
    return why + "; kept byte for byte in every level (keep_unreadable_images)";
}

// The source's size, or why it cannot be read. An unreadable image fails the bake unless the settings
// keep it; then *is_verbatim is set (or, for a texture without bytes, nothing can be kept).
Status readSource(const Texture& source, const std::string& label, const BakeSettings& settings,
                  Diagnostics& diagnostics, ImageSize* size, bool* is_readable, bool* is_verbatim) {
    const bool keep = settings.textures.keep_unreadable_images;
    if (source.bytes.empty()) {
        if (!keep) return invalidInput(label + ": no image data" + unreadableHint());
        diagnostics.warn(label + ": no image data to keep; the material slots using it are left empty");
        return Status::okStatus();
    }
    Result<ImageSize> probed = probeImageSize(source.bytes, label);
    if (probed.ok()) {
        *size = *probed;
        *is_readable = true;
        return Status::okStatus();
    }
    // The OpenImageIO module missing is the installation's problem, not the image's.
    if (probed.status().code() != StatusCode::InvalidInput) return probed.status();
    if (!keep) return invalidInput(probed.status().message() + unreadableHint());
    diagnostics.warn(keptMessage(probed.status().message()));
    *is_verbatim = true;
    return Status::okStatus();
}

bool sameSize(ImageSize a, ImageSize b) {
    return a.width == b.width && a.height == b.height;
}

} // namespace

std::string levelTextureName(const Texture& source, size_t texture_index, size_t level) {
    std::string base = source.name;
    if (base.empty()) base = source.uri.substr(source.uri.find_last_of('/') + 1);
    if (base.empty()) base = "texture" + std::to_string(texture_index);
    std::string lower = base;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    const std::string suffix = "_lod" + std::to_string(level);
    for (const char* ext : {".png", ".jpg", ".jpeg"}) {
        const size_t n = std::char_traits<char>::length(ext);
        if (lower.size() > n && lower.compare(lower.size() - n, n, ext) == 0)
            return base.substr(0, base.size() - n) + suffix + base.substr(base.size() - n);
    }
    return base + suffix;
}

Result<TextureLevels> textureLevels(const Mesh& lod0, size_t level_count, const LodMetrics& metrics,
                                    const BakeSettings& settings, const std::string& name, Diagnostics& diagnostics) {
    TextureLevels out;
    const std::vector<Texture>& sources = lod0.textures;
    const size_t count = sources.size();
    const std::vector<bool> srgb = srgbTextures(lod0);
    std::vector<ImageSize> source_sizes(count);
    std::vector<bool> readable(count, false), resizable(count, false);
    out.is_verbatim.assign(count, false);
    // Messages name the texture as its source names it (the MTL map or the glTF image uri).
    std::vector<std::string> labels(count);
    for (size_t t = 0; t < count; ++t) {
        const std::string& file = sources[t].uri.empty() ? sources[t].name : sources[t].uri;
        labels[t] = name + ": texture " + std::to_string(t) + (file.empty() ? "" : " '" + file + "'");
        bool is_readable = false, is_verbatim = false;
        LODBAKE_RETURN_IF_ERROR(readSource(sources[t], labels[t], settings, diagnostics, &source_sizes[t],
                                           &is_readable, &is_verbatim));
        readable[t] = is_readable;
        resizable[t] = is_readable && settings.textures.enabled;
        out.is_verbatim[t] = is_verbatim;
    }
    const TextureLodSettings& ts = settings.textures;
    out.sizes.assign(level_count, std::vector<ImageSize>(count));
    std::vector<std::vector<ImageSize>> wanted(count);
    for (size_t l = 0; l < level_count; ++l)
        for (size_t t = 0; t < count; ++t) {
            ImageSize& size = out.sizes[l][t];
            size = source_sizes[t];
            if (!resizable[t]) continue;
            // LOD0 is seen from any distance up to its switch: only the cap limits it.
            const double target = l == 0 ? std::numeric_limits<double>::infinity()
                                         : metrics.levels[l].screen_coverage * settings.viewport_height_px *
                                               ts.texels_per_pixel;
            size = levelTextureSize(source_sizes[t], target, ts.min_size_px, ts.max_size_px);
            if (sameSize(size, source_sizes[t])) continue;
            if (out.resized.emplace(std::make_pair(t, std::make_pair(size.width, size.height)), std::vector<uint8_t>())
                    .second)
                wanted[t].push_back(size);
        }
    // One job per texture: decode once, then the pyramid and every size it needs (parallel inside).
    // A texture no level resizes is decoded all the same: a PNG or JPEG whose header reads but whose
    // pixels do not is as unreadable as one whose header does not, and must not ship unnoticed.
    std::vector<Result<std::vector<std::vector<uint8_t>>>> job_results(
        count, Result<std::vector<std::vector<uint8_t>>>(std::vector<std::vector<uint8_t>>()));
    LODBAKE_RETURN_IF_ERROR(parallelFor(count, 1, [&](size_t t) {
        if (!readable[t]) return;
        TextureResizeOptions options;
        options.is_srgb = srgb[t];
        job_results[t] = resizeEncodedImageLevels(sources[t].bytes, labels[t], wanted[t], options);
    }));
    for (size_t t = 0; t < count; ++t) {
        if (!job_results[t].ok()) {
            const Status& failed = job_results[t].status();
            // A header that reads but pixels that do not: damaged, like an unreadable image.
            if (failed.code() != StatusCode::InvalidInput) return failed;
            if (!ts.keep_unreadable_images) return invalidInput(failed.message() + unreadableHint());
            diagnostics.warn(keptMessage(failed.message()));
            out.is_verbatim[t] = true;
            for (std::vector<ImageSize>& level : out.sizes) level[t] = source_sizes[t];
            for (const ImageSize& s : wanted[t]) out.resized.erase({t, {s.width, s.height}});
            continue;
        }
        for (size_t k = 0; k < wanted[t].size(); ++k)
            out.resized[{t, {wanted[t][k].width, wanted[t][k].height}}] = std::move(job_results[t].value()[k]);
    }
    return out;
}

Status addNormalMapTangents(Mesh& mesh, const std::string& name, Diagnostics& diagnostics) {
    const int uv_set = tangentUvSet(mesh);
    if (uv_set < 0) return Status::okStatus();
    LODBAKE_ASSIGN_OR_RETURN(const TangentReport report, generateTangents(mesh, uint32_t(uv_set), name));
    diagnostics.note(name + ": tangents generated for the normal map (MikkTSpace, texture coordinates " +
                     std::to_string(uv_set) + "), " + std::to_string(report.vertices_added) + " vertices split");
    return Status::okStatus();
}

void applyTextureLevels(const TextureLevels& textures, std::vector<PackLevel>& levels) {
    if (levels.empty()) return;
    // LOD0's textures keep their names and URIs (only their bytes may change), so they name the levels.
    const std::vector<Texture>& sources = levels[0].mesh.textures;
    for (size_t l = 0; l < levels.size() && l < textures.sizes.size(); ++l) {
        std::vector<Texture>& level_textures = levels[l].mesh.textures;
        for (size_t t = 0; t < level_textures.size() && t < sources.size(); ++t) {
            if (textures.is_verbatim[t]) {
                level_textures[t].is_verbatim = true;
                continue;
            }
            const ImageSize& size = textures.sizes[l][t];
            const auto found = textures.resized.find({t, {size.width, size.height}});
            if (found == textures.resized.end()) continue;
            level_textures[t].bytes = found->second;
            if (l > 0) level_textures[t].name = levelTextureName(sources[t], t, l);
        }
    }
}

} // namespace bake_detail
} // namespace lodbake
