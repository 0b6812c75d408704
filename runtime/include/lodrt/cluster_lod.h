#pragma once
// Per-view cut of a cluster LOD hierarchy (docs/cluster_lod.md): a DAG of small clusters in which
// every group of clusters was merged, simplified with its outer border locked and split again into
// the group's output clusters. A group carries one error and one LOD sphere; they are the "self"
// error of its output clusters and the "parent" error of its input clusters, and both are monotonic
// up the DAG (a group's error is at least its input clusters' errors, its LOD sphere encloses theirs),
// so the projected error is monotonic too. A cluster is drawn when its own error projects to at most
// the pixel threshold and its parent group's error to more; since the two sides of one group use the
// same value, either all of a group's inputs or all of its outputs pass, and the cut has no crack.
//
// The projection is the one of selection.h: error e at distance d (from the eye to the sphere, 0
// inside it, model units) projects to e * K / d pixels, K = pixelsPerUnitAtDistanceOne(params).
//
// The cut is found by a walk down the DAG from the roots: a group is entered only when its error
// projects to more than the threshold (its inputs may be drawn) and its culling sphere, which
// encloses everything below it, is not outside the frustum, so the cost follows what is drawn and
// what is visible. With a frustum, the cut is exactly the frustum-less cut less the clusters whose
// own sphere is outside or whose normal cone faces away from the eye. No allocation: the
// caller owns the scratch and the output. Pure apart from the caller's scratch; callable from any
// thread with one scratch per thread.

#include <cstddef>
#include <cstdint>

#include "lodrt/export.h"
#include "lodrt/frustum.h"
#include "lodrt/result.h"
#include "lodrt/selection.h"

namespace lodrt {

inline constexpr uint32_t kClusterNone = 0xffffffffu;

/// One group: input clusters merged, simplified, split into output clusters.
struct ClusterLodGroup {
    float lod_center[3] = {}; // LOD sphere: encloses the LOD spheres of its input clusters
    float lod_radius = 0;
    float error = 0;             // model units: distance bound of its outputs to LOD0, >= its inputs' errors
    float bounds_center[3] = {}; // culling sphere: encloses its outputs' geometry and everything below
                                 // it (its inputs' geometry and their own groups' culling spheres)
    float bounds_radius = 0;
    uint32_t first_child = 0; // range of ClusterLodView::group_children: the input clusters
    uint32_t child_count = 0;
    uint32_t depth = 0; // 1 for groups of LOD0 clusters, one more per level above
};

/// One cluster: at most kMaxTriangles triangles over at most kMaxVertices vertices.
struct ClusterLodCluster {
    float center[3] = {}; // geometry sphere (culling)
    float radius = 0;
    uint32_t self_group = kClusterNone;   // group whose simplification made it; kClusterNone for LOD0
    uint32_t parent_group = kClusterNone; // group it is an input of; kClusterNone for a root
    uint32_t first_vertex = 0;            // range of the hierarchy's vertex array
    uint32_t vertex_count = 0;
    uint32_t first_triangle = 0; // range of the hierarchy's triangles (3 local vertex indices each)
    uint32_t triangle_count = 0;
    /// Normal cone (conservative): every triangle's unit normal n has dot(n, cone_axis) >=
    /// cone_cutoff = cos(a), cone_sin = sin(a). cone_cutoff <= 0 means no cone (never cone-culled).
    float cone_axis[3] = {};
    float cone_cutoff = -1;
    float cone_sin = 1;

