// PFRep region-block writer (docs/format/pfrep.md "Region blocks").
#include "lodbake/pfrep/pfrep_region.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <string>

#include "lodrt/detail/pfrep_region.h"
#include "lodrt/format.h"
#include "lodrt/pfrep.h"

namespace lodbake {
namespace {

void putU32(std::vector<uint8_t>& out, uint32_t v) {
    for (int k = 0; k < 4; ++k) out.push_back(uint8_t(v >> (8 * k)));
}
void putF32(std::vector<uint8_t>& out, float f) {
    uint32_t v;
    std::memcpy(&v, &f, 4);
    putU32(out, v);
}
void putVarint(std::vector<uint8_t>& out, uint32_t v) {
    while (v >= 0x80) {
        out.push_back(uint8_t(v | 0x80));
        v >>= 7;
    }
    out.push_back(uint8_t(v));
}

// Bounds of what may need a vertex: its own bounding sphere (as a box) and error, joined with the
// bounds of every vertex whose insertion closure can reach it.
struct Bounds {
    std::array<float, 3> lo{}, hi{};
    float error = 0;
    void join(const Bounds& o) {
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], o.lo[k]);
            hi[k] = std::max(hi[k], o.hi[k]);
        }
        error = std::max(error, o.error);
    }
};

// InsertVertex(v) inserts the corners of v's fans (ranks above v), recursively: so a vertex a is
// reached from every v whose A_v holds it, and from whatever reaches v. In increasing rank, each
// vertex's bounds are final before they are joined into its neighbours'.
std::vector<Bounds> closureBounds(const lodrt::PfrepModel& m) {
    std::vector<Bounds> bounds(m.vertex_count);
    for (uint32_t v = 0; v < m.vertex_count; ++v) {
        lodrt::PfrepVertexBounds vb;
        (void)lodrt::pfrepVertexBounds(m, v, &vb);
        Bounds& b = bounds[v];
        for (int k = 0; k < 3; ++k) {
            // Padded by a relative epsilon: the runtime computes distances from the same floats.
            const float pad = vb.radius + 1e-6f * (std::fabs(vb.position[k]) + vb.radius);
            b.lo[k] = vb.position[k] - pad;
            b.hi[k] = vb.position[k] + pad;
        }
        b.error = vb.error;
    }
    std::vector<uint32_t> ring(size_t(m.max_fan_neighbours) + 1);
    for (uint32_t v = 0; v < m.vertex_count; ++v) {
        const size_t n = lodrt::detail::pfrepEntryNeighbours(m, v, ring.data(), ring.size());
        for (size_t j = 0; j < std::min(n, ring.size()); ++j) bounds[ring[j]].join(bounds[v]);
    }
    return bounds;
}

// A vertex of a band: the centre of its bounds, its reach (the distance within which its bounds'
// error is refined, from the options' screen) and its rank.
struct BandVertex {
    std::array<float, 4> key;
    uint32_t rank;
};

// Cuts `vertices` into `pieces` blocks of near-equal size by median splits across the longest axis
// of their keys (ties by rank). A block is needed when a view comes within its max_error's reach of
// its box, so the region where it is needed spans its box plus that reach on every side: splitting
// the longest of the three box extents and the reach's spread keeps both small. (A run of a
// space-filling curve of the same size can also straddle one of the curve's jumps and span two
// distant parts.)
void splitBand(std::vector<BandVertex>::iterator first, std::vector<BandVertex>::iterator last, size_t pieces,
               std::vector<std::vector<uint32_t>>& blocks) {
    if (pieces <= 1) {
        std::vector<uint32_t> ranks;
        for (auto it = first; it != last; ++it) ranks.push_back(it->rank);
        std::sort(ranks.begin(), ranks.end());
        blocks.push_back(std::move(ranks));
        return;
    }
    std::array<float, 4> lo = first->key, hi = first->key;
    for (auto it = first; it != last; ++it)
        for (size_t k = 0; k < 4; ++k) {
            lo[k] = std::min(lo[k], it->key[k]);
            hi[k] = std::max(hi[k], it->key[k]);
        }
    size_t axis = 0;
    for (size_t k = 1; k < 4; ++k)
        if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
    const size_t left = pieces / 2, count = size_t(last - first);
    const auto mid = first + std::ptrdiff_t(count * left / pieces);
    std::nth_element(first, mid, last, [axis](const BandVertex& a, const BandVertex& b) {
        return a.key[axis] != b.key[axis] ? a.key[axis] < b.key[axis] : a.rank < b.rank;
    });
    splitBand(first, mid, left, blocks);
    splitBand(mid, last, pieces - left, blocks);
}

