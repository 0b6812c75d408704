// The partition job (lodbake/ooc/partition_build.h).
#include "lodbake/ooc/partition_build.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <functional>
#include <system_error>

#include <fcntl.h>
#include <unistd.h>

#include "lodbake/core/file_io.h"
#include "lodbake/core/hash.h"
#include "lodbake/ooc/partition.h"
#include "lodbake/core/spill_file.h"
#include "lodrt/format.h"

namespace lodbake::ooc {

// The hierarchy's records are written as the host's arrays: little-endian, without padding.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "partition hierarchies are written as little-endian arrays");
static_assert(sizeof(lodrt::ClusterLodCluster) == 60, "a cluster record is 15 four-byte fields");
static_assert(sizeof(lodrt::ClusterLodGroup) == 48, "a group record is 12 four-byte fields");

namespace {

constexpr uint64_t kWriteBuffer = uint64_t(1) << 20;
constexpr size_t kHeaderBytes = lodrt::format::kPartitionLodHeaderBytes;

// The partition's border: its edges not used by exactly two of its triangles (open boundary: the
// cut to other partitions and the input's own boundary; non-manifold edges too, a superset the
// merge narrows down by matching neighbours), as global ids.
void findBorder(const PartitionData& d, PartitionLod& out) {
    std::vector<uint64_t> edges;
    edges.reserve(d.indices.size());
    for (size_t f = 0; f < d.indices.size(); f += 3) {
        const uint32_t* t = &d.indices[f];
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue; // dropped by the builder too
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = t[k], b = t[(k + 1) % 3];
            edges.push_back(uint64_t(std::min(a, b)) << 32 | std::max(a, b));
        }
    }
    std::sort(edges.begin(), edges.end());
    std::vector<uint64_t> border;
    for (size_t i = 0; i < edges.size();) {
        size_t j = i;
        while (j < edges.size() && edges[j] == edges[i]) ++j;
        if (j - i != 2) border.push_back(edges[i]);
        i = j;
    }
    std::vector<uint64_t>().swap(edges);
    std::vector<uint32_t> verts;
    for (uint64_t e : border) {
        verts.push_back(uint32_t(e >> 32));
        verts.push_back(uint32_t(e));
    }
    std::sort(verts.begin(), verts.end());
    verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
    // Local numbers are in increasing global id, so indices into `verts` keep the edges sorted.
    for (uint32_t v : verts) {
        out.border_ids.push_back(d.global_ids[v]);
        out.border_positions.push_back(d.positions[v]);
    }
    for (uint64_t e : border) {
        const auto at = [&](uint32_t v) { return uint32_t(std::lower_bound(verts.begin(), verts.end(), v) - verts.begin()); };
        out.border_edges.push_back(at(uint32_t(e >> 32)));
        out.border_edges.push_back(at(uint32_t(e)));
    }
}

template <class T>
uint64_t bytesOf(const std::vector<T>& v) {
    return uint64_t(v.capacity()) * sizeof(T);
}

uint64_t hierarchyBytes(const PartitionLod& p) {
    const ClusterLodHierarchy& h = p.hierarchy;
    return bytesOf(h.clusters) + bytesOf(h.groups) + bytesOf(h.group_children) + bytesOf(h.roots) +
           bytesOf(h.positions) + bytesOf(h.indices) + bytesOf(p.border_ids) + bytesOf(p.border_positions) +
           bytesOf(p.border_edges);
}

// The file image, piece by piece, to `put` (hashed once, then written once).
Status emit(const PartitionLod& p, const std::function<Status(const void*, size_t)>& put) {
    const ClusterLodHierarchy& h = p.hierarchy;
    const uint32_t counts[11] = {uint32_t(h.clusters.size()),
                                 uint32_t(h.groups.size()),
                                 uint32_t(h.group_children.size()),
                                 uint32_t(h.roots.size()),
                                 uint32_t(h.positions.size()),
                                 uint32_t(h.indices.size() / 3),
                                 h.lod0_cluster_count,
                                 h.level_count,
                                 h.reached_single_group ? 1u : 0u,
                                 uint32_t(p.border_ids.size()),
                                 uint32_t(p.border_edges.size() / 2)};
    LODBAKE_RETURN_IF_ERROR(put(lodrt::format::kPartitionLodMagic, 8));
    LODBAKE_RETURN_IF_ERROR(put(&p.source_hash, 8));
    LODBAKE_RETURN_IF_ERROR(put(counts, sizeof counts));
    LODBAKE_RETURN_IF_ERROR(put(h.clusters.data(), h.clusters.size() * sizeof(lodrt::ClusterLodCluster)));
    LODBAKE_RETURN_IF_ERROR(put(h.groups.data(), h.groups.size() * sizeof(lodrt::ClusterLodGroup)));
    LODBAKE_RETURN_IF_ERROR(put(h.group_children.data(), h.group_children.size() * 4));
    LODBAKE_RETURN_IF_ERROR(put(h.roots.data(), h.roots.size() * 4));
    LODBAKE_RETURN_IF_ERROR(put(h.positions.data(), h.positions.size() * sizeof(Vec3f)));
    LODBAKE_RETURN_IF_ERROR(put(h.indices.data(), h.indices.size()));
    LODBAKE_RETURN_IF_ERROR(put(p.border_ids.data(), p.border_ids.size() * 4));
    LODBAKE_RETURN_IF_ERROR(put(p.border_positions.data(), p.border_positions.size() * sizeof(Vec3f)));
    return put(p.border_edges.data(), p.border_edges.size() * 4);
}

// The partition's vertex and triangle counts from its header, or nothing when the header is not a
// partition's (readPartitionFile then says what is wrong).
bool peekCounts(const std::string& path, uint32_t counts[2]) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return false;
    uint8_t head[16];
    const bool ok = readAt(fd, 0, head, sizeof head, path).ok() &&
                    std::memcmp(head, lodrt::format::kPartitionMagic, 8) == 0;
    ::close(fd);
    if (ok) std::memcpy(counts, head + 8, 8);
    return ok;
}

