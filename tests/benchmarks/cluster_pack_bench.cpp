// LODBAKE_cluster_lod sizes and page decode speed (docs/format/cluster_lod.md), with anchors from the
// same run: per scan (repaired as the bake does), the extension's bytes (table + pages) per LOD0
// triangle; the bytes of the pages that hold only LOD0 clusters against LOD0 coded as one
// positions-only valence stream at the same bits (what paging LOD0 costs); and the decode rate of
// all pages (lodrt::clusterPageDecode) against one decode of that LOD0 stream (lodrt::valenceDecode).
//
// usage: cluster_pack_bench [MESH...]   (default: bunny_zipper, igea, dragon_poisson from ../shared/meshes)
#include <cstdio>
#include <string>
#include <vector>

#include "bench_mesh.h"
#include "bench_timing.h"
#include "lodbake/cluster/cluster_lod.h"
#include "lodbake/codec/valence_encoder.h"
#include "lodbake/pack/cluster_lod_pack.h"
#include "lodrt/cluster_pack.h"
#include "lodrt/valence.h"

namespace {

struct Pages {
    std::vector<uint64_t> memory;
    lodrt::ClusterLodPack pack;
    std::vector<uint64_t> scratch;
    std::vector<float> positions;
    std::vector<uint32_t> indices;
};

bool openPages(const std::vector<uint8_t>& table, const std::vector<uint8_t>& pages, Pages& p) {
    lodrt::ClusterPackInfo info;
    if (lodrt::clusterPackReadInfo(table.data(), table.size(), &info) != lodrt::Result::Ok) return false;
    p.memory.assign(info.memory_bytes / 8 + 1, 0);
    if (lodrt::clusterPackOpen(table.data(), table.size(), pages.size(), p.memory.data(), p.memory.size() * 8,
                               &p.pack) != lodrt::Result::Ok)
        return false;
    size_t scratch = 0, vertices = 0, triangles = 0;
    for (uint32_t i = 0; i < p.pack.page_count; ++i) {
        lodrt::ClusterPageInfo pi;
        const lodrt::ClusterPage& page = p.pack.pages[i];
        if (lodrt::clusterPageReadInfo(p.pack, i, pages.data() + page.byte_offset, page.byte_length, &pi) !=
            lodrt::Result::Ok)
            return false;
        scratch = std::max(scratch, pi.scratch_bytes);
        vertices = std::max<size_t>(vertices, pi.vertex_count);
        triangles = std::max<size_t>(triangles, pi.triangle_count);
    }
    p.scratch.assign(scratch / 8 + 1, 0);
    p.positions.resize(3 * vertices);
    p.indices.resize(3 * triangles);
    return true;
}

bool decodeAll(const std::vector<uint8_t>& pages, Pages& p, size_t* triangles) {
    *triangles = 0;
    for (uint32_t i = 0; i < p.pack.page_count; ++i) {
        const lodrt::ClusterPage& page = p.pack.pages[i];
        if (lodrt::clusterPageDecode(p.pack, i, pages.data() + page.byte_offset, page.byte_length, p.positions.data(),
                                     p.positions.size(), p.indices.data(), p.indices.size(), p.scratch.data(),
                                     p.scratch.size() * 8) != lodrt::Result::Ok)
            return false;
        *triangles += page.triangle_count;
    }
    return true;
}

bool run(const std::string& path) {
    lodbake::Diagnostics diagnostics;
    lodbake::Mesh mesh;
    if (!lodbake_bench::loadRepaired(path, mesh, diagnostics)) return false;
    auto built = lodbake::buildClusterLod(lodbake::MeshView(mesh), lodbake::ClusterLodOptions{}, diagnostics);
    if (!built.ok()) return std::fprintf(stderr, "error: %s\n", built.status().message().c_str()), false;
    lodbake::Result<lodbake::ClusterPackResult> written = lodbake::internalError("not run");
    const double write_s =
        1e-3 * lodbake_bench::bestMs(1, [&] { written = lodbake::writeClusterLodPack(*built, lodbake::ClusterPackOptions{}); });
    if (!written.ok()) return std::fprintf(stderr, "error: %s\n", written.status().message().c_str()), false;
    const std::vector<uint8_t>& table = written->extension.blobs[0];
    const std::vector<uint8_t>& pages = written->extension.blobs[1];
    const lodbake::ClusterPackStats& s = written->stats;
    // Anchor: LOD0 as one positions-only stream at the same bits.
    lodbake::Mesh lod0;
    lod0.positions = mesh.positions;
    lod0.indices = mesh.indices;
    lodbake::codec::ValenceEncodeOptions options;
    options.position_bits = lodbake::ClusterPackOptions{}.position_bits;
    auto stream = lodbake::codec::encodeValence(lod0, options);
    if (!stream.ok()) return std::fprintf(stderr, "error: %s\n", stream.status().message().c_str()), false;
    Pages p;
    if (!openPages(table, pages, p)) return std::fprintf(stderr, "error: the pages do not open\n"), false;
    size_t page_triangles = 0;
    bool ok = true;
    const double pages_ms = lodbake_bench::bestMs(3, [&] { ok = ok && decodeAll(pages, p, &page_triangles); });
    lodrt::ValenceInfo info;
    const std::vector<uint8_t>& lbm = stream->bytes;
    ok = ok && lodrt::valenceReadInfo(lbm.data(), lbm.size(), &info) == lodrt::Result::Ok;
    std::vector<uint64_t> scratch(lodrt::valenceScratchSize(info) / 8 + 1);
    std::vector<float> positions(3 * size_t(info.vertex_count));
    std::vector<uint32_t> indices(3 * size_t(info.triangle_count));
    lodrt::ValenceOutput out;
    out.indices = indices.data();
    out.index_capacity = indices.size();
    out.positions = positions.data();
    out.position_capacity = positions.size();
    out.scratch = scratch.data();
    out.scratch_size = scratch.size() * 8;
    ok = ok && lodrt::valenceDecode(lbm.data(), lbm.size(), out) == lodrt::Result::Ok;
    const double lod0_ms =
        lodbake_bench::bestMs(3, [&] { ok = ok && lodrt::valenceDecode(lbm.data(), lbm.size(), out) == lodrt::Result::Ok; });
    if (!ok) return std::fprintf(stderr, "error: decoding failed\n"), false;
    const double lod0_tris = double(s.lod0_triangles);
    std::printf("%s: LOD0 %zu triangles, %zu clusters, %zu groups, %zu pages (largest %zu bytes), written in %.2f s (wall, all threads)\n",
                path.c_str(), s.lod0_triangles, built->clusters.size(), built->groups.size(), s.page_count,
                s.max_page_bytes, write_s);
    std::printf("  extension %zu bytes = %.3f per LOD0 triangle (table %zu, pages %zu, runs %zu)\n",
                s.table_bytes + s.page_bytes, double(s.table_bytes + s.page_bytes) / lod0_tris, s.table_bytes,
                s.page_bytes, s.run_bytes);
    std::printf("  LOD0-only pages %zu bytes vs LOD0 valence stream (positions, %u bits) %zu bytes: %.3fx\n",
                s.lod0_page_bytes, options.position_bits, lbm.size(), double(s.lod0_page_bytes) / double(lbm.size()));
    std::printf("  decode: all pages %.1f ms (%.2f M triangles/s) vs LOD0 stream %.1f ms (%.2f M triangles/s): %.2fx "
                "the time per triangle\n",
                pages_ms, double(page_triangles) / pages_ms / 1e3, lod0_ms, double(info.triangle_count) / lod0_ms / 1e3,
                (pages_ms / double(page_triangles)) / (lod0_ms / double(info.triangle_count)));
    return true;
}

} // namespace

int main(int argc, char** argv) {
    std::vector<std::string> meshes;
    for (int i = 1; i < argc; ++i) meshes.push_back(argv[i]);
    if (meshes.empty())
        for (const char* name : {"bunny_zipper.ply", "igea.ply", "dragon_poisson.ply"})
            meshes.push_back(std::string(LODBAKE_BENCH_MESHES_DIR) + "/" + name);
    bool ok = true;
    for (const std::string& m : meshes) ok = run(m) && ok;
    return ok ? 0 : 1;
}
