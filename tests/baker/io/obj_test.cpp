// OBJ/MTL reader and writer: statement forms, vertex unification, triangulation, materials and side
// files, hostile input, the shared scans and a write/read round trip.

#include "lodbake/io/obj.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "lodbake/core/file_io.h"
#include "mesh_builders.h"
#include "test_paths.h"

namespace {

using namespace lodbake;

// Side files served from memory, keyed by the path the reader asks for.
struct FakeFiles {
    std::map<std::string, std::vector<uint8_t>> files;
    std::vector<std::string> requested;

    void add(const std::string& path, const std::string& text) {
        files[path] = std::vector<uint8_t>(text.begin(), text.end());
    }
    SideFileLoader loader() {
        return [this](const std::string& path) -> Result<std::vector<uint8_t>> {
            requested.push_back(path);
            const auto it = files.find(path);
            if (it == files.end()) return ioError(path + ": cannot open: No such file or directory");
            return it->second;
        };
    }
};

const std::vector<uint8_t> kPngBytes = {0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a, 0, 0, 0, 13};
const std::vector<uint8_t> kJpegBytes = {0xff, 0xd8, 0xff, 0xe0, 0, 16, 'J', 'F', 'I', 'F'};

Result<LoadedMesh> readObj(const std::string& text, FakeFiles* side = nullptr, Diagnostics* diag = nullptr,
                           const ReadOptions& options = ReadOptions()) {
    FakeFiles none;
    Diagnostics local;
    FakeFiles& files = side ? *side : none;
    return readObjFromMemory(reinterpret_cast<const uint8_t*>(text.data()), text.size(), "dir/m.obj", files.loader(),
                             options, diag ? *diag : local);
}

std::string errorOf(const std::string& text, FakeFiles* side = nullptr, const ReadOptions& options = ReadOptions()) {
    const Result<LoadedMesh> r = readObj(text, side, nullptr, options);
    EXPECT_FALSE(r.ok()) << "expected an error for:\n" << text.substr(0, 200);
    if (r.ok()) return "";
    EXPECT_EQ(r.status().message().find('\n'), std::string::npos) << "error must be one line";
    EXPECT_EQ(r.status().message().rfind("dir/m.obj: ", 0), 0u) << r.status().message();
    return r.status().message();
}

double triangleArea(const Mesh& m, size_t t, Vec3d* normal_out = nullptr) {
    const auto tri = m.triangle(FaceId(uint32_t(t)));
    const Vec3d a = toDouble(m.position(tri[0])), b = toDouble(m.position(tri[1])), c = toDouble(m.position(tri[2]));
    const Vec3d n = cross(b - a, c - a);
    if (normal_out) *normal_out = n;
    return 0.5 * length(n);
}

const char* kSquareMtl = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

TEST(ObjReaderTest, ReadsEveryFaceFormAndUnifiesCorners) {
    const std::string text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
                             "vt 0 0\nvt 1 0\nvt 0 1\n"
                             "vn 0 0 2\n"
                             "f 1 2 3\n"
                             "f 1/1 2/2 3/3\n"
                             "f 1//1 2//1 3//1\n"
                             "f 2/2/1 4/1/1 3/3/1\n";
    Diagnostics diag;
    const auto r = readObj(text, nullptr, &diag);
    ASSERT_TRUE(r.ok()) << r.status().message();
    const Mesh& m = r->mesh;
    // Distinct (v, vt, vn): 3 plain + 3 with vt + 3 with vn + (2/2/1, 4/1/1, 3/3/1) = 12.
    EXPECT_EQ(m.vertexCount(), 12u);
    EXPECT_EQ(m.faceCount(), 4u);
    ASSERT_EQ(m.uvs.size(), 1u);
    EXPECT_EQ(r->source.file_vertex_count, 4u);
    EXPECT_EQ(r->source.file_face_count, 4u);
    EXPECT_EQ(r->source.face_kind, "triangles");
    EXPECT_EQ(r->source.encoding, "ascii");
    // Corners lacking normals make the reader drop normals (with a warning) rather than invent them.
    EXPECT_FALSE(m.hasNormals());
    EXPECT_GT(diag.warningCount(), 0u);
    // vt (0,1) flips to (0,0) in the glTF convention.
    const uint32_t corner = m.indices[5]; // second face, third corner: 3/3
    EXPECT_EQ(m.positions[corner], Vec3f(0, 1, 0));
    EXPECT_EQ(m.uvs[0][corner], Vec2f(0.0f, 0.0f));
}

TEST(ObjReaderTest, SharedCornersBecomeOneVertexAndNormalsAreUnit) {
    const std::string text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 3\nf 1//1 2//1 3//1\nf 2//1 4//1 3//1\n";
    const auto r = readObj(text);
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->mesh.vertexCount(), 4u);
    ASSERT_TRUE(r->mesh.hasNormals());
    for (const Vec3f& n : r->mesh.normals) EXPECT_EQ(n, Vec3f(0, 0, 1));
    EXPECT_EQ(r->mesh.indices, (std::vector<uint32_t>{0, 1, 2, 1, 3, 2}));
}

