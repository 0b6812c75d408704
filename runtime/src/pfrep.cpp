// PFRep reader (Cortés Carrillo's progressive fans): validation, progressive and selective
// extraction, SimplifyVertex / InsertVertex and Hoppe's view-dependent criterion.
// Layout: docs/format/pfrep.md and lodrt/format.h.
#include "lodrt/pfrep.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "box_distance.h"
#include "lodrt/format.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace lodrt {
namespace {

uint32_t loadU32(const uint8_t* p) {
    uint32_t v;
    std::memcpy(&v, p, 4);
    return v;
}
uint16_t loadU16(const uint8_t* p) {
    uint16_t v;
    std::memcpy(&v, p, 2);
    return v;
}
float loadF32(const uint8_t* p) {
    float v;
    std::memcpy(&v, p, 4);
    return v;
}

// Reads `n` <= 32 bits at bit position `bit` of `base` (LSB first). The caller guarantees 8
// readable bytes from bit / 8 (the stream padding).
inline uint32_t bitsAt(const uint8_t* base, uint64_t bit, uint32_t n) {
    uint64_t w;
    std::memcpy(&w, base + (bit >> 3), 8);
    return uint32_t((w >> (bit & 7)) & ((uint64_t(1) << n) - 1));
}

// A decoded entry header: where its arrays start.
struct Entry {
    uint32_t neighbours = 0;
    uint32_t dependencies = 0;
    bool has_original = false;
    uint32_t neighbour_width = 0;
    uint32_t dependency_width = 0;
    uint64_t neighbour_bit = 0; // first bit of A
    uint64_t first_mask_bit = 0;
    uint64_t end_bit = 0;
};

inline uint32_t blockOffset(const PfrepModel& m, uint32_t b) {
    return loadU32(m.data + format::kPfrepHeaderSize + size_t(b) * 4);
}
inline uint32_t blockVertices(const PfrepModel& m, uint32_t b) {
    return std::min(uint32_t(1) << m.block_shift, m.vertex_count - (b << m.block_shift));
}
// Where block b ends: the start of block b - 1 (stored after it), or the blob's end.
inline uint64_t blockEnd(const PfrepModel& m, uint32_t b) { return b > 0 ? blockOffset(m, b - 1) : m.blob_size; }

// Vertex record of v (v must be loaded).
inline const uint8_t* record(const PfrepModel& m, uint32_t v) {
    const uint32_t b = v >> m.block_shift;
    return m.data + blockOffset(m, b) + size_t(v - (b << m.block_shift)) * format::kPfrepVertexRecordSize;
}

// Bit position (from m.data) of entry i (i must be loaded).
inline uint64_t entryStart(const PfrepModel& m, uint32_t i) {
    const uint32_t b = i >> m.block_shift;
    const uint64_t base = blockOffset(m, b);
    const uint32_t count = blockVertices(m, b);
    const uint16_t rel = loadU16(m.data + base + size_t(count) * format::kPfrepVertexRecordSize +
                                 size_t(i - (b << m.block_shift)) * 2);
    return (base + uint64_t(count) * (format::kPfrepVertexRecordSize + 2) + rel) * 8;
}

inline Entry decodeHeader(const uint8_t* s, uint64_t bit) {
    Entry e;
    e.neighbours = bitsAt(s, bit, format::kPfrepCountBits);
    bit += format::kPfrepCountBits;
    if (e.neighbours == (1u << format::kPfrepCountBits) - 1) {
        e.neighbours += bitsAt(s, bit, format::kPfrepCountEscapeBits);
        bit += format::kPfrepCountEscapeBits;
    }
    e.dependencies = bitsAt(s, bit, format::kPfrepDependencyCountBits);
    bit += format::kPfrepDependencyCountBits;
    if (e.dependencies == (1u << format::kPfrepDependencyCountBits) - 1) {
        e.dependencies += bitsAt(s, bit, format::kPfrepCountEscapeBits);
        bit += format::kPfrepCountEscapeBits;
    }
    e.has_original = bitsAt(s, bit, 1) != 0;
    bit += 1;
    e.neighbour_width = bitsAt(s, bit, format::kPfrepWidthBits);
    bit += format::kPfrepWidthBits;
    if (e.dependencies > 0) {
        e.dependency_width = bitsAt(s, bit, format::kPfrepWidthBits);
        bit += format::kPfrepWidthBits;
    }
    e.neighbour_bit = bit;
    e.first_mask_bit = bit + uint64_t(e.neighbours) * e.neighbour_width;
    e.end_bit = e.first_mask_bit + (e.has_original ? e.neighbours : 0) +
                uint64_t(e.dependencies) * (uint64_t(e.dependency_width) + e.neighbours);
    return e;
}

inline uint32_t neighbourAt(const uint8_t* s, const Entry& e, uint32_t i, uint32_t j) {
    return i + 1 + bitsAt(s, e.neighbour_bit + uint64_t(j) * e.neighbour_width, e.neighbour_width);
}

inline bool maskBit(const uint8_t* mask, uint32_t v) { return (mask[v >> 3] >> (v & 7)) & 1; }
// Whether v's record and entry are loaded: the resident bits of a region model, else the prefix rule.
inline bool isResident(const PfrepModel& m, uint32_t v) {
    return m.resident ? maskBit(m.resident, v) : v >= m.loaded_from;
}
inline void setBit(uint8_t* mask, uint32_t v) { mask[v >> 3] = uint8_t(mask[v >> 3] | (1u << (v & 7))); }
inline void clearBit(uint8_t* mask, uint32_t v) { mask[v >> 3] = uint8_t(mask[v >> 3] & ~(1u << (v & 7))); }

// Calls fn(slot) for every set bit of the `n`-bit mask at `bit`.
template <typename Fn> inline void forEachSlot(const uint8_t* s, uint64_t bit, uint32_t n, Fn&& fn) {
    for (uint32_t c = 0; c < n; c += 32) {
        uint32_t m = bitsAt(s, bit + c, std::min(32u, n - c));
        while (m) {
            const uint32_t j = c + uint32_t(__builtin_ctz(m));
            m &= m - 1;
            fn(j);
        }
    }
}

// Entry i starts at bit `start` and must end by `limit` (bits from m.data; the block's padding
// follows `limit`).
Result validateEntry(const PfrepModel& m, uint32_t i, uint64_t start, uint64_t limit, uint64_t& original_triangles,
                     Entry& out) {
    const uint8_t* s = m.data;
    // The header is at most 6+16+3+16+1+5+5 bits: reading it stays in the padding.
    if (start >= limit) return Result::OutOfBounds;
    const Entry e = decodeHeader(s, start);
    if (e.end_bit > limit) return Result::OutOfBounds;
    if (e.neighbour_width > 31 || e.dependency_width > 31) return Result::BadStructure;
    if (e.neighbours > 0 && e.neighbour_width == 0 && uint64_t(i) + 1 >= m.vertex_count) return Result::OutOfBounds;
    for (uint32_t j = 0; j < e.neighbours; ++j) {
        const uint64_t a = uint64_t(i) + 1 + bitsAt(s, e.neighbour_bit + uint64_t(j) * e.neighbour_width, e.neighbour_width);
        if (a >= m.vertex_count) return Result::OutOfBounds;
    }
    out = e;
    bool degenerate = false;
    auto check = [&](uint32_t j) {
        const uint32_t next = j + 1 == e.neighbours ? 0 : j + 1;
        if (neighbourAt(s, e, i, j) == neighbourAt(s, e, i, next)) degenerate = true;
    };
    uint64_t bit = e.first_mask_bit;
    if (e.has_original) {
        forEachSlot(s, bit, e.neighbours, [&](uint32_t j) {
            check(j);
            ++original_triangles;
        });
        bit += e.neighbours;
    }
    uint32_t previous = 0;
    for (uint32_t k = 0; k < e.dependencies; ++k) {
        const uint32_t delta = bitsAt(s, bit, e.dependency_width);
        bit += e.dependency_width;
        // Dependencies rank strictly below the entry: simplify/insert closures always terminate.
        if (delta >= i) return Result::BadStructure;
        const uint32_t d = i - 1 - delta;
        if (d >= m.removed_count) return Result::BadStructure;
        // Strictly increasing: extraction stops at the first dependency not yet removed.
        if (k > 0 && d <= previous) return Result::BadStructure;
        previous = d;
        forEachSlot(s, bit, e.neighbours, check);
        bit += e.neighbours;
    }
    if (degenerate) return Result::BadStructure;
    return Result::Ok;
}

// Emits the triangles of entry i visible under `keep(d)` (d = dependency; kNone for originals).
constexpr uint32_t kNoDependency = 0xffffffffu;

template <typename Keep, typename Emit>
inline bool visitEntry(const PfrepModel& m, const uint8_t* s, uint32_t i, Keep&& keep, Emit&& emit) {
    const Entry e = decodeHeader(s, entryStart(m, i));
    uint64_t bit = e.first_mask_bit;
    bool ok = true;
    if (e.has_original) {
        if (keep(kNoDependency))
            forEachSlot(s, bit, e.neighbours, [&](uint32_t j) {
                const uint32_t next = j + 1 == e.neighbours ? 0 : j + 1;
                ok &= emit(e, j, neighbourAt(s, e, i, j), neighbourAt(s, e, i, next));
            });
        bit += e.neighbours;
    }
    for (uint32_t k = 0; k < e.dependencies; ++k) {
        const uint32_t d = i - 1 - bitsAt(s, bit, e.dependency_width);
        bit += e.dependency_width;
        if (keep(d))
            forEachSlot(s, bit, e.neighbours, [&](uint32_t j) {
                const uint32_t next = j + 1 == e.neighbours ? 0 : j + 1;
                ok &= emit(e, j, neighbourAt(s, e, i, j), neighbourAt(s, e, i, next));
            });
        bit += e.neighbours;
    }
    return ok;
}

// True when the 64 mask bytes at p are all ones (every vertex removed): 4 vector loads with SSE2, 8
// word loads otherwise. Mask scans are most of a step's memory traffic.
inline bool allRemoved64(const uint8_t* p) {
#if defined(__SSE2__)
    const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
    const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 16));
    const __m128i c = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 32));
    const __m128i d = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 48));
    const __m128i x = _mm_and_si128(_mm_and_si128(a, b), _mm_and_si128(c, d));
    return _mm_movemask_epi8(_mm_cmpeq_epi8(x, _mm_set1_epi8(char(-1)))) == 0xffff;
