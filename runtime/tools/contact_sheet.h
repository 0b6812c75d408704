#pragma once
// loddump --render: a software rasteriser that draws every level of every LOD group side by side
// (one row per group, highest detail on the left) so a person sees the chain at a glance. Internal
// to loddump; depends on nothing but the standard library.

#include <cstdint>
#include <string>
#include <vector>

namespace loddump {

/// One level's triangles: positions xyz, 3 indices per triangle.
struct SheetMesh {
    std::vector<float> positions;
    std::vector<uint32_t> indices;
    std::string label; // drawn in the cell's top-left corner (digits, letters and a few symbols)
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
/// right and slightly above (azimuth 30 degrees, elevation 20 degrees, +Y up), flat shaded with a
/// headlight. Empty levels leave their cell blank.
SheetImage renderContactSheet(const std::vector<std::vector<SheetMesh>>& rows, const SheetOptions& options);

} // namespace loddump
