#pragma once
// The pack of an out-of-core bake (docs/pipeline.md, "The pack of an out-of-core bake"): the driver
// (driver.h) builds the merged cluster hierarchy and its LODBAKE_cluster_lod pages under the memory
// limit; discrete levels are then cut from the hierarchy (level_cut.h) at the bake's LOD ratios,
// those that fit in memory become the MSFT_lod chain (the input itself first, when it fits), coded
// by the valence stream like any level, with MSFT_screencoverage and LODBAKE_lod_metrics; the
// cluster extension goes on the chain's finest level with its pages copied from a file; the GLB is
// written by writePackGlbFile. The metrics record the input's triangle count (inputTriangles), so a
// reader sees where the chain starts.
//
// Levels that fit: with the table's records held (TreeClusterTable, its accounted peak) and the
// extension's table blob, the chain's levels must fit the rest of the limit, less kOocPackFixedBytes:
//   sum over kept levels of levelHeldBytes + max over kept levels of levelWorkBytes
// (the levels are held until the GLB is written, each extracted and coded one at a time). The kept
// levels are the longest run of the coarsest levels that fits, decided from the cuts' counts before
// any geometry is read; finer levels exist only as cluster pages. None fitting is a ResourceLimit
// error naming the input.
//
// The finest kept level is a cut (the input does not fit in memory); the coarser kept levels are the
// in-memory bake's LOD chain (buildLodChain, the bake's simplifier options) run on that level's mesh
// down to the same targets (fractions of the input's triangles): a whole-level simplification is
// closer to the input than a cut, whose groups were simplified apart. This needs the simplifier's
// working set (kBakeBytesPerTriangle per triangle of the finest kept level, bake/memory_budget.h)
// beside the kept levels' held bytes, and the measurement of every simplified level (they have no
// cut's bound to fall back on); otherwise, or when the simplifier stops above a target, the coarser
// levels are cuts too and a diagnostic note says why (OocPackLevel::simplified says which).
//
// Errors of a level: measured against the input (measureLevelErrors, level_error.h: the bake's
// error_samples, one pass over the partition files for every kept level), the two-sided distance
// the in-memory bake records; the input itself (the cut at 0) has error 0. The measurement's bound
// (levelErrorBound) is reserved beside the kept levels' meshes, its subsample shrunk (time, not bits)
// before a level is given up; the finest levels whose measurement does not fit keep the cut's group-error bound (LevelCut::error_bound, a bound on their
// distance to the input) as both errors, and a diagnostic note says which. A coarser level's errors
// are at least the finer level's, as in the in-memory bake.
//
// Determinism: the driver's output, the cuts, the welding and the coding depend on the input and the
// options only; the limit decides only which levels are kept and whether the coarser ones are the
// simplifier's. Failure: every file the run made
// (partition, hierarchy and merge files, the pages, the output's temporaries) is removed, the work
// folder too when the run created it, and no output is left.

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "lodbake/core/diagnostics.h"
#include "lodbake/core/lod_policy.h"
#include "lodbake/core/status.h"
#include "lodbake/ooc/driver.h"
#include "lodbake/ooc/level_cut.h"
#include "lodbake/pack/pack.h"
#include "lodbake/simplify/mesh_distance.h"
#include "lodbake/stream/stream.h"

