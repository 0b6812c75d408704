// LODBAKE_cluster_lod (docs/format/cluster_lod.md): the writer (lodbake/pack/cluster_lod_pack.h) and
// the lodrt reader (lodrt/cluster_pack.h) together. Decoded pages keep the crack-free property of
// every cut (one shared grid), normal cones never remove a front-facing triangle, the bake writes the
// extension with identical bytes at 1 and 2 threads, and the reader refuses truncated and corrupted
// tables and pages with a message instead of reading out of bounds.

#include "lodbake/pack/cluster_lod_pack.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "../gltf/gltf_test_util.h"
#include "cluster_edges.h"
#include "cli_runner.h"
#include "data_uri.h"
#include "lodbake/bake/bake.h"
#include "lodbake/core/file_io.h"
#include "lodbake/image/texture_resize.h"
#include "lodbake/cluster/cluster_lod.h"
#include "lodbake/io/mesh_io.h"
#include "lodrt/cluster_pack.h"
#include "lodrt/format.h"
#include "lodrt/pack.h"
#include "mesh_builders.h"
#include "test_paths.h"

namespace {

using lodbake::ClusterLodHierarchy;
using lodbake::Mesh;
using lodbake::Vec3f;

using lodbake_test::bumpySphere;

ClusterLodHierarchy build(const Mesh& mesh) {
    lodbake::Diagnostics d;
    auto h = lodbake::buildClusterLod(mesh, lodbake::ClusterLodOptions(), d);
    EXPECT_TRUE(h.ok()) << h.status().message();
    return h.ok() ? std::move(h.value()) : ClusterLodHierarchy();
}

// The table opened and every page decoded, as a runtime would hold them.
struct Decoded {
    std::vector<uint8_t> table, pages;
    std::vector<uint64_t> memory;
    lodrt::ClusterLodPack pack;
    std::vector<std::vector<float>> positions;    // per page
    std::vector<std::vector<uint32_t>> indices;   // per page, cluster-sorted
    std::string error;
};

bool openAndDecode(Decoded& d) {
    char message[256] = {0};
    lodrt::ClusterPackInfo info;
    if (lodrt::clusterPackReadInfo(d.table.data(), d.table.size(), &info, message, sizeof(message)) != lodrt::Result::Ok) {
        d.error = message;
        return false;
    }
    d.memory.assign(info.memory_bytes / 8 + 1, 0);
    if (lodrt::clusterPackOpen(d.table.data(), d.table.size(), d.pages.size(), d.memory.data(), d.memory.size() * 8,
                               &d.pack, message, sizeof(message)) != lodrt::Result::Ok) {
        d.error = message;
        return false;
    }
    d.positions.resize(d.pack.page_count);
    d.indices.resize(d.pack.page_count);
    std::vector<uint64_t> scratch;
    for (uint32_t p = 0; p < d.pack.page_count; ++p) {
        const lodrt::ClusterPage& page = d.pack.pages[p];
        const uint8_t* bytes = d.pages.data() + page.byte_offset;
        lodrt::ClusterPageInfo pi;
        if (lodrt::clusterPageReadInfo(d.pack, p, bytes, page.byte_length, &pi, message, sizeof(message)) !=
            lodrt::Result::Ok) {
            d.error = message;
            return false;
        }
        scratch.assign(pi.scratch_bytes / 8 + 1, 0);
        d.positions[p].resize(size_t(pi.vertex_count) * 3);
        d.indices[p].resize(size_t(pi.triangle_count) * 3);
        if (lodrt::clusterPageDecode(d.pack, p, bytes, page.byte_length, d.positions[p].data(), d.positions[p].size(),
                                     d.indices[p].data(), d.indices[p].size(), scratch.data(), scratch.size() * 8,
                                     message, sizeof(message)) != lodrt::Result::Ok) {
            d.error = message;
            return false;
        }
    }
    return true;
}

Decoded writeAndDecode(const ClusterLodHierarchy& h, lodbake::ClusterPackStats* stats = nullptr) {
    Decoded d;
    auto written = lodbake::writeClusterLodPack(h, lodbake::ClusterPackOptions());
    EXPECT_TRUE(written.ok()) << written.status().message();
    if (!written.ok()) return d;
    if (stats) *stats = written.value().stats;
    d.table = written.value().extension.blobs[0];
    d.pages = written.value().extension.blobs[1];
    EXPECT_TRUE(openAndDecode(d)) << d.error;
    return d;
}

// The decoded triangles of cluster c, as three positions each.
template <class Fn> void forTriangles(const Decoded& d, uint32_t c, Fn&& fn) {
    const lodrt::ClusterPlace& place = d.pack.places[c];
    const std::vector<float>& pos = d.positions[place.page];
    const std::vector<uint32_t>& idx = d.indices[place.page];
    for (uint32_t t = place.first_triangle; t < place.first_triangle + place.triangle_count; ++t) {
        const float* p[3];
        for (int i = 0; i < 3; ++i) p[i] = &pos[3 * size_t(idx[3 * size_t(t) + size_t(i)])];
        fn(p);
    }
}

using Edge = lodrt_tools::ClusterEdges::Edge;

// The crack check (runtime/tools/cluster_edges.h) over the decoded pages.
class Edges : public lodrt_tools::ClusterEdges {
public:
    explicit Edges(const Decoded& d)
        : ClusterEdges(d.pack.view.cluster_count, [&d](uint32_t c, auto&& fn) { forTriangles(d, c, fn); }) {}
};

lodrt::SelectionParams params() {
    lodrt::SelectionParams p;
    p.pixel_threshold = 1;
    p.viewport_height = 1080;
    p.vertical_fov = 1.0471976f;
    return p;
}

std::vector<uint32_t> cut(const lodrt::ClusterLodView& view, const float eye[3], const lodrt::Frustum* frustum,
                          lodrt::ClusterCutStats* stats = nullptr) {
    std::vector<uint32_t> scratch(lodrt::clusterCutScratchBytes(view) / 4 + 1, 0);
    lodrt::ClusterCutScratch s{scratch.data(), scratch.size() * 4, 0};
    std::vector<uint32_t> out(view.cluster_count);
    lodrt::ClusterCutStats st;
    EXPECT_EQ(lodrt::selectClusterCut(view, lodrt::ClusterInstance(), eye, frustum, params(), s, out.data(),
                                      uint32_t(out.size()), &st),
              lodrt::Result::Ok);
    out.resize(st.written);
    if (stats) *stats = st;
    return out;
}

// Random eyes around the unit-ish object, from touching distance to far away.
std::vector<std::array<float, 3>> randomEyes(size_t n, float radius, uint32_t seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<float> g(0, 1);
    std::uniform_real_distribution<float> u(0, 1);
    std::vector<std::array<float, 3>> eyes;
    for (size_t i = 0; i < n; ++i) {
        float v[3] = {g(rng), g(rng), g(rng)};
        const float len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) + 1e-6f;
        const float dist = radius * (1.05f + 40.0f * u(rng) * u(rng) * u(rng));
        eyes.push_back({v[0] / len * dist, v[1] / len * dist, v[2] / len * dist});
    }
    return eyes;
}

