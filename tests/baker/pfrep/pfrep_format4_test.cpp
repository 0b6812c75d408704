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
    EXPECT_EQ(decode4(with32(60, 4), b.lod0.view()).result, lodrt::Result::BadStructure); // an unknown flag
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

} // namespace
