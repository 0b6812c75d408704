// The out-of-core partitioner (lodbake/ooc/partition.h).
#include "lodbake/ooc/partition.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <system_error>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "lodbake/core/file_io.h"
#include "lodbake/core/hash.h"
#include "lodbake/core/spill_file.h"
#include "lodrt/format.h"

namespace lodbake::ooc {

// Partition files and the spill are written as the host's arrays of u32 and float: the format is
// little-endian, and so is every host the baker runs on.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "partition files are written as little-endian arrays");

namespace {

constexpr uint64_t kSpillBufferBytes = uint64_t(1) << 20;
constexpr uint64_t kSpillBlockBytes = uint64_t(64) << 10;
constexpr uint64_t kJobFileBuffer = uint64_t(1) << 20;
constexpr uint64_t kMaxAppendBuffer = uint64_t(1) << 20;
constexpr uint64_t kMinAppendBuffer = uint64_t(4) << 10;
constexpr uint32_t kNoChild = 0xffffffffu;

// The memory this run holds in its large buffers, and the most it held at once.
class MemoryAccount {
public:
    void add(uint64_t bytes) {
        const uint64_t now = current_.fetch_add(bytes) + bytes;
        uint64_t peak = peak_.load();
        while (now > peak && !peak_.compare_exchange_weak(peak, now)) {
        }
    }
    void sub(uint64_t bytes) { current_.fetch_sub(bytes); }
    uint64_t peak() const { return peak_.load(); }

private:
    std::atomic<uint64_t> current_{0}, peak_{0};
};

// Files this run created; removed when the run fails (all) or succeeds (the temporaries only).
class RunFiles {
public:
    ~RunFiles() {
        for (const std::string& p : temporaries_) ::unlink(p.c_str());
        if (!committed_)
            for (const std::string& p : outputs_) ::unlink(p.c_str());
    }
    void temporary(const std::string& p) { temporaries_.push_back(p); }
    void output(const std::string& p) { outputs_.push_back(p); }
    void commit() { committed_ = true; }

private:
    std::vector<std::string> temporaries_, outputs_;
    bool committed_ = false;
};

Vec3f vmin(const Vec3f& a, const Vec3f& b) { return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)}; }
Vec3f vmax(const Vec3f& a, const Vec3f& b) { return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}; }

Status cancelled(const std::string& input) { return ioError(input + ": partitioning cancelled"); }

struct KdNode {
    uint32_t axis = 0;
    float split = 0.0f;
    uint32_t left = kNoChild, right = kNoChild; // kNoChild on both: a leaf
    uint32_t leaf = 0;
};

// Splits sample[begin, end) into `leaves` leaves: at the quantile that gives each side a share of
// the points proportional to its leaves, along the longest axis of the points' bounds. The order is
// total (coordinate, then sample position), so the tree depends on the sample only.
uint32_t buildKd(std::vector<std::pair<Vec3f, uint32_t>>& sample, size_t begin, size_t end, uint32_t leaves,
                 uint32_t& next_leaf, std::vector<KdNode>& nodes) {
    const uint32_t id = uint32_t(nodes.size());
    nodes.emplace_back();
    if (leaves <= 1 || end - begin < 2) {
        nodes[id].leaf = next_leaf;
        next_leaf += std::max<uint32_t>(leaves, 1);
        return id;
    }
    Vec3f lo = sample[begin].first, hi = lo;
    for (size_t i = begin; i < end; ++i) {
        lo = vmin(lo, sample[i].first);
        hi = vmax(hi, sample[i].first);
    }
    const Vec3f ext = hi - lo;
    const uint32_t axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : ext.y >= ext.z ? 1 : 2;
    const uint32_t left_leaves = leaves / 2;
    const size_t mid = begin + size_t(double(end - begin) * left_leaves / leaves);
    auto less = [axis](const std::pair<Vec3f, uint32_t>& a, const std::pair<Vec3f, uint32_t>& b) {
        const float fa = a.first[int(axis)], fb = b.first[int(axis)];
        return fa < fb || (fa == fb && a.second < b.second);
    };
    std::nth_element(sample.begin() + std::ptrdiff_t(begin), sample.begin() + std::ptrdiff_t(mid),
                     sample.begin() + std::ptrdiff_t(end), less);
    nodes[id].axis = axis;
    nodes[id].split = sample[mid].first[int(axis)];
    const uint32_t l = buildKd(sample, begin, mid, left_leaves, next_leaf, nodes);
    const uint32_t r = buildKd(sample, mid, end, leaves - left_leaves, next_leaf, nodes);
    nodes[id].left = l;
    nodes[id].right = r;
    return id;
}