lodrt::Frustum everything() {
    lodrt::Frustum f;
    for (int i = 0; i < 6; ++i) {
        f.planes[i][i / 2] = i % 2 == 0 ? 1.0f : -1.0f;
        f.planes[i][3] = 1e6f;
    }
    return f;
}

// Every cut of the decoded pages has no boundary edge that the decoded LOD0 clusters lack.
void expectCrackFree(const Decoded& d, size_t views, float radius) {
    const Edges edges(d);
    std::vector<uint32_t> lod0;
    for (uint32_t c = 0; c < d.pack.view.cluster_count; ++c)
        if (d.pack.view.clusters[c].self_group == lodrt::kClusterNone) lod0.push_back(c);
    const std::vector<Edge> lod0_boundary = edges.boundary(lod0);
    size_t distinct_cuts = 0, previous = 0;
    for (const auto& eye : randomEyes(views, radius, 7)) {
        const std::vector<uint32_t> drawn = cut(d.pack.view, eye.data(), nullptr);
        std::vector<Edge> b = edges.boundary(drawn), extra;
        std::set_difference(b.begin(), b.end(), lod0_boundary.begin(), lod0_boundary.end(), std::back_inserter(extra));
        ASSERT_TRUE(extra.empty()) << extra.size() << " boundary edges LOD0 lacks, eye " << eye[0] << " " << eye[1]
                                   << " " << eye[2];
        distinct_cuts += drawn.size() != previous;
        previous = drawn.size();
    }
    EXPECT_GT(distinct_cuts, views / 4); // the views cut at many depths, not all at one
}

