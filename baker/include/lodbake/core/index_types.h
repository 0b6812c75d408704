#pragma once
// Strong index types (Draco attributes/geometry_indices.h, pmp Handle): a VertexId cannot be passed
// where a FaceId is expected. Raw uint32_t appears only at buffer and API edges.

#include <cstdint>
#include <functional>
#include <limits>

namespace lodbake {

template <class Tag> struct StrongIndex {
    static constexpr uint32_t kInvalidValue = std::numeric_limits<uint32_t>::max();

    uint32_t value = kInvalidValue;

    constexpr StrongIndex() = default;
    constexpr explicit StrongIndex(uint32_t v) : value(v) {}

    static constexpr StrongIndex invalid() { return StrongIndex(); }
    constexpr bool isValid() const { return value != kInvalidValue; }

    constexpr bool operator==(StrongIndex o) const { return value == o.value; }
    constexpr bool operator!=(StrongIndex o) const { return value != o.value; }
    constexpr bool operator<(StrongIndex o) const { return value < o.value; }
    constexpr bool operator<=(StrongIndex o) const { return value <= o.value; }
    constexpr bool operator>(StrongIndex o) const { return value > o.value; }
    constexpr bool operator>=(StrongIndex o) const { return value >= o.value; }
};

struct VertexTag {};
struct FaceTag {};
struct CornerTag {};
struct EdgeTag {};
struct MaterialTag {};

using VertexId = StrongIndex<VertexTag>;     // index into a Mesh's attribute streams
using FaceId = StrongIndex<FaceTag>;         // triangle index: corners 3f, 3f+1, 3f+2
using CornerId = StrongIndex<CornerTag>;     // index into Mesh::indices
using EdgeId = StrongIndex<EdgeTag>;         // index into an edge table built by an algorithm
using MaterialId = StrongIndex<MaterialTag>; // index into Mesh::materials

inline constexpr FaceId faceOf(CornerId c) { return FaceId(c.value / 3); }
inline constexpr CornerId cornerOf(FaceId f, uint32_t k) { return CornerId(f.value * 3 + k); }
inline constexpr CornerId nextCorner(CornerId c) { return CornerId(c.value % 3 == 2 ? c.value - 2 : c.value + 1); }
inline constexpr CornerId prevCorner(CornerId c) { return CornerId(c.value % 3 == 0 ? c.value + 2 : c.value - 1); }

} // namespace lodbake

template <class Tag> struct std::hash<lodbake::StrongIndex<Tag>> {
    size_t operator()(lodbake::StrongIndex<Tag> i) const noexcept { return std::hash<uint32_t>()(i.value); }
};
