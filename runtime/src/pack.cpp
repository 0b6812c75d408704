// glTF 2.0 pack summary and validation (glTF 2.0 specification, sections 3.6 "Binary Data Storage",
// 3.7 "Geometry" and 5 "Properties Reference"). Every count, index and offset is hostile: sizes are
// compared against the bytes that exist before anything is read, with 64-bit arithmetic that cannot
// overflow because every JSON integer is limited to 2^53 and every factor to 64 or less.
#include "lodrt/pack.h"

#include <cassert>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <new>

#include "lodrt/format.h"
#include "lodrt/meshopt.h"
#include "memory.h"

namespace lodrt {

using detail::Growable;

uint32_t componentSize(ComponentType type) {
    switch (type) {
    case ComponentType::Byte:
    case ComponentType::UnsignedByte:
        return 1;
    case ComponentType::Short:
    case ComponentType::UnsignedShort:
        return 2;
    case ComponentType::UnsignedInt:
    case ComponentType::Float:
        return 4;
    }
    return 0;
}

uint32_t componentCount(AccessorType type) {
    switch (type) {
    case AccessorType::Scalar:
        return 1;
    case AccessorType::Vec2:
        return 2;
    case AccessorType::Vec3:
        return 3;
    case AccessorType::Vec4:
        return 4;
    case AccessorType::Mat2:
        return 4;
    case AccessorType::Mat3:
        return 9;
    case AccessorType::Mat4:
        return 16;
    }
    return 0;
}

const char* accessorTypeName(AccessorType type) {
    switch (type) {
    case AccessorType::Scalar:
        return "SCALAR";
    case AccessorType::Vec2:
        return "VEC2";
    case AccessorType::Vec3:
        return "VEC3";
    case AccessorType::Vec4:
        return "VEC4";
    case AccessorType::Mat2:
        return "MAT2";
    case AccessorType::Mat3:
        return "MAT3";
    case AccessorType::Mat4:
        return "MAT4";
    }
    return "?";
}

const char* componentTypeName(ComponentType type) {
    switch (type) {
    case ComponentType::Byte:
        return "i8";
    case ComponentType::UnsignedByte:
        return "u8";
    case ComponentType::Short:
        return "i16";
    case ComponentType::UnsignedShort:
        return "u16";
    case ComponentType::UnsignedInt:
        return "u32";
    case ComponentType::Float:
        return "f32";
    }
    return "?";
}

namespace {

bool parseComponentType(uint64_t code, ComponentType* out) {
    switch (code) {
    case 5120:
    case 5121:
    case 5122:
    case 5123:
    case 5125:
    case 5126:
        *out = ComponentType(uint32_t(code));
        return true;
    default:
        return false;
    }
}

bool parseAccessorType(std::string_view name, AccessorType* out) {
    static const char* const kNames[] = {"SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"};
    for (uint32_t i = 0; i < 7; ++i) {
        if (name == kNames[i]) {
            *out = AccessorType(i);
            return true;
        }
    }
    return false;
}

// Element size including the column padding glTF requires for small-component matrices.
uint32_t elementSize(ComponentType component, AccessorType type) {
    const uint32_t c = componentSize(component);
    if (type == AccessorType::Mat2 && c == 1) return 8;
    if (type == AccessorType::Mat3 && c == 1) return 12;
    if (type == AccessorType::Mat3 && c == 2) return 24;
    return c * componentCount(type);
}

// Appends a JSON pointer reference token (RFC 6901: '~' -> "~0", '/' -> "~1"), cut to fit.
void escapePointerToken(std::string_view token, char* out, size_t out_size) {
    size_t n = 0;
    for (char c : token) {
        const char* piece = c == '~' ? "~0" : c == '/' ? "~1" : nullptr;
        const size_t piece_size = piece ? 2 : 1;
        if (n + piece_size + 1 > out_size) break;
        if (piece) {
            out[n++] = piece[0];
            out[n++] = piece[1];
        } else {
            out[n++] = (uint8_t(c) < 0x20) ? '?' : c;
        }
    }
    out[n] = '\0';
}

struct RawWarning {
    uint32_t pointer_offset;
    uint32_t message_offset;
};

} // namespace

struct PackLoader {
    Allocator allocator;
    LoadOptions options;
    Pack* pack;
    char* error;
    size_t error_size;
    Growable<char> warning_text;
    Growable<RawWarning> warnings;
    uint32_t dropped_warnings = 0;
    Growable<PrimitiveInfo> primitives;
    Growable<AttributeInfo> attributes;

    static void clear(Pack* out) { out->release(); }

    Result begin(Pack* out) {
        pack = out;
        out->allocator_ = allocator;
        void* memory = detail::allocateBytes(allocator, sizeof(JsonDocument));
        if (!memory) return fail(Result::OutOfMemory, "out of memory");
        out->document_ = new (memory) JsonDocument();
        return Result::Ok;
    }

    ~PackLoader() {
        warning_text.reset(allocator);
        warnings.reset(allocator);
        primitives.reset(allocator);
        attributes.reset(allocator);
    }

#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    Result
    fail(Result code, const char* format, ...) {
        if (error && error_size > 0) {
            va_list args;
            va_start(args, format);
            std::vsnprintf(error, error_size, format, args);
            va_end(args);
        }
        return code;
    }

