// The registry of compressed-stream encoders and the --compact rule. The codec (valence
// connectivity, LODBAKE_valence_compression) and pfrep (LODBAKE_progressive_fans) modules register
// here: each adds one PackStreamEncoder to builtinStreamEncoders().
#include "lodbake/pack/pack.h"

#include <memory>
#include <utility>

#include "lodbake/pfrep/pfrep_extension.h"

namespace lodbake {

namespace {
const char* const kStreamExtensions[] = {"LODBAKE_valence_compression", "LODBAKE_progressive_fans"};
}

namespace {
// LODBAKE_progressive_fans on the full-detail mesh: its PFRep blob and the PFRep level matching each
// level of the chain (schemas/LODBAKE_progressive_fans).
PackStreamEncoder progressiveFansEncoder() {
    return makeStreamEncoder(
        "LODBAKE_progressive_fans",
        [](const LodChain& chain, size_t level_index, const Mesh& mesh) -> Result<PackStreamCommit> {
            if (level_index != 0 || mesh.faceCount() == 0) return PackStreamCommit();
            Diagnostics diagnostics; // notes only (e.g. nothing removable); the blob is valid either way
            // From the chain's own collapses when it recorded them (LodChain::removals), else its own
            // half-edge simplification.
            LODBAKE_ASSIGN_OR_RETURN(PfrepExtensionObject object,
                                     buildPfrepExtension(mesh, chain, PfrepOptions{}, diagnostics));
            auto e = std::make_shared<PackExtension>();
            e->name = "LODBAKE_progressive_fans";
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

} // namespace

PackStreamEncoder makeStreamEncoder(
    std::string extension_name,
    std::function<Result<PackStreamCommit>(const LodChain& chain, size_t level_index, const Mesh& mesh)> prepare) {
    PackStreamEncoder encoder;
    encoder.extension_name = std::move(extension_name);
    encoder.prepare = std::move(prepare);
    return encoder;
}

std::vector<PackStreamEncoder> builtinStreamEncoders(const ValenceStreamOptions& valence) {
    // Both prepare from the levels as baked (PFRep from LOD0 before the valence commit renumbers it
    // into the decoded vertex order); commits run in this order.
    std::vector<PackStreamEncoder> encoders;
    encoders.push_back(progressiveFansEncoder());
    encoders.push_back(valenceStreamEncoder(valence));
    return encoders;
}

Status checkCompact(const PackDescription& description) {
    if (!description.compact) return Status::okStatus();
    for (const PackAsset& asset : description.assets)
        for (const PackLevel& level : asset.levels) {
            for (const PackExtension& e : level.mesh_extensions)
                if (e.is_stream) return Status::okStatus();
            for (const auto& list : level.primitive_extensions)
                for (const PackExtension& e : list)
                    if (e.is_stream) return Status::okStatus();
        }
    std::string names;
    for (const char* name : kStreamExtensions) names += (names.empty() ? "" : " or ") + std::string(name);
    return unsupported("--compact needs compressed streams (" + names +
                       "), but no level got one; bake without --compact");
}

} // namespace lodbake
