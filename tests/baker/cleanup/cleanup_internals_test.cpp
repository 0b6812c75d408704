// The linear-time internals of the cleanup module (edge table, weld maps by hashing, topology counts
// from the edge table, duplicate grouping, the bake's lazily validated repair) against the plain
// sort-based definitions they replaced, on random meshes built to hit every branch (repeated ids,
// duplicates in both windings, edges with many faces, high-valence vertices, -0/+0 and NaN
// positions) and on a shared scan.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <random>

#include "cleanup/mesh_edit.h"
#include "core/parallel.h"
#include "cleanup_builders.h"
#include "lodbake/cleanup/passes.h"
#include "lodbake/cleanup/repair.h"
#include "lodbake/cleanup/topology.h"
#include "lodbake/cleanup/validate.h"
#include "lodbake/core/hash.h"
#include "lodbake/io/mesh_io.h"
#include "test_paths.h"

using namespace lodbake;
using namespace lodbake::cleanup_detail;

namespace {

// ---- reference definitions (sort everything) ------------------------------------------------------

EdgeTable referenceEdgeTable(const Mesh& m) {
    std::vector<std::pair<uint64_t, uint32_t>> half; // (key, corner)
    for (size_t f = 0; f < m.faceCount(); ++f) {
        if (hasRepeatedIndex(m, f)) continue;
        for (uint32_t k = 0; k < 3; ++k) {
            const uint32_t c = uint32_t(3 * f + k);
            half.push_back({edgeKey(halfStart(m, c), halfEnd(m, c)), c});
        }
    }
    std::sort(half.begin(), half.end());
    EdgeTable t;
    t.corner_edge.assign(m.indices.size(), kNone);
    for (size_t i = 0; i < half.size(); ++i) {
        if (i == 0 || half[i].first != half[i - 1].first) {
            t.keys.push_back(half[i].first);
            t.begin.push_back(uint32_t(i));
        }
        t.corners.push_back(half[i].second);
        t.corner_edge[half[i].second] = uint32_t(t.keys.size() - 1);
    }
    t.begin.push_back(uint32_t(half.size()));
    return t;
}

// Lowest vertex with an equal position, by a quadratic scan; `bitwise` compares the bit patterns.
std::vector<uint32_t> quadraticWeldMap(const Mesh& m, bool bitwise) {
    std::vector<uint32_t> rep(m.vertexCount());
    for (uint32_t v = 0; v < rep.size(); ++v) {
        rep[v] = v;
        for (uint32_t u = 0; u < v; ++u) {
            const bool equal = bitwise ? std::memcmp(&m.positions[u], &m.positions[v], sizeof(Vec3f)) == 0
                                       : m.positions[u] == m.positions[v];
            if (equal) {
                rep[v] = u;
                break;
            }
        }
    }
    return rep;
}

// The weld maps as first written: vertices sorted by position (as floats, or as bits), each run of
// equal positions mapped to its first. With a NaN the float order is not a strict weak order, so a
// run may be broken up; positionWeldMap keeps exactly this definition for such meshes.
std::vector<uint32_t> referenceWeldMap(const Mesh& m, bool bitwise) {
    if (bitwise) return quadraticWeldMap(m, true);
    const uint32_t n = uint32_t(m.vertexCount());
    std::vector<uint32_t> order(n), rep(n);
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
        const Vec3f& p = m.positions[a];
        const Vec3f& q = m.positions[b];
        if (p.x != q.x) return p.x < q.x;
        if (p.y != q.y) return p.y < q.y;
        if (p.z != q.z) return p.z < q.z;
        return a < b;
    });
    for (uint32_t i = 0; i < n; ++i)
        rep[order[i]] = (i > 0 && m.positions[order[i]] == m.positions[order[i - 1]]) ? rep[order[i - 1]] : order[i];
    return rep;
}

bool hasNan(const Mesh& m) {
    for (const Vec3f& p : m.positions)
        if (std::isnan(p.x) || std::isnan(p.y) || std::isnan(p.z)) return true;
    return false;
}

