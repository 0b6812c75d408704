#include "lodbake/core/mesh.h"

#include <algorithm>
#include <cmath>

namespace lodbake {

void Aabb::expand(const Vec3f& p) {
    if (isEmpty()) {
        min = max = p;
        return;
    }
    min = {std::min(min.x, p.x), std::min(min.y, p.y), std::min(min.z, p.z)};
    max = {std::max(max.x, p.x), std::max(max.y, p.y), std::max(max.z, p.z)};
}

double Aabb::diagonal() const {
    if (isEmpty()) return 0.0;
    return length(toDouble(max) - toDouble(min));
}

Aabb computeBounds(const Mesh& mesh) {
    Aabb box;
    if (mesh.indices.empty()) {
        for (const Vec3f& p : mesh.positions) box.expand(p);
        return box;
    }
    std::vector<uint8_t> seen(mesh.vertexCount(), 0);
    for (uint32_t i : mesh.indices) {
        if (i < seen.size() && !seen[i]) {
            seen[i] = 1;
            box.expand(mesh.positions[i]);
        }
    }
    return box;
}

namespace {

Status checkStream(size_t stream_size, size_t vertex_count, const char* stream, const std::string& name) {
    if (stream_size != 0 && stream_size != vertex_count)
        return internalError(name + ": " + stream + " stream has " + std::to_string(stream_size) +
                             " entries, expected " + std::to_string(vertex_count) + " (one per vertex)");
    return Status();
}

Status checkSlot(const TextureSlot& slot, size_t texture_count, size_t uv_count, const std::string& where) {
    if (!slot.isSet()) return Status();
    if (size_t(slot.texture) >= texture_count)
        return internalError(where + ": texture " + std::to_string(slot.texture) + " out of range (" +
                             std::to_string(texture_count) + " textures)");
    if (slot.texcoord >= std::max<size_t>(uv_count, 1))
        return internalError(where + ": texcoord " + std::to_string(slot.texcoord) + " but the mesh has " +
                             std::to_string(uv_count) + " UV sets");
    return Status();
}

} // namespace

Status checkMeshConsistency(const Mesh& mesh, const std::string& name) {
    const size_t n = mesh.vertexCount();
    LODBAKE_RETURN_IF_ERROR(checkStream(mesh.normals.size(), n, "normal", name));
    LODBAKE_RETURN_IF_ERROR(checkStream(mesh.tangents.size(), n, "tangent", name));
    LODBAKE_RETURN_IF_ERROR(checkStream(mesh.colors.size(), n, "colour", name));
    for (const auto& uv : mesh.uvs) LODBAKE_RETURN_IF_ERROR(checkStream(uv.size() == 0 ? n : uv.size(), n, "UV", name));
    if (mesh.indices.size() % 3 != 0)
        return internalError(name + ": index count " + std::to_string(mesh.indices.size()) + " is not a multiple of 3");
    for (size_t c = 0; c < mesh.indices.size(); ++c)
        if (mesh.indices[c] >= n)
            return internalError(name + ": face " + std::to_string(c / 3) + ": vertex index " +
                                 std::to_string(mesh.indices[c]) + " out of range (" + std::to_string(n) +
                                 " vertices)");
    size_t expected_first = 0;
    for (size_t s = 0; s < mesh.submeshes.size(); ++s) {
        const SubMesh& sm = mesh.submeshes[s];
        const std::string where = name + ": sub-mesh " + std::to_string(s);
        if (sm.first_index != expected_first || sm.index_count % 3 != 0)
            return internalError(where + ": range [" + std::to_string(sm.first_index) + ", +" +
                                 std::to_string(sm.index_count) + ") does not continue the previous one at " +
                                 std::to_string(expected_first) + " in whole triangles");
        if (sm.material.isValid() && sm.material.value >= mesh.materials.size())
            return internalError(where + ": material " + std::to_string(sm.material.value) + " out of range (" +
                                 std::to_string(mesh.materials.size()) + " materials)");
        expected_first += sm.index_count;
    }
    if (!mesh.submeshes.empty() && expected_first != mesh.indices.size())
        return internalError(name + ": sub-meshes cover " + std::to_string(expected_first) + " of " +
                             std::to_string(mesh.indices.size()) + " indices");
    for (size_t m = 0; m < mesh.materials.size(); ++m) {
        const Material& mat = mesh.materials[m];
        const std::string where = name + ": material " + std::to_string(m);
        const size_t t = mesh.textures.size(), u = mesh.uvs.size();
        LODBAKE_RETURN_IF_ERROR(checkSlot(mat.base_color_texture, t, u, where + " base colour"));
        LODBAKE_RETURN_IF_ERROR(checkSlot(mat.metallic_roughness_texture, t, u, where + " metallic-roughness"));
        LODBAKE_RETURN_IF_ERROR(checkSlot(mat.normal_texture, t, u, where + " normal"));
        LODBAKE_RETURN_IF_ERROR(checkSlot(mat.occlusion_texture, t, u, where + " occlusion"));
        LODBAKE_RETURN_IF_ERROR(checkSlot(mat.emissive_texture, t, u, where + " emissive"));
    }
    return Status();
}

size_t countRepeatedIndexFaces(const Mesh& mesh) {
    size_t n = 0;
    for (size_t f = 0; f < mesh.faceCount(); ++f) {
        const uint32_t* t = &mesh.indices[f * 3];
        n += t[0] == t[1] || t[1] == t[2] || t[0] == t[2];
    }
    return n;
}

size_t countUnreferencedVertices(const Mesh& mesh) {
    std::vector<uint8_t> used(mesh.vertexCount(), 0);
    for (uint32_t i : mesh.indices)
        if (i < used.size()) used[i] = 1;
    return size_t(std::count(used.begin(), used.end(), uint8_t(0)));
}

namespace {

template <class T> void appendStream(std::vector<T>& dst, const std::vector<T>& src, size_t dst_n, size_t src_n) {
    if (dst.empty() && src.empty()) return;
    dst.resize(dst_n, T());
    if (src.empty())
        dst.resize(dst_n + src_n, T());
    else
        dst.insert(dst.end(), src.begin(), src.end());
}

void remapSlot(TextureSlot& slot, int32_t offset) {
    if (slot.isSet()) slot.texture += offset;
}

} // namespace

void appendMesh(Mesh& mesh, const Mesh& other) {
    const size_t n0 = mesh.vertexCount(), n1 = other.vertexCount();
    const uint32_t base = uint32_t(n0);
    const size_t first_index = mesh.indices.size();
    const uint32_t material_base = uint32_t(mesh.materials.size());
    const int32_t texture_base = int32_t(mesh.textures.size());

    // A mesh with triangles but no sub-meshes is one implicit range: make it explicit before appending.
    if (mesh.submeshes.empty() && !mesh.indices.empty()) mesh.submeshes.push_back({"", 0, uint32_t(first_index), {}});

    appendStream(mesh.normals, other.normals, n0, n1);
    appendStream(mesh.tangents, other.tangents, n0, n1);
    appendStream(mesh.colors, other.colors, n0, n1);
    const size_t uv_sets = std::max(mesh.uvs.size(), other.uvs.size());
    mesh.uvs.resize(uv_sets);
    for (size_t s = 0; s < uv_sets; ++s) {
        static const std::vector<Vec2f> kNone;
        appendStream(mesh.uvs[s], s < other.uvs.size() ? other.uvs[s] : kNone, n0, n1);
        if (!mesh.uvs[s].empty()) mesh.uvs[s].resize(n0 + n1);
    }
    mesh.positions.insert(mesh.positions.end(), other.positions.begin(), other.positions.end());
    for (uint32_t i : other.indices) mesh.indices.push_back(i + base);

    if (other.submeshes.empty()) {
        if (!other.indices.empty())
            mesh.submeshes.push_back({"", uint32_t(first_index), uint32_t(other.indices.size()), {}});
    } else {
        for (SubMesh sm : other.submeshes) {
            sm.first_index += uint32_t(first_index);
            if (sm.material.isValid()) sm.material = MaterialId(sm.material.value + material_base);
            mesh.submeshes.push_back(sm);
        }
    }
    for (Material m : other.materials) {
        remapSlot(m.base_color_texture, texture_base);
        remapSlot(m.metallic_roughness_texture, texture_base);
        remapSlot(m.normal_texture, texture_base);
        remapSlot(m.occlusion_texture, texture_base);
        remapSlot(m.emissive_texture, texture_base);
        mesh.materials.push_back(std::move(m));
    }
    mesh.textures.insert(mesh.textures.end(), other.textures.begin(), other.textures.end());
}

} // namespace lodbake
