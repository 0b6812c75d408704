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
#include "bake/texture_levels.h"
#include "core/parallel.h"
#include "lodbake/cleanup/repair.h"
#include "lodbake/core/json_writer.h"
#include "lodbake/core/math.h"
#include "lodbake/pack/pack_glb.h"
#include "lodbake/reconstruct/merge.h"
#include "lodbake/simplify/lod_chain.h"
#include "lodbake/simplify/mesh_distance.h"
#include "lodbake/stream/stream.h"
#include "lodrt/format.h"

namespace lodbake {

namespace {

using bake_detail::addNormalMapTangents;
using bake_detail::applyTextureLevels;
using bake_detail::concurrentPhases;
using bake_detail::PhaseTask;
using bake_detail::TextureLevels;
using bake_detail::textureLevels;

ScreenParams screenParams(const BakeSettings& s) {
    ScreenParams screen;
    screen.pixel_threshold = s.pixel_threshold;
    screen.viewport_height_px = s.viewport_height_px;
    screen.vertical_fov_rad = s.vertical_fov_deg * kPi / 180.0;
    return screen;
}

struct AssetSlot {
    Status status = Status::okStatus();
    Diagnostics diagnostics;
    PackAsset asset;
    BakeAssetReport report;
};

// measureLodChain (lod_chain.h) with the reference sides that a MeasureReference task measured
// (`reference_sides[i]` for chain level i, when present and ok).
void measureChain(const Mesh& mesh, LodChain& chain, const LodChainOptions& options,
                  const std::vector<Result<OneSidedDistance>>& reference_sides, Diagnostics& diagnostics) {
    std::vector<const OneSidedDistance*> known;
    for (size_t i = 0; i < chain.levels.size(); ++i)
        known.push_back(i < reference_sides.size() && reference_sides[i].ok() ? &*reference_sides[i] : nullptr);
    measureLodChain(mesh, chain, options, known, diagnostics);
}

// The range-view merge (settings.merge), then the repair pipeline. `auto` merges only when the
// input's components overlap as sheets, so single surfaces and separate pieces pass through
// untouched. The merge reads the sheets as scanned: the repair's hole filling would add invented
// samples, and dropping speckle is the merge's density trim's job; the merged surface is repaired.
Status repairInput(BakeInput& input, const BakeSettings& settings, AssetSlot& slot, size_t index,
                   const BakeHooks& hooks) {
    slot.report.name = input.name;
    slot.report.input_triangles = input.mesh.faceCount();
    slot.report.input_vertices = input.mesh.vertexCount();
    if (!settings.repair && settings.merge == MergeMode::Off) return Status::okStatus();
    StageTimer timer(hooks, index, BakeStage::Repair);
    const bool merge = settings.merge == MergeMode::Poisson ||
                       (settings.merge == MergeMode::Auto &&
                        overlappingSheetFraction(input.mesh) >= kOverlappingSheetFraction);
    if (merge) {
        MergeOptions merge_options;
        merge_options.distance_samples = 200000; // the report's distances: a fixed subset of the samples
        LODBAKE_ASSIGN_OR_RETURN(MergeReport merged, mergeRangeViews(input.mesh, merge_options, input.name));
        slot.report.merge = mergeReportLines(merged);
        for (const std::string& line : slot.report.merge) slot.diagnostics.note(input.name + ": merge: " + line);
    }
    if (!settings.repair) {
        if (!merge) timer.cancel(); // nothing ran
        return Status::okStatus();
    }
    RepairOptions repair_options;
    repair_options.report_welded = false; // only `unresolved` goes into the bake's report
    repair_options.report_before = false; // likewise: the input is validated only if a skip test needs it
    LODBAKE_ASSIGN_OR_RETURN(RepairReport repair, repairMesh(input.mesh, repair_options, input.name, slot.diagnostics));
    slot.report.repair_unresolved = repair.unresolved;
    return Status::okStatus();
}

LodChainOptions chainOptions(const BakeSettings& settings, const std::vector<PackStreamEncoder>& encoders) {
    LodChainOptions options;
    options.ratios = settings.lod_ratios;
    options.screen = screenParams(settings);
    options.distance.sample_count = settings.error_samples;
    options.simplify.remove_covered_components = settings.remove_covered_components;
    options.measure_error = false; // measured beside the stream encoders (AssetTasks)
    options.record_collapses = false;
    // A stream that reads the collapse record gets the chain's collapses as vertex removals.
    for (const PackStreamEncoder& encoder : encoders) options.record_removals |= encoder.needs.collapse_record;
    return options;
}

// After the chain, the remaining work of an asset is a fixed set of tasks that only read the
// meshes (STYLE.md §7: each writes its own slot; which thread runs which, and when, changes no
// byte): the error measurement (then the metrics and texture levels that follow from it), and the
// stream encoders' prepare steps. They run in phases (concurrentPhases) cut by the streams' own cost
// estimates: with 2 threads a small asset's LOD0-only streams (the PFRep build: a replay of the
// chain's logged collapses, then the blob) run beside the measurement and the coding of the levels;
// a large asset's run beside the measurement's reference sides (MeasureReference), then the rest of
// the measurement (parallel inside), then the coding of every level side by side. The commits
// (cheap; the valence commit renumbers its level) then run in encoder and level order on this thread.
//
// AssetTasks holds those tasks and what they produce; each task writes its own members.
class AssetTasks {
public:
    AssetTasks(const Mesh& mesh, LodChain& chain, const LodChainOptions& chain_options, const BakeSettings& settings,
               const std::vector<PackStreamEncoder>& encoders, const std::string& name, size_t index,
               const BakeHooks& hooks)
        : mesh_(mesh), chain_(chain), chain_options_(chain_options), settings_(settings), encoders_(encoders),
          name_(name), index_(index), hooks_(hooks), level_count_(chain.levels.size() + 1),
          commits(encoders.size() * level_count_, PackStreamCommit()), kept_levels_(level_count_, 1),
          level_with_measure_(level_count_, false) {}

