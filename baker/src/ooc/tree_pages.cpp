// The pages of a merge tree written without its geometry (lodbake/ooc/tree_pages.h).
#include "lodbake/ooc/tree_pages.h"

#include <algorithm>
#include <cerrno>
#include <cstring>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "lodbake/core/spill_file.h"
#include "lodrt/format.h"

namespace lodbake::ooc {

namespace {

constexpr uint32_t kNone = lodrt::kClusterNone;
constexpr size_t kPartitionHeader = lodrt::format::kPartitionLodHeaderBytes;
constexpr size_t kMergeHeader = lodrt::format::kPartitionMergeHeaderBytes;
constexpr uint64_t kSeedRecord = lodrt::format::kMergeSeedRecordBytes;
constexpr uint32_t kRecordsPerRead = 1024; // cluster records read at once (60 KiB)
static_assert(sizeof(lodrt::ClusterLodCluster) == 60 && sizeof(lodrt::ClusterLodGroup) == 48, "record layout");

// The counts both layouts share, in header order, and the arrays in file order.
enum Count {
    kClusters,
    kGroups,
    kChildren,
    kRoots,
    kPositions,
    kTriangles,
    kLod0,
    kLevels,
    kSingle,
    kBorderVerts,
    kBorderEdges
};
enum Array {
    aClusters,
    aGroups,
    aChildren,
    aRoots,
    aPositions,
    aIndices,
    aBorderIds,
    aBorderPositions,
    aBorderEdges,
    aSeeds
};

// A file's header as read, with its arrays' offsets.
struct Head {
    bool merge = false;
    uint32_t counts[11] = {};
    uint64_t offset[10] = {};
    uint64_t size = 0;
    int64_t mtime_ns = 0;
};

template <class T> uint64_t bytesOf(const std::vector<T>& v) {
    return uint64_t(v.capacity()) * sizeof(T);
}

struct Closer {
    int fd = -1;
    ~Closer() {
        if (fd >= 0) ::close(fd);
    }
};

Status corrupt(const std::string& path, const std::string& what) {
    return invalidInput(path + ": " + what);
}

int64_t mtimeOf(const struct stat& st) {
    return int64_t(st.st_mtim.tv_sec) * 1000000000 + int64_t(st.st_mtim.tv_nsec);
}

Status readHead(int fd, const std::string& path, bool merge, Head& h) {
    struct stat st {};
    if (::fstat(fd, &st) != 0) return ioError(path + ": cannot stat: " + std::strerror(errno));
    h.size = uint64_t(st.st_size);
    h.mtime_ns = mtimeOf(st);
    h.merge = merge;
    const size_t header = merge ? kMergeHeader : kPartitionHeader;
    const char* magic = merge ? lodrt::format::kPartitionMergeMagic : lodrt::format::kPartitionLodMagic;
    uint8_t head[kMergeHeader];
    if (h.size < header || !readAt(fd, 0, head, header, path).ok() || std::memcmp(head, magic, 8) != 0)
        return corrupt(path, merge ? "header: expected a merge (magic LBPMRG01)"
                                   : "header: expected a partition hierarchy (magic LBPLOD01)");
    std::memcpy(h.counts, head + (merge ? 32 : 16), sizeof h.counts);
    const uint32_t* c = h.counts;
    const uint64_t sizes[10] = {60 * uint64_t(c[kClusters]),   48 * uint64_t(c[kGroups]),
                                4 * uint64_t(c[kChildren]),    4 * uint64_t(c[kRoots]),
                                12 * uint64_t(c[kPositions]),  3 * uint64_t(c[kTriangles]),
                                4 * uint64_t(c[kBorderVerts]), 12 * uint64_t(c[kBorderVerts]),
                                8 * uint64_t(c[kBorderEdges]), merge ? kSeedRecord * c[kLod0] : 0};
    uint64_t at = header;
    for (int i = 0; i < 10; ++i) {
        h.offset[i] = at;
        at += sizes[i];
    }
    if (h.size != at)
        return corrupt(path, "header: the counts need " + std::to_string(at) + " bytes, the file has " +
                                 std::to_string(h.size));
    if (c[kLod0] > c[kClusters] || c[kRoots] == 0 || c[kRoots] > c[kClusters])
        return corrupt(path, "header: expected 1..clusters roots and at most clusters level-0 clusters");
    return Status();
}

Status openRead(const std::string& path, Closer& f) {
    f.fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (f.fd < 0) return invalidInput(path + ": cannot open: " + std::strerror(errno));
    return Status();
}

// Every file of the tree (partitions in leaf order, then merges as run) with its header.
struct Files {
    std::vector<std::string> paths;
    std::vector<Head> heads;
    size_t partitions = 0;
    size_t top = 0;
};

Result<Files> readHeads(const MergeTree& tree) {
    if (tree.partitions.empty()) return invalidInput("merge tree: expected at least one partition hierarchy");
    Files files;
    files.partitions = tree.partitions.size();
    files.paths = tree.partitions;
    for (const MergeFile& m : tree.merges) files.paths.push_back(m.path);
    files.heads.resize(files.paths.size());
    bool found = false;
    for (size_t i = 0; i < files.paths.size(); ++i) {
        Closer f;
        LODBAKE_RETURN_IF_ERROR(openRead(files.paths[i], f));
        LODBAKE_RETURN_IF_ERROR(readHead(f.fd, files.paths[i], i >= files.partitions, files.heads[i]));
        if (files.paths[i] == tree.top) {
            files.top = i;
            found = true;
        }
    }
    if (!found) return invalidInput(tree.top + ": expected the top file to be one of the tree's files");
    return files;
}

uint64_t boundOf(const Files& files) {
    uint64_t clusters = 0, groups = 0, children = 0, per_file = 0, transient = 0;
    for (size_t i = 0; i < files.heads.size(); ++i) {
        const uint32_t* c = files.heads[i].counts;
        const bool merge = i >= files.partitions;
        clusters += c[kClusters] - (merge ? c[kLod0] : 0);
        groups += c[kGroups];
        children += c[kChildren];
        per_file += kTreeTableBytesPerFile + 2 * (files.paths[i].size() + 1) + 4 * uint64_t(c[kRoots]);
        transient = std::max(transient, 4 * uint64_t(c[kClusters]) + std::max(merge ? kSeedRecord * c[kLod0] : 0,
                                                                              60 * uint64_t(kRecordsPerRead)));
    }
    return 72 * clusters + 48 * groups + 4 * children + 4 * uint64_t(files.heads[files.top].counts[kRoots]) + per_file +
           transient;
}

uint32_t remapGroup(uint32_t g, uint32_t base) {
    return g == kNone ? kNone : g + base;
}

// The state of the numbering as the files are read in order.
struct Assembly {
    const Files* files = nullptr;
    const MergeTree* tree = nullptr;
    TreeClusterTable* table = nullptr;
    std::vector<std::vector<uint32_t>> root_global; // per file done: its roots' global numbers
    std::vector<uint32_t> lod0_base;                // per partition: its LOD0 clusters' first number
    uint32_t next = 0, groups = 0;
    uint64_t held = 0; // the arrays held besides one file's transients
};

// The global number of every cluster of file `f` (a merge's seeds: its inputs' roots).
Status numberFile(Assembly& a, size_t f, int fd, std::vector<uint32_t>& global, uint32_t own_base) {
    const Head& h = a.files->heads[f];
    const std::string& path = a.files->paths[f];
    const uint32_t lod0 = h.counts[kLod0];
    global.resize(h.counts[kClusters]);
    if (!h.merge) {
        for (uint32_t c = 0; c < lod0; ++c) global[c] = a.lod0_base[f] + c;
    } else {
        const MergeFile& m = a.tree->merges[f - a.files->partitions];
        size_t input[2];
        for (int k = 0; k < 2; ++k) {
            const auto end = a.files->paths.begin() + std::ptrdiff_t(f);
            const auto it = std::find(a.files->paths.begin(), end, m.input_path[k]);
            if (it == end) return corrupt(path, "input " + m.input_path[k] + ": expected a file merged before it");
            input[k] = size_t(it - a.files->paths.begin());
        }
        std::vector<uint8_t> seeds(size_t(kSeedRecord) * lod0);
        if (!seeds.empty()) LODBAKE_RETURN_IF_ERROR(readAt(fd, h.offset[aSeeds], seeds.data(), seeds.size(), path));
        for (uint32_t c = 0; c < lod0; ++c) {
            uint32_t origin;
            std::memcpy(&origin, seeds.data() + kSeedRecord * c, 4);
            const std::vector<uint32_t>& roots = a.root_global[input[origin >> 31]];
            if ((origin & 0x7fffffffu) >= roots.size())
                return corrupt(path, "seed " + std::to_string(c) + ": root out of range");
            global[c] = roots[origin & 0x7fffffffu];
        }
    }
    for (uint32_t c = lod0; c < h.counts[kClusters]; ++c) global[c] = own_base + (c - lod0);
    return Status();
}

// Reads file `f`'s records into the table: its own clusters at their numbers, its seeds' parents,
// its groups with their children renumbered, its roots' numbers.
Status readFile(Assembly& a, size_t f) {
    const Head& h = a.files->heads[f];
    const std::string& path = a.files->paths[f];
    TreeClusterTable& t = *a.table;
    const uint32_t* c = h.counts;
    Closer file;
    LODBAKE_RETURN_IF_ERROR(openRead(path, file));
    Head again;
    LODBAKE_RETURN_IF_ERROR(readHead(file.fd, path, h.merge, again));
    if (again.size != h.size || again.mtime_ns != h.mtime_ns ||
        std::memcmp(again.counts, h.counts, sizeof h.counts) != 0)
        return corrupt(path, "changed while the table was read");
    const uint32_t own_base = a.next, group_base = a.groups;
    const uint32_t lod0 = c[kLod0];
    a.next += c[kClusters] - lod0;
    a.groups += c[kGroups];
    std::vector<uint32_t> global;
    LODBAKE_RETURN_IF_ERROR(numberFile(a, f, file.fd, global, own_base));
    // Beside the global numbers: the seeds' records while numberFile ran, then the read buffer.
    std::vector<lodrt::ClusterLodCluster> buffer(kRecordsPerRead);
    t.accounted_peak_bytes = std::max(
        t.accounted_peak_bytes, a.held + bytesOf(global) + std::max(h.merge ? kSeedRecord * lod0 : 0, bytesOf(buffer)));
    for (uint32_t k = 0; k < c[kClusters]; ++k) {
        if (k % kRecordsPerRead == 0) {
            const uint32_t n = std::min<uint32_t>(kRecordsPerRead, c[kClusters] - k);
            LODBAKE_RETURN_IF_ERROR(
                readAt(file.fd, h.offset[aClusters] + 60 * uint64_t(k), buffer.data(), 60 * size_t(n), path));
        }
        lodrt::ClusterLodCluster rec = buffer[k % kRecordsPerRead];
        const bool groups_ok = (rec.self_group == kNone || rec.self_group < c[kGroups]) &&
                               (rec.parent_group == kNone || rec.parent_group < c[kGroups]);
        if (!groups_ok || uint64_t(rec.first_vertex) + rec.vertex_count > c[kPositions] ||
            uint64_t(rec.first_triangle) + rec.triangle_count > c[kTriangles])
            return corrupt(path, "cluster " + std::to_string(k) + ": expected its groups and ranges within the file");
        if (h.merge && k < lod0) { // a seed: the input's root, which now has a parent here
            t.clusters[global[k]].parent_group = remapGroup(rec.parent_group, group_base);
            continue;
        }
        t.locators[global[k]] = ClusterLocator{uint32_t(f), rec.first_vertex, rec.first_triangle};
        rec.self_group = remapGroup(rec.self_group, group_base);
        rec.parent_group = remapGroup(rec.parent_group, group_base);
        t.clusters[global[k]] = rec;
    }
    const size_t child_base = t.group_children.size();
    t.group_children.resize(child_base + c[kChildren]);
    if (c[kChildren] > 0)
        LODBAKE_RETURN_IF_ERROR(
            readAt(file.fd, h.offset[aChildren], &t.group_children[child_base], 4 * size_t(c[kChildren]), path));
    for (size_t i = child_base; i < t.group_children.size(); ++i) {
        if (t.group_children[i] >= c[kClusters]) return corrupt(path, "group children: cluster out of range");
        t.group_children[i] = global[t.group_children[i]];
    }
    for (uint32_t g = 0; g < c[kGroups]; ++g) {
        lodrt::ClusterLodGroup rec;
        LODBAKE_RETURN_IF_ERROR(readAt(file.fd, h.offset[aGroups] + 48 * uint64_t(g), &rec, 48, path));
        if (uint64_t(rec.first_child) + rec.child_count > c[kChildren])
            return corrupt(path, "group " + std::to_string(g) + ": children out of range");
        rec.first_child += uint32_t(child_base);
        t.level_count = std::max(t.level_count, rec.depth);
        t.groups.push_back(rec);
    }
    std::vector<uint32_t>& roots = a.root_global[f];
    roots.resize(c[kRoots]);
    LODBAKE_RETURN_IF_ERROR(readAt(file.fd, h.offset[aRoots], roots.data(), 4 * roots.size(), path));
    for (uint32_t& r : roots) {
        if (r >= c[kClusters]) return corrupt(path, "roots: cluster out of range");
        r = global[r];
    }
    a.held += bytesOf(roots);
    return Status();
}

// The table's arrays sized from the headers, the partitions' LOD0 numbered first.
void sizeTable(Assembly& a) {
    const Files& files = *a.files;
    TreeClusterTable& t = *a.table;
    uint64_t clusters = 0, groups = 0, children = 0;
    a.lod0_base.resize(files.partitions);
    for (size_t i = 0; i < files.heads.size(); ++i) {
        const uint32_t* c = files.heads[i].counts;
        clusters += c[kClusters] - (i >= files.partitions ? c[kLod0] : 0);
        groups += c[kGroups];
        children += c[kChildren];
        if (i < files.partitions) {
            a.lod0_base[i] = a.next;
            a.next += c[kLod0];
        }
    }
    t.lod0_cluster_count = a.next;
    t.clusters.resize(size_t(clusters));
    t.locators.resize(size_t(clusters));
    t.groups.reserve(size_t(groups));
    t.group_children.reserve(size_t(children));
    t.roots.reserve(files.heads[files.top].counts[kRoots]);
    a.root_global.resize(files.heads.size());
    for (size_t i = 0; i < files.heads.size(); ++i) {
        TreeFile tf;
        tf.path = files.paths[i];
        tf.positions_offset = files.heads[i].offset[aPositions];
        tf.indices_offset = files.heads[i].offset[aIndices];
        tf.vertex_count = files.heads[i].counts[kPositions];
        tf.triangle_count = files.heads[i].counts[kTriangles];
        tf.size = files.heads[i].size;
        tf.mtime_ns = files.heads[i].mtime_ns;
        t.files.push_back(std::move(tf));
    }
    a.held = bytesOf(t.clusters) + bytesOf(t.locators) + bytesOf(t.groups) + bytesOf(t.group_children) +
             bytesOf(t.roots) + bytesOf(t.files) + bytesOf(a.lod0_base) + bytesOf(a.root_global) +
             bytesOf(files.heads) + bytesOf(files.paths);
    for (size_t i = 0; i < files.heads.size(); ++i)
        if (files.paths[i].capacity() > 15) a.held += 2 * (files.paths[i].capacity() + 1); // both copies
}

} // namespace

lodrt::ClusterLodView TreeClusterTable::view() const {
    lodrt::ClusterLodView v;
    v.clusters = clusters.data();
    v.cluster_count = uint32_t(clusters.size());
    v.groups = groups.data();
    v.group_count = uint32_t(groups.size());
    v.group_children = group_children.data();
    v.group_child_count = uint32_t(group_children.size());
    v.roots = roots.data();
    v.root_count = uint32_t(roots.size());
    v.vertex_count = vertex_count;
    v.triangle_count = triangle_count;
    return v;
}

Result<uint64_t> clusterTableBound(const MergeTree& tree) {
    LODBAKE_ASSIGN_OR_RETURN(Files files, readHeads(tree));
    return boundOf(files);
}

Result<TreeClusterTable> assembleClusterTable(const MergeTree& tree, uint64_t memory_limit_bytes) {
    LODBAKE_ASSIGN_OR_RETURN(Files files, readHeads(tree));
    const uint64_t bound = boundOf(files);
    if (bound > memory_limit_bytes)
        return resourceLimit(tree.top + ": memory limit of " + std::to_string(memory_limit_bytes >> 20) +
                             " MiB is too small for the hierarchy's table (needs " + std::to_string((bound >> 20) + 1) +
                             " MiB)");
    TreeClusterTable t;
    t.memory_bound_bytes = bound;
    Assembly a;
    a.files = &files;
    a.tree = &tree;
    a.table = &t;
    sizeTable(a);
    for (size_t f = 0; f < files.paths.size(); ++f) LODBAKE_RETURN_IF_ERROR(readFile(a, f));
    t.roots = a.root_global[files.top];
    t.reached_single_group = t.roots.size() == 1;
    // Geometry offsets as in the concatenation of every cluster's geometry in cluster order.
    uint64_t vertices = 0, triangles = 0;
    for (lodrt::ClusterLodCluster& c : t.clusters) {
        c.first_vertex = uint32_t(vertices);
        c.first_triangle = uint32_t(triangles);
        vertices += c.vertex_count;
        triangles += c.triangle_count;
        if (vertices > UINT32_MAX || triangles > UINT32_MAX)
            return resourceLimit(tree.top + ": hierarchy: more than 2^32 - 1 vertices or triangles");
    }
    t.vertex_count = uint32_t(vertices);
    t.triangle_count = uint32_t(triangles);
    if (lodrt::validateClusterLod(t.view()) != lodrt::Result::Ok)
        return invalidInput(tree.top + ": assembled hierarchy: expected a valid cluster hierarchy");
    return t;
}

TreePageSource::TreePageSource(const TreeClusterTable& table, size_t window_bytes, size_t max_open_files)
    : table_(table), fds_(table.files.size(), -1), max_open_(std::max<size_t>(max_open_files, 1)),
      window_(std::max<size_t>(window_bytes, 4096)) {}

TreePageSource::~TreePageSource() {
    for (int fd : fds_)
        if (fd >= 0) ::close(fd);
}

Status TreePageSource::openFile(uint32_t file) {
    if (fds_[file] >= 0) return Status();
    if (open_count_ >= max_open_) { // a tree of many files: close them all, reopen as needed
        for (int& fd : fds_)
            if (fd >= 0) {
                ::close(fd);
                fd = -1;
            }
        open_count_ = 0;
    }
    const TreeFile& tf = table_.files[file];
    Closer f;
    LODBAKE_RETURN_IF_ERROR(openRead(tf.path, f));
    struct stat st {};
    if (::fstat(f.fd, &st) != 0) return ioError(tf.path + ": cannot stat: " + std::strerror(errno));
    if (uint64_t(st.st_size) != tf.size || mtimeOf(st) != tf.mtime_ns)
        return corrupt(tf.path, "changed since the hierarchy's table was read (expected " + std::to_string(tf.size) +
                                    " bytes, has " + std::to_string(uint64_t(st.st_size)) + ")");
    fds_[file] = f.fd;
    f.fd = -1;
    ++open_count_;
    return Status();
}

Status TreePageSource::read(uint32_t file, uint64_t offset, void* data, size_t size) {
    LODBAKE_RETURN_IF_ERROR(openFile(file));
    const TreeFile& tf = table_.files[file];
    if (offset + size > tf.size) return corrupt(tf.path, "geometry: read past the end of the file");
    bytes_read_ += size;
    if (size > window_.size()) return readAt(fds_[file], offset, data, size, tf.path);
    if (file != window_file_ || offset < window_offset_ || offset + size > window_offset_ + window_size_) {
        window_file_ = ~0u;
        window_size_ = size_t(std::min<uint64_t>(window_.size(), tf.size - offset));
        Status s = readAt(fds_[file], offset, window_.data(), window_size_, tf.path);
        if (!s.ok())
            return corrupt(tf.path, "geometry: expected " + std::to_string(window_size_) + " bytes at " +
                                        std::to_string(offset) + " (" + s.message() + ")");
        window_file_ = file;
        window_offset_ = offset;
    }
    std::memcpy(data, window_.data() + (offset - window_offset_), size);
    return Status();
}

Status TreePageSource::readCluster(uint32_t cluster, ClusterPageGeometry& out) {
    const lodrt::ClusterLodCluster& c = table_.clusters[cluster];
    const ClusterLocator& at = table_.locators[cluster];
    const TreeFile& tf = table_.files[at.file];
    const size_t v = out.positions.size(), t = out.indices.size();
    out.positions.resize(v + c.vertex_count);
    out.indices.resize(t + size_t(c.triangle_count) * 3);
    if (c.vertex_count > 0)
        LODBAKE_RETURN_IF_ERROR(read(at.file, tf.positions_offset + 12 * uint64_t(at.first_vertex), &out.positions[v],
                                     12 * size_t(c.vertex_count)));
    if (c.triangle_count > 0)
        LODBAKE_RETURN_IF_ERROR(read(at.file, tf.indices_offset + 3 * uint64_t(at.first_triangle), &out.indices[t],
                                     3 * size_t(c.triangle_count)));
    return Status();
}

Status TreePageSource::readPage(uint32_t, const uint32_t* clusters, size_t count, ClusterPageGeometry& out) {
    // Sized once to the page (the writer counts the arrays at their capacity: no doubling growth).
    size_t vertices = 0, triangles = 0;
    for (size_t i = 0; i < count; ++i) {
        if (clusters[i] >= table_.clusters.size()) return invalidInput("page source: cluster out of range");
        vertices += table_.clusters[clusters[i]].vertex_count;
        triangles += table_.clusters[clusters[i]].triangle_count;
    }
    // Arrays kept from earlier pages are reallocated to this page's size unless they fit it exactly:
    // the positions' capacity from one page and the triangles' from another can together exceed the
    // writer's bound, which takes the largest page's 12 V + 3 T.
    if (out.positions.capacity() != vertices || out.indices.capacity() != 3 * triangles) {
        out = ClusterPageGeometry();
        out.positions.reserve(vertices);
        out.indices.reserve(3 * triangles);
    }
    for (size_t i = 0; i < count; ++i) LODBAKE_RETURN_IF_ERROR(readCluster(clusters[i], out));
    return Status();
}

Result<ClusterPackBounds> TreePageSource::bounds() {
    ClusterPackBounds b;
    Vec3f points[lodrt::ClusterLodCluster::kMaxVertices];
    for (uint32_t i = 0; i < table_.clusters.size(); ++i) {
        const lodrt::ClusterLodCluster& c = table_.clusters[i];
        const ClusterLocator& at = table_.locators[i];
        if (c.vertex_count > lodrt::ClusterLodCluster::kMaxVertices)
            return corrupt(table_.files[at.file].path, "cluster: more than 255 vertices");
        if (c.vertex_count == 0) continue;
        LODBAKE_RETURN_IF_ERROR(read(at.file, table_.files[at.file].positions_offset + 12 * uint64_t(at.first_vertex),
                                     points, 12 * size_t(c.vertex_count)));
        for (uint32_t k = 0; k < c.vertex_count; ++k) b.add(points[k]);
    }
    return b;
}

Result<TreePagesResult> writeTreeClusterPages(const MergeTree& tree, const std::string& output_path,
                                              const TreePagesOptions& options) {
    LODBAKE_ASSIGN_OR_RETURN(TreeClusterTable table, assembleClusterTable(tree, options.memory_limit_bytes));
    TreePageSource source(table, options.window_bytes);
    LODBAKE_ASSIGN_OR_RETURN(ClusterPackBounds bounds, source.bounds());
    LODBAKE_ASSIGN_OR_RETURN(ClusterPackStreamResult pack,
                             writeClusterLodPackStreamed(table.view(), bounds, source, output_path, options.stream));
    TreePagesResult r;
    r.pack = std::move(pack);
    r.table_bound_bytes = table.memory_bound_bytes;
    r.table_accounted_bytes = table.accounted_peak_bytes;
    r.bytes_read = source.bytesRead();
    r.cluster_count = uint32_t(table.clusters.size());
    return r;
}

} // namespace lodbake::ooc