#else
    uint64_t all = ~uint64_t(0);
    for (int k = 0; k < 8; ++k) {
        uint64_t x;
        std::memcpy(&x, p + 8 * k, 8);
        all &= x;
    }
    return all == ~uint64_t(0);
#endif
}

// Calls fn(i) for every vertex whose mask bit is 0 (present), 64 bits at a time; fn may change the
// mask (a bit cleared ahead in the current word is then skipped until the next pass).
template <typename Fn> inline bool forEachPresent(const PfrepModel& m, const uint8_t* mask, Fn&& fn) {
    const size_t bytes = pfrepMaskBytes(m);
    // Start at the first loaded vertex's word: the bits below are set in a well-formed mask. A
    // region model may have resident vertices anywhere; its non-resident bits are set in a
    // well-formed mask, and their bytes in the decoded buffer are validated or zero either way.
    const uint32_t from = m.resident ? 0 : m.loaded_from;
    size_t b = size_t(from / 64) * 8;
    auto word = [&](size_t at) {
        uint64_t w;
        std::memcpy(&w, mask + at, 8);
        uint64_t present = ~w;
        while (present) {
            const uint32_t i = uint32_t(at * 8) + uint32_t(__builtin_ctzll(present));
            present &= present - 1;
            if (i >= m.vertex_count) return 1;
            if (i < from) continue; // not loaded (a well-formed mask has these bits set)
            if (!fn(i)) return 0;
        }
        return 2;
    };
    // Groups of 8 words: a group of removed vertices (the usual case far from the camera) costs one
    // test; in any other group each word is read when it is reached (fn may have changed it).
    for (; b + 64 <= bytes; b += 64) {
        if (allRemoved64(mask + b)) continue;
        for (size_t k = 0; k < 64; k += 8) {
            const int r = word(b + k);
            if (r != 2) return r == 1;
        }
    }
    for (; b + 8 <= bytes; b += 8) {
        const int r = word(b);
        if (r != 2) return r == 1;
    }
    for (; b < bytes; ++b) {
        uint32_t present = uint32_t(~mask[b]) & 0xffu;
        while (present) {
            const uint32_t i = uint32_t(b * 8) + uint32_t(__builtin_ctz(present));
            present &= present - 1;
            if (i >= m.vertex_count) return true;
            if (i < from) continue;
            if (!fn(i)) return false;
        }
    }
    return true;
}

