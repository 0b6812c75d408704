// OFF reader and writer: keyword variants (C, N, ST and their combinations), header layouts,
// colours, polygons, refusal of unsupported variants and of hostile counts, and round trips.

#include "lodbake/io/off.h"

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "mesh_builders.h"

namespace {

using namespace lodbake;

Result<LoadedMesh> readOff(const std::string& text, Diagnostics* diag = nullptr,
                           const ReadOptions& options = ReadOptions()) {
    Diagnostics local;
    return readOffFromMemory(reinterpret_cast<const uint8_t*>(text.data()), text.size(), "m.off", options,
                             diag ? *diag : local);
}

Status errorOf(const std::string& text, const ReadOptions& options = ReadOptions()) {
    const Result<LoadedMesh> r = readOff(text, nullptr, options);
    EXPECT_FALSE(r.ok()) << "expected an error for:\n" << text.substr(0, 200);
    if (r.ok()) return Status();
    EXPECT_EQ(r.status().message().find('\n'), std::string::npos) << "error must be one line";
    EXPECT_EQ(r.status().message().rfind("m.off: ", 0), 0u) << r.status().message();
    return r.status();
}

bool contains(const Status& s, const std::string& what) {
    return s.message().find(what) != std::string::npos;
}

TEST(OffReaderTest, ReadsPlainOffWithCommentsAndCountsOnEitherLine) {
    for (const std::string& text :
         {std::string("OFF\n# a comment\n4 2 0\n0 0 0\n1 0 0\n1 1 0 # corner\n0 1 0\n\n"
                      "3 0 1 2\n3 0 2 3\n"),
          std::string("OFF 4 2 5\r\n0 0 0\r\n1 0 0\r\n1 1 0\r\n0 1 0\r\n3 0 1 2\r\n3 0 2 3")}) {
        const auto r = readOff(text);
        ASSERT_TRUE(r.ok()) << r.status().message();
        const Mesh& m = r->mesh;
        EXPECT_EQ(m.vertexCount(), 4u);
        EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
        EXPECT_EQ(m.positions[2], Vec3f(1, 1, 0));
        EXPECT_EQ(r->source.format, MeshFormat::Off);
        EXPECT_EQ(r->source.encoding, "ascii");
        EXPECT_EQ(r->source.file_vertex_count, 4u);
        EXPECT_EQ(r->source.file_face_count, 2u);
        EXPECT_EQ(r->source.face_kind, "triangles");
        EXPECT_FALSE(m.hasColors());
        EXPECT_FALSE(m.hasNormals());
    }
}

TEST(OffReaderTest, CoffColoursFollowGeomviewIntegerAndFloatRules) {
    // Integers are 0..255, numbers with a point are 0..1; three or four components; sRGB to linear.
    const auto r = readOff("COFF\n3 1 0\n0 0 0 255 0 0\n1 0 0 0.5 0 0 0.25\n0 1 0 0 0 128 255\n3 0 1 2\n");
    ASSERT_TRUE(r.ok()) << r.status().message();
    const Mesh& m = r->mesh;
    ASSERT_TRUE(m.hasColors());
    EXPECT_FLOAT_EQ(m.colors[0].x, 1.0f);
    EXPECT_FLOAT_EQ(m.colors[0].w, 1.0f);
    EXPECT_NEAR(m.colors[1].x, 0.21404f, 1e-4f);
    EXPECT_FLOAT_EQ(m.colors[1].w, 0.25f);
    EXPECT_NEAR(m.colors[2].z, 0.21586f, 1e-4f); // 128/255 sRGB
}

TEST(OffReaderTest, ReadsNormalsAndTexcoordsInEveryCombination) {
    const auto n = readOff("NOFF\n3 1 0\n0 0 0 0 0 2\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n");
    ASSERT_TRUE(n.ok()) << n.status().message();
    ASSERT_TRUE(n->mesh.hasNormals());
    EXPECT_EQ(n->mesh.normals[0], Vec3f(0, 0, 1));

    const auto cn =
        readOff("CNOFF\n3 1 0\n0 0 0 0 0 1 1.0 1.0 1.0 1.0\n1 0 0 0 0 1 0 0 0\n0 1 0 0 0 1 0 255 0\n3 0 1 2\n");
    ASSERT_TRUE(cn.ok()) << cn.status().message();
    EXPECT_TRUE(cn->mesh.hasNormals());
    EXPECT_FLOAT_EQ(cn->mesh.colors[2].y, 1.0f);

    const auto st = readOff("STOFF\n3 1 0\n0 0 0 0 0\n1 0 0 1 0.25\n0 1 0 0 1\n3 0 1 2\n");
    ASSERT_TRUE(st.ok()) << st.status().message();
    ASSERT_EQ(st->mesh.uvs.size(), 1u);
    EXPECT_EQ(st->mesh.uvs[0][1], Vec2f(1.0f, 0.75f)); // flipped to the glTF convention

    const auto stcn = readOff("STCNOFF\n3 1 0\n0 0 0 0 0 1 9 9 9 0.5 0.5\n1 0 0 0 0 1 9 9 9 1 1\n"
                              "0 1 0 0 0 1 9 9 9 0 0\n3 0 1 2\n");
    ASSERT_TRUE(stcn.ok()) << stcn.status().message();
    EXPECT_EQ(stcn->mesh.uvs[0][2], Vec2f(0.0f, 1.0f));
    EXPECT_TRUE(stcn->mesh.hasColors());
    EXPECT_TRUE(stcn->mesh.hasNormals());
}

TEST(OffReaderTest, TriangulatesPolygonsAndSkipsFaceColours) {
    Diagnostics diag;
    const auto r = readOff("OFF\n5 1 0\n0 0 0\n2 0 0\n2 2 0\n1 1 0\n0 2 0\n5 0 1 2 3 4 255 0 0\n", &diag);
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->mesh.faceCount(), 3u);
    EXPECT_EQ(r->source.face_kind, "polygons");
    EXPECT_EQ(r->source.file_face_count, 1u);
    double area = 0.0;
    for (size_t t = 0; t < 3; ++t) {
        const auto tri = r->mesh.triangle(FaceId(uint32_t(t)));
        const Vec3d n = cross(toDouble(r->mesh.position(tri[1]) - r->mesh.position(tri[0])),
                              toDouble(r->mesh.position(tri[2]) - r->mesh.position(tri[0])));
        EXPECT_GT(n.z, 0.0);
        area += 0.5 * length(n);
    }
    EXPECT_NEAR(area, 3.0, 1e-9); // 2x2 square minus the notch triangle of area 1
    ASSERT_EQ(diag.items().size(), 1u);
    EXPECT_NE(diag.items()[0].message.find("colours of 1 faces"), std::string::npos);
}

