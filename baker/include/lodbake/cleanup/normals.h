#pragma once
// Vertex normals weighted by corner angle and face area, with a crease angle that splits vertices at
// hard edges.

#include <cstdint>

#include "lodbake/cleanup/passes.h"
#include "lodbake/core/mesh.h"

namespace lodbake {

enum class NormalWeighting {
    Area,      // face normal scaled by area
    Angle,     // unit face normal scaled by the corner angle (Thürmer & Wüthrich 1998)
    AreaAngle, // both
};

struct NormalOptions {
    NormalWeighting weighting = NormalWeighting::AreaAngle;
    double crease_angle_deg =
        180.0; // faces whose normals differ by more than this do not share a normal; 180: never split
};

struct NormalsReport {
    uint64_t vertices_split = 0; // vertices given one copy per smooth group at a crease
    uint64_t vertices_added = 0;
    uint64_t crease_edges = 0;
    PassCounters counters() const;
};

/// Replaces (or creates) the normal stream. Corners around a position are grouped across edges whose
/// dihedral is within crease_angle_deg; every group gets one normal, and a vertex whose corners fall
/// in several groups is split (all streams copied). Vertices already split at UV seams but sharing a
/// position still share the normal. Degenerate faces contribute nothing; a vertex with no usable face
/// gets (0,0,1).
NormalsReport computeNormals(Mesh& mesh, const NormalOptions& options = {});

} // namespace lodbake