struct LogTable {
    float value[256];
    LogTable() {
        value[0] = 0.0f;
        for (int c = 1; c < 256; ++c) value[c] = std::exp2(float(c - 1) / float(format::kPfrepLogCodeSteps));
    }
};

// Built once at load time (constant afterwards): no initialisation guard on the per-vertex path.
const LogTable kLogTable;

float logValue(const PfrepModel& m, uint32_t code) { return m.error_unit * kLogTable.value[code & 255]; }

} // namespace

namespace {

// Header and directory of data[0, size): everything but the blocks. Truncated when they are cut.
Result openHeader(const uint8_t* p, size_t size, PfrepModel& m) {
    if (size < format::kPfrepHeaderSize) return Result::Truncated;
    if (loadU32(p) != format::kPfrepMagic) return Result::BadMagic;
    if (loadU32(p + 4) != format::kPfrepVersion) return Result::UnsupportedVersion;
    m.data = p;
    m.vertex_count = loadU32(p + 8);
    m.removed_count = loadU32(p + 12);
    m.block_shift = loadU32(p + 16);
    m.level0_triangles = loadU32(p + 20);
    for (int k = 0; k < 3; ++k) {
        m.position_min[k] = loadF32(p + 24 + 4 * k);
        m.position_step[k] = loadF32(p + 36 + 4 * k);
        if (!std::isfinite(m.position_min[k]) || !std::isfinite(m.position_step[k]) || m.position_step[k] < 0)
            return Result::BadStructure;
    }
    m.error_unit = loadF32(p + 48);
    if (!std::isfinite(m.error_unit) || m.error_unit < 0) return Result::BadStructure;
    m.blob_size = loadU32(p + 52);
    m.block_count = loadU32(p + 56);
    if (m.vertex_count > format::kPfrepMaxVertices || m.removed_count > m.vertex_count ||
        m.block_shift > format::kPfrepMaxBlockShift || loadU32(p + 60) != 0)
        return Result::BadStructure;
    const uint64_t blocks = (uint64_t(m.vertex_count) + (uint64_t(1) << m.block_shift) - 1) >> m.block_shift;
    if (m.block_count != blocks) return Result::BadStructure;
    const uint64_t directory_end = format::kPfrepHeaderSize + blocks * 4;
    if (directory_end > m.blob_size) return Result::OutOfBounds;
    if (size > m.blob_size) return Result::TrailingBytes;
    if (size < directory_end) return Result::Truncated;
    // Blocks back to back in decreasing b, each at least as long as its records, offsets and padding.
    uint64_t at = directory_end;
    for (uint32_t b = m.block_count; b-- > 0;) {
        if (blockOffset(m, b) != at) return Result::OutOfBounds;
        const uint64_t end = blockEnd(m, b);
        if (end < at + uint64_t(blockVertices(m, b)) * (format::kPfrepVertexRecordSize + 2) + format::kPfrepStreamPadding)
            return Result::OutOfBounds;
        at = end;
    }
    m.size = size_t(directory_end);
    m.loaded_blocks = 0;
    m.loaded_from = m.vertex_count;
    m.loaded_original_triangles = 0;
    m.max_fan_neighbours = 0;
    m.max_radius = 0;
    m.max_error = 0;
    return Result::Ok;
}

// Validates the blocks that data[0, size) holds beyond those already loaded into m.
Result loadBlocks(PfrepModel& m, size_t size) {
    uint64_t original = m.loaded_original_triangles;
    uint32_t max_neighbours = m.max_fan_neighbours;
    uint32_t max_radius_code = 0, max_error_code = 0;
    uint32_t loaded = m.loaded_blocks;
    while (loaded < m.block_count) {
        const uint32_t b = m.block_count - 1 - loaded;
        const uint64_t start = blockOffset(m, b), end = blockEnd(m, b);
        if (end > size) break;
        const uint32_t first = b << m.block_shift, count = blockVertices(m, b);
        const uint64_t stream = start + uint64_t(count) * (format::kPfrepVertexRecordSize + 2);
        const uint64_t stream_end = end - format::kPfrepStreamPadding;
        for (uint64_t k = stream_end; k < end; ++k)
            if (m.data[k] != 0) return Result::BadStructure;
        // Entries are contiguous inside a block (each starts at the byte after the previous one
        // ends), so progressive extraction walks a block's stream without its offsets.
        uint64_t expected = stream * 8;
        for (uint32_t i = first; i < first + count; ++i) {
            if (entryStart(m, i) != expected) return Result::BadStructure;
            Entry e;
            const Result r = validateEntry(m, i, expected, stream_end * 8, original, e);
            if (r != Result::Ok) return r;
            max_neighbours = std::max(max_neighbours, e.neighbours);
            expected = (e.end_bit + 7) & ~uint64_t(7);
            const uint8_t* rec = record(m, i);
            max_radius_code = std::max<uint32_t>(max_radius_code, rec[6]);
            max_error_code = std::max<uint32_t>(max_error_code, rec[7]);
        }
        if (expected != stream_end * 8) return Result::BadStructure;
        if (original > m.level0_triangles) return Result::BadStructure;
        ++loaded;
    }
    if (loaded == m.block_count && original != m.level0_triangles) return Result::BadStructure;
    m.loaded_blocks = loaded;
    m.loaded_from = loaded == 0 ? m.vertex_count : (m.block_count - loaded) << m.block_shift;
    m.loaded_original_triangles = uint32_t(original);
    m.max_fan_neighbours = max_neighbours;
    m.max_radius = std::max(m.max_radius, logValue(m, max_radius_code));
    m.max_error = std::max(m.max_error, logValue(m, max_error_code));
    m.size = size;
    return Result::Ok;
}

} // namespace

Result openPfrepPrefix(const void* data, size_t size, PfrepModel* model) {
    if (!model || (!data && size > 0)) return Result::InvalidArgument;
    if (size < format::kPfrepHeaderSize) return Result::Truncated;
    PfrepModel m;
    Result r = openHeader(static_cast<const uint8_t*>(data), size, m);
    if (r != Result::Ok) return r;
    r = loadBlocks(m, size);
    if (r != Result::Ok) return r;
    *model = m;
    return Result::Ok;
}

Result openPfrep(const void* data, size_t size, PfrepModel* model) {
    if (!data || !model) return Result::InvalidArgument;
    PfrepModel m;
    Result r = openHeader(static_cast<const uint8_t*>(data), size, m);
    if (r != Result::Ok) return r;
    if (size < m.blob_size) return Result::Truncated;
    r = loadBlocks(m, size);
    if (r != Result::Ok) return r;
    *model = m;
    return Result::Ok;
}

