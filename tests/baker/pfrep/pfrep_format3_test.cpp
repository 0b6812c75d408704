// PfrepFormat3Test: a format 3 blob decodes to exactly the format 2 blob it was coded from (so every
// level, fan and refinement is format 2's), and the decoder survives every truncation and
// corruption of a blob with an error or a valid model, never a read or write outside its buffers
// (the sanitizer builds run these too).
#include <gtest/gtest.h>

#include <cstring>
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

struct Decoded {
    lodrt::Result result = lodrt::Result::InvalidArgument;
    std::vector<uint8_t> bytes;
    lodrt::PfrepModel model;
};

// Decodes with buffers of exactly the sizes the header asks for (capped for hostile headers).
Decoded decode(const std::vector<uint8_t>& coded) {
    Decoded d;
    lodrt::PfrepCompressedInfo info;
    d.result = lodrt::pfrepCompressedInfo(coded.data(), coded.size(), &info);
    if (d.result != lodrt::Result::Ok) return d;
    if (info.decoded_bytes > (64u << 20) || info.scratch_bytes > (512u << 20)) {
        d.result = lodrt::Result::OutOfMemory;
        return d;
    }
    d.bytes.resize(info.decoded_bytes);
    std::vector<uint64_t> scratch((info.scratch_bytes + 7) / 8);
    d.result = lodrt::pfrepDecompress(coded.data(), coded.size(), d.bytes.data(), d.bytes.size(), scratch.data(),
                                      info.scratch_bytes, &d.model);
    return d;
}

std::vector<uint8_t> buildBlob(const lodbake::Mesh& mesh) {
    lodbake::Diagnostics diagnostics;
    auto build = lodbake::buildPfrep(mesh, {}, diagnostics);
    EXPECT_TRUE(build.ok()) << build.status().message();
    return build.ok() ? build->blob : std::vector<uint8_t>();
}

// Byte equality, then what it implies checked through the API: the same levels, and the same
// view-dependent refinement from the same camera.
void expectSameAsFormat2(const std::vector<uint8_t>& blob) {
    auto coded = lodbake::compressPfrep(blob);
    ASSERT_TRUE(coded.ok()) << coded.status().message();
    EXPECT_LT(coded->size(), blob.size());
    const Decoded d = decode(*coded);
    ASSERT_EQ(d.result, lodrt::Result::Ok) << lodrt::resultName(d.result);
    ASSERT_EQ(d.bytes, blob);
    lodrt::PfrepModel original;
    ASSERT_EQ(lodrt::openPfrep(blob.data(), blob.size(), &original), lodrt::Result::Ok);
    std::vector<uint32_t> a(lodrt::pfrepMaxTriangles(original) * 3), b(a.size());
    for (uint32_t k : {0u, original.removed_count / 3, original.removed_count}) {
        size_t na = 0, nb = 0;
        ASSERT_EQ(lodrt::pfrepExtractLevel(original, k, a.data(), a.size() / 3, &na), lodrt::Result::Ok);
        ASSERT_EQ(lodrt::pfrepExtractLevel(d.model, k, b.data(), b.size() / 3, &nb), lodrt::Result::Ok);
        ASSERT_EQ(na, nb);
        EXPECT_TRUE(std::equal(a.begin(), a.begin() + std::ptrdiff_t(na * 3), b.begin()));
    }
    lodrt::PfrepView view;
    view.eye[0] = 3.0f;
    for (int p = 0; p < 6; ++p) view.planes[p][3] = 1e6f;
    std::vector<uint8_t> mask_a(lodrt::pfrepMaskBytes(original)), mask_b(mask_a.size());
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(original));
    lodrt::pfrepMaskCoarsest(original, mask_a.data());
    lodrt::pfrepMaskCoarsest(d.model, mask_b.data());
    for (int step = 0; step < 4; ++step) {
        size_t ca = 0, cb = 0;
        ASSERT_EQ(lodrt::pfrepRefine(original, view, mask_a.data(), scratch.data(), scratch.size(), &ca), lodrt::Result::Ok);
        ASSERT_EQ(lodrt::pfrepRefine(d.model, view, mask_b.data(), scratch.data(), scratch.size(), &cb), lodrt::Result::Ok);
        EXPECT_EQ(ca, cb);
    }
    EXPECT_EQ(mask_a, mask_b);
}

TEST(PfrepFormat3Test, DecodesToTheFormat2BlobOnGeneratedMeshes) {
    expectSameAsFormat2(buildBlob(lodbake_test::icosphere(3)));
    expectSameAsFormat2(buildBlob(lodbake_test::bumpyIcosphere(3)));
    expectSameAsFormat2(buildBlob(lodbake_test::flatGrid(24))); // borders
}

