// libFuzzer target for the PFRep reader (lodrt/pfrep.h): open (whole, and as a prefix that then
// grows to the whole input), then every extraction and refinement entry point on whatever opened;
// a format 3 input is decoded (pfrepDecompress) and the result exercised the same way; a format 4
// input is decoded (pfrepDecodeFormat4) against a generated LOD0 (a torus of 8 x 6 points, the LOD0
// of the format 4 seeds; for a blob with a split list, the torus with two vertices on one position,
// numbered with the list by pfrepNumberLod0Split) and exercised; a region-block input (PFRG) is
// opened, its blocks inside the input loaded (root first), the model exercised, then a block
// released and evicted and the model exercised again.
// Build with -DLODRT_BUILD_FUZZERS=ON and Clang; run as `lodrt_fuzz_pfrep CORPUS_DIR` (blobs written
// by `lodbake pfrep` make a good seed corpus).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "lodrt/pfrep.h"

namespace {

// Every extraction and refinement entry point on an opened (whole or prefix) model.
void exercise(const lodrt::PfrepModel& model) {
    if (model.vertex_count > (1u << 20) || model.level0_triangles > (1u << 22)) return;
    std::vector<uint32_t> indices(lodrt::pfrepMaxTriangles(model) * 3 + 3);
    std::vector<uint32_t> fans(lodrt::pfrepMaxFanValues(model) + 4);
    std::vector<float> positions(size_t(model.vertex_count) * 3);
    std::vector<uint8_t> mask(lodrt::pfrepMaskBytes(model));
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(model) + 1);
    size_t n = 0;
    (void)lodrt::pfrepDecodePositions(model, positions.data(), positions.size());
    for (uint32_t k : {0u, model.removed_count / 2, model.removed_count}) {
        (void)lodrt::pfrepExtractLevel(model, k, indices.data(), indices.size() / 3, &n);
        (void)lodrt::pfrepExtractLevelFans(model, k, fans.data(), fans.size(), &n);
    }
    lodrt::pfrepMaskCoarsest(model, mask.data());
    for (uint32_t v = 0; v < model.vertex_count; v += 3)
        (void)lodrt::pfrepInsertVertex(model, mask.data(), v, scratch.data(), scratch.size());
    for (uint32_t v = 0; v < model.vertex_count; v += 5)
        (void)lodrt::pfrepSimplifyVertex(model, mask.data(), v, scratch.data(), scratch.size());
    (void)lodrt::pfrepExtractSelective(model, mask.data(), indices.data(), indices.size() / 3, &n);
    lodrt::PfrepView view;
    view.eye[2] = 1.0f;
    for (int p = 0; p < 6; ++p) view.planes[p][3] = 1e6f;
    (void)lodrt::pfrepRefine(model, view, mask.data(), scratch.data(), scratch.size(), &n);
    // A bounded step from the finest mask with the cull band on (the closures' early-abort path).
    lodrt::pfrepMaskFinest(model, mask.data());
    view.eye[2] = 1e3f;
    view.max_changed_bits = 7;
    view.cull_hysteresis = 0.2f;
    (void)lodrt::pfrepRefine(model, view, mask.data(), scratch.data(), scratch.size(), &n);
    (void)lodrt::pfrepExtractSelective(model, mask.data(), indices.data(), indices.size() / 3, &n);
}

} // namespace

// Format 3: decoded into buffers of exactly the sizes the header asks for (capped, so a header that
// announces a huge mesh costs nothing), then exercised.
void decodeCompressed(const std::vector<uint8_t>& blob) {
    lodrt::PfrepCompressedInfo info;
    if (lodrt::pfrepCompressedInfo(blob.data(), blob.size(), &info) != lodrt::Result::Ok) return;
    if (info.vertex_count > (1u << 20) || info.decoded_bytes > (64u << 20) || info.scratch_bytes > (256u << 20)) return;
    std::vector<uint8_t> decoded(info.decoded_bytes);
    std::vector<uint64_t> scratch((info.scratch_bytes + 7) / 8);
    lodrt::PfrepModel model;
    if (lodrt::pfrepDecompress(blob.data(), blob.size(), decoded.data(), decoded.size(), scratch.data(),
                               info.scratch_bytes, &model) == lodrt::Result::Ok)
        exercise(model);
}