TEST(OffReaderTest, RefusesUnsupportedVariants) {
    EXPECT_EQ(errorOf("4OFF\n1 0 0\n0 0 0 1\n").code(), StatusCode::Unsupported);
    EXPECT_EQ(errorOf("nOFF\n2\n1 0 0\n0 0\n").code(), StatusCode::Unsupported);
    const Status binary = errorOf(std::string("OFF BINARY\n\0\0\0\3", 15));
    EXPECT_EQ(binary.code(), StatusCode::Unsupported);
    EXPECT_TRUE(contains(binary, "binary OFF"));
    EXPECT_TRUE(contains(errorOf("PLY\n3 1 0\n"), "header: expected an OFF keyword"));
    EXPECT_TRUE(contains(errorOf("XOFF\n3 1 0\n"), "expected an OFF keyword"));
    EXPECT_TRUE(contains(errorOf(""), "header: expected more data"));
}

TEST(OffReaderTest, RefusesCountsTheFileCannotHoldBeforeAllocating) {
    const Status s = errorOf("OFF\n4000000000 1 0\n0 0 0\n");
    EXPECT_EQ(s.code(), StatusCode::ResourceLimit);
    ReadOptions big;
    big.max_vertex_count = UINT64_MAX;
    big.max_face_count = UINT64_MAX;
    const Status s2 = errorOf("OFF\n4000000000 9000000000000000000 0\n0 0 0\n", big);
    EXPECT_TRUE(contains(s2, "header: 4000000000 vertices and 9000000000000000000 faces need at least"))
        << s2.message();
    EXPECT_TRUE(contains(errorOf("OFF\n100 10 0\n0 0 0\n"), "but the file has"));
    EXPECT_TRUE(contains(errorOf("OFF\n0 0 0\n"), "no vertices"));
    EXPECT_TRUE(contains(errorOf("OFF\n-3 1 0\n"), "header: expected the vertex count"));
    EXPECT_TRUE(contains(errorOf("OFF\n3 x 0\n"), "header: expected the face count"));
    EXPECT_TRUE(contains(errorOf("OFF\n3 1 0 7\n0 0 0\n0 0 0\n0 0 0\n3 0 1 2\n"), "extra values"));
}

TEST(OffReaderTest, RejectsBadElementsNamingThem) {
    const std::string head = "OFF\n3 1 0\n0 0 0\n1 0 0\n";
    EXPECT_TRUE(contains(errorOf(head + "0 1 abc\n3 0 1 2\n"), "vertex 2: expected a number, got 'abc'"));
    EXPECT_TRUE(contains(errorOf(head + "0 nan 0\n3 0 1 2\n"), "vertex 2: value is not finite"));
    EXPECT_TRUE(contains(errorOf(head + "0 1\n3 0 1 2\n# padding\n"), "vertex 2: expected 3 values, got 2"));
    EXPECT_TRUE(contains(errorOf(head + "0 1 0\n3 0 1 3\n"), "face 0: vertex index 3 out of range (3 vertices)"));
    EXPECT_TRUE(contains(errorOf(head + "0 1 0\n3 0 1 -1\n"), "face 0: vertex index -1 out of range"));
    EXPECT_TRUE(contains(errorOf(head + "0 1 0\n2 0 1\n# padding\n"), "face 0: expected at least 3 vertices, got 2"));
    EXPECT_TRUE(contains(errorOf(head + "0 1 0\n4 0 1 2\n"), "face 0: expected 4 vertex indices, got 3"));
    EXPECT_TRUE(contains(errorOf(head + "0 1 0\n3 0 x 2\n"), "face 0: expected a vertex index, got 'x'"));
    EXPECT_TRUE(contains(errorOf(head + "0 1 0\nthree 0 1 2\n"), "face 0: expected the vertex count"));
    EXPECT_TRUE(contains(errorOf("OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"), "but the file has"));
    EXPECT_TRUE(contains(errorOf("OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n# padding padding\n"),
                         "face 1: expected more data"));
    EXPECT_TRUE(
        contains(errorOf("COFF\n3 1 0\n0 0 0 1 1\n1 0 0\n0 1 0\n3 0 1 2\n"), "vertex 0: expected 6 or 7 values"));
    ReadOptions small;
    small.max_polygon_vertices = 3;
    EXPECT_TRUE(contains(errorOf("OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n", small),
                         "face 0: 4 vertices, more than 3"));
}

