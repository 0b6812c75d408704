// PFRep region blocks (docs/format/pfrep.md "Region blocks"): open the directory and skeleton,
// lay blocks into a format 2 buffer as they arrive, evict them, and list the blocks a view needs.
// Every byte is hostile: all offsets, counts, ranks and entries are checked before use.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "lodrt/detail/pfrep_region.h"
#include "lodrt/format.h"
#include "lodrt/pfrep.h"
#include "box_distance.h"
#include "little_endian.h"

namespace lodrt {
namespace {

using detail::loadF32;
using detail::loadU32;
using detail::storeU16;
using detail::storeU32;

// LEB128 (7 bits per byte, low first, at most 5 bytes for 32 bits). False when it runs past `end`
// or does not fit 32 bits.
bool readVarint(const uint8_t*& p, const uint8_t* end, uint32_t& out) {
    uint64_t v = 0;
    for (int shift = 0; shift < 35; shift += 7) {
        if (p == end) return false;
        const uint8_t b = *p++;
        v |= uint64_t(b & 0x7f) << shift;
        if (!(b & 0x80)) {
            if (v > 0xffffffffu) return false;
            out = uint32_t(v);
            return true;
        }
    }
    return false;
}

size_t align8(size_t n) {
    return (n + 7) & ~size_t(7);
}

// The state buffer: directory copy, resident bits, loaded flags, per-block input-triangle counts,
// first rank slot of each block, and every block's rank list (filled when it loads).
struct StateLayout {
    size_t blocks = 0, resident = 0, loaded = 0, originals = 0, first = 0, ranks = 0, total = 0;
};

StateLayout stateLayout(uint32_t vertices, uint32_t block_count) {
    StateLayout l;
    l.blocks = 0;
    l.resident = align8(sizeof(PfrepRegionBlock) * block_count);
    l.loaded = l.resident + align8((size_t(vertices) + 7) / 8);
    l.originals = l.loaded + align8(block_count);
    l.first = l.originals + align8(size_t(block_count) * 4);
    l.ranks = l.first + align8(size_t(block_count) * 4);
    l.total = l.ranks + align8(size_t(vertices) * 4);
    return l;
}

struct RegionHeader {
    uint32_t vertex_count, removed_count, block_count, decoded_size, skeleton_size, blob_size, max_codes;
};

Result readHeader(const uint8_t* p, size_t size, RegionHeader& h) {
    if (size < format::kPfrepRegionHeaderSize) return Result::Truncated;
    if (loadU32(p) != format::kPfrepRegionMagic) return Result::BadMagic;
    if (loadU32(p + 4) != format::kPfrepRegionVersion) return Result::UnsupportedVersion;
    h.vertex_count = loadU32(p + 8);
    h.removed_count = loadU32(p + 12);
    h.block_count = loadU32(p + 16);
    h.decoded_size = loadU32(p + 20);
    h.skeleton_size = loadU32(p + 24);
    h.blob_size = loadU32(p + 28);
    h.max_codes = loadU32(p + 32);
    for (uint32_t at = 36; at < format::kPfrepRegionHeaderSize; at += 4)
        if (loadU32(p + at) != 0) return Result::BadStructure;
    if (h.vertex_count == 0 || h.vertex_count > format::kPfrepMaxVertices || h.removed_count > h.vertex_count ||
        h.block_count == 0 || h.block_count > format::kPfrepRegionMaxBlocks || h.block_count > h.vertex_count ||
        (h.max_codes >> 16) != 0 || h.skeleton_size < format::kPfrepHeaderSize + h.vertex_count ||
        h.decoded_size < format::kPfrepHeaderSize)
        return Result::BadStructure;
    const uint64_t open = uint64_t(format::kPfrepRegionHeaderSize) +
                          uint64_t(h.block_count) * format::kPfrepRegionDirectoryRecordSize + h.skeleton_size;
    if (open > h.blob_size) return Result::BadStructure;
    return Result::Ok;
}

uint64_t openBytes(const RegionHeader& h) {
    return uint64_t(format::kPfrepRegionHeaderSize) +
           uint64_t(h.block_count) * format::kPfrepRegionDirectoryRecordSize + h.skeleton_size;
}

// The directory into `blocks`: back to back from open_bytes to blob_size, vertex counts summing to V,
// finite bounds.
Result readDirectory(const uint8_t* p, const RegionHeader& h, PfrepRegionBlock* blocks) {
    uint64_t at = openBytes(h), vertices = 0;
    for (uint32_t k = 0; k < h.block_count; ++k) {
        const uint8_t* r = p + format::kPfrepRegionHeaderSize + size_t(k) * format::kPfrepRegionDirectoryRecordSize;
        PfrepRegionBlock b;
        b.offset = loadU32(r);
        b.size = loadU32(r + 4);
        b.vertices = loadU32(r + 8);
        for (int c = 0; c < 3; ++c) {
            b.lo[c] = loadF32(r + 12 + 4 * c);
            b.hi[c] = loadF32(r + 24 + 4 * c);
            if (!std::isfinite(b.lo[c]) || !std::isfinite(b.hi[c]) || !(b.lo[c] <= b.hi[c]))
                return Result::BadStructure;
        }
        b.max_error = loadF32(r + 36);
        if (!std::isfinite(b.max_error) || b.max_error < 0) return Result::BadStructure;
        if (b.offset != at || b.vertices == 0) return Result::OutOfBounds;
        // At least one rank byte and one record per vertex.
        if (uint64_t(b.size) < uint64_t(b.vertices) * (1 + format::kPfrepVertexRecordSize)) return Result::OutOfBounds;
        at += b.size;
        vertices += b.vertices;
        blocks[k] = b;
    }
    if (at != h.blob_size) return Result::OutOfBounds;
    if (vertices != h.vertex_count) return Result::BadStructure;
    return Result::Ok;
}

// The skeleton: the format 2 header, then one entry length per vertex (rank order). Writes the
// format 2 header, block directory and every block's entry offsets into `out` (zeroed first), then
// opens that layout as a prefix holding no block. Allocation-free: the lengths are walked three
// times (block stream sizes, then block offsets, then entry offsets).
Result readSkeleton(const uint8_t* p, const RegionHeader& h, uint8_t* out, size_t capacity, PfrepModel& model) {
    const uint8_t* s =
        p + format::kPfrepRegionHeaderSize + size_t(h.block_count) * format::kPfrepRegionDirectoryRecordSize;
    const uint8_t* end = s + h.skeleton_size;
    if (loadU32(s) != format::kPfrepMagic || loadU32(s + 4) != format::kPfrepVersion) return Result::BadStructure;
    const uint32_t vertices = loadU32(s + 8), removed = loadU32(s + 12), shift = loadU32(s + 16);
    const uint32_t blob_size = loadU32(s + 52), blocks = loadU32(s + 56);
    if (vertices != h.vertex_count || removed != h.removed_count || blob_size != h.decoded_size ||
        shift > format::kPfrepMaxBlockShift || blocks != ((uint64_t(vertices) + (uint64_t(1) << shift) - 1) >> shift))
        return Result::BadStructure;
    const uint64_t directory_end = format::kPfrepHeaderSize + uint64_t(blocks) * 4;
    if (directory_end > h.decoded_size) return Result::BadStructure;
    if (capacity < h.decoded_size) return Result::BufferTooSmall;
    std::memset(out, 0, h.decoded_size);
    std::memcpy(out, s, format::kPfrepHeaderSize);
    auto count = [&](uint32_t b) { return std::min(uint32_t(1) << shift, vertices - (b << shift)); };
    // 1: each block's stream size, in its directory slot for now (every entry starts below 2^16).
    const uint8_t* q = s + format::kPfrepHeaderSize;
    for (uint32_t b = 0; b < blocks; ++b) {
        uint64_t stream = 0;
        for (uint32_t j = 0; j < count(b); ++j) {
            uint32_t length = 0;
            if (!readVarint(q, end, length)) return Result::Truncated;
            if (length < 2 || stream > 0xffff) return Result::BadStructure;
            stream += length;
        }
        if (stream > 0xffffffffu) return Result::BadStructure;
        storeU32(out + format::kPfrepHeaderSize + size_t(b) * 4, uint32_t(stream));
    }
    if (q != end) return Result::BadStructure;
    // 2: block offsets, blocks back to back in decreasing b.
    uint64_t at = directory_end;
    for (uint32_t b = blocks; b-- > 0;) {
        const uint64_t stream = loadU32(out + format::kPfrepHeaderSize + size_t(b) * 4);
        storeU32(out + format::kPfrepHeaderSize + size_t(b) * 4, uint32_t(at));
        at += uint64_t(count(b)) * (format::kPfrepVertexRecordSize + 2) + stream + format::kPfrepStreamPadding;
        if (at > h.decoded_size) return Result::BadStructure;
    }
    if (at != h.decoded_size) return Result::BadStructure;
    // 3: entry offsets.
    q = s + format::kPfrepHeaderSize;
    for (uint32_t b = 0; b < blocks; ++b) {
        uint8_t* rel = out + loadU32(out + format::kPfrepHeaderSize + size_t(b) * 4) +
                       size_t(count(b)) * format::kPfrepVertexRecordSize;
        uint32_t offset = 0;
        for (uint32_t j = 0; j < count(b); ++j) {
            uint32_t length = 0;
            readVarint(q, end, length); // checked in pass 1
            storeU16(rel + size_t(j) * 2, uint16_t(offset));
            offset += length;
        }
    }
    PfrepModel m;
    const Result r = openPfrepPrefix(out, size_t(directory_end), &m);
    if (r != Result::Ok) return r;
    model = m;
    return Result::Ok;
}

// Byte range of entry v in the decoded buffer: up to the next entry of its format 2 block, or the
// block's stream end.
void entryRange(const PfrepModel& m, uint32_t v, uint64_t& begin, uint64_t& end) {
    begin = detail::pfrepEntryOffset(m, v);
    const uint32_t next = v + 1;
    end = (next < m.vertex_count && (next >> m.block_shift) == (v >> m.block_shift)) ? detail::pfrepEntryOffset(m, next)
                                                                                     : detail::pfrepStreamEnd(m, v);
}

// Zeroes the records and entries of ranks[0, n) (a failed or evicted block).
void clearVertices(const PfrepRegions& g, const uint32_t* ranks, uint32_t n) {
    for (uint32_t k = 0; k < n; ++k) {
        uint64_t begin = 0, end = 0;
        entryRange(g.model, ranks[k], begin, end);
        std::memset(g.decoded + begin, 0, size_t(end - begin));
        std::memset(g.decoded + detail::pfrepRecordOffset(g.model, ranks[k]), 0, format::kPfrepVertexRecordSize);
    }
}

// Lowest rank of the resident suffix.
uint32_t residentSuffix(const PfrepModel& m, uint32_t from) {
    while (from > 0 && ((m.resident[(from - 1) >> 3] >> ((from - 1) & 7)) & 1)) --from;
    return from;
}

} // namespace

Result pfrepRegionInfo(const void* data, size_t size, PfrepRegionInfo* info) {
    if (!data || !info) return Result::InvalidArgument;
    RegionHeader h;
    const Result r = readHeader(static_cast<const uint8_t*>(data), size, h);
    if (r != Result::Ok) return r;
    PfrepRegionInfo i;
    i.vertex_count = h.vertex_count;
    i.block_count = h.block_count;
    i.decoded_bytes = h.decoded_size;
    i.open_bytes = openBytes(h);
    i.blob_size = h.blob_size;
    i.state_bytes = stateLayout(h.vertex_count, h.block_count).total;
    *info = i;
    return Result::Ok;
}

Result pfrepRegionOpen(const void* data, size_t size, void* decoded, size_t decoded_capacity, void* state,
                       size_t state_bytes, PfrepRegions* regions) {
    if (!data || !regions || !decoded || !state || (reinterpret_cast<uintptr_t>(state) & 7) != 0)
        return Result::InvalidArgument;
    const uint8_t* p = static_cast<const uint8_t*>(data);
    RegionHeader h;
    Result r = readHeader(p, size, h);
    if (r != Result::Ok) return r;
    if (size < openBytes(h)) return Result::Truncated;
    const StateLayout l = stateLayout(h.vertex_count, h.block_count);
    if (state_bytes < l.total) return Result::BufferTooSmall;
    uint8_t* st = static_cast<uint8_t*>(state);
    PfrepRegionBlock* blocks = reinterpret_cast<PfrepRegionBlock*>(st + l.blocks);
    r = readDirectory(p, h, blocks);
    if (r != Result::Ok) return r;
    PfrepModel m;
    r = readSkeleton(p, h, static_cast<uint8_t*>(decoded), decoded_capacity, m);
    if (r != Result::Ok) return r;
    std::memset(st + l.resident, 0, l.ranks - l.resident);
    uint32_t* first = reinterpret_cast<uint32_t*>(st + l.first);
    for (uint32_t k = 0, at = 0; k < h.block_count; at += blocks[k].vertices, ++k) first[k] = at;
    m.size = h.decoded_size;
    m.resident = st + l.resident;
    m.loaded_from = h.vertex_count;
    // The whole blob's largest radius and error (pfrepRefine's instance test must see the same values
    // as on the whole blob); loads raise them if a block holds larger ones.
    m.max_radius = detail::pfrepLogValue(m, h.max_codes & 0xff);
    m.max_error = detail::pfrepLogValue(m, (h.max_codes >> 8) & 0xff);
    PfrepRegions g;
    g.model = m;
    g.blocks = blocks;
    g.block_count = h.block_count;
    g.open_bytes = openBytes(h);
    g.blob_size = h.blob_size;
    g.loaded_bytes = g.open_bytes;
    g.block_loaded = st + l.loaded;
    g.decoded = static_cast<uint8_t*>(decoded);
    g.state = st;
    *regions = g;
    return Result::Ok;
}

namespace {

// Checks the rank list of a block: strictly increasing, below V, not resident; ranks of never-removed
// vertices only in block 0, and there all of them. Writes them to `ranks` and returns the bytes read.
Result readRanks(const PfrepRegions& g, uint32_t block, const uint8_t* p, const uint8_t* end, uint32_t* ranks,
                 const uint8_t** after) {
    const PfrepModel& m = g.model;
    const uint32_t n = g.blocks[block].vertices;
    uint64_t previous = 0;
    uint32_t tail = 0;
    for (uint32_t k = 0; k < n; ++k) {
        uint32_t gap = 0;
        if (!readVarint(p, end, gap)) return Result::Truncated;
        const uint64_t v = k == 0 ? uint64_t(gap) : previous + 1 + gap;
        if (v >= m.vertex_count) return Result::OutOfBounds;
        if ((m.resident[v >> 3] >> (v & 7)) & 1) return Result::BadStructure;
        if (v >= m.removed_count) ++tail;
        ranks[k] = uint32_t(v);
        previous = v;
    }
    if (block == 0 ? tail != m.vertex_count - m.removed_count : tail != 0) return Result::BadStructure;
    *after = p;
    return Result::Ok;
}

} // namespace

namespace {

// A block's bytes: its ranks written to the block's rank slots in the state, its records and its
// entries (each exactly its skeleton length). Checks sizes and ranks, and with `claimed` that no
// rank is staged by another block of the same batch.
struct BlockParts {
    uint32_t* ranks = nullptr;
    uint32_t n = 0;
    const uint8_t* records = nullptr;
    const uint8_t* entries = nullptr;
};

Result parseBlock(const PfrepRegions& g, uint32_t block, const void* bytes, size_t size, const uint8_t* claimed,
                  BlockParts* parts) {
    if (g.block_loaded[block]) return Result::InvalidArgument;
    const PfrepRegionBlock& b = g.blocks[block];
    if (size < b.size) return Result::Truncated;
    if (size > b.size) return Result::TrailingBytes;
    const StateLayout l = stateLayout(g.model.vertex_count, g.block_count);
    BlockParts out;
    out.ranks =
        reinterpret_cast<uint32_t*>(g.state + l.ranks) + reinterpret_cast<const uint32_t*>(g.state + l.first)[block];
    out.n = b.vertices;
    const uint8_t* p = static_cast<const uint8_t*>(bytes);
    const uint8_t* end = p + size;
    Result r = readRanks(g, block, p, end, out.ranks, &out.records);
    if (r != Result::Ok) return r;
    // A rank another block of the same batch staged is held twice.
    if (claimed) {
        for (uint32_t k = 0; k < out.n; ++k)
            if ((claimed[out.ranks[k] >> 3] >> (out.ranks[k] & 7)) & 1) return Result::BadStructure;
    }
    if (uint64_t(end - out.records) < uint64_t(out.n) * format::kPfrepVertexRecordSize) return Result::Truncated;
    out.entries = out.records + size_t(out.n) * format::kPfrepVertexRecordSize;
    uint64_t total = 0;
    for (uint32_t k = 0; k < out.n; ++k) {
        uint64_t begin = 0, stop = 0;
        entryRange(g.model, out.ranks[k], begin, stop);
        total += stop - begin;
    }
    if (total < uint64_t(end - out.entries)) return Result::TrailingBytes;
    if (total > uint64_t(end - out.entries)) return Result::Truncated;
    *parts = out;
    return Result::Ok;
}

// Validates the block's entries as openPfrep does, each read at at(begin, length) (its format 2
// offset and length; 8 readable bytes must follow it: the bit reader loads whole words), and
// gathers what the commit needs.
template <typename At>
Result validateEntries(const PfrepModel& m, const BlockParts& parts, At at, detail::PfrepRegionStaged* staged) {
    detail::PfrepRegionStaged out;
    out.max_neighbours = m.max_fan_neighbours;
    // Validation reads only the entry's own bits and the model's counts, so a copy of the model whose
    // data is the entry validates it wherever it lies.
    PfrepModel at_entry = m;
    for (uint32_t k = 0; k < parts.n; ++k) {
        uint64_t begin = 0, stop = 0;
        entryRange(m, parts.ranks[k], begin, stop);
        at_entry.data = at(begin, stop - begin);
        uint32_t neighbours = 0;
        const Result r =
            detail::pfrepValidateEntryAt(at_entry, parts.ranks[k], 0, stop - begin, &out.originals, &neighbours);
        if (r != Result::Ok) return r;
        const uint8_t* rec = parts.records + size_t(k) * format::kPfrepVertexRecordSize;
        out.max_neighbours = std::max(out.max_neighbours, neighbours);
        out.max_radius_code = std::max<uint32_t>(out.max_radius_code, rec[6]);
        out.max_error_code = std::max<uint32_t>(out.max_error_code, rec[7]);
    }
    *staged = out;
    return Result::Ok;
}

// Copies the block's records and entries to their format 2 places.
void layOut(const PfrepRegions& g, const BlockParts& parts) {
    const uint8_t* entries = parts.entries;
    for (uint32_t k = 0; k < parts.n; ++k) {
        uint64_t begin = 0, stop = 0;
        entryRange(g.model, parts.ranks[k], begin, stop);
        std::memcpy(g.decoded + detail::pfrepRecordOffset(g.model, parts.ranks[k]),
                    parts.records + size_t(k) * format::kPfrepVertexRecordSize, format::kPfrepVertexRecordSize);
        std::memcpy(g.decoded + begin, entries, size_t(stop - begin));
        entries += stop - begin;
    }
}

// Checks the input triangles of all loaded blocks with this one's and makes its vertices resident;
// on BadStructure its laid-out bytes are zero again.
Result makeResident(PfrepRegions& g, uint32_t block, const detail::PfrepRegionStaged& staged) {
    const StateLayout l = stateLayout(g.model.vertex_count, g.block_count);
    const uint32_t* ranks = reinterpret_cast<const uint32_t*>(g.state + l.ranks) +
                            reinterpret_cast<const uint32_t*>(g.state + l.first)[block];
    const uint32_t n = g.blocks[block].vertices;
    uint32_t* block_originals = reinterpret_cast<uint32_t*>(g.state + l.originals);
    uint64_t all = staged.originals;
    bool complete = true;
    for (uint32_t k = 0; k < g.block_count; ++k) {
        if (g.block_loaded[k])
            all += block_originals[k];
        else if (k != block)
            complete = false;
    }
    if (all > g.model.level0_triangles || (complete && all != g.model.level0_triangles)) {
        clearVertices(g, ranks, n);
        return Result::BadStructure;
    }
    uint8_t* resident = g.state + l.resident;
    for (uint32_t k = 0; k < n; ++k)
        resident[ranks[k] >> 3] = uint8_t(resident[ranks[k] >> 3] | (1u << (ranks[k] & 7)));
    block_originals[block] = uint32_t(staged.originals);
    g.state[l.loaded + block] = 1;
    g.loaded_bytes += g.blocks[block].size;
    g.model.loaded_original_triangles = uint32_t(all);
    g.model.max_fan_neighbours = std::max(g.model.max_fan_neighbours, staged.max_neighbours);
    g.model.max_radius = std::max(g.model.max_radius, detail::pfrepLogValue(g.model, staged.max_radius_code));
    g.model.max_error = std::max(g.model.max_error, detail::pfrepLogValue(g.model, staged.max_error_code));
    g.model.loaded_from = residentSuffix(g.model, g.model.loaded_from);
    g.model.loaded_blocks = 0; // prefix blocks: not used by a region model
    g.model.criterion_table = nullptr;
    return Result::Ok;
}

} // namespace

namespace detail {

// Stage: validated from the block's own bytes; nothing of the decoded buffer is written (refinement
// may read it meanwhile, and its word-wide bit reads run past a resident entry's end into the next).
Result pfrepRegionStageBlock(const PfrepRegions& g, uint32_t block, const void* bytes, size_t size, uint8_t* claimed,
                             PfrepRegionStaged* staged) {
    if (!g.state || block >= g.block_count || (!bytes && size > 0) || !staged) return Result::InvalidArgument;
    BlockParts parts;
    Result r = parseBlock(g, block, bytes, size, claimed, &parts);
    if (r != Result::Ok) return r;
    const uint8_t* entries = parts.entries;
    r = validateEntries(
        g.model, parts,
        [&entries](uint64_t, uint64_t length) {
            const uint8_t* at = entries;
            entries += length;
            return at;
        },
        staged);
    if (r != Result::Ok) return r;
    staged->records_offset = uint64_t(parts.records - static_cast<const uint8_t*>(bytes));
    if (claimed) {
        for (uint32_t k = 0; k < parts.n; ++k)
            claimed[parts.ranks[k] >> 3] = uint8_t(claimed[parts.ranks[k] >> 3] | (1u << (parts.ranks[k] & 7)));
    }
    return Result::Ok;
}

void pfrepRegionUnclaim(const PfrepRegions& g, uint32_t block, uint8_t* claimed) {
    if (!g.state || block >= g.block_count || !claimed) return;
    const StateLayout l = stateLayout(g.model.vertex_count, g.block_count);
    const uint32_t* ranks = reinterpret_cast<const uint32_t*>(g.state + l.ranks) +
                            reinterpret_cast<const uint32_t*>(g.state + l.first)[block];
    for (uint32_t k = 0; k < g.blocks[block].vertices; ++k)
        claimed[ranks[k] >> 3] = uint8_t(claimed[ranks[k] >> 3] & ~(1u << (ranks[k] & 7)));
}

Result pfrepRegionCommitBlock(PfrepRegions* regions, uint32_t block, const void* bytes,
                              const PfrepRegionStaged& staged) {
    if (!regions || !regions->state || block >= regions->block_count || regions->block_loaded[block] || !bytes)
        return Result::InvalidArgument;
    PfrepRegions& g = *regions;
    const StateLayout l = stateLayout(g.model.vertex_count, g.block_count);
    BlockParts parts;
    parts.ranks =
        reinterpret_cast<uint32_t*>(g.state + l.ranks) + reinterpret_cast<const uint32_t*>(g.state + l.first)[block];
    parts.n = g.blocks[block].vertices;
    parts.records = static_cast<const uint8_t*>(bytes) + staged.records_offset;
    parts.entries = parts.records + size_t(parts.n) * format::kPfrepVertexRecordSize;
    layOut(g, parts);
    return makeResident(g, block, staged);
}

} // namespace detail

// Single-threaded: laid out first and validated in place, where the format 2 block padding follows
// every entry (the caller's buffer need not be padded).
Result pfrepRegionLoadBlock(PfrepRegions* regions, uint32_t block, const void* bytes, size_t size) {
    if (!regions || !regions->state || block >= regions->block_count || (!bytes && size > 0))
        return Result::InvalidArgument;
    PfrepRegions& g = *regions;
    if (g.block_loaded[block]) return Result::Ok;
    BlockParts parts;
    Result r = parseBlock(g, block, bytes, size, nullptr, &parts);
    if (r != Result::Ok) return r;
    layOut(g, parts);
    detail::PfrepRegionStaged staged;
    r = validateEntries(
        g.model, parts, [&g](uint64_t begin, uint64_t) { return static_cast<const uint8_t*>(g.decoded) + begin; },
        &staged);
    if (r != Result::Ok) {
        clearVertices(g, parts.ranks, parts.n);
        return r;
    }
    return makeResident(g, block, staged);
}

Result pfrepRegionReleaseMask(const PfrepRegions& g, uint32_t block, uint8_t* mask, uint32_t* scratch,
                              size_t scratch_capacity) {
    if (!g.state || block >= g.block_count || !mask || !scratch) return Result::InvalidArgument;
    if (!g.block_loaded[block]) return Result::Ok;
    const StateLayout l = stateLayout(g.model.vertex_count, g.block_count);
    const uint32_t* ranks = reinterpret_cast<const uint32_t*>(g.state + l.ranks) +
                            reinterpret_cast<const uint32_t*>(g.state + l.first)[block];
    for (uint32_t k = 0; k < g.blocks[block].vertices; ++k) {
        const Result r = pfrepSimplifyVertex(g.model, mask, ranks[k], scratch, scratch_capacity);
        if (r != Result::Ok) return r;
    }
    return Result::Ok;
}

Result pfrepRegionEvictBlock(PfrepRegions* regions, uint32_t block) {
    if (!regions || !regions->state || block >= regions->block_count || block == 0) return Result::InvalidArgument;
    PfrepRegions& g = *regions;
    if (!g.block_loaded[block]) return Result::Ok;
    const StateLayout l = stateLayout(g.model.vertex_count, g.block_count);
    const uint32_t* ranks = reinterpret_cast<const uint32_t*>(g.state + l.ranks) +
                            reinterpret_cast<const uint32_t*>(g.state + l.first)[block];
    const uint32_t n = g.blocks[block].vertices;
    clearVertices(g, ranks, n);
    uint8_t* resident = g.state + l.resident;
    for (uint32_t k = 0; k < n; ++k) {
        resident[ranks[k] >> 3] = uint8_t(resident[ranks[k] >> 3] & ~(1u << (ranks[k] & 7)));
        if (ranks[k] >= g.model.loaded_from) g.model.loaded_from = ranks[k] + 1;
    }
    uint32_t* block_originals = reinterpret_cast<uint32_t*>(g.state + l.originals);
    g.model.loaded_original_triangles -= block_originals[block];
    block_originals[block] = 0;
    g.state[l.loaded + block] = 0;
    g.loaded_bytes -= g.blocks[block].size;
    g.model.criterion_table = nullptr;
    return Result::Ok;
}

namespace {

constexpr float kBlockMargin = 1e-4f;

// Conservative form of pfrep.cpp's bounds test for every vertex whose sphere lies in the box and
// whose error is at most max_error (docs/format/pfrep.md "Region blocks").
bool blockPasses(const PfrepRegionBlock& b, const PfrepView& view, float tolerance, float sin_band) {
    const auto [near2, far2] = detail::eyeBoxDistance(view.eye, b.lo, b.hi);
    float half2 = 0.0f, scale = 0.0f;
    for (int k = 0; k < 3; ++k) {
        half2 += 0.25f * (b.hi[k] - b.lo[k]) * (b.hi[k] - b.lo[k]);
        scale = std::max(scale, std::max(std::fabs(b.lo[k]), std::fabs(b.hi[k])) + std::fabs(view.eye[k]));
    }
    // A vertex passes only when dist - radius < error * ppu / tolerance; dist - radius >= the box's
    // distance from the eye.
    if (tolerance > 0.0f) {
        const float reach = b.max_error * view.pixels_per_unit_at_distance_one / tolerance;
        const float near = std::sqrt(near2);
        if (near > reach + kBlockMargin * (scale + reach)) return false;
    }
    const float far = std::sqrt(far2), half = std::sqrt(half2);
    for (const auto& plane : view.planes) {
        float high = plane[3], pscale = std::fabs(plane[3]);
        const float n = std::sqrt(plane[0] * plane[0] + plane[1] * plane[1] + plane[2] * plane[2]);
        for (int k = 0; k < 3; ++k) {
            high += plane[k] * (plane[k] >= 0 ? b.hi[k] : b.lo[k]);
            pscale += std::fabs(plane[k]) * std::max(std::fabs(b.lo[k]), std::fabs(b.hi[k]));
        }
        // A sphere (p, r) in the box has plane(p) <= high - r |n|; it fails when plane(p) < -r - sin_band dist.
        const float slack = sin_band * far + (n < 1.0f ? (1.0f - n) * half : 0.0f);
        if (high < -slack - kBlockMargin * (pscale + slack)) return false;
    }
    return true;
}

} // namespace

Result pfrepRegionBlocksNeeded(const PfrepRegions& g, const PfrepView& view, uint32_t* blocks, size_t capacity,
                               size_t* count) {
    if (!count || !g.blocks || (!blocks && capacity > 0)) return Result::InvalidArgument;
    const float h = view.hysteresis > 0.0f && view.hysteresis <= 1.0f ? view.hysteresis : 1.0f;
    const float band = view.cull_hysteresis >= 0.0f && view.cull_hysteresis <= 0.5f ? view.cull_hysteresis : 0.0f;
    const float tolerance = h * view.pixel_tolerance;
    const float sin_band = std::sin(band);
    size_t n = 0;
    for (uint32_t k = 0; k < g.block_count; ++k) {
        if (k != 0 && !blockPasses(g.blocks[k], view, tolerance, sin_band)) continue;
        if (n < capacity) blocks[n] = k;
        ++n;
    }
    *count = n;
    return n <= capacity ? Result::Ok : Result::BufferTooSmall;
}

} // namespace lodrt