TEST(ObjReaderTest, ResolvesNegativeIndicesRelativeToDefinitionsSoFar) {
    const std::string text = "v 5 5 5\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 9 9 9\nf -4 -3 -1\n";
    const auto r = readObj(text);
    ASSERT_TRUE(r.ok()) << r.status().message();
    const Mesh& m = r->mesh;
    ASSERT_EQ(m.faceCount(), 2u);
    EXPECT_EQ(m.positions[m.indices[0]], Vec3f(0, 0, 0));
    EXPECT_EQ(m.positions[m.indices[2]], Vec3f(0, 1, 0));
    EXPECT_EQ(m.positions[m.indices[5]], Vec3f(9, 9, 9));
    // Vertex 1 (5,5,5) is used by no face: kept, in file order.
    EXPECT_EQ(m.vertexCount(), 5u);
    EXPECT_EQ(m.positions[0], Vec3f(5, 5, 5));
}

TEST(ObjReaderTest, SplitsQuadsOnTheShorterDiagonal) {
    // A rhombus: diagonal 2-4 is much shorter than 1-3.
    const auto r = readObj("v 0 0 0\nv 2 -0.5 0\nv 4 0 0\nv 2 0.5 0\nf 1 2 3 4\n");
    ASSERT_TRUE(r.ok()) << r.status().message();
    const Mesh& m = r->mesh;
    ASSERT_EQ(m.faceCount(), 2u);
    EXPECT_EQ(r->source.face_kind, "polygons");
    EXPECT_EQ(r->source.file_face_count, 1u);
    for (size_t t = 0; t < 2; ++t) {
        const auto tri = m.triangle(FaceId(uint32_t(t)));
        bool has1 = false, has3 = false;
        for (VertexId v : tri) {
            has1 |= m.position(v) == Vec3f(2, -0.5f, 0);
            has3 |= m.position(v) == Vec3f(2, 0.5f, 0);
        }
        EXPECT_TRUE(has1 && has3) << "each triangle must use the short diagonal";
    }
}

TEST(ObjReaderTest, ConcaveQuadUsesTheInsideDiagonal) {
    // A tall dart with its notch at vertex 3: the short diagonal 2-4 lies outside the quad.
    const auto r = readObj("v 0 -100 0\nv -1 0 0\nv 0 -1 0\nv 1 0 0\nf 1 2 3 4\n");
    ASSERT_TRUE(r.ok()) << r.status().message();
    const Mesh& m = r->mesh;
    ASSERT_EQ(m.faceCount(), 2u);
    double area = 0.0;
    for (size_t t = 0; t < 2; ++t) {
        Vec3d n;
        area += triangleArea(m, t, &n);
        EXPECT_LT(n.z, 0.0) << "triangle " << t << " flipped"; // the quad is clockwise from +z
    }
    // Shoelace area of the dart: two triangles of base 1 and height 99, 49.5 each.
    EXPECT_NEAR(area, 99.0, 1e-9);
}

TEST(ObjReaderTest, EarClipsConcavePolygonsInTheirPlane) {
    // An L-shaped hexagon, tilted out of every axis plane, listed clockwise seen from +z.
    const std::string text = "v 0 0 0\nv 0 2 1\nv 1 2 1\nv 1 1 0.5\nv 2 1 0.5\nv 2 0 0\nf 1 2 3 4 5 6\n";
    const auto r = readObj(text);
    ASSERT_TRUE(r.ok()) << r.status().message();
    const Mesh& m = r->mesh;
    ASSERT_EQ(m.faceCount(), 4u);
    double area = 0.0;
    for (size_t t = 0; t < 4; ++t) {
        Vec3d n;
        area += triangleArea(m, t, &n);
        EXPECT_LT(n.z, 0.0) << "winding must follow the polygon's (clockwise from +z)";
    }
    // Projected L area is 3; the plane z = y/2 stretches areas by sqrt(1 + 1/4).
    EXPECT_NEAR(area, 3.0 * std::sqrt(1.25), 1e-6);
}