uint32_t leafOf(const std::vector<KdNode>& nodes, const Vec3f& p) {
    uint32_t n = 0;
    while (nodes[n].left != kNoChild) n = p[int(nodes[n].axis)] < nodes[n].split ? nodes[n].left : nodes[n].right;
    return nodes[n].leaf;
}

struct Plan {
    uint64_t fixed = 0, cell_bytes = 2, jobs = 1, target = 0, leaves = 1, append_buffer = 0, bound = 0;
};

Result<Plan> planMemory(const PartitionOptions& o, uint64_t vertices, uint64_t triangles, const std::string& input) {
    Plan plan;
    const StreamReadOptions& r = o.read;
    plan.fixed = std::max(r.buffer_bytes, r.max_record_bytes) + 12 * (r.vertex_chunk + r.triangle_chunk) +
                 32 * o.sample_cap + kSpillBufferBytes + kSpillBlockBytes;
    const int concurrency = o.threads > 0 ? o.threads : tbb::this_task_arena::max_concurrency();
    plan.jobs = uint64_t(std::max(1, concurrency));
    const uint64_t limit = o.memory_limit_bytes;
    const uint64_t per_job_fixed = kSpillBlockBytes + kJobFileBuffer;
    // Leaves sized for the job that will build them when that job needs more than this one.
    const uint64_t per_triangle = std::max(kJobBytesPerTriangle, o.build_bytes_per_triangle);
    auto too_small = [&](uint64_t needed) {
        return resourceLimit(input + ": memory limit of " + std::to_string(limit >> 20) + " MiB is too small (needs at least " +
                             std::to_string((needed >> 20) + 1) + " MiB for this input)");
    };
    if (o.leaf_triangles > 0) {
        // A fixed leaf size: the limit decides only how many jobs run at once.
        plan.target = o.leaf_triangles;
        const uint64_t job = per_job_fixed + per_triangle * plan.target;
        if (limit < plan.fixed + job) return too_small(plan.fixed + job);
        plan.jobs = std::min(plan.jobs, (limit - plan.fixed) / job);
    } else {
        // Jobs share what is left after the fixed part; fewer jobs when one would get too few triangles.
        while (plan.jobs > 1 && limit < plan.fixed + plan.jobs * (per_job_fixed + per_triangle * 4096)) --plan.jobs;
        if (limit < plan.fixed + plan.jobs * (per_job_fixed + per_triangle * 64))
            return too_small(plan.fixed + per_job_fixed + per_triangle * 64);
        plan.target = (limit - plan.fixed - plan.jobs * per_job_fixed) / (plan.jobs * per_triangle);
    }
    // A job's corners are numbered in 32 bits (the sorted pairs keep the corner's index).
    plan.target = std::min<uint64_t>(plan.target, 0xffffffffu / 4);
    const uint64_t sized = std::max<uint64_t>(1, plan.target * 4 / 5);
    plan.leaves = std::max<uint64_t>(1, (triangles + sized - 1) / sized);
    plan.cell_bytes = plan.leaves > 65535 ? 4 : 2;
    const uint64_t pass3_fixed = plan.fixed + vertices * plan.cell_bytes;
    if (limit < pass3_fixed + plan.leaves * kMinAppendBuffer) return too_small(pass3_fixed + plan.leaves * kMinAppendBuffer);
    plan.append_buffer = std::min(kMaxAppendBuffer, (limit - pass3_fixed) / plan.leaves);
    plan.bound = std::max(pass3_fixed + plan.leaves * plan.append_buffer,
                          plan.fixed + plan.jobs * (per_job_fixed + per_triangle * plan.target));
    return plan;
}

