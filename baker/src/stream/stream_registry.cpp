// The registry of stream encoders and the --compact rule. A stream is registered here with one
// line in kStreams; everything the bake needs to know about it is in its PackStreamEncoder.
#include "lodbake/stream/stream.h"

#include <optional>

#include "lodrt/format.h"

namespace lodbake {

// Each stream's factory (defined in its own source file): its encoder, or nothing when `settings`
// leave it out.
std::optional<PackStreamEncoder> progressiveFansStream(const StreamSettings& settings); // pfrep_stream.cpp
std::optional<PackStreamEncoder> valenceStream(const StreamSettings& settings);         // valence_stream.cpp
std::optional<PackStreamEncoder> clusterLodStream(const StreamSettings& settings);      // cluster_stream.cpp

namespace {

using StreamFactory = std::optional<PackStreamEncoder> (*)(const StreamSettings&);

// In the order the commits run. Both prepare from the levels as baked (PFRep from LOD0 before the
// valence commit renumbers it into the decoded vertex order).
constexpr StreamFactory kStreams[] = {
    progressiveFansStream,
    clusterLodStream,
    valenceStream,
};

} // namespace

PackStreamEncoder makeStreamEncoder(
    std::string extension_name, StreamNeeds needs, StreamCost cost,
    std::function<Result<PackStreamCommit>(const LodChain& chain, size_t level_index, const Mesh& mesh)> prepare) {
    PackStreamEncoder encoder;
    encoder.extension_name = std::move(extension_name);
    encoder.needs = needs;
    encoder.cost = cost;
    encoder.prepare = std::move(prepare);
    return encoder;
}

std::vector<PackStreamEncoder> builtinStreamEncoders(const StreamSettings& settings) {
    std::vector<PackStreamEncoder> encoders;
    for (StreamFactory factory : kStreams)
        if (std::optional<PackStreamEncoder> encoder = factory(settings)) encoders.push_back(std::move(*encoder));
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
    for (const char* name : lodrt::format::kDecodedStreamExtensions)
        names += (names.empty() ? "" : " or ") + std::string(name);
    return unsupported("--compact needs compressed streams (" + names +
                       "), but no level got one; bake without --compact");
}

} // namespace lodbake