TEST(OffReaderTest, EveryTruncatedPrefixFailsCleanly) {
    const std::string text =
        "COFF\n4 2 0\n0 0 0 255 0 0\n1 0 0 0 255 0\n1 1 0 0 0 255\n0 1 0 9 9 9\n3 0 1 2\n3 0 2 3\n";
    const size_t last_line = text.rfind("3 0 2 3");
    for (size_t n = 0; n < last_line; ++n) {
        const Result<LoadedMesh> r = readOff(text.substr(0, n));
        EXPECT_FALSE(r.ok()) << "prefix of " << n << " bytes loaded";
    }
    EXPECT_TRUE(readOff(text).ok());
}

TEST(OffReaderTest, SurvivesSeededByteMutations) {
    const std::string base = "CNOFF\n5 2 0\n0 0 0 0 0 1 255 0 0\n1 0 0 0 0 1 0 1.0 0\n1 1 0 0 0 1 0 0 255 255\n"
                             "0 1 0 0 0 1 9 9 9\n0.5 0.5 1 0 0 1 1 1 1\n5 0 1 2 4 3 1 0 0\n3 0 2 3\n# end\n";
    const char kAlphabet[] = "0123456789 -.#eE\nCNOF\r\x00\xff";
    uint64_t state = 0x2545f4914f6cdd1dull; // fixed seed
    auto next = [&state]() {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        return state;
    };
    size_t loaded = 0;
    for (int iteration = 0; iteration < 3000; ++iteration) {
        std::string text = base;
        const int edits = 1 + int(next() % 4);
        for (int e = 0; e < edits; ++e) {
            const size_t pos = size_t(next() % text.size());
            const char c = kAlphabet[next() % (sizeof(kAlphabet) - 1)];
            switch (next() % 3) {
            case 0:
                text[pos] = c;
                break;
            case 1:
                text.insert(text.begin() + long(pos), c);
                break;
            default:
                text.erase(pos, 1);
                break;
            }
        }
        const Result<LoadedMesh> r = readOff(text);
        if (r.ok()) {
            ++loaded;
            EXPECT_TRUE(checkMeshConsistency(r->mesh, "mutated").ok()) << text;
        } else {
            EXPECT_EQ(r.status().message().find('\n'), std::string::npos) << r.status().message();
        }
    }
    EXPECT_GT(loaded, 0u);
}

TEST(OffReaderTest, WarnsAboutTrailingLines) {
    Diagnostics diag;
    const auto r = readOff("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n", &diag);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(diag.warningCount(), 1u);
}

TEST(OffWriterTest, WritesPlainOffDeterministically) {
    const std::string text = writeOffToMemory(lodbake_test::tetrahedron());
    EXPECT_EQ(text, "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
    const auto r = readOff(text);
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->mesh.positions, lodbake_test::tetrahedron().positions);
    EXPECT_EQ(r->mesh.indices, lodbake_test::tetrahedron().indices);
}

TEST(OffWriterTest, RoundTripsColoursThroughCoff) {
    Mesh m = lodbake_test::quad();
    m.positions[1] = {1.0f / 3.0f, -2.5e-7f, 12345.678f};
    m.colors = {{1, 0, 0, 1}, {0, 1, 0, 0.5f}, {0.2f, 0.2f, 0.2f, 1}, {0.9f, 0.01f, 0.5f, 1}};
    const std::string text = writeOffToMemory(m);
    EXPECT_EQ(text.rfind("COFF\n4 2 0\n", 0), 0u);
    EXPECT_EQ(writeOffToMemory(m), text);
    const auto r = readOff(text);
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->mesh.positions, m.positions); // shortest round-trip text: exact
    EXPECT_EQ(r->mesh.indices, m.indices);
    ASSERT_TRUE(r->mesh.hasColors());
    for (size_t i = 0; i < 4; ++i)
        for (int c = 0; c < 4; ++c)
            EXPECT_NEAR(r->mesh.colors[i][c], m.colors[i][c], 0.01f) << i << " " << c; // 8-bit sRGB steps
}

} // namespace
