#pragma once
// The LODBAKE_cluster_lod writer for hierarchies larger than memory (docs/pipeline.md, "Streamed
// pack writer"): it holds the hierarchy's table part (cluster, group, children and root records,
// no geometry) and asks a ClusterPageSource for the geometry of one page's clusters at a time, in
// page order. Each page is coded as writeClusterLodPack codes it (cluster_lod_pack.h: one grid for
// every page, decoded back with the runtime decoder for the cones and spheres) and appended to a
// spill file beside the output; the table is filled as pages are coded. writePackGlbFile
// (pack_glb.h) then writes the GLB with the spill copied in place of the pages blob. For the same
// hierarchy and options the bytes are those of writeClusterLodPack (which runs the same code with
// the pages in memory), for any thread count and any pages_in_flight.
//
// Memory formula (bytes; C clusters, G groups, H group children, R roots, P pages, J pages in
// flight; a page of T triangles whose clusters have V vertices in all, as the table counts them):
//   bound = 48 C + 48 G + 4 H + 4 R + 16 P + 64              (the table being filled)
//         + 4 C + 4 P + 4                                    (the page plan: each page's clusters)
//         + J * max over pages of (12 V + 3 T                (a page's geometry from the source)
//                                  + kClusterPageBytesPerTriangle T)  (coding it)
//         + the spill's write buffer (1 MiB by default)
// plus the caller's table records (ClusterLodView: 60 C + 48 G + 4 H + 4 R, lent, not copied).
// clusterPackStreamBound() computes it; the writer reports the bytes it accounted at most (each
// slot's geometry at its capacity, each page in flight at the allowance). A source that grows its
// arrays beyond the counts (push_back doubling) is held at its capacity and can exceed it.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "lodbake/cluster/cluster_lod.h"
#include "lodbake/core/math.h"
#include "lodbake/core/status.h"
#include "lodbake/pack/cluster_lod_pack.h"
#include "lodbake/pack/pack.h"
#include "lodbake/core/spill_file.h"

namespace lodbake {

/// Bytes per page triangle allowed for coding one page: the welded page mesh and its weld table,
/// the valence encoder's working set and output, the decoded page, and the per-cluster normals and
/// vertex lists the cones and spheres are derived from. An allowance with margin over the heap
/// peak measured for one page (cluster_pack_bench --stream), not a proven bound.
constexpr uint64_t kClusterPageBytesPerTriangle = 1024;

/// The hierarchy's bounding box, accumulated point by point; the shared grid is its cube. add()
/// takes the first point as is and then keeps the smaller (larger) coordinate, so points added in
/// the hierarchy's position order give the bits writeClusterLodPack derives (a -0 against a +0
/// keeps the first seen).
struct ClusterPackBounds {
    float min[3] = {0, 0, 0};
    float max[3] = {0, 0, 0};
    bool empty = true;
    void add(const Vec3f& p);
};

/// The geometry of one page's clusters, as a source hands it over.
struct ClusterPageGeometry {
    std::vector<Vec3f> positions; // each cluster's vertex_count positions, the page's clusters in order
    std::vector<uint8_t> indices; // each cluster's 3 * triangle_count indices into its own positions
};

/// Where the pages' geometry comes from. readPage is called once per page, in page order (0, 1, ...),
/// from one thread at a time; `clusters` are the page's clusters in ascending id (the table's order).
/// `out` comes cleared (its capacity kept from earlier pages). An error stops the writer and is
/// returned as is.
class ClusterPageSource {
public:
    virtual ~ClusterPageSource() = default;
    virtual Status readPage(uint32_t page, const uint32_t* clusters, size_t count, ClusterPageGeometry& out) = 0;
};

/// A source over a hierarchy in memory (the in-memory bake, and the streamed writer's test oracle).
class HierarchyPageSource : public ClusterPageSource {
public:
    explicit HierarchyPageSource(const ClusterLodHierarchy& hierarchy) : h_(hierarchy) {}
    Status readPage(uint32_t page, const uint32_t* clusters, size_t count, ClusterPageGeometry& out) override;

private:
    const ClusterLodHierarchy& h_;
};

/// The bounds of every position of `hierarchy`, in order (what writeClusterLodPack uses).
ClusterPackBounds clusterPackBounds(const ClusterLodHierarchy& hierarchy);

/// The pages: page p holds clusters [page_first[p], page_first[p + 1]) of page_clusters. Group g's
/// inputs are page g (sorted), then the roots in pages of up to 32 (each sorted), as
/// docs/format/cluster_lod.md lays them out. A source may use it to prepare its reads.
struct ClusterPagePlan {
    std::vector<uint32_t> page_first;
    std::vector<uint32_t> page_clusters;
    size_t pageCount() const { return page_first.empty() ? 0 : page_first.size() - 1; }
};
ClusterPagePlan planClusterPages(const lodrt::ClusterLodView& table);

struct ClusterPackStreamOptions {
    ClusterPackOptions pack;
    /// Pages read, then coded in parallel, at once; 0: twice the worker threads. Never changes bytes.
    size_t pages_in_flight = 0;
    size_t spill_buffer_bytes = size_t(1) << 20;
    const std::atomic<bool>* cancel = nullptr; // set to stop: the writer fails and removes its spill
};

struct ClusterPackStreamResult {
    /// kExtClusterLod with the table blob in memory and the pages blob in `pages` (extension.spilled[1]).
    PackExtension extension;
    ClusterPackStats stats;
    std::shared_ptr<SpillFile> pages; // the spill, removed when the last owner drops it
    uint64_t memory_bound_bytes = 0;     // the formula above
    uint64_t accounted_peak_bytes = 0;   // the arrays held at most, coding at its per-triangle allowance
};

/// The formula above for `table` and its `plan` at `pages_in_flight` pages (not 0) and
/// `spill_buffer_bytes` (at least 4 KiB, as SpillFile holds).
uint64_t clusterPackStreamBound(const lodrt::ClusterLodView& table, const ClusterPagePlan& plan,
                                size_t pages_in_flight, size_t spill_buffer_bytes);

/// Writes the pack of the hierarchy whose records are `table` (it must pass lodrt::validateClusterLod;
/// the clusters' vertex and triangle ranges are the source's business and are only checked against
/// table.vertex_count and triangle_count), the grid from `bounds` (every cluster vertex), the
/// geometry from `source`. The pages go to a spill beside `output_path` (a temporary in its folder,
/// named after it). Errors as writeClusterLodPack's, and: the source's; geometry that does not
/// match the table (InvalidInput); IoError naming `output_path` for a failed spill write or a
/// cancel. On any error the spill is already removed.
Result<ClusterPackStreamResult> writeClusterLodPackStreamed(const lodrt::ClusterLodView& table,
                                                            const ClusterPackBounds& bounds, ClusterPageSource& source,
                                                            const std::string& output_path,
                                                            const ClusterPackStreamOptions& options);

} // namespace lodbake