TEST(ClusterLodPack, DecodedPagesKeepEveryCutCrackFree) {
    const Mesh sphere = bumpySphere(90, 120);
    const ClusterLodHierarchy h = build(sphere);
    ASSERT_GT(h.groups.size(), 10u);
    lodbake::ClusterPackStats stats;
    const Decoded d = writeAndDecode(h, &stats);
    ASSERT_TRUE(d.error.empty()) << d.error;
    EXPECT_EQ(d.pack.view.cluster_count, h.clusters.size());
    EXPECT_EQ(stats.page_count, h.groups.size() + (h.roots.size() + 31) / 32);
    expectCrackFree(d, 1000, 1.05f);
}

TEST(ClusterLodPack, DecodedScanKeepsEveryCutCrackFree) {
    LODBAKE_REQUIRE_SHARED_DIR(lodbake_test::sharedMeshesDir());
    lodbake::Diagnostics diagnostics;
    auto loaded = lodbake::readMesh(lodbake_test::sharedMesh("bunny_zipper.ply"), lodbake::ReadOptions(), diagnostics);
    ASSERT_TRUE(loaded.ok()) << loaded.status().message();
    const Mesh& mesh = loaded.value().mesh;
    const ClusterLodHierarchy h = build(mesh);
    const Decoded d = writeAndDecode(h);
    ASSERT_TRUE(d.error.empty()) << d.error;
    float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
    for (const Vec3f& p : mesh.positions)
        for (int j = 0; j < 3; ++j) {
            lo[j] = std::min(lo[j], p[j]);
            hi[j] = std::max(hi[j], p[j]);
        }
    // Views around the scan's centre: shift the decoded hierarchy's eye by the centre.
    const float radius = 0.5f * std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                          (hi[2] - lo[2]) * (hi[2] - lo[2]));
    const Edges edges(d);
    std::vector<uint32_t> lod0;
    for (uint32_t c = 0; c < d.pack.view.cluster_count; ++c)
        if (d.pack.view.clusters[c].self_group == lodrt::kClusterNone) lod0.push_back(c);
    const std::vector<Edge> lod0_boundary = edges.boundary(lod0);
    for (auto eye : randomEyes(300, radius, 11)) {
        for (int j = 0; j < 3; ++j) eye[size_t(j)] += 0.5f * (lo[j] + hi[j]);
        const std::vector<uint32_t> drawn = cut(d.pack.view, eye.data(), nullptr);
        std::vector<Edge> b = edges.boundary(drawn), extra;
        std::set_difference(b.begin(), b.end(), lod0_boundary.begin(), lod0_boundary.end(), std::back_inserter(extra));
        ASSERT_TRUE(extra.empty()) << extra.size() << " boundary edges LOD0 lacks";
    }
}

