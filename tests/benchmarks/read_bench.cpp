// read_bench: times readMesh on every mesh file under ../shared/meshes (best of 5 runs each) and
// prints milliseconds, triangles per second, and the ratio to an anchor measured in the same run:
// reading the file's bytes into memory (readFileBytes), so a noisy machine shows up in both figures.
//
// usage: read_bench [DIR]   (DIR defaults to the shared meshes folder next to the repository)

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "bench_bar.h"
#include "bench_timing.h"

#include "lodbake/core/file_io.h"
#include "lodbake/io/mesh_io.h"

namespace fs = std::filesystem;

namespace {

constexpr int kRuns = 5;

template <class F> double bestMs(F&& f) { return lodbake_bench::bestMs(kRuns, f); }

} // namespace

int main(int argc, char** argv) {
    // --check is accepted so that scripts/bench.sh can pass it to every bench; there is no bar.
    (void)lodbake_bench::takeCheckFlag(argc, argv);
    lodbake_bench::Bars::printNone("read_bench",
                                   "reader throughput next to reading the bytes; no bar in the docs or issues");
    const std::string dir = argc > 1 ? argv[1] : LODBAKE_BENCH_SHARED_MESHES_DIR;
    std::vector<std::string> files;
    std::error_code ec;
    for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
        if (!it->is_regular_file()) continue;
        if (lodbake::formatFromPath(it->path().string()) != lodbake::MeshFormat::Unknown)
            files.push_back(it->path().string());
    }
    if (ec || files.empty()) {
        std::fprintf(stderr, "read_bench: no mesh files found in %s\n", dir.c_str());
        return 1;
    }
    std::sort(files.begin(), files.end());
    std::printf("%-58s %10s %10s %12s %10s %8s\n", "file", "MB", "read ms", "Mtri/s", "anchor ms", "ratio");
    for (const std::string& path : files) {
        const std::string shown = fs::path(path).lexically_relative(dir).string();
        lodbake::Diagnostics diagnostics;
        lodbake::Result<lodbake::LoadedMesh> first = lodbake::readMesh(path, lodbake::ReadOptions(), diagnostics);
        if (!first.ok()) {
            std::printf("%-58s skipped: %s\n", shown.c_str(), first.status().message().c_str());
            continue;
        }
        const size_t triangles = first->mesh.faceCount();
        const double ms = bestMs([&] {
            lodbake::Diagnostics d;
            lodbake::Result<lodbake::LoadedMesh> r = lodbake::readMesh(path, lodbake::ReadOptions(), d);
            if (!r.ok()) std::abort();
        });
        size_t bytes = 0;
        const double anchor_ms = bestMs([&] {
            lodbake::Result<std::vector<uint8_t>> b = lodbake::readFileBytes(path);
            if (!b.ok()) std::abort();
            bytes = b->size();
        });
        std::printf("%-58s %10.2f %10.2f %12.2f %10.2f %8.1f\n", shown.c_str(), double(bytes) / 1e6, ms,
                    double(triangles) / (ms * 1e3), anchor_ms, ms / std::max(anchor_ms, 1e-6));
    }
    return 0;
}
