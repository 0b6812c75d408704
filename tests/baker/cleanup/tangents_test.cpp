// MikkTSpace tangents against analytic frames: a UV-mapped plane (and its mirror image), a cylinder
// with a UV seam, and a plane mirrored in UV along a shared row of vertices (which must be split).
// glTF's rule: bitangent = cross(normal, tangent.xyz) * tangent.w points up the image (towards -v).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "lodbake/cleanup/tangents.h"
#include "lodbake/io/mesh_io.h"
#include "test_paths.h"

namespace {

using namespace lodbake;

constexpr double kPi = 3.14159265358979323846;

// An n x n grid over (s, t) in [0, 1]^2: position(s, t), normal(s, t) and uv(s, t) per vertex,
// counter-clockwise triangles seen from the normal's side.
Mesh grid(int n, const std::function<Vec3f(double, double)>& position, const std::function<Vec3f(double, double)>& normal,
          const std::function<Vec2f(double, double)>& uv) {
    Mesh m;
    m.uvs.resize(1);
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            const double s = double(i) / n, t = double(j) / n;
            m.positions.push_back(position(s, t));
            m.normals.push_back(normal(s, t));
            m.uvs[0].push_back(uv(s, t));
        }
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const uint32_t a = uint32_t(j * (n + 1) + i), b = a + 1, c = a + uint32_t(n + 1), d = c + 1;
            m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
        }
    return m;
}

Vec3d v3(const Vec4f& t) {
    return {double(t.x), double(t.y), double(t.z)};
}

double angleDeg(const Vec3d& a, const Vec3d& b) {
    const double c = dot(a, b) / (length(a) * length(b));
    return std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / kPi;
}

// Every vertex's tangent is unit length, within `tolerance_deg` of expected_t(vertex) and has the
// handedness whose bitangent points along expected_up(vertex) (up the image).
void expectFrames(const Mesh& m, const std::function<Vec3d(uint32_t)>& expected_t,
                  const std::function<Vec3d(uint32_t)>& expected_up, double tolerance_deg) {
    ASSERT_EQ(m.tangents.size(), m.vertexCount());
    for (uint32_t v = 0; v < m.vertexCount(); ++v) {
        const Vec4f& t = m.tangents[v];
        ASSERT_NEAR(length(v3(t)), 1.0, 1e-5) << "vertex " << v;
        ASSERT_TRUE(t.w == 1.0f || t.w == -1.0f) << "vertex " << v << " w " << t.w;
        EXPECT_LT(angleDeg(v3(t), expected_t(v)), tolerance_deg) << "vertex " << v;
        const Vec3d bitangent = cross(Vec3d(m.normals[v]), v3(t)) * double(t.w);
        EXPECT_GT(dot(bitangent, expected_up(v)), 0.9 * length(expected_up(v))) << "vertex " << v;
    }
}

TEST(TangentsTest, PlaneTangentFollowsUAndBitangentPointsUpTheImage) {
    // u along +x, v down the image = towards -y: the image's up is +y.
    Mesh m = grid(
        4, [](double s, double t) { return Vec3f(float(s), float(t), 0); },
        [](double, double) { return Vec3f(0, 0, 1); }, [](double s, double t) { return Vec2f(float(s), float(1 - t)); });
    const auto r = generateTangents(m, 0, "plane");
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->vertices_added, 0u);
    EXPECT_EQ(r->corners_without_uv_frame, 0u);
    expectFrames(m, [](uint32_t) { return Vec3d(1, 0, 0); }, [](uint32_t) { return Vec3d(0, 1, 0); }, 1e-3);
    for (const Vec4f& t : m.tangents) EXPECT_EQ(t.w, 1.0f);
}

TEST(TangentsTest, MirroredUvsFlipTangentAndHandedness) {
    // u runs along -x: tangent -x, and the image's up is still +y, so the frame is left-handed.
    Mesh m = grid(
        4, [](double s, double t) { return Vec3f(float(s), float(t), 0); },
        [](double, double) { return Vec3f(0, 0, 1); },
        [](double s, double t) { return Vec2f(float(1 - s), float(1 - t)); });
    ASSERT_TRUE(generateTangents(m, 0, "mirrored").ok());
    expectFrames(m, [](uint32_t) { return Vec3d(-1, 0, 0); }, [](uint32_t) { return Vec3d(0, 1, 0); }, 1e-3);
    for (const Vec4f& t : m.tangents) EXPECT_EQ(t.w, -1.0f);
}

// A cylinder of radius 1 around +y, u = angle / 2 pi, image up = +y. Its seam (u = 0 and u = 1) has
// separate vertices, so no vertex is split; the tangent is the direction of increasing angle.
TEST(TangentsTest, CylinderTangentsAreTheAngularDirection) {
    const int n = 32;
    auto angle = [](double s) { return 2 * kPi * s; };
    Mesh m = grid(
        n, [&](double s, double t) { return Vec3f(float(std::sin(angle(s))), float(t), float(std::cos(angle(s)))); },
        [&](double s, double) { return Vec3f(float(std::sin(angle(s))), 0, float(std::cos(angle(s)))); },
        [](double s, double t) { return Vec2f(float(s), float(1 - t)); });
    const auto r = generateTangents(m, 0, "cylinder");
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->vertices_added, 0u);
    // d(position)/d(angle) = (cos a, 0, -sin a); the mean of the neighbouring faces' chords is within
    // half a segment's angle of it.
    expectFrames(
        m,
        [&](uint32_t v) {
            const Vec3f& p = m.positions[v];
            return Vec3d(double(p.z), 0, -double(p.x));
        },
        [](uint32_t) { return Vec3d(0, 1, 0); }, 180.0 / n + 1e-3);
}