// Pass 1: positions to the spill, and the sample (every `stride`-th vertex; when the sample
// reaches twice the cap, every other entry is dropped and the stride doubles).
struct VertexPass {
    std::vector<std::pair<Vec3f, uint32_t>> sample;
    uint64_t stride = 1;
    uint64_t count = 0;
};

Status spillVertices(MeshStreamReader& reader, const PartitionOptions& o, const std::string& input,
                     const std::string& spill_path, MemoryAccount& memory, VertexPass& pass) {
    SpillFile spill;
    LODBAKE_RETURN_IF_ERROR(spill.open(spill_path, kSpillBufferBytes));
    pass.sample.reserve(size_t(2 * o.sample_cap));
    memory.add(32 * o.sample_cap);
    const Status streamed = reader.forEachVertexChunk([&](uint64_t first, const Vec3f* p, size_t n) -> Status {
        if (o.cancel && o.cancel->load()) return cancelled(input);
        LODBAKE_RETURN_IF_ERROR(spill.write(p, n * sizeof(Vec3f)));
        for (size_t i = 0; i < n; ++i) {
            const uint64_t id = first + i;
            if (id % pass.stride != 0) continue;
            pass.sample.push_back({p[i], uint32_t(id)});
            if (pass.sample.size() < 2 * o.sample_cap) continue;
            size_t kept = 0;
            pass.stride *= 2;
            for (const auto& s : pass.sample)
                if (s.second % pass.stride == 0) pass.sample[kept++] = s;
            pass.sample.resize(kept);
        }
        pass.count = first + n;
        return Status();
    });
    LODBAKE_RETURN_IF_ERROR(streamed);
    static_assert(sizeof(Vec3f) == 12, "the spill holds packed float triples");
    return spill.commit();
}

