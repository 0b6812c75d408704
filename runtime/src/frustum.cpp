// Frustum plane extraction and sphere/box classification.
// Gribb & Hartmann 2001, "Fast Extraction of Viewing Frustum Planes from the World-View-Projection
// Matrix": with clip = M v and rows r0..r3 of M, -w <= x <= w gives r3 + r0 >= 0 and r3 - r0 >= 0,
// and so on for y; z gives r3 + r2 (OpenGL, -w <= z) or r2 alone (0 <= z) for the near plane and
// r3 - r2 for the far plane.

#include "lodrt/frustum.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>

#include "memory.h"

namespace lodrt {

namespace {

inline float minf(float a, float b) {
    return a < b ? a : b;
}
inline float maxf(float a, float b) {
    return a > b ? a : b;
}

inline Containment classify(float min_plus, float min_minus) {
    // min_plus = min over planes of (distance + extent), min_minus = min of (distance - extent).
    return min_plus < 0 ? Containment::Outside : (min_minus >= 0 ? Containment::Inside : Containment::Intersecting);
}

// Spreads the low 10 bits of v to every third bit.
uint32_t spreadBits(uint32_t v) {
    v &= 0x3FF;
    v = (v | (v << 16)) & 0x030000FF;
    v = (v | (v << 8)) & 0x0300F00F;
    v = (v | (v << 4)) & 0x030C30C3;
    v = (v | (v << 2)) & 0x09249249;
    return v;
}

} // namespace

bool extractFrustum(const float m[16], ClipDepth depth, Frustum* out) {
    assert(m && out);
    float row[4][4];
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) row[r][c] = m[c * 4 + r];
    Frustum f;
    for (int c = 0; c < 4; ++c) {
        f.planes[0][c] = row[3][c] + row[0][c];                                             // left
        f.planes[1][c] = row[3][c] - row[0][c];                                             // right
        f.planes[2][c] = row[3][c] + row[1][c];                                             // bottom
        f.planes[3][c] = row[3][c] - row[1][c];                                             // top
        f.planes[4][c] = depth == ClipDepth::ZeroToOne ? row[2][c] : row[3][c] + row[2][c]; // near
        f.planes[5][c] = row[3][c] - row[2][c];                                             // far
    }
    for (auto& p : f.planes) {
        const double len = std::sqrt(double(p[0]) * p[0] + double(p[1]) * p[1] + double(p[2]) * p[2]);
        if (!(len > 0) || !std::isfinite(len) || !std::isfinite(p[3])) return false;
        for (float& v : p) v = float(v / len);
    }
    *out = f;
    return true;
}

Containment classifySphere(const Frustum& frustum, const float center[3], float radius) {
    float min_plus = INFINITY, min_minus = INFINITY;
    for (const auto& p : frustum.planes) {
        const float d = p[0] * center[0] + p[1] * center[1] + p[2] * center[2] + p[3];
        min_plus = minf(min_plus, d + radius);
        min_minus = minf(min_minus, d - radius);
    }
    return classify(min_plus, min_minus);
}

Containment classifyBox(const Frustum& frustum, const float box_min[3], const float box_max[3]) {
    float c[3], e[3];
    for (int k = 0; k < 3; ++k) {
        c[k] = 0.5f * (box_min[k] + box_max[k]);
        e[k] = 0.5f * (box_max[k] - box_min[k]);
    }
    float min_plus = INFINITY, min_minus = INFINITY;
    for (const auto& p : frustum.planes) {
        const float d = p[0] * c[0] + p[1] * c[1] + p[2] * c[2] + p[3];
        const float r = std::fabs(p[0]) * e[0] + std::fabs(p[1]) * e[1] + std::fabs(p[2]) * e[2];
        min_plus = minf(min_plus, d + r);
        min_minus = minf(min_minus, d - r);
    }
    return classify(min_plus, min_minus);
}

size_t classifySpheres(const Frustum& frustum, const float* __restrict x, const float* __restrict y,
                       const float* __restrict z, const float* __restrict radius, size_t count,
                       Containment* __restrict out) {
    assert(count == 0 || (x && y && z && radius && out));
    // Planes as scalars so the loop body is straight-line code over lanes of instances.
    float a[6], b[6], c[6], d[6];
    for (int k = 0; k < 6; ++k) {
        a[k] = frustum.planes[k][0];
        b[k] = frustum.planes[k][1];
        c[k] = frustum.planes[k][2];
        d[k] = frustum.planes[k][3];
    }
    uint8_t* codes = reinterpret_cast<uint8_t*>(out);
    size_t visible = 0;
    for (size_t i = 0; i < count; ++i) {
        const float px = x[i], py = y[i], pz = z[i], r = radius[i];
        float m = a[0] * px + b[0] * py + c[0] * pz + d[0];
        m = minf(m, a[1] * px + b[1] * py + c[1] * pz + d[1]);
        m = minf(m, a[2] * px + b[2] * py + c[2] * pz + d[2]);
        m = minf(m, a[3] * px + b[3] * py + c[3] * pz + d[3]);
        m = minf(m, a[4] * px + b[4] * py + c[4] * pz + d[4]);
        m = minf(m, a[5] * px + b[5] * py + c[5] * pz + d[5]);
        const uint8_t is_visible = m + r >= 0 ? 1 : 0;
        const uint8_t is_inside = m - r >= 0 ? 1 : 0;
        codes[i] = uint8_t(is_visible + is_inside);
        visible += is_visible;
    }
    return visible;
}