// Ranks of each block: block 0 the coarsest ranks; below them bands of halving size from the fine
// end ([0, r/2), [r/2, 3r/4), ...: each about one level of detail, errors of one range), each cut
// by splitBand into blocks of near-equal size. Coarse bands come first in the blob.
std::vector<std::vector<uint32_t>> cutBlocks(const lodrt::PfrepModel& m, const std::vector<Bounds>& bounds,
                                             const PfrepRegionOptions& options, uint32_t* bands) {
    const uint32_t per_block = std::max<uint32_t>(options.block_vertices, 1);
    const uint32_t root = std::max(m.vertex_count - m.removed_count, std::min(m.vertex_count, options.root_vertices));
    const uint32_t top = m.vertex_count - root;
    std::vector<std::pair<uint32_t, uint32_t>> ranges;
    for (uint32_t lo = 0; lo < top;) {
        const uint32_t hi = top - lo <= 2 * per_block ? top : lo + (top - lo) / 2;
        ranges.emplace_back(lo, hi);
        lo = hi;
    }
    std::vector<std::vector<uint32_t>> blocks(1);
    for (uint32_t v = top; v < m.vertex_count; ++v) blocks[0].push_back(v);
    *bands = uint32_t(ranges.size()) + 1;
    // switchDistance is linear in the error; a screen without a finite reach cuts by position.
    const double per_error = switchDistance(1.0, options.screen);
    const double reach = std::isfinite(per_error) ? per_error : 0.0;
    std::vector<BandVertex> band_vertices;
    for (size_t band = ranges.size(); band-- > 0;) {
        band_vertices.clear();
        for (uint32_t v = ranges[band].first; v < ranges[band].second; ++v) {
            BandVertex b;
            for (int k = 0; k < 3; ++k) b.key[size_t(k)] = 0.5f * (bounds[v].lo[k] + bounds[v].hi[k]);
            b.key[3] = float(reach * double(bounds[v].error));
            b.rank = v;
            band_vertices.push_back(b);
        }
        const size_t pieces = (band_vertices.size() + per_block - 1) / per_block;
        splitBand(band_vertices.begin(), band_vertices.end(), pieces, blocks);
    }
    return blocks;
}

// Byte range of entry v in the format 2 blob (as the runtime's region reader computes it).
void entryRange(const lodrt::PfrepModel& m, uint32_t v, uint64_t& begin, uint64_t& end) {
    begin = lodrt::detail::pfrepEntryOffset(m, v);
    const uint32_t next = v + 1;
    end = (next < m.vertex_count && (next >> m.block_shift) == (v >> m.block_shift))
              ? lodrt::detail::pfrepEntryOffset(m, next)
              : lodrt::detail::pfrepStreamEnd(m, v);
}

// Decodes `region` with the runtime reader, every block loaded, and compares with `format2`.
Status verify(const std::vector<uint8_t>& region, const std::vector<uint8_t>& format2) {
    lodrt::PfrepRegionInfo info;
    if (lodrt::pfrepRegionInfo(region.data(), region.size(), &info) != lodrt::Result::Ok)
        return internalError("pfrep regions: the header written does not read back");
    std::vector<uint8_t> decoded(info.decoded_bytes);
    std::vector<uint64_t> state((info.state_bytes + 7) / 8);
    lodrt::PfrepRegions g;
    lodrt::Result r = lodrt::pfrepRegionOpen(region.data(), region.size(), decoded.data(), decoded.size(), state.data(),
                                             info.state_bytes, &g);
    for (uint32_t k = 0; k < g.block_count && r == lodrt::Result::Ok; ++k)
        r = lodrt::pfrepRegionLoadBlock(&g, k, region.data() + g.blocks[k].offset, g.blocks[k].size);
    if (r != lodrt::Result::Ok)
        return internalError(std::string("pfrep regions: the blob written does not load: ") + lodrt::resultName(r));
    if (decoded != format2) return internalError("pfrep regions: the blocks do not rebuild the format 2 blob");
    return Status::okStatus();
}

} // namespace