    Result appendText(const char* text, uint32_t* offset) {
        *offset = uint32_t(warning_text.size);
        return warning_text.append(allocator, text, std::strlen(text) + 1) ? Result::Ok : Result::OutOfMemory;
    }

#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    Result
    warn(const char* pointer, const char* format, ...) {
        if (warnings.size >= kMaxPackWarnings) {
            ++dropped_warnings;
            return Result::Ok;
        }
        char message[256];
        va_list args;
        va_start(args, format);
        std::vsnprintf(message, sizeof(message), format, args);
        va_end(args);
        RawWarning raw{};
        Result r = appendText(pointer, &raw.pointer_offset);
        if (r == Result::Ok) r = appendText(message, &raw.message_offset);
        if (r == Result::Ok && !warnings.push(allocator, raw)) r = Result::OutOfMemory;
        return r;
    }

    // Reads an optional (or required) non-negative integer member; path is the owner's pointer.
    Result getInteger(JsonValue owner, const char* path, const char* key, bool required, uint64_t fallback,
                      uint64_t* out) {
        JsonValue value = owner.find(key);
        if (!value.isValid()) {
            if (required) return fail(Result::BadGltf, "%s/%s: missing; expected a non-negative integer", path, key);
            *out = fallback;
            return Result::Ok;
        }
        if (!value.asUint64(out)) {
            if (value.isNumber())
                return fail(Result::BadGltf, "%s/%s: expected a non-negative integer, got %.17g", path, key,
                            value.number());
            return fail(Result::BadGltf, "%s/%s: expected a non-negative integer", path, key);
        }
        return Result::Ok;
    }

    // Reads an optional (or required) index into an array of `limit` objects named `what`.
    Result getIndex(JsonValue owner, const char* path, const char* key, bool required, uint32_t limit, const char* what,
                    uint32_t* out) {
        uint64_t value = 0;
        Result r = getInteger(owner, path, key, required, kNoIndex, &value);
        if (r != Result::Ok) return r;
        if (!required && !owner.find(key).isValid()) {
            *out = kNoIndex;
            return Result::Ok;
        }
        if (value >= limit)
            return fail(Result::BadGltf, "%s/%s: index %llu out of range (%u %s)", path, key,
                        static_cast<unsigned long long>(value), limit, what);
        *out = uint32_t(value);
        return Result::Ok;
    }

    // Returns the array member `key` of the root (absent means empty) or fails if it is not an array.
    Result getRootArray(const char* key, JsonValue* out) {
        JsonValue value = pack->document_->root().find(key);
        if (value.isValid() && !value.isArray()) return fail(Result::BadGltf, "/%s: expected an array", key);
        *out = value;
        return Result::Ok;
    }

    template <typename T> Result allocateInfos(uint32_t count, T** out) {
        *out = nullptr;
        if (count == 0) return Result::Ok;
        *out = detail::allocateArray<T>(allocator, count);
        if (!*out) return Result::OutOfMemory;
        for (uint32_t i = 0; i < count; ++i) (*out)[i] = T();
        return Result::Ok;
    }

    Result loadAsset() {
        JsonValue root = pack->document_->root();
        if (!root.isObject()) return fail(Result::BadGltf, ": expected the top-level value to be an object");
        JsonValue asset = root.find("asset");
        if (!asset.isObject()) return fail(Result::BadGltf, "/asset: missing; expected an object");
        JsonValue version = asset.find("version");
        if (!version.isString()) return fail(Result::BadGltf, "/asset/version: missing; expected a string");
        const std::string_view v = version.string();
        if (v.size() < 3 || v[0] != '2' || v[1] != '.') {
            char shown[64];
            escapePointerToken(v, shown, sizeof(shown));
            return fail(Result::UnsupportedVersion, "/asset/version: expected \"2.x\", got \"%s\"", shown);
        }
        JsonValue required = root.find("extensionsRequired");
        if (required.isValid() && !required.isArray())
            return fail(Result::BadGltf, "/extensionsRequired: expected an array of strings");
        for (uint32_t i = 0; i < required.size(); ++i) {
            JsonValue name = required.at(i);
            if (!name.isString())
                return fail(Result::BadGltf, "/extensionsRequired/%u: expected an extension name string", i);
            // Streams lodrt has decoders for (lodrt/valence.h, lodrt/pfrep.h) are not worth a warning.
            bool decoded = false;
            for (const char* stream : format::kDecodedStreamExtensions) decoded |= name.string() == stream;
            decoded |= name.string() == format::kExtMeshoptCompression || name.string() == format::kExtKhrMeshQuantization;
            if (decoded) continue;
            char pointer[64], shown[96];
            std::snprintf(pointer, sizeof(pointer), "/extensionsRequired/%u", i);
            escapePointerToken(name.string(), shown, sizeof(shown));
            Result r = warn(pointer, "extension %s is required but lodrt does not decode it", shown);
            if (r != Result::Ok) return r;
        }
        return Result::Ok;
    }

    // True when some bufferView uses buffer `b` and every one that does is EXT_meshopt_compression
    // compressed (a fallback buffer's rule).
    bool onlyCompressedViewsUse(uint32_t b) {
        const JsonValue views = pack->document_->root().find("bufferViews");
        bool used = false;
        for (uint32_t v = 0; v < views.size(); ++v) {
            uint64_t buffer = 0;
            if (!views.at(v).find("buffer").asUint64(&buffer) || buffer != b) continue;
            if (!views.at(v).find("extensions").find(format::kExtMeshoptCompression).isValid()) return false;
            used = true;
        }
        return used;
    }