// computeTopologyStats as first written: every half-edge sorted by (lo, hi, face, corner).
TopologyStats referenceTopologyStats(const Mesh& mesh, bool weld_by_position) {
    TopologyStats s;
    const size_t n = mesh.vertexCount();
    const size_t face_count = mesh.faceCount();
    std::vector<uint32_t> remap;
    if (weld_by_position) remap = referenceWeldMap(mesh, true);
    auto vid = [&](size_t c) { return remap.empty() ? mesh.indices[c] : remap[mesh.indices[c]]; };
    s.face_count = face_count;
    for (const Vec3f& p : mesh.positions) s.non_finite_vertex_count += !isFinite(p);
    std::vector<uint8_t> referenced(n, 0);
    for (size_t c = 0; c < mesh.indices.size(); ++c) referenced[vid(c)] = 1;
    uint64_t distinct = 0;
    for (size_t v = 0; v < n; ++v) distinct += remap.empty() || remap[v] == v;
    s.vertex_count = distinct;
    s.referenced_vertex_count = uint64_t(std::count(referenced.begin(), referenced.end(), uint8_t(1)));
    s.unreferenced_vertex_count = distinct - s.referenced_vertex_count;
    std::vector<uint8_t> repeated(face_count, 0);
    std::vector<std::array<uint32_t, 4>> keys;
    for (size_t f = 0; f < face_count; ++f) {
        const uint32_t a = vid(3 * f), b = vid(3 * f + 1), c = vid(3 * f + 2);
        repeated[f] = a == b || b == c || a == c;
        bool zero_area = false;
        if (!repeated[f]) {
            const Vec3d pa = toDouble(mesh.positions[a]);
            const Vec3d e = cross(toDouble(mesh.positions[b]) - pa, toDouble(mesh.positions[c]) - pa);
            zero_area = dot(e, e) == 0.0;
        }
        s.degenerate_face_count += repeated[f] || zero_area;
        std::array<uint32_t, 4> k = {a, b, c, uint32_t(f)};
        std::sort(k.begin(), k.begin() + 3);
        keys.push_back(k);
    }
    std::sort(keys.begin(), keys.end());
    for (size_t i = 1; i < keys.size(); ++i)
        s.duplicate_face_count +=
            keys[i][0] == keys[i - 1][0] && keys[i][1] == keys[i - 1][1] && keys[i][2] == keys[i - 1][2];
    struct Half {
        uint32_t lo, hi, face, corner;
        bool forward;
    };
    std::vector<Half> half;
    for (size_t f = 0; f < face_count; ++f) {
        if (repeated[f]) continue;
        for (uint32_t k = 0; k < 3; ++k) {
            const uint32_t a = vid(3 * f + k), b = vid(3 * f + (k + 1) % 3);
            half.push_back({std::min(a, b), std::max(a, b), uint32_t(f), k, a < b});
        }
    }
    std::sort(half.begin(), half.end(), [](const Half& x, const Half& y) {
        return std::tie(x.lo, x.hi, x.face, x.corner) < std::tie(y.lo, y.hi, y.face, y.corner);
    });
    UnionFind fans(face_count * 3);
    std::vector<uint8_t> on_nonmanifold_edge(n, 0);
    std::vector<std::pair<uint32_t, uint32_t>> boundary;
    for (size_t i = 0; i < half.size();) {
        size_t j = i;
        while (j < half.size() && half[j].lo == half[i].lo && half[j].hi == half[i].hi) ++j;
        ++s.edge_count;
        if (j - i == 1) {
            ++s.boundary_edge_count;
            const Half& h = half[i];
            boundary.push_back(h.forward ? std::make_pair(h.lo, h.hi) : std::make_pair(h.hi, h.lo));
        } else if (j - i == 2) {
            const Half& h0 = half[i];
            const Half& h1 = half[i + 1];
            if (h0.forward == h1.forward) ++s.inconsistent_edge_count;
            for (uint32_t v : {h0.lo, h0.hi}) {
                uint32_t c0 = 0, c1 = 0;
                for (uint32_t k = 0; k < 3; ++k) {
                    if (vid(3 * size_t(h0.face) + k) == v) c0 = 3 * h0.face + k;
                    if (vid(3 * size_t(h1.face) + k) == v) c1 = 3 * h1.face + k;
                }
                fans.unite(c0, c1);
            }
        } else {
            ++s.non_manifold_edge_count;
            on_nonmanifold_edge[half[i].lo] = on_nonmanifold_edge[half[i].hi] = 1;
        }
        i = j;
    }
    std::vector<uint32_t> first_fan(n, UINT32_MAX);
    std::vector<uint8_t> multi_fan(n, 0);
    for (size_t f = 0; f < face_count; ++f) {
        if (repeated[f]) continue;
        for (uint32_t k = 0; k < 3; ++k) {
            const uint32_t c = uint32_t(3 * f + k), v = vid(c);
            const uint32_t root = fans.find(c);
            if (first_fan[v] == UINT32_MAX) first_fan[v] = root;
            else if (first_fan[v] != root) multi_fan[v] = 1;
        }
    }
    for (size_t v = 0; v < n; ++v) s.non_manifold_vertex_count += multi_fan[v] || on_nonmanifold_edge[v];
    std::sort(boundary.begin(), boundary.end());
    std::vector<uint8_t> used(boundary.size(), 0);
    auto next_from = [&](uint32_t v) -> size_t {
        for (size_t i = 0; i < boundary.size(); ++i)
            if (boundary[i].first == v && !used[i]) return i;
        return SIZE_MAX;
    };
    for (size_t e = 0; e < boundary.size(); ++e) {
        if (used[e]) continue;
        ++s.boundary_loop_count;
        const uint32_t start = boundary[e].first;
        size_t cur = e;
        while (cur != SIZE_MAX) {
            used[cur] = 1;
            if (boundary[cur].second == start) break;
            cur = next_from(boundary[cur].second);
        }
    }
    UnionFind comps(n);
    for (size_t f = 0; f < face_count; ++f) {
        comps.unite(vid(3 * f), vid(3 * f + 1));
        comps.unite(vid(3 * f), vid(3 * f + 2));
    }
    for (size_t v = 0; v < n; ++v) s.component_count += referenced[v] && comps.find(uint32_t(v)) == v;
    s.euler_characteristic = int64_t(s.referenced_vertex_count) - int64_t(s.edge_count) +
                             int64_t(face_count - std::count(repeated.begin(), repeated.end(), uint8_t(1)));
    return s;
}

