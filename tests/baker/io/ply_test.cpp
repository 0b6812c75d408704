// PLY reader and writer: every encoding and scalar type built in memory, the conventions (sRGB
// colours, flipped v, strip parity, range-grid triangulation), hostile input, and the shared scans.

#include "lodbake/io/ply.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "lodbake/io/mesh_io.h"
#include "test_paths.h"

using namespace lodbake;

namespace {

// Builds PLY files byte by byte: a header, then values in the chosen encoding.
class PlyBuilder {
public:
    explicit PlyBuilder(std::string encoding) : encoding_(std::move(encoding)) {}

    PlyBuilder& line(const std::string& s) {
        header_ += s + "\n";
        return *this;
    }

    // Appends one value of PLY type `type` (ascii: as text, followed by a space).
    PlyBuilder& value(const std::string& type, double v) {
        if (encoding_ == "ascii") {
            char buf[64];
            if (type == "float" || type == "float32" || type == "double" || type == "float64")
                std::snprintf(buf, sizeof(buf), "%.9g ", v);
            else
                std::snprintf(buf, sizeof(buf), "%lld ", static_cast<long long>(v));
            body_ += buf;
            return *this;
        }
        uint8_t b[8];
        size_t n = 0;
        auto put = [&](auto x) {
            n = sizeof(x);
            std::memcpy(b, &x, n);
        };
        if (type == "char" || type == "int8") put(int8_t(v));
        else if (type == "uchar" || type == "uint8") put(uint8_t(v));
        else if (type == "short" || type == "int16") put(int16_t(v));
        else if (type == "ushort" || type == "uint16") put(uint16_t(v));
        else if (type == "int" || type == "int32") put(int32_t(v));
        else if (type == "uint" || type == "uint32") put(uint32_t(v));
        else if (type == "float" || type == "float32") put(float(v));
        else put(double(v));
        if (encoding_ == "binary_big_endian") std::reverse(b, b + n);
        body_.append(reinterpret_cast<const char*>(b), n);
        return *this;
    }

    // Ends a record (ascii: a line break).
    PlyBuilder& endRecord() {
        if (encoding_ == "ascii") body_ += "\n";
        return *this;
    }

