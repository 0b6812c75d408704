// UV layouts through an LOD chain, on the two textured scans: seams survive every level (charts may
// collapse away, never split), no face flips in texture space, every level reaches its target and
// the UV stretch of every level is reported; and a small chart collapsing away on a grid.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <numeric>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "lodbake/io/mesh_io.h"
#include "lodbake/simplify/lod_chain.h"
#include "lodbake/simplify/simplify.h"
#include "simplify_test_meshes.h"
#include "test_paths.h"

namespace {

using lodbake::Mesh;

struct UvStats {
    size_t islands = 0;       // faces connected through edges whose two corners share position and UV
    size_t seam_edges = 0;    // position edges whose faces disagree on the UV of an endpoint
    size_t open_uv_edges = 0; // island border edges that are neither a seam nor a mesh border
    size_t flipped = 0;       // faces whose signed UV area opposes their island's
    size_t zero_uv_area = 0;  // faces with (numerically) no UV area
    double stretch = 0;       // area-weighted mean of max(r, 1/r), r = (UV area / 3D area) / (total ratio);
                              // 1 = no area distortion; faces without UV area left out
};

uint64_t bitsOf(float f) {
    uint32_t b;
    std::memcpy(&b, &f, sizeof b);
    return b;
}

size_t findRoot(std::vector<size_t>& parent, size_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
}

UvStats uvStats(const Mesh& m) {
    // Keys: a point is a position, a wedge a position + UV (bit-exact, as the simplifier welds).
    auto positionKey = [&](uint32_t v) {
        const auto& p = m.positions[v];
        return std::make_tuple(bitsOf(p.x), bitsOf(p.y), bitsOf(p.z));
    };
    std::map<std::tuple<uint64_t, uint64_t, uint64_t>, uint32_t> point_ids;
    std::map<std::tuple<uint32_t, uint64_t, uint64_t>, uint32_t> wedge_ids;
    std::vector<uint32_t> point(m.vertexCount()), wedge(m.vertexCount());
    for (uint32_t v = 0; v < m.vertexCount(); ++v) {
        point[v] = point_ids.emplace(positionKey(v), uint32_t(point_ids.size())).first->second;
        const auto& uv = m.uvs[0][v];
        wedge[v] = wedge_ids.emplace(std::make_tuple(point[v], bitsOf(uv.x), bitsOf(uv.y)), uint32_t(wedge_ids.size()))
                       .first->second;
    }
    const size_t faces = m.faceCount();
    // Position edge -> (face, wedge at the lower point, wedge at the higher point).
    std::map<std::pair<uint32_t, uint32_t>, std::vector<std::tuple<size_t, uint32_t, uint32_t>>> edges;
    for (size_t f = 0; f < faces; ++f)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = m.indices[f * 3 + k], b = m.indices[f * 3 + (k + 1) % 3];
            const bool swap = point[a] > point[b];
            edges[{std::min(point[a], point[b]), std::max(point[a], point[b])}].emplace_back(
                f, swap ? wedge[b] : wedge[a], swap ? wedge[a] : wedge[b]);
        }
    std::vector<size_t> parent(faces);
    std::iota(parent.begin(), parent.end(), size_t(0));
    UvStats s;
    for (const auto& [key, uses] : edges) {
        bool seam = false;
        for (size_t i = 1; i < uses.size(); ++i) {
            if (std::get<1>(uses[i]) == std::get<1>(uses[0]) && std::get<2>(uses[i]) == std::get<2>(uses[0]))
                parent[findRoot(parent, std::get<0>(uses[i]))] = findRoot(parent, std::get<0>(uses[0]));
            else
                seam = true;
        }
        if (seam) ++s.seam_edges;
    }
    // An island border edge (used once with its wedges) must be a seam or a mesh border.
    for (const auto& [key, uses] : edges) {
        for (const auto& use : uses) {
            size_t same = 0;
            for (const auto& other : uses)
                same += std::get<1>(other) == std::get<1>(use) && std::get<2>(other) == std::get<2>(use);
            bool seam = false;
            for (const auto& other : uses)
                seam = seam || std::get<1>(other) != std::get<1>(use) || std::get<2>(other) != std::get<2>(use);
            if (same == 1 && uses.size() > 1 && !seam) ++s.open_uv_edges;
        }
    }
    std::vector<double> uv_area(faces), area(faces);
    double uv_total = 0, area_total = 0;
    for (size_t f = 0; f < faces; ++f) {
        const uint32_t i0 = m.indices[f * 3], i1 = m.indices[f * 3 + 1], i2 = m.indices[f * 3 + 2];
        const auto &t0 = m.uvs[0][i0], &t1 = m.uvs[0][i1], &t2 = m.uvs[0][i2];
        uv_area[f] =
            0.5 * ((double(t1.x) - t0.x) * (double(t2.y) - t0.y) - (double(t2.x) - t0.x) * (double(t1.y) - t0.y));
        const lodbake::Vec3d p0(m.positions[i0]), p1(m.positions[i1]), p2(m.positions[i2]);
        area[f] = 0.5 * lodbake::length(lodbake::cross(p1 - p0, p2 - p0));
        uv_total += std::abs(uv_area[f]);
        area_total += area[f];
    }
    std::map<size_t, double> island_area;
    for (size_t f = 0; f < faces; ++f) island_area[findRoot(parent, f)] += uv_area[f];
    s.islands = island_area.size();
    const double scale = uv_total / area_total;
    double weighted = 0, weighted_area = 0;
    for (size_t f = 0; f < faces; ++f) {
        const double island = island_area[findRoot(parent, f)];
        if (std::abs(uv_area[f]) <= 1e-12 * uv_total) {
            ++s.zero_uv_area;
        } else if ((uv_area[f] > 0) != (island > 0)) {
            ++s.flipped;
        }
        // Faces without UV area are counted above; their stretch is undefined.
        if (area[f] > 0 && std::abs(uv_area[f]) > 1e-12 * uv_total) {
            const double r = std::abs(uv_area[f]) / area[f] / scale;
            weighted += area[f] * std::max(r, 1.0 / r);
            weighted_area += area[f];
        }
    }
    s.stretch = weighted_area > 0 ? weighted / weighted_area : 0.0;
    return s;
}

