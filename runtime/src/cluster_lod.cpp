// Cut selection over a cluster LOD hierarchy (lodrt/cluster_lod.h, docs/cluster_lod.md): a walk
// down the group DAG from the roots with a caller-owned stack and visit stamps, so nothing is
// allocated per frame and each group is entered at most once per cut.

#include "lodrt/cluster_lod.h"

#include <cmath>
#include <cstring>

namespace lodrt {

namespace {

bool finiteSphere(const float center[3], float radius) {
    return std::isfinite(center[0]) && std::isfinite(center[1]) && std::isfinite(center[2]) && std::isfinite(radius) &&
           radius >= 0;
}

// A cone is unit-axis with cos and sin of one angle, or absent (cutoff <= 0, never used).
bool validCone(const ClusterLodCluster& cl) {
    if (!std::isfinite(cl.cone_cutoff) || cl.cone_cutoff > 1 || !std::isfinite(cl.cone_sin)) return false;
    if (!(cl.cone_cutoff > 0)) return true;
    const float len2 =
        cl.cone_axis[0] * cl.cone_axis[0] + cl.cone_axis[1] * cl.cone_axis[1] + cl.cone_axis[2] * cl.cone_axis[2];
    const float unit = cl.cone_cutoff * cl.cone_cutoff + cl.cone_sin * cl.cone_sin;
    return std::isfinite(len2) && std::fabs(len2 - 1) < 1e-3f && cl.cone_sin >= 0 && unit > 1 - 1e-3f;
}

bool rangeFits(uint32_t first, uint32_t count, uint32_t size) {
    return uint64_t(first) + uint64_t(count) <= uint64_t(size);
}

Result validateClusters(const ClusterLodView& lod, uint32_t& with_parent, uint32_t& without_parent) {
    with_parent = 0;
    without_parent = 0;
    for (uint32_t c = 0; c < lod.cluster_count; ++c) {
        const ClusterLodCluster& cl = lod.clusters[c];
        if (cl.self_group != kClusterNone && cl.self_group >= lod.group_count) return Result::OutOfBounds;
        if (cl.parent_group != kClusterNone && cl.parent_group >= lod.group_count) return Result::OutOfBounds;
        if (!rangeFits(cl.first_vertex, cl.vertex_count, lod.vertex_count) ||
            !rangeFits(cl.first_triangle, cl.triangle_count, lod.triangle_count))
            return Result::OutOfBounds;
        if (cl.vertex_count > ClusterLodCluster::kMaxVertices || cl.triangle_count > ClusterLodCluster::kMaxTriangles ||
            !finiteSphere(cl.center, cl.radius) || (cl.self_group != kClusterNone && cl.self_group == cl.parent_group) ||
            !validCone(cl))
            return Result::BadStructure;
        (cl.parent_group == kClusterNone ? without_parent : with_parent) += 1;
    }
    return Result::Ok;
}

Result validateGroups(const ClusterLodView& lod, uint32_t with_parent) {
    uint64_t listed = 0;
    for (uint32_t g = 0; g < lod.group_count; ++g) {
        const ClusterLodGroup& group = lod.groups[g];
        if (!rangeFits(group.first_child, group.child_count, lod.group_child_count)) return Result::OutOfBounds;
        if (!finiteSphere(group.lod_center, group.lod_radius) ||
            !finiteSphere(group.bounds_center, group.bounds_radius) || !std::isfinite(group.error) || group.error < 0)
            return Result::BadStructure;
        for (uint32_t i = 0; i < group.child_count; ++i) {
            const uint32_t c = lod.group_children[group.first_child + i];
            if (c >= lod.cluster_count) return Result::OutOfBounds;
            if (lod.clusters[c].parent_group != g) return Result::BadStructure;
        }
        listed += group.child_count;
    }
    return listed == with_parent ? Result::Ok : Result::BadStructure;
}

// Model-space copy of a world-space frustum for model -> world = p * s + t: a unit plane n.x + d >= 0
// becomes n.x + (n.t + d) / s >= 0, still with a unit normal, so classifySphere applies unchanged.
Frustum modelFrustum(const Frustum& world, const ClusterInstance& instance) {
    Frustum model = world;
    for (auto& p : model.planes)
        p[3] =
            (p[0] * instance.translation[0] + p[1] * instance.translation[1] + p[2] * instance.translation[2] + p[3]) /
            instance.scale;
    return model;
}

struct Walk {
    const ClusterLodView& lod;
    const Frustum* frustum; // model space, or null
    float eye[3];           // model space
    float error_scale;      // K / (threshold * 2^bias): an error e is too coarse when e * error_scale > d
    uint32_t* stamps;
    uint32_t* stack;
    uint32_t stack_size;
    uint32_t epoch;
    uint32_t* out;
    uint32_t capacity;
    ClusterCutStats stats;
    ClusterResidency* residency; // or null: every group resident

