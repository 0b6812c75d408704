// The bake's memory budget (docs/bake.md, "Memory"): footprints read without loading, the gate that
// lets a batch's jobs run side by side only while their allowances fit, and --memory-limit.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <string>
#include <vector>
#include <thread>

#include "../gltf/gltf_test_util.h"
#include "lodbake/bake/batch.h"
#include "lodbake/bake/memory_budget.h"
#include "lodbake/core/file_io.h"
#include "lodbake/io/mesh_io.h"
#include "mesh_builders.h"
#include "test_paths.h"

namespace {

namespace fs = std::filesystem;
using namespace lodbake;

std::string scratch() {
    const std::string dir = lodbake_test::scratchDir() + "/memory_budget";
    fs::create_directories(dir);
    return dir;
}

std::string shared(const std::string& name) { return lodbake_test::sourceDir() + "/../shared/meshes/" + name; }

// A bumpy (n x n)-cell grid written to `path`: 2 n^2 triangles.
std::string writeGrid(int n, const std::string& path) {
    const Mesh mesh = lodbake_test::wavyField(n + 1, 0.05f, 0.7f, 0.45f);
    Diagnostics diagnostics;
    EXPECT_TRUE(writeMesh(mesh, path, WriteOptions{}, diagnostics).ok()) << path;
    return path;
}

TEST(MemoryBudgetTest, FootprintsAreReadFromHeadersOrOnePassWithoutLoading) {
    Diagnostics diagnostics;
    Result<BakeFootprint> ply = peekInputFootprint(shared("bunny_zipper.ply"), ReadOptions{}, diagnostics);
    ASSERT_TRUE(ply.ok()) << ply.status().message();
    EXPECT_TRUE(ply->known);
    EXPECT_EQ(ply->triangles, 69451u);
    Result<BakeFootprint> obj = peekInputFootprint(shared("nefertiti.obj"), ReadOptions{}, diagnostics);
    ASSERT_TRUE(obj.ok()) << obj.status().message();
    EXPECT_TRUE(obj->known);
    EXPECT_EQ(obj->triangles, 99938u);
    // Formats that need loading say so instead of guessing.
    Result<BakeFootprint> glb = peekInputFootprint(shared("nefertiti_fraunhofer_textured.glb"), ReadOptions{}, diagnostics);
    ASSERT_TRUE(glb.ok());
    EXPECT_FALSE(glb->known);
    Result<BakeFootprint> strips = peekInputFootprint(shared("igea_tristrips.ply"), ReadOptions{}, diagnostics);
    ASSERT_TRUE(strips.ok());
    EXPECT_FALSE(strips->known);
    // A broken header is the reader's error, naming the file.
    const std::string broken = scratch() + "/broken.ply";
    std::ofstream(broken) << "ply\nformat ascii 1.0\nelement vertex many\nend_header\n";
    Result<BakeFootprint> bad = peekInputFootprint(broken, ReadOptions{}, diagnostics);
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.status().message().find(broken), std::string::npos) << bad.status().message();
}

TEST(MemoryBudgetTest, LoadedFootprintCountsTrianglesAndTexelsOfEachTextureOnce) {
    Diagnostics diagnostics;
    Result<LoadedMesh> loaded = readMesh(shared("nefertiti_fraunhofer_textured.glb"), ReadOptions{}, diagnostics);
    ASSERT_TRUE(loaded.ok()) << loaded.status().message();
    const BakeFootprint one = loadedFootprint({&loaded->mesh});
    EXPECT_EQ(one.triangles, loaded->mesh.indices.size() / 3);
    EXPECT_EQ(one.texels, 2u * 2048u * 2048u); // base colour and normal map
    const BakeFootprint twice = loadedFootprint({&loaded->mesh, &loaded->mesh});
    EXPECT_EQ(twice.triangles, 2 * one.triangles);
    EXPECT_EQ(twice.texels, one.texels);
    EXPECT_EQ(bakeMemoryAllowance(one),
              kBakeBaseBytes + kBakeBytesPerTriangle * one.triangles + kBakeBytesPerTexel * one.texels);
}

TEST(MemoryBudgetTest, GateRefusesTooLargeAndServesWaitersInArrivalOrder) {
    MemoryGate gate(100);
    const Status refused = gate.acquire(101, "big.ply");
    EXPECT_EQ(refused.code(), StatusCode::ResourceLimit);
    EXPECT_NE(refused.message().find("big.ply"), std::string::npos);
    ASSERT_TRUE(gate.acquire(60, "a").ok());
    std::mutex mutex;
    std::vector<std::string> order;
    auto enter = [&](uint64_t bytes, const std::string& name) {
        EXPECT_TRUE(gate.acquire(bytes, name).ok());
        std::lock_guard<std::mutex> lock(mutex);
        order.push_back(name);
    };
    std::thread b([&] { enter(60, "b"); }); // must wait for a
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    std::thread c([&] { enter(40, "c"); }); // fits beside a, but arrived after b
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    {
        std::lock_guard<std::mutex> lock(mutex);
        EXPECT_TRUE(order.empty()); // neither passed a waiting reservation
        order.push_back("a leaves");
    }
    gate.release(60);
    b.join();
    c.join();
    EXPECT_EQ(order, (std::vector<std::string>{"a leaves", "b", "c"}));
    gate.release(100);
    ASSERT_TRUE(gate.acquire(100, "d").ok()); // everything was given back
    gate.release(100);
}