// validate() as first written: the counts above, then loops and components on a float-welded copy.
ValidationReport referenceValidate(const Mesh& input, bool weld_by_position) {
    ValidationReport r;
    r.topology = referenceTopologyStats(input, weld_by_position);
    Mesh m;
    m.positions = input.positions;
    m.indices = input.indices;
    if (weld_by_position) {
        const std::vector<uint32_t> rep = referenceWeldMap(input, false);
        for (uint32_t& i : m.indices) i = rep[i];
    }
    const EdgeTable table = referenceEdgeTable(m);
    for (const BoundaryLoop& loop : findBoundaryLoops(m, table)) {
        r.boundary_loop_lengths.push_back(uint32_t(loop.vertices.size()));
        r.open_boundary_chains += !loop.closed;
    }
    std::sort(r.boundary_loop_lengths.begin(), r.boundary_loop_lengths.end(), std::greater<uint32_t>());
    UnionFind comps(m.vertexCount());
    for (size_t f = 0; f < m.faceCount(); ++f) {
        comps.unite(m.indices[3 * f], m.indices[3 * f + 1]);
        comps.unite(m.indices[3 * f], m.indices[3 * f + 2]);
    }
    std::vector<uint32_t> faces_of_root(m.vertexCount(), 0);
    for (size_t f = 0; f < m.faceCount(); ++f) ++faces_of_root[comps.find(m.indices[3 * f])];
    for (uint32_t c : faces_of_root)
        if (c) r.component_face_counts.push_back(c);
    std::sort(r.component_face_counts.begin(), r.component_face_counts.end(), std::greater<uint32_t>());
    return r;
}

// ---- inputs ------------------------------------------------------------------------------------------

