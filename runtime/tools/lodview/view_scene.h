#pragma once
// lodview's scene: packs opened through lodrt with range reads (PackSource::openReader over pread),
// one Streamer per pack with a byte budget whose reads run on a job thread, a grid of instances of
// every model of every pack (each scaled to a bounding radius of 1), an InstanceBvh over them, and
// per frame: cull, select (selectLevels, or level 0 for every visible instance when LOD is forced
// off), demand, stream, then mirror the streamer's resident levels on the GPU (each new one decoded
// by LevelDecoder on the frame thread: plain, --web and --compact packs alike) and draw.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "gl_renderer.h"
#include "level_pool.h"
#include "lodrt/lodrt.h"

namespace lodview {

/// Lod: discrete levels by screen-space error. ForceLod0: level 0 for every visible instance.
/// Pfrep: instances of models with a PFRep blob are refined per vertex (pfrepUpdateInstance) from
/// the streamed prefix, the others drawn as in Lod.
enum class LodMode : uint8_t { Lod, ForceLod0, Pfrep };

struct ViewConfig {
    uint32_t width = 1280, height = 720;
    float vertical_fov = 1.0471976f; // 60 degrees
    float pixel_threshold = 1;       // screen-space error bound of the selection
    float hysteresis = 0.1f;
    int grid = 5;              // grid x grid instances
    float spacing = 4;         // between grid cells; every instance has a bounding radius of 1
    uint64_t budget_bytes = 0; // per pack streamer budget; 0 = unlimited
    LodMode mode = LodMode::Lod;
    bool colour_by_level = false;
    bool sync_streaming = false; // before drawing, wait until every selected level is resident
    uint32_t pfrep_steps = 1;    // Pfrep mode: refinement steps per instance per frame
};

/// What one frame did (times in milliseconds).
struct FrameStats {
    double cull_ms = 0, select_ms = 0, stream_ms = 0, upload_ms = 0, wait_ms = 0, pfrep_ms = 0;
    double decode_ms = 0;            // decoding newly resident levels (not part of upload_ms)
    uint32_t levels_decoded = 0;     // levels decoded and uploaded this frame
    uint64_t decode_growths = 0;     // decode buffers that had to grow (lodview's, not lodrt's)
    uint32_t visible = 0, culled = 0, draw_calls = 0, instances_drawn = 0;
    uint32_t textured_draw_calls = 0; // draw calls with the material's base colour texture
    uint64_t triangles = 0;
    uint32_t levels_resident = 0;
    uint64_t resident_bytes = 0, bytes_streamed = 0;
    uint32_t histogram[lodrt::kMaxLevels] = {}; // instances drawn per level
    uint32_t not_drawable = 0;                  // visible instances with no resident level yet
    uint32_t coarser_than_selected = 0;         // drawn coarser than selected (streaming lag)
    float max_sse_px = 0;                       // worst projected error of the drawn levels
    uint64_t lodrt_allocations = 0;             // allocator calls made by lodrt during the frame
    uint64_t lodrt_heap_allocations = 0;        // of those, served by malloc instead of the level pool
    uint32_t stream_requests = 0;               // level / PFRep reads the streamers started
    uint32_t pfrep_decodes = 0;                 // of those, format 3 PFRep decodes (two allocations each)
    uint32_t pfrep_instances = 0;               // instances drawn from their PFRep (Pfrep mode)
    uint64_t pfrep_triangles = 0;               // their triangles (part of `triangles`)
    uint64_t pfrep_changes = 0;                 // mask bits the refinement changed
};

/// The engine side of job scheduling: one worker thread with a queue (lodrt calls submit from
/// Streamer::update; the worker runs the reads).
class JobThread {
public:
    JobThread();
    ~JobThread();
    static void submit(void* user, void (*run)(void*), void* task);

private:
    void loop();
    std::deque<std::pair<void (*)(void*), void*>> queue_;
    std::mutex mutex_;
    std::condition_variable cv_;
    bool stop_ = false;
    // Last: members are constructed in declaration order, and the worker uses all of the above.
    std::thread thread_;
};

class View {
public:
    View();
    ~View();
    View(const View&) = delete;
    View& operator=(const View&) = delete;

    /// Opens every pack (header and JSON read; no level bytes). False with *error set
    /// ("<path>: <what>").
    bool open(const std::vector<std::string>& paths, std::string* error);
    /// Places the instances and prepares selection and streaming. False with *error set.
    bool init(const ViewConfig& config, std::string* error);
    void setMode(LodMode mode) { config_.mode = mode; }
    void setColourByLevel(bool on) { config_.colour_by_level = on; }
    const ViewConfig& config() const { return config_; }

    /// Camera of the walk at t in [0, 1]: in from outside the grid, along an aisle between two
    /// columns and out the far side, eye at standing height, looking ahead with a slow sway.
    void camera(float t, float eye[3], float target[3]) const;
    /// The lodrt part of a frame and the GPU mirror of the resident levels. False with *error set
    /// on a GPU upload failure or a level read failure.
    bool update(const float eye[3], const float view_proj[16], Renderer* renderer, FrameStats* stats,
                std::string* error);
    /// Draws every visible instance at its drawable level.
    void draw(Renderer* renderer, FrameStats* stats) const;
    /// Waits until no read job is outstanding (before the streamers are destroyed).
    void drain();
    void releaseGpu(Renderer* renderer);

    size_t instanceCount() const { return instance_count_; }
    size_t packCount() const { return packs_.size(); }
    uint64_t totalStreamedBytes() const;
    /// Triangles of every instance at level 0 (what forced LOD0 would draw with nothing culled).
    uint64_t level0Triangles() const;

    struct Pack; // internal

private:
    bool placeInstances(std::string* error);
    void selectPack(Pack& pack, const float eye[3]);
    bool selectedResident() const;
    bool waitForSelected(std::string* error);
    bool mirrorResident(Renderer* renderer, FrameStats* stats, std::string* error);
    void measure(const float eye[3], FrameStats* stats) const;
    bool refinePfrep(const lodrt::Frustum& frustum, const float eye[3], Renderer* renderer, FrameStats* stats,
                     std::string* error);
    std::vector<std::unique_ptr<Pack>> packs_;
    ViewConfig config_;
    JobThread jobs_thread_;
    lodrt::JobSystem jobs_;
    lodrt::Allocator allocator_; // setup allocations (packs, tables, hierarchy), counted, malloc
    std::atomic<uint64_t> allocations_{0};
    LevelPool pool_; // the streamers' allocations
    // Instances, ordered by pack (each pack's are contiguous), structure of arrays.
    size_t instance_count_ = 0;
    std::vector<float> x_, y_, z_, r_, scale_;
    std::vector<uint32_t> model_, asset_;
    std::vector<float> placement_; // 16 floats per instance: instance -> world (scale, translation)
    std::vector<uint8_t> level_, draw_;
    std::vector<lodrt::Containment> visibility_;
    lodrt::InstanceBvh bvh_;
    LevelDecoder decoder_; // the frame thread's decode buffers, sized at init for the largest level
    lodrt::SelectionParams params_;
    float k_ = 0; // pixels per unit at distance one
};

} // namespace lodview
