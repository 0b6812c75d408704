#pragma once
// The crack-free check of cluster LOD cuts, shared by the cluster LOD tests, the out-of-core
// partition tests and cluster_bench (no gtest here): for a cut, the boundary edges (by position)
// that LOD0 lacks.

#include <algorithm>
#include <array>
#include <cstring>
#include <iterator>
#include <string>
#include <unordered_map>
#include <vector>

#include "lodbake/cluster/cluster_lod.h"
#include "lodbake/core/mesh.h"
#include "lodrt/cluster_lod.h"

namespace lodbake_test {

using lodbake::ClusterLodHierarchy;
using lodbake::Mesh;
using lodbake::Vec3f;

struct PositionBitsHash {
    size_t operator()(const std::array<uint32_t, 3>& k) const {
        uint64_t h = (uint64_t(k[0]) * 0x9e3779b97f4a7c15ull) ^ (uint64_t(k[1]) * 0xc2b2ae3d27d4eb4full) ^ k[2];
        return size_t(h ^ (h >> 29));
    }
};

struct PositionIds {
    std::unordered_map<std::array<uint32_t, 3>, uint32_t, PositionBitsHash> ids;
    uint32_t of(const Vec3f& p) {
        std::array<uint32_t, 3> k;
        const float v[3] = {p.x + 0.0f, p.y + 0.0f, p.z + 0.0f};
        std::memcpy(k.data(), v, 12);
        return ids.emplace(k, uint32_t(ids.size())).first->second;
    }
};

using Edge = uint64_t;
inline Edge edgeOf(uint32_t a, uint32_t b) {
    return uint64_t(std::min(a, b)) << 32 | std::max(a, b);
}

// Edges used once in a list of edges (each triangle edge listed once per use).
inline std::vector<Edge> singleEdges(std::vector<Edge> edges) {
    std::sort(edges.begin(), edges.end());
    std::vector<Edge> out;
    for (size_t i = 0; i < edges.size();) {
        size_t j = i;
        while (j < edges.size() && edges[j] == edges[i]) ++j;
        if (j - i == 1) out.push_back(edges[i]);
        i = j;
    }
    return out;
}

// Edges by position of LOD0 and of every cluster (each use), computed once; a cut's boundary is
// the edges its clusters use once in all.
class CrackChecker {
public:
    /// Groups whose outputs' boundary (by position) differs from their inputs': the border a group
    /// shares with its neighbours must survive its simplification unchanged.
    std::string groupBorderMismatch() const {
        std::vector<std::vector<uint32_t>> outputs(h_.groups.size());
        for (uint32_t c = 0; c < h_.clusters.size(); ++c)
            if (h_.clusters[c].self_group != lodrt::kClusterNone) outputs[h_.clusters[c].self_group].push_back(c);
        for (size_t g = 0; g < h_.groups.size(); ++g) {
            std::vector<Edge> in, out;
            for (uint32_t i = 0; i < h_.groups[g].child_count; ++i) {
                const auto& e = cluster_edges_[h_.group_children[h_.groups[g].first_child + i]];
                in.insert(in.end(), e.begin(), e.end());
            }
            for (uint32_t c : outputs[g]) out.insert(out.end(), cluster_edges_[c].begin(), cluster_edges_[c].end());
            const std::vector<Edge> a = singleEdges(in), b = singleEdges(out);
            if (a != b) {
                std::vector<Edge> only_out;
                std::set_difference(b.begin(), b.end(), a.begin(), a.end(), std::back_inserter(only_out));
                return "group " + std::to_string(g) + ": inputs' border " + std::to_string(a.size()) +
                       " edges, outputs' " + std::to_string(b.size()) + ", " + std::to_string(only_out.size()) +
                       " only in the outputs";
            }
        }
        return "";
    }

    CrackChecker(const Mesh& lod0, const ClusterLodHierarchy& h) : h_(h) {
        std::vector<Edge> edges;
        for (size_t f = 0; f < lod0.faceCount(); ++f) {
            uint32_t t[3];
            for (int k = 0; k < 3; ++k) t[k] = ids_.of(lod0.positions[lod0.indices[f * 3 + k]]);
            if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue; // the builder drops these too
            for (int k = 0; k < 3; ++k) edges.push_back(edgeOf(t[k], t[(k + 1) % 3]));
        }
        lod0_boundary_ = singleEdges(edges);
        cluster_edges_.resize(h.clusters.size());
        for (size_t c = 0; c < h.clusters.size(); ++c) {
            const auto& cl = h.clusters[c];
            std::vector<Edge> e;
            for (uint32_t t = 0; t < cl.triangle_count; ++t) {
                uint32_t v[3];
                for (int k = 0; k < 3; ++k)
                    v[k] = ids_.of(h.positions[cl.first_vertex + h.indices[(size_t(cl.first_triangle) + t) * 3 + k]]);
                for (int k = 0; k < 3; ++k) e.push_back(edgeOf(v[k], v[(k + 1) % 3]));
            }
            // Every use, not only the cluster's single edges: an edge of more than two triangles
            // (non-manifold spots the simplifier leaves alone) may be spread over several clusters.
            std::sort(e.begin(), e.end());
            cluster_edges_[c] = std::move(e);
        }
        indexSharedEdges();
    }

