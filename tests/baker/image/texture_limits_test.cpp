// Hostile and damaged images: an image header claiming more pixels than TextureResizeOptions allows
// is refused before anything is decoded; truncated PNG and JPEG files, corrupt headers and corrupt
// pixel data fail with one line naming the file, through the library and through `lodbake bake`
// (no pack written). The images are built here byte by byte (a stored-deflate PNG, a baseline JPEG
// with one-code Huffman tables), so the cases need no image library.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "../gltf/gltf_test_util.h"
#include "lodbake/core/file_io.h"
#include "lodbake/image/texture_resize.h"
#include "test_paths.h"

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#include <sanitizer/lsan_interface.h>
#define LODBAKE_TEST_WITH_LSAN 1
#endif
#endif

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

uint32_t adler32(const std::vector<uint8_t>& data) {
    uint32_t a = 1, b = 0;
    for (uint8_t byte : data) {
        a = (a + byte) % 65521u;
        b = (b + a) % 65521u;
    }
    return (b << 16) | a;
}

// A valid 32 x 32 RGB8 PNG (a gradient), its pixel data in one stored (uncompressed) deflate block.
std::vector<uint8_t> goodPng() {
    const uint32_t side = 32;
    std::vector<uint8_t> raw;
    for (uint32_t y = 0; y < side; ++y) {
        raw.push_back(0); // filter: none
        for (uint32_t x = 0; x < side; ++x) raw.insert(raw.end(), {uint8_t(8 * x), uint8_t(8 * y), 128});
    }
    std::vector<uint8_t> zlib{0x78, 0x01, 0x01, uint8_t(raw.size()), uint8_t(raw.size() >> 8),
                              uint8_t(~raw.size()), uint8_t(~raw.size() >> 8)};
    zlib.insert(zlib.end(), raw.begin(), raw.end());
    putU32(zlib, adler32(raw));
    std::vector<uint8_t> png{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    std::vector<uint8_t> ihdr;
    putU32(ihdr, side);
    putU32(ihdr, side);
    ihdr.insert(ihdr.end(), {8, 2, 0, 0, 0}); // 8 bits, RGB, deflate, adaptive filter, no interlace
    putChunk(png, "IHDR", ihdr);
    putChunk(png, "IDAT", zlib);
    putChunk(png, "IEND", {});
    return png;
}

constexpr size_t kPngIdatData = 8 + 25 + 8; // signature, IHDR chunk, IDAT length and type

void putMarker(std::vector<uint8_t>& out, uint8_t marker, const std::vector<uint8_t>& body) {
    out.insert(out.end(), {0xFF, marker, uint8_t((body.size() + 2) >> 8), uint8_t(body.size() + 2)});
    out.insert(out.end(), body.begin(), body.end());
}

// A valid 32 x 32 greyscale baseline JPEG: flat quantisation, Huffman tables with the single code
// "0" (DC difference 0, AC end of block), so each of the 16 blocks is two 0 bits: a flat grey image.
std::vector<uint8_t> goodJpeg() {
    std::vector<uint8_t> jpeg{0xFF, 0xD8};
    std::vector<uint8_t> dqt{0x00};
    dqt.insert(dqt.end(), 64, 1);
    putMarker(jpeg, 0xDB, dqt);
    putMarker(jpeg, 0xC0, {8, 0, 32, 0, 32, 1, 1, 0x11, 0}); // 8 bits, 32 x 32, one component
    std::vector<uint8_t> one_code(17, 0);
    one_code[1] = 1;      // one code of length 1
    one_code.push_back(0); // its symbol: 0 (DC category 0; for AC, end of block)
    std::vector<uint8_t> dc = one_code, ac = one_code;
    dc[0] = 0x00;
    ac[0] = 0x10;
    putMarker(jpeg, 0xC4, dc);
    putMarker(jpeg, 0xC4, ac);
    putMarker(jpeg, 0xDA, {1, 1, 0x00, 0, 63, 0});
    jpeg.insert(jpeg.end(), {0x00, 0x00, 0x00, 0x00}); // 16 blocks x 2 bits
    jpeg.insert(jpeg.end(), {0xFF, 0xD9});
    return jpeg;
}

size_t findMarker(const std::vector<uint8_t>& jpeg, uint8_t marker) {
    for (size_t i = 0; i + 1 < jpeg.size(); ++i)
        if (jpeg[i] == 0xFF && jpeg[i + 1] == marker) return i;
    return jpeg.size();
}

struct DamagedImage {
    const char* name; // also the texture's file name in the bake test
    std::vector<uint8_t> bytes;
};

std::vector<DamagedImage> damagedImages() {
    const std::vector<uint8_t> png = goodPng(), jpeg = goodJpeg();
    std::vector<DamagedImage> out;
    out.push_back({"png_cut_in_pixel_data.png", std::vector<uint8_t>(png.begin(), png.begin() + long(kPngIdatData + 300))});
    out.push_back({"png_cut_in_header.png", std::vector<uint8_t>(png.begin(), png.begin() + 20)});
    std::vector<uint8_t> header_crc = png;
    header_crc[8 + 8 + 13] ^= 0x40; // IHDR's CRC
    out.push_back({"png_header_crc.png", header_crc});
    std::vector<uint8_t> bit_depth = png;
    bit_depth[8 + 8 + 8] = 7; // IHDR bit depth 7 (CRC fixed: a well-formed chunk saying nonsense)
    std::vector<uint8_t> ihdr_typed(bit_depth.begin() + 12, bit_depth.begin() + 12 + 4 + 13);
    const uint32_t crc = crc32(ihdr_typed.data(), ihdr_typed.size());
    for (int k = 0; k < 4; ++k) bit_depth[12 + 17 + size_t(k)] = uint8_t(crc >> (24 - 8 * k));
    out.push_back({"png_bad_bit_depth.png", bit_depth});
    std::vector<uint8_t> pixel = png;
    pixel[kPngIdatData + 7 + 100] ^= 0x55; // a pixel byte; the IDAT CRC no longer matches
    out.push_back({"png_pixel_data_crc.png", pixel});
    std::vector<uint8_t> zstream = png;
    zstream[kPngIdatData + 2] = 0x07; // deflate block type 3 (reserved)
    out.push_back({"png_bad_deflate_block.png", zstream});
    const size_t sos = findMarker(jpeg, 0xDA), eoi = findMarker(jpeg, 0xD9);
    out.push_back({"jpeg_cut_in_scan.jpg", std::vector<uint8_t>(jpeg.begin(), jpeg.begin() + long(sos + 10 + 1))});
    out.push_back({"jpeg_cut_after_header.jpg", std::vector<uint8_t>(jpeg.begin(), jpeg.begin() + long(sos))});
    out.push_back({"jpeg_cut_in_header.jpg", std::vector<uint8_t>(jpeg.begin(), jpeg.begin() + 30)});
    std::vector<uint8_t> height = jpeg;
    const size_t sof = findMarker(jpeg, 0xC0);
    height[sof + 5] = 0; // frame height 0
    height[sof + 6] = 0;
    out.push_back({"jpeg_zero_height.jpg", height});
    std::vector<uint8_t> components = jpeg;
    components[sof + 9] = 7; // 7 components in a frame header sized for one
    out.push_back({"jpeg_bad_component_count.jpg", components});
    std::vector<uint8_t> scan = jpeg;
    for (size_t k = sos + 10; k < eoi; ++k) scan[k] = 0xF0; // codes the tables do not have
    out.push_back({"jpeg_bad_huffman_codes.jpg", scan});
    return out;
}

TEST(TextureLimitsTest, GoodHandMadeImagesResize) {
    TextureResizeOptions options;
    for (const auto& [name, bytes] : {std::make_pair("good.png", goodPng()), std::make_pair("good.jpg", goodJpeg())}) {
        const auto size = probeImageSize(bytes, name);
        ASSERT_TRUE(size.ok()) << size.status().message();
        EXPECT_EQ(size->width, 32u);
        const auto r = resizeEncodedImageLevels(bytes, name, {{16, 16}, {4, 4}}, options);
        ASSERT_TRUE(r.ok()) << r.status().message();
        ASSERT_EQ(r->size(), 2u);
        const auto small = probeImageSize((*r)[1], "level");
        ASSERT_TRUE(small.ok()) << small.status().message();
        EXPECT_EQ(small->width, 4u);
    }
    // A PNG cut after its last pixel row (only IEND missing) loses nothing: it decodes to the same
    // levels as the whole file.
    const std::vector<uint8_t> png = goodPng();
    const auto whole = resizeEncodedImageLevels(png, "whole.png", {{8, 8}}, options);
    const auto no_end = resizeEncodedImageLevels({png.begin(), png.end() - 12}, "no_iend.png", {{8, 8}}, options);
    ASSERT_TRUE(whole.ok() && no_end.ok()) << no_end.status().message();
    EXPECT_EQ(*whole, *no_end);
}

// libpng reports a damaged PNG by a longjmp out of OpenImageIO's error callback, past the destructor
// of the message string OpenImageIO built there: a leak inside the library, one string per damaged
// file, not in lodbake. LeakSanitizer ignores what the decode allocates on this thread; every other
// check of the sanitizer stays on.
struct LibraryLeaksIgnored {
#if LODBAKE_TEST_WITH_LSAN
    LibraryLeaksIgnored() { __lsan_disable(); }
    ~LibraryLeaksIgnored() { __lsan_enable(); }
#endif
};

TEST(TextureLimitsTest, DamagedImagesFailWithOneLineNamingTheFile) {
    TextureResizeOptions options;
    for (const DamagedImage& d : damagedImages()) {
        SCOPED_TRACE(d.name);
        const auto r = [&] {
            [[maybe_unused]] LibraryLeaksIgnored library_leaks;
            return resizeEncodedImageLevels(d.bytes, d.name, {{16, 16}}, options);
        }();
        ASSERT_FALSE(r.ok()) << "a damaged image was decoded";
        const std::string& m = r.status().message();
        EXPECT_EQ(m.rfind(std::string(d.name) + ": ", 0), 0u) << m;
        EXPECT_EQ(m.find('\n'), std::string::npos) << m;
        EXPECT_EQ(r.status().code(), StatusCode::InvalidInput) << m;
    }
}

// The same images as an OBJ's texture: the bake fails with one error line naming the texture, and
// leaves no pack behind.
TEST(TextureLimitsTest, BakeOfAnAssetWithADamagedTextureFailsWithoutOutput) {
    namespace fs = std::filesystem;
    const std::string dir = lodbake_test::scratchDir() + "/damaged_textures";
    fs::remove_all(dir);
    fs::create_directories(dir);
    // A gently curved 9 x 9 grid with UVs, so the levels have fewer triangles than LOD0.
    std::string obj = "mtllib quad.mtl\n";
    const int n = 9;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const double u = x / double(n - 1), v = y / double(n - 1);
            obj += "v " + std::to_string(u) + " " + std::to_string(v) + " " + std::to_string(0.1 * u * v) + "\n";
            obj += "vt " + std::to_string(u) + " " + std::to_string(v) + "\n";
        }
    obj += "usemtl paint\n";
    for (int y = 0; y + 1 < n; ++y)
        for (int x = 0; x + 1 < n; ++x) {
            const int a = y * n + x + 1, b = a + 1, c = a + n, d = c + 1;
            for (const auto& f : {std::array<int, 3>{a, b, d}, std::array<int, 3>{a, d, c}})
                obj += "f " + std::to_string(f[0]) + "/" + std::to_string(f[0]) + " " + std::to_string(f[1]) + "/" +
                       std::to_string(f[1]) + " " + std::to_string(f[2]) + "/" + std::to_string(f[2]) + "\n";
        }
    ASSERT_TRUE(writeFileAtomic(dir + "/quad.obj", obj.data(), obj.size()).ok());
    // Level textures of at most 8 px: every level after LOD0 decodes and resizes the 32 px texture.
    const std::string preset = R"({"version": 1, "textures": {"max_size_px": 8, "min_size_px": 4}})";
    ASSERT_TRUE(writeFileAtomic(dir + "/small_textures.json", preset.data(), preset.size()).ok());
    auto bake = [&](const std::string& texture) {
        const std::string mtl = "newmtl paint\nKd 1 1 1\nmap_Kd " + texture + "\n";
        EXPECT_TRUE(writeFileAtomic(dir + "/quad.mtl", mtl.data(), mtl.size()).ok());
        fs::remove(dir + "/quad.glb");
        // The damaged PNGs leak in the library as above, so the CLI runs without the leak check.
        return lodbake_test::runCommand(lodbake_test::withoutLeakCheck() +
                                        lodbake_test::shellQuote(lodbake_test::lodbakeCli()) + " bake " +
                                        lodbake_test::shellQuote(dir + "/quad.obj") + " -o " +
                                        lodbake_test::shellQuote(dir + "/quad.glb") + " --levels 0.5,0.25 --preset " +
                                        lodbake_test::shellQuote(dir + "/small_textures.json") + " --quiet");
    };
    const std::vector<uint8_t> png = goodPng();
    ASSERT_TRUE(writeFileAtomic(dir + "/good.png", png.data(), png.size()).ok());
    const auto good = bake("good.png");
    ASSERT_EQ(good.exit_code, 0) << good.output;
    EXPECT_TRUE(fs::exists(dir + "/quad.glb"));
    for (const DamagedImage& d : damagedImages()) {
        SCOPED_TRACE(d.name);
        ASSERT_TRUE(writeFileAtomic(dir + "/" + d.name, d.bytes.data(), d.bytes.size()).ok());
        const auto r = bake(d.name);
        EXPECT_EQ(r.exit_code, 1) << r.output;
        size_t errors = 0;
        std::string line;
        for (size_t start = 0; start < r.output.size();) {
            const size_t end = r.output.find('\n', start);
            const std::string l = r.output.substr(start, end - start);
            if (l.rfind("error: ", 0) == 0) {
                ++errors;
                line = l;
            }
            start = end == std::string::npos ? r.output.size() : end + 1;
        }
        EXPECT_EQ(errors, 1u) << r.output;
        EXPECT_NE(line.find(std::string("'") + d.name + "'"), std::string::npos) << line;
        EXPECT_FALSE(fs::exists(dir + "/quad.glb")) << "a failed bake left a pack";
    }
}

} // namespace
