// Removal of vertices no face references, compacting every attribute stream.
#include "lodbake/cleanup/passes.h"
#include "mesh_edit.h"

namespace lodbake {

using namespace cleanup_detail;

UnreferencedReport removeUnreferencedVertices(Mesh& mesh) {
    UnreferencedReport r;
    const size_t n = mesh.vertexCount();
    std::vector<uint8_t> used(n, 0);
    for (uint32_t i : mesh.indices) used[i] = 1;
    std::vector<uint32_t> old_to_new(n, kNone);
    uint32_t next = 0;
    for (size_t v = 0; v < n; ++v)
        if (used[v]) old_to_new[v] = next++;
    r.vertices_removed = n - next;
    if (r.vertices_removed) remapVertices(mesh, old_to_new, next);
    return r;
}

} // namespace lodbake
