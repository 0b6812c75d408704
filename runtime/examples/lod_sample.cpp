// lod_sample: a headless engine-style use of lodrt (document 000's test scene). Opens a baked pack
// through a range-read callback (only the header and JSON are read up front), runs level reads on
// two worker threads through the job callback, places a 5x5 grid of instances, flies a camera
// path and prints per frame: visible, culled, level histogram, triangles with and without LOD,
// memory resident and bytes streamed; then summary numbers.
//
// usage: lod_sample PACK.glb [--frames N] [--budget BYTES] [--quiet]

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <mutex>
#include <thread>
#include <vector>

#include "lodrt/lodrt.h"
#include "sample_scene.h"

namespace {

// The engine side of file IO: lodrt itself never opens files.
struct PackFile {
    std::FILE* file = nullptr;
    std::mutex mutex; // one FILE position shared by the worker threads
    uint64_t reads = 0, read_bytes = 0;
    static lodrt::Result read(void* user, uint64_t offset, void* dst, size_t size) {
        PackFile* self = static_cast<PackFile*>(user);
        std::lock_guard<std::mutex> lock(self->mutex);
        ++self->reads;
        self->read_bytes += size;
        if (std::fseek(self->file, long(offset), SEEK_SET) != 0) return lodrt::Result::Truncated;
        return std::fread(dst, 1, size, self->file) == size ? lodrt::Result::Ok : lodrt::Result::Truncated;
    }
};

// A minimal engine job system: a queue and N worker threads.
class WorkerPool {
public:
    explicit WorkerPool(int threads) {
        for (int i = 0; i < threads; ++i) workers_.emplace_back([this] { loop(); });
    }
    ~WorkerPool() {
        {
            std::lock_guard<std::mutex> lock(mutex_);
            stop_ = true;
        }
        cv_.notify_all();
        for (auto& t : workers_) t.join();
    }
    static void submit(void* user, void (*run)(void*), void* task) {
        WorkerPool* self = static_cast<WorkerPool*>(user);
        {
            std::lock_guard<std::mutex> lock(self->mutex_);
            self->queue_.push_back({run, task});
        }
        self->cv_.notify_one();
    }

private:
    void loop() {
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
    std::vector<std::thread> workers_;
    std::deque<std::pair<void (*)(void*), void*>> queue_;
    std::mutex mutex_;
    std::condition_variable cv_;
    bool stop_ = false;
};

} // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: lod_sample PACK.glb [--frames N] [--budget BYTES] [--quiet]\n");
        return 2;
    }
    lodrt_sample::SceneConfig config;
    for (int i = 2; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--frames") && i + 1 < argc) {
            config.frames = std::atoi(argv[++i]);
        } else if (!std::strcmp(argv[i], "--budget") && i + 1 < argc) {
            config.budget_bytes = std::strtoull(argv[++i], nullptr, 10);
        } else if (!std::strcmp(argv[i], "--quiet")) {
            config.print_frames = false;
        } else {
            std::fprintf(stderr, "lod_sample: unknown argument %s\n", argv[i]);
            return 2;
        }
    }
    if (config.frames < 2) config.frames = 2;
    PackFile file;
    file.file = std::fopen(argv[1], "rb");
    if (!file.file) {
        std::fprintf(stderr, "error: %s: cannot open\n", argv[1]);
        return 1;
    }
    std::fseek(file.file, 0, SEEK_END);
    const uint64_t file_size = uint64_t(std::ftell(file.file));

    const auto t0 = std::chrono::steady_clock::now();
    lodrt::PackSource source;
    char message[256];
    lodrt::Result r =
        source.openReader(lodrt::RangeReader{&PackFile::read, &file}, file_size, nullptr, message, sizeof(message));
    if (r != lodrt::Result::Ok) {
        std::fprintf(stderr, "error: %s: %s (%s)\n", argv[1], message, lodrt::resultName(r));
        std::fclose(file.file);
        return 1;
    }
    const double open_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::printf("pack %s: %llu bytes, %u models; opened in %.3f ms reading %llu bytes in %llu calls\n", argv[1],
                static_cast<unsigned long long>(file_size), source.models().modelCount(), open_ms,
                static_cast<unsigned long long>(file.read_bytes), static_cast<unsigned long long>(file.reads));
    for (uint32_t m = 0; m < source.models().modelCount(); ++m) {
        const lodrt::ModelInfo& model = source.models().model(m);
        std::printf("model %u \"%.*s\": %u levels, radius %.4g:", m, int(model.name.size()), model.name.data(),
                    model.level_count, model.sphere_radius);
        for (uint32_t l = 0; l < model.level_count; ++l) {
            const lodrt::LevelInfo& level = source.models().modelLevel(m, l);
            std::printf(" [%u: %llu tris, err %.3g, %llu B]", l, static_cast<unsigned long long>(level.triangle_count),
                        level.hausdorff_error, static_cast<unsigned long long>(level.data_size));
        }
        std::printf("\n");
    }

    int exit_code = 0;
    {
        WorkerPool pool(2);
        lodrt::JobSystem jobs{&WorkerPool::submit, &pool};
        lodrt_sample::Scene scene(source, config);
        r = scene.init(&jobs);
        if (r != lodrt::Result::Ok) {
            std::fprintf(stderr, "error: scene: %s\n", lodrt::resultName(r));
            std::fclose(file.file);
            return 1;
        }
        lodrt_sample::SceneSummary summary;
        for (int f = 0; f < config.frames && exit_code == 0; ++f) {
            if (!scene.frame(f, &summary, stdout)) exit_code = 1;
            // A frame of a 90 Hz engine: the worker threads stream meanwhile.
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
        while (!scene.streamer().idle()) {
            scene.streamer().update(nullptr);
            std::this_thread::yield();
        }
        const double ratio = summary.triangles_lod ? double(summary.triangles_lod0) / double(summary.triangles_lod) : 0;
        std::printf("summary: %d frames, %zu instances, visible %llu culled %llu (instance-frames)\n", config.frames,
                    scene.instanceCount(), static_cast<unsigned long long>(summary.visible),
                    static_cast<unsigned long long>(summary.culled));
        std::printf("summary: triangles submitted with LOD %llu, always LOD0 %llu, reduction %.2fx\n",
                    static_cast<unsigned long long>(summary.triangles_lod),
                    static_cast<unsigned long long>(summary.triangles_lod0), ratio);
        std::printf("summary: max screen-space error selected %.3f px (threshold %.3g), drawn %.3f px; %u "
                    "instance-frames drawn coarser while streaming\n",
                    summary.max_sse_selected_px, config.pixel_threshold, summary.max_sse_drawn_px,
                    summary.fallback_draws);
        std::printf("summary: most level changes of one instance %u, reversals %u\n", summary.max_flips,
                    summary.max_reversals);
        std::printf(
            "summary: streamed %llu bytes of %llu, peak resident %llu bytes, every model drawable at frame %d\n",
            static_cast<unsigned long long>(summary.streamed_bytes), static_cast<unsigned long long>(file_size),
            static_cast<unsigned long long>(summary.peak_resident_bytes), summary.first_drawable_frame);
        if (summary.max_sse_selected_px > config.pixel_threshold * 1.0001f) {
            std::fprintf(stderr, "error: selected levels exceed the pixel threshold\n");
            exit_code = 1;
        }
    }
    std::fclose(file.file);
    return exit_code;
}