    std::string bytes() const { return "ply\nformat " + encoding_ + " 1.0\n" + header_ + "end_header\n" + body_; }

private:
    std::string encoding_;
    std::string header_;
    std::string body_;
};

Result<LoadedMesh> readString(const std::string& s, const ReadOptions& options = ReadOptions()) {
    Diagnostics diagnostics;
    return readPlyFromMemory(reinterpret_cast<const uint8_t*>(s.data()), s.size(), "t.ply", options, diagnostics);
}

std::string errorOf(const std::string& s, const ReadOptions& options = ReadOptions()) {
    Result<LoadedMesh> r = readString(s, options);
    return r.ok() ? std::string("(no error)") : r.status().message();
}

// A unit square (two triangles) with the given vertex property types.
std::string squareFile(const std::string& encoding, const std::string& pos_type, const std::string& count_type,
                       const std::string& index_type) {
    PlyBuilder b(encoding);
    b.line("comment square").line("element vertex 4");
    for (const char* axis : {"x", "y", "z"}) b.line("property " + pos_type + " " + axis);
    b.line("element face 2").line("property list " + count_type + " " + index_type + " vertex_indices");
    const double pts[4][3] = {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    for (const auto& p : pts) b.value(pos_type, p[0]).value(pos_type, p[1]).value(pos_type, p[2]).endRecord();
    b.value(count_type, 3).value(index_type, 0).value(index_type, 1).value(index_type, 2).endRecord();
    b.value(count_type, 3).value(index_type, 0).value(index_type, 2).value(index_type, 3).endRecord();
    return b.bytes();
}

const char* const kEncodings[] = {"ascii", "binary_little_endian", "binary_big_endian"};
const char* const kScalarTypes[] = {"char",  "int8",   "uchar", "uint8",   "short", "int16",  "ushort",  "uint16",
                                    "int",   "int32",  "uint",  "uint32",  "float", "float32", "double", "float64"};
const char* const kIntegerTypes[] = {"char", "uchar", "short", "ushort", "int", "uint", "int8", "uint32"};

} // namespace

TEST(PlyReaderTest, ReadsEveryEncodingAndScalarType) {
    for (const char* enc : kEncodings)
        for (const char* type : kScalarTypes) {
            SCOPED_TRACE(std::string(enc) + " " + type);
            Result<LoadedMesh> r = readString(squareFile(enc, type, "uchar", "int"));
            ASSERT_TRUE(r.ok()) << r.status().message();
            const Mesh& m = r->mesh;
            ASSERT_EQ(m.vertexCount(), 4u);
            EXPECT_EQ(m.positions[2], Vec3f(1, 1, 1));
            EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
            EXPECT_EQ(r->source.encoding, enc);
            EXPECT_EQ(r->source.file_vertex_count, 4u);
            EXPECT_EQ(r->source.file_face_count, 2u);
            EXPECT_EQ(r->source.face_kind, "polygons");
        }
}

TEST(PlyReaderTest, ReadsListsWithAnyCountAndIndexType) {
    for (const char* enc : kEncodings)
        for (const char* count_type : kIntegerTypes)
            for (const char* index_type : kIntegerTypes) {
                SCOPED_TRACE(std::string(enc) + " " + count_type + " " + index_type);
                Result<LoadedMesh> r = readString(squareFile(enc, "float", count_type, index_type));
                ASSERT_TRUE(r.ok()) << r.status().message();
                EXPECT_EQ(r->mesh.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
            }
}

TEST(PlyReaderTest, BigEndianValuesAreSwapped) {
    PlyBuilder b("binary_big_endian");
    b.line("element vertex 3").line("property double x").line("property float y").line("property int z");
    b.line("element face 1").line("property list ushort uint vertex_indices");
    b.value("double", 1.5).value("float", -2.25).value("int", 70000).endRecord();
    b.value("double", 0).value("float", 0).value("int", -3).endRecord();
    b.value("double", 0).value("float", 1).value("int", 0).endRecord();
    b.value("ushort", 3).value("uint", 2).value("uint", 1).value("uint", 0);
    Result<LoadedMesh> r = readString(b.bytes());
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->mesh.positions[0], Vec3f(1.5f, -2.25f, 70000.0f));
    EXPECT_EQ(r->mesh.positions[1].z, -3.0f);
    EXPECT_EQ(r->mesh.indices, (std::vector<uint32_t>{2, 1, 0}));
}

TEST(PlyReaderTest, SkipsExtraElementsAndProperties) {
    for (const char* enc : kEncodings) {
        SCOPED_TRACE(enc);
        PlyBuilder b(enc);
        b.line("obj_info scanner 3030").line("element camera 1").line("property float view_px");
        b.line("property list uchar float track");
        b.line("element vertex 3").line("property float confidence").line("property float x").line("property float y");
        b.line("property list uint short junk").line("property float z").line("property uchar flags");
        b.line("element face 1").line("property int material").line("property list uchar int vertex_indices");
        b.line("property list uchar float texcoord").line("element edge 1").line("property int vertex1");
        b.line("property int vertex2");
        b.value("float", 7).value("uchar", 2).value("float", 1).value("float", 2).endRecord();
        for (int i = 0; i < 3; ++i) {
            b.value("float", 0.5).value("float", i).value("float", 2 * i).value("uint", 2).value("short", -1);
            b.value("short", 9).value("float", 3 * i).value("uchar", 255).endRecord();
        }
        b.value("int", 4).value("uchar", 3).value("int", 2).value("int", 0).value("int", 1).value("uchar", 6);
        for (int i = 0; i < 6; ++i) b.value("float", 0.25);
        b.endRecord().value("int", 0).value("int", 1).endRecord();
        Result<LoadedMesh> r = readString(b.bytes());
        ASSERT_TRUE(r.ok()) << r.status().message();
        EXPECT_EQ(r->mesh.positions[2], Vec3f(2, 4, 6));
        EXPECT_EQ(r->mesh.indices, (std::vector<uint32_t>{2, 0, 1}));
        EXPECT_FALSE(r->mesh.hasColors());
        EXPECT_FALSE(r->mesh.hasNormals());
        EXPECT_TRUE(r->mesh.uvs.empty());
    }
}

TEST(PlyReaderTest, UcharColoursAreDecodedFromSrgb) {
    PlyBuilder b("binary_little_endian");
    b.line("element vertex 3").line("property float x").line("property float y").line("property float z");
    b.line("property uchar red").line("property uchar green").line("property uchar blue").line("property uchar alpha");
    const int rgba[3][4] = {{0, 128, 255, 255}, {10, 188, 54, 0}, {255, 255, 255, 128}};
    for (const auto& c : rgba) {
        b.value("float", 0).value("float", 0).value("float", 0);
        for (int k : c) b.value("uchar", k);
    }
    Result<LoadedMesh> r = readString(b.bytes());
    ASSERT_TRUE(r.ok()) << r.status().message();
    const auto& c = r->mesh.colors;
    ASSERT_EQ(c.size(), 3u);
    EXPECT_EQ(c[0].x, 0.0f);
    EXPECT_NEAR(c[0].y, 0.2158605, 1e-6);     // sRGB 128/255 in linear light
    EXPECT_EQ(c[0].z, 1.0f);
    EXPECT_NEAR(c[1].x, 10 / 255.0 / 12.92, 1e-7); // the linear toe of the sRGB curve
    EXPECT_EQ(c[1].w, 0.0f);
    EXPECT_NEAR(c[2].w, 128 / 255.0, 1e-7);  // alpha is not sRGB-encoded
}

TEST(PlyReaderTest, FloatAndDiffuseColours) {
    PlyBuilder b("ascii");
    b.line("element vertex 1").line("property float x").line("property float y").line("property float z");
    b.line("property float diffuse_red").line("property float diffuse_green").line("property float diffuse_blue");
    b.value("float", 0).value("float", 0).value("float", 0).value("float", 1).value("float", 0.5).value("float", 0);
    Result<LoadedMesh> r = readString(b.bytes());
    ASSERT_TRUE(r.ok()) << r.status().message();
    ASSERT_EQ(r->mesh.colors.size(), 1u);
    EXPECT_EQ(r->mesh.colors[0].x, 1.0f);
    EXPECT_NEAR(r->mesh.colors[0].y, 0.2140411, 1e-6);
    EXPECT_EQ(r->mesh.colors[0].w, 1.0f); // no alpha: opaque
}

TEST(PlyReaderTest, TextureCoordinatesFlipV) {
    for (const auto& names : std::vector<std::pair<std::string, std::string>>{
             {"s", "t"}, {"u", "v"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}}) {
        SCOPED_TRACE(names.first);
        PlyBuilder b("ascii");
        b.line("element vertex 1").line("property float x").line("property float y").line("property float z");
        b.line("property float " + names.first).line("property float " + names.second);
        b.value("float", 0).value("float", 0).value("float", 0).value("float", 0.25).value("float", 0.875);
        Result<LoadedMesh> r = readString(b.bytes());
        ASSERT_TRUE(r.ok()) << r.status().message();
        ASSERT_EQ(r->mesh.uvs.size(), 1u);
        EXPECT_EQ(r->mesh.uvs[0][0], Vec2f(0.25f, 0.125f));
    }
}

TEST(PlyReaderTest, NormalsAreKept) {
    PlyBuilder b("binary_little_endian");
    b.line("element vertex 1").line("property float x").line("property float y").line("property float z");
    b.line("property float nx").line("property float ny").line("property float nz");
    b.value("float", 1).value("float", 2).value("float", 3).value("float", 0).value("float", 0).value("float", 2);
    Result<LoadedMesh> r = readString(b.bytes());
    ASSERT_TRUE(r.ok()) << r.status().message();
    ASSERT_TRUE(r->mesh.hasNormals());
    EXPECT_EQ(r->mesh.normals[0], Vec3f(0, 0, 1));
}

namespace {

// Signed area of a triangle list projected on z (polygons below lie in z = 0).
double areaZ(const Mesh& m) {
    double a = 0;
    for (size_t t = 0; t < m.faceCount(); ++t) {
        const Vec3f& p = m.positions[m.indices[3 * t]];
        const Vec3f& q = m.positions[m.indices[3 * t + 1]];
        const Vec3f& s = m.positions[m.indices[3 * t + 2]];
        a += 0.5 * ((double(q.x) - p.x) * (double(s.y) - p.y) - (double(q.y) - p.y) * (double(s.x) - p.x));
    }
    return a;
}

std::string polygonFile(const std::vector<std::array<float, 2>>& outline) {
    PlyBuilder b("ascii");
    b.line("element vertex " + std::to_string(outline.size()));
    b.line("property float x").line("property float y").line("property float z");
    b.line("element face 1").line("property list uchar int vertex_indices");
    for (const auto& p : outline) b.value("float", p[0]).value("float", p[1]).value("float", 0).endRecord();
    b.value("uchar", double(outline.size()));
    for (size_t i = 0; i < outline.size(); ++i) b.value("int", double(i));
    return b.bytes();
}

} // namespace

TEST(PlyReaderTest, ConcaveQuadUsesTheInsideDiagonal) {
    // Dart: concave at vertex 2, so the fan diagonal 0-2 would leave the outline.
    Result<LoadedMesh> r = readString(polygonFile({{{0, 0}}, {{2, 1}}, {{0.5f, 0.5f}}, {{1, 2}}}));
    ASSERT_TRUE(r.ok()) << r.status().message();
    ASSERT_EQ(r->mesh.faceCount(), 2u);
    // Every triangle keeps the polygon's orientation and the areas add up exactly.
    EXPECT_NEAR(areaZ(r->mesh), 0.5 * (2 * 0.5 - 1 * 0.5) + 0.5 * (0.5 * 2 - 0.5 * 1), 1e-6);
    for (size_t t = 0; t < 2; ++t) {
        Mesh one;
        one.positions = r->mesh.positions;
        one.indices.assign(r->mesh.indices.begin() + 3 * t, r->mesh.indices.begin() + 3 * t + 3);
        EXPECT_GT(areaZ(one), 0.0);
    }
}

TEST(PlyReaderTest, ConcavePolygonIsEarClipped) {
    // An L-shaped hexagon (area 3) and a comb-like octagon; a fan from vertex 0 would overlap itself.
    for (const auto& outline : std::vector<std::vector<std::array<float, 2>>>{
             {{{0, 0}}, {{2, 0}}, {{2, 1}}, {{1, 1}}, {{1, 2}}, {{0, 2}}},
             {{{1, 1}}, {{0, 2}}, {{0, 0}}, {{3, 0}}, {{3, 2}}, {{2, 2}}, {{2, 1.5f}}, {{1.5f, 1.5f}}}}) {
        Result<LoadedMesh> r = readString(polygonFile(outline));
        ASSERT_TRUE(r.ok()) << r.status().message();
        ASSERT_EQ(r->mesh.faceCount(), outline.size() - 2);
        double expected = 0;
        for (size_t i = 0; i < outline.size(); ++i) {
            const auto& p = outline[i];
            const auto& q = outline[(i + 1) % outline.size()];
            expected += 0.5 * (double(p[0]) * q[1] - double(q[0]) * p[1]);
        }
        double absolute = 0;
        for (size_t t = 0; t < r->mesh.faceCount(); ++t) {
            Mesh one;
            one.positions = r->mesh.positions;
            one.indices.assign(r->mesh.indices.begin() + 3 * t, r->mesh.indices.begin() + 3 * t + 3);
            EXPECT_GT(areaZ(one), 0.0) << "triangle " << t << " flipped";
            absolute += std::fabs(areaZ(one));
        }
        EXPECT_NEAR(absolute, expected, 1e-6); // no overlap, no gap
    }
}

TEST(PlyReaderTest, TristripsKeepParityAndDropDegenerates) {
    for (const char* enc : kEncodings) {
        SCOPED_TRACE(enc);
        PlyBuilder b(enc);
        b.line("element vertex 7").line("property float x").line("property float y").line("property float z");
        b.line("element tristrips 1").line("property list int int vertex_indices");
        for (int i = 0; i < 7; ++i) b.value("float", i % 3).value("float", i / 3).value("float", 0).endRecord();
        // Strip 0 1 2 3 3 4: (0,1,2) (2,1,3) [2,3,3 and 3,3,4 degenerate] then restart 4 5 6.
        const int strip[] = {0, 1, 2, 3, 3, 4, -1, 4, 5, 6};
        b.value("int", 10);
        for (int v : strip) b.value("int", v);
        b.endRecord();
        Result<LoadedMesh> r = readString(b.bytes());
        ASSERT_TRUE(r.ok()) << r.status().message();
        EXPECT_EQ(r->mesh.indices, (std::vector<uint32_t>{0, 1, 2, 2, 1, 3, 4, 5, 6}));
        EXPECT_EQ(r->source.face_kind, "tristrips");
        EXPECT_EQ(r->source.file_face_count, 1u);
    }
}

namespace {

// A range grid of `rows` x `cols` with samples on the plane z = depth (x to the right, y up in the
// image, so rows go down), `missing` cells empty; optional one sample pushed far away.
std::string rangeGridFile(size_t rows, size_t cols, const std::set<size_t>& missing, size_t far_cell = size_t(-1)) {
    std::vector<std::array<float, 3>> pts;
    std::vector<int> cell_vertex(rows * cols, -1);
    for (size_t r = 0; r < rows; ++r)
        for (size_t c = 0; c < cols; ++c) {
            const size_t cell = r * cols + c;
            if (missing.count(cell)) continue;
            cell_vertex[cell] = int(pts.size());
            pts.push_back({float(c) * 0.001f, -float(r) * 0.0012f, cell == far_cell ? -0.05f : 0.0f});
        }
    PlyBuilder b("ascii");
    b.line("obj_info is_cyberware_data 1").line("obj_info num_cols " + std::to_string(cols));
    b.line("obj_info num_rows " + std::to_string(rows)).line("element vertex " + std::to_string(pts.size()));
    b.line("property float x").line("property float y").line("property float z");
    b.line("element range_grid " + std::to_string(rows * cols)).line("property list uchar int vertex_indices");
    for (const auto& p : pts) b.value("float", p[0]).value("float", p[1]).value("float", p[2]).endRecord();
    for (int v : cell_vertex) {
        if (v < 0) b.value("uchar", 0).endRecord();
        else b.value("uchar", 1).value("int", v).endRecord();
    }
    return b.bytes();
}

Vec3d faceNormal(const Mesh& m, size_t t) {
    const Vec3d a = toDouble(m.positions[m.indices[3 * t]]);
    return cross(toDouble(m.positions[m.indices[3 * t + 1]]) - a, toDouble(m.positions[m.indices[3 * t + 2]]) - a);
}

} // namespace

TEST(PlyReaderTest, RangeGridTriangulation) {
    // 3 x 4 grid: full cells give 2 triangles, the cell next to the hole at (1,1) gives 1 or 0.
    {
        Result<LoadedMesh> r = readString(rangeGridFile(3, 4, {}));
        ASSERT_TRUE(r.ok()) << r.status().message();
        EXPECT_EQ(r->mesh.faceCount(), 2u * 3u * 2u);
        EXPECT_EQ(r->source.face_kind, "range_grid");
        EXPECT_EQ(r->source.file_face_count, 12u);
        // Scanner convention (checked against the Stanford data in PlySharedMeshesTest): for this grid
        // layout the front faces point to -z.
        for (size_t t = 0; t < r->mesh.faceCount(); ++t) EXPECT_LT(faceNormal(r->mesh, t).z, 0.0);
    }
    {
        // Sample (1,1) missing: the 4 cells around it have 3 samples each -> 1 triangle each.
        Result<LoadedMesh> r = readString(rangeGridFile(3, 4, {5}));
        ASSERT_TRUE(r.ok()) << r.status().message();
        EXPECT_EQ(r->mesh.faceCount(), 4u * 1u + 2u * 2u);
        for (size_t t = 0; t < r->mesh.faceCount(); ++t) EXPECT_LT(faceNormal(r->mesh, t).z, 0.0);
    }
    {
        // Sample (2,3) far behind the others: every triangle touching it has a long edge and goes.
        Result<LoadedMesh> r = readString(rangeGridFile(3, 4, {}, 11));
        ASSERT_TRUE(r.ok()) << r.status().message();
        EXPECT_EQ(r->mesh.faceCount(), 12u - 1u); // its cell splits on the other diagonal: 1 triangle touches it
        ReadOptions loose;
        loose.range_grid_max_edge_factor = 1000.0;
        Result<LoadedMesh> all = readString(rangeGridFile(3, 4, {}, 11), loose);
        ASSERT_TRUE(all.ok());
        EXPECT_EQ(all->mesh.faceCount(), 12u);
    }
}

TEST(PlyReaderTest, RangeGridSplitsOnTheShorterDiagonal) {
    // One cell whose top-right corner is pulled towards the bottom-left one.
    PlyBuilder b("ascii");
    b.line("obj_info num_cols 2").line("obj_info num_rows 2").line("element vertex 4");
    b.line("property float x").line("property float y").line("property float z");
    b.line("element range_grid 4").line("property list uchar int vertex_indices");
    b.line("comment order: tl tr bl br");
    const float pts[4][3] = {{0, 0, 0}, {0.6f, -0.4f, 0}, {0, -1, 0}, {1, -1, 0}};
    for (const auto& p : pts) b.value("float", p[0]).value("float", p[1]).value("float", p[2]).endRecord();
    for (int i = 0; i < 4; ++i) b.value("uchar", 1).value("int", i).endRecord();
    ReadOptions loose;
    loose.range_grid_max_edge_factor = 100.0;
    Result<LoadedMesh> r = readString(b.bytes(), loose);
    ASSERT_TRUE(r.ok()) << r.status().message();
    ASSERT_EQ(r->mesh.faceCount(), 2u);
    // The tr-bl diagonal (1-2) is the shorter one, so both triangles use it.
    for (size_t t = 0; t < 2; ++t) {
        const auto tri = r->mesh.triangle(FaceId(uint32_t(t)));
        const std::set<uint32_t> s{tri[0].value, tri[1].value, tri[2].value};
        EXPECT_TRUE(s.count(1) && s.count(2));
    }
}

TEST(PlyReaderTest, HeaderQuirksAreTolerated) {
    // Stray `bye` lines (Stanford dragon scans), comments, obj_info, CRLF line ends and blank lines.
    std::string s = "ply\r\nformat ascii 1.0\r\ncomment hello\r\nobj_info num_cols 0\r\nbye\r\nbye\r\n\r\n"
                    "element vertex 3\r\nproperty float x\r\nproperty float y\r\nproperty float z\r\n"
                    "element face 1\r\nproperty list uchar int vertex_index\r\nend_header\r\n"
                    "0 0 0\r\n1 0 0\r\n0 1 0\r\n3 0 1 2\r\n";
    Diagnostics diagnostics;
    Result<LoadedMesh> r =
        readPlyFromMemory(reinterpret_cast<const uint8_t*>(s.data()), s.size(), "q.ply", ReadOptions(), diagnostics);
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->mesh.indices, (std::vector<uint32_t>{0, 1, 2}));
    EXPECT_EQ(diagnostics.warningCount(), 0u);
    ASSERT_EQ(diagnostics.items().size(), 1u); // one note for the two `bye` lines
    EXPECT_EQ(diagnostics.items()[0].message, "q.ply: header: ignored 2 non-standard 'bye' line(s)");
}

