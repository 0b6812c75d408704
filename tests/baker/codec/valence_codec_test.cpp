// ValenceCodecTest: encoder (baker) + decoder (runtime) round trips on hand-built meshes and shared
// scans. ValenceDecoderSafetyTest: hostile streams give error codes, never out-of-bounds access.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

#include "lodbake/codec/valence_encoder.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/core/file_io.h"
#include "lodbake/io/mesh_io.h"
#include "lodrt/detail/valence_model.h"
#include "lodrt/format.h"
#include "lodrt/valence.h"
#include "mesh_builders.h"
#include "test_paths.h"

namespace {

using lodbake::Mesh;
using lodbake::Vec3f;
using lodbake::codec::decodeValence;
using lodbake::codec::encodeValence;
using lodbake::codec::ValenceEncodeOptions;
using lodbake::codec::ValenceEncodeResult;

// Smallest rotation of a triangle (keeps the orientation).
std::array<uint32_t, 3> canonical(uint32_t a, uint32_t b, uint32_t c) {
    if (a <= b && a <= c) return {a, b, c};
    if (b <= a && b <= c) return {b, c, a};
    return {c, a, b};
}

// Checks the decoded mesh against the input through the encoder's permutations: same triangles (up to
// rotation) and positions within half a quantization step.
void expectRoundTrip(const Mesh& in, const ValenceEncodeOptions& options, ValenceEncodeResult* out = nullptr) {
    auto enc = encodeValence(in, options);
    ASSERT_TRUE(enc.ok()) << enc.status().message();
    auto dec = decodeValence(enc->bytes, "test");
    ASSERT_TRUE(dec.ok()) << dec.status().message();
    const Mesh& m = *dec;
    ASSERT_EQ(m.vertexCount(), in.vertexCount());
    ASSERT_EQ(m.faceCount(), in.faceCount());
    ASSERT_EQ(enc->old_face_of.size(), in.faceCount());
    // The permutations are permutations.
    std::vector<uint32_t> seen(in.vertexCount(), 0);
    for (uint32_t v : enc->new_vertex_of) {
        ASSERT_LT(v, in.vertexCount());
        ++seen[v];
    }
    for (uint32_t s : seen) ASSERT_EQ(s, 1u);
    std::vector<uint32_t> faces = enc->old_face_of;
    std::sort(faces.begin(), faces.end());
    for (size_t f = 0; f < faces.size(); ++f) ASSERT_EQ(faces[f], f);
    for (size_t f = 0; f < m.faceCount(); ++f) {
        uint32_t o = enc->old_face_of[f];
        auto want = canonical(enc->new_vertex_of[in.indices[3 * o]], enc->new_vertex_of[in.indices[3 * o + 1]],
                              enc->new_vertex_of[in.indices[3 * o + 2]]);
        auto got = canonical(m.indices[3 * f], m.indices[3 * f + 1], m.indices[3 * f + 2]);
        ASSERT_EQ(got, want) << "face " << f;
    }
    lodbake::Aabb box;
    for (const Vec3f& p : in.positions) box.expand(p);
    float cube = in.positions.empty() ? 0.0f : std::max({box.extent().x, box.extent().y, box.extent().z});
    double tol = cube / double((1u << options.position_bits) - 1) * 0.5 + 1e-6 * (cube + 1.0);
    double max_err = 0.0;
    for (size_t v = 0; v < in.vertexCount(); ++v) {
        const Vec3f& a = in.positions[v];
        const Vec3f& b = m.positions[enc->new_vertex_of[v]];
        max_err = std::max(
            {max_err, double(std::fabs(a.x - b.x)), double(std::fabs(a.y - b.y)), double(std::fabs(a.z - b.z))});
    }
    EXPECT_LE(max_err, tol);
    EXPECT_NEAR(max_err, enc->max_position_error, 1e-6 * (cube + 1.0));
    if (in.hasNormals() && options.encode_normals) {
        ASSERT_TRUE(m.hasNormals());
        double tol_n = 4.0 / double((1u << options.normal_bits) - 1);
        for (size_t v = 0; v < in.vertexCount(); ++v) {
            Vec3f a = in.normals[v];
            float len = std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z);
            if (!(len > 0.0f)) continue;
            const Vec3f& b = m.normals[enc->new_vertex_of[v]];
            double d =
                std::sqrt(double(a.x / len - b.x) * (a.x / len - b.x) + double(a.y / len - b.y) * (a.y / len - b.y) +
                          double(a.z / len - b.z) * (a.z / len - b.z));
            ASSERT_LE(d, tol_n) << "normal " << v;
        }
    }
    // Re-encoding gives identical bytes.
    auto again = encodeValence(in, options);
    ASSERT_TRUE(again.ok());
    EXPECT_EQ(again->bytes, enc->bytes);
    if (out) *out = std::move(*enc);
}

Mesh grid(int n, bool holes) {
    Mesh m;
    for (int y = 0; y <= n; ++y)
        for (int x = 0; x <= n; ++x) m.positions.push_back(Vec3f{float(x), float(y), 0.1f * float((x * y) % 5)});
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            if (holes && (x % 4 == 1) && (y % 3 == 1)) continue;
            uint32_t a = uint32_t(y * (n + 1) + x), b = a + 1, c = a + uint32_t(n + 1), d = c + 1;
            m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
        }
    return m;
}

Mesh torus(int nu, int nv) {
    Mesh m;
    const float kPi = 3.14159265358979f;
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            float u = 2 * kPi * float(i) / float(nu), v = 2 * kPi * float(j) / float(nv);
            m.positions.push_back(Vec3f{(2 + std::cos(v)) * std::cos(u), (2 + std::cos(v)) * std::sin(u), std::sin(v)});
            m.normals.push_back(Vec3f{std::cos(v) * std::cos(u), std::cos(v) * std::sin(u), std::sin(v)});
        }
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            uint32_t a = uint32_t(i * nv + j), b = uint32_t(((i + 1) % nu) * nv + j),
                     c = uint32_t(i * nv + (j + 1) % nv), d = uint32_t(((i + 1) % nu) * nv + (j + 1) % nv);
            m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
        }
    return m;
}

