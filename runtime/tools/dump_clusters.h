#pragma once
// loddump's view of LODBAKE_cluster_lod (docs/format/cluster_lod.md): the hierarchy's counts per
// depth and its page sizes, and the checks of a good bake: every page decodes, errors and LOD spheres
// grow up the DAG, every cluster is reachable from the roots, and cuts from a few views have no
// boundary edge that LOD0 lacks.

#include <cstdint>
#include <string>
#include <vector>

#include "contact_sheet.h"
#include "lodrt/pack.h"

namespace loddump {

struct ClusterDepthRow {
    uint32_t depth = 0; // 0: LOD0 clusters; d: outputs of groups of depth d
    uint64_t clusters = 0;
    uint64_t triangles = 0;
    double max_error = 0; // largest own error of its clusters (their self group's)
};

struct ClusterSummary {
    uint32_t mesh = 0;
    uint32_t clusters = 0, groups = 0, roots = 0, pages = 0, cone_clusters = 0;
    uint32_t position_bits = 0;
    double quantization_error = 0;
    uint64_t table_bytes = 0, page_bytes = 0, min_page_bytes = 0, max_page_bytes = 0;
    uint64_t lod0_triangles = 0;
    uint32_t cuts_checked = 0;
    std::vector<ClusterDepthRow> depths;
};

/// Reads, decodes and checks mesh `mesh`'s extension (which must be present). False with a one-line
/// message (the element inside the extension, then what was expected) on the first problem.
bool checkClusterLod(const lodrt::Pack& pack, uint32_t mesh, ClusterSummary* out, std::string* error);

/// loddump --render: the cuts of mesh `mesh`'s hierarchy for an eye on the contact sheet's camera
/// direction at 2, 8 and 32 times the roots' radius from their centre (1 px threshold, 1080 px
/// viewport, 60 degree field of view), each cluster in one of a few colours so that clusters and
/// their sizes show. False with a one-line message when the extension does not read or decode.
bool clusterCutSheets(const lodrt::Pack& pack, uint32_t mesh, std::vector<SheetMesh>* out, std::string* error);

} // namespace loddump
