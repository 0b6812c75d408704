#pragma once
// The baker's mesh: an indexed triangle list with separate (structure-of-arrays) attribute streams,
// sub-meshes with material ids, and the materials and textures they reference.
//
// Connectivity (indices) and geometry (streams) are kept apart so an algorithm can take only what it
// needs (STYLE.md §2). Every non-empty stream has exactly vertexCount() entries.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/core/index_types.h"
#include "lodbake/core/math.h"
#include "lodbake/core/status.h"

namespace lodbake {

/// An image used by materials. Either the encoded bytes are held (embedded in a GLB, or read from
/// disk by a reader) or only the URI is known.
struct Texture {
    std::string name;
    std::string uri;             // as written in the source (OBJ map_Kd, glTF image uri); may be empty
    std::string mime_type;       // "image/png", "image/jpeg", ... (empty if unknown)
    std::vector<uint8_t> bytes;  // encoded image file contents
    bool is_verbatim = false;    // written as these bytes even when they are no PNG or JPEG (the bake's
                                 // keep_unreadable_images); otherwise writers drop undecodable images
};

/// A material slot's texture reference.
struct TextureSlot {
    int32_t texture = -1; // index into Mesh::textures, -1 for none
    uint32_t texcoord = 0; // which UV set (Mesh::uvs index) it samples
    bool isSet() const { return texture >= 0; }
};

enum class AlphaMode { Opaque, Mask, Blend };

/// A metallic-roughness PBR material, the glTF 2.0 model; OBJ/MTL maps onto it.
struct Material {
    std::string name;
    Vec4f base_color_factor{1.0f, 1.0f, 1.0f, 1.0f}; // linear RGBA
    float metallic_factor = 1.0f;
    float roughness_factor = 1.0f;
    Vec3f emissive_factor{0.0f, 0.0f, 0.0f};
    TextureSlot base_color_texture;
    TextureSlot metallic_roughness_texture;
    TextureSlot normal_texture;
    float normal_scale = 1.0f;
    TextureSlot occlusion_texture;
    float occlusion_strength = 1.0f;
    TextureSlot emissive_texture;
    AlphaMode alpha_mode = AlphaMode::Opaque;
    float alpha_cutoff = 0.5f;
    bool is_double_sided = false;
};

/// A contiguous range of Mesh::indices drawn with one material.
struct SubMesh {
    std::string name;
    uint32_t first_index = 0;               // multiple of 3
    uint32_t index_count = 0;               // multiple of 3
    MaterialId material = MaterialId::invalid(); // invalid: no material (viewer default)
};

struct Mesh {
    std::vector<Vec3f> positions;          // defines vertexCount()
    std::vector<Vec3f> normals;            // empty, or unit vectors per vertex
    std::vector<Vec4f> tangents;           // empty, or xyz unit tangent + w handedness (+1/-1)
    std::vector<std::vector<Vec2f>> uvs;   // UV sets; glTF convention: (0,0) is the image's top-left
    std::vector<Vec4f> colors;             // empty, or linear RGBA in [0,1]
    std::vector<uint32_t> indices;         // 3 per triangle, counter-clockwise is the front face
    std::vector<SubMesh> submeshes;        // cover `indices` in order; empty means one range, no material
    std::vector<Material> materials;
    std::vector<Texture> textures;

    size_t vertexCount() const { return positions.size(); }
    size_t faceCount() const { return indices.size() / 3; }
    bool hasNormals() const { return !normals.empty(); }
    bool hasColors() const { return !colors.empty(); }
    bool hasTangents() const { return !tangents.empty(); }

    VertexId corner(CornerId c) const { return VertexId(indices[c.value]); }
    std::array<VertexId, 3> triangle(FaceId f) const {
        const uint32_t* t = &indices[size_t(f.value) * 3];
        return {VertexId(t[0]), VertexId(t[1]), VertexId(t[2])};
    }
    const Vec3f& position(VertexId v) const { return positions[v.value]; }
};

/// A read-only view of an array another object owns (C++17 has no std::span).
template <class T>
class ArrayView {
public:
    ArrayView() = default;
    ArrayView(const T* data, size_t size) : data_(data), size_(size) {}
    ArrayView(const std::vector<T>& v) : data_(v.data()), size_(v.size()) {} // NOLINT: implicit by design

    const T* data() const { return data_; }
    size_t size() const { return size_; }
    bool empty() const { return size_ == 0; }
    const T& operator[](size_t i) const { return data_[i]; }
    const T* begin() const { return data_; }
    const T* end() const { return data_ + size_; }

private:
    const T* data_ = nullptr;
    size_t size_ = 0;
};

/// A mesh's geometry lent without a copy: its positions and triangles, pointing into the arrays of a
/// Mesh that outlives the view. A stage that reads only the geometry takes a MeshView, so LOD0 can
/// be read by it while other tasks read the same Mesh, and nothing is moved out or copied.
struct MeshView {
    ArrayView<Vec3f> positions;  // defines vertexCount()
    ArrayView<uint32_t> indices; // 3 per triangle

    MeshView() = default;
    MeshView(ArrayView<Vec3f> p, ArrayView<uint32_t> i) : positions(p), indices(i) {}
    MeshView(const Mesh& mesh) : positions(mesh.positions), indices(mesh.indices) {} // NOLINT: implicit by design

    size_t vertexCount() const { return positions.size(); }
    size_t faceCount() const { return indices.size() / 3; }
};

/// Axis-aligned bounding box. Empty (min > max) when built from no points.
struct Aabb {
    Vec3f min{1.0f, 1.0f, 1.0f};
    Vec3f max{-1.0f, -1.0f, -1.0f};

    bool isEmpty() const { return min.x > max.x; }
    void expand(const Vec3f& p);
    Vec3f center() const { return (min + max) * 0.5f; }
    Vec3f extent() const { return max - min; }
    double diagonal() const; // 0 for an empty box
};

/// Bounds of the vertices referenced by at least one triangle (unreferenced strays do not count),
/// or of all vertices when the mesh has no triangles.
Aabb computeBounds(const Mesh& mesh);

/// Checks the mesh's internal consistency: stream sizes match vertexCount(), index count is a
/// multiple of 3, indices in range, sub-meshes cover `indices` in order with valid materials,
/// material texture slots in range. `name` prefixes the message. Does not judge geometry quality.
Status checkMeshConsistency(const Mesh& mesh, const std::string& name);

/// Number of triangles whose three indices are not all distinct.
size_t countRepeatedIndexFaces(const Mesh& mesh);

/// Number of vertices no triangle references.
size_t countUnreferencedVertices(const Mesh& mesh);

/// Appends `other` (its vertices, triangles, sub-meshes, materials and textures) to `mesh`.
/// UV sets present in only one side are filled with zeros; absent normals/colours likewise.
void appendMesh(Mesh& mesh, const Mesh& other);

} // namespace lodbake