void decodeFormat4Against(const std::vector<uint8_t>& blob, const lodrt::PfrepFormat4Info& info,
                          const lodrt::PfrepLod0& lod0) {
    std::vector<uint8_t> decoded(info.decoded_bytes);
    std::vector<uint64_t> scratch((info.scratch_bytes + 7) / 8);
    lodrt::PfrepModel model;
    if (lodrt::pfrepDecodeFormat4(blob.data(), blob.size(), lod0, decoded.data(), decoded.size(), scratch.data(),
                                  info.scratch_bytes, &model) == lodrt::Result::Ok)
        exercise(model);
}

// Format 4 against the torus LOD0 (8 x 6 points, 96 triangles; tests/malformed/lbp/f4_torus.lbp is
// its format 4 blob, written by PfrepFormat4Test.FuzzTorusSeed), with capped buffers.
void decodeFormat4(const std::vector<uint8_t>& blob) {
    lodrt::PfrepFormat4Info info;
    if (lodrt::pfrepFormat4Info(blob.data(), blob.size(), &info) != lodrt::Result::Ok) return;
    if (info.decoded_bytes > (64u << 20) || info.scratch_bytes > (256u << 20)) return;
    constexpr uint32_t kRing = 8, kTube = 6;
    std::vector<float> points;
    std::vector<uint32_t> triangles;
    for (uint32_t i = 0; i < kRing; ++i)
        for (uint32_t j = 0; j < kTube; ++j) {
            const float u = float(i) * 6.2831853f / kRing, v = float(j) * 6.2831853f / kTube;
            points.push_back((2.0f + std::cos(v)) * std::cos(u));
            points.push_back((2.0f + std::cos(v)) * std::sin(u));
            points.push_back(std::sin(v));
            const uint32_t a = i * kTube + j, b = ((i + 1) % kRing) * kTube + j;
            const uint32_t c = ((i + 1) % kRing) * kTube + (j + 1) % kTube, d = i * kTube + (j + 1) % kTube;
            triangles.insert(triangles.end(), {a, b, c, a, c, d});
        }
    lodrt::PfrepLod0 lod0;
    const void* split = nullptr;
    size_t split_bytes = 0;
    if (lodrt::pfrepFormat4SplitList(blob.data(), blob.size(), &split, &split_bytes) != lodrt::Result::Ok) return;
    std::vector<float> split_points(points.size());
    std::vector<uint32_t> split_triangles(triangles.size());
    if (split) {
        // A blob with a split list (a pack's): the torus with vertex 27 on vertex 0's position, numbered
        // with the list (tests/malformed/lbp/f4_torus_split.lbp, PfrepFormat4Test.FuzzWeldedTorusSeed).
        std::copy(points.begin(), points.begin() + 3, points.begin() + 27 * 3);
        std::vector<uint64_t> number_scratch((lodrt::pfrepNumberLod0ScratchBytes(kRing * kTube) + 7) / 8);
        if (lodrt::pfrepNumberLod0Split(split, split_bytes, points.data(), kRing * kTube, triangles.data(),
                                        uint32_t(triangles.size() / 3), split_points.data(), split_points.size(),
                                        split_triangles.data(), split_triangles.size(), number_scratch.data(),
                                        number_scratch.size() * 8, &lod0) != lodrt::Result::Ok)
            return;
        decodeFormat4Against(blob, info, lod0);
        return;
    }
    // Points renumbered by first use, as format 4 numbers LOD0 (the positions are all distinct).
    std::vector<uint32_t> id(kRing * kTube, ~0u);
    std::vector<float> numbered;
    for (uint32_t& p : triangles) {
        if (id[p] == ~0u) {
            id[p] = uint32_t(numbered.size() / 3);
            numbered.insert(numbered.end(), points.begin() + p * 3, points.begin() + p * 3 + 3);
        }
        p = id[p];
    }
    points.swap(numbered);
    lod0.positions = points.data();
    lod0.point_count = kRing * kTube;
    lod0.triangles = triangles.data();
    lod0.triangle_count = uint32_t(triangles.size() / 3);
    decodeFormat4Against(blob, info, lod0);
}