TEST(ClusterLodPack, ConeCullingDropsOnlyBackFacingClusters) {
    const ClusterLodHierarchy h = build(bumpySphere(60, 80));
    const Decoded d = writeAndDecode(h);
    ASSERT_TRUE(d.error.empty()) << d.error;
    const lodrt::Frustum all = everything();
    size_t culled = 0, drawn_total = 0;
    for (const auto& eye : randomEyes(200, 1.05f, 3)) {
        lodrt::ClusterCutStats with, without;
        std::vector<uint32_t> full = cut(d.pack.view, eye.data(), nullptr, &without);
        std::vector<uint32_t> drawn = cut(d.pack.view, eye.data(), &all, &with);
        std::sort(full.begin(), full.end());
        std::sort(drawn.begin(), drawn.end());
        // The drawn clusters are the full cut less the culled ones (the frustum holds everything).
        ASSERT_TRUE(std::includes(full.begin(), full.end(), drawn.begin(), drawn.end()));
        ASSERT_EQ(full.size() - drawn.size(), with.cone_culled);
        std::vector<uint32_t> gone;
        std::set_difference(full.begin(), full.end(), drawn.begin(), drawn.end(), std::back_inserter(gone));
        for (uint32_t c : gone)
            forTriangles(d, c, [&](const float* const* p) {
                const double e[3] = {double(p[1][0]) - p[0][0], double(p[1][1]) - p[0][1], double(p[1][2]) - p[0][2]};
                const double f[3] = {double(p[2][0]) - p[0][0], double(p[2][1]) - p[0][1], double(p[2][2]) - p[0][2]};
                const double n[3] = {e[1] * f[2] - e[2] * f[1], e[2] * f[0] - e[0] * f[2], e[0] * f[1] - e[1] * f[0]};
                for (int i = 0; i < 3; ++i) {
                    const double s = n[0] * (p[i][0] - eye[0]) + n[1] * (p[i][1] - eye[1]) + n[2] * (p[i][2] - eye[2]);
                    ASSERT_GE(s, 0.0) << "cluster " << c << " culled with a front-facing triangle";
                }
            });
        culled += gone.size();
        drawn_total += drawn.size();
    }
    // Seen from outside a sphere about half of it faces away: culling must find a good part of that.
    EXPECT_GT(culled, drawn_total / 5) << culled << " culled, " << drawn_total << " drawn";
}

