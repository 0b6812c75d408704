// Removal of small connected components (speckle), by face count and by area fraction.
#include <algorithm>
#include <cmath>

#include "lodbake/cleanup/passes.h"
#include "mesh_edit.h"

namespace lodbake {

using namespace cleanup_detail;

namespace {

VertexId corner(const Mesh& mesh, CornerId c) {
    return VertexId(mesh.indices[c.value]);
}

} // namespace

PassCounters ComponentReport::counters() const {
    return {{"components_before", components_before},
            {"components_removed", components_removed},
            {"faces_removed", faces_removed},
            {"area_removed_ppm", area_removed_ppm}};
}

ComponentReport removeSmallComponents(Mesh& mesh, const ComponentOptions& options) {
    ComponentReport r;
    const size_t face_count = mesh.faceCount();
    if (face_count == 0) return r;
    // UV islands of one surface are not separate components: join the vertices of boundary edges
    // that meet another boundary edge at the same positions (a seam). A vertex merely shared by
    // position (a pinch the manifold pass split) does not join anything.
    UnionFind uf(mesh.vertexCount());
    // Seams need an attribute that differs; without any attribute stream there are none to join.
    const bool has_attributes = mesh.hasNormals() || mesh.hasTangents() || mesh.hasColors() || !mesh.uvs.empty();
    const std::vector<uint32_t> weld = has_attributes ? positionWeldMap(mesh) : std::vector<uint32_t>();
    bool shared = false;
    for (uint32_t v = 0; v < weld.size() && !shared; ++v) shared = weld[v] != v;
    if (shared) {
        const EdgeTable table = buildEdgeTable(mesh);
        const std::vector<uint8_t> seam = seamCorners(mesh, table, weld);
        for (uint32_t c = 0; c < seam.size(); ++c)
            if (seam[c]) {
                uf.unite(halfStart(mesh, c), weld[halfStart(mesh, c)]);
                uf.unite(halfEnd(mesh, c), weld[halfEnd(mesh, c)]);
            }
    }
    for (FaceId f(0); f.value < face_count; ++f.value) {
        const VertexId a = corner(mesh, cornerOf(f, 0));
        uf.unite(a.value, corner(mesh, cornerOf(f, 1)).value);
        uf.unite(a.value, corner(mesh, cornerOf(f, 2)).value);
    }
    // Components are numbered by their first face; per component: face count and area.
    std::vector<uint32_t> comp_of_root(mesh.vertexCount(), kNone);
    std::vector<uint32_t> face_comp(face_count);
    std::vector<uint64_t> faces;
    std::vector<double> area;
    double total = 0.0;
    for (FaceId f(0); f.value < face_count; ++f.value) {
        const uint32_t root = uf.find(corner(mesh, cornerOf(f, 0)).value);
        if (comp_of_root[root] == kNone) {
            comp_of_root[root] = uint32_t(faces.size());
            faces.push_back(0);
            area.push_back(0.0);
        }
        const uint32_t c = comp_of_root[root];
        face_comp[f.value] = c;
        ++faces[c];
        const Vec3d n = faceNormal(mesh, f.value);
        const double a = std::isfinite(n.x + n.y + n.z) ? 0.5 * length(n) : 0.0;
        area[c] += a;
        total += a;
    }
    r.components_before = faces.size();
    // Components are numbered by first face, so '>' keeps the lowest-numbered one on ties.
    uint32_t largest = 0;
    for (uint32_t c = 1; c < faces.size(); ++c)
        if (area[c] > area[largest] || (area[c] == area[largest] && faces[c] > faces[largest])) largest = c;
    std::vector<uint8_t> drop(faces.size(), 0);
    double area_removed = 0.0;
    for (uint32_t c = 0; c < faces.size(); ++c) {
        if (c == largest) continue;
        drop[c] = faces[c] < options.min_face_count || area[c] < options.min_area_fraction * total;
        r.components_removed += drop[c];
        if (drop[c]) area_removed += area[c];
    }
    r.area_removed_ppm = total > 0.0 ? uint64_t(std::llround(1e6 * area_removed / total)) : 0;
    if (!r.components_removed) return r;
    std::vector<uint8_t> keep(face_count);
    for (FaceId f(0); f.value < face_count; ++f.value) keep[f.value] = !drop[face_comp[f.value]];
    r.faces_removed = removeFaces(mesh, keep);
    return r;
}

} // namespace lodbake
