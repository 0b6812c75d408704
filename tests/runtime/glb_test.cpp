#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "glb_builder.h"
#include "lodrt/glb.h"

using lodrt::GlbView;
using lodrt::Result;
using lodrt_test::Chunk;
using lodrt_test::kChunkBin;
using lodrt_test::kChunkJson;
using lodrt_test::makeGlb;
using lodrt_test::makeGlbChunks;

namespace {

std::vector<uint8_t> bytesOf(const std::string& text) {
    return std::vector<uint8_t>(text.begin(), text.end());
}

Result parse(const std::vector<uint8_t>& bytes, GlbView* view) {
    return lodrt::parseGlb(bytes.data(), bytes.size(), view);
}

bool isEmpty(const GlbView& view) {
    return !view.json && view.json_size == 0 && !view.bin && view.bin_size == 0 && !view.is_binary;
}

} // namespace

TEST(GlbTest, ParsesJsonAndBinChunks) {
    const std::vector<uint8_t> bin = {1, 2, 3, 4, 5};
    const std::vector<uint8_t> glb = makeGlb("{\"a\":1}", bin);
    GlbView view;
    ASSERT_EQ(parse(glb, &view), Result::Ok);
    EXPECT_TRUE(view.is_binary);
    ASSERT_EQ(view.json_size, 8u); // 7 bytes padded with one space
    EXPECT_EQ(std::string(reinterpret_cast<const char*>(view.json), view.json_size), "{\"a\":1} ");
    EXPECT_EQ(view.json, glb.data() + 20);
    ASSERT_EQ(view.bin_size, 8u);
    EXPECT_EQ(view.bin, glb.data() + 36);
    EXPECT_EQ(std::memcmp(view.bin, bin.data(), bin.size()), 0);
}

TEST(GlbTest, AcceptsGlbWithoutBinChunk) {
    GlbView view;
    ASSERT_EQ(parse(makeGlb("{}"), &view), Result::Ok);
    EXPECT_TRUE(view.is_binary);
    EXPECT_EQ(view.bin, nullptr);
    EXPECT_EQ(view.bin_size, 0u);
}

TEST(GlbTest, AcceptsPlainGltfJson) {
    const std::vector<uint8_t> text = bytesOf("  \n{\"asset\":{}}");
    GlbView view;
    ASSERT_EQ(parse(text, &view), Result::Ok);
    EXPECT_FALSE(view.is_binary);
    EXPECT_EQ(view.json, text.data());
    EXPECT_EQ(view.json_size, text.size());
    EXPECT_EQ(view.bin, nullptr);

    const std::vector<uint8_t> with_bom = bytesOf("\xEF\xBB\xBF{}");
    EXPECT_EQ(parse(with_bom, &view), Result::Ok);
    EXPECT_FALSE(view.is_binary);
}

TEST(GlbTest, SkipsUnknownChunkTypes) {
    std::vector<Chunk> chunks = {{kChunkJson, bytesOf("{}  ")}, {kChunkBin, {9, 9, 9, 9}}, {0x12345678u, {1, 2, 3, 4}}};
    const std::vector<uint8_t> glb = makeGlbChunks(chunks);
    GlbView view;
    ASSERT_EQ(parse(glb, &view), Result::Ok);
    EXPECT_EQ(view.bin_size, 4u);
    EXPECT_EQ(view.bin[0], 9);
}

TEST(GlbTest, EveryTruncatedPrefixFailsCleanly) {
    const std::vector<uint8_t> glb = lodrt_test::quadGlb();
    for (size_t size = 0; size < glb.size(); ++size) {
        // A copy of exactly `size` bytes so ASan catches any read past the prefix.
        std::vector<uint8_t> prefix(glb.begin(), glb.begin() + size);
        GlbView view;
        view.json_size = 77; // must be reset
        const Result result = lodrt::parseGlb(size ? prefix.data() : nullptr, size, &view);
        EXPECT_EQ(result, Result::Truncated) << "prefix of " << size << " bytes";
        EXPECT_TRUE(isEmpty(view));
    }
}

TEST(GlbTest, RejectsTrailingBytes) {
    std::vector<uint8_t> glb = makeGlb("{}", {1, 2, 3, 4});
    glb.push_back(0);
    GlbView view;
    EXPECT_EQ(parse(glb, &view), Result::TrailingBytes);
    EXPECT_TRUE(isEmpty(view));
    // If the header claims the extra bytes too, they form an incomplete chunk header.
    for (int extra = 1; extra < 8; ++extra) {
        std::vector<uint8_t> longer = makeGlb("{}", {1, 2, 3, 4});
        longer.resize(longer.size() + extra, 0);
        lodrt_test::setU32(longer, 8, uint32_t(longer.size()));
        EXPECT_NE(parse(longer, &view), Result::Ok) << extra;
    }
    // Eight zero bytes are a complete empty chunk of unknown type 0, which the spec says to skip.
    std::vector<uint8_t> empty_chunk = makeGlb("{}", {1, 2, 3, 4});
    empty_chunk.resize(empty_chunk.size() + 8, 0);
    lodrt_test::setU32(empty_chunk, 8, uint32_t(empty_chunk.size()));
    EXPECT_EQ(parse(empty_chunk, &view), Result::Ok);
}

