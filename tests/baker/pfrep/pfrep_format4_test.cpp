// PfrepFormat4Test: a format 4 blob, decoded against LOD0's points and triangles, gives the format
// 2 blob's levels (every one, as triangle sets), records and selective refinement; the decoder
// survives every truncation and corruption of a blob, and a LOD0 that does not match, with an error
// or a valid model, never a read or write outside its buffers (the sanitizer builds run these too).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <random>
#include <vector>

#include "../simplify/simplify_test_meshes.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/pfrep/pfrep_builder.h"
#include "lodbake/pfrep/pfrep_compress.h"
#include "lodbake/simplify/lod_chain.h"
#include "lodrt/format.h"
#include "lodrt/pfrep.h"
#include "test_paths.h"

namespace {

struct Lod0Points {
    std::vector<lodbake::Vec3f> points;
    std::vector<uint32_t> triangles;
    lodrt::PfrepLod0 view() const {
        lodrt::PfrepLod0 l;
        l.positions = points.empty() ? nullptr : &points[0].x;
        l.point_count = uint32_t(points.size());
        l.triangles = triangles.data();
        l.triangle_count = uint32_t(triangles.size() / 3);
        return l;
    }
};

struct Format4Decoded {
    lodrt::Result result = lodrt::Result::InvalidArgument;
    std::vector<uint8_t> bytes;
    lodrt::PfrepModel model;
};

// Decodes with buffers of exactly the sizes the header asks for (capped for hostile headers).
Format4Decoded decode4(const std::vector<uint8_t>& coded, const lodrt::PfrepLod0& lod0) {
    Format4Decoded d;
    lodrt::PfrepFormat4Info info;
    d.result = lodrt::pfrepFormat4Info(coded.data(), coded.size(), &info);
    if (d.result != lodrt::Result::Ok) return d;
    if (info.decoded_bytes > (64u << 20) || info.scratch_bytes > (512u << 20)) {
        d.result = lodrt::Result::OutOfMemory;
        return d;
    }
    d.bytes.resize(info.decoded_bytes);
    std::vector<uint64_t> scratch((info.scratch_bytes + 7) / 8);
    d.result = lodrt::pfrepDecodeFormat4(coded.data(), coded.size(), lod0, d.bytes.data(), d.bytes.size(),
                                         scratch.data(), info.scratch_bytes, &d.model);
    return d;
}

struct Built {
    lodbake::PfrepBuild build;
    Lod0Points lod0;
    std::vector<uint8_t> coded;
};

Built buildAndCode(const lodbake::Mesh& mesh) {
    Built b;
    lodbake::Diagnostics diagnostics;
    auto build = lodbake::buildPfrep(mesh, {}, diagnostics);
    EXPECT_TRUE(build.ok()) << build.status().message();
    if (!build.ok()) return b;
    b.build = std::move(*build);
    EXPECT_TRUE(lodbake::chainPoints(mesh, b.lod0.points, b.lod0.triangles).ok());
    auto coded = lodbake::compressPfrepFormat4(b.build, b.lod0.points, b.lod0.triangles);
    EXPECT_TRUE(coded.ok()) << coded.status().message();
    if (coded.ok()) b.coded = std::move(*coded);
    return b;
}

std::vector<std::array<uint32_t, 3>> sortedTriangles(const uint32_t* indices, size_t count) {
    std::vector<std::array<uint32_t, 3>> out(count);
    for (size_t t = 0; t < count; ++t) out[t] = {indices[t * 3], indices[t * 3 + 1], indices[t * 3 + 2]};
    std::sort(out.begin(), out.end());
    return out;
}

// Every level as a triangle set, and view-dependent refinement from two cameras step for step.
void expectSameAsFormat2(const Built& b, bool every_level) {
    ASSERT_FALSE(b.coded.empty());
    EXPECT_LT(b.coded.size(), b.build.blob.size() / 4);
    const Format4Decoded d = decode4(b.coded, b.lod0.view());
    ASSERT_EQ(d.result, lodrt::Result::Ok) << lodrt::resultName(d.result);
    lodrt::PfrepModel original;
    ASSERT_EQ(lodrt::openPfrep(b.build.blob.data(), b.build.blob.size(), &original), lodrt::Result::Ok);
    ASSERT_EQ(d.model.vertex_count, original.vertex_count);
    ASSERT_EQ(d.model.removed_count, original.removed_count);
    std::vector<uint32_t> x(lodrt::pfrepMaxTriangles(original) * 3), y(x.size());
    const uint32_t step = every_level ? 1 : std::max(1u, original.removed_count / 64);
    for (uint32_t k = 0; k <= original.removed_count; k += step) {
        size_t nx = 0, ny = 0;
        ASSERT_EQ(lodrt::pfrepExtractLevel(original, k, x.data(), x.size() / 3, &nx), lodrt::Result::Ok);
        ASSERT_EQ(lodrt::pfrepExtractLevel(d.model, k, y.data(), y.size() / 3, &ny), lodrt::Result::Ok);
        ASSERT_EQ(nx, ny) << "level " << k;
        ASSERT_EQ(sortedTriangles(x.data(), nx), sortedTriangles(y.data(), ny)) << "level " << k;
    }
    std::vector<float> pa(size_t(original.vertex_count) * 3), pb(pa.size());
    ASSERT_EQ(lodrt::pfrepDecodePositions(original, pa.data(), pa.size()), lodrt::Result::Ok);
    ASSERT_EQ(lodrt::pfrepDecodePositions(d.model, pb.data(), pb.size()), lodrt::Result::Ok);
    EXPECT_EQ(pa, pb);
    for (float eye : {3.0f, 0.4f}) {
        lodrt::PfrepView view;
        view.eye[0] = eye;
        for (int p = 0; p < 6; ++p) view.planes[p][3] = 1e6f;
        std::vector<uint8_t> mask_a(lodrt::pfrepMaskBytes(original)), mask_b(mask_a.size());
        std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(original));
        lodrt::pfrepMaskCoarsest(original, mask_a.data());
        lodrt::pfrepMaskCoarsest(d.model, mask_b.data());
        for (int s = 0; s < 4; ++s) {
            size_t ca = 0, cb = 0;
            ASSERT_EQ(lodrt::pfrepRefine(original, view, mask_a.data(), scratch.data(), scratch.size(), &ca),
                      lodrt::Result::Ok);
            ASSERT_EQ(lodrt::pfrepRefine(d.model, view, mask_b.data(), scratch.data(), scratch.size(), &cb),
                      lodrt::Result::Ok);
            EXPECT_EQ(ca, cb);
        }
        EXPECT_EQ(mask_a, mask_b);
        size_t nx = 0, ny = 0;
        ASSERT_EQ(lodrt::pfrepExtractSelective(original, mask_a.data(), x.data(), x.size() / 3, &nx), lodrt::Result::Ok);
        ASSERT_EQ(lodrt::pfrepExtractSelective(d.model, mask_b.data(), y.data(), y.size() / 3, &ny), lodrt::Result::Ok);
        EXPECT_EQ(sortedTriangles(x.data(), nx), sortedTriangles(y.data(), ny));
    }
}

