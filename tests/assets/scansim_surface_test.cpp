// lodbake_scansim's surface mode (writeSurfacePly): the grid it promises, a closed outward-facing
// torus, the same bytes for the same seed, the same mesh in every encoding, and no file left behind
// when writing fails.

#include <csignal>
#include <filesystem>
#include <map>
#include <string>
#include <utility>

#include <sys/resource.h>

#include <gtest/gtest.h>

#include "lodbake/core/file_io.h"
#include "lodbake/io/mesh_io.h"
#include "scansim.h"
#include "test_paths.h"

namespace fs = std::filesystem;
using namespace lodbake::scansim;

namespace {

std::string freshDir(const std::string& name) {
    const std::string dir = lodbake_test::scratchDir() + "/" + name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

lodbake::LoadedMesh readBack(const std::string& path) {
    lodbake::Diagnostics d;
    lodbake::Result<lodbake::LoadedMesh> m = lodbake::readMesh(path, lodbake::ReadOptions(), d);
    EXPECT_TRUE(m.ok()) << m.status().message();
    return m.ok() ? std::move(m).value() : lodbake::LoadedMesh();
}

} // namespace

TEST(ScanSimSurfaceTest, WritesTheClosedOutwardTorusItPromises) {
    const std::string dir = freshDir("surface_closed");
    SurfaceOptions o;
    o.triangles = 3000;
    lodbake::Result<SurfaceStats> stats = writeSurfacePly(o, dir + "/s.ply");
    ASSERT_TRUE(stats.ok()) << stats.status().message();
    EXPECT_EQ(stats->triangles, 2 * stats->rows * stats->cols);
    EXPECT_NEAR(double(stats->triangles), 3000.0, 300.0);
    EXPECT_EQ(stats->bytes, fs::file_size(dir + "/s.ply"));
    const lodbake::LoadedMesh m = readBack(dir + "/s.ply");
    ASSERT_EQ(m.mesh.vertexCount(), stats->vertices);
    ASSERT_EQ(m.mesh.faceCount(), stats->triangles);
    // Closed and consistently oriented: every directed edge once, and its reverse once.
    std::map<std::pair<uint32_t, uint32_t>, int> directed;
    for (size_t t = 0; t < m.mesh.faceCount(); ++t)
        for (int k = 0; k < 3; ++k) ++directed[{m.mesh.indices[3 * t + k], m.mesh.indices[3 * t + (k + 1) % 3]}];
    for (const auto& [edge, count] : directed) {
        ASSERT_EQ(count, 1);
        ASSERT_EQ(directed.count({edge.second, edge.first}), 1u);
    }
    // Facing outwards: positive signed volume, close to the torus's 2 pi^2 R r^2.
    double volume = 0;
    for (size_t t = 0; t < m.mesh.faceCount(); ++t) {
        const lodbake::Vec3d a = lodbake::toDouble(m.mesh.positions[m.mesh.indices[3 * t]]);
        const lodbake::Vec3d b = lodbake::toDouble(m.mesh.positions[m.mesh.indices[3 * t + 1]]);
        const lodbake::Vec3d c = lodbake::toDouble(m.mesh.positions[m.mesh.indices[3 * t + 2]]);
        volume += lodbake::dot(a, lodbake::cross(b, c)) / 6.0;
    }
    const double torus = 2.0 * 3.14159265358979 * 3.14159265358979 * o.major_radius * o.minor_radius * o.minor_radius;
    EXPECT_GT(volume, 0.8 * torus);
    EXPECT_LT(volume, 1.2 * torus);
}

TEST(ScanSimSurfaceTest, SameSeedSameBytesOtherSeedOtherRelief) {
    const std::string dir = freshDir("surface_seed");
    SurfaceOptions o;
    o.triangles = 2000;
    ASSERT_TRUE(writeSurfacePly(o, dir + "/a.ply").ok());
    ASSERT_TRUE(writeSurfacePly(o, dir + "/b.ply").ok());
    o.seed = 2;
    ASSERT_TRUE(writeSurfacePly(o, dir + "/c.ply").ok());
    const auto a = lodbake::readFileBytes(dir + "/a.ply"), b = lodbake::readFileBytes(dir + "/b.ply");
    const auto c = lodbake::readFileBytes(dir + "/c.ply");
    ASSERT_TRUE(a.ok() && b.ok() && c.ok());
    EXPECT_EQ(*a, *b);
    EXPECT_EQ(a->size(), c->size());
    EXPECT_NE(*a, *c);
}

TEST(ScanSimSurfaceTest, EveryEncodingHoldsTheSameMesh) {
    const std::string dir = freshDir("surface_encodings");
    SurfaceOptions o;
    o.triangles = 1000;
    ASSERT_TRUE(writeSurfacePly(o, dir + "/le.ply").ok());
    o.encoding = SurfaceOptions::Encoding::BinaryBigEndian;
    ASSERT_TRUE(writeSurfacePly(o, dir + "/be.ply").ok());
    o.encoding = SurfaceOptions::Encoding::Ascii;
    ASSERT_TRUE(writeSurfacePly(o, dir + "/ascii.ply").ok());
    const lodbake::LoadedMesh le = readBack(dir + "/le.ply");
    for (const char* other : {"/be.ply", "/ascii.ply"}) {
        const lodbake::LoadedMesh m = readBack(dir + other);
        EXPECT_EQ(m.mesh.positions, le.mesh.positions) << other;
        EXPECT_EQ(m.mesh.indices, le.mesh.indices) << other;
    }
}

TEST(ScanSimSurfaceTest, BadOptionsAndFailedWritesLeaveNoFile) {
    const std::string dir = freshDir("surface_errors");
    SurfaceOptions o;
    o.triangles = 17;
    lodbake::Result<SurfaceStats> small = writeSurfacePly(o, dir + "/small.ply");
    ASSERT_FALSE(small.ok());
    EXPECT_NE(small.status().message().find("triangles"), std::string::npos) << small.status().message();
    o.triangles = 2000;
    lodbake::Result<SurfaceStats> missing = writeSurfacePly(o, dir + "/no/such/folder/s.ply");
    ASSERT_FALSE(missing.ok());
    EXPECT_NE(missing.status().message().find(dir + "/no/such/folder/s.ply"), std::string::npos);
    // A full disk, simulated by a file size limit (writes beyond it fail with EFBIG).
    std::signal(SIGXFSZ, SIG_IGN);
    rlimit old{};
    ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old), 0);
    rlimit low = old;
    low.rlim_cur = 8192;
    ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &low), 0);
    lodbake::Result<SurfaceStats> full = writeSurfacePly(o, dir + "/full.ply");
    setrlimit(RLIMIT_FSIZE, &old);
    ASSERT_FALSE(full.ok());
    EXPECT_EQ(full.status().code(), lodbake::StatusCode::IoError);
    EXPECT_NE(full.status().message().find(dir + "/full.ply: write failed"), std::string::npos)
        << full.status().message();
    EXPECT_TRUE(fs::is_empty(dir)) << "a failed write left a file behind";
}
