// The merge job (lodbake/ooc/partition_merge.h): two hierarchy files' roots in, continued as one
// hierarchy, out as a content-hashed file.
#include "lodbake/ooc/partition_merge.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <system_error>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "lodbake/core/file_io.h"
#include "lodbake/core/hash.h"
#include "lodbake/core/spill_file.h"
#include "lodrt/format.h"

namespace lodbake::ooc {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "merge files are written as little-endian arrays");

namespace {

constexpr uint64_t kBuffer = uint64_t(1) << 20;
constexpr size_t kPartitionHeader = lodrt::format::kPartitionLodHeaderBytes;
constexpr size_t kMergeHeader = lodrt::format::kPartitionMergeHeaderBytes;
constexpr size_t kSeedRecord = lodrt::format::kMergeSeedRecordBytes;
constexpr uint32_t kNone = lodrt::kClusterNone;

// The counts both layouts share, in header order.
enum Count { kClusters, kGroups, kChildren, kRoots, kPositions, kTriangles, kLod0, kLevels, kSingle, kBorderVerts, kBorderEdges };

template <class T>
uint64_t bytesOf(const std::vector<T>& v) {
    return uint64_t(v.capacity()) * sizeof(T);
}

struct Closer {
    int fd = -1;
    ~Closer() {
        if (fd >= 0) ::close(fd);
    }
};

std::string stemOf(const std::string& path) {
    return std::filesystem::path(path).stem().string();
}

// A hierarchy file's roots, what they carry, and its border: all the merge needs of an input.
struct InputTop {
    std::string path;
    LodFileKind kind = LodFileKind::Partition;
    uint64_t hash = 0;
    uint32_t counts[11] = {};
    uint64_t offset[10] = {}; // clusters, groups, children, roots, positions, indices, border ids,
                              // border positions, border edges, seeds
    std::vector<uint32_t> roots;
    std::vector<lodrt::ClusterLodCluster> records;
    std::vector<ClusterLodSeed::Cluster> carried; // per root: error, spheres, depth
    std::vector<Vec3f> positions;                 // the roots' vertices, root after root
    std::vector<uint8_t> indices;                 // the roots' triangles (local indices)
    std::vector<uint32_t> border_ids;
    std::vector<Vec3f> border_positions;
    std::vector<uint32_t> border_edges;
    uint64_t root_vertices = 0, root_triangles = 0;

