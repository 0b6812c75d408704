#pragma once
// The edge-collapse engine shared by simplify() and buildLodChain(): a corner table (half-edge =
// corner, uint32 twins) over the input welded by position, per-point quadrics, per-wedge
// attribute quadrics and an indexed collapse queue. It can be run towards successively smaller
// targets and snapshotted in between, which is how a whole LOD chain costs one pass.

#include <cstdint>
#include <vector>

#include "lodbake/core/diagnostics.h"
#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"
#include "lodbake/simplify/lod_chain.h"
#include "lodbake/simplify/quadric.h"
#include "lodbake/simplify/simplify.h"
#include "simplify/collapse_queue.h"
#include "core/large_array.h"

namespace lodbake::detail {

class EdgeCollapser {
public:
    /// Builds the connectivity, quadrics and queue. Fails on invalid input.
    Status init(const Mesh& mesh, const SimplifyOptions& options, Diagnostics& diagnostics);

    /// Collapses edges in cost order until at most `target_faces` remain or no valid collapse with
    /// estimated error ≤ max_error is left. Appends to `sequence` when not null. Returns true when
    /// the face target was reached.
    bool run(size_t target_faces, double max_error, CollapseSequence* sequence);

    /// The current mesh (alive faces in input order, referenced wedges in first-use order).
    Mesh extract() const;

    /// Points, wedges and attribute layout of the sequence (before any record); for a half-edge
    /// sequence (KeepEndpoint) also its point triangles, and later runs log the re-created triangles.
    void describe(CollapseSequence& sequence);

    /// Appends (removed point, kept point, kept point unmoved, removed point nearer the merged
    /// position) of every later collapse to `log` (null: stop), for the chain's vertex-removal
    /// reading (LodChainOptions::record_removals).
    void setRemovalLog(CollapsePairLog* log) { removal_log_ = log; }

    /// run() starts with partitioned rounds (two parts of the mesh collapsed side by side, then
    /// merged; docs/simplify.md, "Partitioned rounds") while at least this many faces are alive and
    /// nothing the parts would share is in use. Default kRoundMinFaces, so that smaller meshes keep
    /// the serial collapse order; tests lower it to reach rounds on small meshes.
    void setRoundMinFaces(size_t faces) { round_min_faces_ = faces; }
    static constexpr size_t kRoundMinFaces = 200000;
    size_t roundCount() const { return rounds_; } // partitioned rounds run so far

    size_t faceCount() const { return alive_faces_; }
    // refine_late_levels applies to a snapshot taken now: at most 2.5 % of the input's faces (the 2 %
    // and 0.5 % levels it is tuned for; a 3 % level is not refined, which saves most of the
    // refinement's cost in the default 5-level chain).
    bool refinesSnapshot() const {
        return options_.refine_late_levels && options_.placement == CollapsePlacement::Optimal &&
               double(alive_faces_) <= 0.025 * double(initial_faces_);
    }
    size_t initialFaceCount() const { return initial_faces_; }
    size_t collapseCount() const { return collapses_; }
    size_t removalCount() const { return removals_; }       // components removed (remove_covered_components)
    size_t removedFaceCount() const { return removed_faces_; } // faces they had
    double maxCollapseError() const { return max_error_done_; }
    size_t chartCount() const { return chart_count_; }          // UV charts of the input (first UV set)
    size_t droppedChartCount() const { return dropped_charts_; } // charts whose last face was collapsed

private:
    enum Kind : uint8_t { kFree = 0, kLine = 1, kCorner = 2, kLocked = 3, kDead = 4 };
    static constexpr uint32_t kNone = 0xffffffffu;

    struct Candidate {
        uint32_t edge = kNone; // canonical half-edge
        uint32_t removed = kNone;
        uint32_t kept = kNone;
        Vec3d position;
        double cost = 0;
        double error = 0; // geometric RMS distance estimate, object units
    };
    struct WedgePair {
        uint32_t removed;
        uint32_t kept;
    };