TEST(ObjReaderTest, GroupsFacesIntoOneSubMeshPerMaterialInFirstUseOrder) {
    FakeFiles side;
    side.add("dir/m.mtl", "newmtl red\nKd 1 0 0\nnewmtl blue\nKd 0 0 1\nnewmtl unused\n");
    const std::string text = std::string("mtllib m.mtl\n") + kSquareMtl +
                             "f 1 2 3\n"              // no material
                             "usemtl blue\nf 1 3 4\n" // blue
                             "o other\ng grp\ns 1\n"
                             "usemtl red\nf 2 3 4\n"
                             "usemtl blue\nf 1 2 4\n";
    const auto r = readObj(text, &side);
    ASSERT_TRUE(r.ok()) << r.status().message();
    const Mesh& m = r->mesh;
    ASSERT_EQ(m.materials.size(), 3u);
    EXPECT_EQ(m.materials[0].name, "red");
    ASSERT_EQ(m.submeshes.size(), 3u);
    EXPECT_FALSE(m.submeshes[0].material.isValid());
    EXPECT_EQ(m.submeshes[1].material.value, 1u); // blue first used before red
    EXPECT_EQ(m.submeshes[1].name, "blue");
    EXPECT_EQ(m.submeshes[1].index_count, 6u);
    EXPECT_EQ(m.submeshes[2].material.value, 0u);
    EXPECT_EQ(m.submeshes[2].first_index, 9u);
    // Blue's two faces, in file order.
    EXPECT_EQ(m.positions[m.indices[3]], Vec3f(0, 0, 0));
    EXPECT_EQ(m.positions[m.indices[4]], Vec3f(1, 1, 0));
    EXPECT_EQ(m.positions[m.indices[7]], Vec3f(1, 0, 0));
    EXPECT_TRUE(checkMeshConsistency(m, "m").ok());
    EXPECT_EQ(side.requested, (std::vector<std::string>{"dir/m.mtl"}));
}

TEST(ObjReaderTest, MapsMtlOntoMetallicRoughness) {
    FakeFiles side;
    side.add("dir/mat/lib.mtl", "# comment\n"
                                "newmtl skin\n"
                                "Ka 0.1 0.1 0.1\nKd 0.5 0.5 0.5\nKs 1 1 1\nNs 98\nd 0.5\nillum 2\n"
                                "Ke 1 0 0\n"
                                "map_Kd -s 1 1 1 -o 0.5 0.5 -bm 0.5 -clamp on tex/skin color.png\n"
                                "map_Bump -bm 0.3 tex\\normal.jpg\n"
                                "newmtl metal\nKd 1\nTr 0.25\nPm 0.75\nPr 0.2\nNs 5\n"
                                "map_Kd tex/skin color.png\n");
    side.files["dir/mat/tex/skin color.png"] = kPngBytes;
    side.files["dir/mat/tex/normal.jpg"] = kJpegBytes;
    const auto r = readObj(
        std::string("mtllib mat/lib.mtl\nusemtl skin\n") + kSquareMtl + "f 1 2 3\nusemtl metal\nf 1 3 4\n", &side);
    ASSERT_TRUE(r.ok()) << r.status().message();
    const Mesh& m = r->mesh;
    ASSERT_EQ(m.materials.size(), 2u);
    const Material& skin = m.materials[0];
    EXPECT_NEAR(skin.base_color_factor.x, 0.21404f, 1e-4f); // sRGB 0.5 in linear
    EXPECT_FLOAT_EQ(skin.base_color_factor.w, 0.5f);
    EXPECT_EQ(skin.alpha_mode, AlphaMode::Blend);
    EXPECT_NEAR(skin.roughness_factor, std::sqrt(2.0f / 100.0f), 1e-6f);
    EXPECT_FLOAT_EQ(skin.metallic_factor, 0.0f);
    EXPECT_EQ(skin.emissive_factor, Vec3f(1, 0, 0));
    ASSERT_TRUE(skin.base_color_texture.isSet());
    ASSERT_TRUE(skin.normal_texture.isSet());
    EXPECT_NEAR(skin.normal_scale, 0.3f, 1e-6f);
    const Texture& color = m.textures[size_t(skin.base_color_texture.texture)];
    EXPECT_EQ(color.mime_type, "image/png");
    EXPECT_EQ(color.bytes, kPngBytes);
    EXPECT_EQ(color.uri, "mat/tex/skin color.png");
    EXPECT_EQ(m.textures[size_t(skin.normal_texture.texture)].mime_type, "image/jpeg");
    const Material& metal = m.materials[1];
    EXPECT_FLOAT_EQ(metal.base_color_factor.x, 1.0f);
    EXPECT_FLOAT_EQ(metal.base_color_factor.w, 0.75f);
    EXPECT_FLOAT_EQ(metal.metallic_factor, 0.75f);
    EXPECT_FLOAT_EQ(metal.roughness_factor, 0.2f); // Pr wins over Ns
    // The same file is loaded once and shared.
    EXPECT_EQ(m.textures.size(), 2u);
    EXPECT_EQ(metal.base_color_texture.texture, skin.base_color_texture.texture);
}

TEST(ObjReaderTest, WithoutTextureLoadingKeepsOnlyTheUri) {
    FakeFiles side;
    side.add("dir/m.mtl", "newmtl a\nmap_Kd absent.jpg\n");
    ReadOptions options;
    options.load_textures = false;
    const auto r = readObj(std::string("mtllib m.mtl\nusemtl a\n") + kSquareMtl + "f 1 2 3\n", &side, nullptr, options);
    ASSERT_TRUE(r.ok()) << r.status().message();
    ASSERT_EQ(r->mesh.textures.size(), 1u);
    EXPECT_TRUE(r->mesh.textures[0].bytes.empty());
    EXPECT_EQ(r->mesh.textures[0].uri, "absent.jpg");
    EXPECT_EQ(r->mesh.textures[0].mime_type, "image/jpeg");
}