// A random triangle soup over few vertices on a coarse grid: repeated ids, duplicate faces (both
// windings), edges with many faces, equal positions (and, when `signed_zero`, -0 beside +0 and a NaN).
Mesh randomMesh(uint32_t seed, bool signed_zero) {
    std::mt19937 rng(seed);
    const uint32_t n = 4 + rng() % 40;
    Mesh m;
    for (uint32_t v = 0; v < n; ++v) {
        auto coord = [&] { return float(int(rng() % 3) - 1); };
        Vec3f p(coord(), coord(), coord());
        if (signed_zero && rng() % 4 == 0) p.x = p.x == 0.0f ? -0.0f : p.x;
        m.positions.push_back(p);
    }
    if (signed_zero && rng() % 2) m.positions[rng() % n].y = std::numeric_limits<float>::quiet_NaN();
    const uint32_t faces = 1 + rng() % (3 * n);
    for (uint32_t f = 0; f < faces; ++f) {
        const uint32_t pick = rng() % 10;
        if (pick == 0 && f > 0) { // a duplicate of an earlier face, either winding
            const uint32_t g = rng() % f;
            const uint32_t a = m.indices[3 * g], b = m.indices[3 * g + 1], c = m.indices[3 * g + 2];
            if (rng() % 2) m.indices.insert(m.indices.end(), {b, c, a});
            else m.indices.insert(m.indices.end(), {a, c, b});
        } else if (pick == 1) { // a repeated id
            const uint32_t a = rng() % n, b = rng() % n;
            m.indices.insert(m.indices.end(), {a, a, b});
        } else {
            m.indices.insert(m.indices.end(), {uint32_t(rng() % n), uint32_t(rng() % n), uint32_t(rng() % n)});
        }
    }
    return m;
}

// A fan of `count` triangles around vertex 0: its bucket in the edge table is long (> 64 half-edges).
Mesh wideFan(uint32_t count) {
    Mesh m;
    m.positions.push_back({0, 0, 0});
    for (uint32_t i = 0; i <= count; ++i) {
        const double a = 2 * M_PI * i / (count + 1);
        m.positions.push_back({float(std::cos(a)), float(std::sin(a)), 0});
    }
    for (uint32_t i = 1; i <= count; ++i) m.indices.insert(m.indices.end(), {0, i, i % (count + 1) + 1});
    return m;
}

void expectSameTable(const EdgeTable& a, const EdgeTable& b) {
    EXPECT_EQ(a.keys, b.keys);
    EXPECT_EQ(a.begin, b.begin);
    EXPECT_EQ(a.corners, b.corners);
    EXPECT_EQ(a.corner_edge, b.corner_edge);
}

void expectSameStats(const TopologyStats& a, const TopologyStats& b, const std::string& what) {
    SCOPED_TRACE(what);
    EXPECT_EQ(a.vertex_count, b.vertex_count);
    EXPECT_EQ(a.face_count, b.face_count);
    EXPECT_EQ(a.referenced_vertex_count, b.referenced_vertex_count);
    EXPECT_EQ(a.unreferenced_vertex_count, b.unreferenced_vertex_count);
    EXPECT_EQ(a.edge_count, b.edge_count);
    EXPECT_EQ(a.boundary_edge_count, b.boundary_edge_count);
    EXPECT_EQ(a.boundary_loop_count, b.boundary_loop_count);
    EXPECT_EQ(a.non_manifold_edge_count, b.non_manifold_edge_count);
    EXPECT_EQ(a.non_manifold_vertex_count, b.non_manifold_vertex_count);
    EXPECT_EQ(a.inconsistent_edge_count, b.inconsistent_edge_count);
    EXPECT_EQ(a.component_count, b.component_count);
    EXPECT_EQ(a.degenerate_face_count, b.degenerate_face_count);
    EXPECT_EQ(a.duplicate_face_count, b.duplicate_face_count);
    EXPECT_EQ(a.non_finite_vertex_count, b.non_finite_vertex_count);
    EXPECT_EQ(a.euler_characteristic, b.euler_characteristic);
}

void expectSameValidation(const ValidationReport& a, const ValidationReport& b, const std::string& what) {
    expectSameStats(a.topology, b.topology, what);
    EXPECT_EQ(a.boundary_loop_lengths, b.boundary_loop_lengths) << what;
    EXPECT_EQ(a.open_boundary_chains, b.open_boundary_chains) << what;
    EXPECT_EQ(a.component_face_counts, b.component_face_counts) << what;
}

} // namespace

TEST(CleanupInternalsTest, EdgeTableMatchesGlobalSort) {
    for (uint32_t seed = 0; seed < 200; ++seed) {
        const Mesh m = randomMesh(seed, false);
        SCOPED_TRACE(seed);
        expectSameTable(buildEdgeTable(m), referenceEdgeTable(m));
    }
    // Long buckets: insertion sort up to 32 entries, std::sort above, the spill buffer above 64.
    for (uint32_t count : {20u, 40u, 100u}) {
        Mesh m = wideFan(count);
        std::reverse(m.indices.begin(), m.indices.end()); // corners out of order within the bucket
        expectSameTable(buildEdgeTable(m), referenceEdgeTable(m));
    }
    const Mesh empty;
    EXPECT_EQ(buildEdgeTable(empty).edgeCount(), 0u);
    EXPECT_EQ(buildEdgeTable(empty).begin, detail::LargeArray<uint32_t>{0});
}

