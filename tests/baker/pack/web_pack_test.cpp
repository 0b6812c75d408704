// The --web pack form and EXT_meshopt_compression input (docs/format/web.md):
// - lodrt's decoders (lodrt/meshopt.h) against meshoptimizer's encoders and filter decoders (Debian
//   libmeshoptimizer, an anchor only), and on truncated and corrupted streams;
// - `lodbake bake --web` on a shared scan: validator clean, and every level lodrt decodes is the plain
//   pack's level (the same triangles on the position grid the writer quantizes to);
// - gltfpack -cc output of shared scans (npm gltfpack from scripts/node-bench) opens in lodrt and in
//   `lodbake info`.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <meshoptimizer.h>

#include "../gltf/gltf_test_util.h"
#include "lodbake/core/file_io.h"
#include "lodrt/meshopt.h"
#include "lodrt/model.h"
#include "lodrt/pack.h"
#include "pack/web_meshopt.h"
#include "test_paths.h"

namespace {

namespace fs = std::filesystem;
using lodbake_test::CommandResult;
using lodbake_test::runCommand;
using lodbake_test::shellQuote;

struct Rng {
    uint32_t s = 2463534242u;
    uint32_t next() {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        return s;
    }
    float unit() { return float(next() >> 8) / float(1 << 24); }
};

// A 2D grid of quads as triangles, in vertex-cache and fetch order.
std::vector<uint32_t> gridIndices(uint32_t n) {
    std::vector<uint32_t> idx;
    for (uint32_t y = 0; y + 1 < n; ++y)
        for (uint32_t x = 0; x + 1 < n; ++x) {
            const uint32_t a = y * n + x, b = a + 1, c = a + n, d = c + 1;
            idx.insert(idx.end(), {a, b, c, b, d, c});
        }
    std::vector<uint32_t> cache(idx.size());
    meshopt_optimizeVertexCache(cache.data(), idx.data(), idx.size(), size_t(n) * n);
    std::vector<uint32_t> remap(size_t(n) * n);
    meshopt_optimizeVertexFetchRemap(remap.data(), cache.data(), cache.size(), remap.size());
    for (uint32_t& i : cache) i = remap[i];
    return cache;
}

std::vector<uint8_t> encodeTriangles(const std::vector<uint32_t>& idx, size_t vertices) {
    meshopt_encodeIndexVersion(1);
    std::vector<uint8_t> out(meshopt_encodeIndexBufferBound(idx.size(), vertices));
    out.resize(meshopt_encodeIndexBuffer(out.data(), out.size(), idx.data(), idx.size()));
    return out;
}

std::vector<uint8_t> encodeVertices(const std::vector<uint8_t>& data, size_t count, size_t stride) {
    std::vector<uint8_t> out(meshopt_encodeVertexBufferBound(count, stride));
    out.resize(meshopt_encodeVertexBuffer(out.data(), out.size(), data.data(), count, stride));
    return out;
}

// Smooth per-byte data (small deltas, some large jumps) so every group mode of the codec is used.
std::vector<uint8_t> vertexData(size_t count, size_t stride, Rng& rng) {
    std::vector<uint8_t> v(count * stride);
    for (size_t k = 0; k < stride; ++k) {
        uint8_t x = uint8_t(rng.next());
        const uint32_t spread = 1u << (k % 8);
        for (size_t i = 0; i < count; ++i) {
            x = uint8_t(x + (rng.next() % spread) - spread / 2);
            if (rng.next() % 97 == 0) x = uint8_t(rng.next());
            v[i * stride + k] = x;
        }
    }
    return v;
}

TEST(MeshoptDecodeTest, VertexStreamsDecodeAsMeshoptEncodedThem) {
    Rng rng;
    for (size_t stride : {4u, 8u, 12u, 16u, 20u, 64u, 256u})
        for (size_t count : {1u, 15u, 16u, 17u, 300u, 2000u}) {
            const std::vector<uint8_t> data = vertexData(count, stride, rng);
            const std::vector<uint8_t> encoded = encodeVertices(data, count, stride);
            std::vector<uint8_t> decoded(count * stride, 0xCD);
            ASSERT_EQ(lodrt::meshoptDecodeVertexBuffer(decoded.data(), count, stride, encoded.data(), encoded.size()),
                      lodrt::Result::Ok)
                << "stride " << stride << " count " << count;
            EXPECT_EQ(decoded, data) << "stride " << stride << " count " << count;
        }
}

// Each triangle rotated to start at its smallest index (winding kept), in order.
std::vector<uint32_t> rotated(const std::vector<uint32_t>& idx) {
    std::vector<uint32_t> out(idx.size());
    for (size_t t = 0; t + 3 <= idx.size(); t += 3) {
        const size_t first =
            size_t(std::min_element(idx.begin() + std::ptrdiff_t(t), idx.begin() + std::ptrdiff_t(t + 3)) -
                   (idx.begin() + std::ptrdiff_t(t)));
        for (size_t k = 0; k < 3; ++k) out[t + k] = idx[t + (first + k) % 3];
    }
    return out;
}

TEST(MeshoptDecodeTest, TriangleAndSequenceStreamsDecodeAsMeshoptEncodedThem) {
    Rng rng;
    std::vector<uint32_t> grid = gridIndices(60);
    // A shuffled copy: explicit indices, FIFO misses and the "next" restarts.
    std::vector<uint32_t> shuffled = grid;
    for (size_t t = shuffled.size() / 3; t > 1; --t) {
        const size_t u = rng.next() % t;
        for (size_t k = 0; k < 3; ++k) std::swap(shuffled[(t - 1) * 3 + k], shuffled[u * 3 + k]);
    }
    for (const std::vector<uint32_t>* idx : {&grid, &shuffled}) {
        const std::vector<uint8_t> encoded = encodeTriangles(*idx, 3600);
        // The encoder may rotate a triangle's corners (winding kept): the reference is meshoptimizer's
        // own decoder, and the triangles as rotation-free triples.
        std::vector<uint32_t> reference(idx->size());
        ASSERT_EQ(meshopt_decodeIndexBuffer(reference.data(), idx->size(), 4, encoded.data(), encoded.size()), 0);
        EXPECT_EQ(rotated(reference), rotated(*idx));
        for (size_t size : {2u, 4u}) {
            std::vector<uint8_t> decoded(idx->size() * size);
            ASSERT_EQ(
                lodrt::meshoptDecodeIndexBuffer(decoded.data(), idx->size(), size, encoded.data(), encoded.size()),
                lodrt::Result::Ok);
            for (size_t i = 0; i < idx->size(); ++i) {
                uint32_t v = 0;
                std::memcpy(&v, &decoded[i * size], size);
                ASSERT_EQ(v, reference[i]) << "index " << i;
            }
        }
        std::vector<uint8_t> sequence(meshopt_encodeIndexSequenceBound(idx->size(), 3600));
        sequence.resize(meshopt_encodeIndexSequence(sequence.data(), sequence.size(), idx->data(), idx->size()));
        std::vector<uint32_t> decoded(idx->size());
        ASSERT_EQ(lodrt::meshoptDecodeIndexSequence(reinterpret_cast<uint8_t*>(decoded.data()), idx->size(), 4,
                                                    sequence.data(), sequence.size()),
                  lodrt::Result::Ok);
        EXPECT_EQ(decoded, *idx);
    }
}

TEST(MeshoptDecodeTest, FiltersMatchMeshoptsDecoders) {
    Rng rng;
    const size_t n = 1000;
    std::vector<float> vectors(n * 4), quats(n * 4), floats(n * 3);
    for (size_t i = 0; i < n; ++i) {
        float v[4] = {rng.unit() * 2 - 1, rng.unit() * 2 - 1, rng.unit() * 2 - 1, rng.unit() * 2 - 1};
        const float l3 = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) + 1e-6f;
        const float l4 = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + v[3] * v[3]) + 1e-6f;
        for (int c = 0; c < 3; ++c) vectors[i * 4 + size_t(c)] = v[c] / l3;
        vectors[i * 4 + 3] = v[3] < 0 ? -1.0f : 1.0f;
        for (int c = 0; c < 4; ++c) quats[i * 4 + size_t(c)] = v[c] / l4;
        for (int c = 0; c < 3; ++c)
            floats[i * 3 + size_t(c)] = (rng.unit() - 0.5f) * std::ldexp(1.0f, int(i % 40) - 20);
    }
    auto compare = [](const std::vector<uint8_t>& a, const std::vector<uint8_t>& b, size_t component, int tolerance) {
        for (size_t i = 0; i < a.size(); i += component) {
            int x = 0, y = 0;
            if (component == 1) {
                x = int8_t(a[i]), y = int8_t(b[i]);
            } else {
                int16_t s = 0, t = 0;
                std::memcpy(&s, &a[i], 2);
                std::memcpy(&t, &b[i], 2);
                x = s, y = t;
            }
            ASSERT_LE(std::abs(x - y), tolerance) << "byte " << i;
        }
    };
    for (int bits : {8, 12, 16}) {
        const size_t stride = bits > 8 ? 8 : 4;
        std::vector<uint8_t> ours(n * stride);
        meshopt_encodeFilterOct(ours.data(), n, stride, bits, vectors.data());
        std::vector<uint8_t> theirs = ours;
        meshopt_decodeFilterOct(theirs.data(), n, stride);
        ASSERT_EQ(lodrt::meshoptApplyFilter(lodrt::MeshoptFilter::Octahedral, ours.data(), n, stride),
                  lodrt::Result::Ok);
        compare(ours, theirs, stride / 4, 1);
    }
    std::vector<uint8_t> q(n * 8);
    meshopt_encodeFilterQuat(q.data(), n, 8, 12, quats.data());
    std::vector<uint8_t> q_theirs = q;
    meshopt_decodeFilterQuat(q_theirs.data(), n, 8);
    ASSERT_EQ(lodrt::meshoptApplyFilter(lodrt::MeshoptFilter::Quaternion, q.data(), n, 8), lodrt::Result::Ok);
    compare(q, q_theirs, 2, 1);
    std::vector<uint8_t> e(n * 12);
    meshopt_encodeFilterExp(e.data(), n, 12, 15, floats.data());
    std::vector<uint8_t> e_theirs = e;
    meshopt_decodeFilterExp(e_theirs.data(), n, 12);
    ASSERT_EQ(lodrt::meshoptApplyFilter(lodrt::MeshoptFilter::Exponential, e.data(), n, 12), lodrt::Result::Ok);
    EXPECT_EQ(e, e_theirs);
}

