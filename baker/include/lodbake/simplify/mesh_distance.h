#pragma once
// Two-sided surface distance between a reference mesh and an approximation, the error every LOD
// level carries. Metro-style: area-uniform (stratified) samples on each surface plus its vertices, exact
// point-to-triangle distance to the other surface through a BVH. Agrees with
// ../shared/eval/meshdist.py (same definitions) within sampling noise.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "lodbake/core/bvh.h"
#include "lodbake/core/mapped_array.h"
#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"

namespace lodbake {

namespace detail {
/// Storage of DistanceIndex's arrays: allocations of 2 MB and more are mapped on their own with
/// transparent huge pages, which saves the page faults of filling them and the TLB misses of the
/// queries' scattered reads.
template <class T>
using DistanceArray = MappedArray<T, MappedPages::Huge>;
} // namespace detail

struct DistanceOptions {
    uint32_t sample_count = 200000; // area-uniform samples per side (vertices are added on top)
    uint64_t seed = 1;              // sampling is deterministic for a seed, whatever the thread count
    bool include_vertices = true;   // also measure from every referenced vertex, so spikes are not missed
};

/// Distances in object units and relative to the reference's bounding-box diagonal.
struct DistanceResult {
    double hausdorff = 0.0; // max of both one-sided maxima
    double mean = 0.0;      // (mean(ref→approx) + mean(approx→ref)) / 2
    double rms = 0.0;       // sqrt((ms(ref→approx) + ms(approx→ref)) / 2)
    double max_ref_to_approx = 0.0;
    double max_approx_to_ref = 0.0;
    double diagonal = 0.0; // reference bounding-box diagonal (referenced vertices)
    double hausdorffRel() const { return diagonal > 0 ? hausdorff / diagonal : 0.0; }
    double meanRel() const { return diagonal > 0 ? mean / diagonal : 0.0; }
    double rmsRel() const { return diagonal > 0 ? rms / diagonal : 0.0; }
};

/// One side of a two-sided distance: the distances from one surface's points to the other surface,
/// combined in chunk order (what DistanceResult is computed from, two sides at a time).
struct OneSidedDistance {
    double max = 0.0;
    double sum = 0.0;
    double sum_sq = 0.0;
    uint64_t count = 0;
};

/// Measures the two-sided distance. Fails (InvalidInput) if either mesh has no triangle of
/// non-zero area, has an index out of range or a referenced vertex with a NaN/Inf coordinate, or if
/// options ask for no points at all (sample_count 0 and include_vertices false).
/// The result is bit-identical for any thread count.
Result<DistanceResult> measureSurfaceDistance(const Mesh& reference, const Mesh& approx,
                                              const DistanceOptions& options = {});

/// Nearest-surface index used by the measurement: a 4-wide BVH whose child boxes are tested four at a
/// time in float (boxes widened so the float test never prunes a triangle that could be nearest), and
/// whose leaf triangles are measured exactly in double (closestPointOnTriangle, lodbake/core/bvh.h).
/// The distance returned is the minimum of that exact computation over every triangle, so it does not
/// depend on the tree's shape or on the hint.
class DistanceIndex {
public:
    DistanceIndex() = default;

    /// \pre indices.size() % 3 == 0, every index < positions.size(), positions finite.
    /// Fails only when resources run out (2^28 triangles or more, or a failed allocation).
    static Result<DistanceIndex> build(const std::vector<Vec3f>& positions, const std::vector<uint32_t>& indices);

    static constexpr uint32_t kNoHint = 0xffffffffu;
    static constexpr uint32_t kCursorDepth = 32;

    /// What one query leaves for the next, nearby one (one cursor per thread, default-constructed at
    /// first): the nearest triangle's slot, whose distance starts the next search, and the nodes the
    /// search descended through alone (each the only child of its parent within the bound), each with
    /// a lower bound on the distance from `point` to every triangle outside it. The next query starts
    /// at the deepest such node whose bound, less the distance between the two points, still exceeds
    /// its first bound, instead of at the root.
    struct Cursor {
        uint32_t hint = kNoHint;
        uint32_t depth = 0; // path entries in use
        Vec3d point;        // the query the clearances are relative to
        uint32_t node[kCursorDepth];
        double clearance[kCursorDepth];
    };

    /// Squared distance from `p` to the nearest triangle (infinity for an empty index). `hint` is a
    /// triangle slot near the last query (kNoHint at first): its distance starts the search; it is
    /// updated to the nearest triangle's slot. Thread-safe with one hint per thread.
    double closestDistanceSq(const Vec3d& p, uint32_t& hint) const;
    /// The same distance; the search starts from `cursor` (see Cursor) and updates it.
    double closestDistanceSq(const Vec3d& p, Cursor& cursor) const;
    /// The input triangle of a slot.
    uint32_t faceOfSlot(uint32_t slot) const { return face_of_slot_[slot]; }