// Pass 2: the leaf of every vertex, from the spill read back in order.
template <class Cell>
Status assignCells(const std::string& spill_path, const std::vector<KdNode>& nodes, uint64_t vertices,
                   std::vector<Cell>& cells) {
    const int fd = ::open(spill_path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return ioError(spill_path + ": cannot open: " + std::strerror(errno));
    std::vector<Vec3f> block(kSpillBufferBytes / sizeof(Vec3f));
    Status s;
    for (uint64_t v = 0; v < vertices && s.ok(); v += block.size()) {
        const size_t n = size_t(std::min<uint64_t>(block.size(), vertices - v));
        s = readAt(fd, v * sizeof(Vec3f), block.data(), n * sizeof(Vec3f), spill_path);
        for (size_t i = 0; i < n && s.ok(); ++i) cells[size_t(v + i)] = Cell(leafOf(nodes, block[i]));
    }
    ::close(fd);
    return s;
}

std::string rawPath(const std::string& dir, uint64_t leaf) {
    return joinPath(dir, ".raw" + std::to_string(leaf) + "_" + std::to_string(::getpid()));
}

// Pass 3: triangles appended to their leaf's raw file.
template <class Cell>
Status distributeTriangles(MeshStreamReader& reader, const PartitionOptions& o, const std::string& input,
                           const Plan& plan, const std::vector<Cell>& cells, RunFiles& files,
                           std::vector<uint64_t>& leaf_triangles) {
    const size_t per_buffer = size_t(plan.append_buffer / 12);
    std::vector<std::vector<uint32_t>> buffers(size_t(plan.leaves));
    leaf_triangles.assign(size_t(plan.leaves), 0);
    auto flush = [&](size_t leaf) -> Status {
        std::vector<uint32_t>& b = buffers[leaf];
        if (b.empty()) return Status();
        const std::string path = rawPath(o.work_dir, leaf);
        if (leaf_triangles[leaf] == b.size() / 3) files.temporary(path);
        LODBAKE_RETURN_IF_ERROR(appendToFile(path, b.data(), b.size() * 4));
        b.clear();
        return Status();
    };
    const Status streamed = reader.forEachTriangleChunk([&](uint64_t, const uint32_t* t, size_t n) -> Status {
        if (o.cancel && o.cancel->load()) return cancelled(input);
        for (size_t i = 0; i < n; ++i, t += 3) {
            const uint32_t ca = cells[t[0]], cb = cells[t[1]], cc = cells[t[2]];
            const uint32_t leaf = ca == cb || ca == cc ? ca : cb == cc ? cb : std::min({ca, cb, cc});
            std::vector<uint32_t>& b = buffers[leaf];
            if (b.capacity() == 0) b.reserve(per_buffer * 3);
            b.insert(b.end(), t, t + 3);
            ++leaf_triangles[leaf];
            if (b.size() >= per_buffer * 3) LODBAKE_RETURN_IF_ERROR(flush(leaf));
        }
        return Status();
    });
    LODBAKE_RETURN_IF_ERROR(streamed);
    for (size_t leaf = 0; leaf < buffers.size(); ++leaf) LODBAKE_RETURN_IF_ERROR(flush(leaf));
    return Status();
}

// Passes 2 and 3 with leaf numbers of `Cell` type (2 or 4 bytes per vertex).
template <class Cell>
Status cellsAndTriangles(MeshStreamReader& reader, const PartitionOptions& o, const std::string& input, const Plan& plan,
                         const std::vector<KdNode>& nodes, const std::string& spill_path, uint64_t vertices,
                         RunFiles& files, std::vector<uint64_t>& leaf_triangles) {
    std::vector<Cell> cells(static_cast<size_t>(vertices));
    LODBAKE_RETURN_IF_ERROR(assignCells(spill_path, nodes, vertices, cells));
    return distributeTriangles(reader, o, input, plan, cells, files, leaf_triangles);
}

// Pass 4, one leaf: the partition file, named by the hash of its bytes.
Status writePartition(const PartitionOptions& o, const std::string& spill_path, int spill_fd, uint64_t spill_bytes,
                      uint64_t leaf, uint64_t triangles, MemoryAccount& memory, PartitionFile& out, bool& created) {
    const std::string raw_path = rawPath(o.work_dir, leaf);
    const uint64_t job_bytes = kSpillBlockBytes + kJobFileBuffer + 36 * triangles;
    memory.add(job_bytes);
    std::vector<uint32_t> tri(size_t(triangles * 3)), ids;
    {
        const int fd = ::open(raw_path.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd < 0) return ioError(raw_path + ": cannot open: " + std::strerror(errno));
        const Status read = readAt(fd, 0, tri.data(), tri.size() * 4, raw_path);
        ::close(fd);
        LODBAKE_RETURN_IF_ERROR(read);
    }
    // Local numbers in increasing global id. A leaf is compact in space and scans number their
    // vertices in scan order, so its ids usually span a range within a small multiple of its
    // triangle count: then a bitmap over the range with a running count per 64 ids (3/16 byte per id,
    // at most 24 bytes per triangle) gives each id its rank. Otherwise (id, corner) pairs are sorted
    // once and swept. A binary search per corner would touch memory at random, and dominates on
    // large leaves.
    uint64_t vertex_bytes = 0;
    const auto [lo_it, hi_it] = std::minmax_element(tri.begin(), tri.end());
    const uint64_t first_id = *lo_it, range = uint64_t(*hi_it) - first_id + 1;
    if (range <= std::min<uint64_t>(o.bitmap_ids_per_triangle, 128) * triangles) {
        const size_t words = size_t((range + 63) / 64);
        std::vector<uint64_t> bits(words, 0);
        std::vector<uint32_t> rank(words, 0);
        for (uint32_t v : tri) {
            const uint64_t r = v - first_id;
            bits[size_t(r >> 6)] |= uint64_t(1) << (r & 63);
        }
        uint32_t distinct = 0;
        for (size_t w = 0; w < words; ++w) {
            rank[w] = distinct;
            distinct += uint32_t(__builtin_popcountll(bits[w]));
        }
        ids.reserve(distinct);
        memory.add(4 * uint64_t(distinct));
        for (size_t w = 0; w < words; ++w)
            for (uint64_t m = bits[w]; m != 0; m &= m - 1)
                ids.push_back(uint32_t(first_id + 64 * w + uint64_t(__builtin_ctzll(m))));
        for (uint32_t& v : tri) {
            const uint64_t r = v - first_id;
            const size_t w = size_t(r >> 6);
            v = rank[w] + uint32_t(__builtin_popcountll(bits[w] & ((uint64_t(1) << (r & 63)) - 1)));
        }
    } else {
        std::vector<uint64_t> keyed(tri.size());
        for (size_t i = 0; i < tri.size(); ++i) keyed[i] = (uint64_t(tri[i]) << 32) | uint64_t(i);
        std::sort(keyed.begin(), keyed.end());
        size_t distinct = 0;
        for (size_t i = 0; i < keyed.size(); ++i) distinct += i == 0 || (keyed[i] >> 32) != (keyed[i - 1] >> 32);
        ids.reserve(distinct);
        memory.add(4 * uint64_t(distinct));
        for (uint64_t k : keyed) {
            const uint32_t id = uint32_t(k >> 32);
            if (ids.empty() || ids.back() != id) ids.push_back(id);
            tri[size_t(k & 0xffffffffu)] = uint32_t(ids.size() - 1);
        }
    }
    memory.sub(24 * triangles);
    vertex_bytes = 16 * uint64_t(ids.size());
    memory.add(12 * uint64_t(ids.size()));
    std::vector<Vec3f> positions(ids.size());
    // Ids are sorted, so each block of the spill is read at most once.
    std::vector<uint8_t> block(kSpillBlockBytes);
    uint64_t block_start = 0, block_len = 0;
    for (size_t i = 0; i < ids.size(); ++i) {
        const uint64_t at = uint64_t(ids[i]) * sizeof(Vec3f);
        if (block_len == 0 || at < block_start || at + sizeof(Vec3f) > block_start + block_len) {
            block_start = at;
            block_len = std::min<uint64_t>(kSpillBlockBytes, spill_bytes - at);
            LODBAKE_RETURN_IF_ERROR(readAt(spill_fd, block_start, block.data(), size_t(block_len), spill_path));
        }
        std::memcpy(&positions[i], block.data() + (at - block_start), sizeof(Vec3f));
    }
    Vec3f lo = positions[0], hi = positions[0];
    for (const Vec3f& p : positions) {
        lo = vmin(lo, p);
        hi = vmax(hi, p);
    }
    // The file image, hashed as it is written.
    const std::string provisional = joinPath(o.work_dir, ".job" + std::to_string(leaf) + "_" + std::to_string(::getpid()));
    SpillFile file;
    LODBAKE_RETURN_IF_ERROR(file.open(provisional, size_t(kJobFileBuffer)));
    Hasher hasher;
    auto put = [&](const void* data, size_t size) {
        hasher.addBytes(data, size);
        return file.write(data, size);
    };
    const uint32_t counts[2] = {uint32_t(ids.size()), uint32_t(triangles)};
    const float bounds[6] = {lo.x, lo.y, lo.z, hi.x, hi.y, hi.z};
    LODBAKE_RETURN_IF_ERROR(put(lodrt::format::kPartitionMagic, sizeof(lodrt::format::kPartitionMagic)));
    LODBAKE_RETURN_IF_ERROR(put(counts, sizeof counts));
    LODBAKE_RETURN_IF_ERROR(put(bounds, sizeof bounds));
    LODBAKE_RETURN_IF_ERROR(put(ids.data(), ids.size() * 4));
    LODBAKE_RETURN_IF_ERROR(put(positions.data(), positions.size() * sizeof(Vec3f)));
    LODBAKE_RETURN_IF_ERROR(put(tri.data(), tri.size() * 4));
    LODBAKE_RETURN_IF_ERROR(file.commit());
    out.content_hash = hasher.digest();
    out.path = joinPath(o.work_dir, hashToHex(out.content_hash) + lodrt::format::kPartitionExtension);
    out.vertex_count = counts[0];
    out.triangle_count = counts[1];
    out.bounds_min = lo;
    out.bounds_max = hi;
    // A file of that name holds these very bytes (its name is their hash): one from an earlier run
    // in the same folder, or an identical leaf of this run. It is kept even if this run fails.
    created = ::access(out.path.c_str(), F_OK) != 0;
    if (std::rename(provisional.c_str(), out.path.c_str()) != 0) {
        const std::string err = std::strerror(errno);
        ::unlink(provisional.c_str());
        return ioError(out.path + ": cannot move into place: " + err);
    }
    memory.sub(kSpillBlockBytes + kJobFileBuffer + 12 * triangles + vertex_bytes);
    return Status();
}

} // namespace

