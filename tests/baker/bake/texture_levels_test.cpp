// The bake's textures end to end, through `lodbake bake` and `loddump --render`: the preset's size cap
// holds from LOD0 on, level images keep their source's name, an unreadable image fails the bake (or
// ships byte for byte when asked), texture bytes do not depend on the thread count, normal-mapped
// assets get tangents, and the contact sheet shows the base colour texture and the normal map.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <regex>
#include <string>

#include "../gltf/gltf_test_util.h"
#include "../image/test_png.h"
#include "lodbake/core/file_io.h"
#include "lodbake/image/texture_resize.h"
#include "test_paths.h"

namespace {

namespace fs = std::filesystem;
using lodbake_test::CommandResult;
using lodbake_test::runCommand;
using lodbake_test::shellQuote;

std::string freshDir(const std::string& name) {
    const std::string dir = lodbake_test::scratchDir() + "/texture_levels/" + name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

void writeBytes(const std::string& path, const std::vector<uint8_t>& bytes) {
    ASSERT_TRUE(lodbake::writeFileAtomic(path, bytes.data(), bytes.size()).ok()) << path;
}

void writeText(const std::string& path, const std::string& text) {
    ASSERT_TRUE(lodbake::writeFileAtomic(path, text.data(), text.size()).ok()) << path;
}

std::vector<uint8_t> bytesOf(const std::string& path) {
    auto r = lodbake::readFileBytes(path);
    return r.ok() ? *r : std::vector<uint8_t>();
}

// dir/quad.obj: an n x n grid over [0, 1]^2 in the z = 0 plane (gently curved when `curved`), UVs with
// the image's top at y = 1, normals, and material "paint" from quad.mtl (`mtl`, written too).
void writeQuad(const std::string& dir, const std::string& mtl, bool curved = true) {
    std::string obj = "mtllib quad.mtl\n";
    const int n = 12;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const double u = x / double(n - 1), v = y / double(n - 1), k = curved ? 0.1 : 0.0;
            obj += "v " + std::to_string(u) + " " + std::to_string(v) + " " + std::to_string(k * u * v) + "\n";
            obj += "vt " + std::to_string(u) + " " + std::to_string(v) + "\n";
            const double nx = -k * v, ny = -k * u, len = std::sqrt(nx * nx + ny * ny + 1);
            obj += "vn " + std::to_string(nx / len) + " " + std::to_string(ny / len) + " " + std::to_string(1 / len) + "\n";
        }
    obj += "usemtl paint\n";
    for (int y = 0; y + 1 < n; ++y)
        for (int x = 0; x + 1 < n; ++x) {
            const int a = y * n + x + 1, b = a + 1, c = a + n, d = c + 1;
            for (const auto& f : {std::array<int, 3>{a, b, d}, std::array<int, 3>{a, d, c}}) {
                obj += "f";
                for (int i : f) obj += " " + std::to_string(i) + "/" + std::to_string(i) + "/" + std::to_string(i);
                obj += "\n";
            }
        }
    writeText(dir + "/quad.obj", obj);
    writeText(dir + "/quad.mtl", "newmtl paint\nKd 1 1 1\n" + mtl);
}

// 8-texel red and blue squares.
std::vector<uint8_t> checkerPng(uint32_t size) {
    return lodbake_test::makeRgbPng(size, size, [](uint32_t x, uint32_t y) -> std::array<uint32_t, 3> {
        return ((x / 8) + (y / 8)) % 2 ? std::array<uint32_t, 3>{230, 30, 30} : std::array<uint32_t, 3>{30, 30, 230};
    });
}

CommandResult bake(const std::string& dir, const std::string& args) {
    // Bakes with textures load the OpenImageIO module: LeakSanitizer's tracer can crash at exit
    // (gltf_test_util.h).
    return runCommand(lodbake_test::withoutLeakCheck() + shellQuote(lodbake_test::lodbakeCli()) + " bake " +
                      shellQuote(dir + "/quad.obj") + " -o " + shellQuote(dir + "/quad.glb") + " " + args);
}

// The encoded bytes of glTF image i.
std::vector<uint8_t> imageBytes(const std::vector<uint8_t>& glb, const nlohmann::json& doc, size_t i) {
    const std::vector<uint8_t> bin = lodbake_test::glbBin(glb);
    const nlohmann::json& view = doc["bufferViews"][size_t(doc["images"][i]["bufferView"])];
    const size_t offset = view.value("byteOffset", size_t(0)), length = view["byteLength"];
    return {bin.begin() + long(offset), bin.begin() + long(offset + length)};
}

// The image index behind every mesh's first primitive's base colour texture, in mesh order.
std::vector<size_t> baseColourImages(const nlohmann::json& doc) {
    std::vector<size_t> out;
    for (const nlohmann::json& mesh : doc["meshes"]) {
        const nlohmann::json& material = doc["materials"][size_t(mesh["primitives"][0]["material"])];
        const size_t texture = material["pbrMetallicRoughness"]["baseColorTexture"]["index"];
        out.push_back(doc["textures"][texture]["source"]);
    }
    return out;
}

TEST(TextureLevelsTest, CapHoldsFromLod0AndLevelImagesKeepTheSourceName) {
    const std::string dir = freshDir("cap");
    writeBytes(dir + "/checker.png", checkerPng(64));
    writeQuad(dir, "map_Kd checker.png\n");
    writeText(dir + "/preset.json",
              R"({"version": 1, "repair": false, "textures": {"max_size_px": 32, "min_size_px": 4, "texels_per_pixel": 0.02}})");
    const CommandResult r = bake(dir, "--levels 0.5,0.25,0.1 --quiet --preset " + shellQuote(dir + "/preset.json"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::vector<uint8_t> glb = bytesOf(dir + "/quad.glb");
    const nlohmann::json doc = lodbake_test::glbJson(glb);
    const std::vector<size_t> images = baseColourImages(doc);
    ASSERT_EQ(images.size(), 4u);
    // LOD0's 64 px source ships at the 32 px cap, under the source's name.
    const auto lod0 = lodbake::probeImageSize(imageBytes(glb, doc, images[0]), "lod0");
    ASSERT_TRUE(lod0.ok()) << lod0.status().message();
    EXPECT_EQ(lod0->width, 32u);
    EXPECT_EQ(doc["images"][images[0]]["name"], "checker");
    bool has_level_image = false;
    for (size_t i = 0; i < doc["images"].size(); ++i) {
        const auto size = lodbake::probeImageSize(imageBytes(glb, doc, i), "image");
        ASSERT_TRUE(size.ok());
        EXPECT_LE(std::max(size->width, size->height), 32u) << "image " << i;
        const std::string name = doc["images"][i]["name"];
        if (i == images[0]) continue;
        EXPECT_TRUE(std::regex_match(name, std::regex("checker_lod[1-3]"))) << name;
        has_level_image = true;
    }
    EXPECT_TRUE(has_level_image);
}

TEST(TextureLevelsTest, UnreadableImageFailsNamingItOrShipsByteForByteWhenAsked) {
    const std::string dir = freshDir("unreadable");
    // A WebP header over junk: nothing here decodes it, whatever its name says.
    const std::string junk_text = "RIFF\x20\0\0\0WEBPVP8 not really an image, only bytes";
    const std::vector<uint8_t> junk(junk_text.begin(), junk_text.end());
    std::vector<uint8_t> damaged = checkerPng(64);
    damaged.resize(damaged.size() / 2); // a PNG cut in the middle of its pixels
    writeBytes(dir + "/paint.webp", junk);
    writeBytes(dir + "/cut.png", damaged);
    writeText(dir + "/keep.json", R"({"version": 1, "textures": {"keep_unreadable_images": true}})");
    for (const auto& [file, bytes] : {std::make_pair("paint.webp", junk), std::make_pair("cut.png", damaged)}) {
        SCOPED_TRACE(file);
        writeQuad(dir, std::string("map_Kd ") + file + "\n");
        fs::remove(dir + "/quad.glb");
        const CommandResult failed = bake(dir, "--levels 0.5,0.25 --quiet");
        EXPECT_EQ(failed.exit_code, 1) << failed.output;
        EXPECT_NE(failed.output.find(std::string("texture 0 '") + file + "'"), std::string::npos) << failed.output;
        EXPECT_NE(failed.output.find("keep_unreadable_images"), std::string::npos) << failed.output;
        EXPECT_FALSE(fs::exists(dir + "/quad.glb"));
        for (const std::string& keep : {std::string("--keep-unreadable-images"), "--preset " + shellQuote(dir + "/keep.json")}) {
            SCOPED_TRACE(keep);
            const CommandResult kept = bake(dir, "--levels 0.5,0.25 " + keep);
            ASSERT_EQ(kept.exit_code, 0) << kept.output;
            EXPECT_NE(kept.output.find("kept byte for byte in every level"), std::string::npos) << kept.output;
            const std::vector<uint8_t> glb = bytesOf(dir + "/quad.glb");
            const nlohmann::json doc = lodbake_test::glbJson(glb);
            const std::vector<size_t> images = baseColourImages(doc); // every level still has its texture
            ASSERT_EQ(images.size(), 3u);
            for (size_t image : images) EXPECT_EQ(imageBytes(glb, doc, image), bytes);
        }
    }
}

TEST(TextureLevelsTest, TextureBytesDoNotDependOnTheThreadCount) {
    const std::string dir = freshDir("threads");
    uint32_t state = 12345;
    writeBytes(dir + "/noise.png", lodbake_test::makeRgbPng(300, 300, [&](uint32_t, uint32_t) -> std::array<uint32_t, 3> {
                   state = state * 1664525u + 1013904223u;
                   return {state >> 24, (state >> 16) & 255, (state >> 8) & 255};
               }));
    writeBytes(dir + "/normal.png", lodbake_test::makeRgbPng(300, 300, [](uint32_t x, uint32_t y) -> std::array<uint32_t, 3> {
                   return {128 + (x * 7 + y * 3) % 64, 128 + (x * 3 + y * 11) % 64, 230};
               }));
    writeQuad(dir, "map_Kd noise.png\nnorm normal.png\n");
    std::vector<uint8_t> first;
    for (const char* threads : {"1", "2", "3"}) {
        const CommandResult r = bake(dir, std::string("--levels 0.5,0.25,0.1 --quiet --threads ") + threads);
        ASSERT_EQ(r.exit_code, 0) << r.output;
        const std::vector<uint8_t> glb = bytesOf(dir + "/quad.glb");
        if (first.empty()) {
            first = glb;
            EXPECT_GT(lodbake_test::glbJson(glb)["images"].size(), 2u); // levels made smaller images
        } else {
            EXPECT_EQ(glb, first) << threads << " threads";
        }
    }
}

TEST(TextureLevelsTest, NormalMappedAssetsGetTangentsOnEveryLevel) {
    const std::string dir = freshDir("tangents");
    writeBytes(dir + "/normal.png", lodbake_test::makeRgbPng(32, 32, [](uint32_t, uint32_t) -> std::array<uint32_t, 3> {
                   return {128, 128, 255};
               }));
    writeQuad(dir, "norm normal.png\n");
    const CommandResult r = bake(dir, "--levels 0.5,0.25");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("tangents generated for the normal map"), std::string::npos) << r.output;
    const nlohmann::json doc = lodbake_test::glbJson(bytesOf(dir + "/quad.glb"));
    ASSERT_EQ(doc["meshes"].size(), 3u);
    for (const nlohmann::json& mesh : doc["meshes"])
        for (const nlohmann::json& primitive : mesh["primitives"]) EXPECT_TRUE(primitive["attributes"].contains("TANGENT"));
}

// --- loddump --render -----------------------------------------------------------------------------

CommandResult render(const std::string& pack, const std::string& png) {
    return runCommand(lodbake_test::withoutLeakCheck() + shellQuote(LODBAKE_TEST_LODDUMP) + " " + shellQuote(pack) +
                      " --level 0 --render " + shellQuote(png));
}

// The rendered cell's object pixels (not background, border or label), as RGB triples with their x.
struct Pixel {
    uint32_t x;
    int r, g, b;
};

std::vector<Pixel> objectPixels(const std::string& png) {
    const auto image = lodbake::decodeImage(bytesOf(png), png);
    EXPECT_TRUE(image.ok()) << image.status().message();
    std::vector<Pixel> out;
    if (!image.ok() || image->channels != 3) return out;
    for (uint32_t y = 24; y + 2 < image->height; ++y)
        for (uint32_t x = 0; x + 2 < image->width; ++x) {
            const uint8_t* p = &image->samples[(size_t(y) * image->width + x) * 3];
            if (p[0] == 236 && p[1] == 236 && p[2] == 240) continue; // background
            out.push_back({x, p[0], p[1], p[2]});
        }
    return out;
}

TEST(TexturedRenderTest, ContactSheetShowsTheBaseColourTexture) {
    const std::string dir = freshDir("render_checker");
    writeBytes(dir + "/checker.png", checkerPng(64));
    writeQuad(dir, "map_Kd checker.png\n");
    writeText(dir + "/preset.json", R"({"version": 1, "repair": false})");
    ASSERT_EQ(bake(dir, "--levels 0.5 --quiet --preset " + shellQuote(dir + "/preset.json")).exit_code, 0);
    const CommandResult r = render(dir + "/quad.glb", dir + "/sheet.png");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::vector<Pixel> pixels = objectPixels(dir + "/sheet.png");
    ASSERT_GT(pixels.size(), 5000u);
    // The checker's two colours, shaded: red-dominant and blue-dominant pixels, each a good share of
    // the surface. Flat shading draws one grey-blue, which is neither.
    size_t red = 0, blue = 0;
    for (const Pixel& p : pixels) {
        red += p.r > 2 * p.b && p.r > 2 * p.g && p.r > 80;
        blue += p.b > 2 * p.r && p.b > 2 * p.g && p.b > 80;
    }
    EXPECT_GT(red, pixels.size() / 4) << red << " red of " << pixels.size();
    EXPECT_GT(blue, pixels.size() / 4) << blue << " blue of " << pixels.size();
}

// A flat white quad whose normal map tilts the left half (u < 0.5) towards -x, away from the camera
// (which looks from the +x side): that half must come out darker. Without the normal map both halves
// would match; with a tangent frame pointing the wrong way the left half would come out brighter.
TEST(TexturedRenderTest, ContactSheetShowsTheNormalMap) {
    const std::string dir = freshDir("render_normal");
    writeBytes(dir + "/normal.png", lodbake_test::makeRgbPng(64, 64, [](uint32_t x, uint32_t) -> std::array<uint32_t, 3> {
                   return x < 32 ? std::array<uint32_t, 3>{37, 128, 218} : std::array<uint32_t, 3>{128, 128, 255};
               }));
    writeQuad(dir, "norm normal.png\n", false);
    writeText(dir + "/preset.json", R"({"version": 1, "repair": false})");
    ASSERT_EQ(bake(dir, "--levels 0.5 --quiet --preset " + shellQuote(dir + "/preset.json")).exit_code, 0);
    const CommandResult r = render(dir + "/quad.glb", dir + "/sheet.png");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::vector<Pixel> pixels = objectPixels(dir + "/sheet.png");
    ASSERT_GT(pixels.size(), 5000u);
    uint32_t lo = UINT32_MAX, hi = 0;
    for (const Pixel& p : pixels) lo = std::min(lo, p.x), hi = std::max(hi, p.x);
    double left = 0, right = 0;
    size_t left_count = 0, right_count = 0;
    for (const Pixel& p : pixels) {
        if (p.x < lo + (hi - lo) / 3) left += p.g, ++left_count;
        if (p.x > hi - (hi - lo) / 3) right += p.g, ++right_count;
    }
    ASSERT_GT(left_count, 0u);
    ASSERT_GT(right_count, 0u);
    left /= double(left_count);
    right /= double(right_count);
    EXPECT_LT(left, 0.8 * right) << "left third " << left << ", right third " << right;
}

// A compact pack has no plain attribute data: the contact sheet must take the UVs and tangents from
// the valence stream and show every level as the plain pack does, up to the quantization (positions
// at 14 bits and UVs at 12 move a few pixels' worth of colour at most on the textured Nefertiti).
TEST(TexturedRenderTest, CompactPackRendersLikeThePlainPack) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    const std::string dir = freshDir("render_compact");
    const std::string input = lodbake_test::sharedMesh("nefertiti_fraunhofer_textured.glb");
    const std::string cli = lodbake_test::withoutLeakCheck() + shellQuote(lodbake_test::lodbakeCli()) + " bake " +
                            shellQuote(input) + " --quiet --no-progressive-fans -o ";
    ASSERT_EQ(runCommand(cli + shellQuote(dir + "/plain.glb")).exit_code, 0);
    ASSERT_EQ(runCommand(cli + shellQuote(dir + "/compact.glb") + " --compact").exit_code, 0);
    for (const char* name : {"plain", "compact"}) {
        const CommandResult r = runCommand(lodbake_test::withoutLeakCheck() + shellQuote(LODBAKE_TEST_LODDUMP) + " " +
                                           shellQuote(dir + "/" + name + ".glb") + " --render " +
                                           shellQuote(dir + "/" + name + ".png"));
        ASSERT_EQ(r.exit_code, 0) << r.output;
    }
    const auto plain = lodbake::decodeImage(bytesOf(dir + "/plain.png"), "plain.png");
    const auto compact = lodbake::decodeImage(bytesOf(dir + "/compact.png"), "compact.png");
    ASSERT_TRUE(plain.ok() && compact.ok());
    ASSERT_EQ(plain->width, compact->width);
    ASSERT_EQ(plain->height, compact->height);
    ASSERT_EQ(plain->samples.size(), compact->samples.size());
    // Textured pixels are far from grey; an untextured (flat) compact render would share few of them.
    size_t object = 0, far = 0;
    double sum = 0;
    for (size_t i = 0; i + 2 < plain->samples.size(); i += 3) {
        const uint8_t* a = &plain->samples[i];
        const uint8_t* b = &compact->samples[i];
        if (a[0] == 236 && a[1] == 236 && a[2] == 240) continue; // background
        ++object;
        int worst = 0;
        for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(int(a[k]) - int(b[k])));
        sum += worst;
        far += worst > 48;
    }
    ASSERT_GT(object, 20000u);
    EXPECT_LT(sum / double(object), 6.0) << "mean largest channel difference over " << object << " pixels";
    EXPECT_LT(double(far), 0.03 * double(object)) << far << " of " << object << " pixels differ by more than 48";
}

} // namespace
