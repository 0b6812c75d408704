// Grouping of clusters by graph partition: METIS multilevel recursive bisection (Karypis & Kumar, "A
// Fast and High Quality Multilevel Scheme for Partitioning Irregular Graphs", 1998) on the cluster
// adjacency graph weighted
// by shared edges, so a group's outer border (what stays locked) is short. METIS is used by this
// file alone; its types never leave it.

#include <algorithm>
#include <mutex>
#include <numeric>

#include <metis.h>

#include "cluster/cluster_internal.h"

namespace lodbake::cluster_detail {

namespace {

using Parts = std::vector<std::vector<uint32_t>>;

// Parts from a part id per vertex, ordered by their smallest vertex, empty parts dropped.
Parts collect(const std::vector<uint32_t>& part_of, uint32_t part_count) {
    Parts parts(part_count);
    for (uint32_t v = 0; v < part_of.size(); ++v) parts[part_of[v]].push_back(v);
    parts.erase(std::remove_if(parts.begin(), parts.end(), [](const auto& p) { return p.empty(); }), parts.end());
    std::sort(parts.begin(), parts.end(), [](const auto& a, const auto& b) { return a.front() < b.front(); });
    return parts;
}

bool metisPartition(const WeightedGraph& g, uint32_t part_count, uint64_t seed, std::vector<uint32_t>& part_of) {
    const size_t n = g.vertex_weight.size();
    idx_t nvtxs = idx_t(n), ncon = 1, nparts = idx_t(part_count), objval = 0;
    std::vector<idx_t> xadj(g.row_begin.begin(), g.row_begin.end());
    std::vector<idx_t> adjncy(g.neighbour.begin(), g.neighbour.end());
    std::vector<idx_t> adjwgt(g.weight.begin(), g.weight.end());
    std::vector<idx_t> vwgt(g.vertex_weight.begin(), g.vertex_weight.end());
    std::vector<idx_t> part(n, 0);
    idx_t options[METIS_NOPTIONS];
    METIS_SetDefaultOptions(options);
    options[METIS_OPTION_SEED] = idx_t(seed & 0x7fffffff);
    options[METIS_OPTION_NUMBERING] = 0;
    // Recursive bisection rather than k-way: with one part per group_size vertices, k-way's
    // coarsening stops at once (it coarsens to a multiple of the part count) and its time goes into
    // an initial partition of the whole graph; recursive bisection coarsens each bisection and
    // gives groups of the same quality for a fraction of the time.
    // METIS seeds and draws from GKlib's random state, which is global to the process: two calls at
    // once (two cluster builds side by side, as the out-of-core driver runs them) interleave their
    // draws and make either partition depend on the schedule. One call at a time keeps each a
    // function of its graph and seed.
    static std::mutex metis_mutex;
    std::lock_guard<std::mutex> metis_lock(metis_mutex);
    const int status = METIS_PartGraphRecursive(&nvtxs, &ncon, xadj.data(), adjncy.data(), vwgt.data(), nullptr,
                                           adjwgt.data(), &nparts, nullptr, nullptr, options, &objval, part.data());
    if (status != METIS_OK) return false;
    part_of.assign(part.begin(), part.end());
    for (uint32_t p : part_of)
        if (p >= part_count) return false;
    return true;
}

// Merges every part below min_size into the neighbouring part it shares the most edge weight with
// (ties: the smaller part, then the lower index) when the union stays within max_size.
void mergeSmallParts(const WeightedGraph& g, std::vector<uint32_t>& part_of, uint32_t part_count, uint32_t min_size,
                     uint32_t max_size) {
    std::vector<uint32_t> size(part_count, 0);
    for (uint32_t p : part_of) ++size[p];
    std::vector<std::vector<uint32_t>> members(part_count);
    for (uint32_t v = 0; v < part_of.size(); ++v) members[part_of[v]].push_back(v);
    std::vector<uint64_t> shared(part_count, 0);
    for (uint32_t p = 0; p < part_count; ++p) {
        if (size[p] == 0 || size[p] >= min_size) continue;
        std::fill(shared.begin(), shared.end(), 0);
        for (uint32_t v : members[p])
            for (uint32_t e = g.row_begin[v]; e < g.row_begin[v + 1]; ++e)
                shared[part_of[g.neighbour[e]]] += g.weight[e];
        uint32_t best = p;
        for (uint32_t q = 0; q < part_count; ++q) {
            if (q == p || shared[q] == 0 || size[q] + size[p] > max_size) continue;
            if (best == p || shared[q] > shared[best] || (shared[q] == shared[best] && size[q] < size[best])) best = q;
        }
        if (best == p) continue;
        for (uint32_t v : members[p]) part_of[v] = best;
        members[best].insert(members[best].end(), members[p].begin(), members[p].end());
        members[p].clear();
        size[best] += size[p];
        size[p] = 0;
    }
}

} // namespace

Result<Parts> partitionGraph(const WeightedGraph& graph, uint32_t group_size, uint32_t min_size, uint32_t max_size,
                             uint64_t seed) {
    const uint32_t n = uint32_t(graph.vertex_weight.size());
    if (n == 0) return Parts{};
    const uint32_t part_count = (n + group_size - 1) / group_size;
    std::vector<uint32_t> part_of(n, 0);
    if (part_count > 1 && !metisPartition(graph, part_count, seed, part_of)) {
        // METIS refused the graph: consecutive clusters (spatially ordered by the splitter) instead.
        for (uint32_t v = 0; v < n; ++v) part_of[v] = v / group_size;
    }
    mergeSmallParts(graph, part_of, part_count, min_size, max_size);
    Parts parts = collect(part_of, part_count);
    // A part above max_size is cut into consecutive pieces of about group_size.
    Parts out;
    for (auto& p : parts) {
        if (p.size() <= max_size) {
            out.push_back(std::move(p));
            continue;
        }
        const size_t pieces = (p.size() + group_size - 1) / group_size;
        for (size_t i = 0; i < pieces; ++i)
            out.emplace_back(p.begin() + p.size() * i / pieces, p.begin() + p.size() * (i + 1) / pieces);
    }
    return out;
}

} // namespace lodbake::cluster_detail