TEST(PfrepFormat4Test, SameLevelsAndRefinementAsFormat2OnGeneratedMeshes) {
    expectSameAsFormat2(buildAndCode(lodbake_test::icosphere(3)), true);
    expectSameAsFormat2(buildAndCode(lodbake_test::bumpyIcosphere(3)), true);
    expectSameAsFormat2(buildAndCode(lodbake_test::flatGrid(24)), true); // borders
}

TEST(PfrepFormat4Test, SameLevelsAndRefinementAsFormat2OnScans) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    lodbake::Diagnostics diagnostics;
    for (const char* name : {"bunny_zipper.ply", "rocker_arm.obj"}) {
        auto loaded = lodbake::readMesh(lodbake_test::sharedMesh(name), {}, diagnostics);
        ASSERT_TRUE(loaded.ok()) << name;
        SCOPED_TRACE(name);
        expectSameAsFormat2(buildAndCode(loaded->mesh), false);
    }
}

// The pack's variant: the chain's own pass read as vertex removals, over chainPoints' numbering.
TEST(PfrepFormat4Test, CodesTheChainsOwnPass) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    lodbake::Diagnostics diagnostics;
    auto loaded = lodbake::readMesh(lodbake_test::sharedMesh("bunny_zipper.ply"), {}, diagnostics);
    ASSERT_TRUE(loaded.ok());
    lodbake::LodChainOptions options;
    options.measure_error = false;
    options.record_removals = true;
    auto chain = lodbake::buildLodChain(loaded->mesh, options, diagnostics);
    ASSERT_TRUE(chain.ok());
    auto shared = lodbake::buildPfrepFromChain(loaded->mesh, chain->removals, diagnostics);
    ASSERT_TRUE(shared.ok());
    Built b;
    b.build = std::move(*shared);
    ASSERT_TRUE(lodbake::chainPoints(loaded->mesh, b.lod0.points, b.lod0.triangles).ok());
    auto coded = lodbake::compressPfrepFormat4(b.build, b.lod0.points, b.lod0.triangles);
    ASSERT_TRUE(coded.ok()) << coded.status().message();
    b.coded = std::move(*coded);
    expectSameAsFormat2(b, false);
}

