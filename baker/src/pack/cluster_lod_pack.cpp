// LODBAKE_cluster_lod writer (lodbake/pack/cluster_lod_pack.h, docs/format/cluster_lod.md): the page
// writer (pack/cluster_page_writer.h) over the hierarchy in memory, its pages appended to one blob.
#include "lodbake/pack/cluster_lod_pack.h"

#include <vector>

#include "core/parallel.h"
#include "lodbake/pack/cluster_pack_stream.h"
#include "lodrt/format.h"
#include "pack/cluster_page_writer.h"

namespace lodbake {

namespace {

namespace fmt = lodrt::format;

// Pages coded at once per worker thread: the pages are in memory anyway, so batches only need to be
// large enough that uneven pages keep every thread busy.
constexpr size_t kPagesPerThread = 16;

} // namespace

Result<ClusterPackResult> writeClusterLodPack(const ClusterLodHierarchy& h, const ClusterPackOptions& options) {
    if (options.position_bits < fmt::kValenceMinPositionBits || options.position_bits > fmt::kValenceMaxPositionBits)
        return invalidInput("cluster pack: position bits outside 8..16");
    const lodrt::ClusterLodView table = h.view();
    LODBAKE_RETURN_IF_ERROR(detail::checkClusterPackTable(table));
    const ClusterPagePlan plan = planClusterPages(table);
    LODBAKE_RETURN_IF_ERROR(detail::checkClusterPackLimits(table, plan));
    HierarchyPageSource source(h);
    std::vector<uint8_t> blob;
    detail::ClusterPageWriterOptions writer;
    writer.pack = options;
    writer.pages_in_flight = kPagesPerThread * maxParallelism();
    LODBAKE_ASSIGN_OR_RETURN(detail::ClusterPagesWritten written,
                             detail::writeClusterPages(table, plan, clusterPackBounds(h), source, writer,
                                                       [&blob](const uint8_t* data, size_t size) {
                                                           blob.insert(blob.end(), data, data + size);
                                                           return Status::okStatus();
                                                       }));
    ClusterPackResult result;
    result.stats = written.stats;
    PackExtension& e = result.extension;
    e.name = fmt::kExtClusterLod;
    e.json = JsonNode::object();
    e.blobs.push_back(std::move(written.table));
    e.blob_view_members.push_back(fmt::kClusterTableMember);
    e.blobs.push_back(std::move(blob));
    e.blob_view_members.push_back(fmt::kClusterPagesMember);
    // Beside LOD0 and its MSFT_lod chain, never instead of them: not a stream --compact requires.
    e.is_stream = false;
    return result;
}

} // namespace lodbake