// Region blocks: buffers of exactly the sizes the header asks for (capped); every block is copied
// into an allocation of exactly its size before loading.
void decodeRegions(const std::vector<uint8_t>& blob) {
    lodrt::PfrepRegionInfo info;
    if (lodrt::pfrepRegionInfo(blob.data(), blob.size(), &info) != lodrt::Result::Ok) return;
    if (info.vertex_count > (1u << 20) || info.decoded_bytes > (64u << 20) || info.state_bytes > (64u << 20)) return;
    std::vector<uint8_t> decoded(info.decoded_bytes);
    std::vector<uint64_t> state((info.state_bytes + 7) / 8);
    lodrt::PfrepRegions g;
    if (lodrt::pfrepRegionOpen(blob.data(), blob.size(), decoded.data(), decoded.size(), state.data(), info.state_bytes,
                               &g) != lodrt::Result::Ok)
        return;
    for (uint32_t k = 0; k < g.block_count; ++k) {
        const lodrt::PfrepRegionBlock& b = g.blocks[k];
        if (uint64_t(b.offset) + b.size > blob.size()) break;
        std::vector<uint8_t> bytes(blob.begin() + b.offset, blob.begin() + b.offset + b.size);
        (void)lodrt::pfrepRegionLoadBlock(&g, k, bytes.data(), bytes.size());
    }
    lodrt::PfrepView view;
    view.eye[2] = 1.0f;
    for (int p = 0; p < 6; ++p) view.planes[p][3] = 1e6f;
    std::vector<uint32_t> needed(g.block_count);
    size_t count = 0;
    (void)lodrt::pfrepRegionBlocksNeeded(g, view, needed.data(), needed.size(), &count);
    exercise(g.model);
    if (g.block_count > 1 && g.block_loaded[1]) {
        std::vector<uint8_t> mask(lodrt::pfrepMaskBytes(g.model));
        std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(g.model));
        lodrt::pfrepMaskFinest(g.model, mask.data());
        (void)lodrt::pfrepRegionReleaseMask(g, 1, mask.data(), scratch.data(), scratch.size());
        (void)lodrt::pfrepRegionEvictBlock(&g, 1);
        exercise(g.model);
    }
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    // The reader copies nothing; a copy of exactly `size` bytes lets ASan see any read past the end.
    std::vector<uint8_t> blob(data, data + size);
    decodeCompressed(blob);
    decodeFormat4(blob);
    decodeRegions(blob);
    lodrt::PfrepModel model;
    if (lodrt::openPfrep(blob.data(), blob.size(), &model) == lodrt::Result::Ok) exercise(model);
    // Streaming: a prefix (cut where the last byte says), then the rest arriving in a moved buffer.
    if (size < 2) return 0;
    const size_t cut = size_t(uint64_t(size) * data[size - 1] / 255);
    std::vector<uint8_t> prefix(data, data + cut);
    lodrt::PfrepModel partial;
    if (lodrt::openPfrepPrefix(prefix.data(), prefix.size(), &partial) != lodrt::Result::Ok) return 0;
    exercise(partial);
    std::vector<uint8_t> whole(data, data + size);
    if (lodrt::pfrepExtendPrefix(&partial, whole.data(), whole.size()) == lodrt::Result::Ok) exercise(partial);
    return 0;
}
