// The two single-threaded stages of a bake on the critical path: the LOD chain and the PFRep build,
// each as the bake runs it. By default (every shipped preset) the chain records nothing and the PFRep
// build runs its own half-edge pass (simplification, point triangles, blob). With --from-chain (preset
// key pfrep_from_chain) the chain logs its collapses as vertex removals and runs on to the end of
// valid collapses, the PFRep blob is built from that log, and the separate pass follows for
// comparison. The input is repaired as the bake repairs it; the chain gets the bake's options
// (desktop ratios, no measurement), the separate PFRep pass a geometry-only copy of LOD0. Prints wall
// and thread CPU seconds per step (best of --runs) and a hash of every level and of the blob, so that
// a change meant to keep output identical can be checked in seconds instead of a whole bake.
//
// usage: bake_stages_bench [--threads N] [--runs N] [--chain-only | --pfrep-only] [--from-chain] MESH

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "bench_bar.h"
#include "bench_mesh.h"
#include "bench_timing.h"
#include "core/parallel.h"
#include "lodbake/cleanup/repair.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/core/hash.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/pfrep/pfrep_builder.h"
#include "lodbake/simplify/lod_chain.h"

namespace {

using namespace lodbake;

struct Clock {
    double wall;
    double cpu;
};

Clock now() {
    const double cpu = lodbake_bench::threadCpuSeconds();
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
    return {wall, cpu};
}

struct Best {
    double wall = 1e300, cpu = 1e300;
    void take(const Clock& a, const Clock& b) {
        wall = std::min(wall, b.wall - a.wall);
        cpu = std::min(cpu, b.cpu - a.cpu);
    }
};

} // namespace

int main(int argc, char** argv) {
    // --check is accepted so that scripts/bench.sh can pass it to every bench; there is no bar.
    (void)lodbake_bench::takeCheckFlag(argc, argv);
    lodbake_bench::Bars::printNone(
        "bake_stages_bench",
        "a diagnostic of the chain and PFRep stages (times and output hashes); no bar in the docs or issues");
    size_t threads = 2;
    int runs = 1;
    bool chain = true, pfrep = true;
    bool from_chain_log = false;
    std::string path;
    for (int a = 1; a < argc; ++a) {
        if (std::strcmp(argv[a], "--threads") == 0 && a + 1 < argc)
            threads = size_t(std::atoi(argv[++a]));
        else if (std::strcmp(argv[a], "--runs") == 0 && a + 1 < argc)
            runs = std::max(1, std::atoi(argv[++a]));
        else if (std::strcmp(argv[a], "--chain-only") == 0)
            pfrep = false;
        else if (std::strcmp(argv[a], "--pfrep-only") == 0)
            chain = false;
        else if (std::strcmp(argv[a], "--from-chain") == 0)
            from_chain_log = true;
        else
            path = argv[a];
    }
    if (path.empty()) {
        std::fprintf(stderr, "usage: bake_stages_bench [--threads N] [--runs N] [--chain-only | --pfrep-only] [--from-chain] MESH\n");
        return 2;
    }
    ScopedThreadLimit limit(threads);
    Diagnostics diagnostics;
    Mesh mesh;
    if (!lodbake_bench::loadRepaired(path, mesh, diagnostics)) return 1;
    std::printf("%s: %zu triangles after repair, %zu thread(s)\n", path.c_str(), mesh.faceCount(), threads);

    // The chain as the bake runs it; with --from-chain its collapses are logged as vertex removals for
    // the PFRep build (record_removals; the pass runs on to the end of valid collapses).
    auto bakeChain = [&](Diagnostics& d) {
        LodChainOptions options;
        options.ratios = {0.5, 0.25, 0.1, 0.03, 0.01};
        options.measure_error = false;
        options.record_collapses = false;
        options.record_removals = from_chain_log;
        return buildLodChain(mesh, options, d);
    };
    std::unique_ptr<LodChain> last_chain;
    if (chain) {
        Best total;
        uint64_t hash = 0;
        for (int r = 0; r < runs; ++r) {
            Diagnostics d;
            const Clock a = now();
            Result<LodChain> c = bakeChain(d);
            const Clock b = now();
            if (!c.ok()) return 1;
            total.take(a, b);
            Hasher h;
            for (const LodLevel& level : c->levels) h.addU64(hashMesh(level.mesh));
            hash = h.digest();
            last_chain = std::make_unique<LodChain>(std::move(*c));
        }
        std::printf("lod_chain  wall %.3f s  thread cpu %.3f s  levels %s  (removal log %zu bytes)\n", total.wall,
                    total.cpu, hashToHex(hash).c_str(), from_chain_log ? last_chain->removals.byteSize() : size_t(0));
    }
    if (pfrep && from_chain_log) {
        // pfrep_from_chain: the blob from the chain's log (no simplification of its own).
        if (!last_chain) {
            Diagnostics d;
            Result<LodChain> c = bakeChain(d);
            if (!c.ok()) return 1;
            last_chain = std::make_unique<LodChain>(std::move(*c));
        }
        Best from_chain;
        uint64_t hash = 0;
        for (int r = 0; r < runs; ++r) {
            Diagnostics d;
            const Clock a = now();
            Result<PfrepBuild> built = buildPfrepFromChain(mesh, last_chain->removals, d);
            const Clock b = now();
            if (!built.ok()) return 1;
            from_chain.take(a, b);
            Hasher h;
            h.addBytes(built->blob.data(), built->blob.size());
            hash = h.digest();
        }
        std::printf("pfrep      wall %.3f s  thread cpu %.3f s  (from the chain's log)  blob %s\n", from_chain.wall,
                    from_chain.cpu, hashToHex(hash).c_str());
    }
    if (pfrep) {
        Mesh geometry;
        geometry.positions = mesh.positions;
        geometry.indices = mesh.indices;
        Best simplify, triangles, blob, total;
        uint64_t hash = 0;
        for (int r = 0; r < runs; ++r) {
            LodChainOptions options;
            options.simplify.placement = CollapsePlacement::KeepEndpoint;
            options.ratios = {1e-9};
            options.measure_error = false;
            options.record_collapses = true;
            Diagnostics d;
            const Clock a = now();
            Result<LodChain> c = buildLodChain(geometry, options, d);
            const Clock b = now();
            if (!c.ok()) return 1;
            Result<std::vector<uint32_t>> t =
                c->sequence.point_triangles.empty()
                    ? pointTriangles(geometry, c->sequence)
                    : Result<std::vector<uint32_t>>(std::move(c->sequence.point_triangles));
            const Clock e = now();
            if (!t.ok()) return 1;
            Result<PfrepBuild> built = buildPfrepFromSequence(c->sequence, *t, d);
            const Clock f = now();
            if (!built.ok()) return 1;
            simplify.take(a, b);
            triangles.take(b, e);
            blob.take(e, f);
            total.take(a, f);
            Hasher h;
            h.addBytes(built->blob.data(), built->blob.size());
            for (uint32_t k : built->level_triangles) h.addU32(k);
            hash = h.digest();
        }
        std::printf("pfrep own  wall %.3f s  thread cpu %.3f s  (simplify %.3f / %.3f, point triangles %.3f / %.3f, "
                    "blob %.3f / %.3f)  blob %s\n",
                    total.wall, total.cpu, simplify.wall, simplify.cpu, triangles.wall, triangles.cpu, blob.wall,
                    blob.cpu, hashToHex(hash).c_str());
    }
    return 0;
}
