#pragma once
// Discrete LOD chains built in ONE incremental simplification pass: the collapse sequence runs
// from full detail downwards and a snapshot is taken whenever a requested level is reached, so a
// 5-level chain costs about one simplification. The collapse sequence is recorded for the
// progressive representation (PFRep).
//
// Collapse record format (CollapseSequence):
//   Vertex ids in records are POINT ids: indices into CollapseSequence::point_positions, the
//   distinct positions of the input (bit-identical positions share a point), numbered in the
//   engine's own order (first use by the faces; match them to input vertices by position).
//   Attribute corners are WEDGE ids: indices into wedge_point, one per distinct
//   (position, attributes) vertex of the input; wedge w lies on point wedge_point[w].
//   records[i] is the i-th collapse in execution order:
//     removed_point  the point that disappears (every reference to it becomes kept_point);
//     kept_point     the surviving point, moved to `position`;
//     position       the new position of kept_point;
//     first_wedge_update, wedge_update_count: a range of wedge_updates. Each entry says that
//       removed_wedge (a wedge of removed_point) is replaced by kept_wedge (a wedge of kept_point),
//       whose attributes become the `attribute_stride` floats at
//       wedge_attributes[(first_wedge_update + k) * attribute_stride] in the layout
//       [normal xyz][uv0 xy][uv1 xy]...[colour rgba] (only the streams the input has).
//   The faces removed by a collapse are those that contained both points.
//   removals (only with SimplifyOptions::remove_covered_components) are whole connected components
//   dropped between collapses: removals[j] applies after records[0 .. removals[j].record_index) and
//   deletes every face that has a corner in removed_points[first_point .. first_point + point_count)
//   (all points of the component, ascending); those points disappear.
//   Level i's mesh is the input after records[0 .. levels[i].collapse_count) interleaved with
//   removals[0 .. levels[i].removal_count); for a level with is_refined (SimplifyOptions::
//   refine_late_levels) the faces are those, the positions of its interior vertices differ.

#include <cstdint>
#include <vector>

#include "lodbake/core/diagnostics.h"
#include "lodbake/core/lod_policy.h"
#include "lodbake/core/mapped_array.h"
#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"
#include "lodbake/simplify/mesh_distance.h"
#include "lodbake/simplify/simplify.h"