    size_t levelCount() const { return level_count_; }
    /// Whether level l of the chain as built (LOD0 = 0) stays in the pack; read once run() has returned.
    bool isKept(size_t l) const { return kept_levels_[l] != 0; }
    const Mesh& levelMesh(size_t l) const { return l == 0 ? mesh_ : chain_.levels[l - 1].mesh; }

    Status run() {
        std::vector<size_t> level_triangles(level_count_);
        for (size_t l = 0; l < level_count_; ++l) level_triangles[l] = levelMesh(l).faceCount();
        std::vector<bake_detail::EncoderCost> costs;
        for (const PackStreamEncoder& encoder : encoders_)
            costs.push_back({encoder.needs.lod0_only, encoder.cost.bytes_per_triangle});
        bake_detail::PhaseEstimates estimates;
        estimates.measure_reference_ahead = maxParallelism() > 1;
        const std::vector<std::vector<PhaseTask>> phases = concurrentPhases(costs, level_triangles, estimates);
        findNestedLevels(phases);
        for (const std::vector<PhaseTask>& phase : phases) LODBAKE_RETURN_IF_ERROR(runPhase(phase));
        return deferred_;
    }

private:
    BakeStage stageOf(size_t e) const { return encoders_[e].needs.lod0_only ? BakeStage::Pfrep : BakeStage::Encode; }

    // The levels that share the measurement's phase (the measurement precedes every level task).
    void findNestedLevels(const std::vector<std::vector<PhaseTask>>& phases) {
        for (const std::vector<PhaseTask>& phase : phases) {
            bool has_measure = false;
            for (const PhaseTask& task : phase) {
                has_measure |= task.kind == PhaseTask::Kind::Measure;
                if (has_measure && task.kind == PhaseTask::Kind::Level) {
                    level_with_measure_[task.index] = true;
                    nested_levels_.push_back(task.index);
                }
            }
        }
    }

    // Every task only reads LOD0 and the chain: a stage that needs LOD0's geometry alone takes a view
    // of it (MeshView), so nothing is moved out of the mesh while the others read it.
    Status runPhase(const std::vector<PhaseTask>& phase) {
        std::atomic<size_t> next{0};
        return parallelFor(phase.size(), 1, [&](size_t) { runTask(phase[next.fetch_add(1)]); });
    }

    void runTask(const PhaseTask& task) {
        switch (task.kind) {
        case PhaseTask::Kind::Measure:
            return measure();
        case PhaseTask::Kind::MeasureReference:
            return measureReference(task.index);
        case PhaseTask::Kind::Lod0Encoder:
            return prepareLod0(task.index);
        case PhaseTask::Kind::Level:
            return prepareLevel(task.index);
        }
    }