Result pfrepExtendPrefix(PfrepModel* model, const void* data, size_t size) {
    if (!model || !data || size < model->size || model->data == nullptr) return Result::InvalidArgument;
    if (size > model->blob_size) return Result::TrailingBytes;
    PfrepModel m = *model;
    m.data = static_cast<const uint8_t*>(data);
    m.criterion_table = nullptr; // it does not cover the new blocks: attach it again
    const Result r = loadBlocks(m, size);
    if (r != Result::Ok) return r;
    *model = m;
    return Result::Ok;
}

uint64_t pfrepPrefixBytesForLevel(const PfrepModel& m, uint32_t level) {
    if (level >= m.vertex_count) return format::kPfrepHeaderSize + uint64_t(m.block_count) * 4;
    return blockEnd(m, level >> m.block_shift);
}

uint64_t pfrepDirectoryBytes(const void* header, size_t size) {
    if (!header || size < format::kPfrepHeaderSize) return 0;
    const uint8_t* p = static_cast<const uint8_t*>(header);
    if (loadU32(p) != format::kPfrepMagic || loadU32(p + 4) != format::kPfrepVersion) return 0;
    return format::kPfrepHeaderSize + uint64_t(loadU32(p + 56)) * 4;
}

Result pfrepDecodePositions(const PfrepModel& m, float* out, size_t capacity) {
    if (!out && m.vertex_count > 0) return Result::InvalidArgument;
    if (capacity < size_t(m.vertex_count) * 3) return Result::BufferTooSmall;
    std::fill(out, out + size_t(m.loaded_from) * 3, 0.0f);
    for (uint32_t v = m.resident ? 0 : m.loaded_from; v < m.vertex_count; ++v) {
        if (!isResident(m, v)) continue;
        const uint8_t* r = record(m, v);
        for (int k = 0; k < 3; ++k) out[size_t(v) * 3 + k] = m.position_min[k] + float(loadU16(r + 2 * k)) * m.position_step[k];
    }
    return Result::Ok;
}

Result pfrepExtractLevel(const PfrepModel& m, uint32_t level, uint32_t* indices, size_t capacity,
                         size_t* triangle_count) {
    if (!triangle_count || (!indices && capacity > 0) || level > m.removed_count) return Result::InvalidArgument;
    if (level < m.loaded_from) return Result::NotLoaded;
    const uint8_t* s = m.data;
    size_t count = 0;
    if (level >= m.vertex_count) {
        *triangle_count = 0;
        return Result::Ok;
    }
    uint64_t bit = entryStart(m, level);
    uint32_t ring[65];
    const uint32_t block_mask = (uint32_t(1) << m.block_shift) - 1;
    for (uint32_t i = level; i < m.vertex_count; ++i) {
        // Blocks are stored in decreasing order: the next block's stream is elsewhere.
        if ((i & block_mask) == 0) bit = entryStart(m, i);
        const Entry e = decodeHeader(s, bit);
        bit = (e.end_bit + 7) & ~uint64_t(7);
        const uint32_t n = e.neighbours;
        if (n > 64) {
            // Rare wide fans: the general path.
            const bool fits = visitEntry(
                m, s, i, [level](uint32_t d) { return d == kNoDependency || d < level; },
                [&](const Entry&, uint32_t, uint32_t a, uint32_t b) {
                    if (count == capacity) return false;
                    uint32_t* t = indices + count * 3;
                    t[0] = i;
                    t[1] = a;
                    t[2] = b;
                    ++count;
                    return true;
                });
            if (!fits) {
                *triangle_count = count;
                return Result::BufferTooSmall;
            }
            continue;
        }
        // The ring is decoded only once a group is kept; dependencies are stored in increasing
        // order, so the first one at or above `level` ends the entry.
        bool ring_ready = false;
        uint64_t mb = e.first_mask_bit;
        const uint32_t groups = e.dependencies + (e.has_original ? 1 : 0);
        for (uint32_t g = 0; g < groups; ++g) {
            if (g > 0 || !e.has_original) {
                const uint32_t d = i - 1 - bitsAt(s, mb, e.dependency_width);
                mb += e.dependency_width;
                if (d >= level) break;
            }
            {
                if (!ring_ready) {
                    const uint32_t w = e.neighbour_width;
                    uint64_t nb = e.neighbour_bit;
                    for (uint32_t j = 0; j < n; ++j, nb += w) ring[j] = i + 1 + bitsAt(s, nb, w);
                    ring[n] = ring[0];
                    ring_ready = true;
                }
                uint64_t bits = bitsAt(s, mb, std::min(n, 32u));
                if (n > 32) bits |= uint64_t(bitsAt(s, mb + 32, n - 32)) << 32;
                if (size_t(__builtin_popcountll(bits)) > capacity - count) {
                    *triangle_count = count;
                    return Result::BufferTooSmall;
                }
                uint32_t* t = indices + count * 3;
                count += size_t(__builtin_popcountll(bits));
                while (bits) {
                    const uint32_t j = uint32_t(__builtin_ctzll(bits));
                    bits &= bits - 1;
                    t[0] = i;
                    t[1] = ring[j];
                    t[2] = ring[j + 1];
                    t += 3;
                }
            }
            mb += n;
        }
    }
    *triangle_count = count;
    return Result::Ok;
}

Result pfrepExtractLevelFans(const PfrepModel& m, uint32_t level, uint32_t* values, size_t capacity,
                             size_t* value_count) {
    if (!value_count || (!values && capacity > 0) || level > m.removed_count) return Result::InvalidArgument;
    if (level < m.loaded_from) return Result::NotLoaded;
    const uint8_t* s = m.data;
    size_t used = 0;
    bool fits = true;
    for (uint32_t i = level; i < m.vertex_count && fits; ++i) {
        // Consecutive slots of one entry extend the open fan; anything else starts a new record.
        size_t record = size_t(-1);
        uint32_t last_slot = 0;
        fits = visitEntry(
            m, s, i, [level](uint32_t d) { return d == kNoDependency || d < level; },
            [&](const Entry&, uint32_t j, uint32_t a, uint32_t b) {
                if (record != size_t(-1) && j == last_slot + 1 && values[used - 1] == a) {
                    if (used == capacity) return false;
                    values[used++] = b;
                    ++values[record];
                } else {
                    if (capacity - used < 4) return false;
                    record = used;
                    values[used++] = 1;
                    values[used++] = i;
                    values[used++] = a;
                    values[used++] = b;
                }
                last_slot = j;
                return true;
            });
    }
    *value_count = used;
    return fits ? Result::Ok : Result::BufferTooSmall;
}