namespace lodbake {

struct CollapseRecord {
    uint32_t removed_point = 0;
    uint32_t kept_point = 0;
    Vec3f position;
    uint32_t first_wedge_update = 0;
    uint32_t wedge_update_count = 0;
};

struct WedgeUpdate {
    uint32_t removed_wedge = 0;
    uint32_t kept_wedge = 0;
};

struct ComponentRemoval {
    uint32_t record_index = 0; // collapses applied before this removal
    uint32_t first_point = 0;  // range of CollapseSequence::removed_points
    uint32_t point_count = 0;
};

struct CollapseSequence {
    std::vector<Vec3f> point_positions;  // initial position of every point
    std::vector<uint32_t> wedge_point;   // point of every wedge
    std::vector<CollapseRecord> records; // in execution order
    std::vector<WedgeUpdate> wedge_updates;
    uint32_t attribute_stride = 0; // floats per wedge update in wedge_attributes
    std::vector<float> wedge_attributes;
    std::vector<ComponentRemoval> removals; // in execution order; empty unless remove_covered_components
    std::vector<uint32_t> removed_points;
    // Half-edge sequences only (placement KeepEndpoint), for the PFRep builder, which then needs no
    // replay of its own (pfrep_builder.h):
    //   point_triangles    3 points per face the simplifier starts from (input order, faces with a
    //                      repeated point dropped: pointTriangles() of the input);
    //   created_triangles  3 points per triangle a record re-creates (each face of removed_point
    //                      without kept_point, removed_point replaced by kept_point, corner order
    //                      kept), record after record; within a record in the order of the triangles
    //                      they replace, oldest first (input triangles by index, then re-created ones
    //                      in creation order);
    //   created_end        per record, the end of its range of created_triangles, in triangles.
    // All three are empty for other sequences.
    std::vector<uint32_t> point_triangles;
    std::vector<uint32_t> created_triangles;
    std::vector<uint32_t> created_end;
};

/// The chain's collapses read as vertex removals (LodChainOptions::record_removals), for the PFRep
/// builder (pfrep_builder.h, buildPfrepFromChain). A full-edge collapse (a, b) -> p is, topologically,
/// the half-edge collapse that removes one end into the other: same link condition, same faces die,
/// the others are re-created with the removed point replaced. Each entry is (removed point, kept
/// point) in execution order, as the engine names them: point ids are CollapseSequence point ids
/// (the input's distinct positions, bit-identical positions welded, numbered in order of first use
/// by the faces that are not degenerate by position), and after a collapse the merged point carries
/// the kept id; `kept_stays` says the kept point did not move (a corner, a border or seam point whose
/// edge leaves its line, or a collapse whose optimum is the kept end). Stored as a byte stream (about
/// 4.5 bytes per collapse instead of 8): per entry, the removed point, then the zigzag difference
/// kept - removed times 2 plus kept_stays, each as an LEB128 varint (ids below 2^30).
class CollapsePairLog {
public:
    void add(uint32_t removed, uint32_t kept, bool kept_stays = false) {
        putVarint(removed);
        const int64_t d = int64_t(kept) - int64_t(removed);
        putVarint(uint64_t(d < 0 ? ((-d) << 1) - 1 : d << 1) << 1 | uint64_t(kept_stays));
        ++count_;
    }
    /// Appends `other`'s entries after this log's (entries are self-contained, so the bytes concatenate).
    void append(const CollapsePairLog& other) {
        bytes_.insert(bytes_.end(), other.bytes_.begin(), other.bytes_.end());
        count_ += other.count_;
    }
    size_t size() const { return count_; }
    bool empty() const { return count_ == 0; }
    size_t byteSize() const { return bytes_.size(); }
    /// Room for `entries` entries of the largest size (11 bytes), so the stream never grows by copying.
    /// A large stream is mapped on its own with ordinary pages (core/mapped_array.h): the pages not yet
    /// written are not resident, and the reservation takes no room in malloc's heap.
    void reserve(size_t entries) { bytes_.reserve(entries * 11); }
    void clear() {
        Bytes().swap(bytes_);
        count_ = 0;
    }
    /// Sequential reader: next() gives the entries in order; false once past the last (or on a
    /// malformed stream).
    class Reader {
    public:
        explicit Reader(const CollapsePairLog& log) : p_(log.bytes_.data()), end_(log.bytes_.data() + log.bytes_.size()) {}
        bool next(uint32_t& removed, uint32_t& kept) {
            bool stays = false;
            return next(removed, kept, stays);
        }
        bool next(uint32_t& removed, uint32_t& kept, bool& kept_stays) {
            uint64_t r = 0, f = 0;
            if (!getVarint(r) || !getVarint(f) || r > 0xffffffffu) return false;
            removed = uint32_t(r);
            kept_stays = f & 1;
            const uint64_t z = f >> 1;
            const int64_t d = (z & 1) ? -int64_t((z + 1) >> 1) : int64_t(z >> 1);
            const int64_t k = int64_t(removed) + d;
            if (k < 0 || k > int64_t(0xffffffffu)) return false;
            kept = uint32_t(k);
            return true;
        }

