#pragma once
// The LODBAKE_cluster_lod page writer both entry points run (cluster_lod_pack.h with the pages in
// memory, cluster_pack_stream.h with the pages spilled to a file): pages read from a source in page
// order, coded in parallel (at most pages_in_flight at once), handed to a sink in page order, and the
// table filled as they are committed. The bytes depend on the hierarchy and the options only.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "lodbake/core/status.h"
#include "lodbake/pack/cluster_lod_pack.h"
#include "lodbake/pack/cluster_pack_stream.h"
#include "lodrt/cluster_lod.h"

namespace lodbake::detail {

struct ClusterPagesWritten {
    std::vector<uint8_t> table;
    ClusterPackStats stats;
    uint64_t accounted_peak_bytes = 0;
};

/// Receives each coded page's bytes (stream then runs), in page order.
using ClusterPageSink = std::function<Status(const uint8_t* data, size_t size)>;

struct ClusterPageWriterOptions {
    ClusterPackOptions pack;
    size_t pages_in_flight = 1;
    const std::atomic<bool>* cancel = nullptr;
    Status cancelled;              // returned when `cancel` is set
    uint64_t sink_bytes = 0;       // memory the sink holds (accounted)
};

/// Checks `table` is a hierarchy (lodrt::validateClusterLod) with clusters and roots (InvalidInput);
/// only then may it be planned.
Status checkClusterPackTable(const lodrt::ClusterLodView& table);
/// Checks `table` and its `plan` against the format's limits (InvalidInput).
Status checkClusterPackLimits(const lodrt::ClusterLodView& table, const ClusterPagePlan& plan);

/// Codes every page of `plan` (checked) and returns the table; pages go to `sink`.
Result<ClusterPagesWritten> writeClusterPages(const lodrt::ClusterLodView& table, const ClusterPagePlan& plan,
                                              const ClusterPackBounds& bounds, ClusterPageSource& source,
                                              const ClusterPageWriterOptions& options, const ClusterPageSink& sink);

} // namespace lodbake::detail