TEST(ObjReaderTest, MissingSideFilesAreErrorsNamingLineAndFile) {
    std::string e = errorOf(std::string("# header\nmtllib gone.mtl\n") + kSquareMtl + "f 1 2 3\n");
    EXPECT_NE(e.find("line 2"), std::string::npos) << e;
    EXPECT_NE(e.find("gone.mtl"), std::string::npos) << e;

    FakeFiles side;
    side.add("dir/m.mtl", "newmtl a\nKd 1 1 1\nmap_Kd lost.png\n");
    e = errorOf(std::string("mtllib m.mtl\nusemtl a\n") + kSquareMtl + "f 1 2 3\n", &side);
    EXPECT_NE(e.find("m.mtl line 3"), std::string::npos) << e;
    EXPECT_NE(e.find("lost.png"), std::string::npos) << e;
}

TEST(ObjReaderTest, RejectsBrokenMtlAndUnknownMaterials) {
    FakeFiles side;
    side.add("dir/bad.mtl", "newmtl a\nKd 1 x 1\n");
    std::string e = errorOf(std::string("mtllib bad.mtl\n") + kSquareMtl + "f 1 2 3\n", &side);
    EXPECT_NE(e.find("bad.mtl line 2: Kd: expected a number, got 'x'"), std::string::npos) << e;

    side.add("dir/early.mtl", "Kd 1 1 1\nnewmtl a\n");
    e = errorOf(std::string("mtllib early.mtl\n") + kSquareMtl + "f 1 2 3\n", &side);
    EXPECT_NE(e.find("before any newmtl"), std::string::npos) << e;

    side.add("dir/ok.mtl", "newmtl a\n");
    e = errorOf(std::string("mtllib ok.mtl\n") + kSquareMtl + "f 1 2 3\n\nusemtl b\nf 1 3 4\n", &side);
    EXPECT_NE(e.find("line 8: usemtl: unknown material 'b'"), std::string::npos) << e;
}

TEST(ObjReaderTest, NonUtf8MaterialNamesAreMadeSafe) {
    FakeFiles side;
    side.add("dir/m.mtl", "newmtl caf\xc3\xa9\nKd 1 1 1\nnewmtl bad\xff\xc3name\nKd 1 1 1\n");
    Diagnostics diag;
    const auto r = readObj(std::string("mtllib m.mtl\nusemtl bad\xff\xc3name\n") + kSquareMtl +
                               "f 1 2 3\nusemtl caf\xc3\xa9\nf 1 3 4\n",
                           &side, &diag);
    ASSERT_TRUE(r.ok()) << r.status().message();
    ASSERT_EQ(r->mesh.materials.size(), 2u);
    EXPECT_EQ(r->mesh.materials[0].name, "caf\xc3\xa9"); // valid UTF-8 is kept
    EXPECT_EQ(r->mesh.materials[1].name, "bad??name");
    EXPECT_EQ(r->mesh.submeshes[0].name, "bad??name");
    EXPECT_EQ(diag.warningCount(), 1u);
}

TEST(ObjReaderTest, MtllibMayFollowUsemtl) {
    FakeFiles side;
    side.add("dir/late.mtl", "newmtl a\nKd 0 1 0\n");
    const auto r = readObj(std::string("usemtl a\n") + kSquareMtl + "f 1 2 3\nmtllib late.mtl\n", &side);
    ASSERT_TRUE(r.ok()) << r.status().message();
    ASSERT_EQ(r->mesh.submeshes.size(), 1u);
    EXPECT_EQ(r->mesh.submeshes[0].material.value, 0u);
}

TEST(ObjReaderTest, VertexColoursAreSrgbAndBecomeLinear) {
    Diagnostics diag;
    const auto r = readObj("v 0 0 0 1 0.5 0\nv 1 0 0 0 0 0\nv 0 1 0 1 1 1\nf 1 2 3\n", nullptr, &diag);
    ASSERT_TRUE(r.ok()) << r.status().message();
    ASSERT_TRUE(r->mesh.hasColors());
    EXPECT_FLOAT_EQ(r->mesh.colors[0].x, 1.0f);
    EXPECT_NEAR(r->mesh.colors[0].y, 0.21404f, 1e-4f);
    EXPECT_FLOAT_EQ(r->mesh.colors[0].w, 1.0f);
    EXPECT_EQ(diag.warningCount(), 0u);

    // 0..255 values are recognised, and a vertex without colour becomes white with a warning.
    Diagnostics diag2;
    const auto r2 = readObj("v 0 0 0 255 0 0\nv 1 0 0\nv 0 1 0 0 0 255\nf 1 2 3\n", nullptr, &diag2);
    ASSERT_TRUE(r2.ok()) << r2.status().message();
    EXPECT_FLOAT_EQ(r2->mesh.colors[0].x, 1.0f);
    EXPECT_FLOAT_EQ(r2->mesh.colors[1].y, 1.0f);
    EXPECT_FLOAT_EQ(r2->mesh.colors[2].z, 1.0f);
    EXPECT_EQ(diag2.warningCount(), 1u);
}