    private:
        bool getVarint(uint64_t& v) {
            v = 0;
            for (uint32_t shift = 0; shift < 42 && p_ < end_; shift += 7) {
                const uint8_t b = *p_++;
                v |= uint64_t(b & 0x7f) << shift;
                if (!(b & 0x80)) return true;
            }
            return false;
        }
        const uint8_t* p_;
        const uint8_t* end_;
    };

private:
    void putVarint(uint64_t v) {
        while (v >= 0x80) {
            bytes_.push_back(uint8_t(v | 0x80));
            v >>= 7;
        }
        bytes_.push_back(uint8_t(v));
    }
    using Bytes = detail::MappedArray<uint8_t, detail::MappedPages::Small>;
    Bytes bytes_;
    size_t count_ = 0;
};

struct LodChainOptions {
    std::vector<double> ratios{0.5, 0.25, 0.1, 0.03, 0.01}; // per level, fraction of input triangles
    SimplifyOptions simplify;                               // validity rules and weights (its targets are ignored)
    bool measure_error = true; // measure each level against the input with measureSurfaceDistance
    DistanceOptions distance;
    ScreenParams screen;
    bool record_collapses = true; // fill LodChain::sequence
    // Fill LodChain::removals, and run the collapses on past the last level to the end of valid ones
    // (the tail is short: the default chain's last level is 1 % of the input). Ignored (removals left empty)
    // with simplify.remove_covered_components, whose component removals are not vertex removals.
    // With record_collapses the sequence then also holds the tail's records.
    bool record_removals = false;
};

struct LodLevel {
    Mesh mesh;
    double target_ratio = 0;
    size_t collapse_count = 0;   // prefix of the collapse sequence that produced this level
    size_t removal_count = 0;    // prefix of sequence.removals included (remove_covered_components)
    bool is_refined = false;     // refine_late_levels moved its vertices: the sequence's replay gives
                                 // its faces, with the positions before refinement
    double quadric_error = 0;    // largest estimated collapse error so far (object units)
    bool reached_target = false; // false: could not simplify further (see Diagnostics)
    bool has_distance = false;
    DistanceResult distance;    // against the input mesh (when measured)
    double switch_distance = 0; // from this distance on the level is acceptable (object units)
    double screen_coverage = 0; // bounding-sphere diameter / viewport height at switch_distance
};

struct LodChain {
    std::vector<LodLevel> levels; // in order of decreasing detail (ratios sorted descending)
    CollapseSequence sequence;
    // With LodChainOptions::record_removals: every collapse of the pass, the levels' ones
    // (levels[i].collapse_count is a prefix) and then the tail's; removals_complete says the pass ran
    // to the end of valid collapses.
    CollapsePairLog removals;
    bool removals_complete = false;
    double bounding_radius = 0; // input bounding sphere radius (half the box diagonal)
};

/// Builds the chain. Ratios must lie in (0, 1]; duplicates are dropped, the rest sorted in
/// decreasing order. A level that cannot be reached is the smallest valid mesh, with
/// reached_target = false and a note giving the reason; the levels after it (and any level whose
/// mesh would equal the previous one's) are omitted with a note, so no two levels are equal and
/// `levels` may be shorter than the ratios. Fails on invalid input or options.
Result<LodChain> buildLodChain(const Mesh& mesh, const LodChainOptions& options, Diagnostics& diagnostics);

/// Measures every level of `chain` against `mesh` (what buildLodChain does when options.measure_error
/// is set; one level at a time, each in parallel inside, so only one level's BVH and samples exist at
/// once), then derives the switch distances and coverages as updateSwitchDistances does. A level
/// that cannot be measured keeps its quadric estimate, with a warning.
void measureLodChain(const Mesh& mesh, LodChain& chain, const LodChainOptions& options, Diagnostics& diagnostics);

/// measureLodChain with the reference sides of some levels measured beforehand by measureReferenceSides
/// (mesh_distance.h; same mesh, options.distance): `reference_sides[i]`, when present and not null, is
/// level i's. The same results, bit for bit, and the same warnings.
void measureLodChain(const Mesh& mesh, LodChain& chain, const LodChainOptions& options,
                     const std::vector<const OneSidedDistance*>& reference_sides, Diagnostics& diagnostics);

/// Leaves out the levels whose `keep` entry is false (`keep[i]` for levels[i]; missing entries keep);
/// the kept levels, the collapse record and the removal log are unchanged, so a kept level's
/// collapse_count still names its prefix of them. The bake drops levels whose switch distance is not
/// distinct from the next coarser one's (lod_policy.h, distinctLevels) this way.
void keepLevels(LodChain& chain, const std::vector<bool>& keep);

/// Switch distance and screen coverage of every level (the policy of core/lod_policy.h): from its
/// measured Hausdorff error when there is one, else its quadric estimate, made non-decreasing down
/// the chain so selection by distance is monotone.
void updateSwitchDistances(LodChain& chain, const ScreenParams& screen);

} // namespace lodbake
