#pragma once
// Which of an asset's post-chain tasks may run side by side (docs/bake.md, "Concurrency"): the
// tasks in their fixed start order, cut into consecutive phases by a working-memory estimate.
// Internal to the bake; the cut never changes a byte of the output, only the peak memory.

#include <cstddef>
#include <vector>

namespace lodbake {
namespace bake_detail {

/// Working memory of the bake's own measurement tasks in bytes per triangle of the mesh they read
/// (resident size above what the bake holds). The streams' estimates come with each stream
/// (StreamCost in lodbake/stream/stream.h).
struct PhaseEstimates {
    double measure_bytes_per_triangle = 160; // LOD0's BVH and points, then two levels' (per LOD0 triangle)
    /// The reference sides measured beforehand (MeasureReference): LOD0's points as their sources (per
    /// LOD0 triangle), then one level's index at a time (per triangle of the largest of its levels).
    double reference_points_bytes_per_triangle = 6;
    double reference_index_bytes_per_triangle = 70;
    /// Whether the reference sides may run ahead (MeasureReference); with one thread nothing idles
    /// beside the LOD0-only streams, and the split only costs (LOD0's points recomputed per query).
    bool measure_reference_ahead = true;
    /// Tasks share a phase only while their estimates add up to at most this; a task above it runs
    /// alone, so with the built-in streams small assets (up to about 400,000 triangles) run every
    /// task at once.
    double budget_bytes = 240.0 * 1024 * 1024;
};

/// What the scheduler knows of one stream encoder (StreamNeeds::lod0_only, StreamCost).
struct EncoderCost {
    bool lod0_only = false;
    double bytes_per_triangle = 0;
};

/// One task: the measurement (then the metrics and texture levels), the reference sides of some levels'
/// measurement ahead of it, one encoder's prepare on LOD0, or every encoder's prepare on one other level.
struct PhaseTask {
    enum class Kind { Measure, MeasureReference, Lod0Encoder, Level };
    Kind kind = Kind::Measure;
    size_t index = 0; // encoder (Lod0Encoder), level (Level), first level (MeasureReference: it and the rest)
    double bytes = 0; // working-memory estimate
};

/// The tasks in their start order -- the LOD0-only encoders (such as the PFRep build: the longest,
/// single-threaded),
/// the measurement (parallel inside), the other encoders on LOD0, the other levels (largest first)
/// -- cut into consecutive phases that fit the budget. The biggest working sets come first, while
/// the least is resident: what each task leaves behind (blobs, renumbered indices, heap pages the
/// allocator keeps) adds to every later task's peak. LOD0's coding comes after the measurement so
/// that on a large asset it shares the last phase with the other levels' coding (single-threaded
/// tasks side by side) rather than running alone, and the measurement's peak holds none of its output.
/// A MeasureReference task (LOD0's points against every level, the part of the
/// measurement that needs neither LOD0's index nor the levels' points) comes between the PFRep build
/// and the measurement when it shares a phase with the PFRep build and not with the measurement:
/// the PFRep build is single-threaded and runs alone on a large asset, so with two threads this part of
/// the measurement takes a core that would idle. Anywhere else it would gain nothing: it is left out.
/// `encoders[e]` describes encoder e; a Level task's estimate is the sum of the other encoders';
/// `level_triangles[0]` is LOD0's count.
std::vector<std::vector<PhaseTask>> concurrentPhases(const std::vector<EncoderCost>& encoders,
                                                     const std::vector<size_t>& level_triangles,
                                                     const PhaseEstimates& estimates = {});

} // namespace bake_detail
} // namespace lodbake