    Result loadBuffers() {
        JsonValue array;
        Result r = getRootArray("buffers", &array);
        if (r != Result::Ok) return r;
        pack->buffer_count_ = array.size();
        r = allocateInfos(pack->buffer_count_, &pack->buffers_);
        if (r != Result::Ok) return r;
        const GlbView& glb = pack->container_;
        for (uint32_t i = 0; i < pack->buffer_count_; ++i) {
            char path[48];
            std::snprintf(path, sizeof(path), "/buffers/%u", i);
            JsonValue json = array.at(i);
            if (!json.isObject()) return fail(Result::BadGltf, "%s: expected an object", path);
            BufferInfo& info = pack->buffers_[i];
            info.json = json;
            r = getInteger(json, path, "byteLength", true, 0, &info.byte_length);
            if (r != Result::Ok) return r;
            if (info.byte_length == 0) return fail(Result::BadGltf, "%s/byteLength: expected at least 1", path);
            JsonValue uri = json.find("uri");
            if (uri.isValid() && !uri.isString()) return fail(Result::BadGltf, "%s/uri: expected a string", path);
            if (uri.isValid()) {
                info.has_uri = true;
                r = warn(path, "buffer data comes from a URI; lodrt does no IO, so its bytes are not checked");
                if (r != Result::Ok) return r;
                continue;
            }
            if (i != 0 || !glb.is_binary || glb.bin_size == 0) {
                // Else an EXT_meshopt_compression fallback buffer (lodrt/meshopt.h).
                if (!onlyCompressedViewsUse(i))
                    return fail(Result::BadGltf,
                                "%s: no uri, but only buffer 0 of a GLB with a BIN chunk may omit it (or a fallback "
                                "buffer only EXT_meshopt_compression views use)",
                                path);
                info.is_fallback = true;
                continue;
            }
            // The BIN chunk is padded to 4 bytes, so it may exceed byteLength by up to 3.
            if (info.byte_length > glb.bin_size || glb.bin_size - info.byte_length > 3)
                return fail(Result::OutOfBounds, "%s/byteLength: %llu bytes, but the BIN chunk has %zu", path,
                            static_cast<unsigned long long>(info.byte_length), glb.bin_size);
            info.is_glb_bin = true;
        }
        return Result::Ok;
    }

    Result loadBufferViews() {
        JsonValue array;
        Result r = getRootArray("bufferViews", &array);
        if (r != Result::Ok) return r;
        pack->buffer_view_count_ = array.size();
        r = allocateInfos(pack->buffer_view_count_, &pack->buffer_views_);
        if (r != Result::Ok) return r;
        for (uint32_t i = 0; i < pack->buffer_view_count_; ++i) {
            char path[48];
            std::snprintf(path, sizeof(path), "/bufferViews/%u", i);
            JsonValue json = array.at(i);
            if (!json.isObject()) return fail(Result::BadGltf, "%s: expected an object", path);
            BufferViewInfo& info = pack->buffer_views_[i];
            info.json = json;
            r = getIndex(json, path, "buffer", true, pack->buffer_count_, "buffers", &info.buffer);
            if (r != Result::Ok) return r;
            r = getInteger(json, path, "byteOffset", false, 0, &info.byte_offset);
            if (r != Result::Ok) return r;
            r = getInteger(json, path, "byteLength", true, 0, &info.byte_length);
            if (r != Result::Ok) return r;
            if (info.byte_length == 0) return fail(Result::BadGltf, "%s/byteLength: expected at least 1", path);
            uint64_t stride = 0;
            r = getInteger(json, path, "byteStride", false, 0, &stride);
            if (r != Result::Ok) return r;
            if (json.find("byteStride").isValid() && (stride < 4 || stride > 252 || stride % 4 != 0))
                return fail(Result::BadGltf, "%s/byteStride: %llu; expected a multiple of 4 in [4, 252]", path,
                            static_cast<unsigned long long>(stride));
            info.byte_stride = uint32_t(stride);
            const uint64_t buffer_length = pack->buffers_[info.buffer].byte_length;
            // Both terms are at most 2^53, so the sum cannot wrap.
            if (info.byte_offset + info.byte_length > buffer_length)
                return fail(Result::OutOfBounds, "%s: bytes [%llu, %llu) exceed buffer %u (%llu bytes)", path,
                            static_cast<unsigned long long>(info.byte_offset),
                            static_cast<unsigned long long>(info.byte_offset + info.byte_length), info.buffer,
                            static_cast<unsigned long long>(buffer_length));
        }
        return checkMeshoptViews();
    }

    // Every EXT_meshopt_compression object follows the extension's rules (lodrt/meshopt.h).
    Result checkMeshoptViews() {
        for (uint32_t i = 0; i < pack->buffer_view_count_; ++i) {
            MeshoptViewInfo info;
            const char* what = "invalid";
            const Result r = meshoptViewInfo(*pack, i, &info, &what);
            if (r == Result::NotLoaded) continue;
            if (r != Result::Ok)
                return fail(r, "/bufferViews/%u/extensions/%s/%s", i, format::kExtMeshoptCompression, what);
        }
        return Result::Ok;
    }