    /// Boundary edges of the cut (edges its clusters use once in all) that LOD0 lacks.
    size_t cracks(const uint32_t* cut, size_t count, std::string* first = nullptr) {
        for (size_t i = 0; i < count; ++i)
            for (const Entry& e : entries_[cut[i]]) count_[e.edge] += e.uses;
        size_t bad = 0;
        for (size_t i = 0; i < count; ++i)
            for (const Entry& e : entries_[cut[i]])
                if (count_[e.edge] == 1 && !on_lod0_boundary_[e.edge]) {
                    if (bad++ == 0 && first) *first = describe(edge_key_[e.edge], cut, count);
                }
        for (size_t i = 0; i < count; ++i)
            for (const Entry& e : entries_[cut[i]]) count_[e.edge] = 0;
        return bad;
    }

private:
    // Only an edge that some cluster does not use exactly twice can be on a cut's boundary: each
    // cluster keeps those edges with its number of uses, and a cut adds them up in a counter per
    // edge (a sort of every edge of every cut is far slower).
    void indexSharedEdges() {
        std::vector<std::pair<Edge, uint32_t>> uses;
        for (uint32_t c = 0; c < cluster_edges_.size(); ++c)
            for (Edge e : cluster_edges_[c]) uses.push_back({e, c});
        std::sort(uses.begin(), uses.end());
        entries_.resize(cluster_edges_.size());
        for (size_t i = 0; i < uses.size();) {
            size_t j = i;
            while (j < uses.size() && uses[j].first == uses[i].first) ++j;
            // An edge every cluster uses exactly twice adds up to an even count in any cut: never on
            // its boundary. Otherwise every use counts.
            bool odd_somewhere = false;
            for (size_t a = i; a < j;) {
                size_t b = a;
                while (b < j && uses[b].second == uses[a].second) ++b;
                odd_somewhere |= b - a != 2;
                a = b;
            }
            bool kept = false;
            for (size_t a = i; a < j;) {
                size_t b = a;
                while (b < j && uses[b].second == uses[a].second) ++b;
                if (odd_somewhere) {
                    entries_[uses[a].second].push_back({uint32_t(edge_key_.size()), uint32_t(b - a)});
                    kept = true;
                }
                a = b;
            }
            if (kept) {
                edge_key_.push_back(uses[i].first);
                on_lod0_boundary_.push_back(
                    std::binary_search(lod0_boundary_.begin(), lod0_boundary_.end(), uses[i].first));
            }
            i = j;
        }
        count_.assign(edge_key_.size(), 0);
    }

    struct Entry {
        uint32_t edge; // into edge_key_
        uint32_t uses;
    };

    // The clusters of the cut whose single edges hold the edge, with their groups: what a failure
    // needs to be understood.
    std::string describe(Edge x, const uint32_t* cut, size_t count) const {
        std::string s = "edge points " + std::to_string(x >> 32) + "-" + std::to_string(x & 0xffffffffu) + ":";
        for (size_t i = 0; i < count; ++i)
            if (std::binary_search(cluster_edges_[cut[i]].begin(), cluster_edges_[cut[i]].end(), x)) {
                const auto& cl = h_.clusters[cut[i]];
                s += " cluster " + std::to_string(cut[i]) + " self " + std::to_string(int(cl.self_group)) + " parent " +
                     std::to_string(int(cl.parent_group));
            }
        return s;
    }

public:
private:
    const ClusterLodHierarchy& h_;
    PositionIds ids_;
    std::vector<Edge> lod0_boundary_;
    std::vector<std::vector<Edge>> cluster_edges_;
    std::vector<std::vector<Entry>> entries_;
    std::vector<Edge> edge_key_;
    std::vector<uint8_t> on_lod0_boundary_;
    std::vector<uint32_t> count_;
};

} // namespace lodbake_test
