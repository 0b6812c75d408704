// The registry of compressed-stream encoders and the --compact rule. The codec (valence
// connectivity, LODBAKE_valence_compression) and pfrep (LODBAKE_progressive_fans) modules register
// here: each adds one PackStreamEncoder to builtinStreamEncoders().
#include "lodbake/pack/pack.h"

namespace lodbake {

namespace {
const char* const kStreamExtensions[] = {"LODBAKE_valence_compression", "LODBAKE_progressive_fans"};
}

std::vector<PackStreamEncoder> builtinStreamEncoders() {
    // TODO(bake): register the valence and progressive-fan encoders when the codec and pfrep modules land.
    return {};
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
    std::string missing;
    for (const char* name : kStreamExtensions) missing += (missing.empty() ? "" : " and ") + std::string(name);
    return unsupported("--compact needs compressed streams, but " + missing +
                       " are not produced by this baker yet (bake without --compact)");
}

} // namespace lodbake
