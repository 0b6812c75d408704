// The LODBAKE_progressive_fans stream (schemas/LODBAKE_progressive_fans): LOD0's PFRep blob and the
// PFRep level matching each level of the chain, on the full-detail mesh. The pfrep module builds the
// extension object; this wraps it into a PackExtension.
#include <memory>
#include <optional>

#include "lodbake/pfrep/pfrep_compress.h"
#include "lodbake/pfrep/pfrep_extension.h"
#include "lodbake/stream/stream.h"
#include "lodrt/format.h"

namespace lodbake {

std::optional<PackStreamEncoder> progressiveFansStream(const StreamSettings& settings) {
    if (!settings.progressive_fans) return std::nullopt;
    StreamNeeds needs;
    needs.lod0_only = true;
    // pfrep_from_chain: the blob is built from the chain's own pass, read as vertex removals
    // (docs/bake.md); otherwise it runs a half-edge simplification of its own.
    needs.collapse_record = settings.pfrep_from_chain;
    StreamCost cost;
    cost.bytes_per_triangle = 190; // its own simplifier or the replay of the chain's collapses
    return makeStreamEncoder(
        lodrt::format::kExtProgressiveFans, needs, cost,
        [format = settings.pfrep_format](const LodChain& chain, size_t level_index,
                                         const Mesh& mesh) -> Result<PackStreamCommit> {
            if (level_index != 0 || mesh.faceCount() == 0) return PackStreamCommit();
            Diagnostics diagnostics; // notes only (e.g. nothing removable); the blob is valid either way
            // From the chain's own collapses when it recorded them (LodChain::removals), else its own
            // half-edge simplification; either reads LOD0's geometry only, as a view (MeshView).
            LODBAKE_ASSIGN_OR_RETURN(PfrepExtensionObject object,
                                     buildPfrepExtension(mesh, chain, PfrepOptions{}, diagnostics));
            if (format == lodrt::format::kPfrepVersionCompressed) {
                // Format 3: the same table range-coded; the runtime decodes it whole into the format
                // 2 bytes. `format` is written only here, so a format 2 object reads as before.
                LODBAKE_ASSIGN_OR_RETURN(object.blob, compressPfrep(object.blob));
                object.json.set(lodrt::format::kPfrepExtensionFormatMember, uint64_t(format));
            }
            auto e = std::make_shared<PackExtension>();
            e->name = lodrt::format::kExtProgressiveFans;
            e->json = std::move(object.json);
            e->blobs.push_back(std::move(object.blob));
            e->blob_view_members.push_back(kPfrepExtensionViewMember);
            // Extra data beside the plain levels, never a replacement for them: a viewer that
            // ignores it loses nothing, so it is not a stream --compact makes required.
            e->is_stream = false;
            return PackStreamCommit([e](PackLevel& level) {
                level.mesh_extensions.push_back(std::move(*e));
                return Status::okStatus();
            });
        });
}

} // namespace lodbake