namespace {
// Mask with exactly the ranks below `end` set.
void maskBelow(const PfrepModel& m, uint8_t* mask, uint32_t end) {
    std::memset(mask, 0, pfrepMaskBytes(m));
    const uint32_t full = end >> 3;
    std::memset(mask, 0xff, full);
    for (uint32_t v = full * 8; v < end; ++v) setBit(mask, v);
    if (!m.resident) return;
    // Region model: every non-resident vertex counts as removed (bits beyond vertex_count stay 0).
    const size_t bytes = pfrepMaskBytes(m);
    for (size_t k = 0; k < bytes; ++k) {
        const uint32_t valid = k + 1 < bytes || m.vertex_count % 8 == 0 ? 0xffu : (1u << (m.vertex_count % 8)) - 1;
        mask[k] = uint8_t(mask[k] | (~m.resident[k] & valid));
    }
}
} // namespace

void pfrepMaskFinest(const PfrepModel& m, uint8_t* mask) {
    if (mask) maskBelow(m, mask, m.resident ? 0 : m.loaded_from);
}

void pfrepMaskCoarsest(const PfrepModel& m, uint8_t* mask) {
    if (mask) maskBelow(m, mask, m.resident ? m.removed_count : std::max(m.removed_count, m.loaded_from));
}

namespace {

// Removes `vertex` and its simplification closure, recording every vertex it removes in
// scratch[0, n) (each once: a vertex is marked when queued, so n <= vertex_count). `veto(d)` is
// asked for every dependency before it is taken; when it says yes the closure stops, every bit it
// set is cleared again and 0 is returned. Returns n otherwise.
template <typename Veto>
size_t simplifyClosure(const PfrepModel& m, uint8_t* mask, uint32_t vertex, uint32_t* scratch, Veto&& veto) {
    const uint8_t* s = m.data;
    size_t queued = 0, next = 0;
    setBit(mask, vertex);
    scratch[queued++] = vertex;
    while (next < queued) {
        const uint32_t x = scratch[next++];
        if (!isResident(m, x)) continue; // not loaded (a malformed mask): its entry is not read
        const Entry e = decodeHeader(s, entryStart(m, x));
        uint64_t bit = e.first_mask_bit + (e.has_original ? e.neighbours : 0);
        for (uint32_t k = 0; k < e.dependencies; ++k) {
            const uint32_t d = x - 1 - bitsAt(s, bit, e.dependency_width);
            bit += e.dependency_width + e.neighbours;
            if (maskBit(mask, d)) continue;
            if (veto(d)) {
                for (size_t q = 0; q < queued; ++q) clearBit(mask, scratch[q]);
                return 0;
            }
            setBit(mask, d);
            scratch[queued++] = d;
        }
    }
    return queued;
}

// Inserts `vertex` (removed, resident) and its insertion closure; returns the number of bits
// cleared. kRegion: the closure may reach a non-resident vertex (a region model whose needed blocks
// are not all loaded); it is then abandoned before that vertex's entry is read, every bit it cleared
// is set again and 0 is returned. Popped vertices are kept at the end of the scratch for that
// (heap + popped <= vertices cleared <= vertex_count). In a prefix model every corner ranks above a
// loaded vertex, so it is loaded: no check.
template <bool kRegion>
size_t insertClosure(const PfrepModel& m, uint8_t* mask, uint32_t vertex, uint32_t* scratch) {
    const uint8_t* s = m.data;
    // A min-heap: vertices are processed in increasing rank, and every insertion pushes only higher
    // ranks, so a dependency's state is final when its triangles are examined.
    size_t top = 0, cleared = 1, popped = 0;
    bool missing = false;
    auto greater = [](uint32_t a, uint32_t b) { return a > b; };
    clearBit(mask, vertex);
    scratch[top++] = vertex;
    while (top > 0) {
        std::pop_heap(scratch, scratch + top, greater);
        const uint32_t x = scratch[--top];
        if (kRegion) scratch[size_t(m.vertex_count) - 1 - popped++] = x;
        visitEntry(
            m, s, x, [&](uint32_t d) { return d == kNoDependency || maskBit(mask, d); },
            [&](const Entry&, uint32_t, uint32_t a, uint32_t b) {
                for (uint32_t c : {a, b}) {
                    if (maskBit(mask, c)) {
                        if (kRegion && (missing || !maskBit(m.resident, c))) {
                            missing = true;
                            return true;
                        }
                        clearBit(mask, c);
                        ++cleared;
                        scratch[top++] = c;
                        std::push_heap(scratch, scratch + top, greater);
                    }
                }
                return true;
            });
        if (kRegion && missing) {
            for (size_t q = 0; q < top; ++q) setBit(mask, scratch[q]);
            for (size_t q = 0; q < popped; ++q) setBit(mask, scratch[size_t(m.vertex_count) - 1 - q]);
            return 0;
        }
    }
    return cleared;
}

size_t insertClosure(const PfrepModel& m, uint8_t* mask, uint32_t vertex, uint32_t* scratch) {
    return m.resident ? insertClosure<true>(m, mask, vertex, scratch) : insertClosure<false>(m, mask, vertex, scratch);
}

} // namespace

Result pfrepSimplifyVertex(const PfrepModel& m, uint8_t* mask, uint32_t vertex, uint32_t* scratch,
                           size_t scratch_capacity) {
    if (!mask || !scratch || scratch_capacity < pfrepScratchValues(m) || vertex >= m.vertex_count)
        return Result::InvalidArgument;
    if (vertex >= m.removed_count || maskBit(mask, vertex)) return Result::Ok;
    simplifyClosure(m, mask, vertex, scratch, [](uint32_t) { return false; });
    return Result::Ok;
}

Result pfrepInsertVertex(const PfrepModel& m, uint8_t* mask, uint32_t vertex, uint32_t* scratch,
                         size_t scratch_capacity) {
    if (!mask || !scratch || scratch_capacity < pfrepScratchValues(m) || vertex >= m.vertex_count)
        return Result::InvalidArgument;
    if (!maskBit(mask, vertex)) return Result::Ok;
    if (!isResident(m, vertex)) return Result::NotLoaded;
    // A region closure that meets a non-resident vertex leaves the mask as it was.
    return insertClosure(m, mask, vertex, scratch) > 0 ? Result::Ok : Result::NotLoaded;
}