Result<PartitionSet> partitionMesh(const std::string& input, const PartitionOptions& o, Diagnostics& diagnostics) {
    std::error_code ec;
    std::filesystem::create_directories(o.work_dir, ec);
    if (ec) return ioError(o.work_dir + ": cannot create the folder: " + ec.message());
    LODBAKE_ASSIGN_OR_RETURN(std::unique_ptr<MeshStreamReader> reader, openMeshStream(input, o.read, diagnostics));
    RunFiles files;
    MemoryAccount memory;
    const StreamReadOptions& r = o.read;
    memory.add(std::max(r.buffer_bytes, r.max_record_bytes) + 12 * (r.vertex_chunk + r.triangle_chunk) +
               kSpillBufferBytes + kSpillBlockBytes);
    const std::string spill_path = joinPath(o.work_dir, ".vertices_" + std::to_string(::getpid()));
    files.temporary(spill_path);
    VertexPass vp;
    LODBAKE_RETURN_IF_ERROR(spillVertices(*reader, o, input, spill_path, memory, vp));
    PartitionSet set;
    set.vertex_count = vp.count;
    LODBAKE_ASSIGN_OR_RETURN(const Plan plan, planMemory(o, vp.count, reader->info().triangle_estimate, input));
    set.leaf_count = plan.leaves;
    set.target_triangles = plan.target;
    set.memory_bound_bytes = plan.bound;

    std::vector<KdNode> nodes;
    uint32_t next_leaf = 0;
    buildKd(vp.sample, 0, vp.sample.size(), uint32_t(plan.leaves), next_leaf, nodes);
    std::vector<std::pair<Vec3f, uint32_t>>().swap(vp.sample);
    memory.sub(32 * o.sample_cap);
    std::vector<uint64_t> leaf_triangles;
    memory.add(vp.count * plan.cell_bytes + plan.leaves * plan.append_buffer);
    if (plan.cell_bytes == 2)
        LODBAKE_RETURN_IF_ERROR(cellsAndTriangles<uint16_t>(*reader, o, input, plan, nodes, spill_path, vp.count, files,
                                                            leaf_triangles));
    else
        LODBAKE_RETURN_IF_ERROR(cellsAndTriangles<uint32_t>(*reader, o, input, plan, nodes, spill_path, vp.count, files,
                                                            leaf_triangles));
    memory.sub(vp.count * plan.cell_bytes + plan.leaves * plan.append_buffer);
    for (uint64_t t : leaf_triangles) {
        set.triangle_count += t;
        set.largest_partition = std::max(set.largest_partition, t);
    }
    if (set.largest_partition > 0xffffffffu / 3) return resourceLimit(input + ": a partition is too large");

    const int spill_fd = ::open(spill_path.c_str(), O_RDONLY | O_CLOEXEC);
    if (spill_fd < 0) return ioError(spill_path + ": cannot open: " + std::strerror(errno));
    std::vector<PartitionFile> out(leaf_triangles.size());
    std::vector<Status> status(leaf_triangles.size());
    std::vector<uint8_t> created(leaf_triangles.size(), 0);
    tbb::task_arena arena(int(plan.jobs));
    arena.execute([&] {
        tbb::parallel_for(size_t(0), leaf_triangles.size(), [&](size_t leaf) {
            if (leaf_triangles[leaf] == 0) return;
            if (o.cancel && o.cancel->load()) {
                status[leaf] = cancelled(input);
                return;
            }
            bool made = false;
            status[leaf] = writePartition(o, spill_path, spill_fd, vp.count * sizeof(Vec3f), leaf,
                                          leaf_triangles[leaf], memory, out[leaf], made);
            created[leaf] = made;
        });
    });
    ::close(spill_fd);
    for (size_t leaf = 0; leaf < out.size(); ++leaf) {
        files.temporary(rawPath(o.work_dir, leaf));
        if (created[leaf]) files.output(out[leaf].path);
    }
    for (const Status& s : status) LODBAKE_RETURN_IF_ERROR(s);
    for (PartitionFile& f : out)
        if (!f.path.empty()) set.partitions.push_back(std::move(f));
    set.accounted_peak_bytes = memory.peak();
    files.commit();
    return set;
}