// Pages arriving in any order: the cut draws only clusters of resident pages, stays crack-free, lists
// the groups it needs, and once every page is in it is the full cut.
TEST(ClusterLodPack, PartialResidencyDrawsResidentClustersWithoutCracks) {
    const ClusterLodHierarchy h = build(bumpySphere(60, 80));
    const Decoded d = writeAndDecode(h);
    ASSERT_TRUE(d.error.empty()) << d.error;
    const lodrt::ClusterLodView& v = d.pack.view;
    const Edges edges(d);
    std::vector<uint32_t> lod0;
    for (uint32_t c = 0; c < v.cluster_count; ++c)
        if (v.clusters[c].self_group == lodrt::kClusterNone) lod0.push_back(c);
    const std::vector<Edge> lod0_boundary = edges.boundary(lod0);
    std::vector<uint8_t> pages(d.pack.page_count, 0), groups(v.group_count, 0);
    std::vector<uint32_t> missing(v.group_count);
    std::vector<uint32_t> scratch(lodrt::clusterCutScratchBytes(v) / 4 + 1, 0), out(v.cluster_count);
    lodrt::ClusterCutScratch s{scratch.data(), scratch.size() * 4, 0};
    std::mt19937 rng(5);
    size_t partial_cuts = 0, stand_ins = 0, closed_off = 0; // groups the upward closure made non-resident
    for (const auto& eye : randomEyes(300, 1.05f, 9)) {
        // Root pages always; every other page resident with a chance of 0.5, 0.75 or 0.95.
        const double chance = 0.5 + 0.25 * double(partial_cuts % 3) - (partial_cuts % 3 == 2 ? 0.05 : 0.0);
        for (uint8_t& p : pages) p = std::uniform_real_distribution<double>(0, 1)(rng) < chance;
        for (uint32_t r = 0; r < v.root_count; ++r) pages[d.pack.places[v.roots[r]].page] = 1;
        lodrt::clusterGroupResidency(d.pack, pages.data(), groups.data());
        for (uint32_t g = 0; g < v.group_count; ++g) {
            bool raw = true;
            for (uint32_t i = 0; i < v.groups[g].child_count; ++i)
                raw = raw && pages[d.pack.places[v.group_children[v.groups[g].first_child + i]].page];
            closed_off += raw && !groups[g];
        }
        lodrt::ClusterResidency residency{groups.data(), missing.data(), uint32_t(missing.size()), 0};
        lodrt::ClusterCutStats st;
        ASSERT_EQ(lodrt::selectClusterCutResident(v, lodrt::ClusterInstance(), eye.data(), nullptr, params(), s,
                                                  &residency, out.data(), uint32_t(out.size()), &st),
                  lodrt::Result::Ok);
        const std::vector<uint32_t> drawn(out.begin(), out.begin() + st.written);
        for (uint32_t c : drawn) ASSERT_TRUE(pages[d.pack.places[c].page]) << "cluster " << c << " of a missing page";
        std::vector<Edge> b = edges.boundary(drawn), extra;
        std::set_difference(b.begin(), b.end(), lod0_boundary.begin(), lod0_boundary.end(), std::back_inserter(extra));
        ASSERT_TRUE(extra.empty()) << extra.size() << " boundary edges LOD0 lacks with partial residency";
        const std::vector<uint32_t> full = cut(v, eye.data(), nullptr);
        if (residency.missing_count == 0) {
            EXPECT_EQ(std::multiset<uint32_t>(drawn.begin(), drawn.end()), std::multiset<uint32_t>(full.begin(), full.end()));
        } else {
            ++stand_ins;
            for (uint32_t i = 0; i < residency.missing_count; ++i) EXPECT_FALSE(groups[missing[i]]);
        }
        ++partial_cuts;
    }
    EXPECT_GT(stand_ins, 20u); // the run did cut with missing pages
    EXPECT_GT(closed_off, 0u) << "the closure never mattered: the test would not see overlapping stand-ins";
    // Everything resident: the full cut.
    std::fill(pages.begin(), pages.end(), uint8_t(1));
    lodrt::clusterGroupResidency(d.pack, pages.data(), groups.data());
    const float eye[3] = {0.0f, 0.0f, 1.3f};
    lodrt::ClusterResidency all{groups.data(), missing.data(), uint32_t(missing.size()), 0};
    lodrt::ClusterCutStats st;
    ASSERT_EQ(lodrt::selectClusterCutResident(v, lodrt::ClusterInstance(), eye, nullptr, params(), s, &all, out.data(),
                                              uint32_t(out.size()), &st),
              lodrt::Result::Ok);
    EXPECT_EQ(all.missing_count, 0u);
    EXPECT_EQ(std::vector<uint32_t>(out.begin(), out.begin() + st.written), cut(v, eye, nullptr));
}

TEST(ClusterLodPack, RefusesEveryTruncationAndCorruptionWithAMessage) {
    const ClusterLodHierarchy h = build(bumpySphere(16, 24));
    Decoded good = writeAndDecode(h);
    ASSERT_TRUE(good.error.empty()) << good.error;
    for (size_t cut_at = 0; cut_at < good.table.size(); cut_at += 7) {
        Decoded d;
        d.table.assign(good.table.begin(), good.table.begin() + std::ptrdiff_t(cut_at));
        d.pages = good.pages;
        EXPECT_FALSE(openAndDecode(d)) << "table cut at " << cut_at;
        EXPECT_FALSE(d.error.empty());
    }
    for (size_t cut_at = 0; cut_at < good.pages.size(); cut_at += 5) {
        Decoded d;
        d.table = good.table;
        d.pages.assign(good.pages.begin(), good.pages.begin() + std::ptrdiff_t(cut_at));
        EXPECT_FALSE(openAndDecode(d)) << "pages cut at " << cut_at;
        EXPECT_FALSE(d.error.empty());
    }
    // Every byte changed, alone: refused with a message, or accepted (a float that stays plausible);
    // either way nothing is read out of bounds (the sanitizer build checks that).
    size_t refused = 0, changes = 0;
    for (int which = 0; which < 2; ++which) {
        const std::vector<uint8_t>& src = which == 0 ? good.table : good.pages;
        for (size_t i = 0; i < src.size(); i += which == 0 ? 1 : 3) {
            Decoded d;
            d.table = good.table;
            d.pages = good.pages;
            (which == 0 ? d.table : d.pages)[i] ^= uint8_t(0x5a);
            const bool ok = openAndDecode(d);
            refused += ok ? 0 : 1;
            ++changes;
            if (!ok) {
                EXPECT_FALSE(d.error.empty());
            }
        }
    }
    EXPECT_GT(refused, changes / 3);
}

