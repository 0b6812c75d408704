// GLB container reader (glTF 2.0 specification, "Binary glTF Layout").
#include "lodrt/glb.h"

#include "little_endian.h"
#include "lodrt/format.h"

namespace lodrt {
namespace {

using detail::loadU32;

bool isJsonSpace(uint8_t c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}

Result parsePlainJson(const uint8_t* data, size_t size, GlbView* out) {
    size_t pos = 0;
    if (size >= 3 && data[0] == 0xEF && data[1] == 0xBB && data[2] == 0xBF) pos = 3;
    while (pos < size && isJsonSpace(data[pos])) ++pos;
    if (pos >= size || data[pos] != '{') return Result::BadMagic;
    out->json = data;
    out->json_size = size;
    out->is_binary = false;
    return Result::Ok;
}

Result parseBinary(const uint8_t* data, size_t size, GlbView* out) {
    using namespace format;
    if (size < kGlbHeaderSize) return Result::Truncated;
    if (loadU32(data + 4) != kGlbVersion) return Result::UnsupportedVersion;
    const uint32_t length = loadU32(data + 8);
    if (length > size) return Result::Truncated;
    if (length < size) return Result::TrailingBytes;
    if (length % 4 != 0) return Result::BadChunk;

    size_t pos = kGlbHeaderSize;
    uint32_t chunk_index = 0;
    GlbView view;
    view.is_binary = true;
    while (pos < size) {
        if (size - pos < kGlbChunkHeaderSize) return Result::Truncated;
        const uint32_t chunk_length = loadU32(data + pos);
        const uint32_t chunk_type = loadU32(data + pos + 4);
        pos += kGlbChunkHeaderSize;
        if (chunk_length > size - pos) return Result::Truncated;
        if (chunk_length % 4 != 0) return Result::BadChunk;
        if (chunk_index == 0) {
            if (chunk_type != kGlbChunkJson || chunk_length == 0) return Result::BadChunk;
            view.json = data + pos;
            view.json_size = chunk_length;
        } else if (chunk_type == kGlbChunkJson) {
            return Result::BadChunk;
        } else if (chunk_type == kGlbChunkBin) {
            if (chunk_index != 1) return Result::BadChunk;
            view.bin = data + pos;
            view.bin_size = chunk_length;
        }
        pos += chunk_length;
        ++chunk_index;
    }
    if (chunk_index == 0) return Result::BadChunk; // a header with no JSON chunk
    *out = view;
    return Result::Ok;
}

} // namespace

Result parseGlb(const uint8_t* data, size_t size, GlbView* out) {
    if (!out) return Result::InvalidArgument;
    *out = GlbView();
    if (!data && size > 0) return Result::InvalidArgument;
    static const uint8_t kMagic[4] = {'g', 'l', 'T', 'F'};
    size_t magic_bytes = size < 4 ? size : 4;
    bool magic_prefix = true;
    for (size_t i = 0; i < magic_bytes; ++i) magic_prefix = magic_prefix && data[i] == kMagic[i];
    if (magic_prefix && size < 4) return Result::Truncated;
    if (magic_prefix) {
        Result result = parseBinary(data, size, out);
        if (result != Result::Ok) *out = GlbView();
        return result;
    }
    return parsePlainJson(data, size, out);
}

} // namespace lodrt