    uint64_t bytes() const {
        return bytesOf(roots) + bytesOf(records) + bytesOf(carried) + bytesOf(positions) + bytesOf(indices) +
               bytesOf(border_ids) + bytesOf(border_positions) + bytesOf(border_edges);
    }
};

Status corrupt(const std::string& path, const std::string& what) {
    return invalidInput(path + ": " + what);
}

// Header, size and content hash (hashed through one buffer, checked against the name when the name
// is a content hash).
Status readHeader(int fd, InputTop& in) {
    struct stat st {};
    if (::fstat(fd, &st) != 0) return ioError(in.path + ": cannot stat: " + std::strerror(errno));
    const uint64_t size = uint64_t(st.st_size);
    uint8_t head[kMergeHeader];
    if (size < kPartitionHeader || !readAt(fd, 0, head, kPartitionHeader, in.path).ok())
        return corrupt(in.path, "header: expected a partition hierarchy or a merge (magic LBPLOD01 or LBPMRG01)");
    size_t header = kPartitionHeader;
    if (std::memcmp(head, lodrt::format::kPartitionLodMagic, 8) == 0) {
        in.kind = LodFileKind::Partition;
        std::memcpy(in.counts, head + 16, sizeof in.counts);
    } else if (std::memcmp(head, lodrt::format::kPartitionMergeMagic, 8) == 0 && size >= kMergeHeader &&
               readAt(fd, 0, head, kMergeHeader, in.path).ok()) {
        in.kind = LodFileKind::Merge;
        header = kMergeHeader;
        std::memcpy(in.counts, head + 32, sizeof in.counts);
    } else {
        return corrupt(in.path, "header: expected a partition hierarchy or a merge (magic LBPLOD01 or LBPMRG01)");
    }
    const uint32_t* c = in.counts;
    const uint64_t sizes[10] = {60 * uint64_t(c[kClusters]),    48 * uint64_t(c[kGroups]),
                                4 * uint64_t(c[kChildren]),     4 * uint64_t(c[kRoots]),
                                12 * uint64_t(c[kPositions]),   3 * uint64_t(c[kTriangles]),
                                4 * uint64_t(c[kBorderVerts]),  12 * uint64_t(c[kBorderVerts]),
                                8 * uint64_t(c[kBorderEdges]),
                                in.kind == LodFileKind::Merge ? kSeedRecord * c[kLod0] : 0};
    uint64_t at = header;
    for (int i = 0; i < 10; ++i) {
        in.offset[i] = at;
        at += sizes[i];
    }
    if (size != at)
        return corrupt(in.path, "header: the counts need " + std::to_string(at) + " bytes, the file has " +
                                    std::to_string(size));
    if (c[kLod0] > c[kClusters] || c[kRoots] == 0 || c[kRoots] > c[kClusters])
        return corrupt(in.path, "header: expected 1..clusters roots and at most clusters level-0 clusters");
    Hasher hasher;
    std::vector<uint8_t> buffer(size_t(std::min<uint64_t>(kBuffer, size)));
    for (uint64_t off = 0; off < size;) {
        const size_t n = size_t(std::min<uint64_t>(buffer.size(), size - off));
        LODBAKE_RETURN_IF_ERROR(readAt(fd, off, buffer.data(), n, in.path));
        hasher.addBytes(buffer.data(), n);
        off += n;
    }
    in.hash = hasher.digest();
    const std::string stem = stemOf(in.path);
    if (stem.size() == 16 && stem.find_first_not_of("0123456789abcdef") == std::string::npos &&
        stem != hashToHex(in.hash))
        return corrupt(in.path, "content: expected bytes hashing to the file's name (" + stem + "), got " +
                                    hashToHex(in.hash) + ": the file is corrupted");
    return Status::okStatus();
}

bool finiteSphere(const float c[3], float r) {
    return std::isfinite(c[0]) && std::isfinite(c[1]) && std::isfinite(c[2]) && std::isfinite(r) && r >= 0;
}

// The roots' records and what each carries (its self group's error and spheres, or a seed's, or an
// LOD0 cluster's own sphere), checked.
Status readRootRecords(int fd, InputTop& in) {
    const uint32_t* c = in.counts;
    in.roots.resize(c[kRoots]);
    LODBAKE_RETURN_IF_ERROR(readAt(fd, in.offset[3], in.roots.data(), 4 * in.roots.size(), in.path));
    in.records.resize(in.roots.size());
    in.carried.resize(in.roots.size());
    for (size_t i = 0; i < in.roots.size(); ++i) {
        const std::string at = "root " + std::to_string(i) + ": ";
        const uint32_t r = in.roots[i];
        if (r >= c[kClusters]) return corrupt(in.path, at + "cluster out of range");
        if (i > 0 && r <= in.roots[i - 1]) return corrupt(in.path, at + "expected roots in increasing order");
        lodrt::ClusterLodCluster& rec = in.records[i];
        LODBAKE_RETURN_IF_ERROR(readAt(fd, in.offset[0] + 60 * uint64_t(r), &rec, 60, in.path));
        if (rec.parent_group != kNone || rec.triangle_count == 0 || rec.triangle_count > 128 ||
            rec.vertex_count == 0 || rec.vertex_count > 255 ||
            uint64_t(rec.first_vertex) + rec.vertex_count > c[kPositions] ||
            uint64_t(rec.first_triangle) + rec.triangle_count > c[kTriangles] || !finiteSphere(rec.center, rec.radius))
            return corrupt(in.path, at + "expected a root cluster within the limits and the file's arrays");
        ClusterLodSeed::Cluster& s = in.carried[i];
        s.triangle_count = rec.triangle_count;
        if (rec.self_group != kNone) {
            if (rec.self_group >= c[kGroups]) return corrupt(in.path, at + "group out of range");
            lodrt::ClusterLodGroup g;
            LODBAKE_RETURN_IF_ERROR(readAt(fd, in.offset[1] + 48 * uint64_t(rec.self_group), &g, 48, in.path));
            s.error = g.error;
            std::copy(g.lod_center, g.lod_center + 3, s.lod_center);
            s.lod_radius = g.lod_radius;
            std::copy(g.bounds_center, g.bounds_center + 3, s.bounds_center);
            s.bounds_radius = g.bounds_radius;
            s.depth = g.depth;
        } else if (r >= c[kLod0]) {
            return corrupt(in.path, at + "expected a level-0 cluster or a group's output");
        } else if (in.kind == LodFileKind::Partition) {
            std::copy(rec.center, rec.center + 3, s.lod_center);
            s.lod_radius = rec.radius;
            std::copy(rec.center, rec.center + 3, s.bounds_center);
            s.bounds_radius = rec.radius;
        } else {
            uint8_t seed[kSeedRecord];
            LODBAKE_RETURN_IF_ERROR(readAt(fd, in.offset[9] + kSeedRecord * r, seed, kSeedRecord, in.path));
            std::memcpy(&s.depth, seed + 4, 4);
            std::memcpy(&s.error, seed + 8, 4);
            std::memcpy(s.lod_center, seed + 12, 12);
            std::memcpy(&s.lod_radius, seed + 24, 4);
            std::memcpy(s.bounds_center, seed + 28, 12);
            std::memcpy(&s.bounds_radius, seed + 40, 4);
        }
        if (!(std::isfinite(s.error) && s.error >= 0) || !finiteSphere(s.lod_center, s.lod_radius) ||
            !finiteSphere(s.bounds_center, s.bounds_radius))
            return corrupt(in.path, at + "expected a finite, non-negative error and spheres");
        in.root_vertices += rec.vertex_count;
        in.root_triangles += rec.triangle_count;
    }
    return Status::okStatus();
}

// The roots' geometry and the border.
Status readGeometry(int fd, InputTop& in) {
    in.positions.resize(in.root_vertices);
    in.indices.resize(in.root_triangles * 3);
    size_t v = 0, t = 0;
    for (size_t i = 0; i < in.records.size(); ++i) {
        const lodrt::ClusterLodCluster& rec = in.records[i];
        LODBAKE_RETURN_IF_ERROR(readAt(fd, in.offset[4] + 12 * uint64_t(rec.first_vertex), &in.positions[v],
                                       12 * size_t(rec.vertex_count), in.path));
        LODBAKE_RETURN_IF_ERROR(readAt(fd, in.offset[5] + 3 * uint64_t(rec.first_triangle), &in.indices[t],
                                       3 * size_t(rec.triangle_count), in.path));
        for (size_t k = t; k < t + 3 * size_t(rec.triangle_count); ++k)
            if (in.indices[k] >= rec.vertex_count)
                return corrupt(in.path, "root " + std::to_string(i) + ": vertex index out of range");
        for (size_t k = v; k < v + rec.vertex_count; ++k)
            if (!isFinite(in.positions[k])) return corrupt(in.path, "root " + std::to_string(i) + ": non-finite position");
        v += rec.vertex_count;
        t += 3 * size_t(rec.triangle_count);
    }
    const uint32_t b = in.counts[kBorderVerts], e = in.counts[kBorderEdges];
    in.border_ids.resize(b);
    in.border_positions.resize(b);
    in.border_edges.resize(size_t(e) * 2);
    LODBAKE_RETURN_IF_ERROR(readAt(fd, in.offset[6], in.border_ids.data(), 4 * size_t(b), in.path));
    LODBAKE_RETURN_IF_ERROR(readAt(fd, in.offset[7], in.border_positions.data(), 12 * size_t(b), in.path));
    LODBAKE_RETURN_IF_ERROR(readAt(fd, in.offset[8], in.border_edges.data(), 8 * size_t(e), in.path));
    for (size_t i = 1; i < in.border_ids.size(); ++i)
        if (in.border_ids[i] <= in.border_ids[i - 1])
            return corrupt(in.path, "border: expected global ids in increasing order");
    for (uint32_t x : in.border_edges)
        if (x >= b) return corrupt(in.path, "border: edge vertex out of range");
    for (const Vec3f& p : in.border_positions)
        if (!isFinite(p)) return corrupt(in.path, "border: non-finite position");
    return Status::okStatus();
}

struct PositionKey {
    uint32_t bits[3];
    bool operator<(const PositionKey& o) const {
        if (bits[0] != o.bits[0]) return bits[0] < o.bits[0];
        if (bits[1] != o.bits[1]) return bits[1] < o.bits[1];
        return bits[2] < o.bits[2];
    }
    bool operator==(const PositionKey& o) const {
        return bits[0] == o.bits[0] && bits[1] == o.bits[1] && bits[2] == o.bits[2];
    }
};

PositionKey keyOf(const Vec3f& p) {
    PositionKey k;
    const float v[3] = {p.x + 0.0f, p.y + 0.0f, p.z + 0.0f}; // -0 and +0 are one position
    for (int a = 0; a < 3; ++a) std::memcpy(&k.bits[a], &v[a], 4);
    return k;
}

// Global vertex identity across the two borders: ids at one position of one file are one vertex
// (its builder welded them), and that joins them in the other file too (union-find over ids).
struct BorderClasses {
    std::vector<uint32_t> ids;    // every id of either border, ascending, unique
    std::vector<uint32_t> parent; // union-find; a class's root is its smallest id's index
    std::vector<Vec3f> position;  // per id

