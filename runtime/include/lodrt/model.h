#pragma once
// Model layer (document 000's Model: N discrete levels plus a bounding box and a bounding sphere,
// shared by every instance that references it). Built from a validated Pack: one model per
// MSFT_lod chain (the chain's root node and its `ids`, finest first) and one single-level model per
// other node with a mesh. Per level: the mesh, its triangle and vertex counts, the errors the baker
// measured (LODBAKE_lod_metrics), switch distances and hysteresis band, and the byte range of the
// BIN chunk holding the level's buffer views (what the streamer fetches).
//
// Everything read from the JSON is validated again here (the pack is hostile): ids in range, no
// node in two chains, no chain nested in another (which also rules out cyclic ids), finite
// non-negative metrics that do not decrease from level to level, POSITION min/max present and finite.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "lodrt/allocator.h"
#include "lodrt/export.h"
#include "lodrt/pack.h"
#include "lodrt/result.h"

namespace lodrt {

/// Most levels one model may have (LOD0 included). Fixed so per-frame tables need no allocation.
constexpr uint32_t kMaxLevels = 8;
/// "No level" in level outputs.
constexpr uint8_t kNoLevel = 0xFF;

/// Where a level's errors came from.
enum class ErrorSource : uint8_t {
    Measured,       // LODBAKE_lod_metrics hausdorffError
    ScreenCoverage, // derived from extras.MSFT_screencoverage at a 1080 px, 60 degree reference view
    Unknown,        // neither present: the level is never chosen by screen-space error
};

struct LevelInfo {
    uint32_t node = kNoIndex;
    uint32_t mesh = kNoIndex;
    uint64_t triangle_count = 0; // sum over the mesh's triangle primitives
    uint64_t vertex_count = 0;   // sum over the mesh's primitives
    float hausdorff_error = 0;   // object units; +inf when ErrorSource::Unknown (levels > 0)
    float mean_error = 0;        // object units; 0 when not measured
    float switch_distance = 0;   // baked distance from which the level is acceptable (object units)
    float band_near = 0;         // hysteresis band: back to the finer level below band_near ...
    float band_far = 0;          // ... switch to this level beyond band_far
    uint64_t data_offset = 0;    // byte range of the BIN chunk covering every buffer view the level uses
    uint64_t data_size = 0;      // 0 when the level's data is not in the GLB BIN chunk
    /// World transform of the level's node (glTF: local TRS or matrix composed through every
    /// parent), column-major 4x4 affine, world = world_transform * object. Identity without one.
    float world_transform[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
};

struct ModelInfo {
    std::string_view name; // the root node's name (or empty)
    uint32_t root_node = kNoIndex;
    uint32_t first_level = 0; // into ModelSet::level()
    uint32_t level_count = 0; // 1 .. kMaxLevels; level 0 is the finest
    ErrorSource error_source = ErrorSource::Unknown;
    /// LODBAKE_lod_metrics inputTriangles: the input's triangles when the chain may start below the
    /// input (an out-of-core bake, level 0 a cut of the cluster hierarchy); 0 when absent.
    uint64_t input_triangle_count = 0;
    float aabb_min[3] = {0, 0, 0}; // of level 0's POSITION accessors (glTF min/max), object units
    float aabb_max[3] = {0, 0, 0};
    float sphere_center[3] = {0, 0, 0}; // bounding sphere around the box
    float sphere_radius = 0;
    /// Level 0's node placement (LevelInfo::world_transform of level 0) and what it does to the
    /// bounds: the sphere centre transformed, the radius times the largest axis scale (so a
    /// non-uniform scale never shrinks the sphere below the scaled mesh).
    float world_transform[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    float max_axis_scale = 1; // maxAxisScale(world_transform)
    float world_sphere_center[3] = {0, 0, 0};
    float world_sphere_radius = 0;
};

/// Largest factor by which the affine column-major transform m stretches a length: the largest
/// column norm of its upper 3x3 (exact for rotation times non-uniform scale, the glTF TRS case).
LODRT_API float maxAxisScale(const float m[16]);
/// out = a * b (column-major 4x4; out may alias neither input).
LODRT_API void multiplyTransforms(const float a[16], const float b[16], float out[16]);
/// Sphere (center, radius) of object space placed by m: centre transformed, radius * maxAxisScale(m).
/// Use it for InstanceArrays (radius) with maxAxisScale(m) as the instance's scale: screen-space
/// errors grow at most by that factor, so selection stays conservative under non-uniform scale.
LODRT_API void transformSphere(const float m[16], const float center[3], float radius, float out_center[3],
                               float* out_radius);

/// Options; zero-initialised means defaults.
struct ModelOptions {
    Allocator allocator;
};

/// The models of one pack. Move-only; owns its arrays. Names point into the Pack's document, so the
/// Pack must outlive the ModelSet.
class LODRT_API ModelSet {
public:
    ModelSet() = default;
    ~ModelSet();
    ModelSet(ModelSet&& other) noexcept;
    ModelSet& operator=(ModelSet&& other) noexcept;
    ModelSet(const ModelSet&) = delete;
    ModelSet& operator=(const ModelSet&) = delete;

    uint32_t modelCount() const { return model_count_; }
    uint32_t levelCount() const { return level_count_; } // over all models
    /// i below the matching count (asserted).
    const ModelInfo& model(uint32_t i) const;
    const LevelInfo& level(uint32_t i) const;
    /// Level `level` of model `model` (both in range, asserted).
    const LevelInfo& modelLevel(uint32_t model, uint32_t level) const;

private:
    friend struct ModelBuilder;
    void release();
    Allocator allocator_;
    ModelInfo* models_ = nullptr;
    LevelInfo* levels_ = nullptr;
    uint32_t model_count_ = 0;
    uint32_t level_count_ = 0;
};

/// Builds the models of `pack`. On failure *out is empty and error_message (if not null) receives
/// one line "<json pointer>: <what was expected>". Returns Ok; BadGltf (bad MSFT_lod ids, a node in
/// two chains, nested or cyclic chains, more than kMaxLevels levels, a level node without a mesh,
/// metrics that break the LODBAKE_lod_metrics rules, POSITION without min/max, a node with both
/// matrix and TRS, non-finite or malformed transforms, a matrix whose last row is not 0 0 0 1, a
/// rotation that is not a unit quaternion, a cycle in the node hierarchy); OutOfMemory;
/// InvalidArgument when out is null.
LODRT_API Result buildModels(const Pack& pack, const ModelOptions* options, ModelSet* out,
                             char* error_message = nullptr, size_t error_message_size = 0);

} // namespace lodrt
