#pragma once
// loddump --render: what the contact sheet shades a level with, read from the pack through lodrt:
// each primitive's normals, tangents and texture coordinates, its glTF material (base colour factor
// and texture, normal map) and the decoded textures. Internal to loddump.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "contact_sheet.h"
#include "lodrt/pack.h"

namespace loddump {

/// Decodes an encoded image (PNG or JPEG) to RGBA8; false with *error set when it cannot.
using DecodeImage = std::function<bool(const uint8_t* data, size_t size, SheetTexture* out, std::string* error)>;

/// The pack's textures, each decoded once on first use. A texture whose image is missing, outside the
/// GLB's binary chunk or undecodable is left out (null) and named in problems().
class SheetTextures {
public:
    SheetTextures(const lodrt::Pack& pack, DecodeImage decode);
    /// glTF texture `index` decoded, or null.
    const SheetTexture* texture(uint64_t index);
    const std::vector<std::string>& problems() const { return problems_; }

private:
    const lodrt::Pack& pack_;
    DecodeImage decode_;
    std::vector<std::unique_ptr<SheetTexture>> decoded_;
    std::vector<bool> is_tried_;
    std::vector<std::string> problems_;
};

/// A primitive's shading attributes decoded from its LODBAKE_valence_compression stream (compact
/// packs, whose plain accessors have no data). An empty vector: the stream does not code it.
struct StreamShading {
    std::vector<float> normals;  // 3 per vertex
    std::vector<float> tangents; // 4 per vertex
    std::vector<float> uvs[2];   // TEXCOORD_0 and TEXCOORD_1, 2 per vertex
};

/// Appends primitive `prim`'s shading data for `vertex_count` vertices and `triangle_count` triangles
/// (its positions and indices are appended by the caller): NORMAL, TANGENT, TEXCOORD_0 and
/// TEXCOORD_1 from `decoded` when it has them (else from the accessors; zeros where a stream is absent
/// or unreadable), and its material for each triangle. Packs without materials add nothing, so their
/// levels stay flat shaded.
void appendShading(const lodrt::Pack& pack, const lodrt::PrimitiveInfo& prim, size_t vertex_count,
                   size_t triangle_count, const StreamShading& decoded, SheetTextures& textures, SheetMesh* out);

} // namespace loddump
