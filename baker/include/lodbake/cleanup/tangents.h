#pragma once
// Tangent frames for normal maps, by the MikkTSpace algorithm (Mikkelsen, "Simulation of Wrinkled
// Surfaces Revisited", 2008), the tangent space glTF 2.0 asks for when a primitive has a normal map
// but no TANGENT: normal-mapping tools bake against it, so a renderer using these tangents shows the
// normal map as it was baked.

#include <cstdint>
#include <string>

#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"

namespace lodbake {

struct TangentReport {
    uint64_t vertices_added = 0;      // copies of vertices whose corners got different tangents
    uint64_t corners_without_uv_frame = 0; // corners of degenerate triangles or UV-less regions: any unit
                                           // tangent perpendicular to the normal, handedness +1
};

/// The UV set the tangents are for: that of the normal map of the first sub-mesh whose material has one
/// (texcoord of its normal texture). -1 when no sub-mesh draws with a normal map, when the mesh already
/// has tangents or no normals, or when that UV set does not exist.
int tangentUvSet(const Mesh& mesh);

/// Replaces (or creates) the tangent stream with MikkTSpace tangents for UV set `uv_set`, which is read
/// as glTF stores it (v down) and flipped to the v-up convention MikkTSpace and the bakers that use it
/// assume, so that bitangent = cross(normal, tangent.xyz) * tangent.w points up the image.
/// As in MikkTSpace, corners are first welded by identical position, normal and UV; the corners of a
/// welded vertex are grouped across shared edges of triangles with the same UV winding, and each group
/// gets the corner-angle-weighted mean of its triangles' UV gradients, projected onto the normal's
/// plane. A vertex whose corners end up with different tangents is split (all streams copied).
/// Requires normals and that UV set (InvalidInput naming `name` otherwise). Deterministic.
Result<TangentReport> generateTangents(Mesh& mesh, uint32_t uv_set, const std::string& name);

} // namespace lodbake
