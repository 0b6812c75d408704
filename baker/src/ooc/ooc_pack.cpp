// The pack of an out-of-core bake (lodbake/ooc/ooc_pack.h).
#include "lodbake/ooc/ooc_pack.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>

#include <fcntl.h>
#include <unistd.h>

#include "core/parallel.h"
#include "lodbake/bake/memory_budget.h"
#include "lodbake/cleanup/normals.h"
#include "lodbake/core/spill_file.h"
#include "lodbake/ooc/jobs.h"
#include "lodbake/ooc/level_error.h"
#include "lodbake/pack/pack_glb.h"
#include "lodbake/simplify/lod_chain.h"
#include "lodrt/format.h"

namespace lodbake::ooc {

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

constexpr size_t kCopyBytes = size_t(64) << 10;
constexpr uint32_t kBoundsClustersPerRead = 256;
constexpr uint32_t kSmallestSubsample = 4096; // the measurement's subsample is not cut below it

// The run's own folder inside the work folder, removed with everything in it however the run ends
// (and the work folder too when the run created it and it is left empty).
class RunFolder {
public:
    ~RunFolder() {
        std::error_code ec;
        if (!path_.empty()) fs::remove_all(path_, ec);
        if (created_parent_) fs::remove(parent_, ec); // only when empty
    }
    Status make(const std::string& work_dir, const std::string& input) {
        static std::atomic<uint64_t> counter{0};
        std::error_code ec;
        parent_ = work_dir;
        if (!fs::exists(parent_, ec)) {
            if (!fs::create_directories(parent_, ec) || ec)
                return ioError(work_dir + ": cannot create the work folder for " + input);
            created_parent_ = true;
        }
        path_ = (fs::path(parent_) / (".lodbake-ooc-" + std::to_string(::getpid()) + "-" +
                                      std::to_string(counter.fetch_add(1))))
                    .string();
        if (!fs::create_directory(path_, ec) || ec) {
            path_.clear();
            return ioError(work_dir + ": cannot create a folder in the work folder for " + input);
        }
        return Status::okStatus();
    }
    const std::string& path() const { return path_; }

private:
    std::string parent_, path_;
    bool created_parent_ = false;
};

// The input (ratio 1) and every ratio's cut, finest first; a cut no coarser than the one before it
// is left out (ratios below what the hierarchy's roots allow give the same cut).
std::vector<OocPackLevel> candidateLevels(const TreeClusterTable& table, uint64_t input_triangles,
                                          const std::vector<double>& ratios) {
    std::vector<double> all{1.0};
    for (double r : ratios)
        if (r > 0 && r < 1) all.push_back(r);
    std::stable_sort(all.begin(), all.end(), [](double a, double b) { return a > b; });
    std::vector<OocPackLevel> out;
    for (double r : all) {
        OocPackLevel level;
        level.ratio = r;
        level.target_triangles = uint64_t(std::llround(r * double(input_triangles)));
        level.cut = r == 1.0 ? measureLevelCut(table, 0.0f) : findLevelCut(table, level.target_triangles);
        if (!out.empty() && level.cut.triangles >= out.back().cut.triangles) continue;
        level.held_bytes = levelHeldBytes(level.cut);
        level.work_bytes = levelWorkBytes(level.cut);
        out.push_back(level);
    }
    return out;
}

// Keeps the longest run of the coarsest levels whose held bytes plus the largest working set fit.
uint64_t keepLevelsThatFit(std::vector<OocPackLevel>& levels, uint64_t budget) {
    uint64_t held = 0, work = 0, peak = 0;
    for (size_t i = levels.size(); i-- > 0;) {
        const uint64_t h = held + levels[i].held_bytes, w = std::max(work, levels[i].work_bytes);
        if (h + w > budget) break;
        held = h;
        work = w;
        peak = h + w;
        levels[i].kept = true;
    }
    return peak;
}

// The bounding box of the hierarchy's LOD0 (the input's triangles), read cluster by cluster.
Result<ClusterPackBounds> lod0Bounds(const TreeClusterTable& table, TreePageSource& source) {
    ClusterPackBounds b;
    std::vector<uint32_t> ids;
    ClusterPageGeometry geometry;
    for (uint32_t first = 0; first < table.lod0_cluster_count; first += kBoundsClustersPerRead) {
        const uint32_t count = std::min(kBoundsClustersPerRead, table.lod0_cluster_count - first);
        ids.resize(count);
        for (uint32_t i = 0; i < count; ++i) ids[i] = first + i;
        geometry.positions.clear();
        geometry.indices.clear();
        LODBAKE_RETURN_IF_ERROR(source.readPage(0, ids.data(), count, geometry));
        for (const Vec3f& p : geometry.positions) b.add(p);
    }
    return b;
}

// The chain's metrics: the kept levels' errors (measured, the cut's bound, or the caller's), the
// switch policy of the in-memory bake (core/lod_policy.h). Level 0 is shown from distance 0 whatever
// its error; the input's triangle count says where the chain starts.
LodMetrics chainMetrics(const std::vector<LevelCut>& cuts, const std::vector<LevelError>& errors, double diagonal,
                        const OocPackOptions& o, uint64_t input_triangles) {
    LodMetrics m;
    m.bounding_radius = diagonal / 2;
    m.pixel_threshold = o.screen.pixel_threshold;
    m.viewport_height_px = o.screen.viewport_height_px;
    m.vertical_fov_rad = o.screen.vertical_fov_rad;
    m.input_triangles = input_triangles;
    for (size_t i = 0; i < cuts.size(); ++i) {
        LodMetricsLevel l;
        l.triangles = cuts[i].triangles;
        l.hausdorff_error = errors[i].hausdorff;
        l.mean_error = errors[i].mean;
        if (i > 0) {
            // A coarser level never claims to be better than the finer one (as the in-memory bake).
            const LodMetricsLevel& prev = m.levels.back();
            l.hausdorff_error = std::max(l.hausdorff_error, prev.hausdorff_error);
            l.mean_error = std::max(l.mean_error, prev.mean_error);
            l.switch_distance = levelSwitchDistance(l.hausdorff_error, prev.switch_distance, o.screen);
            l.screen_coverage = screenCoverage(m.bounding_radius, l.switch_distance, o.screen);
            const HysteresisBand band = hysteresisBand(l.switch_distance, o.hysteresis);
            l.hysteresis_near = band.near;
            l.hysteresis_far = band.far;
        } else {
            l.screen_coverage = 1.0;
        }
        l.hausdorff_error_rel = diagonal > 0 ? l.hausdorff_error / diagonal : 0.0;
        l.mean_error_rel = diagonal > 0 ? l.mean_error / diagonal : 0.0;
        m.levels.push_back(l);
    }
    return m;
}

// One kept level's mesh: the cut extracted (positions and triangles).
Result<Mesh> extractLevel(const TreeClusterTable& table, TreePageSource& source, const LevelCut& cut, size_t index,
                          const std::string& input) {
    Result<Mesh> mesh = extractLevelCut(table, source, cut);
    if (!mesh.ok()) return Status(mesh.status().code(), input + ": level " + std::to_string(index) + ": " +
                                                            mesh.status().message());
    if (mesh->faceCount() == 0) return invalidInput(input + ": level " + std::to_string(index) + ": no triangles");
    return mesh;
}

// One kept level made a pack level: its normals and its valence stream (at the precision the chain's
// errors give it, as in the in-memory bake).
Result<PackLevel> bakeLevel(Mesh mesh, const PackStreamEncoder& encoder, const LodChain& chain, size_t index,
                            const std::string& input) {
    PackLevel level;
    level.mesh = std::move(mesh);
    computeNormals(level.mesh);
    Result<PackStreamCommit> commit = encoder.prepare(chain, index, level.mesh);
    if (!commit.ok()) return Status(commit.status().code(), input + ": level " + std::to_string(index) + ": " +
                                                                commit.status().message());
    if (*commit) LODBAKE_RETURN_IF_ERROR((*commit)(level));
    return level;
}

// The kept levels made pack levels (bakeLevel), finest first. The coder is sequential within a level
// and the finest level takes most of the time, so the levels are coded side by side when all their
// working sets fit beside the held levels; else one after the other, as the level budget was sized.
// Each level is coded alone either way: the same bytes.
Result<std::vector<PackLevel>> bakeLevels(std::vector<Mesh>& meshes, const PackStreamEncoder& encoder,
                                          const LodChain& chain, const std::string& input,
                                          const std::string& output_path, const OocPackOptions& o,
                                          OocPackResult& result) {
    uint64_t held = 0, work = 0;
    for (const OocPackLevel& l : result.levels)
        if (l.kept) {
            held += l.held_bytes;
            work += l.work_bytes;
        }
    std::vector<Result<PackLevel>> made(meshes.size(), Result<PackLevel>(internalError(input + ": level not coded")));
    auto one = [&](size_t i) {
        if (o.driver.cancel && o.driver.cancel->load())
            made[i] = ioError(output_path + ": out-of-core bake cancelled");
        else
            made[i] = bakeLevel(std::move(meshes[i]), encoder, chain, i, input);
    };
    if (held + work <= result.level_budget_bytes) {
        LODBAKE_RETURN_IF_ERROR(parallelFor(meshes.size(), 1, one));
        result.level_peak_bytes = std::max(result.level_peak_bytes, held + work);
    } else {
        for (size_t i = 0; i < meshes.size(); ++i) {
            one(i);
            if (!made[i].ok()) break;
        }
    }
    std::vector<PackLevel> levels;
    for (Result<PackLevel>& level : made) {
        LODBAKE_RETURN_IF_ERROR(level.status());
        levels.push_back(std::move(*level));
    }
    return levels;
}

// The kept levels' errors. The input's level (the cut at 0) has error 0. The others are measured
// against the input's partition files in one pass, as many of the coarsest as fit beside the held
// levels (`room` bytes); the finer ones keep their cut's bound, and a note says so.
// With `simplified` (the levels after the first come from the simplifier, so no cut's bound holds for
// them) every one of them must be measured: when that does not fit, nothing is measured and the list
// comes back empty.
Result<std::vector<LevelError>> measureKeptLevels(const std::vector<LevelCut>& cuts, const std::vector<Mesh>& meshes,
                                                  const std::string& input, const OocPackOptions& o, uint64_t room,
                                                  bool simplified, OocPackResult& result, Diagnostics& diagnostics) {
    std::vector<LevelError> errors(cuts.size());
    std::vector<LevelErrorSource> sources(cuts.size(), LevelErrorSource::Bound);
    size_t first = 0; // the first level that is not the input
    if (!cuts.empty() && cuts[0].threshold <= 0.0f && cuts[0].triangles == result.driver.triangle_count) {
        sources[0] = LevelErrorSource::Input;
        first = 1;
    }
    for (size_t i = first; i < cuts.size(); ++i) errors[i] = {double(cuts[i].error_bound), double(cuts[i].error_bound)};
    LODBAKE_ASSIGN_OR_RETURN(std::vector<std::string> files, partitionFilesOf(result.driver.tree));
    LevelErrorOptions lo;
    lo.distance = o.distance;
    lo.threads = o.driver.threads;
    lo.cancel = o.driver.cancel;
    // The coarsest levels whose measurement fits: the bound grows with every level added. A smaller
    // subsample (the level side's starting search) costs time, never bits: the nearest distance is
    // exact whatever it is, so it shrinks before a level falls back to its bound.
    size_t from = cuts.size();
    uint64_t bound = 0;
    const uint32_t full_subsample = lo.bound_triangles;
    for (size_t k = first; k < cuts.size() && from == cuts.size(); ++k) {
        std::vector<const Mesh*> levels;
        for (size_t i = k; i < cuts.size(); ++i) levels.push_back(&meshes[i]);
        for (uint32_t s = full_subsample;; s /= 4) {
            lo.bound_triangles = s;
            LODBAKE_ASSIGN_OR_RETURN(const uint64_t b, levelErrorBound(files, levels, lo));
            if (b <= room) {
                from = k;
                bound = b;
                break;
            }
            if (s <= kSmallestSubsample) break;
        }
    }
    if (simplified && from > std::max<size_t>(first, 1)) return std::vector<LevelError>{};
    if (from > first)
        diagnostics.note(input + ": " + std::to_string(from - first) +
                         " finest level(s) record their cut's error bound: measuring them against the input does "
                         "not fit the memory limit beside the kept levels");
    if (from < cuts.size()) {
        std::vector<const Mesh*> levels;
        for (size_t i = from; i < cuts.size(); ++i) levels.push_back(&meshes[i]);
        lo.memory_limit_bytes = room;
        LODBAKE_ASSIGN_OR_RETURN(std::vector<LevelErrorResult> measured, measureLevelErrors(files, levels, lo));
        for (size_t i = from; i < cuts.size(); ++i) {
            errors[i] = {measured[i - from].distance.hausdorff, measured[i - from].distance.mean};
            sources[i] = LevelErrorSource::Measured;
        }
        result.measured_levels = cuts.size() - from;
        result.measure_bound_bytes = bound;
        result.measure_peak_bytes = measured.empty() ? 0 : measured[0].accounted_peak_bytes;
    }
    size_t k = 0;
    for (OocPackLevel& l : result.levels)
        if (l.kept) l.error_source = sources[k++];
    return errors;
}

// The driver's pages file copied into a spill beside the output (the GLB writer takes its spilled
// blobs as SpillFiles), then removed when `remove_pages` (the in-process run's own file).
Result<std::shared_ptr<SpillFile>> copyPages(const std::string& pages_path, const std::string& output_path,
                                             bool remove_pages, const std::atomic<bool>* cancel) {
    auto spill = std::make_shared<SpillFile>();
    LODBAKE_RETURN_IF_ERROR(spill->open(output_path));
    const int fd = ::open(pages_path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return ioError(pages_path + ": cannot read the cluster pages");
    std::vector<uint8_t> buffer(kCopyBytes);
    Status s;
    const off_t size = ::lseek(fd, 0, SEEK_END);
    if (size < 0) s = ioError(pages_path + ": cannot read the cluster pages");
    for (uint64_t at = 0; s.ok() && at < uint64_t(size); at += buffer.size()) {
        if (cancel && cancel->load()) {
            s = ioError(output_path + ": out-of-core bake cancelled");
            break;
        }
        const size_t n = size_t(std::min<uint64_t>(buffer.size(), uint64_t(size) - at));
        s = readAt(fd, at, buffer.data(), n, pages_path);
        if (s.ok()) s = spill->write(buffer.data(), n);
    }
    ::close(fd);
    if (remove_pages) std::remove(pages_path.c_str());
    LODBAKE_RETURN_IF_ERROR(s);
    LODBAKE_RETURN_IF_ERROR(spill->finish());
    return spill;
}

PackExtension clusterExtension(std::vector<uint8_t> table, std::shared_ptr<SpillFile> pages) {
    PackExtension e;
    e.name = lodrt::format::kExtClusterLod;
    e.json = JsonNode::object();
    e.blobs.push_back(std::move(table));
    e.blob_view_members.push_back(lodrt::format::kClusterTableMember);
    e.blobs.emplace_back();
    e.blob_view_members.push_back(lodrt::format::kClusterPagesMember);
    e.spilled.push_back(nullptr);
    e.spilled.push_back(std::move(pages));
    e.is_stream = false; // beside the MSFT_lod chain, never instead of it
    return e;
}

// The kept levels' cuts, finest first, from the driver's tree (the table's records held); none fitting
// is a ResourceLimit error naming the input.
Result<std::vector<LevelCut>> keptCuts(const TreeClusterTable& table, const std::string& input, const OocPackOptions& o,
                                       OocPackResult& result) {
    const uint64_t limit = o.driver.memory_limit_bytes;
    result.levels = candidateLevels(table, result.driver.triangle_count, o.lod_ratios);
    const uint64_t fixed = table.accounted_peak_bytes + result.driver.table.size() + kOocPackFixedBytes;
    result.level_budget_bytes = limit > fixed ? limit - fixed : 0;
    result.level_peak_bytes = keepLevelsThatFit(result.levels, result.level_budget_bytes);
    std::vector<LevelCut> cuts;
    for (const OocPackLevel& l : result.levels)
        if (l.kept) cuts.push_back(l.cut);
    if (cuts.empty())
        return resourceLimit(input + ": no discrete level fits the memory limit of " + std::to_string(limit >> 20) +
                             " MiB beside the cluster table (the coarsest needs " +
                             std::to_string((fixed + result.levels.back().held_bytes + result.levels.back().work_bytes +
                                             (uint64_t(1) << 20) - 1) >> 20) +
                             " MiB)");
    return cuts;
}

// The kept levels' errors: the caller's, or measured against the input with every kept level's mesh
// held (positions and triangles: at most 12 bytes per cluster vertex and per triangle).
Result<std::vector<LevelError>> keptLevelErrors(const std::vector<LevelCut>& cuts, const std::vector<Mesh>& meshes,
                                                const std::string& input, const OocPackOptions& o, bool simplified,
                                                OocPackResult& result, Diagnostics& diagnostics) {
    if (o.level_errors) {
        LODBAKE_ASSIGN_OR_RETURN(std::vector<LevelError> errors, o.level_errors(cuts));
        if (!errors.empty()) {
            if (errors.size() != cuts.size())
                return internalError(input + ": level errors: " + std::to_string(errors.size()) + " for " +
                                     std::to_string(cuts.size()) + " levels");
            for (OocPackLevel& l : result.levels)
                if (l.kept) l.error_source = LevelErrorSource::Caller;
            return errors;
        }
    }
    uint64_t meshes_bytes = 0;
    for (const LevelCut& c : cuts) meshes_bytes += 12 * c.cluster_vertices + 12 * c.triangles;
    const uint64_t room = result.level_budget_bytes > meshes_bytes ? result.level_budget_bytes - meshes_bytes : 0;
    LODBAKE_ASSIGN_OR_RETURN(std::vector<LevelError> errors,
                             measureKeptLevels(cuts, meshes, input, o, room, simplified, result, diagnostics));
    result.level_peak_bytes = std::max(result.level_peak_bytes, meshes_bytes + result.measure_bound_bytes);
    return errors;
}

// The levels after the finest kept one made by the in-memory bake's LOD chain (the same simplifier
// and options) run on the finest kept level's mesh, at the same triangle counts (the candidates'
// targets, fractions of the input): a free simplification of the whole level is closer to the input
// than a cut of the hierarchy, whose groups are simplified apart. Only when the simplifier's working
// set (the in-memory bake's per-triangle allowance, kBakeBytesPerTriangle) fits beside the kept
// levels' held bytes; otherwise, or when the chain stops above a target, the cuts stay and a note
// says so. Returns whether `meshes` (the finest level's only on entry) now holds every level.
Result<bool> simplifyCoarserLevels(std::vector<Mesh>& meshes, const std::string& input, const OocPackOptions& o,
                                   OocPackResult& result, Diagnostics& diagnostics) {
    std::vector<const OocPackLevel*> kept;
    uint64_t held = 0;
    for (const OocPackLevel& l : result.levels)
        if (l.kept) {
            kept.push_back(&l);
            held += l.held_bytes;
        }
    if (kept.size() < 2) return false;
    const size_t faces = meshes[0].faceCount();
    const uint64_t work = kBakeBytesPerTriangle * uint64_t(faces);
    if (held + work > result.level_budget_bytes) {
        diagnostics.note(input + ": the coarser levels are cuts of the cluster hierarchy: simplifying the finest "
                                 "kept level does not fit the memory limit beside the kept levels");
        return false;
    }
    LodChainOptions co;
    co.simplify.remove_covered_components = o.remove_covered_components;
    co.screen = o.screen;
    co.measure_error = false; // measured against the input below, with the finest level
    co.record_collapses = false;
    co.ratios.clear();
    for (size_t i = 1; i < kept.size(); ++i)
        co.ratios.push_back(std::min(1.0, double(kept[i]->target_triangles) / double(std::max<size_t>(faces, 1))));
    Diagnostics chain_notes;
    LODBAKE_ASSIGN_OR_RETURN(LodChain chain, buildLodChain(meshes[0], co, chain_notes));
    for (const Diagnostic& item : chain_notes.items()) diagnostics.note(input + ": " + item.message);
    if (chain.levels.size() + 1 != kept.size()) {
        diagnostics.note(input + ": the coarser levels are cuts of the cluster hierarchy: the simplifier stopped "
                                 "above a level's target on the finest kept level");
        return false;
    }
    for (LodLevel& level : chain.levels) meshes.push_back(std::move(level.mesh));
    result.level_peak_bytes = std::max(result.level_peak_bytes, held + work);
    return true;
}

// The kept levels' meshes (finest first) and whether the coarser ones came from the simplifier.
Result<bool> levelMeshes(const TreeClusterTable& table, TreePageSource& source, const std::vector<LevelCut>& cuts,
                         const std::string& input, const std::string& output_path, const OocPackOptions& o,
                         std::vector<Mesh>& meshes, OocPackResult& result, Diagnostics& diagnostics) {
    meshes.clear();
    LODBAKE_ASSIGN_OR_RETURN(Mesh finest, extractLevel(table, source, cuts[0], 0, input));
    meshes.push_back(std::move(finest));
    LODBAKE_ASSIGN_OR_RETURN(const bool simplified, simplifyCoarserLevels(meshes, input, o, result, diagnostics));
    if (simplified) return true;
    for (size_t i = 1; i < cuts.size(); ++i) {
        if (o.driver.cancel && o.driver.cancel->load()) return ioError(output_path + ": out-of-core bake cancelled");
        LODBAKE_ASSIGN_OR_RETURN(Mesh mesh, extractLevel(table, source, cuts[i], i, input));
        meshes.push_back(std::move(mesh));
    }
    return false;
}

// Everything after the driver: the cuts, the levels that fit, their meshes, errors and streams, the GLB.
Status packLevels(const std::string& input, const std::string& output_path, const OocPackOptions& o,
                  bool remove_pages, OocPackResult& result, Diagnostics& diagnostics) {
    Clock::time_point t0 = Clock::now();
    LODBAKE_ASSIGN_OR_RETURN(TreeClusterTable table, assembleClusterTable(result.driver.tree, o.driver.memory_limit_bytes));
    LODBAKE_ASSIGN_OR_RETURN(const std::vector<LevelCut> cuts, keptCuts(table, input, o, result));
    TreePageSource source(table);
    std::vector<Mesh> meshes;
    LODBAKE_ASSIGN_OR_RETURN(bool simplified,
                             levelMeshes(table, source, cuts, input, output_path, o, meshes, result, diagnostics));
    result.cut_seconds = since(t0);
    t0 = Clock::now();
    LODBAKE_ASSIGN_OR_RETURN(std::vector<LevelError> errors,
                             keptLevelErrors(cuts, meshes, input, o, simplified, result, diagnostics));
    if (simplified && errors.empty()) {
        // A simplified level has no bound to fall back on: the cuts, which have one, replace them.
        diagnostics.note(input + ": the coarser levels are cuts of the cluster hierarchy: measuring the simplified "
                                 "levels against the input does not fit the memory limit beside the kept levels");
        meshes.resize(1);
        for (size_t i = 1; i < cuts.size(); ++i) {
            LODBAKE_ASSIGN_OR_RETURN(Mesh mesh, extractLevel(table, source, cuts[i], i, input));
            meshes.push_back(std::move(mesh));
        }
        simplified = false;
        LODBAKE_ASSIGN_OR_RETURN(errors, keptLevelErrors(cuts, meshes, input, o, false, result, diagnostics));
    }
    bool after_finest = false;
    for (OocPackLevel& l : result.levels) {
        l.simplified = simplified && l.kept && after_finest;
        after_finest |= l.kept;
    }
    result.measure_seconds = since(t0);
    t0 = Clock::now();
    LODBAKE_ASSIGN_OR_RETURN(ClusterPackBounds bounds, lod0Bounds(table, source));
    const double dx = double(bounds.max[0]) - bounds.min[0], dy = double(bounds.max[1]) - bounds.min[1],
                 dz = double(bounds.max[2]) - bounds.min[2];
    result.metrics = chainMetrics(cuts, errors, std::sqrt(dx * dx + dy * dy + dz * dz), o, result.driver.triangle_count);
    // The chain the valence stream reads for adaptive precision: each level's error as recorded.
    LodChain chain;
    for (size_t i = 1; i < cuts.size(); ++i) {
        LodLevel level;
        level.has_distance = true;
        level.distance.hausdorff = result.metrics.levels[i].hausdorff_error;
        level.distance.mean = result.metrics.levels[i].mean_error;
        chain.levels.push_back(std::move(level));
    }
    const PackStreamEncoder encoder = valenceStreamEncoder(o.valence);
    PackDescription description;
    description.compact = o.compact;
    PackAsset asset;
    asset.name = o.name;
    LODBAKE_ASSIGN_OR_RETURN(asset.levels, bakeLevels(meshes, encoder, chain, input, output_path, o, result));
    for (size_t i = 0; i < asset.levels.size(); ++i) {
        result.metrics.levels[i].triangles = asset.levels[i].mesh.faceCount();
        result.metrics.levels[i].vertices = asset.levels[i].mesh.vertexCount();
    }
    result.cut_seconds += since(t0);
    t0 = Clock::now();
    asset.screen_coverage = msftScreenCoverage(result.metrics);
    asset.node_extensions.push_back(lodMetricsExtension(result.metrics));
    LODBAKE_ASSIGN_OR_RETURN(std::shared_ptr<SpillFile> pages,
                             copyPages(result.driver.output, output_path, remove_pages, o.driver.cancel));
    asset.levels[0].mesh_extensions.insert(asset.levels[0].mesh_extensions.begin(),
                                           clusterExtension(std::move(result.driver.table), std::move(pages)));
    description.assets.push_back(std::move(asset));
    LODBAKE_RETURN_IF_ERROR(checkCompact(description));
    LODBAKE_ASSIGN_OR_RETURN(result.pack_bytes, writePackGlbFile(std::move(description), output_path, o.driver.cancel));
    result.pack_seconds = since(t0);
    return Status::okStatus();
}

} // namespace

uint64_t leafTrianglesForLimit(uint64_t limit, const StreamReadOptions& read, uint64_t sample_cap) {
    constexpr uint64_t kMiB = uint64_t(1) << 20;
    const uint64_t fixed = read.buffer_bytes + 12 * uint64_t(read.vertex_chunk) + 12 * uint64_t(read.triangle_chunk) +
                           32 * sample_cap + kMiB + (uint64_t(64) << 10);
    uint64_t leaf = kDefaultLeafTriangles;
    while (leaf > 4096 && fixed + kPartitionBuildBytesPerTriangle * leaf + 2 * kMiB > limit) leaf /= 2;
    return leaf;
}

uint64_t levelHeldBytes(const LevelCut& cut) {
    // Positions and normals (V <= V_c), indices, the stream (at most 8 bytes per triangle), and the
    // same accessors again in the GLB's binary chunk.
    return 2 * (24 * cut.cluster_vertices + 12 * cut.triangles) + 8 * cut.triangles;
}

uint64_t levelWorkBytes(const LevelCut& cut) {
    static const double coder = valenceStreamEncoder().cost.bytes_per_triangle;
    const uint64_t coding = 24 * cut.cluster_vertices + 12 * cut.triangles + uint64_t(coder * double(cut.triangles));
    return std::max(levelCutBytes(cut), coding);
}

Result<OocPackResult> writeOutOfCorePack(const std::string& input, const std::string& output_path,
                                         const OocPackOptions& options, Diagnostics& diagnostics) {
    if (options.driver.work_dir.empty()) return invalidInput(input + ": out-of-core bake: no work folder given");
    RunFolder folder;
    LODBAKE_RETURN_IF_ERROR(folder.make(options.driver.work_dir, input));
    OutOfCoreOptions driver = options.driver;
    driver.work_dir = folder.path();
    driver.keep_intermediate = true; // the levels are cut from the tree's files; the folder goes at the end
    driver.pages.pack.position_bits = options.valence.position_bits;
    OocPackResult result;
    LODBAKE_ASSIGN_OR_RETURN(result.driver,
                             buildOutOfCore(input, (fs::path(folder.path()) / "pages.bin").string(), driver, diagnostics));
    LODBAKE_RETURN_IF_ERROR(packLevels(input, output_path, options, true, result, diagnostics));
    result.input_triangles = result.driver.triangle_count;
    result.input_vertices = result.driver.vertex_count;
    return result;
}

Result<OocPackResult> writePlannedPack(const std::string& work_dir, const std::string& output_path,
                                       const OocPackOptions& options, Diagnostics& diagnostics) {
    LODBAKE_ASSIGN_OR_RETURN(JobPlan plan, readJobPlan(jobPlanPath(work_dir)));
    OocPackResult result;
    LODBAKE_ASSIGN_OR_RETURN(result.driver, plannedResult(work_dir));
    const std::string input = plan.input.empty() ? jobPlanPath(work_dir) : plan.input;
    // The pages job's file stays until the GLB is written: a failure leaves the plan as it was.
    LODBAKE_RETURN_IF_ERROR(packLevels(input, output_path, options, false, result, diagnostics));
    result.input_triangles = result.driver.triangle_count;
    result.input_vertices = result.driver.vertex_count;
    removePlannedFiles(work_dir);
    return result;
}

} // namespace lodbake::ooc
