// Level selection by screen-space error or distance bands, with a hysteresis band (see
// lodrt/selection.h). The per-instance rule is a clamp: with `accept` the coarsest level whose
// error is within the threshold and `coarsen` the coarsest level whose switch distance is passed by
// the band, the new level is clamp(current, coarsen, accept). Both counts are branch-free sums over
// a fixed kMaxLevels thresholds padded with +inf.

#include "lodrt/selection.h"

#include <cassert>
#include <cmath>

#include "memory.h"

namespace lodrt {

namespace {

constexpr float kDefaultFov = 1.04719755f; // 60 degrees
constexpr float kDefaultViewport = 1080.0f;
constexpr float kDefaultHysteresis = 0.1f;

struct Resolved {
    float k = 0;
    float threshold = 1;
    float hysteresis = kDefaultHysteresis;
    float bias_scale = 1; // thresholds are multiplied by 2^-bias
    float fade = 0;
};

bool resolve(const SelectionParams& p, Resolved* out) {
    const float fov = p.vertical_fov == 0 ? kDefaultFov : p.vertical_fov;
    const float viewport = p.viewport_height == 0 ? kDefaultViewport : p.viewport_height;
    const float threshold = p.pixel_threshold == 0 ? 1.0f : p.pixel_threshold;
    if (!(fov > 0 && fov < 3.14159265f) || !(viewport > 0) || !std::isfinite(viewport) || !(threshold > 0) ||
        !std::isfinite(threshold) || !std::isfinite(p.hysteresis) || !std::isfinite(p.lod_bias) ||
        !(p.cross_fade >= 0 && p.cross_fade < 1) || p.lod_bias > 64 || p.lod_bias < -64)
        return false;
    out->k = viewport / (2.0f * std::tan(0.5f * fov));
    out->threshold = threshold;
    out->hysteresis = p.hysteresis == 0 ? kDefaultHysteresis : (p.hysteresis < 0 ? 0.0f : p.hysteresis);
    out->bias_scale = std::exp2(-p.lod_bias);
    out->fade = p.cross_fade;
    return true;
}

// The switch policy, as the baker computes it in double (baker/include/lodbake/core/lod_policy.h,
// same names; LodPolicyAgreementTest holds the two to the same numbers). A level of error e is
// acceptable from its switch distance on, where e projects to the pixel threshold p:
// d = e · H / (2 · p · tan(fov / 2)) = e · k / p, with k = H / (2 tan(fov / 2)) resolved once
// (Resolved::k).
inline float switchDistance(float error, float k, float pixel_threshold) {
    return error * k / pixel_threshold;
}

// The far edge of the hysteresis band around a switch distance d (the baker's hysteresisBand):
// the level is taken only beyond d (1 + h).
inline float hysteresisFar(float switch_distance, float hysteresis) {
    return switch_distance * (1 + hysteresis);
}

inline uint8_t clampLevel(uint8_t current, uint32_t lo, uint32_t hi) {
    uint32_t c = current == kNoLevel ? hi : current;
    c = c < lo ? lo : c;
    c = c > hi ? hi : c;
    return uint8_t(c);
}

inline float fadeFactor(const float* coarsen, uint32_t level, uint32_t level_count, float distance, float width) {
    if (width <= 0 || level + 1 >= level_count) return 0;
    const float up = coarsen[level + 1];
    if (!std::isfinite(up) || up <= 0) return 0;
    const float t = (distance - up * (1 - width)) / (up * width);
    return t < 0 ? 0 : (t > 1 ? 1 : t);
}

} // namespace

float pixelsPerUnitAtDistanceOne(const SelectionParams& params) {
    Resolved r;
    return resolve(params, &r) ? r.k : 0.0f;
}

// ---- LodTable ----

LodTable::~LodTable() {
    release();
}

LodTable::LodTable(LodTable&& other) noexcept {
    *this = static_cast<LodTable&&>(other);
}

LodTable& LodTable::operator=(LodTable&& other) noexcept {
    if (this == &other) return *this;
    release();
    allocator_ = other.allocator_;
    accept_ = other.accept_;
    coarsen_ = other.coarsen_;
    level_counts_ = other.level_counts_;
    finest_ = other.finest_;
    model_count_ = other.model_count_;
    fade_ = other.fade_;
    other.accept_ = other.coarsen_ = nullptr;
    other.level_counts_ = other.finest_ = nullptr;
    other.model_count_ = 0;
    return *this;
}

void LodTable::release() {
    detail::deallocateBytes(allocator_, accept_);
    detail::deallocateBytes(allocator_, coarsen_);
    detail::deallocateBytes(allocator_, level_counts_);
    detail::deallocateBytes(allocator_, finest_);
    accept_ = coarsen_ = nullptr;
    level_counts_ = finest_ = nullptr;
    model_count_ = 0;
}

Result LodTable::prepare(const ModelSet& models, const SelectionParams& params, const Allocator* allocator) {
    release();
    allocator_ = allocator ? *allocator : Allocator();
    Resolved check;
    if (!resolve(params, &check)) return Result::InvalidArgument;
    const size_t n = size_t(models.modelCount());
    accept_ = detail::allocateArray<float>(allocator_, n * kMaxLevels);
    coarsen_ = detail::allocateArray<float>(allocator_, n * kMaxLevels);
    level_counts_ = detail::allocateArray<uint8_t>(allocator_, n);
    finest_ = detail::allocateArray<uint8_t>(allocator_, n);
    if (!accept_ || !coarsen_ || !level_counts_ || !finest_) {
        release();
        return Result::OutOfMemory;
    }
    model_count_ = uint32_t(n);
    return update(models, params);
}

Result LodTable::update(const ModelSet& models, const SelectionParams& params) {
    Resolved r;
    if (!resolve(params, &r)) return Result::InvalidArgument;
    if (models.modelCount() != model_count_) return Result::InvalidArgument;
    fade_ = r.fade;
    for (uint32_t m = 0; m < model_count_; ++m) {
        const ModelInfo& model = models.model(m);
        float* accept = accept_ + size_t(m) * kMaxLevels;
        float* coarsen = coarsen_ + size_t(m) * kMaxLevels;
        level_counts_[m] = uint8_t(model.level_count);
        finest_[m] = uint8_t(params.finest_level < model.level_count ? params.finest_level : model.level_count - 1);
        for (uint32_t l = 0; l < kMaxLevels; ++l) {
            float a = INFINITY, c = INFINITY;
            if (l == 0) {
                a = c = 0;
            } else if (l < model.level_count) {
                const LevelInfo& level = models.modelLevel(m, l);
                if (params.mode == SelectionMode::DistanceBands) {
                    a = level.band_near;
                    c = level.band_far;
                } else {
                    a = switchDistance(level.hausdorff_error, r.k, r.threshold);
                    c = hysteresisFar(a, r.hysteresis);
                }
                a *= r.bias_scale;
                c *= r.bias_scale;
                if (!std::isfinite(a)) a = INFINITY;
                if (!std::isfinite(c)) c = INFINITY;
            }
            accept[l] = a;
            coarsen[l] = c;
        }
    }
    return Result::Ok;
}

struct SelectionKernel {
    static uint8_t one(const LodTable& t, uint32_t m, float d, uint8_t current, float* fade) {
        const float* accept = t.accept_ + size_t(m) * kMaxLevels;
        const float* coarsen = t.coarsen_ + size_t(m) * kMaxLevels;
        uint32_t hi = 0, lo = 0;
        for (uint32_t l = 1; l < kMaxLevels; ++l) {
            hi += d >= accept[l];
            lo += d >= coarsen[l];
        }
        uint8_t level = clampLevel(current, lo, hi);
        if (level < t.finest_[m]) level = t.finest_[m];
        if (fade) *fade = fadeFactor(coarsen, level, t.level_counts_[m], d, t.fade_);
        return level;
    }
    static size_t batch(const LodTable& table, const float eye[3], const InstanceArrays& in,
                        const Containment* visibility, const uint8_t* resident, const SelectionOutput& out) {
        assert(in.count == 0 || (in.center_x && in.center_y && in.center_z && in.radius && in.model && out.level));
        const float ex = eye[0], ey = eye[1], ez = eye[2];
        const float* accept_all = table.accept_;
        const float* coarsen_all = table.coarsen_;
        const uint8_t* finest = table.finest_;
        size_t visible = 0;
        // Blocks: first gather the visible indices without branches (visibility is random from the
        // predictor's point of view), then select over the dense list.
        constexpr size_t kBlock = 256;
        uint32_t list[kBlock];
        for (size_t base = 0; base < in.count; base += kBlock) {
            const size_t end = in.count - base < kBlock ? in.count : base + kBlock;
            size_t n = 0;
            if (visibility) {
                for (size_t i = base; i < end; ++i) {
                    list[n] = uint32_t(i - base);
                    n += visibility[i] != Containment::Outside;
                }
                if (out.draw_level)
                    for (size_t i = base; i < end; ++i) out.draw_level[i] = kNoLevel;
            } else {
                for (size_t i = base; i < end; ++i) list[n++] = uint32_t(i - base);
            }
            visible += n;
            for (size_t k = 0; k < n; ++k) {
                const size_t i = base + list[k];
                const uint32_t m = in.model[i];
                assert(m < table.modelCount());
                const float dx = in.center_x[i] - ex, dy = in.center_y[i] - ey, dz = in.center_z[i] - ez;
                float d = std::sqrt(dx * dx + dy * dy + dz * dz) - in.radius[i];
                d = d > 0 ? d : 0;
                if (in.scale) d /= in.scale[i];
                const float* accept = accept_all + size_t(m) * kMaxLevels;
                const float* coarsen = coarsen_all + size_t(m) * kMaxLevels;
                uint32_t hi = 0, lo = 0;
                for (uint32_t l = 1; l < kMaxLevels; ++l) {
                    hi += d >= accept[l];
                    lo += d >= coarsen[l];
                }
                uint8_t level = clampLevel(out.level[i], lo, hi);
                level = level < finest[m] ? finest[m] : level;
                out.level[i] = level;
                if (out.draw_level) out.draw_level[i] = resident ? resident[size_t(m) * kMaxLevels + level] : level;
                if (out.fade) out.fade[i] = fadeFactor(coarsen, level, table.level_counts_[m], d, table.fade_);
            }
        }
        return visible;
    }
};

size_t selectLevels(const LodTable& table, const float eye[3], const InstanceArrays& in, const Containment* visibility,
                    const uint8_t* resident, const SelectionOutput& out) {
    return SelectionKernel::batch(table, eye, in, visibility, resident, out);
}

uint8_t selectLevel(const LodTable& table, uint32_t model, float distance, uint8_t current, float* fade) {
    assert(model < table.modelCount());
    if (!(distance >= 0)) distance = 0;
    return SelectionKernel::one(table, model, distance, current, fade);
}

void accumulateDemand(const LodTable& table, const SelectionParams& params, const float eye[3],
                      const InstanceArrays& in, const Containment* visibility, const uint8_t* level,
                      ModelDemand* demand) {
    const float k = pixelsPerUnitAtDistanceOne(params);
    for (uint32_t m = 0; m < table.modelCount(); ++m) demand[m] = ModelDemand();
    for (size_t i = 0; i < in.count; ++i) {
        if (visibility && visibility[i] == Containment::Outside) continue;
        const uint32_t m = in.model[i];
        const float dx = in.center_x[i] - eye[0], dy = in.center_y[i] - eye[1], dz = in.center_z[i] - eye[2];
        const float center_distance = std::sqrt(dx * dx + dy * dy + dz * dz);
        const float r = in.radius[i];
        const float surface_distance = center_distance > r ? center_distance - r : 0;
        const float screen_px = 2 * r * k / (center_distance > r ? center_distance : (r > 0 ? r : 1));
        const float priority = screen_px / (1 + surface_distance);
        ModelDemand& d = demand[m];
        if (level[i] < d.wanted_level) d.wanted_level = level[i];
        if (priority > d.priority) d.priority = priority;
    }
}

} // namespace lodrt