    uint32_t indexOf(uint32_t id) const {
        return uint32_t(std::lower_bound(ids.begin(), ids.end(), id) - ids.begin());
    }
    uint32_t find(uint32_t i) {
        while (parent[i] != i) i = parent[i] = parent[parent[i]];
        return i;
    }
    void unite(uint32_t a, uint32_t b) {
        a = find(a);
        b = find(b);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
};

BorderClasses classesOf(const InputTop* in[2]) {
    BorderClasses bc;
    for (int i = 0; i < 2; ++i) bc.ids.insert(bc.ids.end(), in[i]->border_ids.begin(), in[i]->border_ids.end());
    std::sort(bc.ids.begin(), bc.ids.end());
    bc.ids.erase(std::unique(bc.ids.begin(), bc.ids.end()), bc.ids.end());
    bc.parent.resize(bc.ids.size());
    bc.position.resize(bc.ids.size());
    for (uint32_t i = 0; i < bc.parent.size(); ++i) bc.parent[i] = i;
    for (int i = 0; i < 2; ++i) {
        std::vector<std::pair<PositionKey, uint32_t>> keys;
        for (size_t v = 0; v < in[i]->border_ids.size(); ++v) {
            const uint32_t x = bc.indexOf(in[i]->border_ids[v]);
            bc.position[x] = in[i]->border_positions[v];
            keys.push_back({keyOf(in[i]->border_positions[v]), x});
        }
        std::sort(keys.begin(), keys.end());
        for (size_t k = 1; k < keys.size(); ++k)
            if (keys[k].first == keys[k - 1].first) bc.unite(keys[k].second, keys[k - 1].second);
    }
    return bc;
}

// The seed: the border classes are the first points, then each input's other root vertices welded
// by position within the input. Roots of a, then of b, in their files' root order.
ClusterLodSeed seedOf(const InputTop* in[2], BorderClasses& bc, uint64_t& peak_extra) {
    ClusterLodSeed seed;
    std::vector<uint32_t> class_point(bc.ids.size(), kNone);
    for (uint32_t x = 0; x < bc.ids.size(); ++x)
        if (bc.find(x) == x) {
            class_point[x] = uint32_t(seed.points.size());
            seed.points.push_back(bc.position[x]);
        }
    for (int i = 0; i < 2; ++i) {
        const InputTop& t = *in[i];
        std::vector<std::pair<PositionKey, uint32_t>> border;
        for (size_t v = 0; v < t.border_ids.size(); ++v) {
            const uint32_t x = bc.find(bc.indexOf(t.border_ids[v]));
            border.push_back({keyOf(t.border_positions[v]), class_point[x]});
        }
        std::sort(border.begin(), border.end());
        std::vector<std::pair<PositionKey, uint32_t>> keys(t.positions.size());
        for (uint32_t v = 0; v < keys.size(); ++v) keys[v] = {keyOf(t.positions[v]), v};
        std::sort(keys.begin(), keys.end());
        std::vector<uint32_t> point_of(t.positions.size());
        for (size_t k = 0; k < keys.size(); ++k) {
            if (k == 0 || !(keys[k].first == keys[k - 1].first)) {
                const auto it = std::lower_bound(border.begin(), border.end(), std::make_pair(keys[k].first, 0u));
                if (it != border.end() && it->first == keys[k].first) {
                    point_of[keys[k].second] = it->second;
                } else {
                    point_of[keys[k].second] = uint32_t(seed.points.size());
                    seed.points.push_back(t.positions[keys[k].second]);
                }
            } else {
                point_of[keys[k].second] = point_of[keys[k - 1].second];
            }
        }
        peak_extra = std::max(peak_extra, bytesOf(keys) + bytesOf(point_of) + bytesOf(border));
        size_t v = 0, f = 0;
        for (size_t r = 0; r < t.records.size(); ++r) {
            ClusterLodSeed::Cluster s = t.carried[r];
            s.first_triangle = uint32_t(seed.triangles.size() / 3);
            for (size_t k = 0; k < 3 * size_t(t.records[r].triangle_count); ++k)
                seed.triangles.push_back(point_of[v + t.indices[f + k]]);
            seed.clusters.push_back(s);
            v += t.records[r].vertex_count;
            f += 3 * size_t(t.records[r].triangle_count);
        }
    }
    return seed;
}

// The output's border: both borders less the edges on both (by class), with every id of a class
// an output edge touches (so a later merge joins the same duplicates). Returns the shared edges.
uint32_t remainingBorder(const InputTop* in[2], BorderClasses& bc, MergedLod& out) {
    struct Edge {
        uint64_t key; // classes, smaller first
        uint32_t a, b; // global ids
        int side;
    };
    std::vector<Edge> edges;
    for (int i = 0; i < 2; ++i)
        for (size_t e = 0; e < in[i]->border_edges.size(); e += 2) {
            const uint32_t a = in[i]->border_ids[in[i]->border_edges[e]], b = in[i]->border_ids[in[i]->border_edges[e + 1]];
            const uint32_t ca = bc.find(bc.indexOf(a)), cb = bc.find(bc.indexOf(b));
            edges.push_back({uint64_t(std::min(ca, cb)) << 32 | std::max(ca, cb), std::min(a, b), std::max(a, b), i});
        }
    std::sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) {
        return x.key != y.key ? x.key < y.key : (x.a != y.a ? x.a < y.a : (x.b != y.b ? x.b < y.b : x.side < y.side));
    });
    std::vector<std::pair<uint32_t, uint32_t>> kept;
    std::vector<uint8_t> class_used(bc.ids.size(), 0);
    uint32_t shared = 0;
    for (size_t i = 0; i < edges.size();) {
        size_t j = i;
        bool sides[2] = {false, false};
        while (j < edges.size() && edges[j].key == edges[i].key) sides[edges[j++].side] = true;
        if (sides[0] && sides[1]) {
            ++shared;
        } else {
            for (size_t k = i; k < j; ++k) kept.push_back({edges[k].a, edges[k].b});
            class_used[edges[i].key >> 32] = class_used[uint32_t(edges[i].key)] = 1;
        }
        i = j;
    }
    for (uint32_t x = 0; x < bc.ids.size(); ++x)
        if (class_used[bc.find(x)]) {
            out.border_ids.push_back(bc.ids[x]);
            out.border_positions.push_back(bc.position[x]);
        }
    const auto at = [&](uint32_t id) {
        return uint32_t(std::lower_bound(out.border_ids.begin(), out.border_ids.end(), id) - out.border_ids.begin());
    };
    std::vector<uint64_t> local;
    for (const auto& e : kept) local.push_back(uint64_t(at(e.first)) << 32 | at(e.second));
    std::sort(local.begin(), local.end());
    local.erase(std::unique(local.begin(), local.end()), local.end());
    for (uint64_t e : local) {
        out.border_edges.push_back(uint32_t(e >> 32));
        out.border_edges.push_back(uint32_t(e));
    }
    return shared;
}