    // The error of the LOD sphere projects to more than the threshold: d = max(|c - eye| - r, 0).
    bool tooCoarse(const ClusterLodGroup& g) const {
        const float dx = g.lod_center[0] - eye[0], dy = g.lod_center[1] - eye[1], dz = g.lod_center[2] - eye[2];
        const float d = std::sqrt(dx * dx + dy * dy + dz * dz) - g.lod_radius;
        return g.error * error_scale > (d > 0 ? d : 0.0f);
    }

    // A cluster whose parent's error is too coarse: drawn when its own error is fine and it is not
    // outside the frustum, else its own group is entered (once) to draw finer clusters there. The
    // group is culled by its own sphere, which encloses everything below it, not by this
    // cluster's: the finer clusters may reach into the frustum where this one does not.
    void consider(uint32_t c) {
        const ClusterLodCluster& cl = lod.clusters[c];
        if (cl.self_group != kClusterNone && tooCoarse(lod.groups[cl.self_group])) {
            const bool resident = !residency || residency->group_resident[cl.self_group] != 0;
            if (stamps[cl.self_group] != epoch) {
                stamps[cl.self_group] = epoch;
                if (resident) {
                    stack[stack_size++] = cl.self_group;
                } else {
                    if (residency->missing_count < residency->missing_capacity)
                        residency->missing[residency->missing_count] = cl.self_group;
                    ++residency->missing_count;
                }
            }
            // Not resident: this cluster stands in for the finer ones (so do its siblings: the same
            // group decides for all of them).
            if (resident) return;
        }
        if (frustum && classifySphere(*frustum, cl.center, cl.radius) == Containment::Outside) return;
        if (frustum && cl.cone_cutoff > 0 && clusterBackFacing(cl, eye)) {
            ++stats.cone_culled;
            return;
        }
        if (stats.written < capacity) out[stats.written++] = c;
        ++stats.selected;
        stats.triangles += cl.triangle_count;
    }