Result<PartitionHeader> readPartitionHeader(int fd, const std::string& path) {
    struct stat st {};
    if (::fstat(fd, &st) != 0) return ioError(path + ": cannot stat: " + std::strerror(errno));
    const uint64_t size = uint64_t(st.st_size);
    PartitionHeader h;
    constexpr size_t head = lodrt::format::kPartitionHeaderBytes;
    if (size < head || !readAt(fd, 0, h.bytes, head, path).ok() ||
        std::memcmp(h.bytes, lodrt::format::kPartitionMagic, 8) != 0)
        return invalidInput(path + ": header: expected a partition file (magic LBPART01)");
    float bounds[6];
    std::memcpy(&h.vertex_count, h.bytes + 8, 4);
    std::memcpy(&h.triangle_count, h.bytes + 12, 4);
    std::memcpy(bounds, h.bytes + 16, 24);
    h.bounds_min = Vec3f(bounds[0], bounds[1], bounds[2]);
    h.bounds_max = Vec3f(bounds[3], bounds[4], bounds[5]);
    const uint64_t expected = head + 16 * uint64_t(h.vertex_count) + 12 * uint64_t(h.triangle_count);
    if (size != expected)
        return invalidInput(path + ": header: " + std::to_string(h.vertex_count) + " vertices and " +
                            std::to_string(h.triangle_count) + " triangles need " + std::to_string(expected) +
                            " bytes, the file has " + std::to_string(size));
    return h;
}