void putSeed(const MergeSeed& s, uint8_t rec[kSeedRecord]) {
    const uint32_t origin = s.input << 31 | s.root;
    std::memcpy(rec, &origin, 4);
    std::memcpy(rec + 4, &s.depth, 4);
    std::memcpy(rec + 8, &s.error, 4);
    std::memcpy(rec + 12, s.lod_center, 12);
    std::memcpy(rec + 24, &s.lod_radius, 4);
    std::memcpy(rec + 28, s.bounds_center, 12);
    std::memcpy(rec + 40, &s.bounds_radius, 4);
}

// The file image, piece by piece, to `put` (hashed once, then written once).
Status emit(const MergedLod& m, const std::function<Status(const void*, size_t)>& put) {
    const ClusterLodHierarchy& h = m.hierarchy;
    const uint32_t kinds[2] = {uint32_t(m.input_kind[0]), uint32_t(m.input_kind[1])};
    const uint32_t counts[11] = {uint32_t(h.clusters.size()), uint32_t(h.groups.size()),
                                 uint32_t(h.group_children.size()), uint32_t(h.roots.size()),
                                 uint32_t(h.positions.size()), uint32_t(h.indices.size() / 3),
                                 h.lod0_cluster_count, h.level_count, h.reached_single_group ? 1u : 0u,
                                 uint32_t(m.border_ids.size()), uint32_t(m.border_edges.size() / 2)};
    LODBAKE_RETURN_IF_ERROR(put(lodrt::format::kPartitionMergeMagic, 8));
    LODBAKE_RETURN_IF_ERROR(put(m.input_hash, 16));
    LODBAKE_RETURN_IF_ERROR(put(kinds, 8));
    LODBAKE_RETURN_IF_ERROR(put(counts, sizeof counts));
    LODBAKE_RETURN_IF_ERROR(put(h.clusters.data(), h.clusters.size() * sizeof(lodrt::ClusterLodCluster)));
    LODBAKE_RETURN_IF_ERROR(put(h.groups.data(), h.groups.size() * sizeof(lodrt::ClusterLodGroup)));
    LODBAKE_RETURN_IF_ERROR(put(h.group_children.data(), h.group_children.size() * 4));
    LODBAKE_RETURN_IF_ERROR(put(h.roots.data(), h.roots.size() * 4));
    LODBAKE_RETURN_IF_ERROR(put(h.positions.data(), h.positions.size() * sizeof(Vec3f)));
    LODBAKE_RETURN_IF_ERROR(put(h.indices.data(), h.indices.size()));
    LODBAKE_RETURN_IF_ERROR(put(m.border_ids.data(), m.border_ids.size() * 4));
    LODBAKE_RETURN_IF_ERROR(put(m.border_positions.data(), m.border_positions.size() * sizeof(Vec3f)));
    LODBAKE_RETURN_IF_ERROR(put(m.border_edges.data(), m.border_edges.size() * 4));
    for (const MergeSeed& s : m.seeds) {
        uint8_t rec[kSeedRecord];
        putSeed(s, rec);
        LODBAKE_RETURN_IF_ERROR(put(rec, kSeedRecord));
    }
    return Status::okStatus();
}