const Built& small() {
    static const Built b = buildAndCode(lodbake_test::bumpyIcosphere(1));
    return b;
}

TEST(PfrepFormat4Test, EveryTruncationIsAnError) {
    const Built& b = small();
    ASSERT_FALSE(b.coded.empty());
    for (size_t size = 0; size < b.coded.size(); ++size) {
        const std::vector<uint8_t> cut(b.coded.begin(), b.coded.begin() + std::ptrdiff_t(size));
        EXPECT_NE(decode4(cut, b.lod0.view()).result, lodrt::Result::Ok) << "cut at " << size;
    }
    std::vector<uint8_t> longer = b.coded;
    longer.push_back(0);
    EXPECT_NE(decode4(longer, b.lod0.view()).result, lodrt::Result::Ok);
}

// Any byte changed: an error, or a model that opened (the decoded blob passed openPfrep) and whose
// extraction runs inside its buffers.
TEST(PfrepFormat4Test, CorruptedBytesGiveAnErrorOrAValidModel) {
    const Built& b = small();
    ASSERT_FALSE(b.coded.empty());
    std::mt19937 rng(7);
    size_t opened = 0;
    for (size_t at = 0; at < b.coded.size(); ++at)
        for (uint8_t flip : {uint8_t(0x01), uint8_t(0x80), uint8_t(rng() | 1)}) {
            std::vector<uint8_t> bad = b.coded;
            bad[at] ^= flip;
            const Format4Decoded d = decode4(bad, b.lod0.view());
            if (d.result != lodrt::Result::Ok) continue;
            ++opened;
            std::vector<uint32_t> idx(lodrt::pfrepMaxTriangles(d.model) * 3 + 3);
            size_t n = 0;
            EXPECT_EQ(lodrt::pfrepExtractLevel(d.model, 0, idx.data(), idx.size() / 3, &n), lodrt::Result::Ok);
        }
    EXPECT_LT(opened, b.coded.size());
}

// LOD0 is input too: other counts, a point out of range, a repeated point, a different mesh.
TEST(PfrepFormat4Test, MismatchedLod0IsAnError) {
    const Built& b = small();
    ASSERT_FALSE(b.coded.empty());
    Lod0Points l = b.lod0;
    l.points.pop_back();
    EXPECT_EQ(decode4(b.coded, l.view()).result, lodrt::Result::BadStructure);
    l = b.lod0;
    l.triangles.resize(l.triangles.size() - 3);
    EXPECT_EQ(decode4(b.coded, l.view()).result, lodrt::Result::BadStructure);
    l = b.lod0;
    l.triangles[4] = uint32_t(l.points.size());
    EXPECT_EQ(decode4(b.coded, l.view()).result, lodrt::Result::BadStructure);
    l = b.lod0;
    l.triangles[1] = l.triangles[0];
    EXPECT_EQ(decode4(b.coded, l.view()).result, lodrt::Result::BadStructure);
    // Same counts, triangles shuffled: an error or a valid model, never a crash.
    l = b.lod0;
    std::mt19937 rng(3);
    for (int trial = 0; trial < 20; ++trial) {
        std::shuffle(l.triangles.begin(), l.triangles.end(), rng);
        bool repeated = false;
        for (size_t t = 0; t < l.triangles.size(); t += 3)
            repeated |= l.triangles[t] == l.triangles[t + 1] || l.triangles[t + 1] == l.triangles[t + 2] ||
                        l.triangles[t] == l.triangles[t + 2];
        const Format4Decoded d = decode4(b.coded, l.view());
        if (repeated) {
            EXPECT_EQ(d.result, lodrt::Result::BadStructure);
        }
    }
}

