// lod_sample: a headless engine-style use of lodrt (document 000's test scene). Opens a baked pack
// through a range-read callback (only the header and JSON are read up front), runs level reads on
// two worker threads through the job callback, places a 5x5 grid of instances, flies a camera
// path and prints per frame: visible, culled, level histogram, triangles with and without LOD,
// memory resident and bytes streamed; then summary numbers.
//
// usage: lod_sample PACK.glb [--frames N] [--budget BYTES] [--threshold PX] [--check-threshold PX] [--quiet]
//   --budget BYTES         streaming budget (resident + in-flight level bytes; 0 = unlimited)
//   --threshold PX         screen-space error bound the selection is given (default 1)
//   --check-threshold PX   bound the selected levels are checked against (default: --threshold);
//                          a check threshold below --threshold breaks the run on purpose
// Exit codes: 0 when every check holds; 1 when the pack cannot be opened or a check fails (an
// `error:` line on stderr for each): a frame fails, a level read fails, a model never becomes
// drawable, a selected level projects above the check threshold, or the peak of resident plus
// in-flight bytes exceeds a non-zero budget; 2 on bad usage.

#include <algorithm>
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

constexpr const char* kUsage = "usage: lod_sample PACK.glb [--frames N] [--budget BYTES] [--threshold PX] "
                               "[--check-threshold PX] [--quiet]\n";

bool parseUnsigned(const char* text, unsigned long long* out) {
    char* end = nullptr;
    if (!*text || *text == '-') return false;
    *out = std::strtoull(text, &end, 10);
    return *end == '\0';
}

bool parsePixels(const char* text, float* out) {
    char* end = nullptr;
    const double value = std::strtod(text, &end);
    if (!*text || *end != '\0' || !(value > 0) || value > 1e9) return false;
    *out = float(value);
    return true;
}

struct Args {
    lodrt_sample::SceneConfig config;
    float check_threshold = -1; // negative: the selection's threshold
};

// Returns false (after printing the message) on bad usage.
bool parseArgs(int argc, char** argv, Args* args) {
    lodrt_sample::SceneConfig& config = args->config;
    for (int i = 2; i < argc; ++i) {
        const bool has_value = i + 1 < argc;
        unsigned long long number = 0;
        if (!std::strcmp(argv[i], "--frames") && has_value) {
            if (!parseUnsigned(argv[++i], &number) || number > 1000000) {
                std::fprintf(stderr, "lod_sample: --frames: expected a frame count up to 1000000, got %s\n", argv[i]);
                return false;
            }
            config.frames = int(number);
        } else if (!std::strcmp(argv[i], "--budget") && has_value) {
            if (!parseUnsigned(argv[++i], &number)) {
                std::fprintf(stderr, "lod_sample: --budget: expected a byte count, got %s\n", argv[i]);
                return false;
            }
            config.budget_bytes = number;
        } else if ((!std::strcmp(argv[i], "--threshold") || !std::strcmp(argv[i], "--check-threshold")) &&
                   has_value) {
            const bool check = argv[i][2] == 'c';
            if (!parsePixels(argv[i + 1], check ? &args->check_threshold : &config.pixel_threshold)) {
                std::fprintf(stderr, "lod_sample: %s: expected a positive number of pixels, got %s\n", argv[i],
                             argv[i + 1]);
                return false;
            }
            ++i;
        } else if (!std::strcmp(argv[i], "--quiet")) {
            config.print_frames = false;
        } else {
            std::fprintf(stderr, "lod_sample: unknown argument %s\n%s", argv[i], kUsage);
            return false;
        }
    }
    if (config.frames < 2) config.frames = 2;
    if (args->check_threshold < 0) args->check_threshold = config.pixel_threshold;
    return true;
}

// The run's own checks, each an `error:` line on stderr. Returns the number that failed.
int checkRun(const Args& args, const lodrt_sample::SceneSummary& summary, const lodrt::StreamStats& stats,
             uint64_t peak_held_bytes, int failed_frame) {
    int failed = 0;
    if (failed_frame >= 0) {
        std::fprintf(stderr, "error: frame %d: the camera's frustum could not be extracted\n", failed_frame);
        ++failed;
    }
    if (stats.failures > 0) {
        std::fprintf(stderr, "error: %u level or PFRep reads failed\n", stats.failures);
        ++failed;
    }
    if (summary.first_drawable_frame < 0) {
        std::fprintf(stderr, "error: some model never had a drawable level\n");
        ++failed;
    }
    // Selection compares in float; the bound gets float rounding's slack.
    if (summary.max_sse_selected_px > args.check_threshold * 1.0001f) {
        std::fprintf(stderr, "error: selected levels project to %.3f px, above the %.3g px threshold\n",
                     summary.max_sse_selected_px, args.check_threshold);
        ++failed;
    }
    const uint64_t budget = args.config.budget_bytes;
    if (budget > 0 && peak_held_bytes > budget) {
        std::fprintf(stderr, "error: peak resident + in-flight %llu bytes exceeds the budget of %llu bytes\n",
                     static_cast<unsigned long long>(peak_held_bytes), static_cast<unsigned long long>(budget));
        ++failed;
    }
    return failed;
}