    static uint32_t nextHe(uint32_t h) { return h % 3 == 2 ? h - 2 : h + 1; }
    static uint32_t prevHe(uint32_t h) { return h % 3 == 0 ? h + 2 : h - 1; }
    uint32_t canonical(uint32_t h) const {
        const uint32_t t = he_[h].twin;
        return (t == kNone || h < t) ? h : t;
    }
    uint32_t wedgeAt(uint32_t h) const { return corner_wedge_.empty() ? he_[h].point : corner_wedge_[h]; }
    // An open edge, a sub-mesh border or an attribute seam (inline: every key evaluation and fan
    // classification asks).
    bool isFeature(uint32_t h) const {
        const uint32_t t = he_[h].twin;
        if (t == kNone) return true;
        if (!face_group_.empty() && face_group_[h / 3] != face_group_[t / 3]) return true;
        if (!corner_wedge_.empty())
            return corner_wedge_[h] != corner_wedge_[nextHe(t)] || corner_wedge_[nextHe(h)] != corner_wedge_[t];
        return false;
    }
    // Scratch, queue and counters of one collapse loop: run()'s serial loop (serial_), or one part of
    // a partitioned round (parts_), which touches only its part's data, so parts run side by side.
    struct Worker {
        std::vector<uint32_t> fan_u, fan_v, fan_tmp;
        std::vector<uint32_t> link_u;                  // isValid: the neighbours of the removed point
        bool fan_u_closed = true, fan_v_closed = true; // from the last isValid
        std::vector<std::pair<uint32_t, uint32_t>> created_tmp; // (triangle id, face)
        PartHeap* heap = nullptr;       // a part's heap; null: queue_ and the engine's counters
        uint32_t part = 0;              // with heap: which part (part_points_)
        std::vector<uint32_t> deferred; // with heap: edges outside the part whose key changed (runRound)
        // With heap and a removal log: the part's collapses, appended to the log in part order at the
        // merge (a valid order: the parts never touch the same data).
        CollapsePairLog removals;
        size_t faces_removed = 0, collapses = 0; // with heap: the part's counters
        double max_error = 0;
    };
    // Fixed, not the thread count, so that the result is the same at any thread count (one thread
    // runs the parts one after the other).
    static constexpr uint32_t kRoundParts = 2;
    // A round removes this fraction of the faces to its target; the serial loop removes the rest,
    // the seam band's first (a larger share leaves it too little to catch up on the seam band, and
    // the Hausdorff error rises above the serial order's).
    static constexpr double kRoundShare = 0.9;
    static constexpr uint32_t kRoundMaxPhases = 16; // key limits per round (runRound)
    // No round that would remove fewer than alive / this faces (its set-up is a few passes over the mesh).
    static constexpr size_t kRoundMinRemovedDivisor = 16;
    bool pointInPart(uint32_t part, uint32_t point) const {
        return (part_points_[part][point >> 6] >> (point & 63)) & 1;
    }
    // Whether an alive edge belongs to the part (both ends in it) during a round.
    bool inPart(uint32_t part, uint32_t edge) const {
        const uint32_t a = he_[edge].point;
        return a != kNone && pointInPart(part, a) && pointInPart(part, he_[nextHe(edge)].point);
    }
    bool roundApplies(size_t target_faces, const CollapseSequence* sequence) const;
    // Collapses kRoundShare of the way to target_faces in kRoundParts parts side by side, then merges
    // their queues and counters (nothing when the mesh cannot be cut or the parts do not fit).
    void runRound(size_t target_faces, double max_error);
    // runRound's steps, in order.
    struct RoundCut;
    // The plane that cuts the alive points in two; false when they have no extent to cut.
    bool findRoundCut(RoundCut& cut) const;
    // part_points_: the points whose collapses touch only their part's data.
    void markRoundParts(const RoundCut& cut);
    // Moves the parts' edges from queue_ to their heaps; false when the parts do not fit.
    bool splitQueue(PartHeap* heaps);
    // Collapses in the parts side by side up to `goal` faces, then merges their queues and counters.
    void collapseRoundParts(PartHeap* heaps, size_t goal, double max_error);
    // The top of w's queue: collapsed, re-queued with its distance penalty, or dropped.
    void step(Worker& w, double max_error, CollapseSequence* sequence);
    // Removes an edge from w's queue (a part: from its heap, or defers an edge outside it).
    void queueRemove(Worker& w, uint32_t edge);
    bool canRemove(uint32_t point, bool feature_edge) const;
    // Outgoing half-edges of `point`, one per incident face; returns false if the fan is open.
    bool gatherFan(uint32_t point, std::vector<uint32_t>& fan) const;
    Kind classify(Worker& w, uint32_t point); // gathers the fan into w.fan_tmp
    Kind classifyFan(const std::vector<uint32_t>& fan, bool closed) const;
    bool evaluate(uint32_t edge, Candidate& c) const;
    void collectPairs(uint32_t edge, uint32_t removed, WedgePair* pairs, int& pair_count) const;
    bool isValid(Worker& w, const Candidate& c, int& pair_count, WedgePair* pairs);
    struct RegionNormal {
        bool ready = false;
        Vec3d normal; // summed face normals of both fans, computed when a sliver needs it
    };
    // Rejects flips and too-large normal rotations; tracks the worst squared face quality of the
    // neighbourhood before (min_old2) and after (min_new2).
    bool checkFaces(const Worker& w, const std::vector<uint32_t>& fan, uint32_t moved, const Vec3d& p, uint32_t f0,
                    uint32_t f1, RegionNormal& region, double& min_old2, double& min_new2) const;
    // True when two normals with dot product d and squared lengths len2_a, len2_b are further apart
    // than max_normal_change_deg.
    bool normalTurnsTooFar(double d, double len2_a, double len2_b) const;
    // Largest squared point distance of a valid collapse (fans from isValid): the endpoints' old
    // positions to the new fan, and the new position to the old fans. Exact when above stop2;
    // otherwise some value no larger than stop2.
    double endpointDistance2(const Worker& w, const Candidate& c, double stop2) const;
    // True when a is strictly further than b from the fan v will have after the collapse c (fans
    // from isValid).
    bool fartherFromNewFan(const Worker& w, const Vec3d& a, const Vec3d& b, const Candidate& c) const;
    // An upper bound of endpointDistance2 from a few point-segment distances.
    double distanceBound2(const Candidate& c) const;
    // False when a face of `fan` (other than f0/f1) would flip or degenerate in any UV set.
    bool checkUvFaces(const std::vector<uint32_t>& fan, const Vec3d& p, uint32_t f0, uint32_t f1,
                      const WedgePair* pairs, int pair_count) const;
    Vec3d fanNormal(const std::vector<uint32_t>& fan) const;
    void collapse(Worker& w, const Candidate& c, const WedgePair* pairs, int pair_count, CollapseSequence* sequence);
    // collapse's steps.
    // Requests the data the collapse and the re-evaluations after it read at random.
    void prefetchNeighbourhood(const Worker& w, const CollapseSequence* sequence) const;
    // Merges each removed wedge's attribute quadrics into the kept one and places its attributes.
    void mergeWedges(const Candidate& c, const WedgePair* pairs, int pair_count, CollapseSequence* sequence);
    // Removes the edge's faces (h's, and t's unless kNone), gluing their other edges' twins.
    void removeCollapsedFaces(Worker& w, uint32_t h, uint32_t t);
    void updateEdgesAround(Worker& w, uint32_t point);
    void updateEdgesInFan(Worker& w); // the edges of the fan in w.fan_tmp
    void requeueAll();
    // init's steps, in order.
    struct InputMap;
    // Welds the input's vertices into points (by position) and wedges (by position and attributes).
    void weldPoints(InputMap& map);
    // Renumbers the points in order of first use by the faces.
    void renumberPointsByFirstUse(InputMap& map);
    // The corner table's points and wedges, the sub-mesh of every face; returns the face count.
    uint32_t buildFaces(const InputMap& map, Diagnostics& diagnostics);
    // Twins and point_he_ from each point's outgoing half-edges (`start`: their ranges by point).
    Status linkTwins(const LargeArray<uint32_t>& start);
    // Each point's kind (locked when its faces form more than one fan).
    Status classifyPoints(const LargeArray<uint32_t>& start, Diagnostics& diagnostics);
    Status accumulateQuadrics(const std::vector<uint8_t>& covered_border);
    Status accumulateAttributeBlocks();
    void buildUvCharts(const Mesh& mesh);
    // Every valid collapse's key, in the queue.
    Status queueInitialKeys();
    // remove_covered_components (covered_components.cpp): removes every connected component whose
    // points, far points and face centroids all lie within `tolerance` of the other components'
    // faces, smallest first; appends each removal to `sequence` when not null.
    void removeCoveredComponents(double tolerance, CollapseSequence* sequence);
    struct Components;
    // Labels the alive faces' components and builds their bounds and BVHs; false with fewer than two.
    bool findComponents(Components& set) const;
    // Per half-edge: 1 for an open border edge whose ends and midpoint lie within its length of
    // another component (a scan's border lying on another scan: not a border of the object).
    void markCoveredBorders(std::vector<uint8_t>& covered) const;
    // `geometric` (the edge's two point quadrics summed) plus the attribute quadrics of the wedge
    // pairs the collapse removing `removed` merges.
    Quadric combinedQuadric(const Quadric& geometric, uint32_t edge, uint32_t removed) const;
    // Hint that the point's quadric and kind are about to be read (random accesses).
    void prefetchPoint(uint32_t point) const {
#if defined(__GNUC__)
        const char* q = reinterpret_cast<const char*>(&quadric_[point]);
        __builtin_prefetch(q);
        __builtin_prefetch(q + 64);
        __builtin_prefetch(q + sizeof(Quadric) - 1);
        __builtin_prefetch(&kind_[point]);
        __builtin_prefetch(&position_[point]);
#else
        (void)point;
#endif
    }
    const double* wedgeBlock(uint32_t wedge) const { return &wedge_block_[size_t(wedge) * block_size_]; }
    // Hint that the wedge's attribute block is about to be read: every line it spans (a block of
    // three channels is 184 bytes, so three or four lines).
    void prefetchWedgeBlock(uint32_t wedge) const {
#if defined(__GNUC__)
        const char* b = reinterpret_cast<const char*>(wedgeBlock(wedge));
        const size_t bytes = block_size_ * sizeof(double);
        for (size_t offset = 0; offset < bytes; offset += 64) __builtin_prefetch(b + offset);
        __builtin_prefetch(b + bytes - 1);
#else
        (void)wedge;
#endif
    }