Result<std::vector<uint8_t>> writePfrepRegions(const std::vector<uint8_t>& format2, const PfrepRegionOptions& options,
                                               PfrepRegionStats* stats) {
    lodrt::PfrepModel m;
    const lodrt::Result opened = lodrt::openPfrep(format2.data(), format2.size(), &m);
    if (opened != lodrt::Result::Ok)
        return invalidInput(std::string("pfrep blob: format 2 table: ") + lodrt::resultName(opened));
    const std::vector<Bounds> bounds = closureBounds(m);
    uint32_t bands = 0;
    const std::vector<std::vector<uint32_t>> blocks = cutBlocks(m, bounds, options, &bands);
    // Skeleton: the format 2 header and every entry's length.
    std::vector<uint8_t> skeleton(format2.begin(), format2.begin() + lodrt::format::kPfrepHeaderSize);
    uint32_t max_radius = 0, max_error = 0;
    for (uint32_t v = 0; v < m.vertex_count; ++v) {
        uint64_t begin = 0, end = 0;
        entryRange(m, v, begin, end);
        putVarint(skeleton, uint32_t(end - begin));
        const uint8_t* r = format2.data() + lodrt::detail::pfrepRecordOffset(m, v);
        max_radius = std::max<uint32_t>(max_radius, r[6]);
        max_error = std::max<uint32_t>(max_error, r[7]);
    }
    std::vector<std::vector<uint8_t>> payloads;
    std::vector<Bounds> block_bounds;
    for (const std::vector<uint32_t>& ranks : blocks) {
        std::vector<uint8_t> p;
        Bounds b = bounds[ranks[0]];
        for (size_t k = 0; k < ranks.size(); ++k) {
            putVarint(p, k == 0 ? ranks[0] : ranks[k] - ranks[k - 1] - 1);
            b.join(bounds[ranks[k]]);
        }
        for (uint32_t v : ranks) {
            const uint8_t* r = format2.data() + lodrt::detail::pfrepRecordOffset(m, v);
            p.insert(p.end(), r, r + lodrt::format::kPfrepVertexRecordSize);
        }
        for (uint32_t v : ranks) {
            uint64_t begin = 0, end = 0;
            entryRange(m, v, begin, end);
            p.insert(p.end(), format2.begin() + long(begin), format2.begin() + long(end));
        }
        payloads.push_back(std::move(p));
        block_bounds.push_back(b);
    }
    const uint32_t n = uint32_t(blocks.size());
    const uint64_t open = lodrt::format::kPfrepRegionHeaderSize +
                          uint64_t(n) * lodrt::format::kPfrepRegionDirectoryRecordSize + skeleton.size();
    uint64_t total = open;
    for (const auto& p : payloads) total += p.size();
    if (total > 0xffffffffu || n > lodrt::format::kPfrepRegionMaxBlocks)
        return resourceLimit("pfrep regions: the blob would exceed 4 GiB or the block limit");
    std::vector<uint8_t> out;
    out.reserve(size_t(total));
    for (uint32_t v :
         {lodrt::format::kPfrepRegionMagic, lodrt::format::kPfrepRegionVersion, m.vertex_count, m.removed_count, n,
          m.blob_size, uint32_t(skeleton.size()), uint32_t(total), max_radius | max_error << 8})
        putU32(out, v);
    out.resize(lodrt::format::kPfrepRegionHeaderSize, 0);
    uint64_t at = open;
    for (uint32_t k = 0; k < n; ++k) {
        putU32(out, uint32_t(at));
        putU32(out, uint32_t(payloads[k].size()));
        putU32(out, uint32_t(blocks[k].size()));
        for (int c = 0; c < 3; ++c) putF32(out, block_bounds[k].lo[c]);
        for (int c = 0; c < 3; ++c) putF32(out, block_bounds[k].hi[c]);
        putF32(out, block_bounds[k].error);
        at += payloads[k].size();
    }
    out.insert(out.end(), skeleton.begin(), skeleton.end());
    for (const auto& p : payloads) out.insert(out.end(), p.begin(), p.end());
    const Status checked = verify(out, format2);
    if (!checked.ok()) return checked;
    if (stats) {
        stats->blocks = n;
        stats->bands = bands;
        stats->open_bytes = open;
        stats->root_bytes = payloads[0].size();
    }
    return out;
}

} // namespace lodbake