    void run() {
        for (uint32_t r = 0; r < lod.root_count; ++r) consider(lod.roots[r]);
        while (stack_size > 0) {
            const ClusterLodGroup& g = lod.groups[stack[--stack_size]];
            if (frustum && classifySphere(*frustum, g.bounds_center, g.bounds_radius) == Containment::Outside) continue;
            ++stats.groups_visited;
            for (uint32_t i = 0; i < g.child_count; ++i) consider(lod.group_children[g.first_child + i]);
        }
    }
};

} // namespace

bool clusterBackFacing(const ClusterLodCluster& cl, const float eye[3]) {
    if (!(cl.cone_cutoff > 0)) return false;
    const float vx = cl.center[0] - eye[0], vy = cl.center[1] - eye[1], vz = cl.center[2] - eye[2];
    const float d = std::sqrt(vx * vx + vy * vy + vz * vz);
    if (!(d > cl.radius)) return false;
    const float cos_f = (vx * cl.cone_axis[0] + vy * cl.cone_axis[1] + vz * cl.cone_axis[2]) / d;
    if (!(cos_f > 0)) return false;
    const float sin_f = std::sqrt(std::fmax(0.0f, 1.0f - cos_f * cos_f));
    // cos(f + a); the margin covers the rounding of the eye's transform and of these few operations.
    const float cos_sum = cos_f * cl.cone_cutoff - sin_f * cl.cone_sin;
    constexpr float kMargin = 1e-4f;
    return cos_sum > kMargin && d * (cos_sum - kMargin) > cl.radius;
}

Result validateClusterLod(const ClusterLodView& lod) {
    if ((lod.cluster_count > 0 && !lod.clusters) || (lod.group_count > 0 && !lod.groups) ||
        (lod.group_child_count > 0 && !lod.group_children) || (lod.root_count > 0 && !lod.roots))
        return Result::InvalidArgument;
    uint32_t with_parent = 0, without_parent = 0;
    Result r = validateClusters(lod, with_parent, without_parent);
    if (r != Result::Ok) return r;
    r = validateGroups(lod, with_parent);
    if (r != Result::Ok) return r;
    if (lod.root_count != without_parent) return Result::BadStructure;
    for (uint32_t i = 0; i < lod.root_count; ++i) {
        if (lod.roots[i] >= lod.cluster_count) return Result::OutOfBounds;
        if (lod.clusters[lod.roots[i]].parent_group != kClusterNone) return Result::BadStructure;
    }
    return Result::Ok;
}

size_t clusterCutScratchBytes(const ClusterLodView& lod) {
    return size_t(lod.group_count) * 2 * sizeof(uint32_t);
}

Result selectClusterCut(const ClusterLodView& lod, const ClusterInstance& instance, const float eye[3],
                        const Frustum* frustum, const SelectionParams& params, ClusterCutScratch& scratch,
                        uint32_t* out, uint32_t capacity, ClusterCutStats* stats) {
    return selectClusterCutResident(lod, instance, eye, frustum, params, scratch, nullptr, out, capacity, stats);
}

void clusterResidencyClosure(const ClusterLodView& lod, uint8_t* group_resident) {
    // A group's outputs are inputs of their parent groups; if one of those is not resident the walk
    // may not reach every output, so the group is not resident either. Parents lie above their
    // children, so a pass per level settles it; the bound only guards a hostile hierarchy.
    for (uint32_t pass = 0; pass <= lod.group_count; ++pass) {
        bool changed = false;
        for (uint32_t c = 0; c < lod.cluster_count; ++c) {
            const ClusterLodCluster& cl = lod.clusters[c];
            if (cl.self_group == kClusterNone || cl.parent_group == kClusterNone) continue;
            if (group_resident[cl.self_group] && !group_resident[cl.parent_group]) {
                group_resident[cl.self_group] = 0;
                changed = true;
            }
        }
        if (!changed) return;
    }
}

Result selectClusterCutResident(const ClusterLodView& lod, const ClusterInstance& instance, const float eye[3],
                                const Frustum* frustum, const SelectionParams& params, ClusterCutScratch& scratch,
                                ClusterResidency* residency, uint32_t* out, uint32_t capacity,
                                ClusterCutStats* stats) {
    if (residency && (!residency->group_resident || (residency->missing_capacity > 0 && !residency->missing)))
        return Result::InvalidArgument;
    if (residency) residency->missing_count = 0;
    const float k = pixelsPerUnitAtDistanceOne(params);
    const float threshold = params.pixel_threshold == 0 ? 1.0f : params.pixel_threshold;
    const size_t need = clusterCutScratchBytes(lod);
    if (!eye || k <= 0 || !(instance.scale > 0) || !std::isfinite(instance.scale) || scratch.size_bytes < need ||
        (need > 0 && !scratch.memory) || (capacity > 0 && !out))
        return Result::InvalidArgument;
    // Stamps from earlier cuts are below the new epoch; when the counter wraps they are cleared once.
    uint32_t* stamps = static_cast<uint32_t*>(scratch.memory);
    if (++scratch.epoch == 0) {
        if (need > 0) std::memset(stamps, 0, size_t(lod.group_count) * sizeof(uint32_t));
        scratch.epoch = 1;
    }
    Frustum model_frustum;
    if (frustum) model_frustum = modelFrustum(*frustum, instance);
    Walk walk{lod,
              frustum ? &model_frustum : nullptr,
              {(eye[0] - instance.translation[0]) / instance.scale, (eye[1] - instance.translation[1]) / instance.scale,
               (eye[2] - instance.translation[2]) / instance.scale},
              k / (threshold * std::exp2(params.lod_bias)),
              stamps,
              stamps + lod.group_count,
              0,
              scratch.epoch,
              out,
              capacity,
              {},
              residency};
    walk.run();
    if (stats) *stats = walk.stats;
    return Result::Ok;
}

} // namespace lodrt
