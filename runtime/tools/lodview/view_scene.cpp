#include "view_scene.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>

namespace lodview {

namespace {

using Clock = std::chrono::steady_clock;
// Longest wait for outstanding level reads in a synchronous (benchmark) frame; local reads take
// milliseconds, so reaching it means a read that never completes.
constexpr std::chrono::seconds kStreamWaitLimit{120};

double msSince(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Clay tones per asset, and one colour per level for --colour-by-level (level 0 red ... coarsest
// blue), so a screenshot shows where the selection switched.
constexpr float kAssetColours[][3] = {{0.80f, 0.74f, 0.64f}, {0.70f, 0.76f, 0.80f}, {0.78f, 0.70f, 0.74f},
                                      {0.72f, 0.78f, 0.68f}, {0.82f, 0.78f, 0.58f}, {0.66f, 0.70f, 0.78f}};
constexpr float kLevelColours[lodrt::kMaxLevels][3] = {
    {0.90f, 0.20f, 0.15f}, {0.95f, 0.55f, 0.10f}, {0.95f, 0.85f, 0.15f}, {0.35f, 0.80f, 0.25f},
    {0.15f, 0.75f, 0.80f}, {0.20f, 0.40f, 0.95f}, {0.55f, 0.30f, 0.85f}, {0.85f, 0.35f, 0.75f}};
constexpr float kPfrepColour[3] = {0.85f, 0.85f, 0.85f}; // refined per vertex: no single level

} // namespace

struct View::Pack {
    std::string path;
    int fd = -1;
    uint64_t size = 0;
    lodrt::PackSource source;
    lodrt::LodTable table;
    lodrt::Streamer streamer; // after source: destroyed first
    std::vector<lodrt::ModelDemand> demand;
    std::vector<GpuLevel> gpu;   // model * kMaxLevels + level
    size_t first = 0, count = 0; // its instances
    // Pfrep mode: per model, the decoded positions of the resident prefix on the GPU; per
    // instance (index - first), its mask and index buffer.
    struct PfrepModelGpu {
        uint32_t vbo = 0;
        uint32_t decoded_from = UINT32_MAX; // loaded_from of the prefix the positions came from
        std::vector<float> positions;
        std::vector<uint32_t> scratch;
    };
    struct PfrepInstance {
        std::vector<uint8_t> mask;
        std::vector<uint32_t> indices;
        uint32_t vao = 0, ibo = 0;
        size_t triangles = 0;
        uint32_t loaded_from = UINT32_MAX;
        bool drawable = false;
    };
    std::vector<PfrepModelGpu> pfrep_models;
    std::vector<PfrepInstance> pfrep_instances;
    uint64_t streamed_before = 0;
    uint32_t requests_before = 0;
    uint32_t decodes_before = 0;

    ~Pack() {
        if (fd >= 0) close(fd);
    }
    // pread: no shared file position, so the job thread and the frame thread may read at once.
    static lodrt::Result read(void* user, uint64_t offset, void* dst, size_t size) {
        const Pack* self = static_cast<const Pack*>(user);
        uint8_t* out = static_cast<uint8_t*>(dst);
        while (size > 0) {
            const ssize_t n = pread(self->fd, out, size, off_t(offset));
            if (n < 0 && errno == EINTR) continue;
            if (n <= 0) return lodrt::Result::Truncated;
            out += n;
            offset += uint64_t(n);
            size -= size_t(n);
        }
        return lodrt::Result::Ok;
    }
};

// Memory the streamer takes for a pack's format 3, 4 and 5 PFRep blobs (the format 2 bytes they are
// decoded or laid out into, and the decoder's scratch or the opening's read): more than the pack's
// own bytes, since a format 3 or 4 blob decodes to three to ten times its size. Blobs whose header
// does not read are not counted (the streamer fails those streams anyway).
uint64_t compressedPfrepDecodeBytes(const lodrt::PackSource& source) {
    uint64_t total = 0;
    for (uint32_t m = 0; m < source.models().modelCount(); ++m) {
        uint64_t decoded = 0, scratch = 0;
        if (source.pfrepDecodeMemory(m, &decoded, &scratch) == lodrt::Result::Ok && decoded > 0)
            total += decoded + scratch + 64; // and two blocks of pool headroom
    }
    return total;
}

JobThread::JobThread() : thread_([this] { loop(); }) {}

JobThread::~JobThread() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stop_ = true;
    }
    cv_.notify_all();
    thread_.join();
}

void JobThread::submit(void* user, void (*run)(void*), void* task) {
    JobThread* self = static_cast<JobThread*>(user);
    {
        std::lock_guard<std::mutex> lock(self->mutex_);
        self->queue_.push_back({run, task});
    }
    self->cv_.notify_one();
}

void JobThread::loop() {
    for (;;) {
        std::pair<void (*)(void*), void*> job;
        {
            std::unique_lock<std::mutex> lock(mutex_);
            cv_.wait(lock, [this] { return stop_ || !queue_.empty(); });
            if (queue_.empty()) return;
            job = queue_.front();
            queue_.pop_front();
        }
        job.first(job.second);
    }
}

View::View() = default;

View::~View() {
    drain();
    packs_.clear();
}

bool View::open(const std::vector<std::string>& paths, std::string* error) {
    // Every lodrt allocation goes through this hook, so a frame's allocations can be counted.
    allocator_.user = &allocations_;
    allocator_.allocate = [](void* user, size_t size) -> void* {
        static_cast<std::atomic<uint64_t>*>(user)->fetch_add(1, std::memory_order_relaxed);
        return std::malloc(size);
    };
    allocator_.deallocate = [](void*, void* ptr) { std::free(ptr); };
    jobs_ = lodrt::JobSystem{&JobThread::submit, &jobs_thread_};
    uint64_t total_bytes = 0, decode_bytes = 0;
    for (const std::string& path : paths) {
        std::unique_ptr<Pack> pack(new Pack);
        pack->path = path;
        pack->fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
        struct stat st;
        if (pack->fd < 0 || fstat(pack->fd, &st) != 0 || !S_ISREG(st.st_mode)) {
            *error = path + ": file: expected a readable pack file";
            return false;
        }
        pack->size = uint64_t(st.st_size);
        total_bytes += pack->size;
        lodrt::LoadOptions options;
        options.allocator = allocator_;
        char message[256] = {};
        const lodrt::Result r = pack->source.openReader(lodrt::RangeReader{&Pack::read, pack.get()}, pack->size,
                                                        &options, message, sizeof(message));
        if (r != lodrt::Result::Ok) {
            *error = path + ": " + message + " (" + lodrt::resultName(r) + ")";
            return false;
        }
        if (pack->source.models().modelCount() == 0) {
            *error = path + ": /nodes: expected at least one node with a mesh";
            return false;
        }
        decode_bytes += compressedPfrepDecodeBytes(pack->source);
        packs_.push_back(std::move(pack));
    }
    // Every level and PFRep prefix is a byte range of its file; a growing prefix briefly holds its
    // old and new buffer. Twice the files' bytes holds all of it at once (untouched pages of the
    // arena cost nothing), plus what decoding the format 3 PFRep blobs takes.
    if (!pool_.init(size_t(2 * total_bytes + decode_bytes + (1u << 20)))) {
        *error = "memory: cannot reserve the level pool";
        return false;
    }
    return true;
}

bool View::placeInstances(std::string* error) {
    struct Asset {
        uint32_t pack, model;
    };
    std::vector<Asset> assets;
    for (uint32_t p = 0; p < packs_.size(); ++p)
        for (uint32_t m = 0; m < packs_[p]->source.models().modelCount(); ++m) assets.push_back({p, m});
    const int n = config_.grid;
    const size_t count = size_t(n) * size_t(n);
    for (uint32_t p = 0; p < packs_.size(); ++p) {
        Pack& pack = *packs_[p];
        pack.first = x_.size();
        for (size_t cell = 0; cell < count; ++cell) {
            const Asset& asset = assets[cell % assets.size()];
            if (asset.pack != p) continue;
            const lodrt::ModelInfo& info = pack.source.models().model(asset.model);
            const float s = info.world_sphere_radius > 0 ? 1.0f / info.world_sphere_radius : 1.0f;
            const float gx = float(int(cell) % n) - 0.5f * float(n - 1);
            const float gz = float(int(cell) / n) - 0.5f * float(n - 1);
            // Bounding sphere of radius 1 resting on the ground at the cell's centre.
            const float centre[3] = {gx * config_.spacing, 1.0f, gz * config_.spacing};
            float m[16] = {s, 0, 0, 0, 0, s, 0, 0, 0, 0, s, 0, 0, 0, 0, 1};
            for (int a = 0; a < 3; ++a) m[12 + a] = centre[a] - s * info.world_sphere_center[a];
            placement_.insert(placement_.end(), m, m + 16);
            x_.push_back(centre[0]);
            y_.push_back(centre[1]);
            z_.push_back(centre[2]);
            r_.push_back(s * info.world_sphere_radius);
            scale_.push_back(s * info.max_axis_scale);
            model_.push_back(asset.model);
            asset_.push_back(uint32_t(cell % assets.size()));
        }
        pack.count = x_.size() - pack.first;
    }
    instance_count_ = x_.size();
    level_.assign(instance_count_, lodrt::kNoLevel);
    draw_.assign(instance_count_, lodrt::kNoLevel);
    visibility_.assign(instance_count_, lodrt::Containment::Outside);
    const lodrt::Result r = bvh_.build(x_.data(), y_.data(), z_.data(), r_.data(), instance_count_, &allocator_);
    if (r != lodrt::Result::Ok) {
        *error = std::string("instances: cannot build the bounding volume hierarchy (") + lodrt::resultName(r) + ")";
        return false;
    }
    return true;
}

bool View::init(const ViewConfig& config, std::string* error) {
    config_ = config;
    if (!placeInstances(error)) return false;
    params_.pixel_threshold = config_.pixel_threshold;
    params_.viewport_height = float(config_.height);
    params_.vertical_fov = config_.vertical_fov;
    params_.hysteresis = config_.hysteresis;
    k_ = lodrt::pixelsPerUnitAtDistanceOne(params_);
    for (auto& pack : packs_) {
        const lodrt::ModelSet& models = pack->source.models();
        lodrt::Result r = pack->table.prepare(models, params_, &allocator_);
        if (r == lodrt::Result::Ok) {
            lodrt::StreamerOptions options;
            options.allocator = pool_.allocator();
            options.budget_bytes = config_.budget_bytes;
            r = pack->streamer.init(&pack->source, &jobs_, &options);
        }
        if (r != lodrt::Result::Ok) {
            *error = pack->path + ": cannot prepare selection and streaming (" + lodrt::resultName(r) + ")";
            return false;
        }
        pack->demand.assign(models.modelCount(), lodrt::ModelDemand());
        pack->pfrep_models.resize(models.modelCount());
        pack->pfrep_instances.resize(pack->count);
        pack->gpu.resize(size_t(models.modelCount()) * lodrt::kMaxLevels);
        // The streamer silently never loads a level whose data is not in one byte range of the BIN
        // chunk; a view would then draw nothing, so such a pack is refused here.
        for (uint32_t m = 0; m < models.modelCount(); ++m)
            for (uint32_t l = 0; l < models.model(m).level_count; ++l)
                if (models.modelLevel(m, l).data_size == 0) {
                    *error = pack->path + ": model " + std::to_string(m) + " level " + std::to_string(l) +
                             ": its data is not in a byte range of the BIN chunk that lodrt streams";
                    return false;
                }
        decoder_.reserve(pack->source);
    }
    return true;
}

void View::camera(float t, float eye[3], float target[3]) const {
    const float half = 0.5f * float(config_.grid - 1) * config_.spacing;
    const float start = half + 3.0f * config_.spacing, end = -half;
    eye[0] = 0.5f * config_.spacing; // the aisle between the two middle columns
    eye[1] = 1.6f;
    eye[2] = start + (end - start) * t;
    const float yaw = 0.45f * std::sin(6.2831853f * 1.5f * t);
    target[0] = eye[0] - 4.0f * std::sin(yaw);
    target[1] = 1.1f;
    target[2] = eye[2] - 4.0f * std::cos(yaw);
}

void View::selectPack(Pack& pack, const float eye[3]) {
    const size_t f = pack.first;
    const lodrt::InstanceArrays in{x_.data() + f,     y_.data() + f,     z_.data() + f, r_.data() + f,
                                   scale_.data() + f, model_.data() + f, pack.count};
    const lodrt::SelectionOutput out{level_.data() + f, draw_.data() + f, nullptr};
    lodrt::selectLevels(pack.table, eye, in, visibility_.data() + f, pack.streamer.residentTable(), out);
    if (config_.mode == LodMode::ForceLod0)
        for (size_t i = f; i < f + pack.count; ++i)
            if (visibility_[i] != lodrt::Containment::Outside) level_[i] = 0;
    lodrt::accumulateDemand(pack.table, params_, eye, in, visibility_.data() + f, level_.data() + f,
                            pack.demand.data());
}

// True when every visible instance's selected level is resident.
bool View::selectedResident() const {
    for (const auto& pack : packs_) {
        const uint8_t* resident = pack->streamer.residentTable();
        for (size_t i = pack->first; i < pack->first + pack->count; ++i)
            if (visibility_[i] != lodrt::Containment::Outside &&
                resident[model_[i] * lodrt::kMaxLevels + level_[i]] != level_[i])
                return false;
    }
    return true;
}

// Benchmark runs draw exactly the selected levels: keep updating the streamers until every
// visible instance's selected level is resident, or until nothing more can be fetched (a budget
// too small for it: the frame then draws coarser and says so in its report). A streamer that stays
// busy past kStreamWaitLimit means reads that never finish, which is an error, not a long frame.
bool View::waitForSelected(std::string* error) {
    const Clock::time_point start = Clock::now();
    while (!selectedResident()) {
        std::this_thread::sleep_for(std::chrono::microseconds(200));
        bool busy = false;
        for (auto& pack : packs_) {
            pack->streamer.update(pack->demand.data());
            busy = busy || !pack->streamer.idle();
        }
        if (!busy) return true; // nothing outstanding: what is still missing does not fit the budget
        if (Clock::now() - start > kStreamWaitLimit) {
            *error = "streaming: level reads still outstanding after " +
                     std::to_string(std::chrono::duration_cast<std::chrono::seconds>(kStreamWaitLimit).count()) +
                     " s while waiting for the selected levels";
            return false;
        }
    }
    return true;
}

bool View::mirrorResident(Renderer* renderer, FrameStats* stats, std::string* error) {
    const uint64_t growths_before = decoder_.growths();
    for (auto& pack : packs_) {
        const lodrt::ModelSet& models = pack->source.models();
        for (uint32_t m = 0; m < models.modelCount(); ++m)
            for (uint32_t l = 0; l < models.model(m).level_count; ++l) {
                GpuLevel& gpu = pack->gpu[m * lodrt::kMaxLevels + l];
                const bool resident = pack->streamer.state(m, l) == lodrt::LevelState::Resident;
                if (resident && !gpu.valid) {
                    size_t size = 0;
                    const uint8_t* bytes = pack->streamer.levelData(m, l, &size);
                    std::string why;
                    const Clock::time_point t0 = Clock::now();
                    const bool decoded = decoder_.decode(pack->source, m, l, bytes, size, &why);
                    stats->decode_ms += msSince(t0);
                    if (!decoded || !renderer->upload(pack->source, decoder_, &gpu, &why)) {
                        renderer->release(&gpu);
                        *error = pack->path + ": model " + std::to_string(m) + " level " + std::to_string(l) + ": " + why;
                        return false;
                    }
                    ++stats->levels_decoded;
                } else if (!resident && gpu.valid) {
                    renderer->release(&gpu); // evicted by the streamer
                }
            }
    }
    stats->decode_growths += decoder_.growths() - growths_before;
    return true;
}

bool View::update(const float eye[3], const float view_proj[16], Renderer* renderer, FrameStats* stats,
                  std::string* error) {
    const uint64_t setup_before = allocations_.load(), pool_before = pool_.calls(), heap_before = pool_.heapCalls();
    for (auto& pack : packs_) {
        pack->streamed_before = pack->streamer.stats().streamed_bytes;
        pack->requests_before = pack->streamer.stats().requests;
        pack->decodes_before = pack->streamer.stats().pfrep_decodes;
    }
    Clock::time_point t0 = Clock::now();
    lodrt::Frustum frustum;
    if (!lodrt::extractFrustum(view_proj, lodrt::ClipDepth::NegativeOneToOne, &frustum)) {
        *error = "camera: the view-projection matrix has a degenerate frustum";
        return false;
    }
    const size_t visible = bvh_.cull(frustum, visibility_.data());
    stats->cull_ms = msSince(t0);
    stats->visible = uint32_t(visible);
    stats->culled = uint32_t(instance_count_ - visible);

    t0 = Clock::now();
    for (auto& pack : packs_) selectPack(*pack, eye);
    stats->select_ms = msSince(t0);

    t0 = Clock::now();
    for (auto& pack : packs_) pack->streamer.update(pack->demand.data());
    stats->stream_ms = msSince(t0);

    if (config_.sync_streaming) {
        t0 = Clock::now();
        const bool settled = waitForSelected(error);
        stats->wait_ms = msSince(t0);
        if (!settled) return false;
    }
    // Draw levels against what is resident after this frame's update.
    for (auto& pack : packs_) {
        const uint8_t* resident = pack->streamer.residentTable();
        for (size_t i = pack->first; i < pack->first + pack->count; ++i)
            draw_[i] = visibility_[i] == lodrt::Containment::Outside
                           ? lodrt::kNoLevel
                           : resident[model_[i] * lodrt::kMaxLevels + level_[i]];
    }
    const uint64_t setup_calls = allocations_.load() - setup_before;
    stats->lodrt_allocations = setup_calls + pool_.calls() - pool_before;
    stats->lodrt_heap_allocations = setup_calls + pool_.heapCalls() - heap_before;

    t0 = Clock::now();
    bool ok = mirrorResident(renderer, stats, error);
    stats->upload_ms = msSince(t0) - stats->decode_ms;
    if (ok && config_.mode == LodMode::Pfrep) {
        t0 = Clock::now();
        ok = refinePfrep(frustum, eye, renderer, stats, error);
        stats->pfrep_ms = msSince(t0);
    }
    for (auto& pack : packs_) {
        const lodrt::StreamStats s = pack->streamer.stats();
        if (s.failures > 0 && ok) {
            *error = pack->path + ": " + std::to_string(s.failures) + " level reads failed";
            return false;
        }
        stats->levels_resident += s.resident_levels;
        stats->resident_bytes += s.resident_bytes;
        stats->bytes_streamed += s.streamed_bytes - pack->streamed_before;
        stats->stream_requests += s.requests - pack->requests_before;
        stats->pfrep_decodes += s.pfrep_decodes - pack->decodes_before;
    }
    measure(eye, stats);
    return ok;
}

// Refines every visible instance of a model whose PFRep prefix holds vertices towards the
// instance's model-space view at the selection's pixel threshold; the index buffer is rewritten
// only when the mask changed. The model and its bytes are valid until the next update.
bool View::refinePfrep(const lodrt::Frustum& frustum, const float eye[3], Renderer* renderer, FrameStats* stats,
                       std::string* error) {
    for (auto& pack : packs_) {
        const lodrt::ModelSet& models = pack->source.models();
        for (size_t i = pack->first; i < pack->first + pack->count; ++i) {
            Pack::PfrepInstance& inst = pack->pfrep_instances[i - pack->first];
            inst.drawable = false;
            const lodrt::PfrepModel* pm = pack->streamer.pfrepModel(model_[i]);
            if (visibility_[i] == lodrt::Containment::Outside || !pm || pm->loaded_from >= pm->vertex_count) continue;
            Pack::PfrepModelGpu& g = pack->pfrep_models[model_[i]];
            if (g.decoded_from != pm->loaded_from) { // more of the prefix (or less) is resident
                g.positions.resize(size_t(pm->vertex_count) * 3);
                g.scratch.resize(lodrt::pfrepScratchValues(*pm));
                if (lodrt::pfrepDecodePositions(*pm, g.positions.data(), g.positions.size()) != lodrt::Result::Ok) {
                    *error = pack->path + ": PFRep positions cannot be decoded";
                    return false;
                }
                renderer->uploadPositions(g.positions.data(), pm->vertex_count, &g.vbo);
                g.decoded_from = pm->loaded_from;
            }
            if (inst.mask.empty()) {
                inst.mask.resize(lodrt::pfrepMaskBytes(*pm));
                inst.indices.resize(lodrt::pfrepMaxTriangles(*pm) * 3);
                renderer->createDynamicMesh(g.vbo, &inst.vao, &inst.ibo);
            }
            // A prefix shrunk for the budget: the mask restarts from the coarsest mesh.
            if (inst.loaded_from == UINT32_MAX || pm->loaded_from > inst.loaded_from)
                lodrt::pfrepMaskCoarsest(*pm, inst.mask.data());
            inst.loaded_from = pm->loaded_from;
            float to_world[16];
            lodrt::multiplyTransforms(&placement_[i * 16], models.modelLevel(model_[i], 0).world_transform, to_world);
            lodrt::PfrepView view;
            size_t triangles = 0, changes = 0;
            lodrt::Result r =
                lodrt::pfrepInstanceViewTransform(frustum, eye, to_world, k_, config_.pixel_threshold, 0.5f, &view);
            // config_.pfrep_steps adaptation steps per frame (1 as an engine would run it); fewer
            // changes than a step allows mean the mask is a fixed point of the view.
            for (uint32_t step = 0; r == lodrt::Result::Ok && step < config_.pfrep_steps; ++step) {
                size_t changed = 0;
                r = lodrt::pfrepRefine(*pm, view, inst.mask.data(), g.scratch.data(), g.scratch.size(), &changed);
                changes += changed;
                if (changed == 0) break;
            }
            if (r == lodrt::Result::Ok)
                r = lodrt::pfrepExtractSelective(*pm, inst.mask.data(), inst.indices.data(), inst.indices.size() / 3,
                                                 &triangles);
            if (r != lodrt::Result::Ok) {
                *error = pack->path + ": PFRep refinement: " + lodrt::resultName(r);
                return false;
            }
            if (changes > 0 || triangles != inst.triangles)
                renderer->uploadIndices(inst.ibo, inst.indices.data(), triangles * 3);
            inst.triangles = triangles;
            inst.drawable = triangles > 0;
            stats->pfrep_changes += changes;
        }
    }
    return true;
}

void View::measure(const float eye[3], FrameStats* stats) const {
    for (const auto& pack : packs_) {
        const lodrt::ModelSet& models = pack->source.models();
        for (size_t i = pack->first; i < pack->first + pack->count; ++i) {
            if (visibility_[i] == lodrt::Containment::Outside) continue;
            // A refined PFRep instance: its per-vertex criterion holds the threshold.
            if (config_.mode == LodMode::Pfrep && pack->pfrep_instances[i - pack->first].drawable) continue;
            if (draw_[i] == lodrt::kNoLevel) {
                ++stats->not_drawable;
                continue;
            }
            if (draw_[i] != level_[i]) ++stats->coarser_than_selected;
            // Projected error as the selection defines it: distance to the bounding sphere in
            // model units.
            const float dx = x_[i] - eye[0], dy = y_[i] - eye[1], dz = z_[i] - eye[2];
            const float d = std::fmax((std::sqrt(dx * dx + dy * dy + dz * dz) - r_[i]) / scale_[i], 1e-6f);
            const float error = models.modelLevel(model_[i], draw_[i]).hausdorff_error;
            if (error > 0) stats->max_sse_px = std::fmax(stats->max_sse_px, error * k_ / d);
        }
    }
}

void View::draw(Renderer* renderer, FrameStats* stats) const {
    for (const auto& pack : packs_) {
        const lodrt::ModelSet& models = pack->source.models();
        for (size_t i = pack->first; i < pack->first + pack->count; ++i) {
            const uint8_t l = draw_[i];
            if (l == lodrt::kNoLevel) continue;
            const Pack::PfrepInstance& inst = pack->pfrep_instances[i - pack->first];
            if (config_.mode == LodMode::Pfrep && inst.drawable) {
                float model[16];
                lodrt::multiplyTransforms(&placement_[i * 16], models.modelLevel(model_[i], 0).world_transform, model);
                const float* colour = config_.colour_by_level ? kPfrepColour : kAssetColours[asset_[i] % 6];
                stats->draw_calls += renderer->drawDynamic(inst.vao, inst.triangles * 3, model, colour);
                stats->triangles += inst.triangles;
                stats->pfrep_triangles += inst.triangles;
                ++stats->pfrep_instances;
                ++stats->instances_drawn;
                continue;
            }
            const GpuLevel& gpu = pack->gpu[model_[i] * lodrt::kMaxLevels + l];
            if (!gpu.valid) continue;
            float model[16];
            lodrt::multiplyTransforms(&placement_[i * 16], models.modelLevel(model_[i], l).world_transform, model);
            const float* colour = config_.colour_by_level ? kLevelColours[l] : kAssetColours[asset_[i] % 6];
            stats->draw_calls +=
                renderer->draw(gpu, model, colour, !config_.colour_by_level, &stats->textured_draw_calls);
            stats->triangles += gpu.triangles;
            ++stats->instances_drawn;
            ++stats->histogram[l];
        }
    }
}

void View::drain() {
    for (;;) {
        bool idle = true;
        for (auto& pack : packs_) {
            if (pack->streamer.idle()) continue;
            pack->streamer.update(nullptr);
            idle = idle && pack->streamer.idle();
        }
        if (idle) return;
        std::this_thread::yield();
    }
}

void View::releaseGpu(Renderer* renderer) {
    for (auto& pack : packs_) {
        for (GpuLevel& gpu : pack->gpu)
            if (gpu.valid || !gpu.buffers.empty()) renderer->release(&gpu);
        for (Pack::PfrepInstance& inst : pack->pfrep_instances) renderer->releaseDynamic(&inst.vao, &inst.ibo);
        for (Pack::PfrepModelGpu& g : pack->pfrep_models) renderer->releaseBuffer(&g.vbo);
    }
}

uint64_t View::totalStreamedBytes() const {
    uint64_t total = 0;
    for (const auto& pack : packs_) total += pack->streamer.stats().streamed_bytes;
    return total;
}

uint64_t View::level0Triangles() const {
    uint64_t total = 0;
    for (const auto& pack : packs_)
        for (size_t i = pack->first; i < pack->first + pack->count; ++i)
            total += pack->source.models().modelLevel(model_[i], 0).triangle_count;
    return total;
}

} // namespace lodview