Result pfrepExtractSelective(const PfrepModel& m, const uint8_t* mask, uint32_t* indices, size_t capacity,
                             size_t* triangle_count) {
    if (!mask || !triangle_count || (!indices && capacity > 0)) return Result::InvalidArgument;
    if (m.loaded_from > m.removed_count) return Result::NotLoaded;
    const uint8_t* s = m.data;
    size_t count = 0;
    bool fits = true;
    fits = forEachPresent(m, mask, [&](uint32_t i) {
        return visitEntry(
            m, s, i, [mask](uint32_t d) { return d == kNoDependency || maskBit(mask, d); },
            [&](const Entry&, uint32_t, uint32_t a, uint32_t b) {
                if (maskBit(mask, a) || maskBit(mask, b)) return true;
                if (count == capacity) return false;
                uint32_t* t = indices + count * 3;
                t[0] = i;
                t[1] = a;
                t[2] = b;
                ++count;
                return true;
            });
    });
    *triangle_count = count;
    return fits ? Result::Ok : Result::BufferTooSmall;
}


namespace {

constexpr float kHalfPi = 1.5707963f;
constexpr size_t kCriterionStride = 8; // floats per vertex: x, y, z, radius, error, cone axis x, y, z

// Cone half-angle codes (one byte per vertex) after the 8 V floats of a criterion table.
const uint8_t* criterionConeCodes(const PfrepModel& m) {
    return reinterpret_cast<const uint8_t*>(m.criterion_table + size_t(m.vertex_count) * kCriterionStride);
}

// Cone half-angles of the 4-bit code (c / 15 · π) with their sine and cosine.
struct ConeTable {
    float angle[16], sin[16], cos[16];
    ConeTable() {
        for (int c = 0; c < 16; ++c) {
            angle[c] = float(c) / 15.0f * 3.14159265f;
            sin[c] = std::sin(angle[c]);
            cos[c] = std::cos(angle[c]);
        }
    }
};

const ConeTable kConeTable;

const ConeTable& coneTable() { return kConeTable; }

// Octahedral axis, 6 bits per coordinate (bits 0-11 of the cone code), normalized.
void decodeConeAxis(uint16_t cone, float axis[3]) {
    float x = float(cone & 63) / 63.0f * 2.0f - 1.0f;
    float y = float((cone >> 6) & 63) / 63.0f * 2.0f - 1.0f;
    const float z = 1.0f - std::fabs(x) - std::fabs(y);
    if (z < 0) {
        const float ox = x;
        x = (1.0f - std::fabs(y)) * (ox >= 0 ? 1.0f : -1.0f);
        y = (1.0f - std::fabs(ox)) * (y >= 0 ? 1.0f : -1.0f);
    }
    const float len = std::sqrt(x * x + y * y + z * z);
    axis[0] = len > 0 ? x / len : 0;
    axis[1] = len > 0 ? y / len : 0;
    axis[2] = len > 0 ? z / len : 1;
}

// One threshold of Hoppe's criterion: the screen-error tolerance and the widening of the frustum
// and back-face tests (0 for insertion; the hysteresis band for keeping a present vertex).
struct Criterion {
    float tolerance_px = 1.0f;
    float reach_per_error = 0.0f; // pixels_per_unit_at_distance_one / tolerance_px (when tolerance_px > 0)
    float band = 0.0f;            // radians
    float sin_band = 0.0f, cos_band = 1.0f;
    uint32_t planes = 0x3f; // frustum planes to test (bit p: plane p); the others hold for the whole instance
};

Criterion criterion(const PfrepView& view, float error_scale, float band) {
    Criterion c;
    c.tolerance_px = error_scale * view.pixel_tolerance;
    if (c.tolerance_px > 0.0f) c.reach_per_error = view.pixels_per_unit_at_distance_one / c.tolerance_px;
    c.band = band;
    c.sin_band = std::sin(band);
    c.cos_band = std::cos(band);
    return c;
}

// Outcome of the criterion. Bounds: the sphere is outside the (widened) frustum or its error is
// below tolerance; the bounds of a vertex contain those of its dependencies (docs/format/pfrep.md),
// so they fail too. Facing: back-facing only (says nothing about the dependencies).
enum class Test { Wanted, Bounds, Facing };

// kBoundsOnly: only the sphere tests (frustum and screen error), never Facing.
template <bool kBoundsOnly = false>
Test test(const PfrepModel& m, const PfrepView& view, const Criterion& c, uint32_t vertex) {
    // From the criterion table when one is attached (8 floats per vertex, the values below
    // exactly), else from the vertex record.
    const float* t = m.criterion_table ? m.criterion_table + size_t(vertex) * kCriterionStride : nullptr;
    const uint8_t* r = t ? nullptr : record(m, vertex);
    float p[3], radius, error;
    if (t) {
        p[0] = t[0];
        p[1] = t[1];
        p[2] = t[2];
        radius = t[3];
        error = t[4];
    } else {
        for (int k = 0; k < 3; ++k) p[k] = m.position_min[k] + float(loadU16(r + 2 * k)) * m.position_step[k];
        radius = logValue(m, r[6]);
        error = logValue(m, r[7]);
    }
    const float dx = p[0] - view.eye[0], dy = p[1] - view.eye[1], dz = p[2] - view.eye[2];
    const float dist2 = dx * dx + dy * dy + dz * dz;
    const bool outside_sphere = dist2 > radius * radius;
    // Screen-space error first, without a square root: it rejects most vertices of distant
    // instances. error · ppu > tolerance · (dist − radius)  <=>  dist < radius + error · ppu / tolerance.
    if (outside_sphere) {
        if (c.tolerance_px > 0.0f) {
            const float reach = radius + error * c.reach_per_error;
            if (!(dist2 < reach * reach)) return Test::Bounds;
        } else if (!(error * view.pixels_per_unit_at_distance_one > c.tolerance_px * (std::sqrt(dist2) - radius))) {
            return Test::Bounds;
        }
    }
    // The band turns each plane outwards about the eye by `band`: a sphere that left the frustum
    // by less than that angle is still inside for a vertex already present.
    if (c.planes != 0) {
        const float slack = radius + (c.sin_band > 0.0f ? c.sin_band * std::sqrt(dist2) : 0.0f);
        for (uint32_t todo = c.planes; todo; todo &= todo - 1) {
            const float* plane = view.planes[__builtin_ctz(todo)];
            if (plane[0] * p[0] + plane[1] * p[1] + plane[2] * p[2] + plane[3] < -slack) return Test::Bounds;
        }
    }
    if (kBoundsOnly || !outside_sphere) return Test::Wanted;
    const uint16_t cone = t ? 0 : loadU16(r + 8);
    const uint32_t a = t ? criterionConeCodes(m)[vertex] : uint32_t(cone >> 12);
    const ConeTable& table = coneTable();
    if (table.angle[a] + c.band < kHalfPi) {
        // Back-facing when every normal of the cone, widened by the band, points away from the eye
        // (Hoppe 1997 §4.2): the view direction is within pi/2 - angle of the axis.
        float axis[3];
        if (t) {
            axis[0] = t[5];
            axis[1] = t[6];
            axis[2] = t[7];
        } else {
            decodeConeAxis(cone, axis);
        }
        const float along = axis[0] * dx + axis[1] * dy + axis[2] * dz;
        const float sin_a = table.sin[a] * c.cos_band + table.cos[a] * c.sin_band;
        if (along > 0 && along * along > dist2 * sin_a * sin_a) return Test::Facing;
    }
    return Test::Wanted;
}

bool wanted(const PfrepModel& m, const PfrepView& view, const Criterion& c, uint32_t vertex) {
    return test(m, view, c, vertex) == Test::Wanted;
}

// The instance as a whole against the view. Every vertex position lies in the quantization box
// [position_min, position_min + 65535 step] and every radius / error is at most max_radius /
// max_error, so one box test settles a plane for all vertices, or all vertices at once.
struct InstanceBox {
    float lo[3], hi[3];
};

InstanceBox instanceBox(const PfrepModel& m) {
    InstanceBox b;
    for (int k = 0; k < 3; ++k) {
        b.lo[k] = m.position_min[k];
        b.hi[k] = m.position_min[k] + 65535.0f * m.position_step[k];
    }
    return b;
}

// Relative margin that absorbs the rounding differences between box and per-vertex arithmetic.
constexpr float kBoxMargin = 1e-4f;

// Clears the bits of the planes every point of the box is inside of (their test cannot fail: the
// slack is never negative).
void dropContainingPlanes(const PfrepView& view, const InstanceBox& b, Criterion& c) {
    for (int p = 0; p < 6; ++p) {
        const float* plane = view.planes[p];
        float low = plane[3], scale = std::fabs(plane[3]);
        for (int k = 0; k < 3; ++k) {
            low += plane[k] * (plane[k] >= 0 ? b.lo[k] : b.hi[k]);
            scale += std::fabs(plane[k]) * std::max(std::fabs(b.lo[k]), std::fabs(b.hi[k]));
        }
        if (low > kBoxMargin * scale) c.planes &= ~(1u << p);
    }
}

// True when every vertex fails the bounds test of `c` (and so of any stricter criterion): the box
// is beyond the reach of the largest error, or entirely outside a plane by more than the largest slack.
bool instanceRejected(const PfrepModel& m, const PfrepView& view, const InstanceBox& b, const Criterion& c) {
    if (!(c.tolerance_px > 0.0f)) return false;
    const auto [near2, far2] = detail::eyeBoxDistance(view.eye, b.lo, b.hi);
    const float reach = m.max_radius + m.max_error * c.reach_per_error;
    if (near2 > reach * reach * (1.0f + kBoxMargin)) return true;
    const float slack = m.max_radius + c.sin_band * std::sqrt(far2);
    for (const auto& plane : view.planes) {
        float high = plane[3], scale = std::fabs(plane[3]);
        for (int k = 0; k < 3; ++k) {
            high += plane[k] * (plane[k] >= 0 ? b.hi[k] : b.lo[k]);
            scale += std::fabs(plane[k]) * std::max(std::fabs(b.lo[k]), std::fabs(b.hi[k]));
        }
        if (high < -slack - kBoxMargin * (scale + slack)) return true;
    }
    return false;
}

float keepScale(const PfrepView& view) {
    const float h = view.hysteresis;
    return h > 0.0f && h <= 1.0f ? h : 1.0f; // NaN and out-of-range values: no band
}

float cullBand(const PfrepView& view) {
    const float b = view.cull_hysteresis;
    return b >= 0.0f && b <= 0.5f ? b : 0.0f; // NaN and out-of-range values: no band
}

} // namespace

