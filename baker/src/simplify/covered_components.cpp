// Removal of covered components (SimplifyOptions::remove_covered_components): a connected
// component whose every point lies within the error the simplification already accepts of the
// rest of the surface adds at most that error when it goes, and its faces are then spent on the
// rest. Merged range scans are the case: overlapping sheets of the same surface, registered to
// within a fraction of a millimetre, where keeping every small sheet (the link condition keeps
// every component) costs triangles that a coarse level needs elsewhere (docs/simplify.md).
#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>
#include <vector>

#include "lodbake/core/bvh.h"
#include "simplify/edge_collapse.h"

namespace lodbake::detail {

struct Box {
    Vec3d lo{HUGE_VAL, HUGE_VAL, HUGE_VAL};
    Vec3d hi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    void add(const Vec3d& p) {
        lo = Vec3d(std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z));
        hi = Vec3d(std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z));
    }
};

namespace {

double gap(double a_lo, double a_hi, double b_lo, double b_hi) {
    return std::max(0.0, std::max(a_lo - b_hi, b_lo - a_hi));
}

// Squared distance between two boxes (0 when they overlap).
double boxDistance2(const Box& a, const Box& b) {
    const double x = gap(a.lo.x, a.hi.x, b.lo.x, b.hi.x);
    const double y = gap(a.lo.y, a.hi.y, b.lo.y, b.hi.y);
    const double z = gap(a.lo.z, a.hi.z, b.lo.z, b.hi.z);
    return x * x + y * y + z * z;
}

double pointBoxDistance2(const Vec3d& p, const Box& b) {
    const double x = gap(p.x, p.x, b.lo.x, b.hi.x);
    const double y = gap(p.y, p.y, b.lo.y, b.hi.y);
    const double z = gap(p.z, p.z, b.lo.z, b.hi.z);
    return x * x + y * y + z * z;
}

} // namespace

// Connected components of the alive faces (joined across twinned edges, numbered by their first
// face), each with its bounds, whether it has a locked point, and a BVH of its faces.
struct EdgeCollapser::Components {
    std::vector<uint32_t> face_component;
    std::vector<uint32_t> first{0}; // faces of component c: faces[first[c] .. first[c + 1])
    std::vector<uint32_t> faces;
    std::vector<Box> box;
    std::vector<uint8_t> locked;
    std::vector<TriangleBvh> bvh;
    uint32_t count() const { return uint32_t(first.size() - 1); }
};

bool EdgeCollapser::findComponents(Components& set) const {
    const uint32_t face_count = uint32_t(he_.size() / 3);
    set.face_component.assign(face_count, kNone);
    set.faces.reserve(alive_faces_);
    for (uint32_t f = 0; f < face_count; ++f) {
        if (he_[f * 3].point == kNone || set.face_component[f] != kNone) continue;
        const uint32_t c = set.count();
        size_t head = set.faces.size();
        set.face_component[f] = c;
        set.faces.push_back(f);
        while (head < set.faces.size()) {
            const uint32_t g = set.faces[head++];
            for (uint32_t k = 0; k < 3; ++k) {
                const uint32_t t = he_[g * 3 + k].twin;
                if (t == kNone || set.face_component[t / 3] != kNone) continue;
                set.face_component[t / 3] = c;
                set.faces.push_back(t / 3);
            }
        }
        set.first.push_back(uint32_t(set.faces.size()));
    }
    const uint32_t component_count = set.count();
    if (component_count < 2) return false;
    std::vector<Vec3f> positions(position_.begin(), position_.end());
    set.box.assign(component_count, Box());
    set.locked.assign(component_count, 0);
    set.bvh.resize(component_count);
    std::vector<uint32_t> indices;
    for (uint32_t c = 0; c < component_count; ++c) {
        indices.clear();
        for (uint32_t i = set.first[c]; i < set.first[c + 1]; ++i) {
            const uint32_t f = set.faces[i];
            for (uint32_t k = 0; k < 3; ++k) {
                const uint32_t p = he_[f * 3 + k].point;
                indices.push_back(p);
                set.box[c].add(Vec3d(position_[p]));
                if (kind_[p] == kLocked) set.locked[c] = 1;
            }
        }
        Result<TriangleBvh> built = TriangleBvh::build(positions, indices);
        if (!built.ok()) return false; // out of resources: go on without
        set.bvh[c] = std::move(built).value();
    }
    return true;
}