TEST(ClusterLodPack, BakeWritesTheExtensionWithIdenticalBytesAtOneAndTwoThreads) {
    std::vector<uint8_t> glb[2];
    for (int t = 0; t < 2; ++t) {
        lodbake::BakeSettings settings;
        settings.cluster_lod = true;
        settings.threads = uint32_t(t + 1);
        settings.lod_ratios = {0.5, 0.1};
        settings.error_samples = 20000;
        std::vector<lodbake::BakeInput> inputs(1);
        inputs[0].name = "sphere";
        inputs[0].mesh = bumpySphere(40, 60);
        lodbake::Diagnostics diagnostics;
        auto out = lodbake::bake(std::move(inputs), settings, diagnostics);
        ASSERT_TRUE(out.ok()) << out.status().message();
        glb[t] = out.value().glb;
    }
    EXPECT_EQ(glb[0], glb[1]);
    {
        lodbake::BakeSettings web;
        web.cluster_lod = true;
        web.web = true;
        std::vector<lodbake::BakeInput> inputs(1);
        inputs[0].mesh = bumpySphere(8, 12);
        lodbake::Diagnostics diagnostics;
        auto refused = lodbake::bake(std::move(inputs), web, diagnostics);
        ASSERT_FALSE(refused.ok());
        EXPECT_NE(refused.status().message().find("/cluster_lod: cannot be combined with web"), std::string::npos)
            << refused.status().message();
    }
    lodrt::Pack pack;
    char message[256] = {0};
    ASSERT_EQ(lodrt::loadPack(glb[0].data(), glb[0].size(), nullptr, &pack, message, sizeof(message)),
              lodrt::Result::Ok)
        << message;
    lodrt::ClusterPackSource source;
    ASSERT_EQ(lodrt::clusterPackFind(pack, 0, &source, message, sizeof(message)), lodrt::Result::Ok) << message;
    Decoded d;
    d.table.assign(source.table, source.table + source.table_size);
    d.pages.assign(source.pages, source.pages + source.pages_size);
    ASSERT_TRUE(openAndDecode(d)) << d.error;
    size_t lod0_triangles = 0;
    for (uint32_t c = 0; c < d.pack.view.cluster_count; ++c)
        if (d.pack.view.clusters[c].self_group == lodrt::kClusterNone) lod0_triangles += d.pack.places[c].triangle_count;
    EXPECT_EQ(lod0_triangles, pack.primitive(pack.mesh(0).first_primitive).triangle_count);
    // A pack opened from its JSON chunk alone (range reads): the same views and byte ranges, no bytes;
    // the table and pages read at those ranges of the BIN chunk are the ones above.
    lodrt::GlbView glb_view;
    ASSERT_EQ(lodrt::parseGlb(glb[0].data(), glb[0].size(), &glb_view), lodrt::Result::Ok);
    lodrt::Pack json_only;
    ASSERT_EQ(lodrt::loadPackJson(glb_view.json, glb_view.json_size, glb_view.bin_size, nullptr, &json_only),
              lodrt::Result::Ok);
    lodrt::ClusterPackSource ranged;
    ASSERT_EQ(lodrt::clusterPackFind(json_only, 0, &ranged), lodrt::Result::Ok);
    EXPECT_EQ(ranged.table, nullptr);
    EXPECT_EQ(ranged.pages, nullptr);
    EXPECT_EQ(ranged.table_view, source.table_view);
    EXPECT_EQ(std::vector<uint8_t>(glb_view.bin + ranged.table_offset, glb_view.bin + ranged.table_offset + ranged.table_size),
              d.table);
    EXPECT_EQ(std::vector<uint8_t>(glb_view.bin + ranged.pages_offset, glb_view.bin + ranged.pages_offset + ranged.pages_size),
              d.pages);
    // Only LOD0's mesh carries it.
    for (uint32_t m = 1; m < pack.meshCount(); ++m)
        EXPECT_EQ(lodrt::clusterPackFind(pack, m, &source), lodrt::Result::NotLoaded);
}

