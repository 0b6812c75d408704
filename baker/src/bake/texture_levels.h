#pragma once
// The bake's texture stage (docs/bake.md, "Texture levels"): which size each level's textures get,
// what happens to images no decoder reads, and the resized images themselves. Internal to the bake.

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "lodbake/config/bake_config.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"
#include "lodbake/image/texture_resize.h"
#include "lodbake/pack/pack.h"

namespace lodbake {
namespace bake_detail {

/// Texture levels of one asset. Level l's textures are sized for the object's projected size at its
/// switch distance, every level's (LOD0's too) at most max_size_px; equal sizes share one image.
struct TextureLevels {
    std::vector<std::vector<ImageSize>> sizes; // per level, per texture: the size it ships at
    std::map<std::pair<size_t, std::pair<uint32_t, uint32_t>>, std::vector<uint8_t>>
        resized;                   // (texture, size) -> encoded bytes, for every size other than the source's
    std::vector<bool> is_verbatim; // per texture: unreadable and shipped byte for byte (keep_unreadable_images)
};

/// Sizes and resized images for LOD0's textures (`lod0.textures`). An image that is not a decodable
/// PNG or JPEG (or holds no bytes) fails the bake with "<name>: texture <t> '<file>': <why>", unless
/// settings.textures.keep_unreadable_images, which ships it unchanged with a warning in `diagnostics`.
/// Textures are decoded and filtered in parallel; the bytes do not depend on the thread count.
Result<TextureLevels> textureLevels(const Mesh& lod0, size_t level_count, const LodMetrics& metrics,
                                    const BakeSettings& settings, const std::string& name, Diagnostics& diagnostics);

/// Gives each level's textures (a copy of LOD0's sources in every level's mesh) their size's bytes.
/// A level's new image is named after its source with "_lod<l>" before the file extension, if any
/// ("bricks.png" -> "bricks_lod2.png", "bricks" -> "bricks_lod2"); LOD0 keeps the source's name.
void applyTextureLevels(const TextureLevels& textures, std::vector<PackLevel>& levels);

/// MikkTSpace tangents (cleanup/tangents.h) for a mesh that draws with a normal map and has no
/// tangents, with a note; the LOD chain then carries them to every level. Nothing otherwise.
Status addNormalMapTangents(Mesh& mesh, const std::string& name, Diagnostics& diagnostics);

/// The name of texture `source`'s image on level `level` (applyTextureLevels).
std::string levelTextureName(const Texture& source, size_t texture_index, size_t level);

} // namespace bake_detail
} // namespace lodbake
