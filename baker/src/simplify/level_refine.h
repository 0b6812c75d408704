#pragma once
// Final vertex-position refinement of a coarse level (docs/simplify.md, "Level refinement"): a
// copy of the engine's snapshot whose interior vertices are moved along the normals of their faces
// towards the input points nearest to those faces. Connectivity is unchanged.

#include "lodbake/core/mesh.h"

namespace lodbake::detail {

/// Moves the vertices of `level` (not on an open or non-manifold edge) towards `input`'s
/// referenced vertices, kLevelRefineIterations damped least-squares steps along the face normals.
/// Vertices with the same position move together. Deterministic and single-threaded.
void refineLevelPositions(const Mesh& input, Mesh& level);

} // namespace lodbake::detail