// u = |x| mirrors the texture at x = 0, where the left and right halves share vertices: those get one
// frame per side (split), each matching its own half.
TEST(TangentsTest, VerticesOnAUvMirrorAreSplitIntoBothFrames) {
    const int n = 4;
    Mesh m = grid(
        n, [](double s, double t) { return Vec3f(float(2 * s - 1), float(t), 0); },
        [](double, double) { return Vec3f(0, 0, 1); },
        [](double s, double t) { return Vec2f(float(std::fabs(2 * s - 1)), float(1 - t)); });
    const size_t before = m.vertexCount();
    const auto r = generateTangents(m, 0, "mirror");
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->vertices_added, uint64_t(n + 1)); // the column x = 0
    EXPECT_EQ(m.vertexCount(), before + size_t(n + 1));
    // Each triangle's corners carry its own half's frame.
    for (size_t c = 0; c < m.indices.size(); ++c) {
        const size_t f = c / 3;
        const double cx = (m.positions[m.indices[f * 3]].x + m.positions[m.indices[f * 3 + 1]].x +
                           m.positions[m.indices[f * 3 + 2]].x) / 3.0;
        const Vec4f& t = m.tangents[m.indices[c]];
        EXPECT_EQ(t.x > 0 ? 1 : -1, cx > 0 ? 1 : -1) << "corner " << c;
        EXPECT_EQ(t.w, cx > 0 ? 1.0f : -1.0f) << "corner " << c;
    }
}

TEST(TangentsTest, NeedsNormalsAndTheUvSetAndIsChosenByTheNormalMap) {
    Mesh m = grid(
        1, [](double s, double t) { return Vec3f(float(s), float(t), 0); },
        [](double, double) { return Vec3f(0, 0, 1); }, [](double s, double t) { return Vec2f(float(s), float(t)); });
    EXPECT_EQ(tangentUvSet(m), -1); // no material with a normal map
    m.materials.resize(1);
    m.materials[0].normal_texture.texture = 0;
    m.textures.resize(1);
    m.submeshes.push_back({"all", 0, uint32_t(m.indices.size()), MaterialId(0)});
    EXPECT_EQ(tangentUvSet(m), 0);
    m.materials[0].normal_texture.texcoord = 1;
    EXPECT_EQ(tangentUvSet(m), -1); // no such UV set
    EXPECT_FALSE(generateTangents(m, 1, "quad").ok());
    Mesh no_normals = m;
    no_normals.normals.clear();
    const auto r = generateTangents(no_normals, 0, "quad");
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.status().message().find("quad: tangents: expected vertex normals"), std::string::npos);
}

// The shared textured Nefertiti ships the TANGENT its exporter computed with MikkTSpace: ours, from
// its positions, normals and UVs alone, must agree corner by corner.
TEST(TangentsTest, AgreeWithTheTangentsAnExporterShipped) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    Diagnostics diagnostics;
    auto read = readMesh(lodbake_test::sharedMesh("nefertiti_fraunhofer_textured.glb"), ReadOptions{}, diagnostics);
    ASSERT_TRUE(read.ok()) << read.status().message();
    Mesh m = std::move(read->mesh);
    const std::vector<Vec4f> shipped = m.tangents;
    ASSERT_EQ(shipped.size(), m.vertexCount());
    const size_t original_vertices = m.vertexCount();
    m.tangents.clear();
    const auto r = generateTangents(m, 0, "nefertiti");
    ASSERT_TRUE(r.ok()) << r.status().message();
    // Split copies keep their original's data: compare each corner with its original vertex.
    std::vector<uint32_t> original(m.vertexCount());
    for (uint32_t v = 0; v < original_vertices; ++v) original[v] = v;
    for (uint32_t v = uint32_t(original_vertices); v < m.vertexCount(); ++v)
        for (uint32_t o = 0; o < original_vertices; ++o)
            if (m.positions[o] == m.positions[v] && m.normals[o] == m.normals[v] && m.uvs[0][o] == m.uvs[0][v]) {
                original[v] = o;
                break;
            }
    std::vector<double> angles;
    size_t same_handedness = 0;
    for (uint32_t v : m.indices) {
        const Vec4f& ours = m.tangents[v];
        const Vec4f& theirs = shipped[original[v]];
        same_handedness += (ours.w > 0) == (theirs.w > 0);
        angles.push_back(angleDeg(v3(ours), v3(theirs)));
    }
    std::sort(angles.begin(), angles.end());
    EXPECT_EQ(same_handedness, angles.size());
    EXPECT_LT(angles[angles.size() / 2], 0.25) << "median angle, degrees";
    EXPECT_LT(angles[angles.size() * 95 / 100], 1.5) << "95th percentile angle, degrees";
}

} // namespace