size_t classifyBoxes(const Frustum& frustum, const float* __restrict min_x, const float* __restrict min_y,
                     const float* __restrict min_z, const float* __restrict max_x, const float* __restrict max_y,
                     const float* __restrict max_z, size_t count, Containment* __restrict out) {
    assert(count == 0 || (min_x && min_y && min_z && max_x && max_y && max_z && out));
    float a[6], b[6], c[6], d[6], aa[6], ab[6], ac[6];
    for (int k = 0; k < 6; ++k) {
        a[k] = frustum.planes[k][0];
        b[k] = frustum.planes[k][1];
        c[k] = frustum.planes[k][2];
        d[k] = frustum.planes[k][3];
        aa[k] = std::fabs(a[k]);
        ab[k] = std::fabs(b[k]);
        ac[k] = std::fabs(c[k]);
    }
    uint8_t* codes = reinterpret_cast<uint8_t*>(out);
    size_t visible = 0;
    for (size_t i = 0; i < count; ++i) {
        const float cx = 0.5f * (min_x[i] + max_x[i]), cy = 0.5f * (min_y[i] + max_y[i]),
                    cz = 0.5f * (min_z[i] + max_z[i]);
        const float ex = 0.5f * (max_x[i] - min_x[i]), ey = 0.5f * (max_y[i] - min_y[i]),
                    ez = 0.5f * (max_z[i] - min_z[i]);
        float min_plus = INFINITY, min_minus = INFINITY;
        for (int k = 0; k < 6; ++k) {
            const float dist = a[k] * cx + b[k] * cy + c[k] * cz + d[k];
            const float r = aa[k] * ex + ab[k] * ey + ac[k] * ez;
            min_plus = minf(min_plus, dist + r);
            min_minus = minf(min_minus, dist - r);
        }
        const uint8_t is_visible = min_plus >= 0 ? 1 : 0;
        const uint8_t is_inside = min_minus >= 0 ? 1 : 0;
        codes[i] = uint8_t(is_visible + is_inside);
        visible += is_visible;
    }
    return visible;
}

// ---- InstanceBvh ----

InstanceBvh::~InstanceBvh() {
    release();
}

InstanceBvh::InstanceBvh(InstanceBvh&& other) noexcept {
    *this = static_cast<InstanceBvh&&>(other);
}

InstanceBvh& InstanceBvh::operator=(InstanceBvh&& other) noexcept {
    if (this == &other) return *this;
    release();
    allocator_ = other.allocator_;
    nodes_ = other.nodes_;
    order_ = other.order_;
    spheres_ = other.spheres_;
    other.spheres_ = nullptr;
    node_count_ = other.node_count_;
    count_ = other.count_;
    other.nodes_ = nullptr;
    other.order_ = nullptr;
    other.node_count_ = 0;
    other.count_ = 0;
    return *this;
}

void InstanceBvh::release() {
    detail::deallocateBytes(allocator_, nodes_);
    detail::deallocateBytes(allocator_, order_);
    detail::deallocateBytes(allocator_, spheres_);
    spheres_ = nullptr;
    nodes_ = nullptr;
    order_ = nullptr;
    node_count_ = 0;
    count_ = 0;
}