    // Checks that `count` elements of `element_size` bytes, `stride` apart, starting at byte_offset,
    // fit in buffer view `view_index`. count >= 1.
    Result checkRange(const char* path, uint32_t view_index, uint64_t byte_offset, uint64_t count,
                      uint32_t element_size, uint32_t alignment) {
        const BufferViewInfo& view = pack->buffer_views_[view_index];
        const uint64_t stride = view.byte_stride ? view.byte_stride : element_size;
        if (view.byte_stride && view.byte_stride < element_size)
            return fail(Result::BadGltf, "%s: elements of %u bytes do not fit bufferView %u's byteStride %u", path,
                        element_size, view_index, view.byte_stride);
        if (alignment > 1 && ((view.byte_offset + byte_offset) % alignment != 0 || stride % alignment != 0))
            return fail(Result::BadGltf, "%s/byteOffset: data at byte %llu of buffer %u is not aligned to %u", path,
                        static_cast<unsigned long long>(view.byte_offset + byte_offset), view.buffer, alignment);
        // count <= 2^53 and stride <= 252 < 2^8, so stride * (count - 1) < 2^61: no wrap.
        const uint64_t needed = byte_offset + stride * (count - 1) + element_size;
        if (needed > view.byte_length)
            return fail(Result::OutOfBounds,
                        "%s/count: %llu elements of %u bytes (stride %llu) from byte %llu need %llu bytes but "
                        "bufferView %u has %llu",
                        path, static_cast<unsigned long long>(count), element_size,
                        static_cast<unsigned long long>(stride), static_cast<unsigned long long>(byte_offset),
                        static_cast<unsigned long long>(needed), view_index,
                        static_cast<unsigned long long>(view.byte_length));
        return Result::Ok;
    }

    Result loadSparse(JsonValue sparse, const char* accessor_path, AccessorInfo& info) {
        char path[80];
        std::snprintf(path, sizeof(path), "%s/sparse", accessor_path);
        if (!sparse.isObject()) return fail(Result::BadGltf, "%s: expected an object", path);
        uint64_t count = 0;
        Result r = getInteger(sparse, path, "count", true, 0, &count);
        if (r != Result::Ok) return r;
        if (count == 0 || count > info.count)
            return fail(Result::BadGltf, "%s/count: %llu; expected 1 to the accessor count %llu", path,
                        static_cast<unsigned long long>(count), static_cast<unsigned long long>(info.count));
        for (int part = 0; part < 2; ++part) {
            const char* key = part == 0 ? "indices" : "values";
            char part_path[96];
            std::snprintf(part_path, sizeof(part_path), "%s/%s", path, key);
            JsonValue json = sparse.find(key);
            if (!json.isObject()) return fail(Result::BadGltf, "%s: missing; expected an object", part_path);
            uint32_t view = 0;
            r = getIndex(json, part_path, "bufferView", true, pack->buffer_view_count_, "bufferViews", &view);
            if (r != Result::Ok) return r;
            uint64_t offset = 0;
            r = getInteger(json, part_path, "byteOffset", false, 0, &offset);
            if (r != Result::Ok) return r;
            uint32_t size = info.element_size, alignment = componentSize(info.component_type);
            if (part == 0) {
                uint64_t code = 0;
                ComponentType type;
                r = getInteger(json, part_path, "componentType", true, 0, &code);
                if (r != Result::Ok) return r;
                if (!parseComponentType(code, &type) ||
                    (type != ComponentType::UnsignedByte && type != ComponentType::UnsignedShort &&
                     type != ComponentType::UnsignedInt))
                    return fail(Result::BadGltf, "%s/componentType: %llu; expected 5121, 5123 or 5125", part_path,
                                static_cast<unsigned long long>(code));
                size = alignment = componentSize(type);
            }
            if (pack->buffer_views_[view].byte_stride)
                return fail(Result::BadGltf, "%s/bufferView: sparse data must not use a strided bufferView", part_path);
            r = checkRange(part_path, view, offset, count, size, alignment);
            if (r != Result::Ok) return r;
        }
        info.is_sparse = true;
        return Result::Ok;
    }

