#pragma once
// The engine-style test scene of document 000: a 5x5 grid of instances of the pack's models, a
// camera that flies in from far away and then low over the grid looking ahead, and per frame:
// cull, select, stream. Shared by the sample program (lod_sample.cpp) and runtime_bench.
// Sample code: it uses std::vector freely at setup; the frame loop itself allocates nothing but
// the level buffers the streamer fetches.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "lodrt/lodrt.h"

namespace lodrt_sample {

struct SceneConfig {
    int grid = 5;                    // grid x grid instances
    int frames = 300;                // camera path length
    float pixel_threshold = 1;       // screen-space error bound
    float viewport_height = 1080;    // pixels
    float vertical_fov = 1.0471976f; // 60 degrees
    float hysteresis = 0.1f;
    uint64_t budget_bytes = 0; // streamer budget (0 = unlimited)
    bool print_frames = true;
};

struct SceneSummary {
    uint64_t triangles_lod = 0;  // submitted over all frames, with LOD (drawn levels)
    uint64_t triangles_lod0 = 0; // the same visible instances, always level 0
    uint64_t visible = 0, culled = 0;
    float max_sse_selected_px = 0; // worst projected error of the selected levels
    float max_sse_drawn_px = 0;    // of the drawn levels (coarser while a level streams in)
    uint32_t fallback_draws = 0;   // instance-frames drawn coarser than selected (streaming lag)
    uint32_t max_flips = 0;        // most level changes of one instance over the path
    uint32_t max_reversals = 0;    // most changes of one instance that undo its previous change
    uint64_t streamed_bytes = 0;
    uint64_t peak_resident_bytes = 0;
    int first_drawable_frame = -1; // first frame at which every model had a drawable level
};

// ---- small camera math (column-major, right-handed, looking down -z in view space) ----

inline void mul4(const float a[16], const float b[16], float out[16]) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) {
            float s = 0;
            for (int k = 0; k < 4; ++k) s += a[k * 4 + r] * b[c * 4 + k];
            out[c * 4 + r] = s;
        }
}

inline void lookAt(const float eye[3], const float target[3], float out[16]) {
    float f[3] = {target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]};
    float fl = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    for (float& v : f) v /= fl;
    const float up[3] = {0, 1, 0};
    float s[3] = {f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0]};
    const float sl = std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    for (float& v : s) v /= sl;
    const float u[3] = {s[1] * f[2] - s[2] * f[1], s[2] * f[0] - s[0] * f[2], s[0] * f[1] - s[1] * f[0]};
    const float m[16] = {s[0],
                         u[0],
                         -f[0],
                         0,
                         s[1],
                         u[1],
                         -f[1],
                         0,
                         s[2],
                         u[2],
                         -f[2],
                         0,
                         -(s[0] * eye[0] + s[1] * eye[1] + s[2] * eye[2]),
                         -(u[0] * eye[0] + u[1] * eye[1] + u[2] * eye[2]),
                         f[0] * eye[0] + f[1] * eye[1] + f[2] * eye[2],
                         1};
    for (int i = 0; i < 16; ++i) out[i] = m[i];
}

// Vulkan / D3D depth (0..1).
inline void perspectiveZeroToOne(float fov, float aspect, float n, float f, float out[16]) {
    const float t = 1.0f / std::tan(0.5f * fov);
    for (int i = 0; i < 16; ++i) out[i] = 0;
    out[0] = t / aspect;
    out[5] = t;
    out[10] = f / (n - f);
    out[11] = -1;
    out[14] = f * n / (n - f);
}

/// The scene: instances of every model of `source` in a grid, and the per-frame pipeline.
class Scene {
public:
    Scene(const lodrt::PackSource& source, const SceneConfig& config) : source_(source), config_(config) {}

