#pragma once
// Level selection (document 000: level by distance; document 003: range-based and projected-area
// criteria, blend switching). Two modes:
// - ScreenSpaceError (default): a level l is acceptable at distance d when its measured error e_l
//   projects to at most pixel_threshold pixels: e_l * K / d <= pixel_threshold, with
//   K = viewport_height / (2 tan(vertical_fov / 2)). So l is acceptable beyond s_l = e_l K / p.
// - DistanceBands: the baked switch distances and hysteresis bands (LODBAKE_lod_metrics).
// Hysteresis: with current level c, the instance moves to a coarser level l only beyond s_l (1 + h)
// and back to a finer one as soon as c is no longer acceptable (below s_c). The screen-space error
// never exceeds the threshold, and a camera that stops inside a band never makes the level flicker.
// The only state is the instance's current level (one byte), passed in and out.
//
// d is the distance from the eye to the instance's bounding sphere (0 inside it), divided by the
// instance's uniform scale (errors are in model units), multiplied by 2^lod_bias.

#include <cstddef>
#include <cstdint>

#include "lodrt/allocator.h"
#include "lodrt/export.h"
#include "lodrt/frustum.h"
#include "lodrt/model.h"
#include "lodrt/result.h"

namespace lodrt {

enum class SelectionMode : uint8_t { ScreenSpaceError = 0, DistanceBands = 1 };

/// Zero-initialised means defaults.
struct SelectionParams {
    SelectionMode mode = SelectionMode::ScreenSpaceError;
    float pixel_threshold = 0; // screen-space error allowed, pixels; 0 means 1
    float vertical_fov = 0;    // radians; 0 means 60 degrees
    float viewport_height = 0; // pixels; 0 means 1080
    float hysteresis = 0;      // band h as a fraction of the switch distance; 0 means 0.1, < 0 means none
    float lod_bias = 0;        // log2 scale of distances: +1 selects as if twice as far (coarser)
    uint32_t finest_level = 0; // finest level allowed (Unity's maximumLODLevel); clamped per model
    float cross_fade = 0;      // width of the fade zone before a coarsening switch, fraction of its
                               // distance, in [0, 1); 0 disables fade output
};

/// K = viewport_height / (2 tan(vertical_fov / 2)) of the resolved params: pixels per unit of size
/// at distance 1.
LODRT_API float pixelsPerUnitAtDistanceOne(const SelectionParams& params);

/// Per-model switch thresholds prepared from a ModelSet and SelectionParams, in a flat layout the
/// per-instance loop reads with one index (model * kMaxLevels + level). Prepare once when the models
/// or the params change; per frame it is read only.
class LODRT_API LodTable {
public:
    LodTable() = default;
    ~LodTable();
    LodTable(LodTable&& other) noexcept;
    LodTable& operator=(LodTable&& other) noexcept;
    LodTable(const LodTable&) = delete;
    LodTable& operator=(const LodTable&) = delete;

    /// Allocates for models.modelCount() models and fills the thresholds. Returns Ok, OutOfMemory,
    /// or InvalidArgument for params out of range (negative threshold, fov outside (0, pi), negative
    /// viewport, cross_fade outside [0, 1), non-finite values).
    Result prepare(const ModelSet& models, const SelectionParams& params, const Allocator* allocator);
    /// Refills the thresholds for new params without allocating (same models). Same results.
    Result update(const ModelSet& models, const SelectionParams& params);

    uint32_t modelCount() const { return model_count_; }
    uint32_t levelCount(uint32_t model) const { return level_counts_[model]; }
    /// Distance (model units, bias applied) from which `level` is acceptable / is switched to.
    float acceptDistance(uint32_t model, uint32_t level) const { return accept_[model * kMaxLevels + level]; }
    float coarsenDistance(uint32_t model, uint32_t level) const { return coarsen_[model * kMaxLevels + level]; }

private:
    friend struct SelectionKernel;
    void release();
    Allocator allocator_;
    float* accept_ = nullptr;  // [model][level]: +inf for missing levels; level 0 is 0
    float* coarsen_ = nullptr; // accept * (1 + h) (SSE) or band_far (bands)
    uint8_t* level_counts_ = nullptr;
    uint8_t* finest_ = nullptr; // finest level allowed per model
    uint32_t model_count_ = 0;
    float fade_ = 0;
};

/// Level of one instance. `current` is its level last frame (kNoLevel when new); `distance` is in
/// model units (already divided by the instance's scale). Returns the new level (the new state).
/// When fade is not null it receives the cross-fade factor towards level + 1 (0 when disabled).
LODRT_API uint8_t selectLevel(const LodTable& table, uint32_t model, float distance, uint8_t current,
                              float* fade = nullptr);

/// Instances in structure-of-arrays form, world space. scale may be null (all 1). Each model index
/// must be below the LodTable's model count (asserted).
struct InstanceArrays {
    const float* center_x = nullptr; // bounding sphere centre
    const float* center_y = nullptr;
    const float* center_z = nullptr;
    const float* radius = nullptr; // bounding sphere radius (world units)
    const float* scale = nullptr;  // uniform scale of the instance (model -> world)
    const uint32_t* model = nullptr;
    size_t count = 0;
};

/// Caller-owned per-instance outputs (each array of InstanceArrays::count entries).
struct SelectionOutput {
    uint8_t* level = nullptr;      // in/out: the hysteresis state (kNoLevel for a new instance)
    uint8_t* draw_level = nullptr; // optional: level to draw given what is resident (kNoLevel: none yet)
    float* fade = nullptr;         // optional: cross-fade factor towards level + 1
};

/// Selects a level for every instance: `visibility` (from classifySpheres / InstanceBvh::cull) may
/// be null to select all; invisible instances keep their level. `resident` (optional, from
/// Streamer::residentTable()) maps model * kMaxLevels + level to the level that can be drawn.
/// Pure; no allocation. Returns the visible count.
LODRT_API size_t selectLevels(const LodTable& table, const float eye[3], const InstanceArrays& instances,
                              const Containment* visibility, const uint8_t* resident, const SelectionOutput& out);

/// What the streamer should fetch for one model: the finest level any visible instance wants and
/// how much it matters (max over instances of projected diameter in pixels / (1 + distance)).
struct ModelDemand {
    uint8_t wanted_level = kNoLevel; // kNoLevel: no visible instance
    float priority = 0;
};

/// Fills demand[0, table.modelCount()) from this frame's selection (resetting it first).
LODRT_API void accumulateDemand(const LodTable& table, const SelectionParams& params, const float eye[3],
                                const InstanceArrays& instances, const Containment* visibility, const uint8_t* level,
                                ModelDemand* demand);

} // namespace lodrt