std::string stemOf(const std::string& path) {
    return std::filesystem::path(path).stem().string();
}

} // namespace

Result<PartitionLodFile> buildPartition(const std::string& partition_path, const PartitionBuildOptions& o,
                                        Diagnostics& diagnostics) {
    (void)diagnostics; // the builder's note about remaining roots is expected here: the roots are reported
    PartitionLodFile result;
    uint32_t counts[2] = {0, 0};
    if (peekCounts(partition_path, counts)) {
        const uint64_t v = counts[0], t = counts[1];
        result.memory_bound_bytes = 16 * v + 12 * t + kClusterBuildBytesPerTriangle * t + kWriteBuffer;
        if (result.memory_bound_bytes > o.memory_limit_bytes)
            return resourceLimit(partition_path + ": memory limit of " + std::to_string(o.memory_limit_bytes >> 20) +
                                 " MiB is too small (needs at least " +
                                 std::to_string((result.memory_bound_bytes >> 20) + 1) + " MiB for this partition)");
    }
    LODBAKE_ASSIGN_OR_RETURN(PartitionData data, readPartitionFile(partition_path));
    const std::string stem = stemOf(partition_path);
    if (stem.size() == 16 && stem.find_first_not_of("0123456789abcdef") == std::string::npos &&
        stem != hashToHex(data.content_hash))
        return invalidInput(partition_path + ": content: expected bytes hashing to the file's name (" + stem +
                            "), got " + hashToHex(data.content_hash) + ": the file is corrupted");
    if (data.indices.empty()) return invalidInput(partition_path + ": triangles: expected at least one");
    const uint64_t input_bytes = bytesOf(data.global_ids) + bytesOf(data.positions) + bytesOf(data.indices);
    const uint64_t triangles = data.indices.size() / 3;

    PartitionLod lod;
    lod.source_hash = data.content_hash;
    findBorder(data, lod);
    uint64_t peak = input_bytes + 8 * triangles * 3; // the border's edge keys
    Diagnostics build_notes;
    Result<ClusterLodHierarchy> built = buildClusterLod(MeshView(data.positions, data.indices), o.cluster, build_notes);
    if (!built.ok()) return Status(built.status().code(), partition_path + ": " + built.status().message());
    lod.hierarchy = std::move(*built);
    peak = std::max(peak, input_bytes + kClusterBuildBytesPerTriangle * triangles);
    PartitionData().global_ids.swap(data.global_ids);
    PartitionData().positions.swap(data.positions);
    PartitionData().indices.swap(data.indices);
    peak = std::max(peak, hierarchyBytes(lod) + kWriteBuffer);

    Hasher hasher;
    LODBAKE_RETURN_IF_ERROR(emit(lod, [&](const void* p, size_t n) {
        hasher.addBytes(p, n);
        return Status::okStatus();
    }));
    result.content_hash = hasher.digest();
    std::error_code ec;
    std::filesystem::create_directories(o.work_dir, ec);
    if (ec) return ioError(o.work_dir + ": cannot create the folder: " + ec.message());
    result.path = joinPath(o.work_dir, hashToHex(result.content_hash) + lodrt::format::kPartitionLodExtension);
    SpillFile file;
    LODBAKE_RETURN_IF_ERROR(file.open(result.path, size_t(kWriteBuffer)));
    LODBAKE_RETURN_IF_ERROR(emit(lod, [&](const void* p, size_t n) { return file.write(p, n); }));
    LODBAKE_RETURN_IF_ERROR(file.commit());

    const ClusterLodHierarchy& h = lod.hierarchy;
    result.source_hash = lod.source_hash;
    result.triangle_count = uint32_t(triangles);
    result.cluster_count = uint32_t(h.clusters.size());
    result.group_count = uint32_t(h.groups.size());
    result.root_count = uint32_t(h.roots.size());
    result.level_count = h.level_count;
    result.border_vertex_count = uint32_t(lod.border_ids.size());
    result.border_edge_count = uint32_t(lod.border_edges.size() / 2);
    result.reached_single_group = h.reached_single_group;
    result.accounted_peak_bytes = peak;
    return result;
}