    static constexpr uint32_t kMaxTriangles = 128;
    static constexpr uint32_t kMaxVertices = 255;
};

/// A hierarchy in memory, lent by its owner. The LOD sphere and error of a cluster are its
/// self_group's (0 error for LOD0 clusters); its parent's are its parent_group's (infinite for a root).
struct ClusterLodView {
    const ClusterLodCluster* clusters = nullptr;
    uint32_t cluster_count = 0;
    const ClusterLodGroup* groups = nullptr;
    uint32_t group_count = 0;
    const uint32_t* group_children = nullptr; // cluster indices, each group's inputs in one range
    uint32_t group_child_count = 0;
    const uint32_t* roots = nullptr; // clusters without a parent group
    uint32_t root_count = 0;
    uint32_t vertex_count = 0;   // size of the vertex array the clusters' vertex ranges index
    uint32_t triangle_count = 0; // size of the triangle array the clusters' triangle ranges index
};

/// Checks what the cut relies on, treating every field as untrusted: every index and range in bounds,
/// finite non-negative errors and radii, normal cones finite with a unit axis (when present), every
/// cluster's parent_group listing it among its children
/// and every root without a parent. Returns Ok, OutOfBounds (an index or range outside its array) or
/// BadStructure (a non-finite or negative value, a child list that disagrees with parent_group). Monotonicity is a
/// property of a good bake, not a safety condition: the walk terminates and stays in bounds without it.
LODRT_API Result validateClusterLod(const ClusterLodView& lod);

/// Bytes of scratch one cut needs for `lod` (group visit stamps and the walk's stack).
LODRT_API size_t clusterCutScratchBytes(const ClusterLodView& lod);

/// Caller-owned scratch of clusterCutScratchBytes(lod) bytes, aligned to 4, zero-filled before the
/// first use and then reused frame after frame (the stamps make clearing unnecessary).
struct ClusterCutScratch {
    void* memory = nullptr;
    size_t size_bytes = 0;
    uint32_t epoch = 0; // in/out: bumped by every cut
};

/// One instance of the hierarchy: model -> world is p * scale + translation.
struct ClusterInstance {
    float translation[3] = {};
    float scale = 1;
};

struct ClusterCutStats {
    uint32_t selected = 0;       // clusters of the cut that are visible (may exceed the capacity)
    uint32_t written = 0;        // cluster indices written to the output
    uint32_t groups_visited = 0; // groups entered
    uint32_t triangles = 0;      // triangles of the selected clusters
    uint32_t cone_culled = 0;    // clusters of the cut not drawn because they face away from the eye
};

/// True when every triangle of `cluster` faces away from `eye` (model space): for every point p of
/// the cluster's sphere and every normal n of its cone, dot(n, p - eye) > 0. Conservative: with
/// angle(axis, center - eye) = f and the cone's half angle a, it holds when f + a < 90 degrees and
/// |center - eye| * cos(f + a) exceeds the radius (plus a small margin for float rounding).
LODRT_API bool clusterBackFacing(const ClusterLodCluster& cluster, const float eye[3]);

/// Selects the cut of one instance for a view: writes the indices of the clusters to draw to
/// out[0, capacity) and returns the counts. `eye` is in world space; `frustum` (world space) may be
/// null to select without culling (the crack-free cut of the whole surface). With a frustum, a
/// cluster of the cut is also not drawn when clusterBackFacing says its normal cone faces away from
/// the eye (only triangles no one can see are dropped; the clusters drawn still meet edge for edge). `params` as in
/// selection.h (pixel_threshold, vertical_fov, viewport_height, lod_bias; other fields unused).
/// Returns InvalidArgument (and no output) when the scratch is too small or the instance scale is
/// not positive and finite; `lod` is assumed to have passed validateClusterLod.
LODRT_API Result selectClusterCut(const ClusterLodView& lod, const ClusterInstance& instance, const float eye[3],
                                  const Frustum* frustum, const SelectionParams& params, ClusterCutScratch& scratch,
                                  uint32_t* out, uint32_t capacity, ClusterCutStats* stats);

/// Which groups' input clusters are loaded (their pages resident), for a cut that draws the finest
/// resident clusters until the missing pages arrive.
struct ClusterResidency {
    /// Per group: nonzero when its input clusters can be drawn. Must be closed upward
    /// (clusterResidencyClosure): a resident group's outputs' parent groups are resident too, else
    /// the stand-in clusters of two groups could overlap.
    const uint8_t* group_resident = nullptr;
    uint32_t* missing = nullptr; // out: groups the cut would have entered but could not, each once
    uint32_t missing_capacity = 0;
    uint32_t missing_count = 0; // out: all of them (may exceed the capacity)
};

/// Clears the residency of every group whose outputs have a non-resident parent group, until the
/// set is closed upward. Call after the resident pages change (not per frame): O(levels x clusters).
LODRT_API void clusterResidencyClosure(const ClusterLodView& lod, uint8_t* group_resident);

/// selectClusterCut over the resident part of the hierarchy: where the cut would enter a group that
/// is not resident, the group's outputs are drawn instead (all of them decide alike, so the drawn
/// clusters still meet edge for edge, only coarser there) and the group is listed as missing.
/// `residency` may be null (every group resident: exactly selectClusterCut). The roots' pages are
/// assumed resident. InvalidArgument also for a residency without group_resident or output.
LODRT_API Result selectClusterCutResident(const ClusterLodView& lod, const ClusterInstance& instance,
                                          const float eye[3], const Frustum* frustum, const SelectionParams& params,
                                          ClusterCutScratch& scratch, ClusterResidency* residency, uint32_t* out,
                                          uint32_t capacity, ClusterCutStats* stats);

} // namespace lodrt