    const Mesh* source_ = nullptr;
    SimplifyOptions options_;
    double cos_max_normal_change_ = 0;
    double attribute_scale_ = 1;
    uint32_t uv_channel_ = 0xffffffffu; // first UV channel, none without UV sets
    uint32_t uv_set_count_ = 0;
    LargeArray<uint32_t> face_chart_;  // UV chart (representative face) per face
    LargeArray<uint32_t> chart_alive_; // alive faces per chart representative
    size_t chart_count_ = 0, dropped_charts_ = 0;
    // Below late_faces_ faces (kLateFraction of the input) the point-distance penalty also
    // measures far_ points and face centroids, and prices distances by the mean area (run()).
    size_t late_faces_ = 0;
    bool late_ = false;
    double total_weight_ = 0; // sum of the points' quadric weights (three times the surface area)
    bool has_penalty_ = false; // tip_distance_weight > 0: the queue payload of an edge is its point-distance
                               // price from its last pop (run())

    // Points (distinct positions) and wedges (distinct position + attributes).
    LargeArray<Vec3f> position_;
    // Per point, one input point it stands for: of the two merged by each collapse, the one
    // further from the new fan (with tip_distance_weight > 0 only).
    LargeArray<Vec3f> far_;
    LargeArray<uint32_t> point_he_; // an outgoing half-edge of an alive face, or kNone
    LargeArray<uint8_t> kind_;
    LargeArray<Quadric> quadric_;
    LargeArray<uint32_t> wedge_vertex_; // an input vertex carrying the wedge's original attributes
    LargeArray<uint32_t> wedge_point_;
    uint32_t channel_count_ = 0;                  // scalar attribute channels per wedge
    std::vector<float> channel_weight_;           // per channel, squared weight × scale²
    LargeArray<float> wedge_value_;              // wedge_count × channel_count_
    size_t block_size_ = 0;             // attributeBlockSize(channel_count_), 0 without attributes
    LargeArray<double> wedge_block_;   // wedge_count × block_size_: each wedge's attribute quadrics

