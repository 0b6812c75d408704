// The LODBAKE_cluster_lod stream (docs/format/cluster_lod.md): LOD0's cluster LOD hierarchy
// (cluster/cluster_lod.h) written by the pack module's writer (pack/cluster_lod_pack.h) as an
// extension on LOD0's mesh, beside the MSFT_lod chain.
#include <memory>
#include <optional>

#include "lodbake/cluster/cluster_lod.h"
#include "lodbake/pack/cluster_lod_pack.h"
#include "lodbake/stream/stream.h"
#include "lodrt/format.h"

namespace lodbake {

std::optional<PackStreamEncoder> clusterLodStream(const StreamSettings& settings) {
    if (!settings.cluster_lod) return std::nullopt;
    StreamNeeds needs;
    needs.lod0_only = true;
    StreamCost cost;
    cost.bytes_per_triangle = 400; // the hierarchy (about twice LOD0's triangles) and a group's simplifier
    return makeStreamEncoder(
        lodrt::format::kExtClusterLod, needs, cost,
        [bits = settings.valence.position_bits](const LodChain&, size_t level_index,
                                                const Mesh& mesh) -> Result<PackStreamCommit> {
            if (level_index != 0 || mesh.faceCount() == 0) return PackStreamCommit();
            Diagnostics diagnostics; // notes only; the hierarchy is valid either way
            LODBAKE_ASSIGN_OR_RETURN(ClusterLodHierarchy hierarchy,
                                     buildClusterLod(MeshView(mesh), ClusterLodOptions{}, diagnostics));
            ClusterPackOptions options;
            options.position_bits = bits;
            LODBAKE_ASSIGN_OR_RETURN(ClusterPackResult written, writeClusterLodPack(hierarchy, options));
            auto e = std::make_shared<PackExtension>(std::move(written.extension));
            return PackStreamCommit([e](PackLevel& level) {
                level.mesh_extensions.push_back(std::move(*e));
                return Status::okStatus();
            });
        });
}

} // namespace lodbake
