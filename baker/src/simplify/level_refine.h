#pragma once
// Final vertex-position refinement of a coarse level (docs/simplify.md, "Level refinement"): a
// copy of the engine's snapshot whose interior vertices are moved along the normals of their faces
// towards the input points nearest to those faces. Connectivity is unchanged.

#include "lodbake/core/mesh.h"

namespace lodbake::detail {

/// Moves the vertices of `level` (not on an open or non-manifold edge) towards `input`'s
/// referenced vertices, kLevelRefineIterations damped least-squares steps along the face normals.
/// Vertices with the same position move together, and none moves if that would turn one of its
/// faces by more than `max_normal_change_deg` (the collapses' bound, SimplifyOptions) or leave it
/// without area. Deterministic and single-threaded.
void refineLevelPositions(const Mesh& input, Mesh& level, float max_normal_change_deg);

} // namespace lodbake::detail