TEST(PfrepFormat3Test, DecodesToTheFormat2BlobOnScans) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    lodbake::Diagnostics diagnostics;
    for (const char* name : {"bunny_zipper.ply", "rocker_arm.obj"}) {
        auto loaded = lodbake::readMesh(lodbake_test::sharedMesh(name), {}, diagnostics);
        ASSERT_TRUE(loaded.ok()) << name;
        SCOPED_TRACE(name);
        expectSameAsFormat2(buildBlob(loaded->mesh));
    }
    // The pack's variant: the chain's own pass read as vertex removals.
    auto loaded = lodbake::readMesh(lodbake_test::sharedMesh("bunny_zipper.ply"), {}, diagnostics);
    ASSERT_TRUE(loaded.ok());
    lodbake::LodChainOptions options;
    options.measure_error = false;
    options.record_removals = true;
    auto chain = lodbake::buildLodChain(loaded->mesh, options, diagnostics);
    ASSERT_TRUE(chain.ok());
    auto shared = lodbake::buildPfrepFromChain(loaded->mesh, chain->removals, diagnostics);
    ASSERT_TRUE(shared.ok());
    expectSameAsFormat2(shared->blob);
}

std::vector<uint8_t> smallCoded() {
    auto coded = lodbake::compressPfrep(buildBlob(lodbake_test::bumpyIcosphere(1)));
    EXPECT_TRUE(coded.ok());
    return coded.ok() ? *coded : std::vector<uint8_t>();
}

TEST(PfrepFormat3Test, EveryTruncationIsAnError) {
    const std::vector<uint8_t> coded = smallCoded();
    ASSERT_FALSE(coded.empty());
    for (size_t size = 0; size < coded.size(); ++size) {
        const std::vector<uint8_t> cut(coded.begin(), coded.begin() + std::ptrdiff_t(size));
        const Decoded d = decode(cut);
        EXPECT_NE(d.result, lodrt::Result::Ok) << "cut at " << size;
    }
    std::vector<uint8_t> longer = coded;
    longer.push_back(0);
    EXPECT_NE(decode(longer).result, lodrt::Result::Ok);
}

// Any byte changed: an error, or a model that opened (the decoded blob passed openPfrep) and whose
// extraction and refinement run inside their buffers.
TEST(PfrepFormat3Test, CorruptedBytesGiveAnErrorOrAValidModel) {
    const std::vector<uint8_t> coded = smallCoded();
    ASSERT_FALSE(coded.empty());
    std::mt19937 rng(7);
    size_t opened = 0;
    for (size_t at = 0; at < coded.size(); ++at)
        for (uint8_t flip : {uint8_t(0x01), uint8_t(0x80), uint8_t(rng() | 1)}) {
            std::vector<uint8_t> bad = coded;
            bad[at] ^= flip;
            const Decoded d = decode(bad);
            if (d.result != lodrt::Result::Ok) continue;
            ++opened;
            std::vector<uint32_t> idx(lodrt::pfrepMaxTriangles(d.model) * 3 + 3);
            size_t n = 0;
            EXPECT_EQ(lodrt::pfrepExtractLevel(d.model, 0, idx.data(), idx.size() / 3, &n), lodrt::Result::Ok);
        }
    // Most changes are caught (the stream must end exactly and rebuild a valid blob).
    EXPECT_LT(opened, coded.size());
}

TEST(PfrepFormat3Test, HeaderErrorsAndShortBuffers) {
    const std::vector<uint8_t> coded = smallCoded();
    ASSERT_GE(coded.size(), size_t(lodrt::format::kPfrepHeaderSize));
    auto with32 = [&](size_t at, uint32_t v) {
        std::vector<uint8_t> b = coded;
        std::memcpy(b.data() + at, &v, 4);
        return b;
    };
    EXPECT_EQ(decode(with32(0, 0x12345678u)).result, lodrt::Result::BadMagic);
    EXPECT_EQ(decode(with32(4, 9)).result, lodrt::Result::UnsupportedVersion);
    EXPECT_EQ(decode(with32(8, 0xFFFFFFF0u)).result, lodrt::Result::BadStructure);
    EXPECT_EQ(decode(with32(60, 1)).result, lodrt::Result::BadStructure);
    // A format 2 blob is not format 3, and the other way round.
    lodrt::PfrepCompressedInfo info;
    const std::vector<uint8_t> blob = buildBlob(lodbake_test::bumpyIcosphere(1));
    EXPECT_EQ(lodrt::pfrepCompressedInfo(blob.data(), blob.size(), &info), lodrt::Result::UnsupportedVersion);
    lodrt::PfrepModel model;
    EXPECT_EQ(lodrt::openPfrep(coded.data(), coded.size(), &model), lodrt::Result::UnsupportedVersion);
    ASSERT_EQ(lodrt::pfrepCompressedInfo(coded.data(), coded.size(), &info), lodrt::Result::Ok);
    EXPECT_EQ(info.decoded_bytes, blob.size());
    std::vector<uint8_t> out(info.decoded_bytes);
    std::vector<uint64_t> scratch((info.scratch_bytes + 7) / 8);
    EXPECT_EQ(lodrt::pfrepDecompress(coded.data(), coded.size(), out.data(), out.size() - 1, scratch.data(),
                                     info.scratch_bytes, &model),
              lodrt::Result::BufferTooSmall);
    EXPECT_EQ(lodrt::pfrepDecompress(coded.data(), coded.size(), out.data(), out.size(), scratch.data(),
                                     info.scratch_bytes - 8, &model),
              lodrt::Result::BufferTooSmall);
    EXPECT_EQ(lodrt::pfrepDecompress(coded.data(), coded.size(), out.data(), out.size(), scratch.data(),
                                     info.scratch_bytes, &model),
              lodrt::Result::Ok);
}

} // namespace