TEST(ValenceCodecTest, SingleTriangle) {
    expectRoundTrip(lodbake_test::singleTriangle(), {});
}
TEST(ValenceCodecTest, Tetrahedron) {
    expectRoundTrip(lodbake_test::tetrahedron(), {});
}
TEST(ValenceCodecTest, EmptyMesh) {
    expectRoundTrip(Mesh(), {});
}
TEST(ValenceCodecTest, OpenGridWithHoles) {
    for (uint32_t bits : {8u, 11u, 14u, 16u}) {
        ValenceEncodeOptions o;
        o.position_bits = bits;
        expectRoundTrip(grid(20, true), o);
    }
}
TEST(ValenceCodecTest, MultipleComponentsAndUnreferencedVertices) {
    Mesh m = grid(5, false);
    lodbake::appendMesh(m, lodbake_test::tetrahedron());
    lodbake::appendMesh(m, torus(6, 5));
    m.positions.push_back(Vec3f{7, 7, 7}); // unreferenced
    m.normals.clear();
    expectRoundTrip(m, {});
}
TEST(ValenceCodecTest, NonManifoldFanAndBowTie) {
    expectRoundTrip(lodbake_test::bowTie(), {});
    expectRoundTrip(lodbake_test::finEdge(), {});
    // Five triangles on one edge (0,1), and one flipped triangle (inconsistent orientation).
    Mesh fan = lodbake_test::makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}, {1, 1, 1}},
                                      {0, 1, 2, 1, 0, 3, 0, 1, 4, 0, 1, 5, 1, 0, 6, 2, 1, 6});
    expectRoundTrip(fan, {});
    // Repeated indices in a triangle are kept too.
    expectRoundTrip(lodbake_test::makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {0, 1, 2, 0, 0, 1}), {});
}
TEST(ValenceCodecTest, MoebiusStripAndClosedManifoldsNeedNoCopies) {
    // A Moebius strip cannot be oriented: the cut must copy vertices, and the copies merge back.
    Mesh strip;
    const int n = 12;
    const float kPi = 3.14159265358979f;
    for (int i = 0; i < n; ++i) {
        const float u = 2 * kPi * float(i) / float(n);
        for (int s = -1; s <= 1; s += 2) {
            const float w = 0.3f * float(s) * std::cos(u / 2);
            strip.positions.push_back(
                Vec3f{(1 + w) * std::cos(u), (1 + w) * std::sin(u), 0.3f * float(s) * std::sin(u / 2)});
        }
    }
    for (int i = 0; i < n; ++i) {
        uint32_t a = uint32_t(2 * i), b = a + 1, c = uint32_t(2 * ((i + 1) % n)), d = c + 1;
        if (i == n - 1) std::swap(c, d); // the half twist
        strip.indices.insert(strip.indices.end(), {a, b, d, a, d, c});
    }
    expectRoundTrip(strip, {});
    ValenceEncodeResult r;
    expectRoundTrip(torus(20, 9), {}, &r);
    EXPECT_EQ(r.cut_vertex_copies, 0u);
    EXPECT_EQ(r.dummy_vertices, 0u);
    expectRoundTrip(grid(9, true), {}, &r);
    EXPECT_EQ(r.cut_vertex_copies, 0u);
    EXPECT_GT(r.dummy_vertices, 1u); // the outer border and the holes
}
TEST(ValenceCodecTest, RandomTriangleSoupsRoundTripExactly) {
    // Random soups over few vertices: repeated, flipped, degenerate and non-manifold triangles of
    // every kind, which drive the cut and its restarts.
    std::mt19937 rng(7);
    for (int trial = 0; trial < 300; ++trial) {
        Mesh m;
        const uint32_t vn = 3 + rng() % 10, fn = 1 + rng() % 30;
        for (uint32_t v = 0; v < vn; ++v)
            m.positions.push_back(Vec3f{float(rng() % 100), float(rng() % 100), float(rng() % 100)});
        for (uint32_t f = 0; f < 3 * fn; ++f) m.indices.push_back(uint32_t(rng() % vn));
        SCOPED_TRACE("trial " + std::to_string(trial));
        expectRoundTrip(m, {});
        if (::testing::Test::HasFatalFailure()) return;
    }
}
// A large regular mesh codes its connectivity in a few hundredths of a bit per vertex: the header's
// plausibility bounds (format.h, kValenceVerticesPerByte ...) must still accept it.
TEST(ValenceCodecTest, RegularTorusFitsThePlausibilityBounds) {
    Mesh m = torus(300, 200);
    ValenceEncodeOptions o;
    o.position_bits = 12;
    ValenceEncodeResult r;
    expectRoundTrip(m, o, &r);
    const double conn_bpv = double(r.connectivity_bytes) * 8.0 / double(m.vertexCount());
    EXPECT_LT(conn_bpv, 0.1);
    EXPECT_LE(double(m.vertexCount()),
              double(lodrt::format::kValenceVerticesPerByte) * double(r.connectivity_bytes + 1));
}

TEST(ValenceCodecTest, TorusWithNormals) {
    for (uint32_t nb : {6u, 10u, 16u}) {
        ValenceEncodeOptions o;
        o.normal_bits = nb;
        expectRoundTrip(torus(24, 12), o);
    }
    ValenceEncodeOptions no_normals;
    no_normals.encode_normals = false;
    ValenceEncodeResult r;
    expectRoundTrip(torus(24, 12), no_normals, &r);
    EXPECT_EQ(r.normal_bytes, 0u);
}
TEST(ValenceCodecTest, RejectsBadOptionsAndNonFinite) {
    ValenceEncodeOptions o;
    o.position_bits = 17;
    EXPECT_FALSE(encodeValence(lodbake_test::tetrahedron(), o).ok());
    Mesh m = lodbake_test::tetrahedron();
    m.positions[2].y = std::nanf("");
    auto r = encodeValence(m, {});
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.status().message().find("vertex 2"), std::string::npos);
}

// Shared scans are loaded once per process.
const Mesh* loadShared(const std::string& name) {
    static std::deque<std::pair<std::string, Mesh>> cache; // deque: pointers stay valid
    for (auto& c : cache)
        if (c.first == name) return &c.second;
    lodbake::Diagnostics diag;
    auto loaded = lodbake::readMesh(lodbake_test::sharedMesh(name), {}, diag);
    if (!loaded.ok()) return nullptr;
    cache.push_back({name, std::move(loaded->mesh)});
    return &cache.back().second;
}

TEST(ValenceCodecTest, SharedScans) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    for (const char* name : {"bunny_zipper.ply", "lucy100k.ply", "dragon_scan_stand0_tri.ply"}) {
        const Mesh* m = loadShared(name);
        ASSERT_NE(m, nullptr) << name;
        ValenceEncodeOptions o;
        o.position_bits = 12;
        ValenceEncodeResult r;
        expectRoundTrip(*m, o, &r);
        // Well below the 96 bits per vertex of float positions plus 3 x 32-bit indices per face.
        EXPECT_LT(double(r.bytes.size()) * 8.0 / double(m->vertexCount()), 40.0) << name;
        // Valence coding: measured 1.15 (bunny), 2.05 (lucy100k) bits per vertex.
        const double conn_bpv = double(r.connectivity_bytes) * 8.0 / double(m->vertexCount());
        EXPECT_LT(conn_bpv, std::string(name) == "bunny_zipper.ply" ? 1.4 : 2.6) << name;
    }
}

struct CliRun {
    int exit_code = -1;
    std::string out, err;
};