TEST(GlbTest, RejectsBadMagic) {
    std::vector<uint8_t> glb = makeGlb("{}");
    glb[3] = 'X';
    GlbView view;
    EXPECT_EQ(parse(glb, &view), Result::BadMagic);
    EXPECT_EQ(parse(bytesOf("[1,2]"), &view), Result::BadMagic);
    EXPECT_EQ(parse(bytesOf("   "), &view), Result::BadMagic);
    EXPECT_EQ(parse(bytesOf("PK\x03\x04...."), &view), Result::BadMagic);
    EXPECT_TRUE(isEmpty(view));
}

TEST(GlbTest, RejectsUnknownVersion) {
    for (uint32_t version : {0u, 1u, 3u, 0xFFFFFFFFu}) {
        GlbView view;
        EXPECT_EQ(parse(makeGlbChunks({{kChunkJson, bytesOf("{}  ")}}, version), &view), Result::UnsupportedVersion)
            << version;
    }
}

TEST(GlbTest, RejectsLengthLies) {
    std::vector<uint8_t> glb = makeGlb("{}", {1, 2, 3, 4});
    GlbView view;
    std::vector<uint8_t> header_lie = glb;
    lodrt_test::setU32(header_lie, 8, uint32_t(glb.size() + 4));
    EXPECT_EQ(parse(header_lie, &view), Result::Truncated);
    lodrt_test::setU32(header_lie, 8, 0xFFFFFFFFu);
    EXPECT_EQ(parse(header_lie, &view), Result::Truncated);

    std::vector<uint8_t> chunk_lie = glb;
    lodrt_test::setU32(chunk_lie, 12, 0xFFFFFFFCu); // JSON chunk length far past the end
    EXPECT_EQ(parse(chunk_lie, &view), Result::Truncated);
    chunk_lie = glb;
    lodrt_test::setU32(chunk_lie, 24, 8); // BIN chunk claims 8 bytes, 4 exist
    EXPECT_EQ(parse(chunk_lie, &view), Result::Truncated);
    chunk_lie = glb;
    lodrt_test::setU32(chunk_lie, 12, 0); // an empty JSON chunk: then "{}  " is read as a chunk header
    EXPECT_EQ(parse(chunk_lie, &view), Result::BadChunk);
}

TEST(GlbTest, RejectsMisalignedChunks) {
    GlbView view;
    EXPECT_EQ(parse(makeGlbChunks({{kChunkJson, bytesOf("{}   ")}}), &view), Result::BadChunk);
    std::vector<uint8_t> glb = makeGlbChunks({{kChunkJson, bytesOf("{}  ")}, {kChunkBin, {1, 2, 3}}});
    EXPECT_NE(parse(glb, &view), Result::Ok);
    glb.push_back(0); // total now a multiple of 4, BIN length 3 still is not
    lodrt_test::setU32(glb, 8, uint32_t(glb.size()));
    EXPECT_EQ(parse(glb, &view), Result::BadChunk);
}

TEST(GlbTest, RejectsMissingOrMisplacedJsonChunk) {
    GlbView view;
    EXPECT_EQ(parse(makeGlbChunks({}), &view), Result::BadChunk);                          // header only
    EXPECT_EQ(parse(makeGlbChunks({{kChunkBin, {1, 2, 3, 4}}}), &view), Result::BadChunk); // BIN first
    EXPECT_EQ(parse(makeGlbChunks({{kChunkJson, {}}}), &view), Result::BadChunk);          // empty JSON
    EXPECT_EQ(parse(makeGlbChunks({{kChunkJson, bytesOf("{}  ")}, {kChunkJson, bytesOf("{}  ")}}), &view),
              Result::BadChunk);
    EXPECT_EQ(
        parse(makeGlbChunks({{kChunkJson, bytesOf("{}  ")}, {kChunkBin, {1, 1, 1, 1}}, {kChunkBin, {2, 2, 2, 2}}}),
              &view),
        Result::BadChunk);
    EXPECT_EQ(
        parse(makeGlbChunks({{kChunkJson, bytesOf("{}  ")}, {7u, {0, 0, 0, 0}}, {kChunkBin, {2, 2, 2, 2}}}), &view),
        Result::BadChunk);
}

TEST(GlbTest, RejectsNullArguments) {
    const std::vector<uint8_t> glb = makeGlb("{}");
    GlbView view;
    EXPECT_EQ(lodrt::parseGlb(glb.data(), glb.size(), nullptr), Result::InvalidArgument);
    EXPECT_EQ(lodrt::parseGlb(nullptr, 4, &view), Result::InvalidArgument);
    EXPECT_EQ(lodrt::parseGlb(nullptr, 0, &view), Result::Truncated);
}
