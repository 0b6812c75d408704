#pragma once
// lodview's decode step between the Streamer and the GPU: turns the bytes the Streamer holds for a
// resident level into float positions, float texture coordinates and uint32 indices per TRIANGLES
// primitive, whatever form the pack stores them in:
// - plain accessors (float, or the integer forms of KHR_mesh_quantization) and
//   EXT_meshopt_compression views, through lodrt's accessor readers (lodrt/meshopt.h);
// - LODBAKE_valence_compression streams whose primitive's accessors have no data (--compact
//   packs), through lodrt::valenceDecode (lodrt/valence.h).
// The output buffers belong to the decoder and are reused from level to level; reserve() sizes
// them for the largest level of the packs, so a frame's decode allocates only when a stream asks
// for more scratch than was reserved (counted in growths()).

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "lodrt/lodrt.h"
#include "lodrt/meshopt.h"
#include "lodrt/valence.h"

namespace lodview {

/// One decoded TRIANGLES primitive: its vertices [first_vertex, first_vertex + vertex_count) of
/// positions() (and of uvs() when has_uv), its indices [first_index, first_index + index_count) of
/// indices(), relative to first_vertex.
struct DecodedPrimitive {
    uint32_t primitive = 0; // index into Pack::primitive()
    uint32_t first_vertex = 0, vertex_count = 0;
    uint32_t first_index = 0, index_count = 0;
    uint32_t image_view = lodrt::kNoIndex; // buffer view of the base colour image, kNoIndex if none
    bool has_uv = false;                   // the texture coordinates that image needs were decoded
    bool from_stream = false;              // decoded from LODBAKE_valence_compression
};

/// The buffer view of the image behind `material`'s base colour texture and the TEXCOORD set it
/// uses, or kNoIndex (the pack is hostile: every step is checked).
uint32_t baseColourImageView(const lodrt::Pack& pack, uint32_t material, uint32_t* tex_coord);

class LevelDecoder {
public:
    /// Sizes the buffers for the largest level (vertices, indices, meshopt scratch) of `source`.
    void reserve(const lodrt::PackSource& source);
    /// Decodes level `level` of `model` from `bytes` (its resident bytes, as PackSource::readLevel
    /// wrote them, `size` of them). False with *error set ("<what>: <why>"): data outside the
    /// level's bytes, a stream or view that does not decode, counts that disagree with the accessors.
    bool decode(const lodrt::PackSource& source, uint32_t model, uint32_t level, const uint8_t* bytes, size_t size,
                std::string* error);

    const std::vector<DecodedPrimitive>& primitives() const { return primitives_; }
    const float* positions() const { return positions_.data(); } // xyz per vertex
    const float* uvs() const { return uvs_.data(); }             // uv per vertex (where has_uv)
    const uint32_t* indices() const { return indices_.data(); }
    uint32_t indexCount() const { return index_count_; }
    /// Times a buffer had to grow inside decode() since reserve().
    uint64_t growths() const { return growths_; }

private:
    bool decodeAccessors(const lodrt::PackSource& source, const lodrt::BinBytes& bin, DecodedPrimitive* out,
                         uint32_t uv_set, std::string* error);
    bool decodeStream(const lodrt::PackSource& source, const lodrt::BinBytes& bin, const lodrt::JsonValue& stream,
                      DecodedPrimitive* out, uint32_t uv_set, std::string* error);
    template <class T> void ensure(std::vector<T>* v, size_t n);

    std::vector<DecodedPrimitive> primitives_;
    std::vector<float> positions_, uvs_;
    std::vector<uint32_t> indices_;
    std::vector<uint64_t> scratch_; // 8-byte aligned, as valenceDecode needs
    uint32_t vertex_count_ = 0, index_count_ = 0;
    uint64_t growths_ = 0;
};

} // namespace lodview