TEST(ObjReaderTest, HandlesContinuationCrlfCommentsAndSkippedStatements) {
    const std::string text = "# exported\r\nv 0 0 0 # origin\r\nv 1 0 \\\r\n 0\r\nv 0 1 0\r\nv 0 0 1 1.0\r\n"
                             "vp 0.5\r\nl 1 2\r\np 3\r\nl 2 3\r\nf 1 2 \\\n3\r\n";
    Diagnostics diag;
    const auto r = readObj(text, nullptr, &diag);
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->mesh.faceCount(), 1u);
    EXPECT_EQ(r->mesh.positions[1], Vec3f(1, 0, 0));
    size_t line_notes = 0;
    for (const Diagnostic& d : diag.items())
        if (d.message.find("2 line (l) and 1 point (p)") != std::string::npos) ++line_notes;
    EXPECT_EQ(line_notes, 1u);
}

TEST(ObjReaderTest, VertexOnlyFileLoadsAsPointsButEmptyFileIsAnError) {
    const auto r = readObj("v 0 0 0\nv 1 2 3\n");
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->mesh.vertexCount(), 2u);
    EXPECT_EQ(r->mesh.faceCount(), 0u);
    EXPECT_EQ(r->source.file_face_count, 0u);
    EXPECT_NE(errorOf("").find("no vertices"), std::string::npos);
    EXPECT_NE(errorOf("# only a comment\n\n").find("no vertices"), std::string::npos);
}

TEST(ObjReaderTest, RejectsHostileInputWithLineNumbers) {
    const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    EXPECT_NE(errorOf(tri + "f 0 1 2\n").find("line 4: f: vertex index 0 is invalid"), std::string::npos);
    EXPECT_NE(errorOf(tri + "f 1 2 4\n").find("line 4: f: vertex index 4 out of range (3 defined so far)"),
              std::string::npos);
    EXPECT_NE(errorOf(tri + "f 1 2 -4\n").find("vertex index -4 out of range"), std::string::npos);
    EXPECT_NE(errorOf(tri + "f 1/1 2/1 3/1\n").find("texture coordinate index 1 out of range (0 defined"),
              std::string::npos);
    EXPECT_NE(errorOf(tri + "f 1//2 2//1 3//1\nvn 0 0 1\n").find("normal index 2 out of range"), std::string::npos);
    EXPECT_NE(errorOf(tri + "f 1 2 x\n").find("expected an integer, got 'x'"), std::string::npos);
    EXPECT_NE(errorOf(tri + "f 1 2 99999999999999999999\n").find("expected an integer"), std::string::npos);
    EXPECT_NE(errorOf(tri + "f 1 2\n").find("line 4: f: expected at least 3 vertices, got 2"), std::string::npos);
    EXPECT_NE(errorOf(tri + "f 1/ 2 3\n").find("f: "), std::string::npos);
    EXPECT_NE(errorOf(tri + "f 1// 2 3\n").find("expected v, v/vt, v//vn or v/vt/vn"), std::string::npos);
    EXPECT_NE(errorOf("v 0 0 abc\n").find("line 1: v: expected a number, got 'abc'"), std::string::npos);
    EXPECT_NE(errorOf("v 0 nan 0\n").find("line 1: v: coordinate is not finite"), std::string::npos);
    EXPECT_NE(errorOf("v 0 0 inf\n").find("not finite"), std::string::npos);
    EXPECT_NE(errorOf("v 0 0 1e999\n").find("expected a number"), std::string::npos);
    EXPECT_NE(errorOf("v 0 0\n").find("expected at least 3 numbers, got 2"), std::string::npos);
    EXPECT_NE(errorOf("v 1 2 3 4 5\n").find("got 5"), std::string::npos);
    EXPECT_NE(errorOf("vn 0 0 nan\n").find("not finite"), std::string::npos);
    EXPECT_NE(
        errorOf(tri + "\x89PNG\x01\x02 junk\n").find("line 4: expected an OBJ statement, got '\\x89PNG\\x01\\x02'"),
        std::string::npos);
    EXPECT_NE(errorOf(tri + "usemtl\n").find("usemtl: expected a material name"), std::string::npos);
    EXPECT_NE(errorOf(tri + "mtllib\n").find("mtllib: expected a file name"), std::string::npos);

    std::string long_line = tri + "v";
    long_line.append(size_t(2) << 20, ' ');
    long_line += "0 0 0\n";
    EXPECT_NE(errorOf(long_line).find("line 4: longer than"), std::string::npos);

    ReadOptions small;
    small.max_polygon_vertices = 4;
    EXPECT_NE(errorOf("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 2 0\nf 1 2 3 4 5\n", nullptr, small)
                  .find("line 6: f: polygon has more than 4 vertices"),
              std::string::npos);
    small.max_vertex_count = 2;
    const Result<LoadedMesh> limited = readObj(tri, nullptr, nullptr, small);
    ASSERT_FALSE(limited.ok());
    EXPECT_EQ(limited.status().code(), StatusCode::ResourceLimit);
}

