// The registry of compressed-stream encoders and the --compact rule. The codec (valence
// connectivity, LODBAKE_valence_compression) and pfrep (LODBAKE_progressive_fans) modules register
// here: each adds one PackStreamEncoder to builtinStreamEncoders().
#include "lodbake/pack/pack.h"

namespace lodbake {

namespace {
const char* const kStreamExtensions[] = {"LODBAKE_valence_compression", "LODBAKE_progressive_fans"};
}

std::vector<PackStreamEncoder> builtinStreamEncoders() {
    std::vector<PackStreamEncoder> encoders;
    encoders.push_back(valenceStreamEncoder());
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
                       "), but no level got one (the valence stream codes single-primitive levels only); bake "
                       "without --compact");
}

} // namespace lodbake