TEST(PlyReaderTest, NoFacesIsAPointCloud) {
    PlyBuilder b("ascii");
    b.line("element vertex 2").line("property float x").line("property float y").line("property float z");
    b.value("float", 1).value("float", 2).value("float", 3).endRecord();
    b.value("float", 4).value("float", 5).value("float", 6).endRecord();
    Result<LoadedMesh> r = readString(b.bytes());
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->mesh.vertexCount(), 2u);
    EXPECT_EQ(r->mesh.faceCount(), 0u);
    EXPECT_EQ(r->source.face_kind, "none");
}

TEST(PlyReaderTest, ErrorsNameTheElement) {
    const std::string good = squareFile("ascii", "float", "uchar", "int");
    EXPECT_NE(errorOf(std::string(good).replace(good.find("0 2 3"), 5, "0 2 9")).find("t.ply: face 1: vertex index 9 out of range"),
              std::string::npos);
    EXPECT_NE(errorOf(std::string(good).replace(good.find("1 0 1"), 5, "1 x 1")).find("t.ply: vertex 1 property 'y': expected a number, got 'x'"),
              std::string::npos);
    EXPECT_NE(errorOf(std::string(good).replace(good.find("1 0 1"), 5, "1 nan 1")).find("t.ply: vertex 1: coordinate is not finite"),
              std::string::npos);
    EXPECT_NE(errorOf("plx\n").find("t.ply: header: expected the magic word 'ply'"), std::string::npos);
    EXPECT_NE(errorOf("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n")
                  .find("no vertices"),
              std::string::npos);
    ReadOptions small;
    small.max_polygon_vertices = 2;
    EXPECT_NE(errorOf(good, small).find("t.ply: face 0 property 'vertex_indices': polygon has 3 vertices, more than the limit of 2"),
              std::string::npos);
}

