// The collapse engine's cost per collapse in the bake's two serial uses of it, next to native
// meshoptimizer on the same mesh in the same run:
//   chain  — the LOD chain (full-edge collapses, optimal placement, the bake's computed normals as
//            attributes, desktop ratios 0.5 0.25 0.1 0.03 0.01, no error measurement);
//   pfrep  — the PFRep build's half-edge simplification (geometry only, as far as valid collapses
//            go, collapse record on);
//   native — meshopt_simplify (Debian 0.18, options 0, no error limit) from the full mesh to the
//            chain's last level, positions only.
// The input is repaired and given normals as `lodbake bake` does. Prints thread CPU seconds (best of
// --runs, runs alternating), the collapse count, microseconds per collapse (native: per removed
// triangle pair, its nearest equivalent), the ratio to native, and hashes of the chain's levels and
// of the half-edge collapse record, so that a change meant to keep output identical can be checked.
//
// usage: collapse_bench [--threads N] [--runs N] MESH

#include <cfloat>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <meshoptimizer.h>

#include "bench_bar.h"
#include "bench_mesh.h"
#include "bench_timing.h"
#include "core/parallel.h"
#include "lodbake/cleanup/repair.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/core/hash.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/simplify/lod_chain.h"

namespace {

using lodbake_bench::threadCpuSeconds;

using namespace lodbake;

struct Step {
    double best = 1e300;
    size_t collapses = 0;
    uint64_t hash = 0;
    void take(double seconds) { best = std::min(best, seconds); }
    double usPerCollapse() const { return collapses ? 1e6 * best / double(collapses) : 0.0; }
};

} // namespace

int main(int argc, char** argv) {
    // --check is accepted so that scripts/bench.sh can pass it to every bench; there is no bar.
    (void)lodbake_bench::takeCheckFlag(argc, argv);
    lodbake_bench::Bars::printNone("collapse_bench", "a diagnostic of the collapse engine (cost per collapse next to "
                                                     "native meshopt, output hashes); no bar in the docs or issues");
    size_t threads = 1;
    int runs = 3;
    std::string path;
    for (int a = 1; a < argc; ++a) {
        if (std::strcmp(argv[a], "--threads") == 0 && a + 1 < argc)
            threads = size_t(std::atoi(argv[++a]));
        else if (std::strcmp(argv[a], "--runs") == 0 && a + 1 < argc)
            runs = std::max(1, std::atoi(argv[++a]));
        else
            path = argv[a];
    }
    if (path.empty()) {
        std::fprintf(stderr, "usage: collapse_bench [--threads N] [--runs N] MESH\n");
        return 2;
    }
    ScopedThreadLimit limit(threads);
    Diagnostics diagnostics;
    Mesh mesh;
    if (!lodbake_bench::loadRepaired(path, mesh, diagnostics)) return 1;
    Mesh geometry;
    geometry.positions = mesh.positions;
    geometry.indices = mesh.indices;
    std::printf("%s: %zu triangles after repair, normals %s, %zu thread(s), best of %d\n", path.c_str(),
                mesh.faceCount(), mesh.hasNormals() ? "yes" : "no", threads, runs);

    Step chain, pfrep, native;
    size_t native_target = 0;
    for (int r = 0; r < runs; ++r) {
        {
            LodChainOptions options;
            options.ratios = {0.5, 0.25, 0.1, 0.03, 0.01};
            options.measure_error = false;
            Diagnostics d;
            const double a = threadCpuSeconds();
            Result<LodChain> c = buildLodChain(mesh, options, d);
            const double b = threadCpuSeconds();
            if (!c.ok() || c->levels.empty()) return 1;
            chain.take(b - a);
            chain.collapses = c->levels.back().collapse_count;
            native_target = c->levels.back().mesh.faceCount();
            Hasher h;
            for (const LodLevel& level : c->levels) h.addU64(hashMesh(level.mesh));
            chain.hash = h.digest();
        }
        {
            LodChainOptions options;
            options.simplify.placement = CollapsePlacement::KeepEndpoint;
            options.ratios = {1e-9};
            options.measure_error = false;
            options.record_collapses = true;
            Diagnostics d;
            const double a = threadCpuSeconds();
            Result<LodChain> c = buildLodChain(geometry, options, d);
            const double b = threadCpuSeconds();
            if (!c.ok()) return 1;
            pfrep.take(b - a);
            pfrep.collapses = c->sequence.records.size();
            Hasher h;
            for (const CollapseRecord& record : c->sequence.records) {
                h.addU32(record.removed_point);
                h.addU32(record.kept_point);
                for (int k = 0; k < 3; ++k) h.addFloat(record.position[k]);
            }
            for (uint32_t v : c->sequence.created_triangles) h.addU32(v);
            pfrep.hash = h.digest();
        }
        {
            std::vector<unsigned int> destination(mesh.indices.size());
            const double a = threadCpuSeconds();
            const size_t count =
                meshopt_simplify(destination.data(), mesh.indices.data(), mesh.indices.size(), &mesh.positions[0].x,
                                 mesh.positions.size(), sizeof(Vec3f), native_target * 3, FLT_MAX, 0, nullptr);
            const double b = threadCpuSeconds();
            native.take(b - a);
            native.collapses = (mesh.faceCount() - count / 3) / 2;
        }
    }
    std::printf("chain   cpu %.3f s  collapses %zu  %.3f us/collapse  levels %s\n", chain.best, chain.collapses,
                chain.usPerCollapse(), hashToHex(chain.hash).c_str());
    std::printf("pfrep   cpu %.3f s  collapses %zu  %.3f us/collapse  record %s\n", pfrep.best, pfrep.collapses,
                pfrep.usPerCollapse(), hashToHex(pfrep.hash).c_str());
    std::printf("native  cpu %.3f s  to %zu triangles  %.3f us per triangle pair\n", native.best, native_target,
                native.usPerCollapse());
    std::printf("ratio   chain/native %.2f  pfrep/native %.2f  (per collapse: %.2f, %.2f)\n", chain.best / native.best,
                pfrep.best / native.best, chain.usPerCollapse() / native.usPerCollapse(),
                pfrep.usPerCollapse() / native.usPerCollapse());
    return 0;
}
