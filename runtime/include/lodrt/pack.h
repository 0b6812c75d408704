#pragma once
// Pack summary: loads a glTF 2.0 document (GLB or plain JSON) from caller bytes, validates the parts
// every later runtime stage relies on (indices in range, accessors and buffer views inside the bytes
// that exist), and exposes meshes -> primitives -> attribute accessors. Each summarised object keeps
// its JsonValue so extensions (LODBAKE_*, MSFT_lod) can be read from the same document.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "lodrt/allocator.h"
#include "lodrt/export.h"
#include "lodrt/glb.h"
#include "lodrt/json.h"
#include "lodrt/result.h"

namespace lodrt {

constexpr uint32_t kNoIndex = 0xFFFFFFFFu;

/// Zero-initialised means defaults.
struct LoadOptions {
    Allocator allocator;           // all memory of the Pack and of its JSON document
    JsonLimits json_limits;        // limits for the JSON chunk
    bool skip_index_check = false; // do not scan index buffers for values >= vertex count
};

/// glTF accessor.componentType codes.
enum class ComponentType : uint32_t {
    Byte = 5120,
    UnsignedByte = 5121,
    Short = 5122,
    UnsignedShort = 5123,
    UnsignedInt = 5125,
    Float = 5126,
};

enum class AccessorType : uint8_t { Scalar, Vec2, Vec3, Vec4, Mat2, Mat3, Mat4 };

/// Bytes of one component, 0 for unknown codes.
LODRT_API uint32_t componentSize(ComponentType type);
/// Components per element (SCALAR 1 ... MAT4 16).
LODRT_API uint32_t componentCount(AccessorType type);
/// glTF spelling: "SCALAR", "VEC3", ...
LODRT_API const char* accessorTypeName(AccessorType type);
/// glTF-ish spelling: "u8", "u16", "u32", "i8", "i16", "f32"; "?" for unknown codes.
LODRT_API const char* componentTypeName(ComponentType type);

struct BufferInfo {
    uint64_t byte_length = 0;
    bool is_glb_bin = false; // the data is the GLB BIN chunk (the only bytes lodrt can see)
    bool has_uri = false;    // external or data: URI; lodrt does no IO, so its bytes are unavailable
    bool is_fallback = false; // no uri and no bytes: only EXT_meshopt_compression views may use it (lodrt/meshopt.h)
    JsonValue json;
};

struct BufferViewInfo {
    uint32_t buffer = 0;
    uint64_t byte_offset = 0;
    uint64_t byte_length = 0;
    uint32_t byte_stride = 0; // 0 when tightly packed
    JsonValue json;
};

struct AccessorInfo {
    uint32_t buffer_view = kNoIndex; // kNoIndex: all zeros (or supplied by sparse / an extension)
    uint64_t byte_offset = 0;
    uint64_t count = 0;
    ComponentType component_type = ComponentType::Float;
    AccessorType type = AccessorType::Scalar;
    bool normalized = false;
    bool is_sparse = false;
    uint32_t element_size = 0; // bytes of one element, without stride padding
    uint64_t byte_length = 0;  // count * element_size: the data this accessor represents
    JsonValue json;
};

struct AttributeInfo {
    std::string_view name; // "POSITION", "TEXCOORD_0", ...
    uint32_t accessor = 0;
};

struct PrimitiveInfo {
    uint32_t mode = 4;           // glTF primitive mode; 4 = TRIANGLES
    uint32_t indices = kNoIndex; // accessor index, or kNoIndex for non-indexed
    uint32_t material = kNoIndex;
    uint64_t vertex_count = 0;    // count of the attribute accessors (all equal)
    uint64_t index_count = 0;     // indices count, or vertex_count when non-indexed
    uint64_t triangle_count = 0;  // 0 for point and line modes
    uint32_t first_attribute = 0; // into Pack::attribute()
    uint32_t attribute_count = 0;
    JsonValue json;
};

struct MeshInfo {
    std::string_view name;
    uint32_t first_primitive = 0; // into Pack::primitive()
    uint32_t primitive_count = 0;
    JsonValue json;
};

struct NodeInfo {
    std::string_view name;
    uint32_t mesh = kNoIndex;
    uint32_t parent = kNoIndex;
    JsonValue json;
};

/// A non-fatal finding, e.g. an unknown required extension or a non-triangle primitive.
struct PackWarning {
    const char* pointer; // JSON pointer of the element, e.g. "/meshes/0/primitives/1/mode"
    const char* message; // what was found
};

/// The loaded summary. Move-only; owns its JSON document and arrays (allocated through
/// LoadOptions::allocator) but not the input bytes, which must outlive it (bin() points into them).
class LODRT_API Pack {
public:
    Pack() = default;
    ~Pack();
    Pack(Pack&& other) noexcept;
    Pack& operator=(Pack&& other) noexcept;
    Pack(const Pack&) = delete;
    Pack& operator=(const Pack&) = delete;