    lodrt::Result init(const lodrt::JobSystem* jobs) {
        const lodrt::ModelSet& models = source_.models();
        if (models.modelCount() == 0) return lodrt::Result::BadGltf;
        float max_radius = 0;
        for (uint32_t m = 0; m < models.modelCount(); ++m)
            max_radius = std::fmax(max_radius, models.model(m).sphere_radius);
        radius_ = max_radius > 0 ? max_radius : 1;
        // Spacing of four bounding radii, as the document's grid at multiples of 4.
        spacing_ = 4 * radius_;
        const int n = config_.grid;
        for (int gz = 0; gz < n; ++gz)
            for (int gx = 0; gx < n; ++gx) {
                const uint32_t m = uint32_t((gz * n + gx) % int(models.modelCount()));
                const lodrt::ModelInfo& info = models.model(m);
                const float t[3] = {(gx - (n - 1) * 0.5f) * spacing_, 0, (gz - (n - 1) * 0.5f) * spacing_};
                x_.push_back(t[0] + info.sphere_center[0]);
                y_.push_back(t[1] + info.sphere_center[1]);
                z_.push_back(t[2] + info.sphere_center[2]);
                r_.push_back(info.sphere_radius);
                model_.push_back(m);
            }
        const size_t count = x_.size();
        level_.assign(count, lodrt::kNoLevel);
        draw_.assign(count, lodrt::kNoLevel);
        prev_level_.assign(count, lodrt::kNoLevel);
        last_change_.assign(count, 0);
        flips_.assign(count, 0);
        reversals_.assign(count, 0);
        visibility_.assign(count, lodrt::Containment::Outside);
        demand_.assign(models.modelCount(), lodrt::ModelDemand());
        params_.pixel_threshold = config_.pixel_threshold;
        params_.viewport_height = config_.viewport_height;
        params_.vertical_fov = config_.vertical_fov;
        params_.hysteresis = config_.hysteresis;
        k_ = lodrt::pixelsPerUnitAtDistanceOne(params_);
        lodrt::Result r = table_.prepare(models, params_, nullptr);
        if (r != lodrt::Result::Ok) return r;
        lodrt::StreamerOptions options;
        options.budget_bytes = config_.budget_bytes;
        return streamer_.init(&source_, jobs, &options);
    }

    /// Camera at frame f: from 400 radii away straight in to 3 grid spacings before the grid, then
    /// low over the grid and out the far side, always looking ahead and slightly down.
    void camera(int f, float eye[3], float target[3]) const {
        const float t = float(f) / float(config_.frames - 1);
        const float half = 0.5f * float(config_.grid - 1) * spacing_;
        const float near_z = half + 3 * spacing_;
        if (t < 0.6f) {
            const float u = t / 0.6f;
            const float start = 400 * radius_;
            eye[2] = near_z + (start - near_z) * std::pow(1 - u, 3.0f);
            eye[1] = 1.5f * radius_;
        } else {
            const float u = (t - 0.6f) / 0.4f;
            eye[2] = near_z - u * (near_z + half + 3 * spacing_);
            eye[1] = 1.5f * radius_;
        }
        eye[0] = 0.3f * spacing_;
        target[0] = eye[0];
        target[1] = eye[1] - 0.5f * radius_;
        target[2] = eye[2] - 4 * radius_;
    }