// Decodes `src` as `info` into an exactly sized buffer followed by a guard area that must stay intact.
lodrt::Result decodeGuarded(const lodrt::MeshoptViewInfo& info, const std::vector<uint8_t>& src) {
    const size_t bytes = size_t(info.count * info.stride);
    std::vector<uint8_t> out(bytes + 64, 0xA5);
    const lodrt::Result r = lodrt::meshoptDecodeView(info, src.data(), src.size(), out.data(), bytes);
    for (size_t i = bytes; i < out.size(); ++i) EXPECT_EQ(out[i], 0xA5) << "write past the output at " << i;
    return r;
}

TEST(MeshoptDecodeTest, TruncatedAndCorruptedStreamsFailWithoutStrayAccess) {
    Rng rng;
    const std::vector<uint32_t> idx = gridIndices(12);
    lodrt::MeshoptViewInfo tri;
    tri.mode = lodrt::MeshoptMode::Triangles;
    tri.stride = 4;
    tri.count = idx.size();
    const std::vector<uint8_t> tri_stream = encodeTriangles(idx, 144);
    lodrt::MeshoptViewInfo attr;
    attr.mode = lodrt::MeshoptMode::Attributes;
    attr.filter = lodrt::MeshoptFilter::Exponential;
    attr.stride = 12;
    attr.count = 300;
    const std::vector<uint8_t> attr_stream = encodeVertices(vertexData(300, 12, rng), 300, 12);
    for (const auto* c : {&tri, &attr}) {
        const std::vector<uint8_t>& full = c == &tri ? tri_stream : attr_stream;
        ASSERT_EQ(decodeGuarded(*c, full), lodrt::Result::Ok);
        for (size_t n = 0; n < full.size(); ++n) {
            const std::vector<uint8_t> cut(full.begin(), full.begin() + std::ptrdiff_t(n));
            EXPECT_NE(decodeGuarded(*c, cut), lodrt::Result::Ok) << "prefix of " << n << " bytes decoded";
        }
        for (size_t i = 0; i < full.size(); ++i)
            for (uint8_t flip : {uint8_t(0x01), uint8_t(0x80), uint8_t(0xFF)}) {
                std::vector<uint8_t> bad = full;
                bad[i] ^= flip;
                (void)decodeGuarded(*c, bad); // any result; no access outside the buffers (ASan, guard)
            }
    }
}