// schemas/LODBAKE_cluster_lod: the example and a baked pack's object validate against the schema,
// and the example's table and pages open and decode.
std::string validateAgainstSchema(const nlohmann::json& object, const std::string& name) {
    const std::string path = lodbake_test::scratchDir() + "/" + name;
    std::ofstream(path) << object.dump(1);
    const std::string schema =
        lodbake_test::sourceDir() + "/schemas/LODBAKE_cluster_lod/schema/mesh.LODBAKE_cluster_lod.schema.json";
    const lodbake_test::CommandResult r = lodbake_test::runCommand(
        lodbake_test::python() + " " +
        lodbake_test::shellQuote(lodbake_test::sourceDir() + "/tests/support/validate_schema.py") + " " +
        lodbake_test::shellQuote(schema) + " " + lodbake_test::shellQuote(path));
    return r.exit_code == 0 ? std::string() : "exit " + std::to_string(r.exit_code) + ": " + r.output;
}

TEST(ClusterLodPack, SchemaExampleIsValidAndDecodes) {
    auto text = lodbake::readFileBytes(lodbake_test::sourceDir() + "/schemas/LODBAKE_cluster_lod/examples/minimal.gltf");
    ASSERT_TRUE(text.ok());
    const nlohmann::json doc = nlohmann::json::parse(text->begin(), text->end());
    const nlohmann::json& object = doc["meshes"][0]["extensions"][lodrt::format::kExtClusterLod];
    EXPECT_EQ(validateAgainstSchema(object, "cluster_example.json"), "");
    nlohmann::json bad = object;
    bad.erase("pages");
    EXPECT_NE(validateAgainstSchema(bad, "cluster_example_bad.json"), ""); // the validator can refuse
    std::vector<uint8_t> buffer;
    ASSERT_TRUE(lodbake_test::dataUriBytes(doc["buffers"][0]["uri"].get<std::string>(), buffer));
    auto viewBytes = [&](const nlohmann::json& index) {
        const nlohmann::json& view = doc["bufferViews"][index.get<size_t>()];
        const size_t offset = view.value("byteOffset", size_t(0)), length = view["byteLength"].get<size_t>();
        EXPECT_LE(offset + length, buffer.size());
        return std::vector<uint8_t>(buffer.begin() + long(offset), buffer.begin() + long(offset + length));
    };
    Decoded d;
    d.table = viewBytes(object["table"]);
    d.pages = viewBytes(object["pages"]);
    ASSERT_TRUE(openAndDecode(d)) << d.error;
    EXPECT_EQ(d.pack.view.cluster_count, 1u);
    EXPECT_EQ(d.pack.places[0].triangle_count, 4u);
}

