#pragma once
// View-frustum culling (document 000, ch. 4.3.5): six planes extracted from the view-projection
// matrix (Gribb & Hartmann, "Fast Extraction of Viewing Frustum Planes from the World-View-Projection
// Matrix", 2001), bounding sphere and box tests with INSIDE / INTERSECTING / OUTSIDE, a batch form
// over structure-of-arrays instance data, and an optional bounding volume hierarchy over instances
// so whole groups are accepted or rejected with one test. Pure functions: no allocation except in
// InstanceBvh::build, callable from any thread.

#include <cstddef>
#include <cstdint>

#include "lodrt/allocator.h"
#include "lodrt/export.h"
#include "lodrt/result.h"

namespace lodrt {

/// Depth range of clip space after the projection.
enum class ClipDepth : uint8_t {
    NegativeOneToOne, // OpenGL: -w <= z <= w
    ZeroToOne,        // Vulkan, Direct3D, Metal: 0 <= z <= w
};

enum class Containment : uint8_t { Outside = 0, Intersecting = 1, Inside = 2 };

/// Planes a x + b y + c z + d >= 0 inside, (a, b, c) unit length, in the order
/// left, right, bottom, top, near, far.
struct Frustum {
    float planes[6][4] = {};
};

/// Extracts the frustum of `view_proj` (16 floats, column-major as in OpenGL / glm: clip = M * v with
/// M[col * 4 + row]). A row-major matrix used with row vectors (DirectXMath, v * M) has the same
/// memory layout and can be passed as is. Planes are in the space the matrix maps from (world space
/// for a view-projection matrix). Returns false (and leaves *out unchanged) when a plane is
/// degenerate (zero normal, or not finite), e.g. for a zero matrix.
LODRT_API bool extractFrustum(const float view_proj[16], ClipDepth depth, Frustum* out);

/// Sphere (center, radius >= 0) against the frustum.
LODRT_API Containment classifySphere(const Frustum& frustum, const float center[3], float radius);
/// Axis-aligned box [min, max] against the frustum. Conservative like every plane test: a box near a
/// frustum corner, outside but not behind a single plane, is reported Intersecting.
LODRT_API Containment classifyBox(const Frustum& frustum, const float box_min[3], const float box_max[3]);

/// Spheres in structure-of-arrays form: center_x[i], center_y[i], center_z[i], radius[i].
/// Writes a Containment per sphere to out[0, count). Returns how many are not Outside. Loops are
/// written so the compiler vectorises them; no allocation.
LODRT_API size_t classifySpheres(const Frustum& frustum, const float* center_x, const float* center_y,
                                 const float* center_z, const float* radius, size_t count, Containment* out);
/// Boxes in structure-of-arrays form (min_x[i] .. max_z[i]); same contract as classifySpheres.
LODRT_API size_t classifyBoxes(const Frustum& frustum, const float* min_x, const float* min_y, const float* min_z,
                               const float* max_x, const float* max_y, const float* max_z, size_t count,
                               Containment* out);

/// A bounding volume hierarchy over instance spheres: instances are ordered along a Morton curve,
/// cut into leaves of up to kBvhLeafSize, and leaves are paired bottom-up into a binary tree of
/// boxes. Culling walks it with a fixed-size stack: an Outside node marks its whole range Outside, an
/// Inside node its whole range Inside, without testing the instances. Rebuild when instances move.
class LODRT_API InstanceBvh {
public:
    static constexpr uint32_t kLeafSize = 32;

    InstanceBvh() = default;
    ~InstanceBvh();
    InstanceBvh(InstanceBvh&& other) noexcept;
    InstanceBvh& operator=(InstanceBvh&& other) noexcept;
    InstanceBvh(const InstanceBvh&) = delete;
    InstanceBvh& operator=(const InstanceBvh&) = delete;

    /// Builds over count spheres (SoA as in classifySpheres). allocator may be null. Returns Ok,
    /// OutOfMemory, or InvalidArgument (null arrays with count > 0, count >= 2^31, non-finite data).
    Result build(const float* center_x, const float* center_y, const float* center_z, const float* radius, size_t count,
                 const Allocator* allocator);

    /// Culls the spheres the hierarchy was built over (it keeps a copy in Morton order, so leaves
    /// are tested with the vectorised classifySpheres) and writes one Containment per instance, in
    /// the caller's original order, to out[0, instanceCount()). Returns how many are not Outside.
    /// No allocation.
    size_t cull(const Frustum& frustum, Containment* out) const;

    size_t instanceCount() const { return count_; }
    uint32_t nodeCount() const { return node_count_; }

private:
    struct Node {
        float min[3];
        float max[3];
        uint32_t first; // leaves: first position in order_; internal: left child index
        uint32_t count; // leaves: instances; internal: 0 (right child = first + 1)
    };
    void release();
    Allocator allocator_;
    Node* nodes_ = nullptr;
    uint32_t* order_ = nullptr; // instance indices in Morton order
    float* spheres_ = nullptr;  // x, y, z, radius blocks of count_ floats each, in Morton order
    uint32_t node_count_ = 0;
    size_t count_ = 0;
};

} // namespace lodrt
