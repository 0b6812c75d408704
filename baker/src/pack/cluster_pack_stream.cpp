// The streamed LODBAKE_cluster_lod writer (lodbake/pack/cluster_pack_stream.h): the page writer
// (pack/cluster_page_writer.h) with its pages appended to a spill file beside the output.
#include "lodbake/pack/cluster_pack_stream.h"

#include <algorithm>
#include <cstring>

#include "core/parallel.h"
#include "lodrt/format.h"
#include "pack/cluster_page_writer.h"

namespace lodbake {

namespace {

namespace fmt = lodrt::format;

// Roots get pages of their own, this many clusters each (a group's inputs are one page).
constexpr size_t kRootPageClusters = 32;

} // namespace

void ClusterPackBounds::add(const Vec3f& p) {
    const float c[3] = {p.x, p.y, p.z};
    for (int j = 0; j < 3; ++j) {
        if (empty || c[j] < min[j]) min[j] = c[j];
        if (empty || c[j] > max[j]) max[j] = c[j];
    }
    empty = false;
}

ClusterPackBounds clusterPackBounds(const ClusterLodHierarchy& h) {
    ClusterPackBounds b;
    for (const Vec3f& p : h.positions) b.add(p);
    return b;
}

Status HierarchyPageSource::readPage(uint32_t, const uint32_t* clusters, size_t count, ClusterPageGeometry& out) {
    size_t vertices = 0, triangles = 0;
    for (size_t k = 0; k < count; ++k) {
        vertices += h_.clusters[clusters[k]].vertex_count;
        triangles += h_.clusters[clusters[k]].triangle_count;
    }
    out.positions.reserve(vertices);
    out.indices.reserve(3 * triangles);
    for (size_t k = 0; k < count; ++k) {
        const lodrt::ClusterLodCluster& c = h_.clusters[clusters[k]];
        if (size_t(c.first_vertex) + c.vertex_count > h_.positions.size() ||
            3 * (size_t(c.first_triangle) + c.triangle_count) > h_.indices.size())
            return invalidInput("cluster pack: cluster " + std::to_string(clusters[k]) + ": geometry out of range");
        out.positions.insert(out.positions.end(), h_.positions.begin() + c.first_vertex,
                             h_.positions.begin() + c.first_vertex + c.vertex_count);
        out.indices.insert(out.indices.end(), h_.indices.begin() + 3 * std::ptrdiff_t(c.first_triangle),
                           h_.indices.begin() + 3 * std::ptrdiff_t(c.first_triangle + c.triangle_count));
    }
    return Status::okStatus();
}

ClusterPagePlan planClusterPages(const lodrt::ClusterLodView& t) {
    ClusterPagePlan plan;
    plan.page_clusters.reserve(t.cluster_count);
    plan.page_first.reserve(t.group_count + (t.root_count + kRootPageClusters - 1) / kRootPageClusters + 1);
    plan.page_first.push_back(0);
    auto add = [&](const uint32_t* list, size_t count) {
        const size_t begin = plan.page_clusters.size();
        plan.page_clusters.insert(plan.page_clusters.end(), list, list + count);
        std::sort(plan.page_clusters.begin() + std::ptrdiff_t(begin), plan.page_clusters.end());
        plan.page_first.push_back(uint32_t(plan.page_clusters.size()));
    };
    // A group's inputs are one page (at most kClusterPageMaxClusters, checked by the writer).
    for (uint32_t g = 0; g < t.group_count; ++g) add(t.group_children + t.groups[g].first_child, t.groups[g].child_count);
    for (size_t first = 0; first < t.root_count; first += kRootPageClusters)
        add(t.roots + first, std::min<size_t>(t.root_count - first, kRootPageClusters));
    return plan;
}

uint64_t clusterPackStreamBound(const lodrt::ClusterLodView& t, const ClusterPagePlan& plan, size_t pages_in_flight,
                                size_t spill_buffer_bytes) {
    uint64_t largest = 0;
    for (size_t p = 0; p < plan.pageCount(); ++p) {
        uint64_t triangles = 0, vertices = 0;
        for (uint32_t i = plan.page_first[p]; i < plan.page_first[p + 1]; ++i) {
            triangles += t.clusters[plan.page_clusters[i]].triangle_count;
            vertices += t.clusters[plan.page_clusters[i]].vertex_count;
        }
        largest = std::max(largest, 12 * vertices + (3 + kClusterPageBytesPerTriangle) * triangles);
    }
    const uint64_t table = fmt::kClusterHeaderSize + 48 * (uint64_t(t.cluster_count) + t.group_count) +
                           4 * (uint64_t(t.group_child_count) + t.root_count) + 16 * uint64_t(plan.pageCount());
    const uint64_t planned = 4 * uint64_t(plan.page_clusters.size() + plan.page_first.size());
    return table + planned + uint64_t(pages_in_flight) * largest + spill_buffer_bytes;
}

Result<ClusterPackStreamResult> writeClusterLodPackStreamed(const lodrt::ClusterLodView& table,
                                                            const ClusterPackBounds& bounds, ClusterPageSource& source,
                                                            const std::string& output_path,
                                                            const ClusterPackStreamOptions& options) {
    if (options.pack.position_bits < fmt::kValenceMinPositionBits ||
        options.pack.position_bits > fmt::kValenceMaxPositionBits)
        return invalidInput("cluster pack: position bits outside 8..16");
    LODBAKE_RETURN_IF_ERROR(detail::checkClusterPackTable(table));
    const ClusterPagePlan plan = planClusterPages(table);
    LODBAKE_RETURN_IF_ERROR(detail::checkClusterPackLimits(table, plan));
    if (bounds.empty) return invalidInput("cluster pack: no bounds for the grid");
    const size_t in_flight = options.pages_in_flight > 0 ? options.pages_in_flight : 2 * maxParallelism();
    auto spill = std::make_shared<SpillFile>();
    LODBAKE_RETURN_IF_ERROR(spill->open(output_path, options.spill_buffer_bytes));
    const size_t spill_buffer = spill->bufferBytes();
    detail::ClusterPageWriterOptions writer;
    writer.pack = options.pack;
    writer.pages_in_flight = in_flight;
    writer.cancel = options.cancel;
    writer.cancelled = ioError(output_path + ": writing cancelled");
    writer.sink_bytes = spill_buffer;
    LODBAKE_ASSIGN_OR_RETURN(detail::ClusterPagesWritten written,
                             detail::writeClusterPages(table, plan, bounds, source, writer,
                                                       [&spill](const uint8_t* data, size_t size) {
                                                           return spill->write(data, size);
                                                       }));
    LODBAKE_RETURN_IF_ERROR(spill->finish());
    ClusterPackStreamResult result;
    result.stats = written.stats;
    result.memory_bound_bytes = clusterPackStreamBound(table, plan, in_flight, spill_buffer);
    result.accounted_peak_bytes = written.accounted_peak_bytes;
    PackExtension& e = result.extension;
    e.name = fmt::kExtClusterLod;
    e.json = JsonNode::object();
    e.blobs.push_back(std::move(written.table));
    e.blob_view_members.push_back(fmt::kClusterTableMember);
    e.blobs.emplace_back(); // the pages: in the spill
    e.blob_view_members.push_back(fmt::kClusterPagesMember);
    e.spilled = {nullptr, spill};
    e.is_stream = false;
    result.pages = std::move(spill);
    return result;
}

} // namespace lodbake