    /// The parsed glTF JSON; an empty document when nothing is loaded. JsonValues taken from it stay
    /// valid until the Pack is destroyed or reloaded (moving the Pack keeps them valid).
    const JsonDocument& document() const;
    const GlbView& container() const { return container_; }

    uint32_t bufferCount() const { return buffer_count_; }
    uint32_t bufferViewCount() const { return buffer_view_count_; }
    uint32_t accessorCount() const { return accessor_count_; }
    uint32_t meshCount() const { return mesh_count_; }
    uint32_t primitiveCount() const { return primitive_count_; }
    uint32_t attributeCount() const { return attribute_count_; }
    uint32_t nodeCount() const { return node_count_; }
    uint32_t materialCount() const { return material_count_; }
    uint32_t warningCount() const { return warning_count_; }

    /// Element access; i must be below the matching count (asserted).
    const BufferInfo& buffer(uint32_t i) const;
    const BufferViewInfo& bufferView(uint32_t i) const;
    const AccessorInfo& accessor(uint32_t i) const;
    const MeshInfo& mesh(uint32_t i) const;
    const PrimitiveInfo& primitive(uint32_t i) const;
    const AttributeInfo& attribute(uint32_t i) const;
    const NodeInfo& node(uint32_t i) const;
    const PackWarning& warning(uint32_t i) const;

private:
    friend struct PackLoader;
    void release();
    void resetFields();
    Allocator allocator_;
    JsonDocument* document_ = nullptr; // separate allocation so JsonValues survive moving the Pack
    GlbView container_;
    BufferInfo* buffers_ = nullptr;
    BufferViewInfo* buffer_views_ = nullptr;
    AccessorInfo* accessors_ = nullptr;
    MeshInfo* meshes_ = nullptr;
    PrimitiveInfo* primitives_ = nullptr;
    AttributeInfo* attributes_ = nullptr;
    NodeInfo* nodes_ = nullptr;
    PackWarning* warnings_ = nullptr;
    char* warning_text_ = nullptr;
    uint32_t buffer_count_ = 0, buffer_view_count_ = 0, accessor_count_ = 0, mesh_count_ = 0;
    uint32_t primitive_count_ = 0, attribute_count_ = 0, node_count_ = 0, material_count_ = 0;
    uint32_t warning_count_ = 0;
};

/// At most this many warnings are kept; later ones are counted in the last one's message.
constexpr uint32_t kMaxPackWarnings = 64;

/// Loads a pack from data[0, size) (GLB or plain .gltf JSON). options may be null for defaults.
/// On failure *out is empty and, when error_message is not null, a one-line NUL-terminated message
/// "<json pointer>: <what was expected>" (e.g. "/accessors/3/count: ...") or "<container>: ..." is
/// written into error_message[0, error_message_size), truncated to fit.
/// Returns Ok; the parseGlb and parseJson codes; BadGltf for a broken glTF rule (wrong type, missing
/// required property, index out of range); UnsupportedVersion for asset.version other than 2.x;
/// OutOfBounds when an accessor, buffer view or index value points outside what exists; OutOfMemory;
/// InvalidArgument for a null out or null data with size > 0.
LODRT_API Result loadPack(const uint8_t* data, size_t size, const LoadOptions* options, Pack* out,
                          char* error_message = nullptr, size_t error_message_size = 0);

/// Loads the JSON chunk of a GLB whose BIN chunk is not in memory (range-read streaming, see
/// lodrt/streaming.h): json[0, json_size) is the JSON chunk payload and bin_size the BIN chunk's
/// length from its chunk header (0 when there is none). Everything loadPack validates is validated
/// except index values, whose bytes are not there (the streamer checks them per level on arrival);
/// container().bin is null and container().bin_size is bin_size. Same results as loadPack.
LODRT_API Result loadPackJson(const uint8_t* json, size_t json_size, uint64_t bin_size, const LoadOptions* options,
                              Pack* out, char* error_message = nullptr, size_t error_message_size = 0);

} // namespace lodrt