TEST(PlyReaderTest, EveryTruncatedPrefixFailsCleanly) {
    for (const char* enc : kEncodings) {
        const std::string full = squareFile(enc, "double", "ushort", "int");
        ASSERT_TRUE(readString(full).ok());
        // Ascii may lose only the final line break and still be complete.
        // (the builder ends it with "3 \n", so the last two bytes are optional).
        const size_t complete = std::string(enc) == "ascii" ? full.size() - 2 : full.size();
        for (size_t n = 0; n < complete; ++n) {
            Result<LoadedMesh> r = readString(full.substr(0, n));
            ASSERT_FALSE(r.ok()) << enc << " prefix " << n;
            EXPECT_EQ(r.status().message().find('\n'), std::string::npos);
            EXPECT_EQ(r.status().message().rfind("t.ply: ", 0), 0u) << r.status().message();
        }
    }
}

TEST(PlyReaderTest, HugeCountsAreRefusedBeforeAllocating) {
    const std::string s = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
                          "property float y\nproperty float z\nend_header\n" + std::string(1200, '\0');
    ReadOptions options;
    options.max_vertex_count = uint64_t(1) << 40;
    EXPECT_NE(errorOf(s, options).find("element vertex count 4000000000 needs at least"), std::string::npos);
    EXPECT_NE(errorOf(s).find("exceeds the limit"), std::string::npos);
}

