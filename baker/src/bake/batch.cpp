// The batch runner. Jobs are the unit of parallelism (grain 1); inside a job bake() parallelises
// over its inputs and texture jobs. Nothing a job produces depends on which worker ran it or when.
#include "lodbake/bake/batch.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <memory>
#include <mutex>

#include "core/parallel.h"
#include "lodbake/bake/cache.h"
#include "lodbake/bake/memory_budget.h"
#include "lodbake/core/file_io.h"
#include "lodbake/io/mesh_io.h"

namespace lodbake {

namespace {

using Clock = std::chrono::steady_clock;

uint64_t fileBytes(const std::filesystem::path& path) {
    std::error_code ec;
    const uintmax_t size = std::filesystem::file_size(path, ec);
    return ec ? 0 : uint64_t(size);
}

// How much an input weighs when ordering jobs: its size, plus for a `.conf` scan set the sizes of the
// scans its `bmesh` lines name (the .conf itself is a few lines). Only an estimate: 0 for files that
// cannot be read (the job then fails when it reads them).
uint64_t inputBytes(const std::string& path) {
    const std::filesystem::path p(path);
    uint64_t bytes = fileBytes(p);
    std::string extension = p.extension().string();
    for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (extension != ".conf" || bytes > (1u << 20)) return bytes;
    std::ifstream in(p);
    std::string line;
    while (std::getline(in, line)) {
        std::istringstream words(line);
        std::string keyword, scan;
        if (words >> keyword >> scan && keyword == "bmesh") bytes += fileBytes(p.parent_path() / scan);
    }
    return bytes;
}

// True when the file at `path` exists and holds exactly `bytes`.
bool fileHolds(const std::string& path, const std::vector<uint8_t>& bytes) {
    std::error_code ec;
    const uintmax_t size = std::filesystem::file_size(path, ec);
    if (ec || size != bytes.size()) return false;
    Result<std::vector<uint8_t>> existing = readFileBytes(path);
    return existing.ok() && *existing == bytes;
}

double secondsSince(Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
}

// An input as a scene graph (glTF with several mesh nodes, unless merge_scene), else one mesh.
Result<LoadedScene> readInputScene(const std::string& path, const BakeSettings& settings, const ReadOptions& read,
                                   Diagnostics& diagnostics) {
    if (!settings.merge_scene) return readMeshScene(path, read, diagnostics);
    LoadedScene scene;
    LODBAKE_ASSIGN_OR_RETURN(scene.flat, readMesh(path, read, diagnostics));
    return scene;
}

// Appends an input's meshes to `inputs` and its nodes to `scene` (an input without a graph: one
// root node named after its group). A graph's meshes are named after the glTF mesh, else the first
// node that instances it, else "<group>_<mesh index>".
void addToScene(const std::string& name, LoadedScene loaded, std::vector<BakeInput>& inputs, PackScene& scene) {
    if (!loaded.isGraph()) {
        PackNode node;
        node.name_from_asset = true;
        node.asset = int32_t(inputs.size());
        scene.roots.push_back(uint32_t(scene.nodes.size()));
        scene.nodes.push_back(std::move(node));
        inputs.push_back({name, std::move(loaded.flat.mesh)});
        return;
    }
    const uint32_t node_base = uint32_t(scene.nodes.size());
    const int32_t asset_base = int32_t(inputs.size());
    for (size_t m = 0; m < loaded.meshes.size(); ++m) {
        std::string group = loaded.mesh_names[m];
        for (const SceneNode& node : loaded.nodes)
            if (group.empty() && node.mesh == int32_t(m)) group = node.name;
        if (group.empty()) group = name + "_" + std::to_string(m);
        inputs.push_back({group, std::move(loaded.meshes[m])});
    }
    for (SceneNode& from : loaded.nodes) {
        PackNode node;
        node.name = std::move(from.name);
        node.matrix = std::move(from.matrix);
        node.translation = std::move(from.translation);
        node.rotation = std::move(from.rotation);
        node.scale = std::move(from.scale);
        node.world = from.world;
        for (uint32_t c : from.children) node.children.push_back(node_base + c);
        node.asset = from.mesh >= 0 ? asset_base + from.mesh : -1;
        scene.nodes.push_back(std::move(node));
    }
    for (uint32_t r : loaded.roots) scene.roots.push_back(node_base + r);
}

// What a refusal over the limit adds: the route that would bake the input anyway.
constexpr const char kOutOfCoreHint[] = "--clusters with a PLY or OBJ input bakes it out of core instead";

// A job's share of the batch's memory limit, held from before its inputs load until its pack is
// staged, and released when the job ends however it ends.
class JobMemory {
public:
    explicit JobMemory(MemoryGate* gate) : gate_(gate) {}
    JobMemory(const JobMemory&) = delete;
    JobMemory& operator=(const JobMemory&) = delete;
    ~JobMemory() {
        if (gate_ && bytes_ > 0) gate_->release(bytes_);
    }
    // Holds the allowance of `footprint` (refused when it alone exceeds the limit). Shrinking returns
    // the difference; growing gives the reservation back and waits for the whole, so a waiting job
    // never holds memory another one waits for.
    Status hold(const BakeFootprint& footprint, const std::string& what) {
        if (!gate_) return Status();
        const uint64_t bytes = bakeMemoryAllowance(footprint);
        if (bytes > gate_->limit()) {
            const Status refused = bakeOverLimit(what, footprint, gate_->limit());
            return Status(refused.code(), refused.message() + "; " + kOutOfCoreHint);
        }
        return holdBytes(bytes, what);
    }
    // Holds `bytes` (at most the limit) as hold() does.
    Status holdBytes(uint64_t bytes, const std::string& what) {
        if (!gate_) return Status();
        if (bytes <= bytes_) {
            gate_->release(bytes_ - bytes);
        } else {
            gate_->release(bytes_);
            bytes_ = 0;
            LODBAKE_RETURN_IF_ERROR(gate_->acquire(bytes, what));
        }
        bytes_ = bytes;
        return Status();
    }

private:
    MemoryGate* gate_ = nullptr;
    uint64_t bytes_ = 0;
};

// The job's footprint before its inputs load, when every input can be sized without loading it
// (memory_budget.h); unknown otherwise, and when a peek fails (the reader that loads the input then
// reports the error in its own words). An OBJ is counted by one pass over it only when it is large
// enough to matter: a face line of n >= 3 corners takes at least 2n bytes, so a file of B bytes
// holds fewer than B / 2 triangles.
BakeFootprint footprintBeforeLoading(const BakeJob& job, const BatchOptions& options, uint64_t limit) {
    BakeFootprint total;
    total.known = true;
    for (const std::string& input : job.inputs) {
        if (formatFromPath(input) == MeshFormat::Obj) {
            BakeFootprint bound;
            bound.triangles = inputBytes(input) / 2;
            if (bakeMemoryAllowance(bound) <= limit) return BakeFootprint{};
        }
        Diagnostics ignored; // warnings come again from the reader that loads the input
        Result<BakeFootprint> one = peekInputFootprint(input, options.read, ignored);
        if (!one.ok() || !one->known) return BakeFootprint{};
        total.triangles += one->triangles;
    }
    return total;
}

// What a memory refusal names: the input, or the output of a pack of several.
std::string jobName(const BakeJob& job) { return job.inputs.size() == 1 ? job.inputs[0] : job.output; }

using StageDone = std::function<void(size_t input, BakeStage stage, const StageTime& time)>;

// A job over the limit baked out of core (BatchOptions::out_of_core), holding the whole limit: the
// pack is written by the out-of-core writer into a temporary staged for job.output, so it is
// committed, or dropped, with the job's other outputs. Not stored in the cache (the pack is never in
// memory).
void runOutOfCoreJob(const BakeJob& job, const BatchOptions& options, JobMemory& memory, uint64_t limit,
                     const StageDone& stage_done, const std::function<void(BakeStage, bool)>& running,
                     BakeJobResult& result) {
    result.status = memory.holdBytes(limit, jobName(job));
    if (!result.status.ok()) return;
    const Clock::time_point start = Clock::now();
    running(BakeStage::LodChain, true);
    OutOfCorePack pack;
    result.staged = std::make_unique<AtomicFileWriter>();
    result.status = result.staged->addFile(job.output, [&](const std::string& temp) -> Status {
        Result<OutOfCorePack> made = options.out_of_core(job, temp, limit, options.threads, result.diagnostics);
        if (!made.ok()) return made.status();
        pack = std::move(made).value();
        return Status();
    });
    running(BakeStage::LodChain, false);
    if (!result.status.ok()) {
        result.staged.reset();
        return;
    }
    Clock::time_point at = start;
    for (const std::pair<BakeStage, double>& run : pack.stage_seconds) {
        StageTime time;
        time.wall_seconds = run.second;
        time.start = at;
        at += std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(run.second));
        stage_done(run.first == BakeStage::Pack ? kWholePack : 0, run.first, time);
    }
    result.files_read.push_back(job.inputs[0]);
    BakeOutput output;
    output.assets.push_back(std::move(pack.report));
    result.report_json = bakeReportJson(output, job.settings, pack.pack_bytes);
    result.summary = bakeSummaryText(output);
    result.pack_bytes = pack.pack_bytes;
    result.wall_seconds = secondsSince(start);
}

void runJob(const BakeJob& job, size_t index, const BatchOptions& options, MemoryGate* gate,
            const BatchHooks& hooks, BakeJobResult& result) {
    const Clock::time_point start = Clock::now();
    std::mutex mutex; // bake() reports the stages of a job's inputs from several workers
    auto stageDone = [&](size_t input, BakeStage stage, const StageTime& time) {
        {
            std::lock_guard<std::mutex> lock(mutex);
            StageTime& sum = result.stage_times[size_t(stage)];
            sum.wall_seconds += time.wall_seconds;
            sum.cpu_seconds += time.cpu_seconds;
            sum.thread_cpu_seconds += time.thread_cpu_seconds;
            BakeJobResult::StageRun run;
            run.stage = stage;
            run.input = input;
            run.level = time.level;
            run.start_seconds = std::max(0.0, std::chrono::duration<double>(time.start - start).count());
            run.wall_seconds = time.wall_seconds;
            run.thread_cpu_seconds = time.thread_cpu_seconds;
            result.timeline.push_back(run);
        }
        if (hooks.stage_done) hooks.stage_done(index, input, stage, time);
    };
    auto running = [&](size_t input, BakeStage stage, bool on) {
        if (hooks.stage_running) hooks.stage_running(index, input, stage, on);
    };
    // Stages timed here (not by bake()) run on this thread alone.
    auto timed = [&](size_t input, BakeStage stage, Clock::time_point wall, double cpu, double thread_cpu) {
        running(input, stage, false);
        StageTime time;
        time.wall_seconds = secondsSince(wall);
        time.cpu_seconds = processCpuSeconds() - cpu;
        time.thread_cpu_seconds = threadCpuSeconds() - thread_cpu;
        time.start = wall;
        stageDone(input, stage, time);
    };
    std::vector<std::string> names;
    for (const std::string& in : job.inputs) names.push_back(inputGroupName(in));

    CacheLookup lookup;
    const bool use_cache = !options.cache_dir.empty();
    if (use_cache) {
        const Clock::time_point t = Clock::now();
        const double cpu = processCpuSeconds(), thread_cpu = threadCpuSeconds();
        running(kWholePack, BakeStage::Load, true);
        Result<CacheLookup> found = cacheLookup(options.cache_dir, job.inputs, names, job.settings);
        timed(kWholePack, BakeStage::Load, t, cpu, thread_cpu);
        if (!found.ok()) {
            result.status = found.status();
            return;
        }
        lookup = std::move(found).value();
        if (lookup.hit) {
            const Clock::time_point w = Clock::now();
            const double w_cpu = processCpuSeconds(), w_thread_cpu = threadCpuSeconds();
            running(kWholePack, BakeStage::Write, true);
            result.staged = std::make_unique<AtomicFileWriter>();
            // An output that already holds these bytes keeps its file and its time stamp.
            result.unchanged = fileHolds(job.output, lookup.entry.glb);
            if (!result.unchanged) result.status = result.staged->add(job.output, lookup.entry.glb);
            timed(kWholePack, BakeStage::Write, w, w_cpu, w_thread_cpu);
            if (!result.status.ok()) return;
            result.cache_hit = true;
            result.cache_key = lookup.result.hex();
            for (const auto& files : lookup.files_read)
                result.files_read.insert(result.files_read.end(), files.begin(), files.end());
            result.report_json = std::move(lookup.entry.report_json);
            result.summary = std::move(lookup.entry.summary);
            result.pack_bytes = lookup.entry.glb.size();
            result.wall_seconds = secondsSince(start);
            return;
        }
    }

    JobMemory memory(gate);
    if (gate) {
        const BakeFootprint before = footprintBeforeLoading(job, options, gate->limit());
        if (before.known && bakeMemoryAllowance(before) > gate->limit() && options.out_of_core && outOfCoreEligible(job))
            return runOutOfCoreJob(job, options, memory, gate->limit(), stageDone,
                                   [&](BakeStage stage, bool on) { running(0, stage, on); }, result);
        if (before.known) result.status = memory.hold(before, jobName(job));
        if (!result.status.ok()) return;
    }
    std::vector<BakeInput> inputs;
    PackScene scene;
    bool has_graph = false;
    std::vector<std::vector<std::string>> files_read;
    for (size_t i = 0; i < job.inputs.size(); ++i) {
        const Clock::time_point t = Clock::now();
        const double cpu = processCpuSeconds(), thread_cpu = threadCpuSeconds();
        running(i, BakeStage::Load, true);
        Result<LoadedScene> loaded = readInputScene(job.inputs[i], job.settings, options.read, result.diagnostics);
        timed(i, BakeStage::Load, t, cpu, thread_cpu);
        if (!loaded.ok()) {
            result.status = loaded.status();
            return;
        }
        const SourceInfo& source = loaded->isGraph() ? loaded->source : loaded->flat.source;
        files_read.push_back(source.files_read);
        result.files_read.insert(result.files_read.end(), source.files_read.begin(), source.files_read.end());
        has_graph |= loaded->isGraph();
        addToScene(names[i], std::move(loaded).value(), inputs, scene);
    }
    if (!has_graph) scene = PackScene{}; // no graph anywhere: the pack layout of plain inputs
    if (gate) {
        std::vector<const Mesh*> meshes;
        for (const BakeInput& input : inputs) meshes.push_back(&input.mesh);
        result.status = memory.hold(loadedFootprint(meshes), jobName(job));
        if (!result.status.ok()) return;
    }
    BakeSettings settings = job.settings;
    settings.threads = 0; // the batch's thread limit applies
    BakeHooks bake_hooks;
    bake_hooks.stage_done = stageDone;
    bake_hooks.stage_running = running;
    bake_hooks.release_memory = hooks.release_memory;
    Result<BakeOutput> baked = bakeScene(std::move(inputs), std::move(scene), settings, result.diagnostics, bake_hooks);
    if (!baked.ok()) {
        result.status = baked.status();
        return;
    }
    result.report_json = bakeReportJson(*baked, job.settings);
    result.summary = bakeSummaryText(*baked);
    result.pack_bytes = baked->glb.size();
    const Clock::time_point w = Clock::now();
    const double w_cpu = processCpuSeconds(), w_thread_cpu = threadCpuSeconds();
    running(kWholePack, BakeStage::Write, true);
    result.staged = std::make_unique<AtomicFileWriter>();
    result.status = result.staged->add(job.output, baked->glb);
    timed(kWholePack, BakeStage::Write, w, w_cpu, w_thread_cpu);
    if (!result.status.ok()) return;
    if (use_cache) {
        CacheEntry entry;
        entry.glb = std::move(baked->glb);
        entry.report_json = result.report_json;
        entry.summary = result.summary;
        const Status stored = cacheStore(options.cache_dir, lookup.primary, job.inputs, files_read, entry);
        if (!stored.ok()) result.cache_warning = stored.message();
    }
    result.wall_seconds = secondsSince(start);
}

} // namespace