TEST(ObjReaderTest, EveryPrefixOfAFileFailsCleanlyOrLoadsConsistently) {
    FakeFiles side;
    side.add("dir/m.mtl", "newmtl a\nKd 1 0 0\n");
    const std::string text =
        "mtllib m.mtl\nv 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 1 1 0 0 0 1\nv 0 1 0 1 1 1\n"
        "vt 0 0\nvt 1 1\nvn 0 0 1\nusemtl a\nf 1/1/1 2/2/1 3/1/1 4/2/1\nf -1/-1/-1 -2/-2/-1 -3/-1/-1\n";
    for (size_t n = 0; n <= text.size(); ++n) {
        const Result<LoadedMesh> r = readObj(text.substr(0, n), &side);
        if (r.ok()) {
            EXPECT_TRUE(checkMeshConsistency(r->mesh, "prefix").ok()) << n;
        } else {
            EXPECT_EQ(r.status().message().find('\n'), std::string::npos);
        }
    }
}

TEST(ObjReaderTest, SurvivesSeededByteMutations) {
    FakeFiles side;
    side.add("dir/m.mtl", "newmtl a\nKd 1 0 0\nmap_Kd -s 1 1 1 t.png\n");
    side.files["dir/t.png"] = kPngBytes;
    const std::string base = "mtllib m.mtl\nv 0 0 0 1 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 1\nvt 0 0\nvt 1 1\n"
                             "vn 0 0 1\nusemtl a\nf 1/1/1 2/2/1 3/1/1 4/2/1 5/1/1\nf -1 -2 -3\nl 1 2\n";
    const char kAlphabet[] = "0123456789 -/.#\\\nfvtnl\r\x00\xff";
    uint64_t state = 0x9e3779b97f4a7c15ull; // fixed seed: the same mutations on every run
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
        const Result<LoadedMesh> r = readObj(text, &side);
        if (r.ok()) {
            ++loaded;
            EXPECT_TRUE(checkMeshConsistency(r->mesh, "mutated").ok()) << text;
        } else {
            EXPECT_EQ(r.status().message().find('\n'), std::string::npos) << r.status().message();
        }
    }
    EXPECT_GT(loaded, 0u); // the mutations must not all be fatal, or the check above proves nothing
}

// The shared scans, each loaded once for the suite.
class ObjSharedMeshTest : public testing::Test {
protected:
    static std::map<std::string, std::optional<LoadedMesh>>& cache() {
        static std::map<std::string, std::optional<LoadedMesh>> c;
        return c;
    }
    static double& nefertitiSeconds() {
        static double s = 0.0;
        return s;
    }
    static const LoadedMesh* load(const std::string& file) {
        auto& c = cache();
        auto it = c.find(file);
        if (it == c.end()) {
            const Result<std::vector<uint8_t>> bytes = readFileBytes(lodbake_test::sharedMesh(file));
            std::optional<LoadedMesh> value;
            if (bytes.ok()) {
                Diagnostics diag;
                const SideFileLoader loader = [](const std::string& p) { return readFileBytes(p); };
                const auto t0 = std::chrono::steady_clock::now();
                Result<LoadedMesh> r = readObjFromMemory(bytes->data(), bytes->size(), lodbake_test::sharedMesh(file),
                                                         loader, ReadOptions(), diag);
                const auto t1 = std::chrono::steady_clock::now();
                if (file == "nefertiti.obj") nefertitiSeconds() = std::chrono::duration<double>(t1 - t0).count();
                EXPECT_TRUE(r.ok()) << r.status().message();
                if (r.ok()) value = std::move(r).value();
            }
            it = c.emplace(file, std::move(value)).first;
        }
        return it->second ? &*it->second : nullptr;
    }
};

TEST_F(ObjSharedMeshTest, CountsMatchTheReadme) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    struct Expect {
        const char* file;
        uint64_t v, f;
    };
    for (const Expect& e : {Expect{"nefertiti.obj", 49971, 99938}, Expect{"rocker_arm.obj", 10044, 20088},
                            Expect{"fandisk.obj", 6475, 12946}, Expect{"spot.obj", 2930, 5856}}) {
        const LoadedMesh* m = load(e.file);
        ASSERT_NE(m, nullptr) << e.file;
        EXPECT_EQ(m->source.file_vertex_count, e.v) << e.file;
        EXPECT_EQ(m->source.file_face_count, e.f) << e.file;
        EXPECT_EQ(m->mesh.faceCount(), e.f) << e.file;
        EXPECT_EQ(m->source.face_kind, "triangles") << e.file;
        EXPECT_TRUE(checkMeshConsistency(m->mesh, e.file).ok()) << e.file;
        EXPECT_EQ(countUnreferencedVertices(m->mesh), 0u) << e.file;
    }
    // Without vt/vn the unified vertices are exactly the file's.
    EXPECT_EQ(load("nefertiti.obj")->mesh.vertexCount(), 49971u);
    EXPECT_FALSE(load("nefertiti.obj")->mesh.hasNormals());
}