namespace {

Mesh attributeMesh() {
    Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, -0.5f}};
    m.normals = {{0, 0, 1}, {0, 0.6f, 0.8f}, {1, 0, 0}, {0, -1, 0}};
    m.uvs = {{{0, 0}, {1, 0.5f}, {0.25f, 1}, {0.75f, 0.125f}}};
    for (int i = 0; i < 4; ++i) m.colors.push_back({0, 0, 0, 1});
    m.indices = {0, 1, 2, 2, 1, 3};
    return m;
}

} // namespace

TEST(PlyWriterTest, RoundTripBinaryAndAscii) {
    Mesh m = attributeMesh();
    // Colours that came from bytes must survive exactly.
    Result<LoadedMesh> colours = readString([] {
        PlyBuilder b("binary_little_endian");
        b.line("element vertex 4").line("property float x").line("property float y").line("property float z");
        b.line("property uchar red").line("property uchar green").line("property uchar blue").line("property uchar alpha");
        const int c[4][4] = {{1, 2, 3, 4}, {128, 200, 255, 0}, {17, 99, 254, 255}, {250, 60, 0, 77}};
        for (const auto& v : c) {
            b.value("float", 0).value("float", 0).value("float", 0);
            for (int k : v) b.value("uchar", k);
        }
        return b.bytes();
    }());
    ASSERT_TRUE(colours.ok()) << colours.status().message();
    m.colors = colours->mesh.colors;
    for (bool binary : {true, false}) {
        SCOPED_TRACE(binary ? "binary" : "ascii");
        const std::vector<uint8_t> bytes = writePlyToMemory(m, binary);
        EXPECT_EQ(bytes, writePlyToMemory(m, binary)); // deterministic
        Diagnostics diagnostics;
        Result<LoadedMesh> r = readPlyFromMemory(bytes.data(), bytes.size(), "rt.ply", ReadOptions(), diagnostics);
        ASSERT_TRUE(r.ok()) << r.status().message();
        EXPECT_EQ(r->source.encoding, binary ? "binary_little_endian" : "ascii");
        EXPECT_EQ(r->mesh.positions, m.positions);
        EXPECT_EQ(r->mesh.indices, m.indices);
        EXPECT_EQ(r->mesh.colors, m.colors);
        ASSERT_EQ(r->mesh.normals.size(), 4u);
        for (size_t i = 0; i < 4; ++i) EXPECT_NEAR(length(toDouble(r->mesh.normals[i]) - toDouble(m.normals[i])), 0.0, 1e-7);
        ASSERT_EQ(r->mesh.uvs.size(), 1u);
        EXPECT_EQ(r->mesh.uvs[0], m.uvs[0]); // these values flip exactly
        EXPECT_TRUE(diagnostics.empty());
    }
}

