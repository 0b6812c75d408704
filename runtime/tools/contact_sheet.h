#pragma once
// loddump --render: a software rasteriser that draws every level of every LOD group side by side
// (one row per group, highest detail on the left) so a person sees the chain at a glance. Internal
// to loddump; depends on nothing but the standard library.

#include <cstdint>
#include <string>
#include <vector>

namespace loddump {

/// An RGBA8 image (rows top to bottom) decoded from a pack's texture.
struct SheetTexture {
    uint32_t width = 0, height = 0;
    std::vector<uint8_t> rgba;
};

/// What a triangle is shaded with, as glTF defines it: base colour = factor x texture (sRGB texels),
/// and a tangent-space normal map. Textures are sampled bilinearly with repeat wrapping.
struct SheetMaterial {
    float base_colour[4] = {1.0f, 1.0f, 1.0f, 1.0f}; // linear RGBA factor
    const SheetTexture* base_colour_texture = nullptr; // not owned; null: the factor alone
    uint32_t base_colour_uv = 0;                       // index into SheetMesh::uvs
    const SheetTexture* normal_texture = nullptr;      // not owned; null: no normal map
    uint32_t normal_uv = 0;
    float normal_scale = 1.0f;
};

/// One level's triangles: positions xyz, 3 indices per triangle, and for textured shading the
/// per-vertex attributes and each triangle's material.
struct SheetMesh {
    std::vector<float> positions;
    std::vector<uint32_t> indices;
    std::string label; // drawn in the cell's top-left corner (digits, letters and a few symbols)
    std::vector<float> normals;              // 3 per vertex, or empty; a zero normal means the face's
    std::vector<float> tangents;             // 4 per vertex (glTF TANGENT), or empty; zero: from the UVs
    std::vector<std::vector<float>> uvs;     // UV sets, 2 per vertex each (glTF convention, v down)
    std::vector<uint32_t> triangle_material; // per triangle, index into materials; empty: flat shading
    std::vector<SheetMaterial> materials;
};

struct SheetOptions {
    uint32_t cell_px = 320;    // width and height of one level's cell
    bool wireframe = false;    // draw triangle edges over the flat shading
};

/// RGB8 image, rows top to bottom.
struct SheetImage {
    uint32_t width = 0, height = 0;
    std::vector<uint8_t> rgb;
};

/// rows[g] are the levels of group g. Every level of a row is framed by the bounding box of the
/// row's first level (the camera is the same for all levels), seen orthographically from the front
/// right and slightly above (azimuth 30 degrees, elevation 20 degrees, +Y up), lit by a headlight.
/// A level without materials is flat shaded in one colour; a level with materials is shaded per pixel
/// with its base colour (factor and texture, in linear light) and its normal map (interpolated
/// normal and tangent, or the face's), as a glTF viewer with a headlight would show it. Empty levels
/// leave their cell blank.
SheetImage renderContactSheet(const std::vector<std::vector<SheetMesh>>& rows, const SheetOptions& options);

} // namespace loddump
