#pragma once
// The LODBAKE_cluster_lod writer (docs/format/cluster_lod.md): a cluster LOD hierarchy
// (cluster/cluster_lod.h) as the extension object on LOD0's mesh, a table buffer view and a pages
// buffer view. Each page holds the input clusters of one group (roots: pages of their own), coded as
// one positions-only valence stream on a quantization grid shared by every page, plus the runs that
// say which decoded triangle belongs to which cluster. The writer decodes every page with the runtime
// decoder and derives from the decoded geometry each cluster's normal cone and its sphere, so what the
// runtime culls with is what it draws.

#include <cstddef>
#include <cstdint>

#include "lodbake/cluster/cluster_lod.h"
#include "lodbake/core/status.h"
#include "lodbake/pack/pack.h"

namespace lodbake {

struct ClusterPackOptions {
    uint32_t position_bits = 14; // the shared grid's bits over the hierarchy's bounding cube, 8..16
};

struct ClusterPackStats {
    size_t table_bytes = 0;
    size_t page_bytes = 0;     // all pages
    size_t run_bytes = 0;      // of which the triangle-to-cluster runs
    size_t page_count = 0;
    size_t max_page_bytes = 0;
    size_t lod0_triangles = 0; // triangles of the LOD0 clusters
    size_t lod0_page_bytes = 0; // bytes of the pages that hold LOD0 clusters only
    size_t cone_clusters = 0;  // clusters with a normal cone (the others are never cone-culled)
    double quantization_error = 0; // added to every group error
};

struct ClusterPackResult {
    PackExtension extension; // kExtClusterLod, its JSON and the two blobs (table, pages)
    ClusterPackStats stats;
};

/// Writes `hierarchy` (it must pass lodrt::validateClusterLod). Deterministic for any thread count
/// (pages are coded in parallel into slots and laid out in page order). Fails (InvalidInput) on a
/// hierarchy outside the format's limits, (Internal) when a decoded page is not what was coded.
Result<ClusterPackResult> writeClusterLodPack(const ClusterLodHierarchy& hierarchy, const ClusterPackOptions& options);

} // namespace lodbake