// ---- packs ----

std::string outDir() {
    const std::string dir = lodbake_test::scratchDir() + "/web_pack";
    fs::create_directories(dir);
    return dir;
}

struct Loaded {
    std::vector<uint8_t> bytes;
    lodrt::Pack pack;
    lodrt::ModelSet models;
};

void loadWithLodrt(const std::string& path, Loaded& out) {
    lodbake::Result<std::vector<uint8_t>> bytes = lodbake::readFileBytes(path);
    ASSERT_TRUE(bytes.ok()) << bytes.status().message();
    out.bytes = std::move(*bytes);
    char error[256] = {};
    ASSERT_EQ(lodrt::loadPack(out.bytes.data(), out.bytes.size(), nullptr, &out.pack, error, sizeof(error)),
              lodrt::Result::Ok)
        << path << ": " << error;
    ASSERT_EQ(lodrt::buildModels(out.pack, nullptr, &out.models, error, sizeof(error)), lodrt::Result::Ok)
        << path << ": " << error;
}

// A mesh's triangles as position triples (every primitive, through readAccessor*); every other
// attribute must decode too.
struct MeshData {
    std::vector<float> positions; // 9 per triangle
};

void decodeMesh(const Loaded& l, uint32_t mesh_index, MeshData& out) {
    const lodrt::Pack& pack = l.pack;
    lodrt::BinBytes bin;
    bin.data = pack.container().bin;
    bin.size = pack.container().bin_size;
    const lodrt::MeshInfo& mesh = pack.mesh(mesh_index);
    for (uint32_t p = mesh.first_primitive; p < mesh.first_primitive + mesh.primitive_count; ++p) {
        const lodrt::PrimitiveInfo& prim = pack.primitive(p);
        ASSERT_EQ(prim.mode, 4u);
        std::vector<float> positions;
        for (uint32_t a = 0; a < prim.attribute_count; ++a) {
            const lodrt::AttributeInfo& attribute = pack.attribute(prim.first_attribute + a);
            const lodrt::AccessorInfo& acc = pack.accessor(attribute.accessor);
            std::vector<float> values(size_t(acc.count) * lodrt::componentCount(acc.type));
            std::vector<uint8_t> scratch(size_t(lodrt::accessorScratchBytes(pack, attribute.accessor)));
            ASSERT_EQ(lodrt::readAccessorFloats(pack, attribute.accessor, bin, values.data(), values.size(),
                                                scratch.data(), scratch.size()),
                      lodrt::Result::Ok)
                << attribute.name;
            for (float f : values) ASSERT_TRUE(std::isfinite(f)) << attribute.name;
            if (attribute.name == "POSITION") positions = values;
        }
        ASSERT_FALSE(positions.empty());
        ASSERT_NE(prim.indices, lodrt::kNoIndex);
        std::vector<uint32_t> indices(size_t(pack.accessor(prim.indices).count));
        std::vector<uint8_t> scratch(size_t(lodrt::accessorScratchBytes(pack, prim.indices)));
        ASSERT_EQ(lodrt::readAccessorIndices(pack, prim.indices, bin, prim.vertex_count, indices.data(), indices.size(),
                                             scratch.data(), scratch.size()),
                  lodrt::Result::Ok);
        for (uint32_t i : indices)
            for (int c = 0; c < 3; ++c) out.positions.push_back(positions[size_t(i) * 3 + size_t(c)]);
    }
}

