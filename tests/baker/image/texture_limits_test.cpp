// Decompression bombs: an image header claiming more pixels than TextureResizeOptions allows is
// refused before anything is decoded.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/image/texture_resize.h"

namespace {

using namespace lodbake;

uint32_t crc32(const uint8_t* data, size_t size) {
    uint32_t crc = 0xffffffffu;
    for (size_t i = 0; i < size; ++i) {
        crc ^= data[i];
        for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
    }
    return ~crc;
}

void putU32(std::vector<uint8_t>& out, uint32_t v) {
    for (int shift = 24; shift >= 0; shift -= 8) out.push_back(uint8_t(v >> shift));
}

void putChunk(std::vector<uint8_t>& out, const char* type, const std::vector<uint8_t>& body) {
    putU32(out, uint32_t(body.size()));
    std::vector<uint8_t> typed(type, type + 4);
    typed.insert(typed.end(), body.begin(), body.end());
    out.insert(out.end(), typed.begin(), typed.end());
    putU32(out, crc32(typed.data(), typed.size()));
}

// A PNG whose IHDR claims width x height RGBA8 pixels, with one tiny (invalid) IDAT chunk: a few
// dozen bytes that a decoder would expand to width * height * 4 bytes or more.
std::vector<uint8_t> pngClaiming(uint32_t width, uint32_t height) {
    std::vector<uint8_t> png{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    std::vector<uint8_t> ihdr;
    putU32(ihdr, width);
    putU32(ihdr, height);
    ihdr.insert(ihdr.end(), {8, 6, 0, 0, 0}); // 8 bits, RGBA, deflate, adaptive filter, no interlace
    putChunk(png, "IHDR", ihdr);
    putChunk(png, "IDAT", {0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01});
    putChunk(png, "IEND", {});
    return png;
}

TEST(TextureLimitsTest, RefusesHugeImageBeforeDecoding) {
    const std::vector<uint8_t> bomb = pngClaiming(100000, 100000);
    const auto probed = probeImageSize(bomb, "bomb.png");
    ASSERT_TRUE(probed.ok()) << probed.status().message(); // the header alone is fine
    EXPECT_EQ(probed->width, 100000u);
    TextureResizeOptions options;
    const auto r = resizeEncodedImageLevels(bomb, "bomb.png", {{64, 64}}, options);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.status().code(), StatusCode::ResourceLimit);
    EXPECT_EQ(r.status().message(), "bomb.png: image header: 100000 x 100000 pixels, expected at most 268435456");
}

TEST(TextureLimitsTest, LimitIsConfigurable) {
    const std::vector<uint8_t> png = pngClaiming(64, 64);
    TextureResizeOptions options;
    options.max_source_pixels = 64 * 64 - 1;
    const auto r = resizeEncodedImageLevels(png, "small.png", {{16, 16}}, options);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.status().code(), StatusCode::ResourceLimit);
    options.max_source_pixels = 64 * 64;
    const auto decoded = resizeEncodedImageLevels(png, "small.png", {{16, 16}}, options);
    ASSERT_FALSE(decoded.ok()); // past the limit check, the bogus pixel data fails to decode
    EXPECT_NE(decoded.status().code(), StatusCode::ResourceLimit) << decoded.status().message();
}

} // namespace