void EdgeCollapser::markCoveredBorders(std::vector<uint8_t>& covered) const {
    covered.assign(he_.size(), 0);
    Components set;
    if (!findComponents(set)) return;
    for (uint32_t h = 0; h < uint32_t(he_.size()); ++h) {
        if (he_[h].twin != kNone) continue;
        const uint32_t a = he_[h].point, b = he_[nextHe(h)].point;
        if (kind_[a] == kLocked || kind_[b] == kLocked) continue;
        const Vec3d pa(position_[a]), pb(position_[b]);
        const double len2 = dot(pb - pa, pb - pa);
        const uint32_t own = set.face_component[h / 3];
        // Covered when both ends and the midpoint lie within the edge's length of another component.
        bool all = true;
        for (const Vec3d& s : {pa, pb, (pa + pb) * 0.5}) {
            bool found = false;
            for (uint32_t d = 0; d < set.count() && !found; ++d) {
                if (d == own || pointBoxDistance2(s, set.box[d]) >= len2) continue;
                found = set.bvh[d].closest(s, len2).isFound();
            }
            all = all && found;
            if (!all) break;
        }
        covered[h] = all ? 1 : 0;
    }
}

void EdgeCollapser::removeCoveredComponents(double tolerance, CollapseSequence* sequence) {
    if (!(tolerance > 0.0)) return;
    Components set;
    if (!findComponents(set)) return;
    const uint32_t component_count = set.count();
    const std::vector<uint32_t>& component_first = set.first;
    const std::vector<uint32_t>& component_faces = set.faces;
    const std::vector<Box>& box = set.box;
    const std::vector<uint8_t>& locked = set.locked;
    const std::vector<TriangleBvh>& bvh = set.bvh;

    // Smallest components first (ties: first face); a removed component is no longer "the rest".
    std::vector<uint32_t> order(component_count);
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
        return component_first[a + 1] - component_first[a] < component_first[b + 1] - component_first[b];
    });
    const double tolerance2 = tolerance * tolerance;
    std::vector<uint8_t> removed(component_count, 0);
    std::vector<uint32_t> stamp(position_.size(), kNone);
    std::vector<uint32_t> neighbours, points;
    for (uint32_t c : order) {
        if (locked[c]) continue;
        neighbours.clear();
        for (uint32_t d = 0; d < component_count; ++d)
            if (d != c && !removed[d] && boxDistance2(box[c], box[d]) < tolerance2) neighbours.push_back(d);
        if (neighbours.empty()) continue;
        size_t last = 0; // the neighbour that covered the previous sample is tried first
        auto covered = [&](const Vec3d& s) {
            for (size_t n = 0; n < neighbours.size(); ++n) {
                const size_t j = (last + n) % neighbours.size();
                const uint32_t d = neighbours[j];
                if (pointBoxDistance2(s, box[d]) >= tolerance2) continue;
                if (bvh[d].closest(s, tolerance2).isFound()) {
                    last = j;
                    return true;
                }
            }
            return false;
        };
        // Samples: every point, the input point it stands for (far_), every face centroid.
        bool all = true;
        points.clear();
        for (uint32_t i = component_first[c]; i < component_first[c + 1] && all; ++i) {
            const uint32_t f = component_faces[i];
            Vec3d centroid;
            for (uint32_t k = 0; k < 3; ++k) {
                const uint32_t p = he_[f * 3 + k].point;
                centroid += Vec3d(position_[p]) * (1.0 / 3.0);
                if (stamp[p] == c) continue;
                stamp[p] = c;
                points.push_back(p);
                all = covered(Vec3d(position_[p])) && (!has_penalty_ || covered(Vec3d(far_[p])));
                if (!all) break;
            }
            all = all && covered(centroid);
        }
        if (!all) continue;

        removed[c] = 1;
        const uint32_t begin = component_first[c], end = component_first[c + 1];
        for (uint32_t i = begin; i < end; ++i)
            for (uint32_t k = 0; k < 3; ++k) queue_.remove(canonical(component_faces[i] * 3 + k));
        for (uint32_t i = begin; i < end; ++i) {
            const uint32_t f = component_faces[i];
            if (uv_channel_ != kNone && --chart_alive_[face_chart_[f]] == 0) ++dropped_charts_;
            for (uint32_t k = 0; k < 3; ++k) {
                he_[f * 3 + k].point = kNone;
                he_[f * 3 + k].twin = kNone;
            }
            --alive_faces_;
        }
        std::sort(points.begin(), points.end());
        for (uint32_t p : points) {
            kind_[p] = kDead;
            point_he_[p] = kNone;
        }
        if (sequence) {
            ComponentRemoval removal;
            removal.record_index = uint32_t(sequence->records.size());
            removal.first_point = uint32_t(sequence->removed_points.size());
            removal.point_count = uint32_t(points.size());
            sequence->removals.push_back(removal);
            sequence->removed_points.insert(sequence->removed_points.end(), points.begin(), points.end());
        }
        ++removals_;
        removed_faces_ += end - begin;
    }
}

} // namespace lodbake::detail