    Result loadAccessors() {
        JsonValue array;
        Result r = getRootArray("accessors", &array);
        if (r != Result::Ok) return r;
        pack->accessor_count_ = array.size();
        r = allocateInfos(pack->accessor_count_, &pack->accessors_);
        if (r != Result::Ok) return r;
        for (uint32_t i = 0; i < pack->accessor_count_; ++i) {
            char path[48];
            std::snprintf(path, sizeof(path), "/accessors/%u", i);
            JsonValue json = array.at(i);
            if (!json.isObject()) return fail(Result::BadGltf, "%s: expected an object", path);
            AccessorInfo& info = pack->accessors_[i];
            info.json = json;
            uint64_t code = 0;
            r = getInteger(json, path, "componentType", true, 0, &code);
            if (r != Result::Ok) return r;
            if (!parseComponentType(code, &info.component_type))
                return fail(Result::BadGltf, "%s/componentType: %llu; expected 5120-5123, 5125 or 5126", path,
                            static_cast<unsigned long long>(code));
            JsonValue type = json.find("type");
            if (!type.isString() || !parseAccessorType(type.string(), &info.type))
                return fail(Result::BadGltf, "%s/type: expected one of SCALAR, VEC2, VEC3, VEC4, MAT2, MAT3, MAT4",
                            path);
            r = getInteger(json, path, "count", true, 0, &info.count);
            if (r != Result::Ok) return r;
            if (info.count == 0) return fail(Result::BadGltf, "%s/count: expected at least 1", path);
            r = getIndex(json, path, "bufferView", false, pack->buffer_view_count_, "bufferViews", &info.buffer_view);
            if (r != Result::Ok) return r;
            r = getInteger(json, path, "byteOffset", false, 0, &info.byte_offset);
            if (r != Result::Ok) return r;
            JsonValue normalized = json.find("normalized");
            if (normalized.isValid() && !normalized.isBool())
                return fail(Result::BadGltf, "%s/normalized: expected a boolean", path);
            info.normalized = normalized.boolean();
            info.element_size = elementSize(info.component_type, info.type);
            info.byte_length = info.count * info.element_size; // < 2^53 * 64: no wrap
            if (info.buffer_view != kNoIndex) {
                r = checkRange(path, info.buffer_view, info.byte_offset, info.count, info.element_size,
                               componentSize(info.component_type));
                if (r != Result::Ok) return r;
            }
            JsonValue sparse = json.find("sparse");
            if (sparse.isValid()) {
                r = loadSparse(sparse, path, info);
                if (r != Result::Ok) return r;
            }
        }
        return Result::Ok;
    }

    // Scans an index accessor stored in the BIN chunk for values >= vertex_count.
    Result checkIndexValues(const char* path, const AccessorInfo& accessor, uint64_t vertex_count) {
        if (options.skip_index_check || accessor.buffer_view == kNoIndex || accessor.is_sparse) return Result::Ok;
        // A deferred load (loadPackJson) has no BIN bytes yet: the streamer checks each level's
        // indices when they arrive.
        if (!pack->container_.bin) return Result::Ok;
        const BufferViewInfo& view = pack->buffer_views_[accessor.buffer_view];
        const BufferInfo& buffer = pack->buffers_[view.buffer];
        if (!buffer.is_glb_bin) return Result::Ok;
        const uint32_t size = componentSize(accessor.component_type);
        const uint64_t stride = view.byte_stride ? view.byte_stride : size;
        const uint8_t* base = pack->container_.bin + view.byte_offset + accessor.byte_offset;
        for (uint64_t k = 0; k < accessor.count; ++k) {
            const uint8_t* p = base + k * stride;
            uint32_t value = p[0];
            if (size >= 2) value |= uint32_t(p[1]) << 8;
            if (size == 4) value |= (uint32_t(p[2]) << 16) | (uint32_t(p[3]) << 24);
            if (value >= vertex_count)
                return fail(Result::OutOfBounds, "%s: index %u at position %llu out of range (%llu vertices)", path,
                            value, static_cast<unsigned long long>(k), static_cast<unsigned long long>(vertex_count));
        }
        return Result::Ok;
    }

    Result loadPrimitive(JsonValue json, const char* path, PrimitiveInfo& info) {
        if (!json.isObject()) return fail(Result::BadGltf, "%s: expected an object", path);
        info.json = json;
        JsonValue attrs = json.find("attributes");
        if (!attrs.isObject() || attrs.size() == 0)
            return fail(Result::BadGltf, "%s/attributes: missing; expected an object naming at least one accessor",
                        path);
        info.first_attribute = uint32_t(attributes.size);
        info.attribute_count = attrs.size();
        bool has_position = false;
        for (uint32_t a = 0; a < attrs.size(); ++a) {
            char key[64];
            escapePointerToken(attrs.keyAt(a), key, sizeof(key));
            char attr_path[160];
            std::snprintf(attr_path, sizeof(attr_path), "%s/attributes/%s", path, key);
            AttributeInfo attribute;
            attribute.name = attrs.keyAt(a);
            uint64_t index = 0;
            if (!attrs.at(a).asUint64(&index))
                return fail(Result::BadGltf, "%s: expected an accessor index", attr_path);
            if (index >= pack->accessor_count_)
                return fail(Result::BadGltf, "%s: index %llu out of range (%u accessors)", attr_path,
                            static_cast<unsigned long long>(index), pack->accessor_count_);
            attribute.accessor = uint32_t(index);
            const uint64_t count = pack->accessors_[index].count;
            if (a == 0) {
                info.vertex_count = count;
            } else if (count != info.vertex_count) {
                char first[64];
                escapePointerToken(attrs.keyAt(0), first, sizeof(first));
                return fail(Result::BadGltf, "%s: count %llu differs from %s count %llu", attr_path,
                            static_cast<unsigned long long>(count), first,
                            static_cast<unsigned long long>(info.vertex_count));
            }
            if (attribute.name == "POSITION") has_position = true;
            if (!attributes.push(allocator, attribute)) return Result::OutOfMemory;
        }
        if (!has_position) {
            Result r = warn(path, "primitive has no POSITION attribute");
            if (r != Result::Ok) return r;
        }
        uint64_t mode = 4;
        Result r = getInteger(json, path, "mode", false, 4, &mode);
        if (r != Result::Ok) return r;
        if (mode > 6)
            return fail(Result::BadGltf, "%s/mode: %llu; expected 0 to 6", path, static_cast<unsigned long long>(mode));
        info.mode = uint32_t(mode);
        r = getIndex(json, path, "material", false, pack->material_count_, "materials", &info.material);
        if (r != Result::Ok) return r;
        r = getIndex(json, path, "indices", false, pack->accessor_count_, "accessors", &info.indices);
        if (r != Result::Ok) return r;
        info.index_count = info.vertex_count;
        if (info.indices != kNoIndex) {
            char index_path[96];
            std::snprintf(index_path, sizeof(index_path), "%s/indices", path);
            const AccessorInfo& accessor = pack->accessors_[info.indices];
            if (accessor.type != AccessorType::Scalar ||
                (accessor.component_type != ComponentType::UnsignedByte &&
                 accessor.component_type != ComponentType::UnsignedShort &&
                 accessor.component_type != ComponentType::UnsignedInt) ||
                accessor.normalized)
                return fail(Result::BadGltf, "%s: accessor %u must be SCALAR u8/u16/u32 and not normalized", index_path,
                            info.indices);
            info.index_count = accessor.count;
            r = checkIndexValues(index_path, accessor, info.vertex_count);
            if (r != Result::Ok) return r;
        }
        const char* count_path = info.indices != kNoIndex ? "indices" : "attributes";
        switch (info.mode) {
        case 4:
            if (info.index_count % 3 != 0)
                return fail(Result::BadGltf, "%s/%s: %llu vertices for TRIANGLES; expected a multiple of 3", path,
                            count_path, static_cast<unsigned long long>(info.index_count));
            info.triangle_count = info.index_count / 3;
            break;
        case 5:
        case 6:
            info.triangle_count = info.index_count >= 3 ? info.index_count - 2 : 0;
            break;
        default: {
            char mode_path[96];
            std::snprintf(mode_path, sizeof(mode_path), "%s/mode", path);
            r = warn(mode_path, "mode %u draws points or lines, not triangles", info.mode);
            if (r != Result::Ok) return r;
        }
        }
        return Result::Ok;
    }

