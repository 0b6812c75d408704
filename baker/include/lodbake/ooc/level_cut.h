#pragma once
// Discrete levels cut from an out-of-core cluster hierarchy (docs/pipeline.md, "The pack of an
// out-of-core bake"). A cut at error threshold t is the set of clusters whose own error is at most
// t and whose parent group's error exceeds it (a root's parent error is infinite, an LOD0 cluster's
// own error 0): the view-independent form of the rule lodrt::selectClusterCut applies per view
// (lodrt/cluster_lod.h). Errors grow up the DAG, so a group's inputs and outputs never both pass,
// the cut covers the surface once and meets edge for edge, and its triangle count does not
// increase with t. findLevelCut searches t for a triangle target over the records of a merge tree
// (TreeClusterTable) alone; extractLevelCut reads the cut's geometry from the tree's files by
// offset (TreePageSource) and welds it into one indexed mesh.
//
// Memory of one extraction (bytes; a cut of C clusters and T triangles whose clusters hold V_c
// vertices, welded to V <= V_c vertices), levelCutBytes():
//   4 C (the cut's list) + 32 V_c (positions read, weld keys, the weld map) + 12 T (corners)
//   + 12 V + 12 T (the mesh) + 12 V (its normals, added by the caller)
// all from the counts findLevelCut returns, so a caller decides before it reads any geometry.

#include <cstdint>
#include <vector>

#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"
#include "lodbake/ooc/tree_pages.h"

namespace lodbake::ooc {

/// A cut of the hierarchy at one error threshold.
struct LevelCut {
    float threshold = 0;          // clusters with own error <= threshold < parent error
    uint64_t triangles = 0;       // of the cut's clusters
    uint64_t cluster_vertices = 0; // of the cut's clusters (before welding)
    uint32_t clusters = 0;
    float error_bound = 0; // largest own error of the cut's clusters: bounds its distance to LOD0
};

/// The formula above for `cut`.
uint64_t levelCutBytes(const LevelCut& cut);

/// The cut at `threshold` (counts only; reads the table's records).
LevelCut measureLevelCut(const TreeClusterTable& table, float threshold);

/// The cut whose triangle count is nearest `target_triangles` among the cuts at 0 and at every group
/// error (binary search: the count does not increase with the threshold); ties go to the finer cut.
LevelCut findLevelCut(const TreeClusterTable& table, uint64_t target_triangles);

/// The cut's clusters as one indexed mesh: positions read from the tree's files through `source`,
/// clusters in table order, vertices welded by their position bits (the cut's clusters share their
/// border points bit for bit) and numbered by first use, triangles that welding made degenerate
/// dropped; no normals. Deterministic. Errors as the source's (each names its file).
Result<Mesh> extractLevelCut(const TreeClusterTable& table, TreePageSource& source, const LevelCut& cut);

} // namespace lodbake::ooc
