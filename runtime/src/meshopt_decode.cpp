// EXT_meshopt_compression decoders and KHR_mesh_quantization accessor readers (lodrt/meshopt.h),
// written from the extension's specification (KhronosGroup/glTF, extensions/2.0/Vendor/
// EXT_meshopt_compression, appendices A and B). Scalar code: clarity and bounds checks over speed.
#include "lodrt/meshopt.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "lodrt/format.h"

namespace lodrt {

namespace {

namespace fmt = format;

uint8_t unzigzag8(uint8_t v) {
    return (v & 1) ? uint8_t(~(v >> 1)) : uint8_t(v >> 1);
}

// One group of 16 byte deltas (zigzag-coded) from data[pos, end) in the given header mode.
bool readGroup(const uint8_t* data, size_t end, size_t& pos, uint32_t mode, uint8_t deltas[16]) {
    if (mode == 0) {
        std::memset(deltas, 0, 16);
        return true;
    }
    if (mode == 3) {
        if (end - pos < 16) return false;
        std::memcpy(deltas, data + pos, 16);
        pos += 16;
        return true;
    }
    const uint32_t bits = mode == 1 ? 2 : 4;
    const size_t packed = 16 * bits / 8;
    if (end - pos < packed) return false;
    const uint8_t* bytes = data + pos;
    pos += packed;
    const uint32_t per_byte = 8 / bits, sentinel = (1u << bits) - 1;
    for (uint32_t i = 0; i < 16; ++i) {
        const uint32_t shift = 8 - bits * (i % per_byte + 1); // most significant first
        uint32_t v = (bytes[i / per_byte] >> shift) & sentinel;
        if (v == sentinel) {
            if (pos >= end) return false;
            v = data[pos++];
        }
        deltas[i] = uint8_t(v);
    }
    return true;
}

// varint-7 (unsigned LEB128), at most 5 bytes for 32 bits.
bool readVarint(const uint8_t* data, size_t end, size_t& pos, uint32_t* out) {
    uint32_t value = 0;
    for (uint32_t shift = 0; shift < 35; shift += 7) {
        if (pos >= end) return false;
        const uint8_t byte = data[pos++];
        value |= uint32_t(byte & 0x7F) << shift;
        if (!(byte & 0x80)) {
            *out = value;
            return true;
        }
    }
    return false;
}

void writeIndex(uint8_t* dst, size_t i, size_t index_size, uint32_t value) {
    if (index_size == 2) {
        const uint16_t v = uint16_t(value);
        std::memcpy(dst + i * 2, &v, 2);
    } else {
        std::memcpy(dst + i * 4, &value, 4);
    }
}

// The triangle decoder's state (appendix A, mode 1).
struct TriangleState {
    uint32_t edges[16][2] = {};
    uint32_t vertices[16] = {};
    uint32_t edge_at = 0, vertex_at = 0;
    uint32_t next = 0, last = 0;
    void pushEdge(uint32_t a, uint32_t b) {
        edges[edge_at][0] = a;
        edges[edge_at][1] = b;
        edge_at = (edge_at + 1) & 15;
    }
    void pushVertex(uint32_t v) {
        vertices[vertex_at] = v;
        vertex_at = (vertex_at + 1) & 15;
    }
    uint32_t vertex(uint32_t recent) const { return vertices[(vertex_at - 1 - recent) & 15]; }
    uint32_t decodeIndex(uint32_t v) {
        const uint32_t delta = (v & 1) ? ~(v >> 1) : (v >> 1);
        last += delta; // two's complement wrap, as specified
        return last;
    }
};

// A code below 0xf0: a recent edge and a third vertex.
bool decodeEdgeTriangle(TriangleState& s, uint8_t code, const uint8_t* data, size_t end, size_t& pos, uint32_t t[3]) {
    const uint32_t* edge = s.edges[(s.edge_at - 1 - (code >> 4)) & 15];
    const uint32_t a = edge[0], b = edge[1], low = code & 15;
    uint32_t c = 0;
    if (low == 0) {
        c = s.next++;
        s.pushVertex(c);
    } else if (low < 0xD) {
        c = s.vertex(low);
    } else if (low < 0xF) {
        c = low == 0xD ? s.last - 1 : s.last + 1;
        s.last = c;
        s.pushVertex(c);
    } else {
        uint32_t v = 0;
        if (!readVarint(data, end, pos, &v)) return false;
        c = s.decodeIndex(v);
        s.pushVertex(c);
    }
    s.pushEdge(c, b);
    s.pushEdge(a, c);
    t[0] = a, t[1] = b, t[2] = c;
    return true;
}

// A code 0xf0..0xff: three vertices from the code table, the FIFO or explicit values.
bool decodeFreeTriangle(TriangleState& s, uint8_t code, const uint8_t* aux, const uint8_t* data, size_t end,
                        size_t& pos, uint32_t t[3]) {
    const bool explicit_form = code >= 0xFE;
    uint32_t zw = 0;
    if (explicit_form) {
        if (pos >= end) return false;
        zw = data[pos++];
        if (zw == 0) s.next = 0;
    } else {
        zw = aux[code & 15];
    }
    const uint32_t z = zw >> 4, w = zw & 15;
    uint32_t a = 0;
    if (code == 0xFF) {
        uint32_t v = 0;
        if (!readVarint(data, end, pos, &v)) return false;
        a = s.decodeIndex(v);
    } else {
        a = s.next++;
    }
    auto other = [&](uint32_t sel, uint32_t* out) {
        if (sel == 0) {
            *out = s.next++;
        } else if (sel < 15 || !explicit_form) {
            *out = s.vertex(sel - 1);
        } else {
            uint32_t v = 0;
            if (!readVarint(data, end, pos, &v)) return false;
            *out = s.decodeIndex(v);
        }
        return true;
    };
    uint32_t b = 0, c = 0;
    if (!other(z, &b) || !other(w, &c)) return false;
    s.pushEdge(b, a);
    s.pushEdge(c, b);
    s.pushEdge(a, c);
    s.pushVertex(a);
    if (z == 0 || (explicit_form && z == 15)) s.pushVertex(b);
    if (w == 0 || (explicit_form && w == 15)) s.pushVertex(c);
    t[0] = a, t[1] = b, t[2] = c;
    return true;
}

bool parseMode(std::string_view text, MeshoptMode* out) {
    if (text == fmt::kMeshoptModeAttributes)
        *out = MeshoptMode::Attributes;
    else if (text == fmt::kMeshoptModeTriangles)
        *out = MeshoptMode::Triangles;
    else if (text == fmt::kMeshoptModeIndices)
        *out = MeshoptMode::Indices;
    else
        return false;
    return true;
}

bool parseFilter(std::string_view text, MeshoptFilter* out) {
    if (text == fmt::kMeshoptFilterNone)
        *out = MeshoptFilter::None;
    else if (text == fmt::kMeshoptFilterOctahedral)
        *out = MeshoptFilter::Octahedral;
    else if (text == fmt::kMeshoptFilterQuaternion)
        *out = MeshoptFilter::Quaternion;
    else if (text == fmt::kMeshoptFilterExponential)
        *out = MeshoptFilter::Exponential;
    else
        return false;
    return true;
}

// round(v * max) clamped to [-max, max]; NaN (a hostile zero "one") becomes 0.
int32_t snorm(float v, float max) {
    if (!(v == v)) return 0;
    const float s = v * max;
    if (s >= max) return int32_t(max);
    if (s <= -max) return -int32_t(max);
    return int32_t(std::lround(s));
}

template <typename T> void octahedral(T* e, float max) {
    const float one = float(e[2]);
    float x = float(e[0]) / one, y = float(e[1]) / one;
    const float z = 1.0f - std::fabs(x) - std::fabs(y);
    const float t = z < 0.0f ? z : 0.0f;
    x -= std::copysign(t, x);
    y -= std::copysign(t, y);
    const float len = std::sqrt(x * x + y * y + z * z);
    e[0] = T(snorm(x / len, max));
    e[1] = T(snorm(y / len, max));
    e[2] = T(snorm(z / len, max));
}

void quaternion(int16_t* e) {
    const float range = 1.0f / std::sqrt(2.0f);
    const float one = float(e[3] | 3);
    const float x = float(e[0]) / one * range, y = float(e[1]) / one * range, z = float(e[2]) / one * range;
    const float ww = 1.0f - x * x - y * y - z * z;
    const float w = std::sqrt(ww > 0.0f ? ww : 0.0f);
    const uint32_t maxcomp = uint32_t(e[3]) & 3;
    int16_t out[4];
    out[(maxcomp + 1) % 4] = int16_t(snorm(x, 32767.0f));
    out[(maxcomp + 2) % 4] = int16_t(snorm(y, 32767.0f));
    out[(maxcomp + 3) % 4] = int16_t(snorm(z, 32767.0f));
    out[maxcomp] = int16_t(snorm(w, 32767.0f));
    std::memcpy(e, out, sizeof(out));
}

float exponential(uint32_t v) {
    const uint32_t eb = v >> 24;
    const int e = int(eb) - (eb >= 128 ? 256 : 0);
    int32_t m = int32_t(v & 0xFFFFFFu);
    if (m & 0x800000) m -= 0x1000000;
    return std::ldexp(float(m), e);
}

bool bytesAt(const BinBytes& bin, uint64_t offset, uint64_t length, const uint8_t** out) {
    if (!bin.data || offset < bin.offset || offset - bin.offset > bin.size || length > bin.size - (offset - bin.offset))
        return false;
    *out = bin.data + (offset - bin.offset);
    return true;
}

// The accessor's element bytes: a pointer to element 0 and the stride, from `bin` or decoded into
// scratch.
Result accessorBytes(const Pack& pack, uint32_t accessor, const BinBytes& bin, uint8_t* scratch, size_t scratch_size,
                     const uint8_t** base, uint64_t* stride) {
    if (accessor >= pack.accessorCount()) return Result::InvalidArgument;
    const AccessorInfo& acc = pack.accessor(accessor);
    if (acc.buffer_view == kNoIndex || acc.is_sparse) return Result::NotLoaded;
    const BufferViewInfo& view = pack.bufferView(acc.buffer_view);
    *stride = view.byte_stride ? view.byte_stride : acc.element_size;
    MeshoptViewInfo info;
    const Result r = meshoptViewInfo(pack, acc.buffer_view, &info);
    if (r == Result::NotLoaded) {
        // loadPack checked the accessor fits the view.
        if (!pack.buffer(view.buffer).is_glb_bin || !bytesAt(bin, view.byte_offset, view.byte_length, base))
            return Result::OutOfBounds;
        *base += acc.byte_offset;
        return Result::Ok;
    }
    if (r != Result::Ok) return r;
    if (!pack.buffer(info.buffer).is_glb_bin) return Result::OutOfBounds;
    const uint8_t* src = nullptr;
    if (!bytesAt(bin, info.byte_offset, info.byte_length, &src)) return Result::OutOfBounds;
    if (!scratch || scratch_size < view.byte_length) return Result::BufferTooSmall;
    const Result d = meshoptDecodeView(info, src, size_t(info.byte_length), scratch, scratch_size);
    if (d != Result::Ok) return d;
    *base = scratch + acc.byte_offset;
    return Result::Ok;
}

float componentValue(const uint8_t* p, ComponentType type, bool normalized) {
    switch (type) {
    case ComponentType::Float: {
        float f = 0;
        std::memcpy(&f, p, 4);
        return f;
    }
    case ComponentType::Byte: {
        const int v = int(p[0]) - (p[0] >= 128 ? 256 : 0);
        return normalized ? std::fmax(float(v) / 127.0f, -1.0f) : float(v);
    }
    case ComponentType::UnsignedByte:
        return normalized ? float(p[0]) / 255.0f : float(p[0]);
    case ComponentType::Short: {
        const int u = int(p[0]) | int(p[1]) << 8;
        const int v = u - (u >= 32768 ? 65536 : 0);
        return normalized ? std::fmax(float(v) / 32767.0f, -1.0f) : float(v);
    }
    case ComponentType::UnsignedShort: {
        const int u = int(p[0]) | int(p[1]) << 8;
        return normalized ? float(u) / 65535.0f : float(u);
    }
    case ComponentType::UnsignedInt: {
        uint32_t u = 0;
        std::memcpy(&u, p, 4);
        return normalized ? float(double(u) / 4294967295.0) : float(u);
    }
    }
    return 0.0f;
}

} // namespace

Result meshoptDecodeVertexBuffer(uint8_t* dst, size_t count, size_t stride, const uint8_t* src, size_t size) {
    if (stride == 0 || stride > fmt::kMeshoptMaxVertexStride || (!dst && count > 0) || (!src && size > 0))
        return Result::InvalidArgument;
    const size_t tail = stride > fmt::kMeshoptVertexTail ? stride : fmt::kMeshoptVertexTail;
    if (size < 1 + tail) return Result::Truncated;
    if (src[0] != fmt::kMeshoptVertexHeader) return Result::BadMagic;
    uint8_t last[fmt::kMeshoptMaxVertexStride];
    std::memcpy(last, src + size - stride, stride);
    const size_t end = size - tail;
    size_t pos = 1;
    const size_t block_max = std::min<size_t>((fmt::kMeshoptVertexBlockMax / stride) & ~size_t(15), 256);
    uint8_t deltas[16];
    for (size_t first = 0; first < count;) {
        const size_t block = std::min(count - first, block_max);
        const size_t groups = (block + 15) / 16, header_bytes = (groups + 3) / 4;
        for (size_t k = 0; k < stride; ++k) {
            if (end - pos < header_bytes) return Result::Truncated;
            const uint8_t* header = src + pos;
            pos += header_bytes;
            for (size_t g = 0; g < groups; ++g) {
                const uint32_t mode = (header[g / 4] >> ((g % 4) * 2)) & 3;
                if (!readGroup(src, end, pos, mode, deltas)) return Result::Truncated;
                const size_t n = std::min<size_t>(16, block - g * 16);
                for (size_t i = 0; i < n; ++i) {
                    last[k] = uint8_t(last[k] + unzigzag8(deltas[i]));
                    dst[(first + g * 16 + i) * stride + k] = last[k];
                }
            }
        }
        first += block;
    }
    return pos == end ? Result::Ok : Result::CorruptStream;
}

Result meshoptDecodeIndexBuffer(uint8_t* dst, size_t count, size_t index_size, const uint8_t* src, size_t size) {
    if ((index_size != 2 && index_size != 4) || count % 3 != 0 || (!dst && count > 0) || (!src && size > 0))
        return Result::InvalidArgument;
    const size_t triangles = count / 3;
    if (size < 1 + 16 || size - 1 - 16 < triangles) return Result::Truncated;
    if (src[0] != (fmt::kMeshoptIndexHeader | 1)) return Result::BadMagic;
    const uint8_t* codes = src + 1;
    const uint8_t* aux = src + size - 16;
    const size_t end = size - 16;
    size_t pos = 1 + triangles;
    TriangleState state;
    for (size_t i = 0; i < triangles; ++i) {
        const uint8_t code = codes[i];
        uint32_t t[3];
        const bool ok = code < 0xF0 ? decodeEdgeTriangle(state, code, src, end, pos, t)
                                    : decodeFreeTriangle(state, code, aux, src, end, pos, t);
        if (!ok) return Result::Truncated;
        for (size_t k = 0; k < 3; ++k) writeIndex(dst, i * 3 + k, index_size, t[k]);
    }
    return pos == end ? Result::Ok : Result::CorruptStream;
}

Result meshoptDecodeIndexSequence(uint8_t* dst, size_t count, size_t index_size, const uint8_t* src, size_t size) {
    if ((index_size != 2 && index_size != 4) || (!dst && count > 0) || (!src && size > 0))
        return Result::InvalidArgument;
    if (size < 1 + 4) return Result::Truncated;
    if (src[0] != (fmt::kMeshoptSequenceHeader | 1)) return Result::BadMagic;
    const size_t end = size - 4;
    size_t pos = 1;
    uint32_t last[2] = {0, 0};
    for (size_t i = 0; i < count; ++i) {
        uint32_t v = 0;
        if (!readVarint(src, end, pos, &v)) return Result::Truncated;
        const uint32_t baseline = v & 1;
        const uint32_t delta = (v & 2) ? ~(v >> 2) : (v >> 2);
        last[baseline] += delta;
        writeIndex(dst, i, index_size, last[baseline]);
    }
    return pos == end ? Result::Ok : Result::CorruptStream;
}

Result meshoptApplyFilter(MeshoptFilter filter, uint8_t* data, size_t count, size_t stride) {
    if (!data && count > 0) return Result::InvalidArgument;
    switch (filter) {
    case MeshoptFilter::None:
        return Result::Ok;
    case MeshoptFilter::Octahedral:
        if (stride != 4 && stride != 8) return Result::InvalidArgument;
        for (size_t i = 0; i < count; ++i) {
            if (stride == 4) {
                int8_t e[4];
                std::memcpy(e, data + i * 4, 4);
                octahedral(e, 127.0f);
                std::memcpy(data + i * 4, e, 4);
            } else {
                int16_t e[4];
                std::memcpy(e, data + i * 8, 8);
                octahedral(e, 32767.0f);
                std::memcpy(data + i * 8, e, 8);
            }
        }
        return Result::Ok;
    case MeshoptFilter::Quaternion:
        if (stride != 8) return Result::InvalidArgument;
        for (size_t i = 0; i < count; ++i) {
            int16_t e[4];
            std::memcpy(e, data + i * 8, 8);
            quaternion(e);
            std::memcpy(data + i * 8, e, 8);
        }
        return Result::Ok;
    case MeshoptFilter::Exponential:
        if (stride % 4 != 0) return Result::InvalidArgument;
        for (size_t i = 0; i < count * (stride / 4); ++i) {
            uint32_t v = 0;
            std::memcpy(&v, data + i * 4, 4);
            const float f = exponential(v);
            std::memcpy(data + i * 4, &f, 4);
        }
        return Result::Ok;
    }
    return Result::InvalidArgument;
}

Result meshoptViewInfo(const Pack& pack, uint32_t view, MeshoptViewInfo* out, const char** what) {
    if (!out || view >= pack.bufferViewCount()) return Result::InvalidArgument;
    auto bad = [what](const char* text) {
        if (what) *what = text;
        return Result::BadGltf;
    };
    const BufferViewInfo& parent = pack.bufferView(view);
    const JsonValue ext = parent.json.find("extensions").find(fmt::kExtMeshoptCompression);
    if (!ext.isValid()) return Result::NotLoaded;
    if (!ext.isObject()) return bad("expected an object");
    uint64_t buffer = 0, stride = 0;
    MeshoptViewInfo info;
    if (!ext.find("buffer").asUint64(&buffer) || buffer >= pack.bufferCount() ||
        pack.buffer(uint32_t(buffer)).is_fallback)
        return bad("buffer: expected the index of a buffer with bytes");
    info.buffer = uint32_t(buffer);
    const JsonValue offset = ext.find("byteOffset");
    if (offset.isValid() && !offset.asUint64(&info.byte_offset)) return bad("byteOffset: expected an integer >= 0");
    if (!ext.find("byteLength").asUint64(&info.byte_length)) return bad("byteLength: expected an integer >= 0");
    if (!ext.find("byteStride").asUint64(&stride) || stride == 0 || stride > fmt::kMeshoptMaxVertexStride)
        return bad("byteStride: expected 1 to 256");
    info.stride = uint32_t(stride);
    if (!ext.find("count").asUint64(&info.count)) return bad("count: expected an integer >= 0");
    const JsonValue mode = ext.find("mode"), filter = ext.find("filter");
    if (!mode.isString() || !parseMode(mode.string(), &info.mode))
        return bad("mode: expected ATTRIBUTES, TRIANGLES or INDICES");
    if (filter.isValid() && (!filter.isString() || !parseFilter(filter.string(), &info.filter)))
        return bad("filter: expected NONE, OCTAHEDRAL, QUATERNION or EXPONENTIAL");
    if (parent.byte_stride && parent.byte_stride != info.stride)
        return bad("byteStride: differs from the bufferView's");
    // count <= 2^53 / 256 keeps count * stride exact.
    if (info.count > (uint64_t(1) << 45) || info.count * info.stride != parent.byte_length)
        return bad("count: count * byteStride must equal the bufferView's byteLength");
    if (info.mode == MeshoptMode::Attributes && info.stride % 4 != 0)
        return bad("byteStride: ATTRIBUTES needs a multiple of 4");
    if (info.mode != MeshoptMode::Attributes && (info.stride != 2 && info.stride != 4))
        return bad("byteStride: index modes need 2 or 4");
    if (info.mode == MeshoptMode::Triangles && info.count % 3 != 0)
        return bad("count: TRIANGLES needs a multiple of 3");
    if (info.mode != MeshoptMode::Attributes && info.filter != MeshoptFilter::None)
        return bad("filter: index modes take none");
    if ((info.filter == MeshoptFilter::Octahedral && info.stride != 4 && info.stride != 8) ||
        (info.filter == MeshoptFilter::Quaternion && info.stride != 8))
        return bad("filter: does not suit byteStride");
    const uint64_t length = pack.buffer(info.buffer).byte_length;
    if (info.byte_offset > length || info.byte_length > length - info.byte_offset) {
        if (what) *what = "byteOffset: the compressed bytes leave their buffer";
        return Result::OutOfBounds;
    }
    *out = info;
    return Result::Ok;
}

Result meshoptDecodeView(const MeshoptViewInfo& info, const uint8_t* src, size_t size, uint8_t* dst, size_t dst_size) {
    if (info.count > (uint64_t(1) << 45) || dst_size < info.count * info.stride) return Result::BufferTooSmall;
    Result r = Result::InvalidArgument;
    switch (info.mode) {
    case MeshoptMode::Attributes:
        r = meshoptDecodeVertexBuffer(dst, size_t(info.count), info.stride, src, size);
        break;
    case MeshoptMode::Triangles:
        r = meshoptDecodeIndexBuffer(dst, size_t(info.count), info.stride, src, size);
        break;
    case MeshoptMode::Indices:
        r = meshoptDecodeIndexSequence(dst, size_t(info.count), info.stride, src, size);
        break;
    }
    if (r != Result::Ok) return r;
    return meshoptApplyFilter(info.filter, dst, size_t(info.count), info.stride);
}

uint64_t accessorScratchBytes(const Pack& pack, uint32_t accessor) {
    if (accessor >= pack.accessorCount()) return 0;
    const AccessorInfo& acc = pack.accessor(accessor);
    if (acc.buffer_view == kNoIndex) return 0;
    MeshoptViewInfo info;
    if (meshoptViewInfo(pack, acc.buffer_view, &info) != Result::Ok) return 0;
    return pack.bufferView(acc.buffer_view).byte_length;
}

Result readAccessorFloats(const Pack& pack, uint32_t accessor, const BinBytes& bin, float* out, size_t capacity,
                          uint8_t* scratch, size_t scratch_size) {
    if (accessor >= pack.accessorCount()) return Result::InvalidArgument;
    const AccessorInfo& acc = pack.accessor(accessor);
    const uint32_t components = componentCount(acc.type), size = componentSize(acc.component_type);
    if (!out || capacity < acc.count * components) return Result::BufferTooSmall;
    const uint8_t* base = nullptr;
    uint64_t stride = 0;
    const Result r = accessorBytes(pack, accessor, bin, scratch, scratch_size, &base, &stride);
    if (r != Result::Ok) return r;
    for (uint64_t i = 0; i < acc.count; ++i)
        for (uint32_t c = 0; c < components; ++c)
            out[i * components + c] = componentValue(base + i * stride + c * size, acc.component_type, acc.normalized);
    return Result::Ok;
}

Result readAccessorIndices(const Pack& pack, uint32_t accessor, const BinBytes& bin, uint64_t vertex_count,
                           uint32_t* out, size_t capacity, uint8_t* scratch, size_t scratch_size) {
    if (accessor >= pack.accessorCount()) return Result::InvalidArgument;
    const AccessorInfo& acc = pack.accessor(accessor);
    const uint32_t size = componentSize(acc.component_type);
    if (acc.type != AccessorType::Scalar || size == 0 || size == 3 || acc.component_type == ComponentType::Float)
        return Result::InvalidArgument;
    if (!out || capacity < acc.count) return Result::BufferTooSmall;
    const uint8_t* base = nullptr;
    uint64_t stride = 0;
    const Result r = accessorBytes(pack, accessor, bin, scratch, scratch_size, &base, &stride);
    if (r != Result::Ok) return r;
    for (uint64_t i = 0; i < acc.count; ++i) {
        const uint8_t* p = base + i * stride;
        uint32_t v = p[0];
        if (size >= 2) v |= uint32_t(p[1]) << 8;
        if (size == 4) v |= uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
        if (v >= vertex_count) return Result::OutOfBounds;
        out[i] = v;
    }
    return Result::Ok;
}

} // namespace lodrt