CliRun runCli(const std::string& args) {
    static int counter = 0;
    const std::string base =
        lodbake_test::scratchDir() + "/valence_cli_" + std::to_string(::getpid()) + "_" + std::to_string(++counter);
    const std::string cmd = "'" + lodbake_test::lodbakeCli() + "' " + args + " >" + base + ".out 2>" + base + ".err";
    const int status = std::system(cmd.c_str());
    CliRun r;
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    for (auto [path, text] : {std::make_pair(base + ".out", &r.out), std::make_pair(base + ".err", &r.err)}) {
        std::ifstream f(path);
        std::stringstream ss;
        ss << f.rdbuf();
        *text = ss.str();
    }
    return r;
}

TEST(ValenceCodecTest, CliEncodeDecode) {
    const std::string dir = lodbake_test::scratchDir();
    const std::string in = dir + "/valence_torus.ply", lbm = dir + "/valence_torus.lbm",
                      out = dir + "/valence_back.ply";
    lodbake::Diagnostics diag;
    ASSERT_TRUE(lodbake::writeMesh(torus(12, 8), in, {}, diag).ok());
    CliRun enc = runCli("encode '" + in + "' -o '" + lbm + "' --bits 12 --normal-bits 8 --json");
    ASSERT_EQ(enc.exit_code, 0) << enc.err;
    EXPECT_NE(enc.out.find("\"connectivity\""), std::string::npos);
    EXPECT_NE(enc.out.find("\"bits_per_vertex\""), std::string::npos);
    CliRun dec = runCli("decode '" + lbm + "' -o '" + out + "'");
    ASSERT_EQ(dec.exit_code, 0) << dec.err;
    auto back = lodbake::readMesh(out, {}, diag);
    ASSERT_TRUE(back.ok());
    EXPECT_EQ(back->mesh.vertexCount(), 96u);
    EXPECT_EQ(back->mesh.faceCount(), 192u);
    EXPECT_TRUE(back->mesh.hasNormals());
    // A cut file: exit 1, one error line naming the file, no output.
    auto bytes = lodbake::readFileBytes(lbm);
    ASSERT_TRUE(bytes.ok());
    const std::string cut = dir + "/valence_cut.lbm", cut_out = dir + "/valence_cut.ply";
    ASSERT_TRUE(lodbake::writeFileAtomic(cut, bytes->data(), bytes->size() - 3).ok());
    CliRun bad = runCli("decode '" + cut + "' -o '" + cut_out + "'");
    EXPECT_EQ(bad.exit_code, 1);
    EXPECT_EQ(bad.err.rfind("error: " + cut + ": ", 0), 0u) << bad.err;
    EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1);
    EXPECT_FALSE(std::ifstream(cut_out).good());
    EXPECT_EQ(runCli("encode '" + in + "' -o '" + lbm + "' --bits 7").exit_code, 2);
}

// ---- decoder safety ----

struct Decoded {
    std::vector<uint32_t> indices;
    std::vector<float> positions, normals;
    std::vector<uint32_t> scratch;
};

// Decodes with buffers sized from the header; guard words after each buffer catch overruns.
lodrt::Result decodeChecked(const std::vector<uint8_t>& bytes) {
    lodrt::ValenceInfo info;
    lodrt::Result r = lodrt::valenceReadInfo(bytes.data(), bytes.size(), &info);
    if (r != lodrt::Result::Ok) return r;
    constexpr uint32_t kGuard = 0xDEADBEEFu;
    std::vector<uint32_t> indices(3 * size_t(info.triangle_count) + 4, kGuard);
    std::vector<float> positions(3 * size_t(info.vertex_count) + 4, 1234.5f);
    std::vector<float> normals(3 * size_t(info.vertex_count) + 4, 1234.5f);
    std::vector<uint64_t> scratch(lodrt::valenceScratchSize(info) / 8 + 4, kGuard);
    lodrt::ValenceOutput out;
    out.indices = indices.data();
    out.index_capacity = indices.size() - 4;
    out.positions = positions.data();
    out.position_capacity = positions.size() - 4;
    out.normals = normals.data();
    out.normal_capacity = normals.size() - 4;
    out.scratch = scratch.data();
    out.scratch_size = (scratch.size() - 4) * 8;
    std::vector<std::vector<float>> attributes(info.attribute_count);
    for (uint32_t i = 0; i < info.attribute_count; ++i) {
        attributes[i].assign(size_t(info.attributes[i].components) * info.vertex_count + 4, 1234.5f);
        out.attributes[i] = attributes[i].data();
        out.attribute_capacity[i] = attributes[i].size() - 4;
    }
    r = lodrt::valenceDecode(bytes.data(), bytes.size(), out);
    for (const std::vector<float>& a : attributes)
        for (int i = 0; i < 4; ++i) EXPECT_EQ(a[a.size() - 1 - size_t(i)], 1234.5f);
    for (int i = 0; i < 4; ++i) {
        EXPECT_EQ(indices[indices.size() - 1 - i], kGuard);
        EXPECT_EQ(positions[positions.size() - 1 - i], 1234.5f);
        EXPECT_EQ(normals[normals.size() - 1 - i], 1234.5f);
        EXPECT_EQ(scratch[scratch.size() - 1 - i], kGuard);
    }
    if (r == lodrt::Result::Ok) {
        for (size_t i = 0; i < 3 * size_t(info.triangle_count); ++i) EXPECT_LT(indices[i], info.vertex_count);
    }
    return r;
}

std::vector<uint8_t> sampleStream() {
    // A handle (merge), holes (dummy vertices), a second component and a non-manifold fan (copies).
    Mesh m = torus(16, 10);
    m.normals.clear();
    lodbake::appendMesh(m, grid(6, true));
    lodbake::appendMesh(m, lodbake_test::makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}},
                                                  {0, 1, 2, 1, 0, 3, 0, 1, 4}));
    auto enc = encodeValence(m, {});
    EXPECT_TRUE(enc.ok());
    return enc->bytes;
}

// Header flags of a stream (format.h: bit 0 normals, bits 1..3 snapped position components).
uint32_t streamFlags(const std::vector<uint8_t>& bytes) {
    return uint32_t(bytes[6]) | uint32_t(bytes[7]) << 8;
}

// A torus whose coordinates are all moved by random amounts: no two neighbours share one.
Mesh jitteredTorus(int nu, int nv, uint32_t seed) {
    std::mt19937 rng(seed);
    Mesh t = torus(nu, nv);
    t.normals.clear();
    for (Vec3f& p : t.positions) {
        p.x += float(rng() % 1000) * 1e-4f;
        p.y += float(rng() % 1000) * 1e-4f;
        p.z += float(rng() % 1000) * 1e-4f;
    }
    return t;
}

