#pragma once
// Internal helpers shared by the cleanup passes: an undirected edge table over face corners, face and
// vertex removal that keeps every attribute stream and sub-mesh range in step, vertex duplication,
// boundary-loop walking. Not part of the public surface.

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "lodbake/cleanup/normals.h"
#include "lodbake/cleanup/passes.h"
#include "lodbake/cleanup/topology.h"
#include "lodbake/cleanup/validate.h"
#include "lodbake/core/mesh.h"
#include "core/large_array.h"

namespace lodbake {
namespace cleanup_detail {

constexpr uint32_t kNone = UINT32_MAX;

inline uint64_t edgeKey(uint32_t a, uint32_t b) {
    return a < b ? (uint64_t(a) << 32) | b : (uint64_t(b) << 32) | a;
}

/// Every half-edge is a face corner c, running from indices[c] to indices[next(c)]. Faces with a
/// repeated index contribute no half-edges. Edges are the distinct undirected keys, sorted.
struct EdgeTable {
    // Large arrays (tens of MB on a scan): huge pages where the OS offers them, see large_array.h.
    detail::LargeArray<uint64_t> keys;        // per edge, sorted ascending
    detail::LargeArray<uint32_t> begin;       // per edge + 1: range into `corners`
    detail::LargeArray<uint32_t> corners;     // half-edges grouped by edge, ascending corner within an edge
    detail::LargeArray<uint32_t> corner_edge; // per corner: its edge, or kNone (face with a repeated index)

