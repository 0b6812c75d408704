// The bake pipeline. Assets are independent: each is processed into its own slot (with its own
// Diagnostics), and everything is serialised in input order on one thread (STYLE.md §7).
#include "lodbake/bake/bake.h"

#include <cmath>
#include <map>
#if defined(__GLIBC__)
#include <malloc.h>
#endif
#include <memory>
#include <set>

#include "core/parallel.h"
#include "lodbake/cleanup/repair.h"
#include "lodbake/core/json_writer.h"
#include "lodbake/gltf/gltf_io.h"
#include "lodbake/simplify/lod_chain.h"

namespace lodbake {

namespace {

constexpr double kPi = 3.14159265358979323846;

ScreenParams screenParams(const BakeSettings& s) {
    ScreenParams screen;
    screen.pixel_threshold = s.pixel_threshold;
    screen.viewport_height_px = s.viewport_height_px;
    screen.vertical_fov_rad = s.vertical_fov_deg * kPi / 180.0;
    return screen;
}

// Textures sampled as colour (base colour, emissive) are sRGB; the rest hold linear data.
std::vector<bool> srgbTextures(const Mesh& mesh) {
    std::vector<bool> srgb(mesh.textures.size(), false);
    for (const Material& m : mesh.materials)
        for (const TextureSlot* slot : {&m.base_color_texture, &m.emissive_texture})
            if (slot->isSet() && size_t(slot->texture) < srgb.size()) srgb[size_t(slot->texture)] = true;
    return srgb;
}

// Between stages, the large arrays of the stage just finished are free but glibc keeps most of them
// (its heap is not returned to the system while fragmented, and freeing a large block raises its
// mmap threshold, so the next stage's arrays come from the heap too): without this the resident
// size of the next stage adds to that of the last one. Releasing the free pages keeps the peak at
// the largest single stage.
void releaseFreeMemory() {
#if defined(__GLIBC__)
    malloc_trim(0);
#endif
}

struct AssetSlot {
    Status status = Status::okStatus();
    Diagnostics diagnostics;
    PackAsset asset;
    BakeAssetReport report;
};

Status bakeAsset(BakeInput& input, const BakeSettings& settings, const std::vector<PackStreamEncoder>& encoders,
                 AssetSlot& slot, size_t index, const BakeHooks& hooks) {
    Mesh& mesh = input.mesh;
    slot.report.name = input.name;
    slot.report.input_triangles = mesh.faceCount();
    slot.report.input_vertices = mesh.vertexCount();
    if (settings.repair) {
        StageTimer timer(hooks, index, BakeStage::Repair);
        LODBAKE_ASSIGN_OR_RETURN(RepairReport repair, repairMesh(mesh, RepairOptions{}, input.name, slot.diagnostics));
        slot.report.repair_unresolved = repair.unresolved;
        releaseFreeMemory();
    }
    const ScreenParams screen = screenParams(settings);
    LodChainOptions chain_options;
    chain_options.ratios = settings.lod_ratios;
    chain_options.screen = screen;
    chain_options.distance.sample_count = settings.error_samples;
    chain_options.record_collapses = false;
    for (const PackStreamEncoder& encoder : encoders) chain_options.record_collapses |= encoder.needs_collapses;
    StageTimer chain_timer(hooks, index, BakeStage::LodChain);
    Result<LodChain> chain_result = buildLodChain(mesh, chain_options, slot.diagnostics);
    if (!chain_result.ok())
        return Status(chain_result.status().code(), input.name + ": " + chain_result.status().message());
    LodChain chain = std::move(chain_result).value();
    releaseFreeMemory();
    const LodMetrics metrics = lodMetrics(mesh, chain, screen, settings.hysteresis);
    slot.report.metrics = metrics;
    chain_timer.finish();

    PackAsset& asset = slot.asset;
    asset.name = input.name;
    asset.screen_coverage = msftScreenCoverage(metrics);
    asset.node_extensions.push_back(lodMetricsExtension(metrics));
    asset.levels.resize(chain.levels.size() + 1);
    asset.levels[0].mesh = std::move(mesh);
    for (size_t l = 0; l < chain.levels.size(); ++l) asset.levels[l + 1].mesh = std::move(chain.levels[l].mesh);

    // Texture levels: LOD0 keeps the sources; level l's textures are sized for the object's projected
    // size at its switch distance. Equal sizes share one resized image (and so one glTF image).
    StageTimer texture_timer(hooks, index, BakeStage::Textures);
    const std::vector<Texture>& sources = asset.levels[0].mesh.textures;
    const std::vector<bool> srgb = srgbTextures(asset.levels[0].mesh);
    std::vector<ImageSize> source_sizes(sources.size());
    std::vector<bool> resizable(sources.size(), false);
    for (size_t t = 0; t < sources.size(); ++t) {
        Result<ImageSize> size = probeImageSize(sources[t].bytes, input.name + ": texture " + std::to_string(t));
        if (size.ok()) {
            source_sizes[t] = *size;
            resizable[t] = settings.textures.enabled;
        } else if (!sources[t].bytes.empty()) {
            slot.diagnostics.warn(size.status().message() + "; kept as is in every level");
        }
    }
    std::map<std::pair<size_t, std::pair<uint32_t, uint32_t>>, std::vector<uint8_t>> resized;
    std::vector<std::vector<ImageSize>> sizes(asset.levels.size(), std::vector<ImageSize>(sources.size()));
    for (size_t l = 0; l < asset.levels.size(); ++l)
        for (size_t t = 0; t < sources.size(); ++t) {
            sizes[l][t] = source_sizes[t];
            if (l == 0 || !resizable[t]) continue;
            const double target =
                metrics.levels[l].screen_coverage * settings.viewport_height_px * settings.textures.texels_per_pixel;
            sizes[l][t] =
                levelTextureSize(source_sizes[t], target, settings.textures.min_size_px, settings.textures.max_size_px);
            if (sizes[l][t].width != source_sizes[t].width || sizes[l][t].height != source_sizes[t].height)
                resized[{t, {sizes[l][t].width, sizes[l][t].height}}];
        }
    // One job per texture: decode and linearise once, then every size it needs (a halving chain).
    std::vector<std::vector<ImageSize>> wanted(sources.size());
    for (const auto& entry : resized)
        wanted[entry.first.first].push_back({entry.first.second.first, entry.first.second.second});
    std::vector<Result<std::vector<std::vector<uint8_t>>>> job_results(
        sources.size(), Result<std::vector<std::vector<uint8_t>>>(std::vector<std::vector<uint8_t>>()));
    LODBAKE_RETURN_IF_ERROR(parallelFor(sources.size(), 1, [&](size_t t) {
        if (wanted[t].empty()) return;
        TextureResizeOptions options;
        options.is_srgb = srgb[t];
        job_results[t] = resizeEncodedImageLevels(sources[t].bytes, input.name + ": texture " + std::to_string(t),
                                                  wanted[t], options);
    }));
    for (size_t t = 0; t < sources.size(); ++t) {
        if (!job_results[t].ok()) return job_results[t].status();
        for (size_t k = 0; k < wanted[t].size(); ++k)
            resized[{t, {wanted[t][k].width, wanted[t][k].height}}] = std::move(job_results[t].value()[k]);
    }
    for (size_t l = 1; l < asset.levels.size(); ++l) {
        std::vector<Texture>& textures = asset.levels[l].mesh.textures;
        for (size_t t = 0; t < textures.size() && t < sources.size(); ++t) {
            const auto found = resized.find({t, {sizes[l][t].width, sizes[l][t].height}});
            if (found == resized.end()) continue;
            textures[t].bytes = found->second;
            textures[t].name =
                sources[t].name + "_" + std::to_string(sizes[l][t].width) + "x" + std::to_string(sizes[l][t].height);
        }
    }
    slot.report.texture_sizes = sizes;
    texture_timer.finish();

    StageTimer encode_timer(hooks, index, BakeStage::Encode);
    for (const PackStreamEncoder& encoder : encoders) {
        for (size_t l = 0; l < asset.levels.size(); ++l)
            LODBAKE_RETURN_IF_ERROR(encoder.encode(chain, l, asset.levels[l]));
        releaseFreeMemory();
    }
    return Status::okStatus();
}

} // namespace

Result<BakeOutput> bake(std::vector<BakeInput> inputs, const BakeSettings& settings, Diagnostics& diagnostics) {
    return bake(std::move(inputs), settings, diagnostics, BakeHooks{});
}

Result<BakeOutput> bake(std::vector<BakeInput> inputs, const BakeSettings& settings, Diagnostics& diagnostics,
                        const BakeHooks& hooks) {
    LODBAKE_RETURN_IF_ERROR(validateSettings(settings, "settings"));
    if (inputs.empty()) return invalidInput("bake: no input meshes");
    std::unique_ptr<ScopedThreadLimit> limit;
    if (settings.threads > 0) limit = std::make_unique<ScopedThreadLimit>(settings.threads);
    // Unique group names, in input order.
    std::map<std::string, int> seen;
    for (BakeInput& input : inputs) {
        if (input.name.empty()) input.name = "mesh";
        const int n = seen[input.name]++;
        if (n > 0) input.name += "_" + std::to_string(n);
    }
    std::vector<PackStreamEncoder> encoders;
    for (PackStreamEncoder& encoder : builtinStreamEncoders())
        if (settings.progressive_fans || encoder.extension_name != "LODBAKE_progressive_fans")
            encoders.push_back(std::move(encoder));
    PackDescription description;
    description.compact = settings.compact;
    // Fail before the expensive stages when no stream encoder exists at all.
    if (settings.compact && encoders.empty()) LODBAKE_RETURN_IF_ERROR(checkCompact(description));

    std::vector<AssetSlot> slots(inputs.size());
    LODBAKE_RETURN_IF_ERROR(parallelFor(
        inputs.size(), 1, [&](size_t i) { slots[i].status = bakeAsset(inputs[i], settings, encoders, slots[i], i, hooks); }));
    BakeOutput output;
    for (AssetSlot& slot : slots) {
        for (const Diagnostic& d : slot.diagnostics.items()) {
            if (d.severity == Severity::Warning)
                diagnostics.warn(d.message);
            else
                diagnostics.note(d.message);
        }
        LODBAKE_RETURN_IF_ERROR(slot.status);
        description.assets.push_back(std::move(slot.asset));
        output.assets.push_back(std::move(slot.report));
    }
    LODBAKE_RETURN_IF_ERROR(checkCompact(description));
    releaseFreeMemory();
    StageTimer pack_timer(hooks, kWholePack, BakeStage::Pack);
    LODBAKE_ASSIGN_OR_RETURN(output.glb, writePackGlb(std::move(description)));
    return output;
}

std::string bakeReportJson(const BakeOutput& output, const BakeSettings& settings) {
    JsonWriter j;
    j.beginObject();
    j.field("packBytes", uint64_t(output.glb.size()));
    j.key("assets").beginArray();
    for (const BakeAssetReport& a : output.assets) {
        j.beginObject();
        j.field("name", a.name);
        j.field("inputTriangles", a.input_triangles);
        j.field("inputVertices", a.input_vertices);
        j.key("repairUnresolved").beginArray();
        for (const std::string& u : a.repair_unresolved) j.value(u);
        j.endArray();
        j.field("boundingRadius", a.metrics.bounding_radius);
        j.key("levels").beginArray();
        for (size_t l = 0; l < a.metrics.levels.size(); ++l) {
            const LodMetricsLevel& m = a.metrics.levels[l];
            j.beginObject();
            j.field("level", uint64_t(l));
            j.field("triangles", m.triangles);
            j.field("vertices", m.vertices);
            j.field("hausdorffError", m.hausdorff_error);
            j.field("hausdorffErrorRelative", m.hausdorff_error_rel);
            j.field("meanError", m.mean_error);
            j.field("meanErrorRelative", m.mean_error_rel);
            j.field("switchDistance", m.switch_distance);
            j.field("screenCoverage", m.screen_coverage);
            j.key("textures").beginArray();
            if (l < a.texture_sizes.size())
                for (const ImageSize& s : a.texture_sizes[l])
                    j.beginArray().value(uint64_t(s.width)).value(uint64_t(s.height)).endArray();
            j.endArray();
            j.endObject();
        }
        j.endArray();
        j.endObject();
    }
    j.endArray();
    j.field("pixelThreshold", settings.pixel_threshold);
    j.field("viewportHeight", settings.viewport_height_px);
    j.endObject();
    return j.str();
}

} // namespace lodbake