// A height field on an integer lattice with random heights and holes, and a jittered torus beside
// it (a handle: merges): x and y of every lattice vertex equal some neighbour's, z almost never, so
// the encoder snaps x and y only.
Mesh latticeMesh() {
    std::mt19937 rng(99);
    Mesh m = grid(24, true);
    for (Vec3f& p : m.positions) p.z = float(rng() % 1000) * 0.013f;
    lodbake::appendMesh(m, jitteredTorus(16, 10, 5));
    return m;
}

std::vector<uint8_t> snapStream() {
    auto enc = encodeValence(latticeMesh(), {});
    EXPECT_TRUE(enc.ok());
    return enc->bytes;
}

TEST(ValenceCodecTest, SnapFlagsFollowTheGeometry) {
    const Mesh m = latticeMesh();
    ValenceEncodeResult r;
    expectRoundTrip(m, {}, &r);
    using lodrt::format::kValenceFlagSnapX;
    EXPECT_EQ(streamFlags(r.bytes), uint32_t(kValenceFlagSnapX | kValenceFlagSnapX << 1)); // x and y
    // Without shared coordinates no component is snapped: the flag would only cost bits.
    const Mesh noisy = jitteredTorus(40, 30, 3);
    ValenceEncodeResult n;
    expectRoundTrip(noisy, {}, &n);
    EXPECT_EQ(streamFlags(n.bytes) & ~uint32_t(lodrt::format::kValenceFlagNormals), 0u);
    // The same mesh codes to the same bytes.
    EXPECT_EQ(encodeValence(m, {})->bytes, r.bytes);
}

// A height field on an integer lattice, a tilted plane on its left half and random heights on its
// right half: where a vertex's parallelograms agree on z its residual is about 0, where they disagree
// it is large, so spread contexts (format version 6) pay for z.
Mesh flatAndRoughTerrain() {
    std::mt19937 rng(7);
    const int n = 40;
    Mesh m = grid(n, false);
    for (size_t i = 0; i < m.positions.size(); ++i)
        m.positions[i].z = int(i % size_t(n + 1)) < n / 2 ? 0.37f * m.positions[i].x + 0.21f * m.positions[i].y
                                                          : float(rng() % 1000) * 0.01f;
    return m;
}

std::vector<uint8_t> spreadStream() {
    auto enc = encodeValence(flatAndRoughTerrain(), {});
    EXPECT_TRUE(enc.ok());
    return enc->bytes;
}

TEST(ValenceCodecTest, SpreadContextFlagsFollowTheGeometry) {
    const Mesh m = flatAndRoughTerrain();
    using lodrt::format::kValenceFlagSpreadX;
    ValenceEncodeResult r;
    expectRoundTrip(m, {}, &r);
    EXPECT_NE(streamFlags(r.bytes) & uint32_t(kValenceFlagSpreadX << 2), 0u); // z
    // The decoder follows the flag: the same bytes read without z's spread contexts do not give the
    // mesh back (an error, or other z values).
    std::vector<uint8_t> cleared = r.bytes;
    cleared[6] = uint8_t(cleared[6] & ~(kValenceFlagSpreadX << 2));
    auto wrong = lodbake::codec::decodeValence(cleared, "cleared.lbm");
    auto right = lodbake::codec::decodeValence(r.bytes, "right.lbm");
    ASSERT_TRUE(right.ok());
    if (wrong.ok()) {
        ASSERT_EQ(wrong->positions.size(), right->positions.size());
        bool same = true;
        for (size_t i = 0; i < right->positions.size(); ++i) same = same && wrong->positions[i].z == right->positions[i].z;
        EXPECT_FALSE(same);
    }
    // With normals too, and at other bit counts, every component's choice decodes.
    for (uint32_t bits : {11u, 16u}) {
        ValenceEncodeOptions o;
        o.position_bits = bits;
        expectRoundTrip(torus(48, 32), o);
        expectRoundTrip(m, o);
    }
}

// The multi-symbol model's search and adaptation (vectorised where the compiler targets SSE2) follow
// the scalar rules of docs/format/valence.md "Range coder" exactly, for both model sizes, through the
// fast first uses and the slow steady state, with symbols skewed toward both ends.
template <class Model> void expectCdfModelFollowsTheSpec(uint32_t last_rate, uint32_t seed) {
    constexpr uint32_t n = Model::kN;
    Model m;
    m.init();
    std::vector<int32_t> cum(n + 1);
    for (uint32_t i = 0; i <= n; ++i) cum[i] = int32_t(m.cum[i]);
    std::mt19937 rng(seed);
    uint32_t uses = 0;
    for (int step = 0; step < 4000; ++step) {
        // Every slot the coder can produce (0 .. just above 2^15) finds the spec's symbol.
        for (int probe = 0; probe < 8; ++probe) {
            const uint32_t slot = rng() % 32840u;
            uint32_t expect = 0;
            for (uint32_t i = 1; i < n; ++i) expect += uint32_t(cum[i]) <= slot ? 1u : 0u;
            ASSERT_EQ(m.find(slot), expect) << "slot " << slot;
        }
        ASSERT_EQ(m.find(uint32_t(cum[n - 1])), n - 1);
        const uint32_t s = (step / 500) % 2 == 0 ? rng() % 3 : n - 1 - rng() % 3;
        const uint32_t r = rng() % 4 == 0 ? rng() % n : s;
        const uint32_t rate = uses < 16 ? 3 : (uses < 32 ? 4 : last_rate);
        uses = std::min(uses + 1, 32u);
        for (uint32_t i = 1; i < n; ++i) {
            const int32_t hi = 32768 - 8 * int32_t(n - i), lo = 8 * int32_t(i);
            cum[i] = i > r ? cum[i] + ((hi - cum[i]) >> rate) : cum[i] - ((cum[i] - lo) >> rate);
        }
        m.update(r);
        for (uint32_t i = 0; i <= n; ++i) ASSERT_EQ(int32_t(m.cum[i]), cum[i]) << "step " << step << " entry " << i;
    }
}

TEST(ValenceCodecTest, MultiSymbolModelsFollowTheSpec) {
    expectCdfModelFollowsTheSpec<lodrt::detail::ResidualLengthModel>(6, 7);
    expectCdfModelFollowsTheSpec<lodrt::detail::ConnectivitySymbolModel>(7, 8);
}

// ---- attributes (format version 7) ----