// Triangles as integer grid triples (each point p / 2^e rounded), each rotated to start at its
// smallest corner (winding kept), sorted.
std::vector<std::array<int64_t, 9>> gridTriangles(const std::vector<float>& p, int e) {
    std::vector<std::array<int64_t, 9>> out;
    for (size_t t = 0; t + 9 <= p.size(); t += 9) {
        std::array<std::array<int64_t, 3>, 3> c;
        for (size_t k = 0; k < 3; ++k)
            for (size_t j = 0; j < 3; ++j) c[k][j] = int64_t(std::nearbyint(std::ldexp(double(p[t + k * 3 + j]), -e)));
        const size_t first = size_t(std::min_element(c.begin(), c.end()) - c.begin());
        std::array<int64_t, 9> tri;
        for (size_t k = 0; k < 3; ++k)
            for (size_t j = 0; j < 3; ++j) tri[k * 3 + j] = c[(first + k) % 3][j];
        out.push_back(tri);
    }
    std::sort(out.begin(), out.end());
    return out;
}

// The coarsest power-of-two grid every coordinate lies on: the smallest exponent k over the nonzero
// values v = M * 2^k with M odd.
int gridExponent(const std::vector<float>& values) {
    int e = 1000;
    for (float v : values) {
        if (v == 0.0f) continue;
        int exponent = 0;
        const double m = std::frexp(double(v), &exponent); // v = m * 2^exponent, 0.5 <= |m| < 1
        auto mantissa = int64_t(std::ldexp(m, 53));
        int k = exponent - 53;
        while ((mantissa & 1) == 0) mantissa /= 2, ++k;
        e = std::min(e, k);
    }
    return e;
}