// The encoder refuses a build that does not replay on the LOD0 it is given, with a message.
TEST(PfrepFormat4Test, EncoderRefusesAnotherLod0) {
    const Built& b = small();
    ASSERT_FALSE(b.coded.empty());
    std::vector<uint32_t> triangles = b.lod0.triangles;
    triangles.resize(triangles.size() - 3);
    EXPECT_FALSE(lodbake::compressPfrepFormat4(b.build, b.lod0.points, triangles).ok());
    triangles = b.lod0.triangles;
    std::reverse(triangles.begin(), triangles.end()); // every triangle flipped: other fans
    auto flipped = lodbake::compressPfrepFormat4(b.build, b.lod0.points, triangles);
    EXPECT_FALSE(flipped.ok());
    lodbake::PfrepBuild other = b.build;
    other.rank_kept[0] = other.rank_point[0]; // not its own neighbour
    EXPECT_FALSE(lodbake::compressPfrepFormat4(other, b.lod0.points, b.lod0.triangles).ok());
}

TEST(PfrepFormat4Test, HeaderErrorsAndShortBuffers) {
    const Built& b = small();
    ASSERT_GE(b.coded.size(), size_t(lodrt::format::kPfrepHeaderSize));
    auto with32 = [&](size_t at, uint32_t v) {
        std::vector<uint8_t> c = b.coded;
        std::memcpy(c.data() + at, &v, 4);
        return c;
    };
    EXPECT_EQ(decode4(with32(0, 0x12345678u), b.lod0.view()).result, lodrt::Result::BadMagic);
    EXPECT_EQ(decode4(with32(4, 3), b.lod0.view()).result, lodrt::Result::UnsupportedVersion);
    EXPECT_EQ(decode4(with32(8, 0xFFFFFFF0u), b.lod0.view()).result, lodrt::Result::BadStructure);
    EXPECT_EQ(decode4(with32(56, 0xFFFFFFF0u), b.lod0.view()).result, lodrt::Result::BadStructure);
    EXPECT_EQ(decode4(with32(60, 8), b.lod0.view()).result, lodrt::Result::BadStructure); // an unknown flag
    EXPECT_EQ(decode4(with32(60, 4), b.lod0.view()).result, lodrt::Result::BadStructure); // a list without the check
    EXPECT_NE(decode4(with32(60, 7), b.lod0.view()).result, lodrt::Result::Ok); // a list that is not there
    EXPECT_NE(decode4(with32(60, 1), b.lod0.view()).result, lodrt::Result::Ok); // a tail the stream does not code
    lodrt::PfrepModel model;
    EXPECT_EQ(lodrt::openPfrep(b.coded.data(), b.coded.size(), &model), lodrt::Result::UnsupportedVersion);
    lodrt::PfrepCompressedInfo info3;
    EXPECT_EQ(lodrt::pfrepCompressedInfo(b.coded.data(), b.coded.size(), &info3), lodrt::Result::UnsupportedVersion);
    lodrt::PfrepFormat4Info info;
    ASSERT_EQ(lodrt::pfrepFormat4Info(b.coded.data(), b.coded.size(), &info), lodrt::Result::Ok);
    std::vector<uint8_t> out(info.decoded_bytes);
    std::vector<uint64_t> scratch((info.scratch_bytes + 7) / 8);
    const lodrt::PfrepLod0 lod0 = b.lod0.view();
    EXPECT_EQ(lodrt::pfrepDecodeFormat4(b.coded.data(), b.coded.size(), lod0, out.data(), out.size() - 1,
                                        scratch.data(), info.scratch_bytes, &model),
              lodrt::Result::BufferTooSmall);
    EXPECT_EQ(lodrt::pfrepDecodeFormat4(b.coded.data(), b.coded.size(), lod0, out.data(), out.size(), scratch.data(),
                                        info.scratch_bytes - 8, &model),
              lodrt::Result::BufferTooSmall);
    EXPECT_EQ(lodrt::pfrepDecodeFormat4(b.coded.data(), b.coded.size(), lod0, out.data(), out.size(), scratch.data(),
                                        info.scratch_bytes, &model),
              lodrt::Result::Ok);
}