uint64_t mergedBytes(const MergedLod& m) {
    const ClusterLodHierarchy& h = m.hierarchy;
    return bytesOf(h.clusters) + bytesOf(h.groups) + bytesOf(h.group_children) + bytesOf(h.roots) +
           bytesOf(h.positions) + bytesOf(h.indices) + bytesOf(m.seeds) + bytesOf(m.border_ids) +
           bytesOf(m.border_positions) + bytesOf(m.border_edges);
}

// Reads both inputs' headers (hashing them) and root records, and refuses a limit below the bound.
Status openInputs(const std::string paths[2], const MergeOptions& o, InputTop tops[2], Closer fds[2],
                  MergeFile& result) {
    for (int i = 0; i < 2; ++i) {
        tops[i].path = paths[i];
        fds[i].fd = ::open(paths[i].c_str(), O_RDONLY | O_CLOEXEC);
        if (fds[i].fd < 0) return ioError(paths[i] + ": cannot open: " + std::strerror(errno));
        LODBAKE_RETURN_IF_ERROR(readHeader(fds[i].fd, tops[i]));
        LODBAKE_RETURN_IF_ERROR(readRootRecords(fds[i].fd, tops[i]));
    }
    if (tops[0].hash == tops[1].hash)
        return invalidInput(paths[1] + ": content: expected a hierarchy other than " + paths[0] +
                            " (the two inputs hold the same bytes)");
    uint64_t roots = 0, v = 0, t = 0, b = 0, e = 0;
    for (int i = 0; i < 2; ++i) {
        roots += tops[i].roots.size();
        v += tops[i].root_vertices;
        t += tops[i].root_triangles;
        b += tops[i].counts[kBorderVerts];
        e += tops[i].counts[kBorderEdges];
    }
    MergeInputSize both;
    both.roots = roots;
    both.root_vertices = v;
    both.root_triangles = t;
    both.border_vertices = b;
    both.border_edges = e;
    result.memory_bound_bytes = kMergeFixedBytes + both.boundBytes();
    if (result.memory_bound_bytes > o.memory_limit_bytes)
        return resourceLimit(paths[0] + ": memory limit of " + std::to_string(o.memory_limit_bytes >> 20) +
                             " MiB is too small (needs at least " + std::to_string((result.memory_bound_bytes >> 20) + 1) +
                             " MiB to merge it with " + paths[1] + ")");
    return Status::okStatus();
}