TEST(PlyWriterTest, EveryColourByteRoundTripsExactly) {
    PlyBuilder b("binary_little_endian");
    b.line("element vertex 256").line("property float x").line("property float y").line("property float z");
    b.line("property uchar red").line("property uchar green").line("property uchar blue").line("property uchar alpha");
    for (int i = 0; i < 256; ++i)
        b.value("float", i).value("float", 0).value("float", 0).value("uchar", i).value("uchar", 255 - i)
            .value("uchar", (i * 7) % 256).value("uchar", i);
    Result<LoadedMesh> r = readString(b.bytes());
    ASSERT_TRUE(r.ok()) << r.status().message();
    const std::vector<uint8_t> bytes = writePlyToMemory(r->mesh, true);
    Diagnostics diagnostics;
    Result<LoadedMesh> back = readPlyFromMemory(bytes.data(), bytes.size(), "rt.ply", ReadOptions(), diagnostics);
    ASSERT_TRUE(back.ok()) << back.status().message();
    EXPECT_EQ(back->mesh.colors, r->mesh.colors);
    // And the colour bytes written are the ones read: the file body ends with the same 4-byte groups.
    const std::string header_end = "end_header\n";
    const std::string text(bytes.begin(), bytes.end());
    const size_t body = text.find(header_end) + header_end.size();
    for (int i = 0; i < 256; ++i) {
        const uint8_t* c = bytes.data() + body + size_t(i) * 16 + 12;
        EXPECT_EQ(int(c[0]), i);
        EXPECT_EQ(int(c[1]), 255 - i);
        EXPECT_EQ(int(c[2]), (i * 7) % 256);
        EXPECT_EQ(int(c[3]), i);
    }
}