TEST_F(ObjSharedMeshTest, SpotHasOneVertexPerTexcoordAndNoMaterial) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    // spot.obj references no mtllib (spot_texture.png sits beside it unreferenced), so it loads
    // without materials; every corner is v/vt and the 3,225 vt give 3,225 GPU vertices.
    const LoadedMesh* m = load("spot.obj");
    ASSERT_NE(m, nullptr);
    ASSERT_EQ(m->mesh.uvs.size(), 1u);
    EXPECT_EQ(m->mesh.vertexCount(), 3225u);
    EXPECT_TRUE(m->mesh.materials.empty());
    // The first face's first corner uses the first vt; its v is flipped to the glTF convention.
    const auto bytes = readFileBytes(lodbake_test::sharedMesh("spot.obj"));
    ASSERT_TRUE(bytes.ok());
    const std::string text(bytes->begin(), bytes->end());
    const size_t vt = text.find("\nvt ");
    const size_t f = text.find("\nf ");
    ASSERT_NE(vt, std::string::npos);
    ASSERT_NE(f, std::string::npos);
    char* end = nullptr;
    const float u = std::strtof(text.c_str() + vt + 4, &end);
    const float v = std::strtof(end, nullptr);
    const long first_vt = std::strtol(text.c_str() + text.find('/', f) + 1, nullptr, 10);
    ASSERT_EQ(first_vt, 1);
    EXPECT_EQ(m->mesh.uvs[0][m->mesh.indices[0]], Vec2f(u, 1.0f - v));
}

TEST_F(ObjSharedMeshTest, NefertitiLoadsQuickly) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    ASSERT_NE(load("nefertiti.obj"), nullptr);
    // Release target is well under 0.2 s; the bound is loose for sanitizer/Debug builds and busy CI.
    RecordProperty("nefertiti_read_seconds", std::to_string(nefertitiSeconds()));
    std::printf("nefertiti.obj read in %.3f s\n", nefertitiSeconds());
    EXPECT_LT(nefertitiSeconds(), 3.0);
}

// ---------------------------------------------------------------------------------------------------

Result<LoadedMesh> readWritten(const ObjFiles& files, const std::string& dir = "out") {
    FakeFiles side;
    if (!files.mtl_text.empty()) side.add(dir + "/" + files.mtl_name, files.mtl_text);
    for (const auto& t : files.textures) side.files[dir + "/" + t.first] = t.second;
    Diagnostics diag;
    const SideFileLoader loader = side.loader();
    return readObjFromMemory(reinterpret_cast<const uint8_t*>(files.obj_text.data()), files.obj_text.size(),
                             dir + "/x.obj", loader, ReadOptions(), diag);
}

Mesh richMesh() {
    Mesh m = lodbake_test::quad();
    m.positions.push_back({0.1f, 0.2f, 1.0f / 3.0f});
    m.indices.insert(m.indices.end(), {2, 4, 3});
    m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0.6f, 0, 0.8f}};
    m.uvs.push_back({{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0.25f, 0.75f}});
    m.colors = {{1, 0, 0, 1}, {0, 1, 0, 1}, {0, 0, 1, 1}, {0.5f, 0.5f, 0.5f, 1}, {0.01f, 0.2f, 0.9f, 1}};
    Material a;
    a.name = "painted metal";
    a.base_color_factor = {0.2f, 0.4f, 0.6f, 0.5f};
    a.alpha_mode = AlphaMode::Blend;
    a.metallic_factor = 0.3f;
    a.roughness_factor = 0.7f;
    a.emissive_factor = {0.1f, 0.0f, 0.0f};
    a.base_color_texture.texture = 0;
    a.normal_texture.texture = 1;
    a.normal_scale = 0.5f;
    Material b;
    b.name = "plain";
    b.metallic_factor = 0.0f;
    m.materials = {a, b};
    Texture t0;
    t0.mime_type = "image/png";
    t0.bytes = kPngBytes;
    Texture t1;
    t1.mime_type = "image/jpeg";
    t1.bytes = kJpegBytes;
    m.textures = {t0, t1};
    SubMesh s0;
    s0.first_index = 0;
    s0.index_count = 6;
    s0.material = MaterialId(1);
    SubMesh s1;
    s1.first_index = 6;
    s1.index_count = 3;
    s1.material = MaterialId(0);
    m.submeshes = {s0, s1};
    return m;
}

