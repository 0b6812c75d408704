// The bake pipeline. Assets are independent: each is processed into its own slot (with its own
// Diagnostics), and everything is serialised in input order on one thread (STYLE.md §7).
#include "lodbake/bake/bake.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <memory>
#include <set>

#include "bake/phases.h"
#include "core/parallel.h"
#include "lodbake/cleanup/repair.h"
#include "lodbake/core/json_writer.h"
#include "lodbake/core/math.h"
#include "lodbake/pack/pack_glb.h"
#include "lodbake/simplify/lod_chain.h"
#include "lodbake/simplify/mesh_distance.h"

namespace lodbake {

namespace {

using bake_detail::concurrentPhases;
using bake_detail::PhaseTask;

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

struct AssetSlot {
    Status status = Status::okStatus();
    Diagnostics diagnostics;
    PackAsset asset;
    BakeAssetReport report;
};

// Texture levels: LOD0 keeps the sources; level l's textures are sized for the object's projected
// size at its switch distance. Equal sizes share one resized image (and so one glTF image).
struct TextureLevels {
    std::vector<std::vector<ImageSize>> sizes; // per level, per texture
    std::map<std::pair<size_t, std::pair<uint32_t, uint32_t>>, std::vector<uint8_t>>
        resized; // (texture, size) -> bytes
};

Result<TextureLevels> textureLevels(const Mesh& lod0, size_t level_count, const LodMetrics& metrics,
                                    const BakeSettings& settings, const std::string& name, Diagnostics& diagnostics) {
    TextureLevels out;
    const std::vector<Texture>& sources = lod0.textures;
    const std::vector<bool> srgb = srgbTextures(lod0);
    std::vector<ImageSize> source_sizes(sources.size());
    std::vector<bool> resizable(sources.size(), false);
    for (size_t t = 0; t < sources.size(); ++t) {
        Result<ImageSize> size = probeImageSize(sources[t].bytes, name + ": texture " + std::to_string(t));
        if (size.ok()) {
            source_sizes[t] = *size;
            resizable[t] = settings.textures.enabled;
        } else if (!sources[t].bytes.empty()) {
            diagnostics.warn(size.status().message() + "; kept as is in every level");
        }
    }
    out.sizes.assign(level_count, std::vector<ImageSize>(sources.size()));
    for (size_t l = 0; l < level_count; ++l)
        for (size_t t = 0; t < sources.size(); ++t) {
            out.sizes[l][t] = source_sizes[t];
            if (l == 0 || !resizable[t]) continue;
            const double target =
                metrics.levels[l].screen_coverage * settings.viewport_height_px * settings.textures.texels_per_pixel;
            out.sizes[l][t] =
                levelTextureSize(source_sizes[t], target, settings.textures.min_size_px, settings.textures.max_size_px);
            if (out.sizes[l][t].width != source_sizes[t].width || out.sizes[l][t].height != source_sizes[t].height)
                out.resized[{t, {out.sizes[l][t].width, out.sizes[l][t].height}}];
        }
    // One job per texture: decode and linearise once, then every size it needs (a halving chain).
    std::vector<std::vector<ImageSize>> wanted(sources.size());
    for (const auto& entry : out.resized)
        wanted[entry.first.first].push_back({entry.first.second.first, entry.first.second.second});
    std::vector<Result<std::vector<std::vector<uint8_t>>>> job_results(
        sources.size(), Result<std::vector<std::vector<uint8_t>>>(std::vector<std::vector<uint8_t>>()));
    LODBAKE_RETURN_IF_ERROR(parallelFor(sources.size(), 1, [&](size_t t) {
        if (wanted[t].empty()) return;
        TextureResizeOptions options;
        options.is_srgb = srgb[t];
        job_results[t] =
            resizeEncodedImageLevels(sources[t].bytes, name + ": texture " + std::to_string(t), wanted[t], options);
    }));
    for (size_t t = 0; t < sources.size(); ++t) {
        if (!job_results[t].ok()) return job_results[t].status();
        for (size_t k = 0; k < wanted[t].size(); ++k)
            out.resized[{t, {wanted[t][k].width, wanted[t][k].height}}] = std::move(job_results[t].value()[k]);
    }
    return out;
}

// measureLodChain (lod_chain.h) with the reference sides that a MeasureReference task measured
// (`reference_sides[i]` for chain level i, when present and ok).
void measureChain(const Mesh& mesh, LodChain& chain, const LodChainOptions& options,
                  const std::vector<Result<OneSidedDistance>>& reference_sides, Diagnostics& diagnostics) {
    std::vector<const OneSidedDistance*> known;
    for (size_t i = 0; i < chain.levels.size(); ++i)
        known.push_back(i < reference_sides.size() && reference_sides[i].ok() ? &*reference_sides[i] : nullptr);
    measureLodChain(mesh, chain, options, known, diagnostics);
}

// After the chain, the remaining work of an asset is a fixed set of tasks that only read the
// meshes (STYLE.md §7: each writes its own slot; which thread runs which, and when, changes no
// byte): the error measurement (then the metrics and texture levels that follow from it), and the
// stream encoders' prepare steps. They run in phases (concurrentPhases): with 2 threads a small
// asset's PFRep build (a replay of the chain's logged collapses, then the blob) runs beside the measurement and the
// valence coding of the levels; a large asset's PFRep build runs beside the measurement's reference sides
// (MeasureReference), then the rest of the measurement (parallel inside), then the coding of every level
// side by side. The commits (cheap; the valence commit renumbers its level) then run in encoder and level
// order on this thread.
Status bakeAsset(BakeInput& input, const BakeSettings& settings, const std::vector<PackStreamEncoder>& encoders,
                 AssetSlot& slot, size_t index, const BakeHooks& hooks) {
    Mesh& mesh = input.mesh;
    slot.report.name = input.name;
    slot.report.input_triangles = mesh.faceCount();
    slot.report.input_vertices = mesh.vertexCount();
    if (settings.repair) {
        StageTimer timer(hooks, index, BakeStage::Repair);
        RepairOptions repair_options;
        repair_options.report_welded = false; // only `unresolved` goes into the bake's report
        repair_options.report_before = false; // likewise: the input is validated only if a skip test needs it
        LODBAKE_ASSIGN_OR_RETURN(RepairReport repair, repairMesh(mesh, repair_options, input.name, slot.diagnostics));
        slot.report.repair_unresolved = repair.unresolved;
    }
    const ScreenParams screen = screenParams(settings);
    LodChainOptions chain_options;
    chain_options.ratios = settings.lod_ratios;
    chain_options.screen = screen;
    chain_options.distance.sample_count = settings.error_samples;
    chain_options.simplify.remove_covered_components = settings.remove_covered_components;
    chain_options.measure_error = false; // measured below, beside the stream encoders
    chain_options.record_collapses = false;
    for (const PackStreamEncoder& encoder : encoders) {
        // pfrep_from_chain: the PFRep blob is built from the chain's own pass, read as vertex removals
        // (docs/bake.md); otherwise it runs a half-edge simplification of its own.
        chain_options.record_removals |=
            settings.pfrep_from_chain && encoder.extension_name == "LODBAKE_progressive_fans";
    }
    StageTimer chain_timer(hooks, index, BakeStage::LodChain);
    Result<LodChain> chain_result = buildLodChain(mesh, chain_options, slot.diagnostics);
    if (!chain_result.ok())
        return Status(chain_result.status().code(), input.name + ": " + chain_result.status().message());
    LodChain chain = std::move(chain_result).value();
    chain_timer.finish();

    const size_t level_count = chain.levels.size() + 1;
    auto levelMesh = [&](size_t l) -> const Mesh& { return l == 0 ? mesh : chain.levels[l - 1].mesh; };
    std::vector<size_t> level_triangles(level_count);
    for (size_t l = 0; l < level_count; ++l) level_triangles[l] = levelMesh(l).faceCount();
    std::vector<Result<PackStreamCommit>> commits(encoders.size() * level_count, PackStreamCommit());
    Diagnostics measure_diagnostics;
    LodMetrics metrics;
    Result<TextureLevels> textures = TextureLevels{};
    Status deferred = Status::okStatus();
    auto stageOf = [&](size_t e) {
        return encoders[e].extension_name == "LODBAKE_progressive_fans" ? BakeStage::Pfrep : BakeStage::Encode;
    };
    // Chain level i's reference side (LOD0's points against the level), when a MeasureReference task
    // measured it in an earlier phase (beside the PFRep build); the measurement then skips it.
    std::vector<Result<OneSidedDistance>> reference_sides;
    std::vector<bool> level_with_measure(level_count, false);
    std::vector<size_t> nested_levels;
    // LOD0 as the running phase's tasks may read it: LOD0 itself, or its positions and indices lent to a
    // geometry-only mesh (below).
    const Mesh* lod0_view = &mesh;
    auto runTask = [&](const PhaseTask& task) {
        switch (task.kind) {
        case PhaseTask::Kind::Measure: {
            {
                StageTimer timer(hooks, index, BakeStage::Measure);
                measureChain(mesh, chain, chain_options, reference_sides, measure_diagnostics);
                metrics = lodMetrics(mesh, chain, screen, settings.hysteresis);
            }
            // Encoders that read the measured errors (adaptive stream precision) code the levels of this
            // phase now, in a nested loop that idle threads join; later phases' Level tasks do it themselves.
            deferred = parallelFor(nested_levels.size(), 1, [&](size_t i) {
                const size_t l = nested_levels[i];
                for (size_t e = 0; e < encoders.size(); ++e) {
                    if (!encoders[e].needs_measurement) continue;
                    StageTimer timer(hooks, index, BakeStage::Encode, l);
                    commits[e * level_count + l] = encoders[e].prepare(chain, l, levelMesh(l));
                }
            });
            StageTimer timer(hooks, index, BakeStage::Textures);
            textures = textureLevels(mesh, level_count, metrics, settings, input.name, measure_diagnostics);
            return;
        }
        case PhaseTask::Kind::MeasureReference: {
            // Levels task.index and on. A failure here (a bad reference or level) leaves the side to the
            // measurement, which then reports it.
            StageTimer timer(hooks, index, BakeStage::Measure);
            std::vector<const Mesh*> meshes;
            for (size_t l = task.index; l < level_count; ++l) meshes.push_back(&levelMesh(l));
            Result<std::vector<Result<OneSidedDistance>>> sides =
                measureReferenceSides(*lod0_view, meshes, chain_options.distance);
            if (!sides.ok()) return;
            reference_sides.assign(task.index - 1, internalError("not measured beforehand"));
            for (Result<OneSidedDistance>& side : *sides) reference_sides.push_back(std::move(side));
            return;
        }
        case PhaseTask::Kind::Lod0Encoder: {
            const size_t e = task.index;
            StageTimer timer(hooks, index, stageOf(e), 0);
            // A PFRep build reads LOD0's positions and indices only (lod0_view); the other encoders all of it.
            commits[e * level_count] =
                encoders[e].prepare(chain, 0, stageOf(e) == BakeStage::Pfrep ? *lod0_view : mesh);
            return;
        }
        case PhaseTask::Kind::Level:
            for (size_t e = 0; e < encoders.size(); ++e) {
                // In the measurement's phase, the measurement task codes these after it (above).
                if (encoders[e].needs_measurement && level_with_measure[task.index]) continue;
                StageTimer timer(hooks, index, stageOf(e), task.index);
                Result<PackStreamCommit>& commit = commits[e * level_count + task.index];
                commit = encoders[e].prepare(chain, task.index, levelMesh(task.index));
                if (commit.ok() && !*commit) timer.cancel(); // nothing to code here (PFRep codes LOD0 only)
            }
            return;
        }
    };
    std::vector<bool> encoder_is_pfrep;
    for (size_t e = 0; e < encoders.size(); ++e) encoder_is_pfrep.push_back(stageOf(e) == BakeStage::Pfrep);
    bake_detail::PhaseEstimates estimates;
    estimates.measure_reference_ahead = maxParallelism() > 1;
    const std::vector<std::vector<PhaseTask>> phases = concurrentPhases(encoder_is_pfrep, level_triangles, estimates);
    // The levels that share the measurement's phase (the measurement precedes every level task).
    for (const std::vector<PhaseTask>& phase : phases) {
        bool has_measure = false;
        for (const PhaseTask& task : phase) {
            has_measure |= task.kind == PhaseTask::Kind::Measure;
            if (has_measure && task.kind == PhaseTask::Kind::Level) {
                level_with_measure[task.index] = true;
                nested_levels.push_back(task.index);
            }
        }
    }
    for (const std::vector<PhaseTask>& phase : phases) {
        // The PFRep build and the reference sides read positions and indices only (the PFRep build would
        // copy them out of a mesh with attributes). When nothing else in the phase reads LOD0, they are
        // lent to a geometry-only mesh instead of copied: the same input, one copy less at the peak.
        bool geometry_only = true;
        for (const PhaseTask& task : phase)
            geometry_only &= task.kind == PhaseTask::Kind::MeasureReference ||
                             (task.kind == PhaseTask::Kind::Lod0Encoder && stageOf(task.index) == BakeStage::Pfrep);
        Mesh geometry;
        if (geometry_only) {
            geometry.positions = std::move(mesh.positions);
            geometry.indices = std::move(mesh.indices);
            lod0_view = &geometry;
        }
        std::atomic<size_t> next{0};
        const Status run = parallelFor(phase.size(), 1, [&](size_t) { runTask(phase[next.fetch_add(1)]); });
        if (geometry_only) {
            mesh.positions = std::move(geometry.positions);
            mesh.indices = std::move(geometry.indices);
            lod0_view = &mesh;
        }
        LODBAKE_RETURN_IF_ERROR(run);
    }
    LODBAKE_RETURN_IF_ERROR(deferred);
    for (const Diagnostic& d : measure_diagnostics.items()) {
        if (d.severity == Severity::Warning)
            slot.diagnostics.warn(d.message);
        else
            slot.diagnostics.note(d.message);
    }
    if (!textures.ok()) return textures.status();
    for (const Result<PackStreamCommit>& commit : commits) LODBAKE_RETURN_IF_ERROR(commit.status());

    slot.report.metrics = metrics;
    slot.report.texture_sizes = textures->sizes;
    PackAsset& asset = slot.asset;
    asset.name = input.name;
    asset.screen_coverage = msftScreenCoverage(metrics);
    asset.node_extensions.push_back(lodMetricsExtension(metrics));
    asset.levels.resize(level_count);
    asset.levels[0].mesh = std::move(mesh);
    for (size_t l = 1; l < level_count; ++l) asset.levels[l].mesh = std::move(chain.levels[l - 1].mesh);
    const std::vector<Texture>& sources = asset.levels[0].mesh.textures;
    for (size_t l = 1; l < level_count; ++l) {
        std::vector<Texture>& level_textures = asset.levels[l].mesh.textures;
        for (size_t t = 0; t < level_textures.size() && t < sources.size(); ++t) {
            const ImageSize& size = textures->sizes[l][t];
            const auto found = textures->resized.find({t, {size.width, size.height}});
            if (found == textures->resized.end()) continue;
            level_textures[t].bytes = found->second;
            level_textures[t].name =
                sources[t].name + "_" + std::to_string(size.width) + "x" + std::to_string(size.height);
        }
    }
    for (size_t e = 0; e < encoders.size(); ++e)
        for (size_t l = 0; l < level_count; ++l) {
            const PackStreamCommit& commit = *commits[e * level_count + l];
            if (commit) LODBAKE_RETURN_IF_ERROR(commit(asset.levels[l]));
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
    ValenceStreamOptions valence;
    valence.position_bits = settings.stream_precision.position_bits;
    valence.normal_bits = settings.stream_precision.normal_bits;
    valence.adaptive = settings.stream_precision.adaptive;
    valence.error_fraction = settings.stream_precision.error_fraction;
    valence.release_memory = hooks.release_memory;
    for (PackStreamEncoder& encoder : builtinStreamEncoders(valence))
        if (settings.progressive_fans || encoder.extension_name != "LODBAKE_progressive_fans")
            encoders.push_back(std::move(encoder));
    PackDescription description;
    description.compact = settings.compact;
    // Fail before the expensive stages when no stream encoder exists at all.
    if (settings.compact && encoders.empty()) LODBAKE_RETURN_IF_ERROR(checkCompact(description));

    std::vector<AssetSlot> slots(inputs.size());
    LODBAKE_RETURN_IF_ERROR(parallelFor(inputs.size(), 1, [&](size_t i) {
        slots[i].status = bakeAsset(inputs[i], settings, encoders, slots[i], i, hooks);
    }));
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