TEST(PlyWriterTest, HeaderListsOnlyPresentAttributes) {
    Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.indices = {0, 1, 2};
    const std::vector<uint8_t> bytes = writePlyToMemory(m, false);
    const std::string text(bytes.begin(), bytes.end());
    EXPECT_EQ(text, "ply\nformat ascii 1.0\ncomment written by lodbake\nelement vertex 3\nproperty float x\n"
                    "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                    "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
}

// ---------------------------------------------------------------------------------------------------
// The shared scans (README counts).

namespace {

struct SharedCase {
    const char* file;
    size_t vertices;
    size_t triangles;
    const char* face_kind;
};

const SharedCase kSharedCases[] = {
    {"bunny_zipper.ply", 35947, 69451, "polygons"},
    {"igea.ply", 134345, 268686, "polygons"},
    {"igea_tristrips.ply", 134345, 268686, "tristrips"},
    {"lucy100k.ply", 50002, 100000, "polygons"},
    {"dragon_poisson.ply", 535884, 1067852, "polygons"},
    {"bunny_scan_bun000.ply", 40256, 78505, "range_grid"},
    {"bunny_scan_bun000_tri.ply", 40173, 78505, "polygons"},
    {"dragon_scan_stand0_tri.ply", 41802, 79436, "polygons"},
    {"dragon_stand_merged.ply", 468773, 886456, "polygons"},
};

Result<LoadedMesh> loadShared(const std::string& name, Diagnostics& diagnostics) {
    return readMesh(lodbake_test::sharedMesh(name), ReadOptions(), diagnostics);
}

} // namespace

TEST(PlySharedMeshesTest, EveryPlyLoadsWithTheReadmeCounts) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    for (const SharedCase& c : kSharedCases) {
        SCOPED_TRACE(c.file);
        Diagnostics diagnostics;
        Result<LoadedMesh> r = loadShared(c.file, diagnostics);
        ASSERT_TRUE(r.ok()) << r.status().message();
        EXPECT_EQ(r->mesh.vertexCount(), c.vertices);
        EXPECT_EQ(r->mesh.faceCount(), c.triangles);
        EXPECT_EQ(r->source.face_kind, c.face_kind);
        EXPECT_EQ(r->source.file_vertex_count, c.vertices);
        EXPECT_EQ(diagnostics.warningCount(), 0u);
    }
}