bool outOfCoreEligible(const BakeJob& job) {
    if (job.inputs.size() != 1 || !job.settings.cluster_lod || job.settings.web) return false;
    const MeshFormat format = formatFromPath(job.inputs[0]);
    return format == MeshFormat::Ply || format == MeshFormat::Obj;
}

std::string inputGroupName(const std::string& path) {
    const size_t slash = path.find_last_of("/\\");
    std::string stem = path.substr(slash == std::string::npos ? 0 : slash + 1);
    const size_t dot = stem.find_last_of('.');
    return dot == std::string::npos ? stem : stem.substr(0, dot);
}

std::string bakeSummaryText(const BakeOutput& output) {
    std::string text;
    for (const BakeAssetReport& a : output.assets) {
        text += a.name + ": " + std::to_string(a.input_triangles) + " triangles -> " +
                std::to_string(a.metrics.levels.size()) + " levels:";
        for (const LodMetricsLevel& l : a.metrics.levels) text += " " + std::to_string(l.triangles);
        text += "\n";
    }
    return text;
}

std::vector<BakeJobResult> runBakeJobs(const std::vector<BakeJob>& jobs, const BatchOptions& options,
                                       const BatchHooks& hooks) {
    std::vector<BakeJobResult> results(jobs.size());
    std::unique_ptr<ScopedThreadLimit> limit;
    if (options.threads > 0) limit = std::make_unique<ScopedThreadLimit>(options.threads);
    // Largest first (longest-processing-time order, by input bytes): a worker that becomes free takes
    // the next job of this list, so the big scans start at once and the small ones fill the gaps at the end. Which
    // worker bakes a job, and when, never changes its bytes.
    std::vector<uint64_t> bytes(jobs.size(), 0);
    for (size_t j = 0; j < jobs.size(); ++j)
        for (const std::string& in : jobs[j].inputs) bytes[j] += inputBytes(in);
    std::vector<size_t> order(jobs.size());
    for (size_t j = 0; j < order.size(); ++j) order[j] = j;
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return bytes[a] > bytes[b]; });
    std::unique_ptr<MemoryGate> gate;
    if (options.memory_limit_bytes > 0) gate = std::make_unique<MemoryGate>(options.memory_limit_bytes);
    std::atomic<size_t> next{0};
    const Status status = parallelFor(jobs.size(), 1, [&](size_t) {
        const size_t j = order[next.fetch_add(1)];
        runJob(jobs[j], j, options, gate.get(), hooks, results[j]);
        // The stages reported as they finished; the timeline lists them as they began (ties: input,
        // then stage, then level, so equal start times print in a fixed order).
        std::vector<BakeJobResult::StageRun>& timeline = results[j].timeline;
        std::sort(timeline.begin(), timeline.end(), [](const BakeJobResult::StageRun& a, const BakeJobResult::StageRun& b) {
            if (a.start_seconds != b.start_seconds) return a.start_seconds < b.start_seconds;
            if (a.input != b.input) return a.input < b.input;
            if (a.stage != b.stage) return a.stage < b.stage;
            return a.level < b.level;
        });
        if (hooks.job_done) hooks.job_done(j, results[j]);
    });
    if (!status.ok())
        for (BakeJobResult& r : results)
            if (r.status.ok() && r.pack_bytes == 0) r.status = status;
    for (BakeJobResult& r : results)
        if (!r.status.ok()) r.staged.reset(); // removes a staged temporary of a failed job
    return results;
}

} // namespace lodbake