// Every level within 5 % of its target (or the chain's last level, stopped with a note), and no
// two levels alike.
void checkTargets(const Mesh& mesh, const lodbake::LodChain& chain, const std::string& name) {
    size_t previous = mesh.faceCount();
    for (const lodbake::LodLevel& level : chain.levels) {
        const double target = std::ceil(level.target_ratio * double(mesh.faceCount()));
        EXPECT_LE(double(level.mesh.faceCount()), 1.05 * target) << name << " level " << level.target_ratio;
        EXPECT_TRUE(level.reached_target) << name << " level " << level.target_ratio;
        EXPECT_LT(level.mesh.faceCount(), previous) << name << " level " << level.target_ratio;
        previous = level.mesh.faceCount();
    }
}

void checkChain(const std::string& name) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    lodbake::Diagnostics d;
    auto loaded = lodbake::readMesh(lodbake_test::sharedMesh(name), lodbake::ReadOptions(), d);
    ASSERT_TRUE(loaded.ok()) << loaded.status().message();
    const Mesh& mesh = loaded->mesh;
    ASSERT_FALSE(mesh.uvs.empty()) << name;
    lodbake::LodChainOptions options;
    options.measure_error = false;
    auto chain = lodbake::buildLodChain(mesh, options, d);
    ASSERT_TRUE(chain.ok()) << chain.status().message();
    const UvStats in = uvStats(mesh);
    std::printf("%s input: %zu tris, %zu islands, %zu seam edges, %zu flipped, %zu zero-area UV faces, stretch %.4f\n",
                name.c_str(), mesh.faceCount(), in.islands, in.seam_edges, in.flipped, in.zero_uv_area, in.stretch);
    for (const lodbake::LodLevel& level : chain->levels) {
        const UvStats out = uvStats(level.mesh);
        std::printf("  level %-5g %6zu tris: %zu islands, %zu seam edges, %zu open UV edges, %zu flipped, %zu "
                    "zero-area UV faces, stretch %.4f\n",
                    level.target_ratio, level.mesh.faceCount(), out.islands, out.seam_edges, out.open_uv_edges,
                    out.flipped, out.zero_uv_area, out.stretch);
        // Charts may collapse away (the coarse levels of an atlas have fewer triangles than it has
        // charts), never split.
        EXPECT_LE(out.islands, in.islands) << name << " level " << level.target_ratio;
        EXPECT_GE(out.islands, 1u) << name << " level " << level.target_ratio;
        EXPECT_GT(out.seam_edges, 0u) << name << " level " << level.target_ratio;
        EXPECT_EQ(out.open_uv_edges, 0u) << name << " level " << level.target_ratio;
        EXPECT_LE(out.flipped, in.flipped) << name << " level " << level.target_ratio;
        EXPECT_LE(out.zero_uv_area, in.zero_uv_area) << name << " level " << level.target_ratio;
    }
    EXPECT_EQ(chain->levels.size(), options.ratios.size()) << name;
    checkTargets(mesh, *chain, name);
}

TEST(SimplifyUvTest, ASmallChartMayCollapseAway) {
    // A flat 12×12 grid mapped by its positions, except one triangle in the middle with a chart of
    // its own (its corners duplicated with UVs elsewhere in the atlas): its corners are seam points
    // that may only move along its three edges, so only a collapse that removes the chart's last
    // face gets the grid below a handful of triangles.
    Mesh m = lodbake_test::flatGrid(12);
    m.uvs.assign(1, {});
    for (const lodbake::Vec3f& p : m.positions) m.uvs[0].push_back({p.x * 0.5f, p.y * 0.5f});
    const size_t face = (3 * 12 + 3) * 2; // quad (3, 3): away from the grid's border
    for (int k = 0; k < 3; ++k) {
        const uint32_t v = m.indices[face * 3 + k];
        m.positions.push_back(m.positions[v]);
        m.uvs[0].push_back({0.75f + 0.2f * m.positions[v].x, 0.75f + 0.2f * m.positions[v].y});
        m.indices[face * 3 + k] = uint32_t(m.positions.size() - 1);
    }
    ASSERT_EQ(uvStats(m).islands, 2u);
    lodbake::SimplifyOptions options;
    options.target_triangles = 4;
    lodbake::Diagnostics d;
    auto out = lodbake::simplify(m, options, d);
    ASSERT_TRUE(out.ok()) << out.status().message();
    EXPECT_TRUE(out->reached_target) << out->mesh.faceCount();
    EXPECT_EQ(uvStats(out->mesh).islands, 1u);
    EXPECT_EQ(uvStats(out->mesh).flipped, 0u);
}

TEST(SimplifyUvTest, LeePerrySmithKeepsSeamsAndReachesItsTargets) {
    checkChain("lee_perry_smith/LeePerrySmith.glb");
}

TEST(SimplifyUvTest, NefertitiAtlasKeepsSeamsAndReachesItsTargets) {
    checkChain("nefertiti_fraunhofer_textured.glb");
}

} // namespace