    Result loadMeshes() {
        JsonValue materials;
        Result r = getRootArray("materials", &materials);
        if (r != Result::Ok) return r;
        pack->material_count_ = materials.size();
        JsonValue array;
        r = getRootArray("meshes", &array);
        if (r != Result::Ok) return r;
        pack->mesh_count_ = array.size();
        r = allocateInfos(pack->mesh_count_, &pack->meshes_);
        if (r != Result::Ok) return r;
        for (uint32_t i = 0; i < pack->mesh_count_; ++i) {
            char path[48];
            std::snprintf(path, sizeof(path), "/meshes/%u", i);
            JsonValue json = array.at(i);
            if (!json.isObject()) return fail(Result::BadGltf, "%s: expected an object", path);
            MeshInfo& mesh = pack->meshes_[i];
            mesh.json = json;
            mesh.name = json.find("name").string();
            JsonValue prims = json.find("primitives");
            if (!prims.isArray() || prims.size() == 0)
                return fail(Result::BadGltf, "%s/primitives: missing; expected a non-empty array", path);
            mesh.first_primitive = uint32_t(primitives.size);
            mesh.primitive_count = prims.size();
            for (uint32_t p = 0; p < prims.size(); ++p) {
                char prim_path[80];
                std::snprintf(prim_path, sizeof(prim_path), "%s/primitives/%u", path, p);
                PrimitiveInfo info;
                r = loadPrimitive(prims.at(p), prim_path, info);
                if (r != Result::Ok) return r;
                if (!primitives.push(allocator, info)) return Result::OutOfMemory;
            }
        }
        return Result::Ok;
    }

    Result loadNodes() {
        JsonValue array;
        Result r = getRootArray("nodes", &array);
        if (r != Result::Ok) return r;
        const uint32_t count = array.size();
        pack->node_count_ = count;
        r = allocateInfos(count, &pack->nodes_);
        if (r != Result::Ok) return r;
        for (uint32_t i = 0; i < count; ++i) {
            char path[48];
            std::snprintf(path, sizeof(path), "/nodes/%u", i);
            JsonValue json = array.at(i);
            if (!json.isObject()) return fail(Result::BadGltf, "%s: expected an object", path);
            pack->nodes_[i].json = json;
            pack->nodes_[i].name = json.find("name").string();
            r = getIndex(json, path, "mesh", false, pack->mesh_count_, "meshes", &pack->nodes_[i].mesh);
            if (r != Result::Ok) return r;
        }
        for (uint32_t i = 0; i < count; ++i) {
            JsonValue children = array.at(i).find("children");
            if (children.isValid() && !children.isArray())
                return fail(Result::BadGltf, "/nodes/%u/children: expected an array of node indices", i);
            for (uint32_t c = 0; c < children.size(); ++c) {
                uint64_t child = 0;
                if (!children.at(c).asUint64(&child) || child >= count)
                    return fail(Result::BadGltf, "/nodes/%u/children/%u: expected a node index below %u", i, c, count);
                if (child == i)
                    return fail(Result::BadGltf, "/nodes/%u/children/%u: a node cannot be its own child", i, c);
                NodeInfo& node = pack->nodes_[child];
                if (node.parent != kNoIndex)
                    return fail(Result::BadGltf, "/nodes/%u/children/%u: node %llu already has parent %u", i, c,
                                static_cast<unsigned long long>(child), node.parent);
                node.parent = i;
            }
        }
        // With one parent per node the hierarchy is a forest unless parent links form a loop. Walk up
        // from every node, marking nodes on the current walk (1) and nodes known to reach a root (2),
        // so the check stays linear for a hostile chain of millions of nodes.
        if (count == 0) return Result::Ok;
        uint8_t* state = detail::allocateArray<uint8_t>(allocator, count);
        if (!state) return Result::OutOfMemory;
        std::memset(state, 0, count);
        Result result = Result::Ok;
        for (uint32_t i = 0; i < count && result == Result::Ok; ++i) {
            uint32_t k = i;
            while (k != kNoIndex && state[k] == 0) {
                state[k] = 1;
                k = pack->nodes_[k].parent;
            }
            if (k != kNoIndex && state[k] == 1)
                result = fail(Result::BadGltf, "/nodes/%u/children: node hierarchy contains a cycle through node %u",
                              pack->nodes_[k].parent, k);
            for (k = i; k != kNoIndex && state[k] == 1; k = pack->nodes_[k].parent) state[k] = 2;
        }
        detail::deallocateBytes(allocator, state);
        return result;
    }