TEST(CleanupInternalsTest, WeldMapsMatchQuadraticScan) {
    int with_nan = 0;
    for (uint32_t seed = 0; seed < 200; ++seed) {
        const Mesh m = randomMesh(seed, true);
        SCOPED_TRACE(seed);
        EXPECT_EQ(bitwiseWeldMap(m), quadraticWeldMap(m, true));
        EXPECT_EQ(positionWeldMap(m), referenceWeldMap(m, false));
        if (hasNan(m)) {
            ++with_nan;
            continue;
        }
        EXPECT_EQ(positionWeldMap(m), quadraticWeldMap(m, false)); // the hashing path: lowest equal position
    }
    EXPECT_GT(with_nan, 20);
    // -0 welds to +0 by value, not by bits; identical NaN bits weld only bitwise.
    const float nan = std::numeric_limits<float>::quiet_NaN();
    Mesh m;
    m.positions = {{0, 1, 2}, {-0.0f, 1, 2}, {3, 0, 0}, {0, 1, 2}};
    EXPECT_EQ(positionWeldMap(m), (std::vector<uint32_t>{0, 0, 2, 0}));
    EXPECT_EQ(bitwiseWeldMap(m), (std::vector<uint32_t>{0, 1, 2, 0}));
    m.positions.push_back({nan, 0, 0});
    m.positions.push_back({nan, 0, 0});
    EXPECT_EQ(bitwiseWeldMap(m), (std::vector<uint32_t>{0, 1, 2, 0, 4, 4}));
    const std::vector<uint32_t> by_value = positionWeldMap(m);
    EXPECT_EQ(by_value[4], 4u);
    EXPECT_EQ(by_value[5], 5u);
}

TEST(CleanupInternalsTest, LowestEqualKeyKeepsFirstOccurrence) {
    std::vector<std::array<uint32_t, 3>> keys;
    std::mt19937 rng(7);
    for (int i = 0; i < 5000; ++i) keys.push_back({uint32_t(rng() % 4), uint32_t(rng() % 4), uint32_t(rng() % 4)});
    const std::vector<uint32_t> rep = lowestEqualKey(uint32_t(keys.size()), [&](uint32_t i) { return keys[i]; });
    for (uint32_t i = 0; i < keys.size(); ++i) {
        const uint32_t first = uint32_t(std::find(keys.begin(), keys.end(), keys[i]) - keys.begin());
        ASSERT_EQ(rep[i], first) << i;
    }
}

TEST(CleanupInternalsTest, TopologyStatsMatchSortedHalfEdges) {
    for (uint32_t seed = 0; seed < 300; ++seed) {
        const Mesh m = randomMesh(seed, seed % 3 == 0);
        TopologyOptions welded;
        welded.weld_by_position = true;
        expectSameStats(computeTopologyStats(m), referenceTopologyStats(m, false), "seed " + std::to_string(seed));
        expectSameStats(computeTopologyStats(m, welded), referenceTopologyStats(m, true),
                        "welded, seed " + std::to_string(seed));
    }
}

TEST(CleanupInternalsTest, ValidateMatchesSeparatePasses) {
    for (uint32_t seed = 0; seed < 300; ++seed) {
        const Mesh m = randomMesh(seed, seed % 3 == 0);
        ValidateOptions welded;
        welded.weld_by_position = true;
        expectSameValidation(validate(m), referenceValidate(m, false), "seed " + std::to_string(seed));
        expectSameValidation(validate(m, welded), referenceValidate(m, true), "welded, seed " + std::to_string(seed));
        EdgeTable table;
        validateWithTable(m, {}, &table);
        expectSameTable(table, referenceEdgeTable(m));
    }
}

