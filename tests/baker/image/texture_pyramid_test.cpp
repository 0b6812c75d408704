// Texture levels from one decoded pyramid: the bytes do not depend on the thread count, filtering
// happens in linear light for colour textures (and not for data textures), constants stay constant,
// odd sizes halve by rounding up, and 16-bit and alpha channels survive.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "core/parallel.h"
#include "lodbake/image/texture_resize.h"
#include "test_png.h"

namespace {

using namespace lodbake;

std::vector<uint8_t> noisePng(uint32_t width, uint32_t height, uint32_t channels, uint32_t bits, uint32_t seed) {
    std::mt19937 rng(seed);
    std::vector<uint32_t> samples(size_t(width) * height * channels);
    for (uint32_t& s : samples) s = rng() % (bits == 16 ? 65536u : 256u);
    return lodbake_test::makePng(width, height, channels, bits, samples);
}

std::vector<std::vector<uint8_t>> levels(const std::vector<uint8_t>& png, const std::vector<ImageSize>& sizes,
                                         bool is_srgb) {
    TextureResizeOptions options;
    options.is_srgb = is_srgb;
    auto r = resizeEncodedImageLevels(png, "test.png", sizes, options);
    EXPECT_TRUE(r.ok()) << r.status().message();
    return r.ok() ? *r : std::vector<std::vector<uint8_t>>{};
}

DecodedImage decoded(const std::vector<uint8_t>& png) {
    auto r = decodeImage(png, "level.png");
    EXPECT_TRUE(r.ok()) << r.status().message();
    return r.ok() ? *r : DecodedImage{};
}

TEST(TexturePyramidTest, SameBytesAtAnyThreadCount) {
    const std::vector<ImageSize> sizes{{150, 100}, {75, 50}, {38, 25}, {19, 13}, {10, 7}, {1, 1}, {120, 90}};
    for (const auto& [channels, bits] : {std::make_pair(3u, 8u), std::make_pair(4u, 8u), std::make_pair(2u, 16u)}) {
        SCOPED_TRACE(std::to_string(channels) + " channels, " + std::to_string(bits) + " bits");
        const std::vector<uint8_t> png = noisePng(300, 200, channels, bits, channels * 100 + bits);
        std::vector<std::vector<uint8_t>> one;
        {
            ScopedThreadLimit limit(1);
            one = levels(png, sizes, true);
        }
        ASSERT_EQ(one.size(), sizes.size());
        for (size_t threads : {2, 3, 8}) {
            ScopedThreadLimit limit(threads);
            EXPECT_EQ(levels(png, sizes, true), one) << threads << " threads";
        }
        for (size_t i = 0; i < sizes.size(); ++i) {
            const DecodedImage level = decoded(one[i]);
            EXPECT_EQ(level.width, sizes[i].width);
            EXPECT_EQ(level.height, sizes[i].height);
            EXPECT_EQ(level.channels, channels);
            EXPECT_EQ(level.bits, bits);
        }
    }
}

// A one-texel black and white checker averages to half the light: sRGB 188, not the 128 of
// averaging the stored values. A data texture (normal map) averages the stored values.
TEST(TexturePyramidTest, ColourFiltersInLinearLightDataDoesNot) {
    const std::vector<uint8_t> png =
        lodbake_test::makeRgbPng(64, 64, [](uint32_t x, uint32_t y) -> std::array<uint32_t, 3> {
            const uint32_t v = (x + y) % 2 ? 255 : 0;
            return {v, v, v};
        });
    for (const bool is_srgb : {true, false}) {
        SCOPED_TRACE(is_srgb ? "colour" : "data");
        const auto out = levels(png, {{32, 32}, {16, 16}}, is_srgb);
        ASSERT_EQ(out.size(), 2u);
        for (const std::vector<uint8_t>& level : out) {
            const DecodedImage image = decoded(level);
            ASSERT_EQ(image.samples.size(), size_t(image.width) * image.height * 3);
            // Linear 0.5 is sRGB 187.5; the edges, where the filter's taps are clamped, are left out.
            const int expected = is_srgb ? 188 : 128;
            for (uint32_t y = 3; y + 3 < image.height; ++y)
                for (uint32_t x = 3; x + 3 < image.width; ++x)
                    ASSERT_NEAR(int(image.samples[(size_t(y) * image.width + x) * 3]), expected, 1)
                        << image.width << " px at " << x << ", " << y;
        }
    }
}

// A constant colour (and a constant alpha) comes back exactly at every size, odd ones included.
TEST(TexturePyramidTest, ConstantImagesStayConstantAndOddSizesRoundUp) {
    std::vector<uint32_t> samples;
    for (int i = 0; i < 45 * 27; ++i) samples.insert(samples.end(), {200, 100, 50, 77});
    const std::vector<uint8_t> png = lodbake_test::makePng(45, 27, 4, 8, samples);
    const std::vector<ImageSize> sizes{{23, 14}, {12, 7}, {6, 4}, {3, 2}, {2, 1}, {1, 1}, {45, 27}};
    const auto out = levels(png, sizes, true);
    ASSERT_EQ(out.size(), sizes.size());
    for (size_t i = 0; i < out.size(); ++i) {
        const DecodedImage image = decoded(out[i]);
        EXPECT_EQ(image.width, sizes[i].width);
        EXPECT_EQ(image.height, sizes[i].height);
        ASSERT_EQ(image.samples.size(), size_t(image.width) * image.height * 4);
        for (size_t p = 0; p < image.samples.size(); p += 4) {
            const std::array<int, 4> texel{image.samples[p], image.samples[p + 1], image.samples[p + 2],
                                           image.samples[p + 3]};
            ASSERT_EQ(texel, (std::array<int, 4>{200, 100, 50, 77})) << sizes[i].width << "x" << sizes[i].height
                                                                      << " texel " << p / 4;
        }
    }
}

// The halving keeps where things are: a white left half and black right half stay split in the
// middle at every level (a shifted filter would smear one side into the other).
TEST(TexturePyramidTest, LevelsKeepFeaturesInPlace) {
    const std::vector<uint8_t> png =
        lodbake_test::makeRgbPng(128, 32, [](uint32_t x, uint32_t) -> std::array<uint32_t, 3> {
            const uint32_t v = x < 64 ? 255 : 0;
            return {v, v, v};
        });
    for (const ImageSize size : {ImageSize{64, 16}, ImageSize{32, 8}, ImageSize{16, 4}}) {
        const auto out = levels(png, {size}, false);
        ASSERT_EQ(out.size(), 1u);
        const DecodedImage image = decoded(out[0]);
        for (uint32_t x = 0; x < size.width; ++x) {
            const int value = image.samples[size_t(x) * 3];
            // Mirror symmetry about the middle: value(x) + value(w - 1 - x) = 255.
            const int mirror = image.samples[size_t(size.width - 1 - x) * 3];
            EXPECT_NEAR(value + mirror, 255, 1) << size.width << " px, x " << x;
            if (x < size.width / 4) {
                EXPECT_GT(value, 240) << size.width << " px, x " << x;
            }
            if (x >= size.width - size.width / 4) {
                EXPECT_LT(value, 15) << size.width << " px, x " << x;
            }
        }
    }
}

} // namespace