Status writeMerged(const MergedLod& m, const MergeOptions& o, MergeFile& result) {
    Hasher hasher;
    LODBAKE_RETURN_IF_ERROR(emit(m, [&](const void* p, size_t n) {
        hasher.addBytes(p, n);
        return Status::okStatus();
    }));
    result.content_hash = hasher.digest();
    std::error_code ec;
    std::filesystem::create_directories(o.work_dir, ec);
    if (ec) return ioError(o.work_dir + ": cannot create the folder: " + ec.message());
    result.path = joinPath(o.work_dir, hashToHex(result.content_hash) + lodrt::format::kPartitionMergeExtension);
    SpillFile file;
    LODBAKE_RETURN_IF_ERROR(file.open(result.path, size_t(kBuffer)));
    LODBAKE_RETURN_IF_ERROR(emit(m, [&](const void* p, size_t n) { return file.write(p, n); }));
    return file.commit();
}

} // namespace

Result<MergeFile> mergePartitionLods(const std::string& a_path, const std::string& b_path, const MergeOptions& o,
                                     Diagnostics& diagnostics) {
    (void)diagnostics; // a continued level that stalls is expected below the top: the roots are reported
    MergeFile result;
    const std::string paths[2] = {a_path, b_path};
    InputTop tops[2];
    {
        Closer fds[2];
        LODBAKE_RETURN_IF_ERROR(openInputs(paths, o, tops, fds, result));
        for (int i = 0; i < 2; ++i) LODBAKE_RETURN_IF_ERROR(readGeometry(fds[i].fd, tops[i]));
    }
    uint64_t peak = kBuffer + tops[0].bytes() + tops[1].bytes();
    const InputTop* in[2] = {&tops[0], &tops[1]};
    MergedLod m;
    BorderClasses bc = classesOf(in);
    const uint64_t border_bytes = bytesOf(bc.ids) + bytesOf(bc.parent) + bytesOf(bc.position);
    result.shared_edges = remainingBorder(in, bc, m);
    uint64_t weld = 0;
    ClusterLodSeed seed = seedOf(in, bc, weld);
    const uint64_t seed_bytes = bytesOf(seed.points) + bytesOf(seed.triangles) + bytesOf(seed.clusters);
    const uint64_t out_border = bytesOf(m.border_ids) + bytesOf(m.border_positions) + bytesOf(m.border_edges);
    peak = std::max(peak, tops[0].bytes() + tops[1].bytes() + border_bytes + out_border + seed_bytes + weld);
    for (int i = 0; i < 2; ++i) {
        m.input_hash[i] = tops[i].hash;
        m.input_kind[i] = tops[i].kind;
        result.input_hash[i] = tops[i].hash;
        result.input_path[i] = paths[i];
        result.input_kind[i] = tops[i].kind;
        for (uint32_t r = 0; r < tops[i].carried.size(); ++r) {
            const ClusterLodSeed::Cluster& c = tops[i].carried[r];
            MergeSeed s;
            s.input = uint32_t(i);
            s.root = r;
            s.depth = c.depth;
            s.error = c.error;
            std::copy(c.lod_center, c.lod_center + 3, s.lod_center);
            s.lod_radius = c.lod_radius;
            std::copy(c.bounds_center, c.bounds_center + 3, s.bounds_center);
            s.bounds_radius = c.bounds_radius;
            m.seeds.push_back(s);
        }
        result.seed_triangles += uint32_t(tops[i].root_triangles);
        tops[i] = InputTop(); // the builder works from the seed
    }
    const uint64_t triangles = result.seed_triangles;
    peak = std::max(peak, seed_bytes + out_border + bytesOf(m.seeds) + kClusterBuildBytesPerTriangle * triangles);
    Diagnostics build_notes;
    Result<ClusterLodHierarchy> built = continueClusterLod(seed, o.cluster, build_notes);
    if (!built.ok()) return Status(built.status().code(), a_path + ": " + built.status().message());
    m.hierarchy = std::move(*built);
    seed = ClusterLodSeed();
    peak = std::max(peak, mergedBytes(m) + kBuffer);
    LODBAKE_RETURN_IF_ERROR(writeMerged(m, o, result));

    const ClusterLodHierarchy& h = m.hierarchy;
    result.seed_count = uint32_t(m.seeds.size());
    result.cluster_count = uint32_t(h.clusters.size());
    result.group_count = uint32_t(h.groups.size());
    result.root_count = uint32_t(h.roots.size());
    for (uint32_t r : h.roots) {
        result.root_vertices += h.clusters[r].vertex_count;
        result.root_triangles += h.clusters[r].triangle_count;
    }
    result.level_count = h.level_count;
    result.border_vertex_count = uint32_t(m.border_ids.size());
    result.border_edge_count = uint32_t(m.border_edges.size() / 2);
    result.reached_single_group = h.reached_single_group;
    result.accounted_peak_bytes = peak;
    return result;
}