TEST(PlySharedMeshesTest, DragonRangeScansTriangulateLikeTheMergedFile) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    size_t vertices = 0, triangles = 0, referenced = 0;
    for (int angle = 0; angle <= 336; angle += 24) {
        const std::string name = "range_scans/dragon_stand/dragonStandRight_" + std::to_string(angle) + ".ply";
        SCOPED_TRACE(name);
        Diagnostics diagnostics;
        Result<LoadedMesh> r = loadShared(name, diagnostics);
        ASSERT_TRUE(r.ok()) << r.status().message();
        EXPECT_EQ(r->source.face_kind, "range_grid");
        EXPECT_EQ(r->source.encoding, "ascii");
        EXPECT_EQ(diagnostics.warningCount(), 0u);
        if (angle == 0) {
            EXPECT_EQ(r->mesh.faceCount(), 79436u); // dragon_scan_stand0_tri.ply
        }
        vertices += r->mesh.vertexCount();
        triangles += r->mesh.faceCount();
        referenced += r->mesh.vertexCount() - countUnreferencedVertices(r->mesh);
    }
    EXPECT_EQ(vertices, 469193u);
    // dragon_stand_merged.ply is the 15 triangulated scans with only their used vertices.
    EXPECT_EQ(triangles, 886456u);
    EXPECT_EQ(referenced, 468773u);
}

TEST(PlySharedMeshesTest, BunnyRangeGridMatchesTheDerivedTriangles) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    Diagnostics diagnostics;
    Result<LoadedMesh> grid = loadShared("bunny_scan_bun000.ply", diagnostics);
    Result<LoadedMesh> derived = loadShared("bunny_scan_bun000_tri.ply", diagnostics);
    ASSERT_TRUE(grid.ok() && derived.ok());
    // bun000 has the identity transform, so positions are bit-identical: match vertices by position
    // and compare every triangle, orientation included (rotated so the smallest index comes first).
    std::map<std::tuple<float, float, float>, uint32_t> by_position;
    const Mesh& d = derived->mesh;
    for (uint32_t v = 0; v < d.vertexCount(); ++v)
        by_position.emplace(std::make_tuple(d.positions[v].x, d.positions[v].y, d.positions[v].z), v);
    auto canonical = [](std::array<uint32_t, 3> t) {
        while (t[0] > t[1] || t[0] > t[2]) t = {t[1], t[2], t[0]};
        return t;
    };
    std::set<std::array<uint32_t, 3>> derived_tris;
    for (size_t t = 0; t < d.faceCount(); ++t)
        derived_tris.insert(canonical({d.indices[3 * t], d.indices[3 * t + 1], d.indices[3 * t + 2]}));
    const Mesh& g = grid->mesh;
    size_t same = 0, reversed = 0;
    for (size_t t = 0; t < g.faceCount(); ++t) {
        std::array<uint32_t, 3> mapped{};
        for (int k = 0; k < 3; ++k) {
            const Vec3f& p = g.positions[g.indices[3 * t + size_t(k)]];
            const auto it = by_position.find(std::make_tuple(p.x, p.y, p.z));
            ASSERT_NE(it, by_position.end());
            mapped[size_t(k)] = it->second;
        }
        if (derived_tris.count(canonical(mapped))) ++same;
        else if (derived_tris.count(canonical({mapped[0], mapped[2], mapped[1]}))) ++reversed;
    }
    EXPECT_EQ(same, d.faceCount());
    EXPECT_EQ(reversed, 0u);
}

TEST(PlySharedMeshesTest, RoundTripOfAScan) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    Diagnostics diagnostics;
    Result<LoadedMesh> r = loadShared("bunny_zipper.ply", diagnostics);
    ASSERT_TRUE(r.ok()) << r.status().message();
    for (bool binary : {true, false}) {
        const std::vector<uint8_t> bytes = writePlyToMemory(r->mesh, binary);
        Result<LoadedMesh> back = readPlyFromMemory(bytes.data(), bytes.size(), "rt.ply", ReadOptions(), diagnostics);
        ASSERT_TRUE(back.ok()) << back.status().message();
        EXPECT_EQ(back->mesh.positions, r->mesh.positions);
        EXPECT_EQ(back->mesh.indices, r->mesh.indices);
        EXPECT_EQ(writePlyToMemory(back->mesh, binary), bytes);
    }
}

TEST(PlyReaderTest, FacesBeforeVerticesAndLooseSkippedValues) {
    // Element order is free in PLY; skipped ascii properties only need to be numbers.
    const std::string s = "ply\nformat ascii 1.0\nelement face 2\nproperty list uchar int vertex_indices\n"
                          "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                          "property uchar intensity\nend_header\n4 0 1 2 3\n2 0 1\n"
                          "0 0 0 0.5\n1 0 0 7\n1 1 0 -3\n0 1 0 1e3\n";
    Diagnostics diagnostics;
    Result<LoadedMesh> r =
        readPlyFromMemory(reinterpret_cast<const uint8_t*>(s.data()), s.size(), "o.ply", ReadOptions(), diagnostics);
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->mesh.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
    ASSERT_EQ(diagnostics.warningCount(), 1u); // the 2-vertex face
    EXPECT_NE(diagnostics.items()[0].message.find("o.ply: face: 1 faces with fewer than 3 vertices dropped"),
              std::string::npos);
}