// ---- Points welded by LOD0's quantization (a pack's LOD0 stream), told apart by the split list ----

// A pack's situation in miniature: `mesh` is LOD0 as built, `decoded` its vertices' positions as a
// quantized stream hands them back (same vertices and triangles), where some of the build's points
// fell on one position.
struct Welded {
    lodbake::Mesh mesh;
    std::vector<lodbake::Vec3f> decoded;
    Built b; // b.lod0: LOD0 numbered from `decoded` with the split list
    std::vector<uint8_t> split;
};

std::array<uint32_t, 3> keyOf(const lodbake::Vec3f& p) {
    std::array<uint32_t, 3> k;
    std::memcpy(k.data(), &p.x, 12);
    return k;
}

// pfrepNumberLod0Split of `decoded` over mesh's triangles with `split` (null: none).
lodrt::Result numberSplit(const std::vector<uint8_t>* split, const std::vector<lodbake::Vec3f>& decoded,
                          const std::vector<uint32_t>& indices, Lod0Points& out) {
    out.points.assign(decoded.size(), lodbake::Vec3f());
    out.triangles.assign(indices.size(), 0);
    std::vector<uint64_t> scratch((lodrt::pfrepNumberLod0ScratchBytes(uint32_t(decoded.size())) + 7) / 8);
    lodrt::PfrepLod0 lod0;
    const lodrt::Result r = lodrt::pfrepNumberLod0Split(
        split ? split->data() : nullptr, split ? split->size() : 0, &decoded[0].x, uint32_t(decoded.size()),
        indices.data(), uint32_t(indices.size() / 3), &out.points[0].x, out.points.size() * 3, out.triangles.data(),
        out.triangles.size(), scratch.data(), scratch.size() * 8, &lod0);
    if (r != lodrt::Result::Ok) return r;
    out.points.resize(lod0.point_count);
    out.triangles.resize(size_t(lod0.triangle_count) * 3);
    return r;
}

// `mesh` built and coded as format 4 against `decoded` (its vertices' positions as the stream hands
// them back) numbered with the split list.
Welded weldedFrom(lodbake::Mesh mesh, std::vector<lodbake::Vec3f> decoded) {
    Welded w;
    w.mesh = std::move(mesh);
    w.decoded = std::move(decoded);
    lodbake::Diagnostics diagnostics;
    auto build = lodbake::buildPfrep(w.mesh, {}, diagnostics);
    EXPECT_TRUE(build.ok()) << build.status().message();
    if (!build.ok()) return w;
    w.b.build = std::move(*build);
    // Labels: the input position bits; welds: the lowest vertex with the decoded position bits.
    std::vector<std::array<uint32_t, 3>> keys;
    for (const auto& p : w.mesh.positions) keys.push_back(keyOf(p));
    std::vector<uint32_t> labels(keys.size()), weld(keys.size());
    for (size_t v = 0; v < keys.size(); ++v) {
        labels[v] = uint32_t(std::find(keys.begin(), keys.end(), keys[v]) - keys.begin());
        weld[v] = uint32_t(v);
        for (size_t u = 0; u < v; ++u)
            if (keyOf(w.decoded[u]) == keyOf(w.decoded[v])) {
                weld[v] = uint32_t(u);
                break;
            }
    }
    w.split = lodbake::codePfrepSplitList(weld, labels);
    EXPECT_EQ(numberSplit(&w.split, w.decoded, w.mesh.indices, w.b.lod0), lodrt::Result::Ok);
    // The build's points (chainPoints) against the split LOD0's, corner by corner.
    Lod0Points built;
    EXPECT_TRUE(lodbake::chainPoints(w.mesh, built.points, built.triangles).ok());
    EXPECT_EQ(built.triangles.size(), w.b.lod0.triangles.size());
    std::vector<uint32_t> point_of(built.points.size(), UINT32_MAX);
    for (size_t c = 0; c < built.triangles.size() && c < w.b.lod0.triangles.size(); ++c) {
        uint32_t& q = point_of[built.triangles[c]];
        EXPECT_TRUE(q == UINT32_MAX || q == w.b.lod0.triangles[c]);
        q = w.b.lod0.triangles[c];
    }
    auto coded = lodbake::compressPfrepFormat4(w.b.build, w.b.lod0.points, w.b.lod0.triangles, point_of, w.split);
    EXPECT_TRUE(coded.ok()) << coded.status().message();
    if (coded.ok()) w.b.coded = std::move(*coded);
    return w;
}