CommandResult validate(const std::string& file) {
    return runCommand(shellQuote(LODBAKE_TEST_NODE) + " " +
                      shellQuote(lodbake_test::sourceDir() + "/scripts/node/validate-gltf.js") + " " +
                      shellQuote(file));
}

TEST(WebPackTest, BakeWebIsValidatorCleanAndLodrtDecodesThePlainLevels) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    const std::string in = shellQuote(lodbake_test::sharedMesh("bunny_zipper.ply"));
    const std::string preset = " --preset " + shellQuote(lodbake_test::sourceDir() + "/configs/desktop.json");
    const std::string web = outDir() + "/bunny_web.glb", plain = outDir() + "/bunny_plain.glb";
    const std::string cli = shellQuote(lodbake_test::lodbakeCli());
    for (const auto& [out, flag] : {std::make_pair(web, " --web"), std::make_pair(plain, "")}) {
        const CommandResult r = runCommand(cli + " bake " + in + preset + flag + " --quiet -o " + shellQuote(out));
        ASSERT_EQ(r.exit_code, 0) << r.output;
    }
    const CommandResult v = validate(web);
    EXPECT_EQ(v.exit_code, 0) << v.output;
    const CommandResult info = runCommand(cli + " info " + shellQuote(web));
    EXPECT_EQ(info.exit_code, 0) << info.output;

    Loaded w, p;
    loadWithLodrt(web, w);
    loadWithLodrt(plain, p);
    ASSERT_EQ(w.models.modelCount(), 1u);
    ASSERT_EQ(w.models.model(0).level_count, p.models.model(0).level_count);
    EXPECT_EQ(w.models.model(0).error_source, lodrt::ErrorSource::Measured); // LODBAKE_lod_metrics kept
    EXPECT_GT(w.models.model(0).level_count, 3u);                            // MSFT_lod kept
    for (uint32_t l = 0; l < w.models.model(0).level_count; ++l) {
        const lodrt::LevelInfo& wl = w.models.modelLevel(0, l);
        EXPECT_GT(wl.data_size, 0u) << "level " << l << " is not streamable";
        EXPECT_EQ(wl.hausdorff_error, p.models.modelLevel(0, l).hausdorff_error);
        MeshData wm, pm;
        decodeMesh(w, wl.mesh, wm);
        decodeMesh(p, p.models.modelLevel(0, l).mesh, pm);
        ASSERT_FALSE(HasFatalFailure());
        // The level's grid, read off its decoded positions: never finer than the default grid (adaptive
        // precision may make later levels' coarser), and the plain level rounded to it is the web level.
        const int e = gridExponent(wm.positions);
        const int finest = lodbake::webPositionExponent(pm.positions.data(), pm.positions.size() / 3);
        EXPECT_GE(e, finest) << "level " << l;
        if (l == 0) {
            EXPECT_EQ(e, finest);
        }
        EXPECT_EQ(gridTriangles(wm.positions, e), gridTriangles(pm.positions, e)) << "level " << l;
    }
}