TEST(ObjWriterTest, RoundTripKeepsGeometryAttributesAndMaterials) {
    const Mesh m = richMesh();
    ASSERT_TRUE(checkMeshConsistency(m, "rich").ok());
    const ObjFiles files = writeObjToMemory(m, "x");
    EXPECT_EQ(files.mtl_name, "x.mtl");
    ASSERT_EQ(files.textures.size(), 2u);
    EXPECT_EQ(files.textures[0].first, "x_0.png");
    EXPECT_EQ(files.textures[1].first, "x_1.jpg");
    const auto r = readWritten(files);
    ASSERT_TRUE(r.ok()) << r.status().message();
    const Mesh& back = r->mesh;
    ASSERT_EQ(back.vertexCount(), m.vertexCount());
    EXPECT_EQ(back.positions, m.positions); // shortest round-trip text: exact
    EXPECT_EQ(back.indices, m.indices);
    ASSERT_EQ(back.uvs.size(), 1u);
    ASSERT_TRUE(back.hasNormals());
    ASSERT_TRUE(back.hasColors());
    for (size_t i = 0; i < m.vertexCount(); ++i) {
        EXPECT_NEAR(back.uvs[0][i].x, m.uvs[0][i].x, 1e-6f);
        EXPECT_NEAR(back.uvs[0][i].y, m.uvs[0][i].y, 1e-6f);
        EXPECT_NEAR(back.normals[i].x, m.normals[i].x, 1e-6f);
        EXPECT_NEAR(back.normals[i].z, m.normals[i].z, 1e-6f);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(back.colors[i][c], m.colors[i][c], 1e-5f) << i << " " << c;
    }
    ASSERT_EQ(back.submeshes.size(), 2u);
    EXPECT_EQ(back.submeshes[0].index_count, 6u);
    EXPECT_EQ(back.materials[back.submeshes[0].material.value].name, "plain");
    const Material& a = back.materials[back.submeshes[1].material.value];
    EXPECT_EQ(a.name, "painted metal");
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a.base_color_factor[c], m.materials[0].base_color_factor[c], 1e-5f);
    EXPECT_FLOAT_EQ(a.base_color_factor.w, 0.5f);
    EXPECT_EQ(a.alpha_mode, AlphaMode::Blend);
    EXPECT_FLOAT_EQ(a.metallic_factor, 0.3f);
    EXPECT_FLOAT_EQ(a.roughness_factor, 0.7f);
    EXPECT_NEAR(a.emissive_factor.x, 0.1f, 1e-5f);
    EXPECT_FLOAT_EQ(a.normal_scale, 0.5f);
    ASSERT_TRUE(a.base_color_texture.isSet());
    EXPECT_EQ(back.textures[size_t(a.base_color_texture.texture)].bytes, kPngBytes);
    EXPECT_EQ(back.textures[size_t(a.normal_texture.texture)].mime_type, "image/jpeg");
}

TEST(ObjWriterTest, OutputIsDeterministicAndMinimalForPlainMeshes) {
    const Mesh m = richMesh();
    const ObjFiles a = writeObjToMemory(m, "x");
    const ObjFiles b = writeObjToMemory(m, "x");
    EXPECT_EQ(a.obj_text, b.obj_text);
    EXPECT_EQ(a.mtl_text, b.mtl_text);

    const ObjFiles plain = writeObjToMemory(lodbake_test::tetrahedron(), "t");
    EXPECT_TRUE(plain.mtl_text.empty());
    EXPECT_TRUE(plain.textures.empty());
    EXPECT_EQ(plain.obj_text, "# lodbake OBJ\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                              "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    const auto r = readWritten(plain);
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->mesh.positions, lodbake_test::tetrahedron().positions);
    EXPECT_EQ(r->mesh.indices, lodbake_test::tetrahedron().indices);
}

TEST(ObjWriterTest, SubMeshWithoutMaterialGetsAStandIn) {
    Mesh m = richMesh();
    m.submeshes[0].material = MaterialId::invalid();
    const auto r = readWritten(writeObjToMemory(m, "x"));
    ASSERT_TRUE(r.ok()) << r.status().message();
    ASSERT_EQ(r->mesh.submeshes.size(), 2u);
    EXPECT_EQ(r->mesh.materials[r->mesh.submeshes[0].material.value].name, "lodbake_default");
    EXPECT_EQ(r->mesh.materials[r->mesh.submeshes[1].material.value].name, "painted metal");
}

TEST(ObjWriterTest, SharedScanRoundTripsExactly) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    const auto bytes = readFileBytes(lodbake_test::sharedMesh("spot.obj"));
    ASSERT_TRUE(bytes.ok());
    Diagnostics diag;
    const SideFileLoader loader = [](const std::string& p) { return readFileBytes(p); };
    const auto first = readObjFromMemory(bytes->data(), bytes->size(), "spot.obj", loader, ReadOptions(), diag);
    ASSERT_TRUE(first.ok()) << first.status().message();
    const ObjFiles files = writeObjToMemory(first->mesh, "spot");
    const auto second = readWritten(files);
    ASSERT_TRUE(second.ok()) << second.status().message();
    EXPECT_EQ(second->mesh.positions, first->mesh.positions);
    EXPECT_EQ(second->mesh.indices, first->mesh.indices);
    // Rewriting what was read back gives the same text.
    EXPECT_EQ(writeObjToMemory(second->mesh, "spot").obj_text, files.obj_text);
}

} // namespace