// bumpyIcosphere(2) with one vertex duplicated (a seam: two vertices, one point of the build), its
// positions rounded to a 1/16384 grid, and then welded as a coarse quantization would weld them:
// two pairs of points apart, a pair joined by an edge (its two triangles flatten) and three points on
// one position; the seam's two vertices stay one weld that does not split.
Welded welded() {
    lodbake::Mesh mesh = lodbake_test::bumpyIcosphere(2);
    const uint32_t seam = uint32_t(mesh.positions.size());
    mesh.positions.push_back(mesh.positions[5]);
    for (size_t c = 0; c < mesh.indices.size(); ++c)
        if (mesh.indices[c] == 5) {
            mesh.indices[c] = seam; // the first triangle around 5 takes the copy
            break;
        }
    std::vector<lodbake::Vec3f> decoded = mesh.positions;
    for (auto& p : decoded)
        p = lodbake::Vec3f(std::round(p.x * 16384) / 16384, std::round(p.y * 16384) / 16384,
                           std::round(p.z * 16384) / 16384);
    const uint32_t a = mesh.indices[0], b = mesh.indices[1]; // joined by an edge
    for (auto pair : {std::array<uint32_t, 2>{10, 100}, std::array<uint32_t, 2>{20, 150}, std::array<uint32_t, 2>{b, a},
                      std::array<uint32_t, 2>{30, 60}, std::array<uint32_t, 2>{30, 120}})
        decoded[pair[1]] = decoded[pair[0]];
    return weldedFrom(std::move(mesh), std::move(decoded));
}

const Welded& weldedOnce() {
    static const Welded w = welded();
    return w;
}

// The whole pack-side decode: the blob's split list applied to `decoded`, then format 4 against it.
Format4Decoded decodeWelded(const std::vector<uint8_t>& coded, const std::vector<lodbake::Vec3f>& decoded,
                            const std::vector<uint32_t>& indices) {
    Format4Decoded d;
    const void* split = nullptr;
    size_t split_bytes = 0;
    d.result = lodrt::pfrepFormat4SplitList(coded.data(), coded.size(), &split, &split_bytes);
    if (d.result != lodrt::Result::Ok) return d;
    const std::vector<uint8_t> list(static_cast<const uint8_t*>(split),
                                    static_cast<const uint8_t*>(split) + split_bytes);
    Lod0Points lod0;
    d.result = numberSplit(split ? &list : nullptr, decoded, indices, lod0);
    if (d.result != lodrt::Result::Ok) return d;
    return decode4(coded, lod0.view());
}

