// Triangle BVH: binned surface-area-heuristic build (Wald, "On fast construction of SAH-based
// bounding volume hierarchies", 2007) and a best-first-ish nearest-triangle query that prunes nodes
// whose box is no closer than the best triangle so far. Closest point on a triangle after Ericson,
// Real-Time Collision Detection (2005), §5.1.5.

#include "lodbake/core/bvh.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <string>

#include "core/parallel.h"

namespace lodbake {
namespace {

struct Box {
    Vec3f min{std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
              std::numeric_limits<float>::infinity()};
    Vec3f max{-std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
              -std::numeric_limits<float>::infinity()};

    void expand(const Vec3f& p) {
        min = Vec3f(std::min(min.x, p.x), std::min(min.y, p.y), std::min(min.z, p.z));
        max = Vec3f(std::max(max.x, p.x), std::max(max.y, p.y), std::max(max.z, p.z));
    }
    void expand(const Box& b) {
        expand(b.min);
        expand(b.max);
    }
    bool isEmpty() const { return min.x > max.x; }
    // Half the surface area; the factor does not matter for comparing costs.
    double halfArea() const {
        if (isEmpty()) return 0.0;
        double dx = double(max.x) - min.x, dy = double(max.y) - min.y, dz = double(max.z) - min.z;
        return dx * dy + dy * dz + dz * dx;
    }
};

Vec3d closestOnSegment(const Vec3d& p, const Vec3d& a, const Vec3d& b) {
    Vec3d ab = b - a;
    double len_sq = dot(ab, ab);
    if (!(len_sq > 0.0)) return a;
    double t = dot(p - a, ab) / len_sq;
    t = std::min(1.0, std::max(0.0, t));
    return a + ab * t;
}

double distanceSq(const Vec3d& a, const Vec3d& b) {
    Vec3d d = a - b;
    return dot(d, d);
}

// Squared distance from p to the box; 0 inside.
double boxDistanceSq(const Vec3d& p, const Vec3f& bmin, const Vec3f& bmax) {
    double d = 0.0;
    for (int k = 0; k < 3; ++k) {
        double lo = bmin[k], hi = bmax[k], v = p[k];
        double e = v < lo ? lo - v : (v > hi ? v - hi : 0.0);
        d += e * e;
    }
    return d;
}

} // namespace

Vec3d closestPointOnDegenerateTriangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    const Vec3d q0 = closestOnSegment(p, a, b), q1 = closestOnSegment(p, b, c), q2 = closestOnSegment(p, c, a);
    const double d0 = distanceSq(p, q0), d1 = distanceSq(p, q1), d2 = distanceSq(p, q2);
    if (d0 <= d1 && d0 <= d2) return q0;
    return d1 <= d2 ? q1 : q2;
}

// Triangles are partitioned in place as one contiguous record each, so every pass over a range reads
// memory sequentially (indirection through an index array made the build cache-bound).
struct TriangleBvh::Prim {
    Box box;
    Vec3f centroid;
    uint32_t face;
};

struct TriangleBvh::BuildTask {
    uint32_t node; // index of the node this range becomes, in the node array being filled
    uint32_t begin, end;
    uint32_t depth;
    Box box;          // bounds of the triangles in [begin, end)
    Box centroid_box; // bounds of their centroids
};

void TriangleBvh::boundsOf(const std::vector<Prim>& prims, BuildTask& task) {
    task.box = Box();
    task.centroid_box = Box();
    for (uint32_t i = task.begin; i < task.end; ++i) {
        task.box.expand(prims[i].box);
        task.centroid_box.expand(prims[i].centroid);
    }
}