TEST(CleanupInternalsTest, DuplicateFacesKeepTheEarliest) {
    for (uint32_t seed = 0; seed < 130; ++seed) {
        Mesh m = randomMesh(seed, false);
        if (seed >= 100) {
            // A wide fan (over 16 faces grouped at vertex 0) with copies of some of its faces.
            m = wideFan(20 + seed % 60);
            std::mt19937 rng(seed);
            const size_t faces = m.faceCount();
            for (size_t i = 0; i < faces; ++i) {
                const size_t g = rng() % faces;
                const uint32_t a = m.indices[3 * g], b = m.indices[3 * g + 1], c = m.indices[3 * g + 2];
                if (rng() % 3 == 0) m.indices.insert(m.indices.end(), {c, b, a});
            }
        }
        // Expected: of the faces that pass the other tests, the first of each vertex set stays.
        std::vector<std::array<uint32_t, 3>> expected;
        std::vector<std::array<uint32_t, 3>> seen;
        for (size_t f = 0; f < m.faceCount(); ++f) {
            if (hasRepeatedIndex(m, f)) continue;
            const Vec3d nn = faceNormal(m, f);
            if (dot(nn, nn) == 0.0) continue;
            std::array<uint32_t, 3> k = {m.indices[3 * f], m.indices[3 * f + 1], m.indices[3 * f + 2]};
            std::array<uint32_t, 3> sorted = k;
            std::sort(sorted.begin(), sorted.end());
            if (std::find(seen.begin(), seen.end(), sorted) != seen.end()) continue;
            seen.push_back(sorted);
            expected.push_back(k);
        }
        removeDegenerateFaces(m);
        ASSERT_EQ(m.faceCount(), expected.size()) << seed;
        for (size_t f = 0; f < expected.size(); ++f)
            EXPECT_EQ((std::array<uint32_t, 3>{m.indices[3 * f], m.indices[3 * f + 1], m.indices[3 * f + 2]}),
                      expected[f]);
    }
}

TEST(CleanupInternalsTest, ManifoldLeavesNoOverusedEdge) {
    // The re-check after the first vertex split is skipped when no edge can be over-used: whenever it
    // was needed, the faces it removes must be gone.
    int overused_inputs = 0;
    for (uint32_t seed = 0; seed < 400; ++seed) {
        Mesh m = randomMesh(seed, false);
        removeDegenerateFaces(m);
        overused_inputs += computeTopologyStats(m).non_manifold_edge_count != 0;
        makeManifold(m);
        EXPECT_EQ(computeTopologyStats(m).non_manifold_edge_count, 0u) << seed;
    }
    EXPECT_GT(overused_inputs, 100); // the inputs do exercise the pass
}

TEST(CleanupInternalsTest, SplitJoinsFromTableMatchListedJoins) {
    // The 2-use edges read from the table, or listed as joins: the same split.
    int split = 0;
    for (uint32_t seed = 0; seed < 300; ++seed) {
        Mesh listed = randomMesh(seed, false);
        removeDegenerateFaces(listed);
        Mesh from_table = listed;
        const EdgeTable table = buildEdgeTable(listed);
        std::vector<CornerPair> joins, extra;
        for (uint32_t e = 0; e < table.edgeCount(); ++e) {
            const uint32_t* c = &table.corners[table.begin[e]];
            if (table.uses(e) == 2) joins.push_back({c[0], c[1]});
            if (table.uses(e) == 4) { // some pairs beside the table, as the manifold pass adds them
                joins.push_back({c[0], c[3]});
                extra.push_back({c[0], c[3]});
            }
        }
        size_t added_listed = 0, added_table = 0;
        const size_t a = splitVerticesByFans(listed, joins, added_listed);
        const size_t b = splitVerticesByFans(from_table, extra, added_table, &table);
        SCOPED_TRACE(seed);
        EXPECT_EQ(a, b);
        EXPECT_EQ(added_listed, added_table);
        EXPECT_EQ(hashMesh(listed), hashMesh(from_table));
        split += a != 0;
    }
    EXPECT_GT(split, 50);
}