    // Corner table: half-edge h goes from he_[h].point to he_[nextHe(h)].point; its twin (opposite
    // half-edge) is he_[h].twin. Point and twin share one array: every fan walk reads both.
    struct HalfEdge {
        uint32_t point; // kNone for dead faces
        uint32_t twin;  // kNone on open or non-manifold edges
    };
    LargeArray<HalfEdge> he_;
    LargeArray<uint32_t> corner_wedge_; // empty when there are no attribute streams
    LargeArray<uint32_t> face_group_;  // sub-mesh per face; empty with a single sub-mesh
    std::vector<uint32_t> group_first_face_;

    CollapseQueue queue_;
    size_t alive_faces_ = 0;
    size_t initial_faces_ = 0;
    size_t collapses_ = 0;
    double max_error_done_ = 0;
    bool remove_components_ = false;   // remove_covered_components with Optimal placement
    size_t next_component_check_ = 0; // remove_covered_components: alive-face count of the next check
    size_t removals_ = 0, removed_faces_ = 0;

    // Half-edge sequences (describe()): the triangle id of every face (an input face is its index, a
    // face re-created by a collapse gets the next id), so that each record lists the triangles it
    // re-creates in the order of the ones they replace (CollapseSequence::created_triangles).
    LargeArray<uint32_t> face_triangle_;
    uint32_t triangle_count_ = 0;

    CollapsePairLog* removal_log_ = nullptr; // setRemovalLog

    Worker serial_;
    Worker parts_[kRoundParts];
    std::vector<uint64_t> part_points_[kRoundParts]; // during a round: per point, 1 when in the part
    size_t round_min_faces_ = kRoundMinFaces;
    int round_axis_ = -1; // cut axis of the last round
    size_t rounds_ = 0;
};

} // namespace lodbake::detail
