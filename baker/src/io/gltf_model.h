#pragma once
// Internal to the gltf module: building a tinygltf::Model from meshes, shared by the single-mesh
// export (gltf_export.cpp) and the pack writer (gltf_pack_export.cpp).

#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include <tiny_gltf.h>

#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"

namespace lodbake {

class BufferBuilder {
public:
    explicit BufferBuilder(tinygltf::Model& model) : model_(model) {}

    // Appends bytes as a new buffer view (4-byte aligned); returns its index.
    int addView(const void* data, size_t size, int target) {
        while (bytes_.size() % 4 != 0) bytes_.push_back(0);
        tinygltf::BufferView view;
        view.buffer = 0;
        view.byteOffset = bytes_.size();
        view.byteLength = size;
        view.target = target;
        const auto* p = static_cast<const uint8_t*>(data);
        bytes_.insert(bytes_.end(), p, p + size);
        model_.bufferViews.push_back(std::move(view));
        return int(model_.bufferViews.size() - 1);
    }

    // Room for `bytes` in all (an upper bound is fine: capacity never touched costs no memory), so the
    // buffer grows without copying itself.
    void reserve(size_t bytes) { bytes_.reserve(bytes); }

    std::vector<uint8_t> finish() {
        while (bytes_.size() % 4 != 0) bytes_.push_back(0);
        return std::move(bytes_);
    }

private:
    tinygltf::Model& model_;
    std::vector<uint8_t> bytes_;
};

/// Components per element of a glTF accessor type (SCALAR 1 ... MAT4 16); 0 for an unknown type.
inline int componentCount(int type) {
    switch (type) {
    case TINYGLTF_TYPE_SCALAR:
        return 1;
    case TINYGLTF_TYPE_VEC2:
        return 2;
    case TINYGLTF_TYPE_VEC3:
        return 3;
    case TINYGLTF_TYPE_VEC4:
    case TINYGLTF_TYPE_MAT2:
        return 4;
    case TINYGLTF_TYPE_MAT3:
        return 9;
    case TINYGLTF_TYPE_MAT4:
        return 16;
    default:
        return 0;
    }
}

/// Sharing across the meshes of one model: identical encoded images become one glTF texture, and
/// identical materials one material.
struct ModelDedupe {
    std::map<std::vector<uint8_t>, int> textures; // encoded bytes -> texture index
    size_t first_material = 0;                    // materials before this index are never shared
};

/// Appends `mesh` (attribute streams, indices, its images, materials, one primitive per non-empty
/// sub-mesh) to `model`; returns the new mesh's index. `dedupe` may be null (no sharing).
/// `vertex_ranges`, when set, gives each non-empty sub-mesh its own vertices (first, count): its
/// primitive gets attribute accessors over that range only and indices relative to `first` (an
/// index outside the range is an internal error). Null: every primitive shares all vertices.
Result<int> addMeshToModel(tinygltf::Model& model, BufferBuilder& buffer, const Mesh& mesh, ModelDedupe* dedupe,
                           const std::vector<std::pair<uint32_t, uint32_t>>* vertex_ranges = nullptr);

} // namespace lodbake