TEST(PfrepFormat4Test, SplitListTellsWeldedPointsApart) {
    const Welded& w = weldedOnce();
    ASSERT_FALSE(w.b.coded.empty());
    // Without the list the welded LOD0 has fewer points (and the flattened triangles are gone).
    Lod0Points plain;
    ASSERT_EQ(numberSplit(nullptr, w.decoded, w.mesh.indices, plain), lodrt::Result::Ok);
    EXPECT_EQ(plain.points.size() + 5, w.b.lod0.points.size());
    EXPECT_EQ(plain.triangles.size() + 6, w.b.lod0.triangles.size());
    EXPECT_EQ(w.b.lod0.points.size(), w.mesh.positions.size() - 1); // the seam's copy is one point
    uint32_t flags = 0;
    std::memcpy(&flags, w.b.coded.data() + 60, 4);
    EXPECT_EQ(flags, lodrt::format::kPfrep4Flags);
    expectSameAsFormat2(w.b, true);
    // The pack decoder's path (list from the blob, numbering, decode) gives the same model.
    const Format4Decoded d = decodeWelded(w.b.coded, w.decoded, w.mesh.indices);
    ASSERT_EQ(d.result, lodrt::Result::Ok) << lodrt::resultName(d.result);
    EXPECT_EQ(d.model.vertex_count, w.b.lod0.points.size());
    // Without welds there is nothing to split: the list is not written (the blob is as before).
    std::vector<uint32_t> weld(5), labels = {0, 1, 2, 3, 3};
    for (uint32_t v = 0; v < 5; ++v) weld[v] = v == 4 ? 3 : v;
    EXPECT_EQ(lodbake::codePfrepSplitList(weld, labels).size(), 5u); // one 0 bit: the weld stays
    EXPECT_EQ(weld[4], 3u);
}

TEST(PfrepFormat4Test, SplitListTruncatedOrCorrupt) {
    const Welded& w = weldedOnce();
    ASSERT_FALSE(w.b.coded.empty());
    for (size_t size = 0; size < w.b.coded.size(); ++size) {
        const std::vector<uint8_t> cut(w.b.coded.begin(), w.b.coded.begin() + std::ptrdiff_t(size));
        EXPECT_NE(decodeWelded(cut, w.decoded, w.mesh.indices).result, lodrt::Result::Ok) << "cut at " << size;
    }
    // The list alone, cut at every length: an error, never a read past it.
    for (size_t size = 1; size < w.split.size(); ++size) {
        const std::vector<uint8_t> cut(w.split.begin(), w.split.begin() + std::ptrdiff_t(size));
        Lod0Points l;
        EXPECT_NE(numberSplit(&cut, w.decoded, w.mesh.indices, l), lodrt::Result::Ok)
            << "list cut at " << size;
    }
    // Any byte of the header, the list and the start of the stream changed: an error or a valid model
    // (a changed quantization box in the header still decodes). A changed list either decodes to the
    // same welds (a change in bits its last symbols do not depend on) and so to the same blob, or
    // numbers LOD0 otherwise, which the blob's LOD0 check refuses.
    const Format4Decoded reference = decodeWelded(w.b.coded, w.decoded, w.mesh.indices);
    ASSERT_EQ(reference.result, lodrt::Result::Ok);
    std::mt19937 rng(5);
    size_t refused = 0, tried = 0;
    const size_t list_begin = lodrt::format::kPfrepHeaderSize, list_end = list_begin + 4 + w.split.size();
    const size_t end = std::min(w.b.coded.size(), list_end + 16);
    for (size_t at = 0; at < end; ++at)
        for (uint8_t flip : {uint8_t(0x01), uint8_t(0x80), uint8_t(rng() | 1)}) {
            std::vector<uint8_t> bad = w.b.coded;
            bad[at] ^= flip;
            const bool in_list = at >= list_begin && at < list_end;
            tried += in_list ? 1 : 0;
            const Format4Decoded d = decodeWelded(bad, w.decoded, w.mesh.indices);
            if (d.result != lodrt::Result::Ok) {
                refused += in_list ? 1 : 0;
                continue;
            }
            if (in_list) {
                EXPECT_EQ(d.bytes, reference.bytes) << "list byte " << at;
            }
            std::vector<uint32_t> idx(lodrt::pfrepMaxTriangles(d.model) * 3 + 3);
            size_t n = 0;
            EXPECT_EQ(lodrt::pfrepExtractLevel(d.model, 0, idx.data(), idx.size() / 3, &n), lodrt::Result::Ok);
        }
    EXPECT_GT(refused * 2, tried);
    // A LOD0 welded otherwise than the blob's (one weld less): refused by the check.
    std::vector<lodbake::Vec3f> other = w.decoded;
    other[100] = w.mesh.positions[100];
    EXPECT_NE(decodeWelded(w.b.coded, other, w.mesh.indices).result, lodrt::Result::Ok);
}

