#include <gtest/gtest.h>

#include "lodbake/core/file_io.h"
#include "lodbake/image/texture_resize.h"
#include "test_paths.h"

namespace {

using namespace lodbake;

TEST(TextureResizeTest, LevelSizesArePowerOfTwoFriendlyAndClamped) {
    auto size = [](uint32_t w, uint32_t h, double target, uint32_t lo, uint32_t hi) {
        const ImageSize s = levelTextureSize({w, h}, target, lo, hi);
        return std::make_pair(s.width, s.height);
    };
    EXPECT_EQ(size(2048, 2048, 300, 16, 4096), std::make_pair(512u, 512u));    // rounds up to a power of two
    EXPECT_EQ(size(2048, 1024, 300, 16, 4096), std::make_pair(512u, 256u));    // keeps the aspect ratio
    EXPECT_EQ(size(2048, 2048, 3, 16, 4096), std::make_pair(16u, 16u));        // min clamp
    EXPECT_EQ(size(2048, 2048, 5000, 16, 1024), std::make_pair(1024u, 1024u)); // max clamp
    EXPECT_EQ(size(512, 512, 5000, 16, 4096), std::make_pair(512u, 512u));     // never upscales
    EXPECT_EQ(size(1, 1, 0.1, 1, 4096), std::make_pair(1u, 1u));
}

TEST(TextureResizeTest, ResizesPngKeepingFormatAndIsDeterministic) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    auto bytes = readFileBytes(lodbake_test::sharedMesh("spot_texture.png"));
    ASSERT_TRUE(bytes.ok()) << bytes.status().message();
    auto source = probeImageSize(*bytes, "spot");
    ASSERT_TRUE(source.ok()) << source.status().message();
    TextureResizeOptions options;
    options.size = levelTextureSize(*source, 64, 16, 4096);
    auto a = resizeEncodedImage(*bytes, "spot", options);
    ASSERT_TRUE(a.ok()) << a.status().message();
    auto b = resizeEncodedImage(*bytes, "spot", options);
    ASSERT_TRUE(b.ok());
    EXPECT_EQ(*a, *b);
    ASSERT_GE(a->size(), 8u);
    EXPECT_EQ((*a)[1], 'P'); // still a PNG
    auto out = probeImageSize(*a, "resized");
    ASSERT_TRUE(out.ok());
    EXPECT_EQ(out->width, options.size.width);
    EXPECT_EQ(out->height, options.size.height);
    EXPECT_LE(std::max(out->width, out->height), 64u);
}

TEST(TextureResizeTest, RejectsWhatIsNotAnImage) {
    const std::vector<uint8_t> junk{1, 2, 3, 4, 5, 6, 7, 8, 9};
    EXPECT_FALSE(probeImageSize(junk, "junk").ok());
    TextureResizeOptions options;
    options.size = {4, 4};
    const auto r = resizeEncodedImage(junk, "junk.png", options);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.status().message().find("junk.png: not a PNG or JPEG image"), std::string::npos);
}

} // namespace
