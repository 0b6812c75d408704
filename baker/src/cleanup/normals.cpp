// Vertex normals: face normals weighted by area and/or corner angle (Thürmer & Wüthrich 1998), grouped
// per position across edges whose dihedral stays within the crease angle; vertices are split where a
// crease separates their corners.
#include "lodbake/cleanup/normals.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "core/parallel.h"
#include "mesh_edit.h"

namespace lodbake {

using namespace cleanup_detail;

PassCounters NormalsReport::counters() const {
    return {{"crease_edges", crease_edges}, {"vertices_split", vertices_split}, {"vertices_added", vertices_added}};
}

NormalsReport computeNormals(Mesh& mesh, const NormalOptions& options) {
    std::vector<uint32_t> weld;
    return cleanup_detail::computeNormals(mesh, options, weld);
}

NormalsReport cleanup_detail::computeNormals(Mesh& mesh, const NormalOptions& options, std::vector<uint32_t>& weld) {
    NormalsReport r;
    const size_t n = mesh.vertexCount();
    const size_t face_count = mesh.faceCount();
    // Welded ids: vertices with equal positions share topology (UV seams do not break fans).
    weld = positionWeldMap(mesh);

    // Face normals and per-corner weights are independent per face: computed in parallel into
    // per-face/per-corner slots; accumulation below stays sequential in corner order, so the sums do
    // not depend on the schedule. faceWork(f, slot) fills slot `slot` with face f's values (area 0:
    // the face adds nothing).
    // Tens of MB each on a scan: huge pages where the OS offers them (core/large_array.h).
    detail::LargeArray<Vec3d> face_n;
    detail::LargeArray<double> face_area;
    detail::LargeArray<double> corner_weight;
    auto faceWork = [&](size_t f, size_t slot) {
        face_area[slot] = 0.0;
        if (hasRepeatedIndex(mesh, f)) return;
        const Vec3d nn = faceNormal(mesh, f);
        const double l = length(nn);
        if (!(l > 0.0) || !std::isfinite(l)) return;
        face_n[slot] = nn / l;
        face_area[slot] = 0.5 * l;
        for (int k = 0; k < 3; ++k) {
            const size_t c = 3 * f + k;
            double weight = 1.0;
            if (options.weighting != NormalWeighting::Area) {
                const Vec3d o = toDouble(mesh.positions[mesh.indices[c]]);
                const Vec3d u = normalize(toDouble(mesh.positions[mesh.indices[3 * f + (k + 1) % 3]]) - o);
                const Vec3d v = normalize(toDouble(mesh.positions[mesh.indices[3 * f + (k + 2) % 3]]) - o);
                weight = std::acos(std::max(-1.0, std::min(1.0, dot(u, v))));
            }
            if (options.weighting != NormalWeighting::Angle) weight *= face_area[slot];
            corner_weight[3 * slot + k] = weight;
        }
    };
    // Faces [first, last) into slots 0.. in parallel (on this thread if a worker runs out of memory).
    auto faceRange = [&](size_t first, size_t last) {
        if (!parallelFor(last - first, 4096, [&](size_t i) { faceWork(first + i, i); }).ok())
            for (size_t f = first; f < last; ++f) faceWork(f, f - first);
    };

    auto unitOrUp = [](const Vec3d& sum) {
        const Vec3d nn = normalize(sum);
        return length(nn) > 0 ? Vec3f(nn) : Vec3f(0, 0, 1);
    };
    const bool split = options.crease_angle_deg < 180.0;
    if (!split) {
        // One smooth group per welded position: sums per welded id, corners in ascending order (the
        // same order as the grouped case below), and no vertex is split. The faces go in fixed
        // blocks whose slots are reused: the same sums in the same order, without arrays of the
        // whole mesh (fresh pages are slow to fault in).
        constexpr size_t kBlock = size_t(1) << 16;
        const size_t block = std::min(face_count, kBlock);
        face_n.resize(block);
        face_area.resize(block);
        corner_weight.resize(3 * block);
        detail::LargeArray<Vec3d> acc(n);
        for (size_t first = 0; first < face_count; first += block) {
            const size_t last = std::min(face_count, first + block);
            faceRange(first, last);
            for (size_t f = first; f < last; ++f) {
                const size_t slot = f - first;
                if (face_area[slot] == 0.0) continue;
                for (size_t k = 0; k < 3; ++k)
                    acc[weld[mesh.indices[3 * f + k]]] += face_n[slot] * corner_weight[3 * slot + k];
            }
        }
        std::vector<uint8_t> referenced(n, 0);
        for (uint32_t v : mesh.indices) referenced[v] = 1;
        mesh.normals.assign(n, Vec3f(0, 0, 1));
        for (size_t v = 0; v < n; ++v)
            if (referenced[v]) mesh.normals[v] = unitOrUp(acc[weld[v]]);
        return r;
    }

    face_n.resize(face_count);
    face_area.resize(face_count);
    corner_weight.resize(mesh.indices.size());
    faceRange(0, face_count);
    std::vector<uint32_t> welded(mesh.indices.size());
    for (size_t c = 0; c < mesh.indices.size(); ++c) welded[c] = weld[mesh.indices[c]];
    UnionFind groups(mesh.indices.size());
    {
        const double cos_limit = std::cos(options.crease_angle_deg * M_PI / 180.0);
        const EdgeTable table = buildEdgeTable(welded, n);
        for (uint32_t e = 0; e < table.edgeCount(); ++e) {
            if (table.uses(e) != 2) continue;
            const uint32_t a = table.corners[table.begin[e]], b = table.corners[table.begin[e] + 1];
            if (dot(face_n[a / 3], face_n[b / 3]) < cos_limit) {
                ++r.crease_edges;
                continue;
            }
            const uint32_t an = a % 3 == 2 ? a - 2 : a + 1, bn = b % 3 == 2 ? b - 2 : b + 1;
            if (welded[a] == welded[b]) {
                groups.unite(a, b);
                groups.unite(an, bn);
            } else {
                groups.unite(a, bn);
                groups.unite(an, b);
            }
        }
    }
    // Dense group ids, numbered by lowest corner (a set's root is its lowest corner, so it is met first).
    detail::LargeArray<uint32_t> group(mesh.indices.size());
    uint32_t group_count = 0;
    for (uint32_t c = 0; c < group.size(); ++c) {
        const uint32_t root = groups.find(c);
        group[c] = root == c ? group_count++ : group[root];
    }
    detail::LargeArray<Vec3d> acc(group_count);
    for (size_t f = 0; f < face_count; ++f) {
        if (face_area[f] == 0.0) continue;
        for (size_t c = 3 * f; c < 3 * f + 3; ++c) acc[group[c]] += face_n[f] * corner_weight[c];
    }

    mesh.normals.assign(n, Vec3f(0, 0, 1));
    std::vector<uint32_t> first_group(n, kNone);
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> extra; // (vertex, group) -> split copy
    std::vector<uint8_t> was_split(n, 0);
    for (uint32_t c = 0; c < mesh.indices.size(); ++c) {
        const uint32_t v = mesh.indices[c];
        const uint32_t g = group[c];
        if (first_group[v] == kNone) {
            first_group[v] = g;
            mesh.normals[v] = unitOrUp(acc[g]);
            continue;
        }
        if (first_group[v] == g) continue;
        auto [it, inserted] = extra.try_emplace({v, g}, 0u);
        if (inserted) {
            it->second = duplicateVertex(mesh, v);
            mesh.normals[it->second] = unitOrUp(acc[g]);
            ++r.vertices_added;
            if (!was_split[v]) {
                was_split[v] = 1;
                ++r.vertices_split;
            }
        }
        mesh.indices[c] = it->second;
    }
    return r;
}

} // namespace lodbake