    size_t triangleCount() const { return face_of_slot_.size(); }
    size_t nodeCount() const { return nodes_.size(); }

    struct Node {
        float lo[3][4]; // lo[axis][child]: box minimum, widened (see mesh_distance.cpp)
        float hi[3][4];
        uint32_t child[4]; // node index, leaf (kLeafBit | first slot << 3 | count - 1) or kEmpty
    };

private:
    double scalarBoxDistanceSq(const Node& node, int child, const Vec3d& p) const;
    double triangleBoxDistanceSq(uint32_t slot, const Vec3d& p) const;

    detail::DistanceArray<Node> nodes_;
    detail::DistanceArray<Vec3f> corners_;         // 3 per slot, leaf order
    detail::DistanceArray<uint32_t> face_of_slot_; // input triangle of every slot
    uint32_t root_ = 0xffffffffu;        // child reference of the root (see mesh_distance.cpp)
    float magnitude_ = 0.0f;             // queries with a larger coordinate take the double box test
    double slack_ = 0.0;                 // how far every box is widened (see mesh_distance.cpp)
};

/// A reference surface checked and indexed once, for measuring several approximations against it
/// (every level of an LOD chain) without rebuilding its BVH each time. Keeps a pointer to the mesh:
/// `reference` must outlive this object and stay unchanged.
class DistanceReference {
public:
    /// Fails as measureSurfaceDistance does for a bad reference.
    static Result<DistanceReference> prepare(const Mesh& reference);

    const Mesh& mesh() const { return *mesh_; }
    const DistanceIndex& index() const { return index_; }
    /// Diagonal of the reference's bounding box (what DistanceResult::diagonal reports).
    double diagonal() const { return diagonal_; }

private:
    friend Result<std::vector<Result<DistanceResult>>> prepareAndMeasureSurfaceDistances(
        const Mesh& reference, const std::vector<const Mesh*>& approximations, const DistanceOptions& options,
        const std::vector<const OneSidedDistance*>& reference_sides);
    static Result<DistanceReference> prepareChecked(const Mesh& reference); // prepare after checkSurface

    const Mesh* mesh_ = nullptr;
    DistanceIndex index_;
    double diagonal_ = 0.0;
};

/// Same as measureSurfaceDistance(reference.mesh(), approx, options), with the same result.
Result<DistanceResult> measureSurfaceDistance(const DistanceReference& reference, const Mesh& approx,
                                              const DistanceOptions& options = {});

/// Measures every approximation against one reference: results[i] is exactly (bit for bit) what
/// measureSurfaceDistance(reference, *approximations[i], options) returns, including its error. The
/// reference side's points are drawn once, and the approximations are measured one after the other,
/// each in parallel inside, the next one's index and points built beside (so at most two
/// approximations' indexes and points exist at once). The result does not depend on the thread count.
/// Pointers must not be null.
std::vector<Result<DistanceResult>> measureSurfaceDistances(const DistanceReference& reference,
                                                            const std::vector<const Mesh*>& approximations,
                                                            const DistanceOptions& options = {});

/// DistanceReference::prepare(reference) followed by measureSurfaceDistances, with the same results, but
/// the reference's index, its points and the first approximation's index and points are built side by
/// side. Fails as prepare does for a bad reference, and for options asking for no points.
Result<std::vector<Result<DistanceResult>>> prepareAndMeasureSurfaceDistances(
    const Mesh& reference, const std::vector<const Mesh*>& approximations, const DistanceOptions& options = {});

/// The reference side alone: for every approximation, the distances from the reference's points to it,
/// bit-identical to the side that prepareAndMeasureSurfaceDistances measures with the same reference and
/// options. It needs neither the reference's index nor the approximations' points, only the reference's
/// points (kept as their sources, 8 bytes each; every query recomputes its point, bit for bit) and one
/// approximation's index at a time, so it can run earlier, where memory is short (the bake runs it
/// beside the PFRep build).
/// Fails as prepareAndMeasureSurfaceDistances does for a bad reference or options; results[i] fails
/// for a bad approximation (the two-sided measurement then fails the same way). Pointers must not be null.
Result<std::vector<Result<OneSidedDistance>>> measureReferenceSides(const Mesh& reference,
                                                                   const std::vector<const Mesh*>& approximations,
                                                                   const DistanceOptions& options = {});

/// prepareAndMeasureSurfaceDistances with the reference sides of some approximations measured beforehand
/// by measureReferenceSides (same reference, same options): `reference_sides[i]`, when present and not
/// null, is taken as approximation i's reference side instead of being measured, and approximation i's
/// index is never built. When every side is given, the reference's points are not drawn. The results
/// are bit-identical to measuring both sides here.
Result<std::vector<Result<DistanceResult>>> prepareAndMeasureSurfaceDistances(
    const Mesh& reference, const std::vector<const Mesh*>& approximations, const DistanceOptions& options,
    const std::vector<const OneSidedDistance*>& reference_sides);

} // namespace lodbake