// Two packs whose allowances fit the limit only one at a time bake one after the other, with the
// bytes of a run without limit; a pack whose allowance alone exceeds the limit fails naming its
// input and leaves no output, while the others are written.
TEST(MemoryBudgetTest, BatchRunsJobsSideBySideOnlyWhileTheyFit) {
    const std::string a = writeGrid(40, scratch() + "/grid_a.ply");
    const std::string b = writeGrid(41, scratch() + "/grid_b.ply");
    std::vector<BakeJob> jobs(2);
    jobs[0].inputs = {a};
    jobs[0].output = scratch() + "/a.glb";
    jobs[1].inputs = {b};
    jobs[1].output = scratch() + "/b.glb";
    for (BakeJob& job : jobs) job.settings.lod_ratios = {0.5, 0.25};

    BatchOptions free_run;
    free_run.threads = 2;
    std::vector<BakeJobResult> reference = runBakeJobs(jobs, free_run, BatchHooks{});
    ASSERT_TRUE(reference[0].status.ok() && reference[1].status.ok());

    BakeFootprint larger;
    larger.triangles = 2 * 41 * 41;
    BatchOptions limited = free_run;
    limited.memory_limit_bytes = bakeMemoryAllowance(larger) + 1; // one at a time
    std::mutex mutex;
    std::map<size_t, int> running; // per job, its stages running now
    size_t most_running = 0;        // jobs with a stage running at one time
    BatchHooks hooks;
    hooks.stage_running = [&](size_t job, size_t, BakeStage, bool on) {
        std::lock_guard<std::mutex> lock(mutex);
        running[job] += on ? 1 : -1;
        size_t jobs_running = 0;
        for (const auto& [j, stages] : running) jobs_running += stages > 0 ? 1 : 0;
        most_running = std::max(most_running, jobs_running);
    };
    std::vector<BakeJobResult> results = runBakeJobs(jobs, limited, hooks);
    ASSERT_TRUE(results[0].status.ok()) << results[0].status.message();
    ASSERT_TRUE(results[1].status.ok()) << results[1].status.message();
    EXPECT_EQ(most_running, 1u);
    for (size_t j = 0; j < 2; ++j) {
        ASSERT_TRUE(reference[j].staged && results[j].staged);
        EXPECT_EQ(results[j].pack_bytes, reference[j].pack_bytes);
        EXPECT_EQ(results[j].report_json, reference[j].report_json);
    }

    BakeFootprint smaller;
    smaller.triangles = 2 * 40 * 40;
    limited.memory_limit_bytes = bakeMemoryAllowance(smaller); // a fits exactly, b does not
    results = runBakeJobs(jobs, limited, BatchHooks{});
    EXPECT_TRUE(results[0].status.ok()) << results[0].status.message();
    EXPECT_EQ(results[1].status.code(), StatusCode::ResourceLimit);
    EXPECT_NE(results[1].status.message().find(b + ": the in-memory bake of 3362 triangles"), std::string::npos)
        << results[1].status.message();
    EXPECT_FALSE(results[1].staged);
}

lodbake_test::CommandResult bake(const std::string& args) {
    return lodbake_test::runCommand(lodbake_test::shellQuote(lodbake_test::lodbakeCli()) + " bake " + args);
}

TEST(MemoryBudgetTest, CliLimitRefusesBeforeLoadingAndNeverChangesBytes) {
    const std::string in = writeGrid(30, scratch() + "/grid_cli.ply");
    const std::string out = scratch() + "/cli.glb", limited = scratch() + "/cli_limited.glb";
    fs::remove(out);
    lodbake_test::CommandResult r = bake(lodbake_test::shellQuote(in) + " --levels 0.5 --memory-limit 1 -o " +
                                         lodbake_test::shellQuote(out));
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("error: " + in + ": the in-memory bake of 1800 triangles and 0 texels is allowed"),
              std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("above the memory limit of 1 MiB (--memory-limit)"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out));
    ASSERT_EQ(bake(lodbake_test::shellQuote(in) + " --levels 0.5 -o " + lodbake_test::shellQuote(out)).exit_code, 0);
    ASSERT_EQ(bake(lodbake_test::shellQuote(in) + " --levels 0.5 --memory-limit 200 -o " +
                   lodbake_test::shellQuote(limited))
                  .exit_code,
              0);
    EXPECT_EQ(readFileBytes(out).value(), readFileBytes(limited).value());
    r = bake("--print-config --memory-limit 512");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("\"memory_limit_mib\": 512"), std::string::npos) << r.output;
    r = bake("--print-config --memory-limit lots");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.output.find("--memory-limit expects an integer number of MiB"), std::string::npos) << r.output;
}

} // namespace
