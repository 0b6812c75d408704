// Removal of degenerate faces (repeated index, zero area, non-finite vertex) and duplicate faces.
#include <algorithm>
#include <array>

#include "core/parallel.h"
#include "lodbake/cleanup/passes.h"
#include "mesh_edit.h"

namespace lodbake {

using namespace cleanup_detail;

PassCounters DegenerateReport::counters() const {
    return {{"repeated_index_faces", repeated_index_faces},
            {"zero_area_faces", zero_area_faces},
            {"non_finite_faces", non_finite_faces},
            {"duplicate_faces", duplicate_faces}};
}

namespace {

// Clears keep[f] for every kept face whose vertex set (either winding) equals that of an earlier
// kept face, so the first of each set stays; returns how many. The kept faces are grouped by their
// lowest vertex (a counting sort, ascending face order within a group), and only the faces of one
// group are compared, in parallel over fixed chunks of groups: each face is in one group, so each
// chunk writes only its own faces' flags, and the count is a sum. Linear time and two small arrays,
// where a hash table of all faces would touch many more fresh pages.
size_t markDuplicateFaces(const Mesh& mesh, std::vector<uint8_t>& keep) {
    const size_t n = mesh.vertexCount();
    const size_t face_count = mesh.faceCount();
    const uint32_t* ix = mesh.indices.data();
    auto lowest = [&](size_t f) { return std::min({ix[3 * f], ix[3 * f + 1], ix[3 * f + 2]}); };
    // The other two ids, ascending, as one key.
    auto rest = [&](size_t f) {
        const uint32_t a = ix[3 * f], b = ix[3 * f + 1], c = ix[3 * f + 2];
        const uint32_t lo = std::min({a, b, c}), hi = std::max({a, b, c});
        const uint32_t mid = a ^ b ^ c ^ lo ^ hi;
        return (uint64_t(mid) << 32) | hi;
    };
    std::vector<uint32_t> start(n + 2, 0); // start[v + 1] ends up as the first slot of group v
    for (size_t f = 0; f < face_count; ++f)
        if (keep[f]) ++start[lowest(f) + 2];
    for (size_t v = 2; v < n + 2; ++v) start[v] += start[v - 1];
    std::vector<uint32_t> faces(start[n + 1]);
    for (size_t f = 0; f < face_count; ++f)
        if (keep[f]) faces[start[lowest(f) + 1]++] = uint32_t(f);
    constexpr size_t kChunk = 8192; // groups per task
    std::vector<uint32_t> chunk_duplicates(chunkCount(n, kChunk), 0);
    auto scan = [&](size_t chunk, size_t first, size_t last) {
        std::vector<std::pair<uint64_t, uint32_t>> long_group;
        uint32_t duplicates = 0;
        for (size_t v = first; v < last; ++v) {
            const uint32_t* g = faces.data() + start[v];
            const size_t count = start[v + 1] - start[v];
            if (count <= 16) {
                for (size_t i = 1; i < count; ++i) {
                    const uint64_t k = rest(g[i]);
                    for (size_t j = 0; j < i; ++j)
                        if (rest(g[j]) == k) {
                            keep[g[i]] = 0;
                            ++duplicates;
                            break;
                        }
                }
                continue;
            }
            long_group.clear();
            for (size_t i = 0; i < count; ++i) long_group.push_back({rest(g[i]), g[i]});
            std::sort(long_group.begin(), long_group.end()); // by key, then face: the first of a key stays
            for (size_t i = 1; i < count; ++i)
                if (long_group[i].first == long_group[i - 1].first) {
                    keep[long_group[i].second] = 0;
                    ++duplicates;
                }
        }
        chunk_duplicates[chunk] = duplicates;
    };
    if (!parallelForChunks(n, kChunk, scan).ok()) {
        // A worker ran out of memory: again on this thread (marking twice changes nothing).
        for (size_t chunk = 0; chunk < chunk_duplicates.size(); ++chunk)
            scan(chunk, chunk * kChunk, std::min(n, (chunk + 1) * kChunk));
    }
    size_t total = 0;
    for (uint32_t d : chunk_duplicates) total += d;
    return total;
}

} // namespace

DegenerateReport removeDegenerateFaces(Mesh& mesh, const DegenerateOptions& options) {
    DegenerateReport r;
    const size_t face_count = mesh.faceCount();
    std::vector<uint8_t> keep(face_count, 1);
    // The per-face tests are independent: run in parallel into per-face slots, counted in face order.
    enum : uint8_t { kKeep, kRepeated, kNonFinite, kZeroArea };
    std::vector<uint8_t> verdict(face_count, kKeep);
    auto test = [&](size_t f) {
        const uint32_t* t = &mesh.indices[3 * f];
        if (hasRepeatedIndex(mesh, f)) {
            verdict[f] = kRepeated;
        } else if (!isFinite(mesh.positions[t[0]]) || !isFinite(mesh.positions[t[1]]) ||
                   !isFinite(mesh.positions[t[2]])) {
            verdict[f] = kNonFinite;
        } else if (options.remove_zero_area) {
            const Vec3d n = faceNormal(mesh, f);
            if (dot(n, n) == 0.0) verdict[f] = kZeroArea;
        }
    };
    if (!parallelFor(face_count, 4096, test).ok())
        for (size_t f = 0; f < face_count; ++f) test(f); // a worker ran out of memory: redo on this thread
    for (size_t f = 0; f < face_count; ++f) {
        switch (verdict[f]) {
        case kRepeated: ++r.repeated_index_faces; break;
        case kNonFinite: ++r.non_finite_faces; break;
        case kZeroArea: ++r.zero_area_faces; break;
        default: break;
        }
        keep[f] = verdict[f] == kKeep;
    }
    if (options.remove_duplicates) r.duplicate_faces = markDuplicateFaces(mesh, keep);
    removeFaces(mesh, keep);
    return r;
}

PassCounters UnreferencedReport::counters() const {
    return {{"vertices_removed", vertices_removed}};
}

} // namespace lodbake