Result pfrepVertexBounds(const PfrepModel& m, uint32_t vertex, PfrepVertexBounds* out) {
    if (!out || vertex >= m.vertex_count) return Result::InvalidArgument;
    if (!isResident(m, vertex)) return Result::NotLoaded;
    const uint8_t* r = record(m, vertex);
    for (int k = 0; k < 3; ++k) out->position[k] = m.position_min[k] + float(loadU16(r + 2 * k)) * m.position_step[k];
    out->radius = logValue(m, r[6]);
    out->error = logValue(m, r[7]);
    const uint16_t cone = loadU16(r + 8);
    decodeConeAxis(cone, out->cone_axis);
    out->cone_angle = coneTable().angle[cone >> 12];
    return Result::Ok;
}

Result pfrepAttachCriterionTable(PfrepModel* model, float* table, size_t capacity) {
    if (!model || (!table && model->vertex_count > 0)) return Result::InvalidArgument;
    const PfrepModel& m = *model;
    if (capacity < pfrepCriterionTableFloats(m)) return Result::BufferTooSmall;
    uint8_t* codes = reinterpret_cast<uint8_t*>(table + size_t(m.vertex_count) * kCriterionStride);
    for (uint32_t v = m.resident ? 0 : m.loaded_from; v < m.vertex_count; ++v) {
        if (!isResident(m, v)) continue;
        const uint8_t* r = record(m, v);
        float* t = table + size_t(v) * kCriterionStride;
        for (int k = 0; k < 3; ++k) t[k] = m.position_min[k] + float(loadU16(r + 2 * k)) * m.position_step[k];
        t[3] = logValue(m, r[6]);
        t[4] = logValue(m, r[7]);
        const uint16_t cone = loadU16(r + 8);
        decodeConeAxis(cone, t + 5);
        codes[v] = uint8_t(cone >> 12);
    }
    model->criterion_table = table;
    return Result::Ok;
}

