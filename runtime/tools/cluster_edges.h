#pragma once
// The crack check of cluster LOD cuts over decoded pages: boundary edges (by decoded position) of a
// set of clusters are the edges used an odd number of times; a cut is crack-free when it has no
// boundary edge that the LOD0 clusters lack. Shared by loddump's cluster checks and the cluster
// pack and cluster streaming tests. Standard library only.

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <map>
#include <vector>

namespace lodrt_tools {

class ClusterEdges {
public:
    using Edge = uint64_t;
    /// each(c, fn) calls fn(const float* const* p) with the three positions of every triangle of
    /// cluster c. Each cluster's edges are found once.
    template <class EachTriangle> ClusterEdges(uint32_t cluster_count, EachTriangle&& each) : cluster_edges_(cluster_count) {
        for (uint32_t c = 0; c < cluster_count; ++c)
            each(c, [&](const float* const* p) {
                const uint32_t v[3] = {id(p[0]), id(p[1]), id(p[2])};
                if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) return;
                for (int k = 0; k < 3; ++k)
                    cluster_edges_[c].push_back(uint64_t(std::min(v[k], v[(k + 1) % 3])) << 32 |
                                                std::max(v[k], v[(k + 1) % 3]));
            });
    }
    std::vector<Edge> boundary(const std::vector<uint32_t>& clusters) const {
        std::vector<Edge> edges;
        for (uint32_t c : clusters) edges.insert(edges.end(), cluster_edges_[c].begin(), cluster_edges_[c].end());
        std::sort(edges.begin(), edges.end());
        std::vector<Edge> out;
        for (size_t i = 0; i < edges.size();) {
            size_t j = i;
            while (j < edges.size() && edges[j] == edges[i]) ++j;
            if ((j - i) % 2 == 1) out.push_back(edges[i]);
            i = j;
        }
        return out;
    }
    /// Boundary edges of `drawn` that `reference` (LOD0's boundary, sorted) lacks.
    std::vector<Edge> cracks(const std::vector<uint32_t>& drawn, const std::vector<Edge>& reference) const {
        const std::vector<Edge> b = boundary(drawn);
        std::vector<Edge> extra;
        std::set_difference(b.begin(), b.end(), reference.begin(), reference.end(), std::back_inserter(extra));
        return extra;
    }

private:
    uint32_t id(const float* p) {
        std::array<uint32_t, 3> k;
        const float v[3] = {p[0] + 0.0f, p[1] + 0.0f, p[2] + 0.0f};
        std::memcpy(k.data(), v, 12);
        return ids_.emplace(k, uint32_t(ids_.size())).first->second;
    }
    std::map<std::array<uint32_t, 3>, uint32_t> ids_;
    std::vector<std::vector<Edge>> cluster_edges_;
};

} // namespace lodrt_tools