Result<PartitionData> readPartitionFile(const std::string& path) {
    // Read straight into the arrays (no copy of the whole file), hashing the bytes in file order:
    // the hash is the one the file is named by.
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return ioError(path + ": cannot open: " + std::strerror(errno));
    struct Closer {
        int fd;
        ~Closer() { ::close(fd); }
    } closer{fd};
    LODBAKE_ASSIGN_OR_RETURN(const PartitionHeader header, readPartitionHeader(fd, path));
    const uint32_t vertices = header.vertex_count;
    PartitionData d;
    d.global_ids.resize(vertices);
    d.positions.resize(vertices);
    d.indices.resize(size_t(header.triangle_count) * 3);
    Hasher hasher;
    hasher.addBytes(header.bytes, sizeof header.bytes);
    uint64_t at = sizeof header.bytes;
    auto read = [&](void* data, size_t bytes) {
        Status s = readAt(fd, at, data, bytes, path);
        hasher.addBytes(data, bytes);
        at += bytes;
        return s;
    };
    LODBAKE_RETURN_IF_ERROR(read(d.global_ids.data(), 4 * d.global_ids.size()));
    LODBAKE_RETURN_IF_ERROR(read(d.positions.data(), 12 * d.positions.size()));
    LODBAKE_RETURN_IF_ERROR(read(d.indices.data(), 4 * d.indices.size()));
    d.content_hash = hasher.digest();
    for (size_t i = 1; i < d.global_ids.size(); ++i)
        if (d.global_ids[i] <= d.global_ids[i - 1])
            return invalidInput(path + ": vertex " + std::to_string(i) + ": expected global ids in increasing order");
    for (size_t i = 0; i < d.indices.size(); ++i)
        if (d.indices[i] >= vertices)
            return invalidInput(path + ": triangle " + std::to_string(i / 3) + ": vertex " + std::to_string(d.indices[i]) +
                                " out of range (" + std::to_string(vertices) + " vertices)");
    return d;
}

void removePartitionFiles(const PartitionSet& set) {
    for (const PartitionFile& f : set.partitions) ::unlink(f.path.c_str());
}

} // namespace lodbake::ooc