    void measure() {
        {
            StageTimer timer(hooks_, index_, BakeStage::Measure);
            measureChain(mesh_, chain_, chain_options_, reference_sides_, measure_diagnostics);
            metrics = lodMetrics(mesh_, chain_, chain_options_.screen, settings_.hysteresis);
            // Dead levels leave the metrics here; their meshes and streams leave the pack once every
            // task that reads the chain is done (assemblePackAsset).
            dropped_levels =
                dropIndistinctLevels(metrics, mesh_, chain_, chain_options_.screen, settings_.lod_min_switch_ratio);
            for (const DroppedLodLevel& d : dropped_levels) {
                kept_levels_[d.level] = 0;
                measure_diagnostics.note(name_ + ": " + droppedLevelNote(d, settings_.lod_min_switch_ratio));
            }
        }
        // Encoders that read the measured errors code the levels of this phase now, in a nested loop
        // that idle threads join; later phases' Level tasks do it themselves.
        deferred_ = parallelFor(nested_levels_.size(), 1, [&](size_t i) {
            const size_t l = nested_levels_[i];
            if (!kept_levels_[l]) return;
            for (size_t e = 0; e < encoders_.size(); ++e) {
                if (!encoders_[e].needs.measured_errors || encoders_[e].needs.lod0_only) continue;
                StageTimer timer(hooks_, index_, BakeStage::Encode, l);
                commits[e * level_count_ + l] = encoders_[e].prepare(chain_, l, levelMesh(l));
            }
        });
        StageTimer timer(hooks_, index_, BakeStage::Textures);
        textures = textureLevels(mesh_, metrics.levels.size(), metrics, settings_, name_, measure_diagnostics);
    }

    // Levels `first` and on. A failure here (a bad reference or level) leaves the side to the
    // measurement, which then reports it.
    void measureReference(size_t first) {
        StageTimer timer(hooks_, index_, BakeStage::Measure);
        std::vector<const Mesh*> meshes;
        for (size_t l = first; l < level_count_; ++l) meshes.push_back(&levelMesh(l));
        Result<std::vector<Result<OneSidedDistance>>> sides =
            measureReferenceSides(mesh_, meshes, chain_options_.distance);
        if (!sides.ok()) return;
        reference_sides_.assign(first - 1, internalError("not measured beforehand"));
        for (Result<OneSidedDistance>& side : *sides) reference_sides_.push_back(std::move(side));
    }

    void prepareLod0(size_t e) {
        StageTimer timer(hooks_, index_, stageOf(e), 0);
        commits[e * level_count_] = encoders_[e].prepare(chain_, 0, mesh_);
    }

    void prepareLevel(size_t l) {
        // A Level task outside the measurement's phase runs after it: a dropped level needs no coding.
        if (!level_with_measure_[l] && !kept_levels_[l]) return;
        for (size_t e = 0; e < encoders_.size(); ++e) {
            if (encoders_[e].needs.lod0_only) continue;
            // In the measurement's phase, the measurement task codes these after it (measure()).
            if (encoders_[e].needs.measured_errors && level_with_measure_[l]) continue;
            StageTimer timer(hooks_, index_, stageOf(e), l);
            Result<PackStreamCommit>& commit = commits[e * level_count_ + l];
            commit = encoders_[e].prepare(chain_, l, levelMesh(l));
            if (commit.ok() && !*commit) timer.cancel(); // nothing to code on this level
        }
    }

