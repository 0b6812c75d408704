// distance_bench: cost of the surface-distance measurement the bake runs for every level
// (docs/surface_distance.md), on one thread, in thread CPU time.
//   - our figure: DistanceReference::prepare + measureSurfaceDistances over the chain's 5 levels;
//   - the bake's split (docs/bake.md, "Concurrency"): prepareAndMeasureSurfaceDistances in one call
//     against measureReferenceSides for every level plus prepareAndMeasureSurfaceDistances with those
//     sides given (the part the bake runs beside the PFRep build, and the rest), results compared bit for bit;
//   - anchor, same run: the core TriangleBvh (lodbake/core/bvh.h) built over the same meshes and queried
//     from every vertex of both sides, cold (no warm start), per query.
// Prints every result with 17 significant digits so two builds can be compared exactly.
// Bar: the split gives the one call's results bit for bit on every level (the bake's results must not
// depend on how the measurement is divided; docs/bake.md, "Concurrency"). The times have no bar.
// usage: distance_bench [MESH (default dragon_poisson.ply)] [--runs N] [--no-anchor] [--check]
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "bench_bar.h"
#include "bench_timing.h"
#include "core/parallel.h"
#include "lodbake/core/bvh.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/simplify/lod_chain.h"
#include "lodbake/simplify/mesh_distance.h"

namespace {

using lodbake_bench::threadCpuSeconds;

// Anchor: every referenced vertex of `from` queried against a core TriangleBvh of `to`.
double anchorSeconds(const lodbake::Mesh& from, const lodbake::Mesh& to, size_t& queries, double& checksum) {
    const double c0 = threadCpuSeconds();
    auto bvh = lodbake::TriangleBvh::build(to.positions, to.indices);
    if (!bvh.ok()) return 0;
    std::vector<uint8_t> used(from.positions.size(), 0);
    for (uint32_t v : from.indices) used[v] = 1;
    for (size_t v = 0; v < used.size(); ++v) {
        if (!used[v]) continue;
        checksum += bvh->closest(lodbake::toDouble(from.positions[v])).distance_sq;
        ++queries;
    }
    return threadCpuSeconds() - c0;
}

} // namespace