// Every validator-clean gltfpack output of a few shared scans opens in lodrt (every accessor decodes)
// and in `lodbake info`.
TEST(WebPackTest, GltfpackCompressedFilesOpenInLodrtAndLodbakeInfo) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    const std::string gltfpack = lodbake_test::sourceDir() + "/scripts/node-bench/node_modules/.bin/gltfpack";
    if (!fs::exists(gltfpack)) GTEST_SKIP() << gltfpack << " missing: run `npm ci` in scripts/node-bench";
    const std::string cli = shellQuote(lodbake_test::lodbakeCli());
    std::vector<std::string> sources;
    for (const char* scan : {"bunny_zipper", "lucy100k"}) {
        const std::string glb = outDir() + "/" + scan + "_source.glb";
        const CommandResult c =
            runCommand(cli + " convert " + shellQuote(lodbake_test::sharedMesh(std::string(scan) + ".ply")) + " -o " +
                       shellQuote(glb));
        ASSERT_EQ(c.exit_code, 0) << c.output;
        sources.push_back(glb);
    }
    sources.push_back(lodbake_test::sharedMesh("nefertiti_fraunhofer_textured.glb"));
    for (const std::string& source : sources)
        for (const char* options : {"-cc", "-c", "-cc -vpf", "-cc -vpn -si 0.25"}) {
            const std::string out = outDir() + "/gltfpack_" + fs::path(source).stem().string() + "_" +
                                    std::to_string(std::hash<std::string>()(options)) + ".glb";
            const CommandResult g = runCommand(shellQuote(gltfpack) + " -i " + shellQuote(source) + " -o " +
                                               shellQuote(out) + " " + options);
            ASSERT_EQ(g.exit_code, 0) << g.output;
            const CommandResult v = validate(out);
            if (v.exit_code != 0) continue; // the bar covers validator-clean files only
            Loaded l;
            loadWithLodrt(out, l);
            ASSERT_FALSE(HasFatalFailure()) << source << " " << options;
            size_t triangles = 0;
            for (uint32_t m = 0; m < l.pack.meshCount(); ++m) {
                MeshData md;
                decodeMesh(l, m, md);
                ASSERT_FALSE(HasFatalFailure()) << source << " " << options;
                triangles += md.positions.size() / 9;
            }
            EXPECT_GT(triangles, 0u);
            const CommandResult info = runCommand(cli + " info " + shellQuote(out));
            EXPECT_EQ(info.exit_code, 0) << source << " " << options << ": " << info.output;
            EXPECT_NE(info.output.find(std::to_string(triangles) + " triangles"), std::string::npos)
                << source << " " << options << ": " << info.output;
        }
}