// The CLI: --clusters writes the extension, --print-config shows the key, loddump prints the
// hierarchy per depth and its checks pass; without the flag the pack has no extension.
TEST(ClusterLodPack, CliFlagAndLoddumpSummary) {
    const std::string dir = lodbake_test::scratchDir();
    const std::string obj = dir + "/cluster_cli_sphere.obj", with = dir + "/cluster_cli_with.glb",
                      without = dir + "/cluster_cli_without.glb";
    lodbake::Diagnostics diagnostics;
    ASSERT_TRUE(lodbake::writeMesh(bumpySphere(24, 32), obj, lodbake::WriteOptions(), diagnostics).ok());
    lodbake_test::CliRun r = lodbake_test::runLodbake({"bake", obj, "-o", with, "--levels", "0.5", "--clusters", "--quiet"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    r = lodbake_test::runLodbake({"bake", obj, "-o", without, "--levels", "0.5", "--quiet"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    r = lodbake_test::runLodbake({"bake", "--clusters", "--print-config"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(nlohmann::json::parse(r.out)["cluster_lod"].get<bool>());
    const lodbake_test::CommandResult dump =
        lodbake_test::runCommand(lodbake_test::shellQuote(LODBAKE_TEST_LODDUMP) + " " + lodbake_test::shellQuote(with));
    ASSERT_EQ(dump.exit_code, 0) << dump.output;
    EXPECT_NE(dump.output.find("cluster LOD on mesh 0 (LODBAKE_cluster_lod)"), std::string::npos) << dump.output;
    EXPECT_NE(dump.output.find("18 cuts crack-free"), std::string::npos) << dump.output;
    const lodbake_test::CommandResult plain = lodbake_test::runCommand(
        lodbake_test::shellQuote(LODBAKE_TEST_LODDUMP) + " " + lodbake_test::shellQuote(without));
    ASSERT_EQ(plain.exit_code, 0) << plain.output;
    EXPECT_EQ(plain.output.find("cluster LOD"), std::string::npos);

    // --render adds a row of three cuts, each cluster in a palette colour: the row below the chain's
    // shows many colours, where the chain's levels are shaded in one.
    auto render = [&](const std::string& pack, const std::string& png) {
        const lodbake_test::CommandResult rendered =
            lodbake_test::runCommand(lodbake_test::withoutLeakCheck() + lodbake_test::shellQuote(LODBAKE_TEST_LODDUMP) +
                                     " " + lodbake_test::shellQuote(pack) + " --render " + lodbake_test::shellQuote(png));
        EXPECT_EQ(rendered.exit_code, 0) << rendered.output;
        const lodbake::Result<std::vector<uint8_t>> bytes = lodbake::readFileBytes(png);
        EXPECT_TRUE(bytes.ok());
        return lodbake::decodeImage(bytes.ok() ? *bytes : std::vector<uint8_t>(), png);
    };
    const auto with_image = render(with, dir + "/cluster_cli_with.png");
    const auto without_image = render(without, dir + "/cluster_cli_without.png");
    ASSERT_TRUE(with_image.ok() && without_image.ok());
    ASSERT_EQ(with_image->channels, 3u);
    EXPECT_EQ(with_image->height, 2 * without_image->height);
    auto hues = [&](uint32_t y0, uint32_t y1) { // hue buckets of 15 degrees that many saturated pixels fall in
        std::map<int, size_t> pixels;
        for (uint32_t y = y0; y < y1; ++y)
            for (uint32_t x = 0; x < with_image->width; ++x) {
                const uint8_t* p = &with_image->samples[(size_t(y) * with_image->width + x) * 3];
                const int red = p[0], green = p[1], blue = p[2];
                const int hi = std::max({red, green, blue}), lo = std::min({red, green, blue});
                if (hi - lo < 40) continue; // grey: background, labels, the chain's shading
                const double h = hi == red     ? double(green - blue) / (hi - lo)
                                 : hi == green ? 2.0 + double(blue - red) / (hi - lo)
                                               : 4.0 + double(red - green) / (hi - lo);
                ++pixels[int(std::floor((h < 0 ? h + 6 : h) * 4))];
            }
        size_t buckets = 0;
        for (const auto& bucket : pixels) buckets += bucket.second >= 200 ? 1 : 0;
        return buckets;
    };
    const uint32_t half = with_image->height / 2;
    EXPECT_LE(hues(0, half), 1u);
    EXPECT_GE(hues(half, with_image->height), 6u);
}

} // namespace