    /// One frame: cull, select, demand, stream. Returns false on a lodrt error.
    bool frame(int f, SceneSummary* summary, std::FILE* out) {
        const lodrt::ModelSet& models = source_.models();
        float eye[3], target[3], view[16], proj[16], view_proj[16];
        camera(f, eye, target);
        lookAt(eye, target, view);
        perspectiveZeroToOne(config_.vertical_fov, 16.0f / 9.0f, 0.01f * radius_, 4000 * radius_, proj);
        mul4(proj, view, view_proj);
        lodrt::Frustum frustum;
        if (!lodrt::extractFrustum(view_proj, lodrt::ClipDepth::ZeroToOne, &frustum)) return false;
        const size_t count = x_.size();
        const size_t visible =
            lodrt::classifySpheres(frustum, x_.data(), y_.data(), z_.data(), r_.data(), count, visibility_.data());
        lodrt::InstanceArrays in{x_.data(), y_.data(), z_.data(), r_.data(), nullptr, model_.data(), count};
        lodrt::SelectionOutput sel{level_.data(), draw_.data(), nullptr};
        lodrt::selectLevels(table_, eye, in, visibility_.data(), streamer_.residentTable(), sel);
        lodrt::accumulateDemand(table_, params_, eye, in, visibility_.data(), level_.data(), demand_.data());
        const uint64_t streamed_before = streamer_.stats().streamed_bytes;
        streamer_.update(demand_.data());

        uint32_t histogram[lodrt::kMaxLevels + 1] = {};
        uint64_t tris = 0, tris0 = 0;
        for (size_t i = 0; i < count; ++i) {
            if (level_[i] != prev_level_[i] && prev_level_[i] != lodrt::kNoLevel) {
                ++flips_[i];
                if (level_[i] == last_change_[i]) ++reversals_[i]; // went back to where it came from
                last_change_[i] = prev_level_[i];
                summary->max_flips = std::max(summary->max_flips, flips_[i]);
                summary->max_reversals = std::max(summary->max_reversals, reversals_[i]);
            }
            prev_level_[i] = level_[i];
            if (visibility_[i] == lodrt::Containment::Outside) continue;
            const uint32_t m = model_[i];
            tris0 += models.modelLevel(m, 0).triangle_count;
            const float dx = x_[i] - eye[0], dy = y_[i] - eye[1], dz = z_[i] - eye[2];
            const float d = std::fmax(std::sqrt(dx * dx + dy * dy + dz * dz) - r_[i], 1e-6f);
            summary->max_sse_selected_px =
                std::fmax(summary->max_sse_selected_px, models.modelLevel(m, level_[i]).hausdorff_error * k_ / d);
            if (draw_[i] == lodrt::kNoLevel) {
                ++histogram[lodrt::kMaxLevels]; // nothing resident yet
                continue;
            }
            ++histogram[draw_[i]];
            if (draw_[i] != level_[i]) ++summary->fallback_draws;
            summary->max_sse_drawn_px =
                std::fmax(summary->max_sse_drawn_px, models.modelLevel(m, draw_[i]).hausdorff_error * k_ / d);
            tris += models.modelLevel(m, draw_[i]).triangle_count;
        }
        bool all_drawable = true;
        for (uint32_t m = 0; m < models.modelCount(); ++m)
            all_drawable = all_drawable && streamer_.residentTable()[m * lodrt::kMaxLevels] != lodrt::kNoLevel;
        if (all_drawable && summary->first_drawable_frame < 0) summary->first_drawable_frame = f;
        const lodrt::StreamStats stats = streamer_.stats();
        summary->triangles_lod += tris;
        summary->triangles_lod0 += tris0;
        summary->visible += visible;
        summary->culled += count - visible;
        summary->streamed_bytes = stats.streamed_bytes;
        summary->peak_resident_bytes = std::max(summary->peak_resident_bytes, stats.resident_bytes);
        if (out && config_.print_frames) {
            std::fprintf(out, "frame %3d eye %7.3f %6.3f %7.3f visible %2zu culled %2zu levels [", f, eye[0], eye[1],
                         eye[2], visible, count - visible);
            for (uint32_t l = 0; l < lodrt::kMaxLevels; ++l) {
                bool used = false;
                for (uint32_t m = 0; m < models.modelCount(); ++m) used = used || l < models.model(m).level_count;
                if (used) std::fprintf(out, "%s%u", l ? " " : "", histogram[l]);
            }
            std::fprintf(out, " | none %u] triangles lod %llu lod0 %llu resident %llu B streamed %llu B\n",
                         histogram[lodrt::kMaxLevels], static_cast<unsigned long long>(tris),
                         static_cast<unsigned long long>(tris0), static_cast<unsigned long long>(stats.resident_bytes),
                         static_cast<unsigned long long>(stats.streamed_bytes - streamed_before));
        }
        return true;
    }

    lodrt::Streamer& streamer() { return streamer_; }
    size_t instanceCount() const { return x_.size(); }

private:
    const lodrt::PackSource& source_;
    SceneConfig config_;
    float radius_ = 1, spacing_ = 4, k_ = 0;
    std::vector<float> x_, y_, z_, r_;
    std::vector<uint32_t> model_;
    std::vector<uint8_t> level_, draw_, prev_level_, last_change_;
    std::vector<uint32_t> flips_, reversals_;
    std::vector<lodrt::Containment> visibility_;
    std::vector<lodrt::ModelDemand> demand_;
    lodrt::SelectionParams params_;
    lodrt::LodTable table_;
    lodrt::Streamer streamer_;
};

} // namespace lodrt_sample