namespace lodbake::ooc {

/// Besides the levels: the GLB writer's buffers (1 MiB write, 64 KiB copy), the pages' copy buffer,
/// the LOD0 bounds pass's window and a margin for the pack's JSON.
constexpr uint64_t kOocPackFixedBytes = uint64_t(4) << 20;

/// A kept level while the others are built and the GLB is written: its mesh (positions, normals,
/// indices), its valence stream, and the same bytes again in the GLB's binary chunk.
uint64_t levelHeldBytes(const LevelCut& cut);
/// Extracting and coding one level: levelCutBytes, or the mesh with the valence coder's working set.
uint64_t levelWorkBytes(const LevelCut& cut);

/// The partition size for a run under `limit`: kDefaultLeafTriangles, halved (down to 4,096) until
/// the partitioner's fixed buffers (reader window and chunks, the sample at `sample_cap`, the spill's
/// buffers) and one partition job of that size (kPartitionBuildBytesPerTriangle, its file buffers)
/// fit. Every limit that holds a default job gets the default, so the tree, hence the pack, depends on
/// the limit only below that (about 300 MiB), where no default job could run at all.
uint64_t leafTrianglesForLimit(uint64_t limit, const StreamReadOptions& read, uint64_t sample_cap);

/// Errors of a kept level (finest first), when a caller replaces the measurement: each entry's
/// hausdorff and mean are recorded as the level's errors.
struct LevelError {
    double hausdorff = 0;
    double mean = 0;
};

/// How the kept levels' errors were found.
enum class LevelErrorSource : uint32_t { Input = 0, Measured = 1, Bound = 2, Caller = 3 };

struct OocPackOptions {
    OutOfCoreOptions driver;         // work folder, limit, threads, cluster and page options, cancel
    std::string name = "mesh";       // the LOD group (asset) name
    std::vector<double> lod_ratios{0.5, 0.25, 0.1, 0.03}; // the chain's targets, fractions of the input
    ScreenParams screen;
    double hysteresis = 0.1;
    ValenceStreamOptions valence;    // the levels' streams (position bits also the pages' grid bits)
    bool compact = false;            // PackDescription::compact
    DistanceOptions distance;        // the measurement's (the bake sets sample_count to error_samples)
    bool remove_covered_components = false; // the simplifier's option for the coarser levels (the bake's)
    /// Called with the kept levels' cuts (finest first) before their metrics are written; returns
    /// one LevelError per level, which replaces the measurement, or an empty list to measure. Optional.
    std::function<Result<std::vector<LevelError>>(const std::vector<LevelCut>& kept)> level_errors;
};

/// One candidate level: the input (ratio 1) and each LOD ratio, with its cut and whether it was kept.
struct OocPackLevel {
    double ratio = 1;
    uint64_t target_triangles = 0;
    LevelCut cut;
    uint64_t held_bytes = 0, work_bytes = 0;
    bool kept = false;
    bool simplified = false; // kept, coarser than the finest kept level, made by the simplifier (not the cut)
    LevelErrorSource error_source = LevelErrorSource::Bound; // kept levels: where their errors came from
};

struct OocPackResult {
    uint64_t pack_bytes = 0;
    uint64_t input_triangles = 0, input_vertices = 0;
    LodMetrics metrics;               // the kept levels, finest first (metrics.input_triangles set)
    std::vector<OocPackLevel> levels; // every candidate (duplicates of a finer cut left out)
    uint64_t level_budget_bytes = 0;  // what the levels could use
    uint64_t level_peak_bytes = 0;    // what the kept levels were accounted (sum held + max work)
    uint64_t measured_levels = 0;     // kept levels measured against the input
    uint64_t measure_bound_bytes = 0; // levelErrorBound of those levels (reserved beside the kept levels)
    uint64_t measure_peak_bytes = 0;  // the measurement's accounted peak
    OutOfCoreResult driver;           // its tree's files are gone
    double cut_seconds = 0, measure_seconds = 0, pack_seconds = 0;
};

/// Bakes `input` (.ply or .obj) out of core into the pack at `output_path` (written through a
/// temporary renamed into place). Errors as buildOutOfCore's, the cuts' and the writer's; each names
/// its file; on any error no output and none of the run's files are left.
Result<OocPackResult> writeOutOfCorePack(const std::string& input, const std::string& output_path,
                                         const OocPackOptions& options, Diagnostics& diagnostics);

/// The pack of a finished job list (jobs.h) in `work_dir`: plannedResult's tree, pages and table, and
/// the partition files the plan's first step wrote, made into the GLB at `output_path` by the same
/// code as writeOutOfCorePack's after its driver, so that for the same options (the plan's and
/// these: options.driver's limit and cancel, the chain's) the bytes are writeOutOfCorePack's. The
/// plan's input names errors. Once the GLB is in place every file the plan lists (partitions, the
/// jobs' outputs and records, plan.json) is removed; on an error they all stay, so it can run again.
Result<OocPackResult> writePlannedPack(const std::string& work_dir, const std::string& output_path,
                                       const OocPackOptions& options, Diagnostics& diagnostics);

} // namespace lodbake::ooc
