#pragma once
// Range-scan merging: aligned views (a .conf scan set, or a mesh whose components overlap as
// sheets) become one surface. Each sample (a vertex on a triangle) gets the area-weighted normal
// of its sheet's triangles, which the range-grid triangulation winds towards the scanner; screened
// Poisson reconstruction (Open3D's, loaded on first use) at an octree depth chosen from the
// sampling density builds the surface; the surface it invents far from every sample (low sample
// density) is trimmed, so real holes stay open; colours come from the nearest samples.
// See docs/bake.md ("Merging range scans").

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"

namespace lodbake {

struct MergeOptions {
    int depth = 0;                   // octree depth; 0 picks it from the sampling density
    int min_depth = 5, max_depth = 11; // the picked depth is clamped to this range
    double cell_per_spacing = 1.0;   // picked depth: the finest whose cell is at least this × the sample spacing
    float scale = 1.1f;              // octree cube / the samples' bounding cube
    double trim_log2 = 1.5;          // trim vertices whose density is this many octaves below the median
    size_t max_points = size_t(1) << 22; // input limit: the octree and its solver grow with the samples
    size_t min_points = 64;              // fewer samples than this cannot define a surface
    uint32_t distance_samples = 0;   // samples measured for the report's distances; 0: every sample
};

struct MergeReport {
    size_t views = 0;         // sheets merged: sub-meshes of a scan set, else connected components
    bool views_are_scans = false; // `views` counts the scans of a scan set (sub-meshes), not components
    size_t points = 0;        // samples fed to the reconstruction
    int depth = 0;            // octree depth used
    double sample_spacing = 0.0; // median edge length of the input triangles
    size_t faces_before_trim = 0;
    size_t faces = 0;         // triangles of the merged surface
    double area = 0.0;        // of the merged surface
    double trimmed_area = 0.0; // removed by the density trim
    double diagonal = 0.0;    // of the input's bounding box
    double mean_distance = 0.0; // input samples to the merged surface, absolute (divide by `diagonal`)
    double p95_distance = 0.0;
};

/// The report as lines for people: what was merged, the trimmed area and the sample distances
/// (absolute and relative to the diagonal).
std::vector<std::string> mergeReportLines(const MergeReport& report);

/// How much of a mesh's surface lies on top of another of its components: the fraction of its
/// referenced vertices whose grid cell (cell size a few sample spacings) also holds a vertex of
/// another component. 0 for a single component (and for an inconsistent mesh). Deterministic.
double overlappingSheetFraction(const Mesh& mesh);

/// A mesh counts as overlapping sheets when overlappingSheetFraction() reaches this.
constexpr double kOverlappingSheetFraction = 0.2;

/// Replaces `mesh` by the merged surface (positions, triangles, colours when the input has them;
/// one sub-mesh). Bad or absurd input is InvalidInput / ResourceLimit naming `name`; on failure `mesh`
/// is unchanged. The result does not depend on the thread count.
Result<MergeReport> mergeRangeViews(Mesh& mesh, const MergeOptions& options, const std::string& name);

} // namespace lodbake