// Builds the subtree for `root` into `nodes` (root.node must already exist there). Ranges of at most
// `defer_count` triangles that still need splitting are appended to `deferred` instead, when given.
void TriangleBvh::buildRange(std::vector<Prim>& prims, const BuildTask& root, const TriangleBvhOptions& options,
                             std::vector<Node>& nodes, uint32_t& depth, uint32_t defer_count,
                             std::vector<BuildTask>* deferred) {
    const uint32_t max_leaf = std::max<uint32_t>(1, options.max_leaf_triangles);
    const uint32_t bin_count = std::min<uint32_t>(64, std::max<uint32_t>(2, options.bin_count));
    struct Bin {
        Box box, centroid_box;
        uint32_t count = 0;
    };
    std::array<Bin, 64> bins;
    std::array<double, 64> right_cost;
    // Past this depth splits are by count only, which bounds the total depth by
    // kSahDepthLimit + log2(triangles) < kMaxDepth.
    constexpr uint32_t kSahDepthLimit = kMaxDepth - 40;

    std::vector<BuildTask> stack{root};
    while (!stack.empty()) {
        BuildTask task = stack.back();
        stack.pop_back();
        depth = std::max(depth, task.depth);
        {
            Node& node = nodes[task.node];
            node.bounds_min = task.box.min;
            node.bounds_max = task.box.max;
        }
        const uint32_t count = task.end - task.begin;
        if (count <= max_leaf) {
            Node& node = nodes[task.node];
            node.first = task.begin;
            node.count = count;
            continue;
        }
        if (deferred && count <= defer_count) {
            deferred->push_back(task);
            continue;
        }

        // Binned SAH along the axis where the centroids spread most.
        const Vec3f ext = task.centroid_box.max - task.centroid_box.min;
        const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
        const float lo = task.centroid_box.min[axis], hi = task.centroid_box.max[axis];
        uint32_t best_split = 0;
        BuildTask left_task{0, task.begin, 0, task.depth + 1, Box(), Box()};
        BuildTask right_task{0, 0, task.end, task.depth + 1, Box(), Box()};
        if (task.depth < kSahDepthLimit && hi > lo) {
            const double scale = double(bin_count) / (double(hi) - lo);
            auto binOf = [&](const Prim& p) {
                return std::min(uint32_t((double(p.centroid[axis]) - lo) * scale), bin_count - 1);
            };
            for (uint32_t b = 0; b < bin_count; ++b) bins[b] = Bin();
            for (uint32_t i = task.begin; i < task.end; ++i) {
                Bin& bin = bins[binOf(prims[i])];
                bin.box.expand(prims[i].box);
                bin.centroid_box.expand(prims[i].centroid);
                bin.count++;
            }
            Box acc;
            uint32_t acc_count = 0;
            for (uint32_t b = bin_count - 1; b > 0; --b) {
                acc.expand(bins[b].box);
                acc_count += bins[b].count;
                right_cost[b] = acc.halfArea() * acc_count;
            }
            acc = Box();
            acc_count = 0;
            double best_cost = std::numeric_limits<double>::infinity();
            for (uint32_t b = 0; b + 1 < bin_count; ++b) {
                acc.expand(bins[b].box);
                acc_count += bins[b].count;
                if (acc_count == 0 || acc_count == count) continue;
                double cost = acc.halfArea() * acc_count + right_cost[b + 1];
                if (cost < best_cost) {
                    best_cost = cost;
                    best_split = b + 1; // bins [0, best_split) go left
                }
            }
            if (best_split > 0) {
                for (uint32_t b = 0; b < bin_count; ++b) {
                    BuildTask& side = b < best_split ? left_task : right_task;
                    side.box.expand(bins[b].box);
                    side.centroid_box.expand(bins[b].centroid_box);
                }
                auto it = std::partition(prims.begin() + task.begin, prims.begin() + task.end,
                                         [&](const Prim& p) { return binOf(p) < best_split; });
                left_task.end = uint32_t(it - prims.begin());
            }
        }
        if (best_split == 0) {
            // All centroids coincide (or the depth limit was hit): split by count, ties broken by
            // triangle index so the tree does not depend on the selection algorithm's internals.
            left_task.end = task.begin + count / 2;
            std::nth_element(prims.begin() + task.begin, prims.begin() + left_task.end, prims.begin() + task.end,
                             [axis](const Prim& a, const Prim& b) {
                                 float ca = a.centroid[axis], cb = b.centroid[axis];
                                 return ca < cb || (ca == cb && a.face < b.face);
                             });
            boundsOf(prims, left_task);
            right_task.begin = left_task.end;
            boundsOf(prims, right_task);
        }
        right_task.begin = left_task.end;

        uint32_t left = uint32_t(nodes.size());
        nodes.emplace_back();
        nodes.emplace_back();
        Node& node = nodes[task.node];
        node.first = left;
        node.count = 0;
        left_task.node = left;
        right_task.node = left + 1;
        stack.push_back(right_task);
        stack.push_back(left_task);
    }
}