    Result finishWarnings() {
        if (dropped_warnings > 0 && warnings.size > 0) {
            char message[256];
            const RawWarning& last = warnings.data[warnings.size - 1];
            std::snprintf(message, sizeof(message), "%s (and %u more warnings)",
                          warning_text.data + last.message_offset, dropped_warnings);
            uint32_t offset = 0;
            if (appendText(message, &offset) != Result::Ok) return Result::OutOfMemory;
            warnings.data[warnings.size - 1].message_offset = offset;
        }
        if (warnings.size == 0) return Result::Ok;
        pack->warnings_ = detail::allocateArray<PackWarning>(allocator, warnings.size);
        if (!pack->warnings_) return Result::OutOfMemory;
        pack->warning_text_ = warning_text.release();
        for (size_t i = 0; i < warnings.size; ++i) {
            pack->warnings_[i].pointer = pack->warning_text_ + warnings.data[i].pointer_offset;
            pack->warnings_[i].message = pack->warning_text_ + warnings.data[i].message_offset;
        }
        pack->warning_count_ = uint32_t(warnings.size);
        return Result::Ok;
    }

    Result run(const uint8_t* data, size_t size) {
        Result r = parseGlb(data, size, &pack->container_);
        if (r != Result::Ok) {
            const char* what = "not a glTF container";
            switch (r) {
            case Result::Truncated:
                what = "truncated: a length field runs past the end of the data";
                break;
            case Result::BadMagic:
                what = "expected the GLB magic \"glTF\" or a JSON object";
                break;
            case Result::UnsupportedVersion:
                what = "GLB container version is not 2";
                break;
            case Result::BadChunk:
                what = "expected a JSON chunk first, an optional BIN chunk second, 4-byte aligned";
                break;
            case Result::TrailingBytes:
                what = "bytes follow the end given in the GLB header";
                break;
            default:
                break;
            }
            return fail(r, "container: %s", what);
        }
        return runDocument();
    }

    Result runDeferred(const uint8_t* json, size_t json_size, uint64_t bin_size) {
        if (bin_size > uint64_t(size_t(-1))) return fail(Result::OutOfBounds, "container: BIN chunk too large");
        pack->container_.json = json;
        pack->container_.json_size = json_size;
        pack->container_.bin = nullptr;
        pack->container_.bin_size = size_t(bin_size);
        pack->container_.is_binary = true;
        return runDocument();
    }