// Flies the camera path over the grid, prints the summary and checks it. Returns the exit code.
int runScene(const lodrt::PackSource& source, const Args& args, uint64_t file_size) {
    const lodrt_sample::SceneConfig& config = args.config;
    WorkerPool pool(2);
    lodrt::JobSystem jobs{&WorkerPool::submit, &pool};
    lodrt_sample::Scene scene(source, config);
    const lodrt::Result r = scene.init(&jobs);
    if (r != lodrt::Result::Ok) {
        std::fprintf(stderr, "error: scene: %s\n", lodrt::resultName(r));
        return 1;
    }
    lodrt_sample::SceneSummary summary;
    // What the budget bounds: resident plus in-flight bytes. Both change only inside update(), so
    // reading them after each update sees every value they take.
    uint64_t peak_held = 0;
    const auto sampleHeld = [&] {
        const lodrt::StreamStats s = scene.streamer().stats();
        peak_held = std::max(peak_held, s.resident_bytes + s.in_flight_bytes);
    };
    int failed_frame = -1;
    for (int f = 0; f < config.frames && failed_frame < 0; ++f) {
        if (!scene.frame(f, &summary, stdout)) failed_frame = f;
        sampleHeld();
        // A frame of a 90 Hz engine: the worker threads stream meanwhile.
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    while (!scene.streamer().idle()) {
        scene.streamer().update(nullptr);
        sampleHeld();
        std::this_thread::yield();
    }
    const lodrt::StreamStats stats = scene.streamer().stats();
    const double ratio = summary.triangles_lod ? double(summary.triangles_lod0) / double(summary.triangles_lod) : 0;
    std::printf("summary: %d frames, %zu instances, visible %llu culled %llu (instance-frames)\n", config.frames,
                scene.instanceCount(), static_cast<unsigned long long>(summary.visible),
                static_cast<unsigned long long>(summary.culled));
    std::printf("summary: triangles submitted with LOD %llu, always LOD0 %llu, reduction %.2fx\n",
                static_cast<unsigned long long>(summary.triangles_lod),
                static_cast<unsigned long long>(summary.triangles_lod0), ratio);
    std::printf("summary: max screen-space error selected %.3f px (threshold %.3g, checked against %.3g), drawn "
                "%.3f px; %u instance-frames drawn coarser while streaming\n",
                summary.max_sse_selected_px, config.pixel_threshold, args.check_threshold, summary.max_sse_drawn_px,
                summary.fallback_draws);
    std::printf("summary: most level changes of one instance %u, reversals %u\n", summary.max_flips,
                summary.max_reversals);
    std::printf("summary: streamed %llu bytes of %llu, peak resident %llu bytes, peak resident + in-flight %llu "
                "bytes (budget %llu), %u failed reads, every model drawable at frame %d\n",
                static_cast<unsigned long long>(summary.streamed_bytes), static_cast<unsigned long long>(file_size),
                static_cast<unsigned long long>(summary.peak_resident_bytes),
                static_cast<unsigned long long>(peak_held), static_cast<unsigned long long>(config.budget_bytes),
                stats.failures, summary.first_drawable_frame);
    return checkRun(args, summary, stats, peak_held, failed_frame) == 0 ? 0 : 1;
}

} // namespace

int main(int argc, char** argv) {
    Args args;
    if (argc < 2) {
        std::fprintf(stderr, "%s", kUsage);
        return 2;
    }
    if (!parseArgs(argc, argv, &args)) return 2;
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
    // The streamer never loads a level whose data is not one byte range of the BIN chunk (data_size
    // 0), so the run could only report that the model never became drawable; say why instead.
    for (uint32_t m = 0; m < source.models().modelCount(); ++m)
        for (uint32_t l = 0; l < source.models().model(m).level_count; ++l)
            if (source.models().modelLevel(m, l).data_size == 0) {
                std::fprintf(stderr, "error: %s: model %u level %u: its data is not in a byte range of the BIN chunk "
                             "that lodrt streams\n", argv[1], m, l);
                std::fclose(file.file);
                return 1;
            }

    const int exit_code = runScene(source, args, file_size);
    std::fclose(file.file);
    return exit_code;
}
