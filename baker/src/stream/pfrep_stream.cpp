// The LODBAKE_progressive_fans stream (schemas/LODBAKE_progressive_fans): LOD0's PFRep blob and the
// PFRep level matching each level of the chain, on the full-detail mesh. The pfrep module builds the
// extension object; this wraps it into a PackExtension.
#include <memory>
#include <optional>
#include <vector>

#include "lodbake/pfrep/pfrep_compress.h"
#include "lodbake/pfrep/pfrep_extension.h"
#include "lodbake/stream/stream.h"
#include "lodrt/format.h"

namespace lodbake {

namespace {

// Leaves in the extension object's `levels` (LOD0's entry, then one per chain level of `ratios`,
// the chain as prepared) the entries of the levels `chain` still holds.
void keepChainLevels(JsonNode& json, const std::vector<double>& ratios, const LodChain& chain) {
    const JsonNode* levels = json.find("levels");
    if (!levels || chain.levels.size() == ratios.size() || levels->items().size() != ratios.size() + 1) return;
    JsonNode kept = JsonNode::array();
    kept.push(levels->items()[0]);
    size_t next = 0; // the next chain level to find
    for (size_t i = 0; i < ratios.size(); ++i)
        if (next < chain.levels.size() && chain.levels[next].target_ratio == ratios[i]) {
            kept.push(levels->items()[i + 1]);
            ++next;
        }
    json.set("levels", std::move(kept));
}

} // namespace

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
            // The bake may drop dead levels from the chain after this prepare (docs/bake.md, "Dead
            // levels"); `levels` has one entry per pack level, so the commit keeps those of the levels
            // the chain still holds when it runs (chain levels are told apart by their ratio).
            std::vector<double> ratios;
            for (const LodLevel& l : chain.levels) ratios.push_back(l.target_ratio);
            return PackStreamCommit([e, ratios, &chain](PackLevel& level) {
                keepChainLevels(e->json, ratios, chain);
                level.mesh_extensions.push_back(std::move(*e));
                return Status::okStatus();
            });
        });
}

} // namespace lodbake