// A torus laid out as a (nu + 1) x (nv + 1) grid whose last row and column repeat the first ones'
// positions with other UVs (the UV seams of a wrapped texture: the copies are separate vertices, so
// the seam is a cut in the connectivity). UV set 0 is the texture, set 1 a scaled and shifted copy
// (a lightmap), RGBA colours vary smoothly, tangents follow increasing u with the handedness flipped
// on the second half, and one vertex no triangle uses carries attributes too.
Mesh texturedTorus(int nu, int nv) {
    Mesh m;
    const float kPi = 3.14159265358979f;
    m.uvs.resize(2);
    for (int i = 0; i <= nu; ++i)
        for (int j = 0; j <= nv; ++j) {
            const float u = 2 * kPi * float(i % nu) / float(nu), v = 2 * kPi * float(j % nv) / float(nv);
            m.positions.push_back(Vec3f{(2 + std::cos(v)) * std::cos(u), (2 + std::cos(v)) * std::sin(u), std::sin(v)});
            m.normals.push_back(Vec3f{std::cos(v) * std::cos(u), std::cos(v) * std::sin(u), std::sin(v)});
            const float s = float(i) / float(nu), t = float(j) / float(nv);
            m.uvs[0].push_back(lodbake::Vec2f{s, t});
            m.uvs[1].push_back(lodbake::Vec2f{0.25f + 0.5f * s, 0.1f + 0.3f * t});
            m.colors.push_back(lodbake::Vec4f{0.5f + 0.5f * std::cos(u), 0.5f + 0.5f * std::sin(v), s, 0.25f + 0.5f * t});
            m.tangents.push_back(lodbake::Vec4f{-std::sin(u), std::cos(u), 0.0f, i < nu / 2 ? 1.0f : -1.0f});
        }
    const int w = nv + 1;
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            const uint32_t a = uint32_t(i * w + j), b = uint32_t((i + 1) * w + j), c = a + 1, d = b + 1;
            m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
        }
    m.positions.push_back(Vec3f{0.0f, 0.0f, 3.0f});
    m.normals.push_back(Vec3f{0.0f, 0.0f, 1.0f});
    m.uvs[0].push_back(lodbake::Vec2f{0.5f, 0.5f});
    m.uvs[1].push_back(lodbake::Vec2f{0.3f, 0.2f});
    m.colors.push_back(lodbake::Vec4f{1.0f, 0.0f, 0.0f, 1.0f});
    m.tangents.push_back(lodbake::Vec4f{1.0f, 0.0f, 0.0f, -1.0f});
    return m;
}

std::vector<uint8_t> attributeStream() {
    auto enc = encodeValence(texturedTorus(12, 8), {});
    EXPECT_TRUE(enc.ok());
    return enc->bytes;
}

// Every attribute decodes within its quantization: UVs and colours within half a step of their
// range, tangents within the octahedral step with the handedness exact; triangles and positions as
// for any stream (expectRoundTrip).
TEST(ValenceCodecTest, AttributesRoundTripWithinTheirQuantization) {
    const Mesh in = texturedTorus(24, 12);
    for (uint32_t uv_bits : {10u, 12u, 16u}) {
        ValenceEncodeOptions options;
        options.uv_bits = uv_bits;
        options.color_bits = uv_bits == 16 ? 12 : 8;
        options.tangent_bits = uv_bits == 10 ? 8 : 10;
        ValenceEncodeResult enc;
        expectRoundTrip(in, options, &enc);
        ASSERT_EQ(enc.attributes.size(), 4u); // two UV sets, colours, tangents
        auto dec = decodeValence(enc.bytes, "textured");
        ASSERT_TRUE(dec.ok()) << dec.status().message();
        const Mesh& m = *dec;
        ASSERT_EQ(m.uvs.size(), 2u);
        ASSERT_TRUE(m.hasColors());
        ASSERT_TRUE(m.hasTangents());
        for (size_t s = 0; s < 2; ++s) {
            float lo[2] = {1e9f, 1e9f}, hi[2] = {-1e9f, -1e9f};
            for (const lodbake::Vec2f& t : in.uvs[s]) {
                lo[0] = std::min(lo[0], t.x), hi[0] = std::max(hi[0], t.x);
                lo[1] = std::min(lo[1], t.y), hi[1] = std::max(hi[1], t.y);
            }
            const double range = std::max(hi[0] - lo[0], hi[1] - lo[1]);
            const double tol = 0.5 * range / double((1u << uv_bits) - 1) + 1e-6;
            double worst = 0.0;
            for (size_t v = 0; v < in.vertexCount(); ++v) {
                const lodbake::Vec2f& a = in.uvs[s][v];
                const lodbake::Vec2f& b = m.uvs[s][enc.new_vertex_of[v]];
                worst = std::max({worst, double(std::fabs(a.x - b.x)), double(std::fabs(a.y - b.y))});
            }
            EXPECT_LE(worst, tol) << "UV set " << s << " at " << uv_bits << " bits";
            EXPECT_NEAR(worst, enc.attributes[s].max_error, 1e-6);
        }
        double worst_color = 0.0;
        for (size_t v = 0; v < in.vertexCount(); ++v) {
            const lodbake::Vec4f& a = in.colors[v];
            const lodbake::Vec4f& b = m.colors[enc.new_vertex_of[v]];
            worst_color = std::max({worst_color, double(std::fabs(a.x - b.x)), double(std::fabs(a.y - b.y)),
                                    double(std::fabs(a.z - b.z)), double(std::fabs(a.w - b.w))});
        }
        EXPECT_LE(worst_color, 0.5 / double((1u << options.color_bits) - 1) + 1e-6);
        const double tol_t = 4.0 / double((1u << options.tangent_bits) - 1);
        for (size_t v = 0; v < in.vertexCount(); ++v) {
            const lodbake::Vec4f& a = in.tangents[v];
            const lodbake::Vec4f& b = m.tangents[enc.new_vertex_of[v]];
            const double d = std::sqrt(double(a.x - b.x) * (a.x - b.x) + double(a.y - b.y) * (a.y - b.y) +
                                       double(a.z - b.z) * (a.z - b.z));
            ASSERT_LE(d, tol_t) << "tangent " << v;
            ASSERT_EQ(a.w, b.w) << "handedness " << v;
        }
    }
}

// Without attributes (or with them switched off) the stream is version 6, byte for byte what the
// position and normal coder alone writes; with them, version 7 with the table flag.
TEST(ValenceCodecTest, AttributesOnlyChangeStreamsThatHaveThem) {
    Mesh plain = texturedTorus(12, 8);
    ValenceEncodeOptions off;
    off.encode_attributes = false;
    auto without = encodeValence(plain, off);
    ASSERT_TRUE(without.ok());
    plain.uvs.clear();
    plain.colors.clear();
    plain.tangents.clear();
    auto bare = encodeValence(plain, {});
    ASSERT_TRUE(bare.ok());
    EXPECT_EQ(without->bytes, bare->bytes);
    EXPECT_EQ(bare->bytes[4], lodrt::format::kValenceVersionWithoutAttributes);
    EXPECT_TRUE(bare->attributes.empty());
    const std::vector<uint8_t> with = attributeStream();
    EXPECT_EQ(with[4], lodrt::format::kValenceVersion);
    EXPECT_NE(streamFlags(with) & lodrt::format::kValenceFlagAttributes, 0u);
}