// glTF-Transform's `meshopt` (EXT_meshopt_compression with quantization) and `quantize`
// (KHR_mesh_quantization) outputs of a few shared scans are validator clean when their source is,
// open in lodrt with every accessor decoded and the source's bounds, keep the source's triangles,
// and open in `lodbake info`.
TEST(WebPackTest, GltfTransformFilesOpenInLodrtAndLodbakeInfo) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    const std::string transform = lodbake_test::sourceDir() + "/scripts/node-bench/node_modules/.bin/gltf-transform";
    if (!fs::exists(transform)) GTEST_SKIP() << transform << " missing: run `npm ci` in scripts/node-bench";
    const std::string cli = shellQuote(lodbake_test::lodbakeCli());
    std::vector<std::string> sources;
    for (const char* scan : {"bunny_zipper", "lucy100k"}) {
        const std::string glb = outDir() + "/" + scan + "_transform_source.glb";
        const CommandResult c =
            runCommand(cli + " convert " + shellQuote(lodbake_test::sharedMesh(std::string(scan) + ".ply")) + " -o " +
                       shellQuote(glb));
        ASSERT_EQ(c.exit_code, 0) << c.output;
        sources.push_back(glb);
    }
    sources.push_back(lodbake_test::sharedMesh("nefertiti_fraunhofer_textured.glb"));
    for (const std::string& source : sources) {
        Loaded original;
        loadWithLodrt(source, original);
        ASSERT_FALSE(HasFatalFailure()) << source;
        const bool source_clean = validate(source).exit_code == 0;
        size_t source_triangles = 0;
        for (uint32_t p = 0; p < original.pack.primitiveCount(); ++p)
            source_triangles += size_t(original.pack.primitive(p).triangle_count);
        for (const char* command : {"meshopt", "quantize"}) {
            const std::string out = outDir() + "/transform_" + fs::path(source).stem().string() + "_" + command + ".glb";
            const CommandResult g =
                runCommand(shellQuote(transform) + " " + command + " " + shellQuote(source) + " " + shellQuote(out));
            ASSERT_EQ(g.exit_code, 0) << g.output;
            // Validator errors of the source (the textured Nefertiti's normals are not unit length)
            // may survive the command; it must add none to a clean source. lodrt opens both kinds.
            if (source_clean) {
                const CommandResult v = validate(out);
                EXPECT_EQ(v.exit_code, 0) << source << " " << command << ": " << v.output;
            }
            Loaded l;
            loadWithLodrt(out, l);
            ASSERT_FALSE(HasFatalFailure()) << source << " " << command;
            size_t triangles = 0;
            for (uint32_t m = 0; m < l.pack.meshCount(); ++m) {
                MeshData md;
                decodeMesh(l, m, md);
                ASSERT_FALSE(HasFatalFailure()) << source << " " << command;
                triangles += md.positions.size() / 9;
            }
            EXPECT_EQ(triangles, source_triangles) << source << " " << command;
            // The model's bounds (from POSITION min / max, normalized integers mapped as the
            // elements are, through the node's dequantizing transform) are the source's.
            ASSERT_EQ(l.models.modelCount(), original.models.modelCount()) << source << " " << command;
            const lodrt::ModelInfo &a = original.models.model(0), &b = l.models.model(0);
            const float r = a.world_sphere_radius;
            EXPECT_NEAR(b.world_sphere_radius, r, 0.01f * r) << source << " " << command;
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(b.world_sphere_center[c], a.world_sphere_center[c], 0.01f * r) << source << " " << command;
            const CommandResult info = runCommand(cli + " info " + shellQuote(out));
            EXPECT_EQ(info.exit_code, 0) << source << " " << command << ": " << info.output;
            EXPECT_NE(info.output.find(std::to_string(triangles) + " triangles"), std::string::npos)
                << source << " " << command << ": " << info.output;
        }
    }
}

} // namespace