Result<TriangleBvh> TriangleBvh::build(const std::vector<Vec3f>& positions, const std::vector<uint32_t>& indices,
                                       const TriangleBvhOptions& options) {
    assert(indices.size() % 3 == 0);
    TriangleBvh bvh;
    const size_t tri_count = indices.size() / 3;
    if (tri_count == 0) return bvh;
    if (tri_count >= std::numeric_limits<uint32_t>::max() / 2) {
        return resourceLimit("triangle BVH: " + std::to_string(tri_count) + " triangles, expected fewer than 2^31");
    }

    std::vector<Prim> prims(tri_count);
    for (size_t t = 0; t < tri_count; ++t) {
        Prim& p = prims[t];
        for (int k = 0; k < 3; ++k) {
            assert(indices[t * 3 + k] < positions.size());
            p.box.expand(positions[indices[t * 3 + k]]);
        }
        p.centroid = (p.box.min + p.box.max) * 0.5f;
        p.face = uint32_t(t);
    }

    // The top of the tree is built on one thread until ranges are small; those subtrees are then
    // built in parallel into their own node arrays and appended in range order. The split rule
    // depends only on the triangle count, so the tree is the same for any thread count.
    const uint32_t defer_count = std::max<uint32_t>(kSubtreeTriangles, uint32_t(tri_count / 64));
    bvh.nodes_.reserve(2 * tri_count / std::max<uint32_t>(1, options.max_leaf_triangles) + 2);
    bvh.nodes_.emplace_back();
    BuildTask root{0, 0, uint32_t(tri_count), 1, Box(), Box()};
    boundsOf(prims, root);
    std::vector<BuildTask> deferred;
    buildRange(prims, root, options, bvh.nodes_, bvh.depth_, defer_count, &deferred);

    struct Subtree {
        std::vector<Node> nodes;
        uint32_t depth = 0;
    };
    std::vector<Subtree> subtrees(deferred.size());
    LODBAKE_RETURN_IF_ERROR(parallelFor(deferred.size(), 1, [&](size_t i) {
        BuildTask local_root = deferred[i];
        local_root.node = 0;
        subtrees[i].nodes.emplace_back();
        // Ranges are disjoint, so each task partitions its own slice of `prims`.
        buildRange(prims, local_root, options, subtrees[i].nodes, subtrees[i].depth, 0, nullptr);
    }));
    for (size_t i = 0; i < deferred.size(); ++i) {
        // Local node 0 replaces the placeholder; local node k >= 1 goes to base + k - 1.
        const std::vector<Node>& local = subtrees[i].nodes;
        const uint32_t base = uint32_t(bvh.nodes_.size());
        auto remap = [&](Node n) {
            if (n.count == 0) n.first = base + n.first - 1;
            return n;
        };
        bvh.nodes_[deferred[i].node] = remap(local[0]);
        for (size_t k = 1; k < local.size(); ++k) bvh.nodes_.push_back(remap(local[k]));
        bvh.depth_ = std::max(bvh.depth_, subtrees[i].depth);
    }
    assert(bvh.depth_ <= kMaxDepth);

    bvh.face_of_slot_.resize(tri_count);
    bvh.corners_.resize(tri_count * 3);
    for (size_t s = 0; s < tri_count; ++s) {
        size_t t = prims[s].face;
        bvh.face_of_slot_[s] = uint32_t(t);
        for (int k = 0; k < 3; ++k) bvh.corners_[s * 3 + k] = positions[indices[t * 3 + k]];
    }
    return bvh;
}

ClosestHit TriangleBvh::closest(const Vec3d& p, double max_distance_sq) const {
    ClosestHit hit;
    hit.distance_sq = max_distance_sq;
    if (nodes_.empty()) return hit;

    struct Entry {
        uint32_t node;
        double distance_sq;
    };
    std::array<Entry, kMaxDepth + 2> stack;
    size_t top = 0;
    stack[top++] = {0, boxDistanceSq(p, nodes_[0].bounds_min, nodes_[0].bounds_max)};

    while (top > 0) {
        const Entry e = stack[--top];
        if (!(e.distance_sq < hit.distance_sq)) continue;
        const Node& node = nodes_[e.node];
        if (node.count > 0) {
            for (uint32_t s = node.first; s < node.first + node.count; ++s) {
                const Vec3f* c = &corners_[size_t(s) * 3];
                Vec3d q = closestPointOnTriangle(p, toDouble(c[0]), toDouble(c[1]), toDouble(c[2]));
                double d = distanceSq(p, q);
                if (d < hit.distance_sq) {
                    hit.distance_sq = d;
                    hit.face = FaceId(face_of_slot_[s]);
                    hit.point = q;
                }
            }
            continue;
        }
        const Node& l = nodes_[node.first];
        const Node& r = nodes_[node.first + 1];
        double dl = boxDistanceSq(p, l.bounds_min, l.bounds_max);
        double dr = boxDistanceSq(p, r.bounds_min, r.bounds_max);
        // Push the farther child first so the nearer one is visited next and tightens the bound.
        Entry near_e{node.first, dl}, far_e{node.first + 1, dr};
        if (dr < dl) std::swap(near_e, far_e);
        if (far_e.distance_sq < hit.distance_sq) stack[top++] = far_e;
        if (near_e.distance_sq < hit.distance_sq) stack[top++] = near_e;
    }
    return hit;
}

} // namespace lodbake
