#pragma once
// Triangulation of the planar-ish polygons that OBJ and OFF faces describe.

#include <cstdint>
#include <vector>

#include "lodbake/core/math.h"

namespace lodbake::detail {

/// Triangulates a simple polygon given its corner positions in order. Appends 3 corner numbers
/// (0..corner_count-1) per triangle to `out`, n-2 triangles in all, keeping the polygon's winding.
/// Triangles use the input order; quads are split on the shorter diagonal unless that diagonal lies
/// outside a concave quad; larger polygons are ear-clipped in their best-fit (Newell) plane. A
/// polygon with no area or without a valid ear (self-intersecting) falls back to a fan, and the
/// function then returns false so the caller can report it.
bool triangulatePolygon(const Vec3f* corners, uint32_t corner_count, std::vector<uint32_t>& out);

} // namespace lodbake::detail