// The seam copies of the textured torus take their positions from their twins: fewer position bytes
// than the same mesh coded without twins (its attributes switched off codes no twins), and the same
// decoded positions (expectRoundTrip checks them against the input).
TEST(ValenceCodecTest, SeamTwinsCostLessThanCodedPositions) {
    const Mesh in = texturedTorus(48, 24);
    ValenceEncodeResult with;
    expectRoundTrip(in, {}, &with);
    lodrt::ValenceInfo info;
    ASSERT_EQ(lodrt::valenceReadInfo(with.bytes.data(), with.bytes.size(), &info), lodrt::Result::Ok);
    EXPECT_GT(info.twin_bytes, 0u);
    ValenceEncodeOptions off;
    off.encode_attributes = false;
    auto without = encodeValence(in, off);
    ASSERT_TRUE(without.ok());
    EXPECT_LT(with.position_bytes + with.normal_bytes, without->position_bytes + without->normal_bytes);
}

// Vertex ids beyond 16 bits: every attribute of a 68,572-vertex textured torus (seams, twins, two
// UV sets, colours, tangents) decodes; UVs within half their step, handedness exact.
TEST(ValenceCodecTest, AttributesBeyondSixteenBitVertexIds) {
    Mesh in = texturedTorus(400, 170);
    in.normals.clear(); // expectRoundTrip's normal bound is tighter than some of these many directions need
    ASSERT_GT(in.vertexCount(), 65536u);
    ValenceEncodeResult enc;
    expectRoundTrip(in, {}, &enc);
    ASSERT_FALSE(enc.bytes.empty());
    auto dec = decodeValence(enc.bytes, "large");
    ASSERT_TRUE(dec.ok()) << dec.status().message();
    ASSERT_EQ(enc.attributes.size(), 4u);
    EXPECT_GT(enc.twin_vertices, 0u);
    double worst_uv = 0.0;
    for (size_t v = 0; v < in.vertexCount(); ++v) {
        const lodbake::Vec2f& a = in.uvs[0][v];
        const lodbake::Vec2f& b = dec->uvs[0][enc.new_vertex_of[v]];
        worst_uv = std::max({worst_uv, double(std::fabs(a.x - b.x)), double(std::fabs(a.y - b.y))});
        ASSERT_EQ(in.tangents[v].w, dec->tangents[enc.new_vertex_of[v]].w) << v;
    }
    EXPECT_LE(worst_uv, 0.5 / 4095.0 + 1e-6);
}

// encode's attribute options and report: a textured, coloured glb with tangents, every attribute in
// the JSON report with its bytes; decode writes them back; bits out of range are usage errors.
TEST(ValenceCodecTest, CliEncodesAttributes) {
    const std::string dir = lodbake_test::scratchDir();
    const std::string in = dir + "/valence_textured.glb", lbm = dir + "/valence_textured.lbm",
                      out = dir + "/valence_textured_back.glb";
    lodbake::Diagnostics diag;
    ASSERT_TRUE(lodbake::writeMesh(texturedTorus(12, 8), in, {}, diag).ok());
    CliRun enc = runCli("encode '" + in + "' -o '" + lbm + "' --uv-bits 10 --color-bits 6 --tangent-bits 9 --json");
    ASSERT_EQ(enc.exit_code, 0) << enc.err;
    for (const char* key : {"\"attributes\"", "\"kind\": \"uv\"", "\"kind\": \"color\"", "\"kind\": \"tangent\"",
                            "\"bits\": 10", "\"bits\": 6", "\"bits\": 9", "\"max_error\""})
        EXPECT_NE(enc.out.find(key), std::string::npos) << key << "\n" << enc.out;
    CliRun dec = runCli("decode '" + lbm + "' -o '" + out + "'");
    ASSERT_EQ(dec.exit_code, 0) << dec.err;
    auto back = lodbake::readMesh(out, {}, diag);
    ASSERT_TRUE(back.ok());
    EXPECT_FALSE(back->mesh.uvs.empty());
    EXPECT_TRUE(back->mesh.hasTangents());
    for (const char* flag : {"--uv-bits 3", "--color-bits 17", "--tangent-bits 2"})
        EXPECT_EQ(runCli("encode '" + in + "' -o '" + lbm + "' " + flag).exit_code, 2) << flag;
}

TEST(ValenceCodecTest, RejectsBadAttributeOptions) {
    const Mesh in = texturedTorus(6, 4);
    for (uint32_t bad : {3u, 17u}) {
        ValenceEncodeOptions o;
        o.uv_bits = bad;
        EXPECT_FALSE(encodeValence(in, o).ok());
        o = {};
        o.color_bits = bad;
        EXPECT_FALSE(encodeValence(in, o).ok());
        o = {};
        o.tangent_bits = bad;
        EXPECT_FALSE(encodeValence(in, o).ok());
    }
    Mesh nan = in;
    nan.uvs[0][3].x = std::nanf("");
    auto r = encodeValence(nan, {});
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.status().message().find("vertex 3: UV set 0 is not finite"), std::string::npos) << r.status().message();
}

// The attribute table is checked field by field before anything is decoded.
TEST(ValenceDecoderSafetyTest, AttributeTableIsChecked) {
    const std::vector<uint8_t> bytes = attributeStream();
    ASSERT_EQ(decodeChecked(bytes), lodrt::Result::Ok);
    const size_t table = lodrt::format::kValenceHeaderSize;
    const size_t rec = table + lodrt::format::kValenceAttributeTablePrefix; // first record: UV set 0
    const size_t tangent = rec + 3 * lodrt::format::kValenceAttributeRecordSize;
    ASSERT_EQ(bytes[tangent], lodrt::format::kValenceAttributeTangent);
    struct Patch {
        size_t at;
        uint8_t value;
        const char* what;
    } patches[] = {{table, 0, "no attributes"},
                   {table, 17, "too many attributes"},
                   {table + 8, 17, "twin cell shift 17"},
                   {table + 9, 1, "table prefix padding"},
                   {rec, 9, "unknown kind"},
                   {rec + 1, 3, "UV with 3 components"},
                   {rec + 2, 3, "3 bits"},
                   {rec + 2, 17, "17 bits"},
                   {rec + 3, 2, "unknown predictor"},
                   {rec + 6, 1, "reserved field"},
                   {rec + 24 + 3, 0xBF, "negative size"},
                   {rec + 24 + 8 + 3, 0x3F, "range of an unused component"},
                   {rec + 2 * lodrt::format::kValenceAttributeRecordSize + 3, 1, "colours with the UV predictor"},
                   {tangent + 3, 3, "tangent predicted from itself"},
                   {tangent + 3, 2, "tangent predicted from the colours"},
                   {4, lodrt::format::kValenceVersionWithoutAttributes, "table in a version 6 stream"}};
    for (const Patch& p : patches) {
        auto bad = bytes;
        bad[p.at] = p.value;
        const lodrt::Result r = decodeChecked(bad);
        EXPECT_TRUE(r == lodrt::Result::CorruptStream || r == lodrt::Result::Truncated ||
                    r == lodrt::Result::TrailingBytes)
            << p.what << ": " << lodrt::resultName(r);
    }
    auto infinite = bytes;
    infinite[rec + 8 + 2] = 0x80; // min[0] = +infinity
    infinite[rec + 8 + 3] = 0x7F;
    EXPECT_EQ(decodeChecked(infinite), lodrt::Result::CorruptStream);
    auto no_flag = bytes;
    no_flag[6] = uint8_t(no_flag[6] & ~lodrt::format::kValenceFlagAttributes);
    EXPECT_EQ(decodeChecked(no_flag), lodrt::Result::CorruptStream);
}