Result<MergeInputSize> mergeInputSize(const std::string& path) {
    InputTop top;
    top.path = path;
    Closer fd;
    fd.fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd.fd < 0) return ioError(path + ": cannot open: " + std::strerror(errno));
    LODBAKE_RETURN_IF_ERROR(readHeader(fd.fd, top));
    LODBAKE_RETURN_IF_ERROR(readRootRecords(fd.fd, top));
    MergeInputSize s;
    s.roots = top.roots.size();
    s.root_vertices = top.root_vertices;
    s.root_triangles = top.root_triangles;
    s.border_vertices = top.counts[kBorderVerts];
    s.border_edges = top.counts[kBorderEdges];
    return s;
}

uint64_t MergeInputSize::boundBytes() const {
    return kMergeBytesPerRoot * roots + 48 * root_vertices + 15 * root_triangles +
           kClusterBuildBytesPerTriangle * root_triangles + 64 * border_vertices + 32 * border_edges;
}

Result<MergedLod> readMergeFile(const std::string& path) {
    LODBAKE_ASSIGN_OR_RETURN(std::vector<uint8_t> bytes, readFileBytes(path));
    if (bytes.size() < kMergeHeader || std::memcmp(bytes.data(), lodrt::format::kPartitionMergeMagic, 8) != 0)
        return invalidInput(path + ": header: expected a merge (magic LBPMRG01)");
    MergedLod m;
    uint32_t kinds[2], c[11];
    std::memcpy(m.input_hash, bytes.data() + 8, 16);
    std::memcpy(kinds, bytes.data() + 24, 8);
    std::memcpy(c, bytes.data() + 32, sizeof c);
    if (kinds[0] > 1 || kinds[1] > 1) return invalidInput(path + ": header: expected input kinds 0 or 1");
    m.input_kind[0] = LodFileKind(kinds[0]);
    m.input_kind[1] = LodFileKind(kinds[1]);
    const uint64_t expected = kMergeHeader + 60 * uint64_t(c[0]) + 48 * uint64_t(c[1]) + 4 * uint64_t(c[2]) +
                              4 * uint64_t(c[3]) + 12 * uint64_t(c[4]) + 3 * uint64_t(c[5]) + 16 * uint64_t(c[9]) +
                              8 * uint64_t(c[10]) + kSeedRecord * uint64_t(c[6]);
    if (bytes.size() != expected)
        return invalidInput(path + ": header: the counts need " + std::to_string(expected) + " bytes, the file has " +
                            std::to_string(bytes.size()));
    ClusterLodHierarchy& h = m.hierarchy;
    size_t at = kMergeHeader;
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
    take(m.border_ids, c[9]);
    take(m.border_positions, c[9]);
    take(m.border_edges, size_t(c[10]) * 2);
    if (lodrt::validateClusterLod(h.view()) != lodrt::Result::Ok || h.lod0_cluster_count > h.clusters.size())
        return invalidInput(path + ": hierarchy: expected a valid cluster hierarchy");
    for (uint32_t e : m.border_edges)
        if (e >= m.border_ids.size()) return invalidInput(path + ": border: edge vertex out of range");
    m.seeds.resize(c[6]);
    for (MergeSeed& s : m.seeds) {
        const uint8_t* rec = bytes.data() + at;
        uint32_t origin;
        std::memcpy(&origin, rec, 4);
        s.input = origin >> 31;
        s.root = origin & 0x7fffffffu;
        std::memcpy(&s.depth, rec + 4, 4);
        std::memcpy(&s.error, rec + 8, 4);
        std::memcpy(s.lod_center, rec + 12, 12);
        std::memcpy(&s.lod_radius, rec + 24, 4);
        std::memcpy(s.bounds_center, rec + 28, 12);
        std::memcpy(&s.bounds_radius, rec + 40, 4);
        at += kSeedRecord;
    }
    return m;
}

} // namespace lodbake::ooc