    const Mesh& mesh_;
    LodChain& chain_;
    const LodChainOptions& chain_options_;
    const BakeSettings& settings_;
    const std::vector<PackStreamEncoder>& encoders_;
    const std::string& name_;
    size_t index_;
    const BakeHooks& hooks_;
    size_t level_count_;

public:
    // Products, read once run() has returned.
    std::vector<Result<PackStreamCommit>> commits; // encoder e, level l at e * levelCount() + l
    Diagnostics measure_diagnostics;
    LodMetrics metrics; // of the kept levels
    std::vector<DroppedLodLevel> dropped_levels;
    Result<TextureLevels> textures = TextureLevels{};

private:
    // Chain level i's reference side (LOD0's points against the level), when a MeasureReference task
    // measured it in an earlier phase; the measurement then skips it.
    std::vector<Result<OneSidedDistance>> reference_sides_;
    // Written by the measurement before any task that reads it starts (bytes, not bits: no shared words).
    std::vector<uint8_t> kept_levels_;
    std::vector<bool> level_with_measure_;
    std::vector<size_t> nested_levels_;
    Status deferred_ = Status::okStatus();
};

// The asset's pack entry: the kept levels' meshes (moved out of `mesh` and the chain, which then
// holds the kept levels only, as the streams' commits read it), their textures, then every stream's
// commit in encoder and level order.
Status assemblePackAsset(const std::string& name, Mesh& mesh, LodChain& chain, AssetTasks& tasks,
                         const std::vector<PackStreamEncoder>& encoders, AssetSlot& slot) {
    const size_t level_count = tasks.levelCount();
    std::vector<size_t> levels; // the kept levels of the chain as built, LOD0 first
    std::vector<bool> keep_chain;
    for (size_t l = 0; l < level_count; ++l) {
        if (tasks.isKept(l)) levels.push_back(l);
        if (l > 0) keep_chain.push_back(tasks.isKept(l));
    }
    keepLevels(chain, keep_chain);
    const TextureLevels& textures = *tasks.textures;
    slot.report.metrics = tasks.metrics;
    slot.report.texture_sizes = textures.sizes;
    slot.report.dropped_levels = tasks.dropped_levels;
    PackAsset& asset = slot.asset;
    asset.name = name;
    asset.screen_coverage = msftScreenCoverage(tasks.metrics);
    asset.node_extensions.push_back(lodMetricsExtension(tasks.metrics));
    asset.levels.resize(levels.size());
    asset.levels[0].mesh = std::move(mesh);
    for (size_t k = 1; k < levels.size(); ++k) asset.levels[k].mesh = std::move(chain.levels[k - 1].mesh);
    applyTextureLevels(textures, asset.levels);
    for (size_t e = 0; e < encoders.size(); ++e)
        for (size_t k = 0; k < levels.size(); ++k) {
            const PackStreamCommit& commit = *tasks.commits[e * level_count + levels[k]];
            if (commit) LODBAKE_RETURN_IF_ERROR(commit(asset.levels[k]));
        }
    return Status::okStatus();
}

// --web with adaptive precision: each level after LOD0 may store its positions on a grid whose
// rounding moves a vertex by at most error_fraction of the level's measured mean error, as the
// streams' adaptive precision does (docs/format/web.md).
void setWebPositionSteps(const BakeSettings& settings, AssetSlot& slot) {
    if (!settings.web || !settings.stream_precision.adaptive) return;
    const std::vector<LodMetricsLevel>& levels = slot.report.metrics.levels;
    for (size_t l = 1; l < slot.asset.levels.size() && l < levels.size(); ++l)
        slot.asset.levels[l].web_position_step =
            settings.stream_precision.error_fraction * levels[l].mean_error / (std::sqrt(3.0) / 2.0);
}

Status bakeAsset(BakeInput& input, const BakeSettings& settings, const std::vector<PackStreamEncoder>& encoders,
                 AssetSlot& slot, size_t index, const BakeHooks& hooks) {
    LODBAKE_RETURN_IF_ERROR(repairInput(input, settings, slot, index, hooks));
    LODBAKE_RETURN_IF_ERROR(addNormalMapTangents(input.mesh, input.name, slot.diagnostics));
    const LodChainOptions chain_options = chainOptions(settings, encoders);
    StageTimer chain_timer(hooks, index, BakeStage::LodChain);
    Result<LodChain> chain_result = buildLodChain(input.mesh, chain_options, slot.diagnostics);
    if (!chain_result.ok())
        return Status(chain_result.status().code(), input.name + ": " + chain_result.status().message());
    LodChain chain = std::move(chain_result).value();
    chain_timer.finish();

    AssetTasks tasks(input.mesh, chain, chain_options, settings, encoders, input.name, index, hooks);
    LODBAKE_RETURN_IF_ERROR(tasks.run());
    for (const Diagnostic& d : tasks.measure_diagnostics.items()) {
        if (d.severity == Severity::Warning)
            slot.diagnostics.warn(d.message);
        else
            slot.diagnostics.note(d.message);
    }
    if (!tasks.textures.ok()) return tasks.textures.status();
    for (const Result<PackStreamCommit>& commit : tasks.commits) LODBAKE_RETURN_IF_ERROR(commit.status());
    LODBAKE_RETURN_IF_ERROR(assemblePackAsset(input.name, input.mesh, chain, tasks, encoders, slot));
    setWebPositionSteps(settings, slot);
    return Status::okStatus();
}

} // namespace

Result<BakeOutput> bake(std::vector<BakeInput> inputs, const BakeSettings& settings, Diagnostics& diagnostics) {
    return bake(std::move(inputs), settings, diagnostics, BakeHooks{});
}

Result<BakeOutput> bake(std::vector<BakeInput> inputs, const BakeSettings& settings, Diagnostics& diagnostics,
                        const BakeHooks& hooks) {
    return bakeScene(std::move(inputs), PackScene{}, settings, diagnostics, hooks);
}

Result<BakeOutput> bakeScene(std::vector<BakeInput> inputs, PackScene scene, const BakeSettings& settings,
                             Diagnostics& diagnostics, const BakeHooks& hooks) {
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
    StreamSettings streams;
    streams.valence.position_bits = settings.stream_precision.position_bits;
    streams.valence.normal_bits = settings.stream_precision.normal_bits;
    streams.valence.adaptive = settings.stream_precision.adaptive;
    streams.valence.error_fraction = settings.stream_precision.error_fraction;
    streams.valence.release_memory = hooks.release_memory;
    streams.progressive_fans = settings.progressive_fans;
    streams.pfrep_from_chain = settings.pfrep_from_chain;
    // Format 4 is decoded from level 0's bytes, which hold LOD0's valence stream only in a compact
    // pack (docs/format/pfrep.md "In a glTF pack"); elsewhere the blob is format 3.
    streams.pfrep_format = settings.pfrep_format == lodrt::format::kPfrepVersionLod0 && !settings.compact
                               ? lodrt::format::kPfrepVersionCompressed
                               : settings.pfrep_format;
    streams.pfrep_regions.block_vertices = settings.pfrep_region_block;
    streams.pfrep_regions.screen = screenParams(settings);
    streams.cluster_lod = settings.cluster_lod;
    // A --web pack is for clients that read none of our streams (docs/format/web.md).
    const std::vector<PackStreamEncoder> encoders =
        settings.web ? std::vector<PackStreamEncoder>() : builtinStreamEncoders(streams);
    PackDescription description;
    description.compact = settings.compact;
    description.web = settings.web;
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
    description.scene = std::move(scene);
    StageTimer pack_timer(hooks, kWholePack, BakeStage::Pack);
    LODBAKE_ASSIGN_OR_RETURN(output.glb, writePackGlb(std::move(description)));
    return output;
}

std::string bakeReportJson(const BakeOutput& output, const BakeSettings& settings) {
    return bakeReportJson(output, settings, uint64_t(output.glb.size()));
}

std::string bakeReportJson(const BakeOutput& output, const BakeSettings& settings, uint64_t pack_bytes) {
    JsonWriter j;
    j.beginObject();
    j.field("packBytes", pack_bytes);
    j.key("assets").beginArray();
    for (const BakeAssetReport& a : output.assets) {
        j.beginObject();
        j.field("name", a.name);
        j.field("inputTriangles", a.input_triangles);
        j.field("inputVertices", a.input_vertices);
        // An out-of-core pack: its chain is cut from the cluster hierarchy and may start below the input.
        if (a.metrics.input_triangles > 0) j.field("outOfCore", true);
        j.key("repairUnresolved").beginArray();
        for (const std::string& u : a.repair_unresolved) j.value(u);
        j.endArray();
        if (!a.merge.empty()) {
            j.key("merge").beginArray();
            for (const std::string& m : a.merge) j.value(m);
            j.endArray();
        }
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
        if (!a.dropped_levels.empty()) {
            j.key("droppedLevels").beginArray();
            for (const DroppedLodLevel& d : a.dropped_levels) {
                j.beginObject();
                j.field("level", uint64_t(d.level));
                j.field("ratio", d.ratio);
                j.field("triangles", d.triangles);
                j.field("hausdorffError", d.hausdorff_error);
                j.field("switchDistance", d.switch_distance);
                j.field("finerLevel", uint64_t(d.finer_level));
                j.field("coarserLevel", uint64_t(d.coarser_level));
                j.field("coarserSwitchDistance", d.coarser_switch_distance);
                j.endObject();
            }
            j.endArray();
        }
        j.endObject();
    }
    j.endArray();
    j.field("pixelThreshold", settings.pixel_threshold);
    j.field("viewportHeight", settings.viewport_height_px);
    j.endObject();
    return j.str();
}

} // namespace lodbake