// Each attribute's range-coded part cut short (its length patched, the file size matching) and each
// raw part's last bit flipped: corrupt, or (a flipped data bit) a different value, never a read past
// the part.
TEST(ValenceDecoderSafetyTest, AttributePartsCutShortAreCorrupt) {
    const std::vector<uint8_t> bytes = attributeStream();
    lodrt::ValenceInfo info;
    ASSERT_EQ(lodrt::valenceReadInfo(bytes.data(), bytes.size(), &info), lodrt::Result::Ok);
    ASSERT_EQ(info.attribute_count, 4u);
    const size_t table = lodrt::format::kValenceHeaderSize + lodrt::format::kValenceAttributeTablePrefix;
    // The twin part (the torus's seams have twins): cut short, its decisions run out.
    ASSERT_GT(info.twin_bytes, 0u);
    const size_t twin_end = table + info.attribute_count * lodrt::format::kValenceAttributeRecordSize +
                            info.connectivity_bytes + info.position_bytes + info.position_raw_bytes + info.twin_bytes;
    for (uint32_t cut = 1; cut <= 6 && cut < info.twin_bytes; ++cut) {
        std::vector<uint8_t> bad(bytes.begin(), bytes.begin() + long(twin_end - cut));
        bad.insert(bad.end(), bytes.begin() + long(twin_end), bytes.end());
        const uint32_t length = info.twin_bytes - cut;
        for (int k = 0; k < 4; ++k) bad[lodrt::format::kValenceHeaderSize + 4 + size_t(k)] = uint8_t(length >> (8 * k));
        EXPECT_EQ(decodeChecked(bad), lodrt::Result::CorruptStream) << "twin part, " << cut << " cut";
    }
    size_t at = twin_end + info.normal_bytes + info.normal_raw_bytes;
    for (uint32_t i = 0; i < info.attribute_count; ++i) {
        const lodrt::ValenceAttribute& a = info.attributes[i];
        const size_t field = table + i * lodrt::format::kValenceAttributeRecordSize + 40;
        const size_t end = at + a.bytes;
        for (uint32_t cut = 1; cut <= 6 && cut < a.bytes; ++cut) {
            std::vector<uint8_t> bad(bytes.begin(), bytes.begin() + long(end - cut));
            bad.insert(bad.end(), bytes.begin() + long(end), bytes.end());
            const uint32_t length = a.bytes - cut;
            for (int k = 0; k < 4; ++k) bad[field + size_t(k)] = uint8_t(length >> (8 * k));
            EXPECT_EQ(decodeChecked(bad), lodrt::Result::CorruptStream) << "attribute " << i << ", " << cut << " cut";
        }
        if (a.raw_bytes > 0) {
            auto bad = bytes;
            bad[end + a.raw_bytes - 1] ^= 0x80;
            const lodrt::Result r = decodeChecked(bad);
            if (r == lodrt::Result::Ok) {
                const auto x = decodeValence(bad, "flipped"), y = decodeValence(bytes, "original");
                ASSERT_TRUE(x.ok() && y.ok());
                EXPECT_TRUE(x->uvs != y->uvs || x->colors != y->colors || x->tangents != y->tangents)
                    << "attribute " << i << ": a raw bit ignored";
            } else {
                EXPECT_EQ(r, lodrt::Result::CorruptStream);
            }
        }
        at = end + a.raw_bytes;
    }
    EXPECT_EQ(at, bytes.size());
}

TEST(ValenceDecoderSafetyTest, ValidStreamDecodes) {
    EXPECT_EQ(decodeChecked(sampleStream()), lodrt::Result::Ok);
}

TEST(ValenceDecoderSafetyTest, EveryTruncatedPrefixFails) {
    for (const std::vector<uint8_t>& bytes : {sampleStream(), snapStream(), spreadStream(), attributeStream()})
        for (size_t n = 0; n < bytes.size(); ++n) {
            std::vector<uint8_t> cut(bytes.begin(), bytes.begin() + long(n));
            lodrt::Result r = decodeChecked(cut);
            ASSERT_NE(r, lodrt::Result::Ok) << "prefix " << n;
            if (n < lodrt::format::kValenceHeaderSize && n >= 4) {
                ASSERT_EQ(r, lodrt::Result::Truncated);
            }
        }
}

TEST(ValenceDecoderSafetyTest, TrailingBytesBadMagicUnknownVersion) {
    std::vector<uint8_t> bytes = sampleStream();
    auto extra = bytes;
    extra.push_back(0);
    EXPECT_EQ(decodeChecked(extra), lodrt::Result::TrailingBytes);
    auto magic = bytes;
    magic[0] ^= 0x20;
    EXPECT_EQ(decodeChecked(magic), lodrt::Result::BadMagic);
    auto version = bytes;
    version[4] = uint8_t(lodrt::format::kValenceVersion + 1);
    EXPECT_EQ(decodeChecked(version), lodrt::Result::UnsupportedVersion);
    auto bits = bytes;
    bits[24] = 17;
    EXPECT_EQ(decodeChecked(bits), lodrt::Result::CorruptStream);
    auto flags = bytes;
    flags[6] |= 16; // no meaning yet
    EXPECT_EQ(decodeChecked(flags), lodrt::Result::CorruptStream);
}

// A stream of the previous format version is refused with a message naming both versions.
TEST(ValenceDecoderSafetyTest, OldVersionIsRefusedClearly) {
    auto old = sampleStream();
    const uint32_t previous = lodrt::format::kValenceVersionWithoutAttributes - 1;
    old[4] = uint8_t(previous);
    EXPECT_EQ(decodeChecked(old), lodrt::Result::UnsupportedVersion);
    auto dec = decodeValence(old, "old.lbm");
    ASSERT_FALSE(dec.ok());
    const std::string& msg = dec.status().message();
    EXPECT_NE(msg.find("old.lbm: header: format version " + std::to_string(previous) +
                       " is not supported (this decoder reads versions " +
                       std::to_string(lodrt::format::kValenceVersionWithoutAttributes) + " and " +
                       std::to_string(lodrt::format::kValenceVersion)),
              std::string::npos)
        << msg;
}

