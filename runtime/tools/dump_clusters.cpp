// loddump: LODBAKE_cluster_lod summary and checks (dump_clusters.h).
#include "dump_clusters.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <utility>

#include "cluster_edges.h"
#include "lodrt/cluster_pack.h"

namespace loddump {

namespace {

struct Opened {
    std::vector<uint64_t> memory;
    lodrt::ClusterLodPack pack;
    std::vector<std::vector<float>> positions; // per page
    std::vector<std::vector<uint32_t>> indices;
};

bool openAll(const lodrt::Pack& pack, uint32_t mesh, Opened& o, ClusterSummary& s, std::string* error) {
    char message[256] = {0};
    lodrt::ClusterPackSource source;
    if (lodrt::clusterPackFind(pack, mesh, &source, message, sizeof(message)) != lodrt::Result::Ok) {
        *error = message;
        return false;
    }
    if (!source.table) {
        *error = "the BIN chunk is not in memory";
        return false;
    }
    lodrt::ClusterPackInfo info;
    if (lodrt::clusterPackReadInfo(source.table, source.table_size, &info, message, sizeof(message)) !=
        lodrt::Result::Ok) {
        *error = message;
        return false;
    }
    o.memory.assign(info.memory_bytes / 8 + 1, 0);
    if (lodrt::clusterPackOpen(source.table, source.table_size, source.pages_size, o.memory.data(),
                               o.memory.size() * 8, &o.pack, message, sizeof(message)) != lodrt::Result::Ok) {
        *error = message;
        return false;
    }
    s.table_bytes = source.table_size;
    s.page_bytes = source.pages_size;
    o.positions.resize(o.pack.page_count);
    o.indices.resize(o.pack.page_count);
    std::vector<uint64_t> scratch;
    for (uint32_t p = 0; p < o.pack.page_count; ++p) {
        const lodrt::ClusterPage& page = o.pack.pages[p];
        const uint8_t* bytes = source.pages + page.byte_offset;
        lodrt::ClusterPageInfo pi;
        if (lodrt::clusterPageReadInfo(o.pack, p, bytes, page.byte_length, &pi, message, sizeof(message)) !=
            lodrt::Result::Ok) {
            *error = message;
            return false;
        }
        scratch.assign(pi.scratch_bytes / 8 + 1, 0);
        o.positions[p].resize(size_t(pi.vertex_count) * 3);
        o.indices[p].resize(size_t(pi.triangle_count) * 3);
        if (lodrt::clusterPageDecode(o.pack, p, bytes, page.byte_length, o.positions[p].data(), o.positions[p].size(),
                                     o.indices[p].data(), o.indices[p].size(), scratch.data(), scratch.size() * 8,
                                     message, sizeof(message)) != lodrt::Result::Ok) {
            *error = message;
            return false;
        }
        s.min_page_bytes = p == 0 ? page.byte_length : std::min<uint64_t>(s.min_page_bytes, page.byte_length);
        s.max_page_bytes = std::max<uint64_t>(s.max_page_bytes, page.byte_length);
    }
    return true;
}

// Errors and LOD spheres grow from a cluster's own group to its parent group.
bool checkMonotonic(const lodrt::ClusterLodView& v, std::string* error) {
    for (uint32_t c = 0; c < v.cluster_count; ++c) {
        const lodrt::ClusterLodCluster& cl = v.clusters[c];
        if (cl.self_group == lodrt::kClusterNone || cl.parent_group == lodrt::kClusterNone) continue;
        const lodrt::ClusterLodGroup& own = v.groups[cl.self_group];
        const lodrt::ClusterLodGroup& parent = v.groups[cl.parent_group];
        if (parent.error < own.error) {
            *error = "cluster " + std::to_string(c) + ": parent group error " + std::to_string(parent.error) +
                     " below its own group's " + std::to_string(own.error) + " (errors must not decrease)";
            return false;
        }
        double d2 = 0;
        for (int j = 0; j < 3; ++j) d2 += double(parent.lod_center[j] - own.lod_center[j]) * (parent.lod_center[j] - own.lod_center[j]);
        if (std::sqrt(d2) + own.lod_radius > double(parent.lod_radius) * (1 + 1e-5) + 1e-6) {
            *error = "cluster " + std::to_string(c) + ": its parent group's LOD sphere does not enclose its own group's";
            return false;
        }
    }
    return true;
}

// Every cluster reached from the roots through the groups' children.
bool checkReachable(const lodrt::ClusterLodView& v, std::string* error) {
    std::vector<char> seen(v.cluster_count, 0), entered(v.group_count, 0);
    std::vector<uint32_t> stack(v.roots, v.roots + v.root_count);
    while (!stack.empty()) {
        const uint32_t c = stack.back();
        stack.pop_back();
        if (seen[c]) continue;
        seen[c] = 1;
        const uint32_t g = v.clusters[c].self_group;
        if (g == lodrt::kClusterNone || entered[g]) continue;
        entered[g] = 1;
        for (uint32_t i = 0; i < v.groups[g].child_count; ++i) stack.push_back(v.group_children[v.groups[g].first_child + i]);
    }
    for (uint32_t c = 0; c < v.cluster_count; ++c)
        if (!seen[c]) {
            *error = "cluster " + std::to_string(c) + ": not reachable from the roots";
            return false;
        }
    return true;
}

// Cuts from eyes on the axes of the roots' bounds, near and far: no boundary edge LOD0 lacks.
bool checkCuts(const Opened& o, ClusterSummary& s, std::string* error) {
    const lodrt::ClusterLodView& v = o.pack.view;
    const lodrt_tools::ClusterEdges edges(v.cluster_count, [&o](uint32_t c, auto&& triangle) {
        const lodrt::ClusterPlace& place = o.pack.places[c];
        const std::vector<float>& pos = o.positions[place.page];
        const std::vector<uint32_t>& idx = o.indices[place.page];
        for (uint32_t t = place.first_triangle; t < place.first_triangle + place.triangle_count; ++t) {
            const float* p[3];
            for (int i = 0; i < 3; ++i) p[i] = &pos[3 * size_t(idx[3 * size_t(t) + size_t(i)])];
            triangle(p);
        }
    });
    std::vector<uint32_t> lod0;
    for (uint32_t c = 0; c < v.cluster_count; ++c)
        if (v.clusters[c].self_group == lodrt::kClusterNone) lod0.push_back(c);
    const std::vector<lodrt_tools::ClusterEdges::Edge> lod0_boundary = edges.boundary(lod0);
    const lodrt::ClusterLodCluster& root = v.clusters[v.roots[0]];
    float radius = root.radius;
    for (uint32_t g = 0; g < v.group_count; ++g) radius = std::max(radius, v.groups[g].bounds_radius);
    std::vector<uint32_t> scratch(lodrt::clusterCutScratchBytes(v) / 4 + 1, 0), out(v.cluster_count);
    lodrt::ClusterCutScratch cut_scratch{scratch.data(), scratch.size() * 4, 0};
    lodrt::SelectionParams params;
    for (float distance : {1.2f, 3.0f, 20.0f})
        for (int axis = 0; axis < 6; ++axis) {
            float eye[3] = {root.center[0], root.center[1], root.center[2]};
            eye[axis / 2] += (axis % 2 ? -1.0f : 1.0f) * distance * std::max(radius, 1e-6f);
            lodrt::ClusterCutStats stats;
            if (lodrt::selectClusterCut(v, lodrt::ClusterInstance(), eye, nullptr, params, cut_scratch, out.data(),
                                        uint32_t(out.size()), &stats) != lodrt::Result::Ok) {
                *error = "cut selection failed";
                return false;
            }
            const std::vector<lodrt_tools::ClusterEdges::Edge> extra =
                edges.cracks(std::vector<uint32_t>(out.begin(), out.begin() + stats.written), lod0_boundary);
            if (!extra.empty()) {
                *error = "a cut has " + std::to_string(extra.size()) + " boundary edges LOD0 lacks (a crack)";
                return false;
            }
            ++s.cuts_checked;
        }
    return true;
}

void summarise(const Opened& o, ClusterSummary& s) {
    const lodrt::ClusterLodView& v = o.pack.view;
    s.clusters = v.cluster_count;
    s.groups = v.group_count;
    s.roots = v.root_count;
    s.pages = o.pack.page_count;
    s.position_bits = o.pack.info.position_bits;
    s.quantization_error = o.pack.info.quantization_error;
    std::map<uint32_t, ClusterDepthRow> rows;
    for (uint32_t c = 0; c < v.cluster_count; ++c) {
        const lodrt::ClusterLodCluster& cl = v.clusters[c];
        const uint32_t depth = cl.self_group == lodrt::kClusterNone ? 0 : v.groups[cl.self_group].depth;
        ClusterDepthRow& row = rows[depth];
        row.depth = depth;
        ++row.clusters;
        row.triangles += cl.triangle_count;
        if (cl.self_group != lodrt::kClusterNone) row.max_error = std::max(row.max_error, double(v.groups[cl.self_group].error));
        s.cone_clusters += cl.cone_cutoff > 0 ? 1 : 0;
        if (depth == 0) s.lod0_triangles += cl.triangle_count;
    }
    for (const auto& r : rows) s.depths.push_back(r.second);
}

// The roots' centre and a radius enclosing every group's culling sphere: where the cut's eyes sit.
void hierarchyBounds(const lodrt::ClusterLodView& v, float centre[3], float* radius) {
    const lodrt::ClusterLodCluster& root = v.clusters[v.roots[0]];
    for (int k = 0; k < 3; ++k) centre[k] = root.center[k];
    *radius = root.radius;
    for (uint32_t g = 0; g < v.group_count; ++g) *radius = std::max(*radius, v.groups[g].bounds_radius);
    *radius = std::max(*radius, 1e-6f);
}

// One cut as a contact-sheet cell: the drawn clusters' triangles, each cluster in a palette colour
// picked by a hash of its index (neighbours rarely share one).
SheetMesh cutMesh(const Opened& o, const uint32_t* cut, uint32_t count, const std::string& label) {
    static const float kPalette[][3] = {{0.90f, 0.30f, 0.25f}, {0.25f, 0.65f, 0.90f}, {0.95f, 0.80f, 0.25f},
                                        {0.40f, 0.80f, 0.35f}, {0.75f, 0.40f, 0.85f}, {0.95f, 0.55f, 0.20f},
                                        {0.30f, 0.85f, 0.80f}, {0.85f, 0.45f, 0.60f}, {0.55f, 0.55f, 0.95f},
                                        {0.70f, 0.85f, 0.30f}, {0.60f, 0.40f, 0.25f}, {0.80f, 0.80f, 0.80f}};
    constexpr uint32_t kColours = sizeof(kPalette) / sizeof(kPalette[0]);
    SheetMesh m;
    m.label = label;
    m.materials.resize(kColours);
    for (uint32_t i = 0; i < kColours; ++i)
        for (int k = 0; k < 3; ++k) m.materials[i].base_colour[k] = kPalette[i][k];
    for (uint32_t i = 0; i < count; ++i) {
        const lodrt::ClusterPlace& place = o.pack.places[cut[i]];
        const std::vector<float>& pos = o.positions[place.page];
        const std::vector<uint32_t>& idx = o.indices[place.page];
        const uint32_t colour = uint32_t((uint64_t(cut[i]) * 0x9E3779B1u) >> 16) % kColours;
        for (uint32_t t = place.first_triangle; t < place.first_triangle + place.triangle_count; ++t) {
            for (int c = 0; c < 3; ++c) {
                const float* p = &pos[3 * size_t(idx[3 * size_t(t) + size_t(c)])];
                m.indices.push_back(uint32_t(m.positions.size() / 3));
                m.positions.insert(m.positions.end(), p, p + 3);
            }
            m.triangle_material.push_back(colour);
        }
    }
    return m;
}

} // namespace

bool clusterCutSheets(const lodrt::Pack& pack, uint32_t mesh, std::vector<SheetMesh>* out, std::string* error) {
    ClusterSummary s;
    Opened o;
    if (!openAll(pack, mesh, o, s, error)) return false;
    const lodrt::ClusterLodView& v = o.pack.view;
    float centre[3], radius;
    hierarchyBounds(v, centre, &radius);
    // The contact sheet's camera direction (contact_sheet.h: azimuth 30, elevation 20 degrees).
    const float azimuth = 30.0f * 3.14159265f / 180.0f, elevation = 20.0f * 3.14159265f / 180.0f;
    const float to_camera[3] = {std::sin(azimuth) * std::cos(elevation), std::sin(elevation),
                                std::cos(azimuth) * std::cos(elevation)};
    std::vector<uint32_t> scratch(lodrt::clusterCutScratchBytes(v) / 4 + 1, 0), cut(v.cluster_count);
    lodrt::ClusterCutScratch cut_scratch{scratch.data(), scratch.size() * 4, 0};
    const lodrt::SelectionParams params;
    for (int distance : {2, 8, 32}) {
        float eye[3];
        for (int k = 0; k < 3; ++k) eye[k] = centre[k] + to_camera[k] * float(distance) * radius;
        lodrt::ClusterCutStats stats;
        if (lodrt::selectClusterCut(v, lodrt::ClusterInstance(), eye, nullptr, params, cut_scratch, cut.data(),
                                    uint32_t(cut.size()), &stats) != lodrt::Result::Ok) {
            *error = "cut selection failed";
            return false;
        }
        // The sheet's font has digits and a few letters: "<distance>r <triangles> tris".
        out->push_back(cutMesh(o, cut.data(), stats.written,
                               std::to_string(distance) + "r " + std::to_string(stats.triangles) + " tris"));
    }
    return true;
}

bool checkClusterLod(const lodrt::Pack& pack, uint32_t mesh, ClusterSummary* out, std::string* error) {
    ClusterSummary s;
    s.mesh = mesh;
    Opened o;
    if (!openAll(pack, mesh, o, s, error)) return false;
    summarise(o, s);
    if (!checkMonotonic(o.pack.view, error) || !checkReachable(o.pack.view, error) || !checkCuts(o, s, error))
        return false;
    *out = std::move(s);
    return true;
}

} // namespace loddump
