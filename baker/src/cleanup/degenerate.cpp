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

DegenerateReport removeDegenerateFaces(Mesh& mesh, const DegenerateOptions& options) {
    DegenerateReport r;
    const size_t face_count = mesh.faceCount();
    std::vector<uint8_t> keep(face_count, 1);
    std::vector<std::array<uint32_t, 3>> keys; // sorted vertex sets of the faces that pass the tests above
    std::vector<uint32_t> key_face;
    if (options.remove_duplicates) {
        keys.reserve(face_count);
        key_face.reserve(face_count);
    }
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
        if (verdict[f] != kKeep) {
            keep[f] = 0;
            continue;
        }
        if (!options.remove_duplicates) continue;
        const uint32_t* t = &mesh.indices[3 * f];
        std::array<uint32_t, 3> k = {t[0], t[1], t[2]};
        std::sort(k.begin(), k.end());
        keys.push_back(k);
        key_face.push_back(uint32_t(f));
    }
    if (options.remove_duplicates) {
        // Faces come in ascending order, so the first of each vertex set (the one that stays) is the earliest.
        const std::vector<uint32_t> first = lowestEqualKey(uint32_t(keys.size()), [&](uint32_t i) { return keys[i]; });
        for (uint32_t i = 0; i < first.size(); ++i)
            if (first[i] != i) {
                keep[key_face[i]] = 0;
                ++r.duplicate_faces;
            }
    }
    removeFaces(mesh, keep);
    return r;
}

PassCounters UnreferencedReport::counters() const {
    return {{"vertices_removed", vertices_removed}};
}

} // namespace lodbake