    Result runDocument() {
        Result r = Result::Ok;
        JsonError json_error;
        const GlbView& glb = pack->container_;
        r = parseJson(reinterpret_cast<const char*>(glb.json), glb.json_size, &allocator, &options.json_limits,
                      pack->document_, &json_error);
        if (r != Result::Ok)
            return fail(r, "JSON byte %zu: %s", json_error.offset,
                        r == Result::BadUtf8            ? "invalid UTF-8 in a string"
                        : r == Result::JsonTooDeep      ? "nesting deeper than the limit"
                        : r == Result::JsonTooLarge     ? "more values or a longer string than the limits allow"
                        : r == Result::NumberOutOfRange ? "number out of the range of a double"
                        : r == Result::OutOfMemory      ? "out of memory"
                                                        : "invalid JSON");
        if ((r = loadAsset()) != Result::Ok) return r;
        if ((r = loadBuffers()) != Result::Ok) return r;
        if ((r = loadBufferViews()) != Result::Ok) return r;
        if ((r = loadAccessors()) != Result::Ok) return r;
        if ((r = loadMeshes()) != Result::Ok) return r;
        if ((r = loadNodes()) != Result::Ok) return r;
        pack->primitive_count_ = uint32_t(primitives.size);
        pack->primitives_ = primitives.release();
        pack->attribute_count_ = uint32_t(attributes.size);
        pack->attributes_ = attributes.release();
        return finishWarnings();
    }
};

Pack::~Pack() {
    release();
}

Pack::Pack(Pack&& other) noexcept {
    *this = static_cast<Pack&&>(other);
}

Pack& Pack::operator=(Pack&& other) noexcept {
    if (this == &other) return *this;
    release();
    // Plain pointer copy: the JSON document lives in its own allocation, so the JsonValues kept in
    // the info arrays stay valid across the move.
    allocator_ = other.allocator_;
    document_ = other.document_;
    container_ = other.container_;
    buffers_ = other.buffers_;
    buffer_views_ = other.buffer_views_;
    accessors_ = other.accessors_;
    meshes_ = other.meshes_;
    primitives_ = other.primitives_;
    attributes_ = other.attributes_;
    nodes_ = other.nodes_;
    warnings_ = other.warnings_;
    warning_text_ = other.warning_text_;
    buffer_count_ = other.buffer_count_;
    buffer_view_count_ = other.buffer_view_count_;
    accessor_count_ = other.accessor_count_;
    mesh_count_ = other.mesh_count_;
    primitive_count_ = other.primitive_count_;
    attribute_count_ = other.attribute_count_;
    node_count_ = other.node_count_;
    material_count_ = other.material_count_;
    warning_count_ = other.warning_count_;
    other.document_ = nullptr;
    other.resetFields();
    return *this;
}

void Pack::release() {
    if (document_) {
        document_->~JsonDocument();
        detail::deallocateBytes(allocator_, document_);
    }
    detail::deallocateBytes(allocator_, buffers_);
    detail::deallocateBytes(allocator_, buffer_views_);
    detail::deallocateBytes(allocator_, accessors_);
    detail::deallocateBytes(allocator_, meshes_);
    detail::deallocateBytes(allocator_, primitives_);
    detail::deallocateBytes(allocator_, attributes_);
    detail::deallocateBytes(allocator_, nodes_);
    detail::deallocateBytes(allocator_, warnings_);
    detail::deallocateBytes(allocator_, warning_text_);
    resetFields();
}

void Pack::resetFields() {
    document_ = nullptr;
    container_ = GlbView();
    buffers_ = nullptr;
    buffer_views_ = nullptr;
    accessors_ = nullptr;
    meshes_ = nullptr;
    primitives_ = nullptr;
    attributes_ = nullptr;
    nodes_ = nullptr;
    warnings_ = nullptr;
    warning_text_ = nullptr;
    buffer_count_ = buffer_view_count_ = accessor_count_ = mesh_count_ = 0;
    primitive_count_ = attribute_count_ = node_count_ = material_count_ = warning_count_ = 0;
}

const JsonDocument& Pack::document() const {
    static const JsonDocument kEmpty;
    return document_ ? *document_ : kEmpty;
}

const BufferInfo& Pack::buffer(uint32_t i) const {
    assert(i < buffer_count_);
    return buffers_[i];
}
const BufferViewInfo& Pack::bufferView(uint32_t i) const {
    assert(i < buffer_view_count_);
    return buffer_views_[i];
}
const AccessorInfo& Pack::accessor(uint32_t i) const {
    assert(i < accessor_count_);
    return accessors_[i];
}
const MeshInfo& Pack::mesh(uint32_t i) const {
    assert(i < mesh_count_);
    return meshes_[i];
}
const PrimitiveInfo& Pack::primitive(uint32_t i) const {
    assert(i < primitive_count_);
    return primitives_[i];
}
const AttributeInfo& Pack::attribute(uint32_t i) const {
    assert(i < attribute_count_);
    return attributes_[i];
}
const NodeInfo& Pack::node(uint32_t i) const {
    assert(i < node_count_);
    return nodes_[i];
}
const PackWarning& Pack::warning(uint32_t i) const {
    assert(i < warning_count_);
    return warnings_[i];
}

Result loadPack(const uint8_t* data, size_t size, const LoadOptions* options, Pack* out, char* error_message,
                size_t error_message_size) {
    if (error_message && error_message_size > 0) error_message[0] = '\0';
    if (!out || (!data && size > 0)) return Result::InvalidArgument;
    PackLoader::clear(out);
    PackLoader loader{};
    loader.options = options ? *options : LoadOptions();
    loader.allocator = loader.options.allocator;
    loader.error = error_message;
    loader.error_size = error_message_size;
    Result result = loader.begin(out);
    if (result == Result::Ok) result = loader.run(data, size);
    if (result == Result::OutOfMemory && error_message && error_message_size > 0 && error_message[0] == '\0')
        loader.fail(result, "out of memory");
    if (result != Result::Ok) PackLoader::clear(out);
    return result;
}

Result loadPackJson(const uint8_t* json, size_t json_size, uint64_t bin_size, const LoadOptions* options, Pack* out,
                    char* error_message, size_t error_message_size) {
    if (error_message && error_message_size > 0) error_message[0] = '\0';
    if (!out || (!json && json_size > 0)) return Result::InvalidArgument;
    PackLoader::clear(out);
    PackLoader loader{};
    loader.options = options ? *options : LoadOptions();
    loader.allocator = loader.options.allocator;
    loader.error = error_message;
    loader.error_size = error_message_size;
    Result result = loader.begin(out);
    if (result == Result::Ok) result = loader.runDeferred(json, json_size, bin_size);
    if (result == Result::OutOfMemory && error_message && error_message_size > 0 && error_message[0] == '\0')
        loader.fail(result, "out of memory");
    if (result != Result::Ok) PackLoader::clear(out);
    return result;
}

} // namespace lodrt