bool pfrepWanted(const PfrepModel& m, const PfrepView& view, uint32_t vertex) {
    if (vertex >= m.vertex_count || !isResident(m, vertex)) return false;
    return wanted(m, view, criterion(view, 1.0f, 0.0f), vertex);
}

Result pfrepRefine(const PfrepModel& m, const PfrepView& view, uint8_t* mask, uint32_t* scratch,
                   size_t scratch_capacity, size_t* changes) {
    if (!mask || !scratch || !changes || scratch_capacity < pfrepScratchValues(m)) return Result::InvalidArgument;
    if (m.loaded_from > m.removed_count) return Result::NotLoaded;
    const uint8_t* s = m.data;
    Criterion insert = criterion(view, 1.0f, 0.0f);
    Criterion keep = criterion(view, keepScale(view), cullBand(view));
    const size_t budget = view.max_changed_bits;
    size_t changed = 0;
    const InstanceBox box = instanceBox(m);
    if (instanceRejected(m, view, box, keep)) {
        // Every vertex fails the bounds test at both thresholds: the pass below would simplify each
        // present removable vertex in increasing rank (no veto, and each closure is that vertex
        // alone: its lower-ranked dependencies were simplified before it) and insert nothing.
        // Same result, without the per-vertex tests.
        const uint32_t end = m.removed_count;
        // Adds the present vertices among `valid` bits of word `w` (lowest ranks first, within the
        // budget); returns false once the budget is spent.
        auto take = [&](uint64_t& w, uint64_t valid) {
            uint64_t present = ~w & valid;
            if (budget > 0) {
                const size_t left = budget - changed;
                while (size_t(__builtin_popcountll(present)) > left)
                    present &= ~(uint64_t(1) << (63 - __builtin_clzll(present)));
            }
            changed += size_t(__builtin_popcountll(present));
            w |= present;
            return !(budget > 0 && changed >= budget);
        };
        const size_t full_words = end / 64;
        bool more = true;
        for (size_t word = 0; word < full_words && more;) {
            // Already coarse (the usual case): runs of all-ones are skipped 64 bytes at a time.
            if (word + 8 <= full_words && allRemoved64(mask + word * 8)) {
                word += 8;
                continue;
            }
            uint64_t w;
            std::memcpy(&w, mask + word * 8, 8);
            if (w != ~uint64_t(0)) {
                more = take(w, ~uint64_t(0));
                std::memcpy(mask + word * 8, &w, 8);
            }
            ++word;
        }
        if (more && end % 64 != 0) {
            const size_t bytes = (end % 64 + 7) / 8;
            uint64_t w = 0;
            std::memcpy(&w, mask + full_words * 8, bytes);
            take(w, (uint64_t(1) << (end % 64)) - 1);
            std::memcpy(mask + full_words * 8, &w, bytes);
        }
        *changes = changed;
        return Result::Ok;
    }
    dropContainingPlanes(view, box, insert);
    keep.planes = insert.planes;
    forEachPresent(m, mask, [&](uint32_t i) {
        if (budget > 0 && changed >= budget) return false;
        if (maskBit(mask, i)) return true; // simplified earlier in this pass
        // Bounds failing at the keep threshold fail at the stricter insert threshold too, for i and
        // (contained bounds) for all its dependencies: nothing of i's entry can be inserted.
        const Test kept = i < m.removed_count ? test(m, view, keep, i) : test(m, view, insert, i);
        if (i < m.removed_count && kept != Test::Wanted) {
            // A closure that would take a vertex still kept (criterion holds at the keep threshold)
            // is abandoned as soon as it meets one: otherwise the next pass would insert it again
            // and a static camera would toggle the same vertices every frame.
            const size_t n =
                simplifyClosure(m, mask, i, scratch, [&](uint32_t d) { return isResident(m, d) && wanted(m, view, keep, d); });
            if (n > 0) {
                changed += n;
                return true;
            }
        }
        if (kept == Test::Bounds) return true;
        // Between the thresholds: i passes the keep test, but when its sphere fails the stricter
        // insert test, so do the contained spheres of all its dependencies; skip decoding them.
        if (i < m.removed_count && test<true>(m, view, insert, i) == Test::Bounds) return true;
        const Entry e = decodeHeader(s, entryStart(m, i));
        uint64_t bit = e.first_mask_bit + (e.has_original ? e.neighbours : 0);
        for (uint32_t k = 0; k < e.dependencies; ++k) {
            const uint32_t d = i - 1 - bitsAt(s, bit, e.dependency_width);
            bit += e.dependency_width + e.neighbours;
            if (maskBit(mask, d) && isResident(m, d) && wanted(m, view, insert, d)) {
                changed += insertClosure(m, mask, d, scratch);
                if (budget > 0 && changed >= budget) return false;
            }
        }
        return true;
    });
    *changes = changed;
    return Result::Ok;
}

namespace detail {

uint64_t pfrepRecordOffset(const PfrepModel& m, uint32_t v) { return uint64_t(record(m, v) - m.data); }

uint64_t pfrepEntryOffset(const PfrepModel& m, uint32_t i) { return entryStart(m, i) / 8; }

uint64_t pfrepStreamEnd(const PfrepModel& m, uint32_t i) {
    return blockEnd(m, i >> m.block_shift) - format::kPfrepStreamPadding;
}

Result pfrepValidateEntryAt(const PfrepModel& m, uint32_t i, uint64_t begin, uint64_t end, uint64_t* originals,
                            uint32_t* neighbours) {
    uint64_t count = *originals;
    Entry e;
    const Result r = validateEntry(m, i, begin * 8, end * 8, count, e);
    if (r != Result::Ok) return r;
    // Canonical: the entry ends in the last byte of its range (as entries are contiguous in format 2).
    if (((e.end_bit + 7) & ~uint64_t(7)) != end * 8) return Result::BadStructure;
    *originals = count;
    *neighbours = e.neighbours;
    return Result::Ok;
}

size_t pfrepEntryNeighbours(const PfrepModel& m, uint32_t i, uint32_t* out, size_t capacity) {
    const Entry e = decodeHeader(m.data, entryStart(m, i));
    const size_t n = std::min<size_t>(e.neighbours, capacity);
    for (size_t j = 0; j < n; ++j) out[j] = neighbourAt(m.data, e, i, uint32_t(j));
    return e.neighbours;
}

float pfrepLogValue(const PfrepModel& m, uint32_t code) { return logValue(m, code); }

} // namespace detail

} // namespace lodrt