int main(int argc, char** argv) {
    const bool check = lodbake_bench::takeCheckFlag(argc, argv);
    std::string name = "dragon_poisson.ply";
    int runs = 3;
    bool anchor_run = true;
    for (int a = 1; a < argc; ++a) {
        if (std::strcmp(argv[a], "--runs") == 0 && a + 1 < argc)
            runs = std::max(1, std::atoi(argv[++a]));
        else if (std::strcmp(argv[a], "--no-anchor") == 0)
            anchor_run = false;
        else
            name = argv[a];
    }
    lodbake::ScopedThreadLimit one_thread(1);
    lodbake::Diagnostics d;
    auto loaded = lodbake::readMesh(std::string(LODBAKE_BENCH_MESHES_DIR) + "/" + name, {}, d);
    if (!loaded.ok()) {
        std::printf("%s: %s\n", name.c_str(), loaded.status().message().c_str());
        return 1;
    }
    const lodbake::Mesh& mesh = loaded->mesh;
    lodbake::LodChainOptions options;
    options.measure_error = false;
    options.record_collapses = false;
    auto chain = lodbake::buildLodChain(mesh, options, d);
    if (!chain.ok()) {
        std::printf("chain: %s\n", chain.status().message().c_str());
        return 1;
    }
    std::vector<const lodbake::Mesh*> levels;
    for (const auto& level : chain->levels) levels.push_back(&level.mesh);
    std::printf("%s: %zu triangles, %zu levels; 1 thread, thread CPU time, best of %d\n", name.c_str(),
                mesh.faceCount(), levels.size(), runs);

    double best_prepare = 1e300, best_measure = 1e300;
    std::vector<lodbake::Result<lodbake::DistanceResult>> results;
    for (int r = 0; r < runs; ++r) {
        const double c0 = threadCpuSeconds();
        auto reference = lodbake::DistanceReference::prepare(mesh);
        const double c1 = threadCpuSeconds();
        if (!reference.ok()) return 1;
        results = lodbake::measureSurfaceDistances(*reference, levels, options.distance);
        const double c2 = threadCpuSeconds();
        best_prepare = std::min(best_prepare, c1 - c0);
        best_measure = std::min(best_measure, c2 - c1);
    }
    size_t points = 0;
    for (size_t l = 0; l < levels.size(); ++l) {
        if (!results[l].ok()) {
            std::printf("  level %zu: %s\n", l + 1, results[l].status().message().c_str());
            continue;
        }
        const lodbake::DistanceResult& r = *results[l];
        std::printf("  level %zu (%8zu tris): hausdorff %.17g mean %.17g rms %.17g\n", l + 1, levels[l]->faceCount(),
                    r.hausdorff, r.mean, r.rms);
        points += 2 * options.distance.sample_count + mesh.vertexCount() + levels[l]->vertexCount();
    }
    // The split the bake runs on a large asset, against the one call, alternating.
    double best_whole = 1e300, best_sides = 1e300, best_rest = 1e300;
    size_t differing = 0; // levels whose split result differs from the one call's, over all runs
    for (int r = 0; r < runs; ++r) {
        const double c0 = threadCpuSeconds();
        auto whole = lodbake::prepareAndMeasureSurfaceDistances(mesh, levels, options.distance);
        const double c1 = threadCpuSeconds();
        auto sides = lodbake::measureReferenceSides(mesh, levels, options.distance);
        const double c2 = threadCpuSeconds();
        if (!whole.ok() || !sides.ok()) return 1;
        std::vector<const lodbake::OneSidedDistance*> known(levels.size(), nullptr);
        for (size_t i = 0; i < levels.size(); ++i)
            if ((*sides)[i].ok()) known[i] = &*(*sides)[i];
        auto rest = lodbake::prepareAndMeasureSurfaceDistances(mesh, levels, options.distance, known);
        const double c3 = threadCpuSeconds();
        if (!rest.ok()) return 1;
        best_whole = std::min(best_whole, c1 - c0);
        best_sides = std::min(best_sides, c2 - c1);
        best_rest = std::min(best_rest, c3 - c2);
        for (size_t l = 0; l < levels.size(); ++l)
            differing += !(
                (*whole)[l].ok() == (*rest)[l].ok() &&
                (!(*whole)[l].ok() || ((*whole)[l]->hausdorff == (*rest)[l]->hausdorff &&
                                       (*whole)[l]->mean == (*rest)[l]->mean && (*whole)[l]->rms == (*rest)[l]->rms)));
    }
    std::printf("one call %.3f s; split: reference sides %.3f s + the rest %.3f s = %.3f s; results %s\n", best_whole,
                best_sides, best_rest, best_sides + best_rest, differing == 0 ? "bit-identical" : "DIFFER");
    lodbake_bench::Bars bars("distance_bench");
    bars.absolute("levels whose split measurement differs from the one call (" + name + ")", double(differing), 0,
                  lodbake_bench::Limit::AtMost);
    double anchor = 0, checksum = 0;
    size_t queries = 0;
    for (const lodbake::Mesh* level : levels) {
        if (!anchor_run) break;
        anchor += anchorSeconds(mesh, *level, queries, checksum);
        anchor += anchorSeconds(*level, mesh, queries, checksum);
    }
    const double ours = best_prepare + best_measure;
    std::printf("ours: prepare %.3f s + measure %.3f s = %.3f s for about %zu points (%.3f us/point)\n", best_prepare,
                best_measure, ours, points, ours / double(points) * 1e6);
    if (!anchor_run) return bars.finish(check);
    std::printf("anchor (core TriangleBvh, cold vertex queries incl. builds): %.3f s for %zu queries (%.3f us/query) "
                "[%g]\n",
                anchor, queries, anchor / double(queries) * 1e6, checksum);
    std::printf("per point, ours / anchor: %.2f (no bar)\n", (ours / double(points)) / (anchor / double(queries)));
    return bars.finish(check);
}