// The pfrep fuzz target's format 4 LOD0: a torus of 8 x 6 points, built as runtime/tools/fuzz_pfrep.cpp
// builds it (the fuzz target then numbers the points by first use, as chainPoints does).
lodbake::Mesh fuzzTorus() {
    constexpr uint32_t kRing = 8, kTube = 6;
    lodbake::Mesh mesh;
    for (uint32_t i = 0; i < kRing; ++i)
        for (uint32_t j = 0; j < kTube; ++j) {
            const float u = float(i) * 6.2831853f / kRing, v = float(j) * 6.2831853f / kTube;
            mesh.positions.push_back(lodbake::Vec3f((2.0f + std::cos(v)) * std::cos(u),
                                                    (2.0f + std::cos(v)) * std::sin(u), std::sin(v)));
            const uint32_t a = i * kTube + j, b = ((i + 1) % kRing) * kTube + j;
            const uint32_t c = ((i + 1) % kRing) * kTube + (j + 1) % kTube, d = i * kTube + (j + 1) % kTube;
            mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
        }
    return mesh;
}

// The fuzz corpus's format 4 seed (tests/malformed/lbp/f4_torus.lbp) decodes against that LOD0, so
// the fuzz target and its replay reach the format 4 decoder and the refinement behind it. A fresh
// seed is written to the build's tests folder (copy it over the corpus file after a format change).
TEST(PfrepFormat4Test, FuzzTorusSeed) {
    const Built fresh = buildAndCode(fuzzTorus());
    ASSERT_FALSE(fresh.coded.empty());
    ASSERT_EQ(fresh.lod0.points.size(), 48u);
    std::ofstream(std::string(LODBAKE_TEST_BINARY_DIR) + "/f4_torus.lbp", std::ios::binary)
        .write(reinterpret_cast<const char*>(fresh.coded.data()), std::streamsize(fresh.coded.size()));
    std::ifstream in(lodbake_test::sourceDir() + "/tests/malformed/lbp/f4_torus.lbp", std::ios::binary);
    ASSERT_TRUE(in.good()) << "the fuzz corpus has no format 4 seed";
    const std::vector<uint8_t> seed((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const Format4Decoded d = decode4(seed, fresh.lod0.view());
    ASSERT_EQ(d.result, lodrt::Result::Ok) << lodrt::resultName(d.result);
    EXPECT_EQ(d.model.vertex_count, 48u);
    EXPECT_GT(d.model.removed_count, 0u);
}

// The format 4 seed with a split list (tests/malformed/lbp/f4_torus_split.lbp): the torus coded
// against its vertices with vertex 27 moved onto vertex 0's position (the fuzz target's welded
// torus), which the blob's list tells apart again. Written to the build's tests folder like the
// seed above.
TEST(PfrepFormat4Test, FuzzWeldedTorusSeed) {
    const lodbake::Mesh torus = fuzzTorus();
    std::vector<lodbake::Vec3f> decoded = torus.positions;
    decoded[27] = decoded[0];
    const Welded fresh = weldedFrom(torus, decoded);
    ASSERT_FALSE(fresh.b.coded.empty());
    ASSERT_FALSE(fresh.split.empty());
    std::ofstream(std::string(LODBAKE_TEST_BINARY_DIR) + "/f4_torus_split.lbp", std::ios::binary)
        .write(reinterpret_cast<const char*>(fresh.b.coded.data()), std::streamsize(fresh.b.coded.size()));
    std::ifstream in(lodbake_test::sourceDir() + "/tests/malformed/lbp/f4_torus_split.lbp", std::ios::binary);
    ASSERT_TRUE(in.good()) << "the fuzz corpus has no format 4 seed with a split list";
    const std::vector<uint8_t> seed((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const Format4Decoded d = decodeWelded(seed, decoded, torus.indices);
    ASSERT_EQ(d.result, lodrt::Result::Ok) << lodrt::resultName(d.result);
    EXPECT_EQ(d.model.vertex_count, 48u);
    EXPECT_GT(d.model.removed_count, 0u);
}

} // namespace