Result<PartitionLod> readPartitionLodFile(const std::string& path) {
    LODBAKE_ASSIGN_OR_RETURN(std::vector<uint8_t> bytes, readFileBytes(path));
    if (bytes.size() < kHeaderBytes || std::memcmp(bytes.data(), lodrt::format::kPartitionLodMagic, 8) != 0)
        return invalidInput(path + ": header: expected a partition hierarchy (magic LBPLOD01)");
    PartitionLod p;
    uint32_t c[11];
    std::memcpy(&p.source_hash, bytes.data() + 8, 8);
    std::memcpy(c, bytes.data() + 16, sizeof c);
    const uint64_t expected = kHeaderBytes + 60 * uint64_t(c[0]) + 48 * uint64_t(c[1]) + 4 * uint64_t(c[2]) +
                              4 * uint64_t(c[3]) + 12 * uint64_t(c[4]) + 3 * uint64_t(c[5]) + 16 * uint64_t(c[9]) +
                              8 * uint64_t(c[10]);
    if (bytes.size() != expected)
        return invalidInput(path + ": header: the counts need " + std::to_string(expected) + " bytes, the file has " +
                            std::to_string(bytes.size()));
    ClusterLodHierarchy& h = p.hierarchy;
    size_t at = kHeaderBytes;
    auto take = [&](auto& v, size_t n) {
        v.resize(n);
        if (n == 0) return; // data() of an empty array may be null
        std::memcpy(static_cast<void*>(v.data()), bytes.data() + at, n * sizeof(v[0]));
        at += n * sizeof(v[0]);
    };
    take(h.clusters, c[0]);
    take(h.groups, c[1]);
    take(h.group_children, c[2]);
    take(h.roots, c[3]);
    take(h.positions, c[4]);
    take(h.indices, size_t(c[5]) * 3);
    h.lod0_cluster_count = c[6];
    h.level_count = c[7];
    h.reached_single_group = c[8] != 0;
    take(p.border_ids, c[9]);
    take(p.border_positions, c[9]);
    take(p.border_edges, size_t(c[10]) * 2);
    if (lodrt::validateClusterLod(h.view()) != lodrt::Result::Ok || h.lod0_cluster_count > h.clusters.size())
        return invalidInput(path + ": hierarchy: expected a valid cluster hierarchy");
    for (uint32_t e : p.border_edges)
        if (e >= p.border_ids.size()) return invalidInput(path + ": border: edge vertex out of range");
    return p;
}

} // namespace lodbake::ooc