TEST(CleanupInternalsTest, ManifoldLocalRecheckMatchesWholeMesh) {
    // The cut mode re-checks only the edges that can still be over-used and re-splits only the
    // vertices of removed faces; the whole-mesh re-check (edge tables of the whole mesh, every
    // vertex re-split) must give the same mesh and counters.
    int rounds_run = 0;
    for (uint32_t seed = 0; seed < 3000; ++seed) {
        // Few vertices and many faces: edges with several faces that the first split cannot free.
        std::mt19937 rng(seed);
        const uint32_t n = 4 + rng() % 8;
        Mesh m;
        for (uint32_t v = 0; v < n; ++v)
            m.positions.push_back(Vec3f(float(rng() % 5), float(rng() % 5), float(rng() % 5)));
        const uint32_t faces = 2 + rng() % (2 * n);
        for (uint32_t f = 0; f < faces; ++f)
            m.indices.insert(m.indices.end(), {uint32_t(rng() % n), uint32_t(rng() % n), uint32_t(rng() % n)});
        removeDegenerateFaces(m);
        if (seed % 2) m.uvs.push_back(std::vector<Vec2f>(m.vertexCount(), Vec2f(0.25f * float(seed % 4), 0.5f)));
        Mesh whole = m;
        Scratch s1, s2;
        const ManifoldReport a = makeManifold(m, ManifoldOptions(), s1);
        const ManifoldReport b = makeManifold(whole, ManifoldOptions(), s2, true);
        SCOPED_TRACE(seed);
        EXPECT_EQ(m.indices, whole.indices);
        EXPECT_EQ(hashMesh(m), hashMesh(whole));
        EXPECT_EQ(a.counters(), b.counters());
        rounds_run += b.faces_removed != 0;
    }
    EXPECT_GT(rounds_run, 50); // the inputs do reach the re-check rounds
}

namespace {
void expectSameRepair(const Mesh& input, const std::string& what) {
    SCOPED_TRACE(what);
    Mesh reported = input, lazy = input;
    Diagnostics d1, d2;
    RepairOptions lazy_options;
    lazy_options.report_before = false;
    lazy_options.report_welded = false;
    Result<RepairReport> a = repairMesh(reported, RepairOptions(), "a", d1);
    Result<RepairReport> b = repairMesh(lazy, lazy_options, "a", d2);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(hashMesh(reported), hashMesh(lazy));
    expectSameValidation(a->after, b->after, "after");
    ASSERT_EQ(a->passes.size(), b->passes.size());
    for (size_t i = 0; i < a->passes.size(); ++i) {
        EXPECT_EQ(a->passes[i].name, b->passes[i].name);
        EXPECT_EQ(a->passes[i].counters, b->passes[i].counters) << a->passes[i].name;
        EXPECT_EQ(a->passes[i].notes, b->passes[i].notes) << a->passes[i].name;
    }
    EXPECT_EQ(a->unresolved, b->unresolved);
    EXPECT_EQ(b->before.topology.face_count, 0u); // not reported
    EXPECT_TRUE(b->before.component_face_counts.empty());
}
} // namespace

TEST(CleanupInternalsTest, RepairWithoutBeforeReportChangesNothingElse) {
    for (uint32_t seed = 0; seed < 60; ++seed) expectSameRepair(randomMesh(seed, false), "seed " + std::to_string(seed));
    // Clean inputs take the skip paths, which then need the (lazily computed) input report.
    expectSameRepair(lodbake_test::uvSphere(8, 12), "sphere");
    expectSameRepair(lodbake_test::hemisphere(4, 12), "hemisphere");
    LODBAKE_REQUIRE_SHARED_MESHES();
    Diagnostics d;
    Result<LoadedMesh> bunny = readMesh(lodbake_test::sharedMesh("bunny_zipper.ply"), ReadOptions(), d);
    ASSERT_TRUE(bunny.ok());
    expectSameRepair(bunny->mesh, "bunny_zipper");
}

TEST(CleanupInternalsTest, ScanCountsMatchReference) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    Diagnostics d;
    Result<LoadedMesh> bunny = readMesh(lodbake_test::sharedMesh("bunny_zipper.ply"), ReadOptions(), d);
    ASSERT_TRUE(bunny.ok());
    const Mesh& m = bunny->mesh;
    const EdgeTable reference = referenceEdgeTable(m);
    for (size_t threads : {1, 2, 4}) { // the table is built in chunks of vertices, in parallel
        ScopedThreadLimit limit(threads);
        SCOPED_TRACE(threads);
        expectSameTable(buildEdgeTable(m), reference);
    }
    expectSameStats(computeTopologyStats(m), referenceTopologyStats(m, false), "bunny");
    const ValidationReport v = validate(m);
    expectSameValidation(v, referenceValidate(m, false), "bunny");
    EXPECT_EQ(v.topology.boundary_edge_count, 223u); // README: 223 boundary edges
    EXPECT_EQ(v.topology.unreferenced_vertex_count, 1113u);
}