// Version 4's raw bit parts: no bit of the last raw byte is ignored (a flipped data bit changes the
// decoded positions, a set padding bit is corrupt), and a byte moved from the raw part to the
// range-coded part (same total size) is corrupt.
TEST(ValenceDecoderSafetyTest, RawBitPartsMustBeExact) {
    std::vector<uint8_t> bytes = sampleStream();
    auto get32 = [&](size_t at) {
        return uint32_t(bytes[at]) | uint32_t(bytes[at + 1]) << 8 | uint32_t(bytes[at + 2]) << 16 |
               uint32_t(bytes[at + 3]) << 24;
    };
    const uint32_t conn = get32(44), pos = get32(48), nrm = get32(52), pos_raw = get32(56), nrm_raw = get32(60);
    ASSERT_GT(pos_raw, 0u);
    ASSERT_EQ(bytes.size(), lodrt::format::kValenceHeaderSize + conn + pos + pos_raw + nrm + nrm_raw);
    auto original = decodeValence(bytes, "sample");
    ASSERT_TRUE(original.ok());
    const size_t last_raw = lodrt::format::kValenceHeaderSize + conn + pos + pos_raw - 1;
    int corrupt = 0, changed = 0;
    for (int bit = 0; bit < 8; ++bit) {
        auto bad = bytes;
        bad[last_raw] = uint8_t(bad[last_raw] ^ (1u << bit));
        auto decoded = decodeValence(bad, "flipped");
        if (!decoded.ok()) {
            EXPECT_EQ(decodeChecked(bad), lodrt::Result::CorruptStream) << "bit " << bit;
            ++corrupt;
        } else {
            EXPECT_NE(decoded->positions, original->positions) << "bit " << bit << " ignored";
            ++changed;
        }
    }
    EXPECT_EQ(corrupt + changed, 8);
    auto moved = bytes;
    const uint32_t pos_more = pos + 1, raw_less = pos_raw - 1;
    for (int i = 0; i < 4; ++i) {
        moved[48 + size_t(i)] = uint8_t(pos_more >> (8 * i));
        moved[56 + size_t(i)] = uint8_t(raw_less >> (8 * i));
    }
    EXPECT_EQ(decodeChecked(moved), lodrt::Result::CorruptStream);
}

// A range-coded part cut short (its last bytes removed and its header length patched, so the file
// size matches): the decoder runs past the part's end, reads zeros there without touching the bytes
// behind it (the next part, or nothing for the last one: ASan sees the exact buffer), and reports the
// stream corrupt. Connectivity, position and normal parts, 1-6 bytes cut.
TEST(ValenceDecoderSafetyTest, RangeCodedPartsCutShortAreCorrupt) {
    Mesh with_normals = torus(24, 12);
    auto normals_stream = encodeValence(with_normals, {});
    ASSERT_TRUE(normals_stream.ok());
    for (const std::vector<uint8_t>& bytes : {sampleStream(), snapStream(), normals_stream->bytes}) {
        auto get32 = [&](size_t at) {
            return uint32_t(bytes[at]) | uint32_t(bytes[at + 1]) << 8 | uint32_t(bytes[at + 2]) << 16 |
                   uint32_t(bytes[at + 3]) << 24;
        };
        // Header part lengths (docs/format/valence.md "Header") and the order of the parts in the file.
        const uint32_t conn = get32(44), pos = get32(48), nrm = get32(52), pos_raw = get32(56);
        const size_t header = lodrt::format::kValenceHeaderSize;
        const struct {
            size_t field;
            uint32_t length;
            size_t end; // one past the part's last byte
        } parts[] = {{44, conn, header + conn},
                     {48, pos, header + conn + pos},
                     {52, nrm, header + conn + pos + pos_raw + nrm}};
        int tested = 0;
        for (const auto& part : parts) {
            if (part.length == 0) continue;
            ++tested;
            for (uint32_t cut = 1; cut <= 6 && cut <= part.length; ++cut) {
                std::vector<uint8_t> bad(bytes.begin(), bytes.begin() + long(part.end - cut));
                bad.insert(bad.end(), bytes.begin() + long(part.end), bytes.end());
                const uint32_t length = part.length - cut;
                for (int i = 0; i < 4; ++i) bad[part.field + size_t(i)] = uint8_t(length >> (8 * i));
                EXPECT_EQ(decodeChecked(bad), lodrt::Result::CorruptStream)
                    << "part at header offset " << part.field << ", " << cut << " bytes cut";
            }
        }
        EXPECT_GE(tested, 2);
    }
}

TEST(ValenceDecoderSafetyTest, SmallBuffersAreRefused) {
    std::vector<uint8_t> bytes = sampleStream();
    lodrt::ValenceInfo info;
    ASSERT_EQ(lodrt::valenceReadInfo(bytes.data(), bytes.size(), &info), lodrt::Result::Ok);
    std::vector<uint32_t> indices(3 * info.triangle_count);
    std::vector<float> positions(3 * info.vertex_count);
    std::vector<uint64_t> scratch(lodrt::valenceScratchSize(info) / 8);
    lodrt::ValenceOutput out;
    out.indices = indices.data();
    out.index_capacity = indices.size() - 1;
    out.positions = positions.data();
    out.position_capacity = positions.size();
    out.scratch = scratch.data();
    out.scratch_size = scratch.size() * 8;
    EXPECT_EQ(lodrt::valenceDecode(bytes.data(), bytes.size(), out), lodrt::Result::BufferTooSmall);
    out.index_capacity = indices.size();
    out.scratch_size -= 8;
    EXPECT_EQ(lodrt::valenceDecode(bytes.data(), bytes.size(), out), lodrt::Result::BufferTooSmall);
    out.scratch_size += 8;
    EXPECT_EQ(lodrt::valenceDecode(bytes.data(), bytes.size(), out), lodrt::Result::Ok);
}

TEST(ValenceDecoderSafetyTest, RandomCorruptionNeverCrashes) {
    for (const std::vector<uint8_t>& bytes : {sampleStream(), snapStream(), spreadStream(), attributeStream()}) {
        std::mt19937 rng(12345);
        int failures = 0;
        for (int trial = 0; trial < 3000; ++trial) {
            auto bad = bytes;
            int flips = 1 + int(rng() % 4);
            for (int k = 0; k < flips; ++k) {
                // Mostly the streams; sometimes the header.
                size_t at = (rng() % 8 == 0) ? rng() % lodrt::format::kValenceHeaderSize : rng() % bad.size();
                bad[at] = uint8_t(rng());
            }
            if (bad == bytes) continue;
            if (decodeChecked(bad) != lodrt::Result::Ok) ++failures;
        }
        // Most corruptions are detected (the rest decode to some in-range mesh, which is allowed).
        EXPECT_GT(failures, 1500);
    }
}

} // namespace