    size_t edgeCount() const { return keys.size(); }
    uint32_t uses(uint32_t e) const { return begin[e + 1] - begin[e]; }
    /// Edge id of (a,b) or kNone.
    uint32_t find(uint32_t a, uint32_t b) const;
};

/// Built in linear time (a counting sort by lower vertex, then a short sort inside each bucket).
EdgeTable buildEdgeTable(const Mesh& mesh);
/// The same over a bare index list whose ids are below vertex_count (e.g. indices with welded ids).
EdgeTable buildEdgeTable(const std::vector<uint32_t>& indices, size_t vertex_count);
/// The same into `out`, reusing its storage (a table rebuilt in place writes to pages already
/// mapped; fresh pages are most of what a new table of a large mesh costs).
void buildEdgeTable(const std::vector<uint32_t>& indices, size_t vertex_count, EdgeTable& out);

/// Storage that the passes of one repairMesh call hand on to each other (see buildEdgeTable).
struct Scratch {
    EdgeTable table;
};

/// Start and end vertex of half-edge (corner) c.
inline uint32_t halfStart(const Mesh& m, uint32_t c) {
    return m.indices[c];
}
inline uint32_t halfEnd(const Mesh& m, uint32_t c) {
    return m.indices[c % 3 == 2 ? c - 2 : c + 1];
}

inline bool hasRepeatedIndex(const Mesh& m, size_t f) {
    const uint32_t* t = &m.indices[3 * f];
    return t[0] == t[1] || t[1] == t[2] || t[0] == t[2];
}

/// Unnormalised face normal (twice the area vector), in double.
Vec3d faceNormal(const Mesh& m, size_t f);

/// Removes the faces with keep[f] == 0, keeping order and sub-mesh ranges. Returns faces removed.
size_t removeFaces(Mesh& mesh, const std::vector<uint8_t>& keep);

/// Appends triangles; each goes at the end of the sub-mesh given in `submesh` (ignored when the mesh
/// has no sub-meshes).
void insertFaces(Mesh& mesh, const std::vector<std::array<uint32_t, 3>>& faces, const std::vector<uint32_t>& submesh);

/// Sub-mesh index of every face (all 0 when there are none).
std::vector<uint32_t> faceSubmeshes(const Mesh& mesh);

/// Rebuilds every stream: old vertex v becomes old_to_new[v] (kNone drops it). A new vertex takes
/// the attributes of the lowest old vertex mapped to it. Indices are rewritten.
void remapVertices(Mesh& mesh, const std::vector<uint32_t>& old_to_new, uint32_t new_count);

/// Appends a copy of vertex v (all streams); returns its index.
uint32_t duplicateVertex(Mesh& mesh, uint32_t v);

/// Appends a vertex whose every attribute is the mean of the three given vertices' (unit vectors
/// renormalised, tangent handedness from the first); returns its index.
uint32_t blendedVertex(Mesh& mesh, const std::array<uint32_t, 3>& from);

/// Union-find with smallest-root-wins, so results depend only on the order of unions.
class UnionFind {
public:
    explicit UnionFind(size_t n);
    uint32_t find(uint32_t x);
    void unite(uint32_t a, uint32_t b);

private:
    detail::LargeArray<uint32_t> parent_;
};

/// A pair of half-edges (corners) across which the surface continues.
struct CornerPair {
    uint32_t a, b;
};

/// Groups the corners around each vertex into fans: corners are joined across every pair in
/// `joins`. A vertex whose corners form k > 1 fans is split into k vertices (the fan holding the
/// lowest corner keeps the index). Returns the number of vertices split; `added` gets the new count.
/// With `table` (an edge table of `mesh` as it is), corners are also joined across its every 2-use edge.
size_t splitVerticesByFans(Mesh& mesh, const std::vector<CornerPair>& joins, size_t& added,
                           const EdgeTable* table = nullptr);

/// Directed boundary walk over half-edges used by exactly one face. Each result is a vertex
/// sequence v0..vn-1 whose faces traverse vi -> vi+1; `closed` tells whether the walk got back to v0.
struct BoundaryLoop {
    std::vector<uint32_t> vertices;
    std::vector<uint32_t> corners; // the boundary half-edge starting at each vertex
    bool closed = true;
};
std::vector<BoundaryLoop> findBoundaryLoops(const Mesh& mesh, const EdgeTable& table);
std::vector<BoundaryLoop> findBoundaryLoops(const std::vector<uint32_t>& indices, const EdgeTable& table);

/// Every vertex mapped to the lowest-numbered vertex with a bit-identical position, so that attribute
/// seams (UV or normal splits) can be told apart from real boundaries.
/// rep[i] = the lowest j with key(j) == key(i), for i in [0, n); key(i) is three 32-bit words. An
/// open-addressing table of first occurrences filled in ascending order (linear time): the result
/// is a function of the keys alone, no iteration order reaches it.
template <class KeyFn> std::vector<uint32_t> lowestEqualKey(uint32_t n, KeyFn key) {
    std::vector<uint32_t> rep(n);
    size_t capacity = 16;
    while (capacity < 2 * size_t(n)) capacity *= 2;
    std::vector<uint32_t> slot(capacity, kNone);
    const size_t mask = capacity - 1;
    for (uint32_t i = 0; i < n; ++i) {
        const std::array<uint32_t, 3> k = key(i);
        uint64_t h = ((uint64_t(k[0]) << 32) | k[1]) * 0x9e3779b97f4a7c15ull;
        h ^= (h >> 29) ^ (uint64_t(k[2]) * 0xc2b2ae3d27d4eb4full);
        h ^= h >> 32;
        for (size_t s = size_t(h) & mask;; s = (s + 1) & mask) {
            if (slot[s] == kNone) {
                slot[s] = i;
                rep[i] = i;
                break;
            }
            if (key(slot[s]) == k) {
                rep[i] = slot[s];
                break;
            }
        }
    }
    return rep;
}

/// Positions compare as floats (-0 equals +0; a NaN equals nothing). Hashing, linear time.
std::vector<uint32_t> positionWeldMap(const Mesh& mesh);

/// The same with positions compared bit for bit (-0 and +0 differ; identical NaN bits are equal).
std::vector<uint32_t> bitwiseWeldMap(const Mesh& mesh);

/// Topology statistics of the triangle list `indices` (ids into mesh.positions, all below
/// vertexCount(); the caller may have replaced ids by their weld representatives) from its edge
/// table. `distinct_vertex_count` is the vertex count to report (representatives only when
/// welded). `components` (sized vertexCount(), fresh) comes back holding the face-connected
/// components through shared ids, so callers can reuse it. The counts from the edge table and those
/// from the faces run side by side; `beside` (if set) runs after the latter, so independent work
/// of the caller overlaps the edge half. It may run twice (a failed parallel run is redone on one
/// thread), so it must assign its results, not add to them.
TopologyStats topologyFromTable(const Mesh& mesh, const std::vector<uint32_t>& indices,
                                uint64_t distinct_vertex_count, const EdgeTable& table, UnionFind& components,
                                const std::function<void()>& beside = {});

/// Per corner: 1 when its half-edge is a boundary edge lying on an attribute seam, that is, another
/// boundary edge has the same two positions and the vertices there differ in some attribute (UV,
/// normal, tangent, colour). Copies with identical attributes (a cut or split pinch) are not seams.
std::vector<uint8_t> seamCorners(const Mesh& mesh, const EdgeTable& table, const std::vector<uint32_t>& weld);

/// Per-vertex sorted unique neighbours, CSR form.
struct VertexAdjacency {
    std::vector<uint32_t> begin; // vertexCount() + 1
    std::vector<uint32_t> neighbours;
};
VertexAdjacency buildVertexAdjacency(const Mesh& mesh);

/// Vertices on an edge used by exactly one face.
std::vector<uint8_t> boundaryVertices(const Mesh& mesh, const EdgeTable& table);

/// The passes as repairMesh runs them: the public functions with storage shared between passes.
/// whole_mesh_recheck: after the first split, find over-used edges and re-split with whole-mesh edge
/// tables, as the `remove` mode always does (tests compare it with the local re-check of `cut`).
ManifoldReport makeManifold(Mesh& mesh, const ManifoldOptions& options, Scratch& scratch,
                            bool whole_mesh_recheck = false);
OrientReport orientFaces(Mesh& mesh, const OrientOptions& options, Scratch& scratch);
HoleFillReport fillHoles(Mesh& mesh, const HoleFillOptions& options, Scratch& scratch);
/// computeNormals() that hands back the weld map it used (positionWeldMap of the mesh it was given;
/// the pass moves no position, so when it adds no vertex this is also the result's weld map).
NormalsReport computeNormals(Mesh& mesh, const NormalOptions& options, std::vector<uint32_t>& weld);

/// validate() that also hands back the edge table it built (of the welded ids when
/// options.weld_by_position), for callers that go on to look at the same mesh. `beside`: independent
/// work of the caller, run beside the topology counts (see topologyFromTable).
ValidationReport validateWithTable(const Mesh& mesh, const ValidateOptions& options, EdgeTable* table_out,
                                   const std::function<void()>& beside = {});

} // namespace cleanup_detail
} // namespace lodbake
