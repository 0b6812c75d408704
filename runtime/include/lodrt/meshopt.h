#pragma once
// EXT_meshopt_compression and KHR_mesh_quantization (docs/format/web.md): the decoders of the
// extension's three bitstreams (attributes, vertex codec version 0; triangles, index codec version 1;
// index sequences) and its filters, written from the extension's specification, and readers that turn
// a (possibly compressed, possibly quantized) accessor into the float and uint32 forms lodrt's
// consumers use. Every decoder is bounds-checked against its input and output sizes and never reads
// or writes outside them; a stream that does not decode exactly is CorruptStream.

#include <cstddef>
#include <cstdint>

#include "lodrt/export.h"
#include "lodrt/pack.h"
#include "lodrt/result.h"

namespace lodrt {

enum class MeshoptMode : uint8_t { Attributes, Triangles, Indices };
enum class MeshoptFilter : uint8_t { None, Octahedral, Quaternion, Exponential };

/// A buffer view's EXT_meshopt_compression object, checked against the extension's rules.
struct MeshoptViewInfo {
    uint32_t buffer = 0;      // the buffer holding the compressed bytes
    uint64_t byte_offset = 0; // of the compressed bytes in that buffer
    uint64_t byte_length = 0;
    uint64_t count = 0;  // elements
    uint32_t stride = 0; // bytes per decoded element
    MeshoptMode mode = MeshoptMode::Attributes;
    MeshoptFilter filter = MeshoptFilter::None;
};

/// Decodes `count` elements of `stride` bytes (1..256) of an attribute stream src[0, size) into
/// dst[0, count * stride). Returns Ok; InvalidArgument (bad stride, null pointers); Truncated;
/// BadMagic (not a version 0 vertex stream); CorruptStream (the blocks do not end at the tail).
LODRT_API Result meshoptDecodeVertexBuffer(uint8_t* dst, size_t count, size_t stride, const uint8_t* src, size_t size);
/// Decodes a triangle stream (count a multiple of 3) into dst as index_size (2 or 4) byte integers.
LODRT_API Result meshoptDecodeIndexBuffer(uint8_t* dst, size_t count, size_t index_size, const uint8_t* src,
                                          size_t size);
/// Decodes an index sequence stream into dst as index_size (2 or 4) byte integers.
LODRT_API Result meshoptDecodeIndexSequence(uint8_t* dst, size_t count, size_t index_size, const uint8_t* src,
                                            size_t size);
/// Applies a filter in place to `count` decoded elements of `stride` bytes. InvalidArgument when the
/// stride does not suit the filter.
LODRT_API Result meshoptApplyFilter(MeshoptFilter filter, uint8_t* data, size_t count, size_t stride);

/// Reads buffer view `view`'s EXT_meshopt_compression object. Returns Ok; NotLoaded when the view has
/// none; BadGltf when it breaks a rule of the extension (with `*what` naming it when not null);
/// OutOfBounds when its compressed bytes leave its buffer.
LODRT_API Result meshoptViewInfo(const Pack& pack, uint32_t view, MeshoptViewInfo* out, const char** what = nullptr);
/// Decodes a compressed view (info from meshoptViewInfo): src[0, size) are its compressed bytes, dst
/// receives info.count * info.stride bytes, filtered.
LODRT_API Result meshoptDecodeView(const MeshoptViewInfo& info, const uint8_t* src, size_t size, uint8_t* dst,
                                   size_t dst_size);

/// The part of the GLB BIN chunk a caller holds: data[0, size) are BIN bytes [offset, offset + size)
/// (the whole chunk, or a level's range as PackSource::readLevel returns it).
struct BinBytes {
    const uint8_t* data = nullptr;
    uint64_t offset = 0;
    uint64_t size = 0;
};

/// Scratch bytes readAccessorFloats / readAccessorIndices need for `accessor`: its buffer view's
/// decoded length when the view is compressed, else 0.
LODRT_API uint64_t accessorScratchBytes(const Pack& pack, uint32_t accessor);
/// Accessor `accessor` as floats, count * components of them, into out[0, capacity): float data as
/// stored, normalized integers mapped to [0, 1] / [-1, 1] (KHR_mesh_quantization), other integers
/// as their values. Compressed views are decoded into scratch. Returns Ok; BufferTooSmall;
/// OutOfBounds when the bytes are not in `bin`; NotLoaded for an accessor without a buffer view or
/// a sparse one; the decoders' results.
LODRT_API Result readAccessorFloats(const Pack& pack, uint32_t accessor, const BinBytes& bin, float* out,
                                    size_t capacity, uint8_t* scratch, size_t scratch_size);
/// Accessor `accessor` as uint32 indices into out[0, capacity), each checked below vertex_count
/// (OutOfBounds otherwise). Same results as readAccessorFloats.
LODRT_API Result readAccessorIndices(const Pack& pack, uint32_t accessor, const BinBytes& bin, uint64_t vertex_count,
                                     uint32_t* out, size_t capacity, uint8_t* scratch, size_t scratch_size);

} // namespace lodrt