Result InstanceBvh::build(const float* x, const float* y, const float* z, const float* radius, size_t count,
                          const Allocator* allocator) {
    release();
    allocator_ = allocator ? *allocator : Allocator();
    if (count == 0) return Result::Ok;
    if (!x || !y || !z || !radius || count >= (size_t(1) << 31)) return Result::InvalidArgument;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < count; ++i) {
        const float p[3] = {x[i], y[i], z[i]};
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]) || !std::isfinite(radius[i]) ||
            radius[i] < 0)
            return Result::InvalidArgument;
        for (int k = 0; k < 3; ++k) {
            lo[k] = minf(lo[k], p[k]);
            hi[k] = maxf(hi[k], p[k]);
        }
    }
    uint64_t* keys = detail::allocateArray<uint64_t>(allocator_, count);
    const size_t leaf_count = (count + kLeafSize - 1) / kLeafSize;
    order_ = detail::allocateArray<uint32_t>(allocator_, count);
    nodes_ = detail::allocateArray<Node>(allocator_, 2 * leaf_count - 1);
    spheres_ = count <= size_t(-1) / 4 ? detail::allocateArray<float>(allocator_, 4 * count) : nullptr;
    if (!keys || !order_ || !nodes_ || !spheres_) {
        detail::deallocateBytes(allocator_, keys);
        release();
        return Result::OutOfMemory;
    }
    float scale[3];
    for (int k = 0; k < 3; ++k) scale[k] = hi[k] > lo[k] ? 1023.0f / (hi[k] - lo[k]) : 0.0f;
    for (size_t i = 0; i < count; ++i) {
        const uint32_t qx = uint32_t((x[i] - lo[0]) * scale[0]), qy = uint32_t((y[i] - lo[1]) * scale[1]),
                       qz = uint32_t((z[i] - lo[2]) * scale[2]);
        const uint32_t code = spreadBits(qx) | (spreadBits(qy) << 1) | (spreadBits(qz) << 2);
        keys[i] = (uint64_t(code) << 32) | uint64_t(i); // ties broken by index: deterministic
    }
    std::sort(keys, keys + count);
    for (size_t i = 0; i < count; ++i) {
        const uint32_t k = uint32_t(keys[i]);
        order_[i] = k;
        spheres_[i] = x[k];
        spheres_[count + i] = y[k];
        spheres_[2 * count + i] = z[k];
        spheres_[3 * count + i] = radius[k];
    }
    detail::deallocateBytes(allocator_, keys);

    // Top-down over leaf ranges with an explicit stack; children are allocated as adjacent pairs.
    struct Pending {
        uint32_t node, leaf_lo, leaf_hi;
    };
    Pending stack[64];
    uint32_t top = 0, next = 1;
    stack[top++] = {0, 0, uint32_t(leaf_count)};
    while (top > 0) {
        const Pending item = stack[--top];
        Node& node = nodes_[item.node];
        if (item.leaf_hi - item.leaf_lo == 1) {
            node.first = item.leaf_lo * kLeafSize;
            node.count = uint32_t(std::min<size_t>(kLeafSize, count - node.first));
            for (int k = 0; k < 3; ++k) {
                node.min[k] = INFINITY;
                node.max[k] = -INFINITY;
            }
            for (uint32_t j = 0; j < node.count; ++j) {
                const uint32_t i = order_[node.first + j];
                const float p[3] = {x[i], y[i], z[i]};
                for (int k = 0; k < 3; ++k) {
                    node.min[k] = minf(node.min[k], p[k] - radius[i]);
                    node.max[k] = maxf(node.max[k], p[k] + radius[i]);
                }
            }
            continue;
        }
        const uint32_t mid = item.leaf_lo + (item.leaf_hi - item.leaf_lo) / 2;
        node.first = next;
        node.count = 0;
        next += 2;
        stack[top++] = {node.first, item.leaf_lo, mid};
        stack[top++] = {node.first + 1, mid, item.leaf_hi};
    }
    node_count_ = next;
    // Internal boxes bottom-up: children always have larger indices than their parent.
    for (uint32_t n = node_count_; n-- > 0;) {
        Node& node = nodes_[n];
        if (node.count > 0) continue;
        const Node& l = nodes_[node.first];
        const Node& r = nodes_[node.first + 1];
        for (int k = 0; k < 3; ++k) {
            node.min[k] = minf(l.min[k], r.min[k]);
            node.max[k] = maxf(l.max[k], r.max[k]);
        }
    }
    count_ = count;
    return Result::Ok;
}

size_t InstanceBvh::cull(const Frustum& frustum, Containment* out) const {
    if (count_ == 0) return 0;
    const float* sx = spheres_;
    const float* sy = spheres_ + count_;
    const float* sz = spheres_ + 2 * count_;
    const float* sr = spheres_ + 3 * count_;
    uint32_t stack[64];
    uint32_t top = 0;
    stack[top++] = 0;
    size_t visible = 0;
    Containment leaf[kLeafSize];
    while (top > 0) {
        const Node& node = nodes_[stack[--top]];
        const Containment c = classifyBox(frustum, node.min, node.max);
        if (c == Containment::Intersecting && node.count == 0) {
            stack[top++] = node.first;
            stack[top++] = node.first + 1;
            continue;
        }
        if (c == Containment::Intersecting) { // a leaf: test its members
            const uint32_t begin = node.first;
            visible += classifySpheres(frustum, sx + begin, sy + begin, sz + begin, sr + begin, node.count, leaf);
            for (uint32_t j = 0; j < node.count; ++j) out[order_[begin + j]] = leaf[j];
            continue;
        }
        // A whole subtree inside or outside: its instances form one range of the Morton order.
        const Node* first_leaf = &node;
        while (first_leaf->count == 0) first_leaf = &nodes_[first_leaf->first];
        const Node* last_leaf = &node;
        while (last_leaf->count == 0) last_leaf = &nodes_[last_leaf->first + 1];
        const uint32_t begin = first_leaf->first, end = last_leaf->first + last_leaf->count;
        for (uint32_t j = begin; j < end; ++j) out[order_[j]] = c;
        if (c == Containment::Inside) visible += end - begin;
    }
    return visible;
}

} // namespace lodrt
