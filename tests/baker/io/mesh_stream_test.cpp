// The streaming readers (lodbake/io/mesh_stream.h): the same positions and triangles as readMesh()
// for triangle meshes in every encoding and at any window size, bounded chunks, fans for polygons,
// and one-line errors naming the file and element for truncated, corrupted and unsupported input.

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "lodbake/core/file_io.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/io/mesh_stream.h"
#include "scansim.h"
#include "test_paths.h"

namespace fs = std::filesystem;
using lodbake::MeshFormat;
using lodbake::Status;
using lodbake::StreamReadOptions;
using lodbake::Vec3f;

namespace {

struct Streamed {
    std::vector<Vec3f> positions;
    std::vector<uint32_t> indices;
    size_t largest_vertex_chunk = 0, largest_triangle_chunk = 0;
    Status status;
};

Streamed streamBytes(const std::vector<uint8_t>& bytes, MeshFormat format, const StreamReadOptions& options,
                     const std::string& name = "mem") {
    Streamed s;
    lodbake::Diagnostics d;
    auto reader = lodbake::openMeshStreamFromMemory(bytes.data(), bytes.size(), name, format, options, d);
    if (!reader.ok()) {
        s.status = reader.status();
        return s;
    }
    s.status = (*reader)->forEachVertexChunk([&](uint64_t first, const Vec3f* p, size_t n) {
        EXPECT_EQ(first, s.positions.size());
        s.largest_vertex_chunk = std::max(s.largest_vertex_chunk, n);
        s.positions.insert(s.positions.end(), p, p + n);
        return Status();
    });
    if (!s.status.ok()) return s;
    s.status = (*reader)->forEachTriangleChunk([&](uint64_t first, const uint32_t* c, size_t n) {
        EXPECT_EQ(first * 3, s.indices.size());
        s.largest_triangle_chunk = std::max(s.largest_triangle_chunk, n);
        s.indices.insert(s.indices.end(), c, c + 3 * n);
        return Status();
    });
    return s;
}

std::vector<uint8_t> bytesOf(const std::string& text) { return std::vector<uint8_t>(text.begin(), text.end()); }

std::string scratch(const std::string& name) {
    const std::string dir = lodbake_test::scratchDir() + "/mesh_stream";
    fs::create_directories(dir);
    return dir + "/" + name;
}

// A generated scan in one encoding, with readMesh's view of it.
std::vector<uint8_t> surfaceBytes(lodbake::scansim::SurfaceOptions::Encoding e, lodbake::LoadedMesh* loaded) {
    lodbake::scansim::SurfaceOptions o;
    o.triangles = 1200;
    o.encoding = e;
    const std::string path = scratch("surface_" + std::to_string(int(e)) + ".ply");
    EXPECT_TRUE(lodbake::scansim::writeSurfacePly(o, path).ok());
    lodbake::Diagnostics d;
    auto m = lodbake::readMesh(path, lodbake::ReadOptions(), d);
    EXPECT_TRUE(m.ok()) << m.status().message();
    if (m.ok() && loaded) *loaded = std::move(m).value();
    auto bytes = lodbake::readFileBytes(path);
    return bytes.ok() ? *bytes : std::vector<uint8_t>();
}

StreamReadOptions tinyWindow(size_t window, size_t chunk) {
    StreamReadOptions o;
    o.buffer_bytes = window;
    o.max_record_bytes = 1 << 16;
    o.vertex_chunk = chunk;
    o.triangle_chunk = chunk;
    return o;
}

} // namespace

TEST(MeshStreamTest, PlyEncodingsMatchReadMeshAtAnyWindow) {
    using E = lodbake::scansim::SurfaceOptions::Encoding;
    for (E e : {E::BinaryLittleEndian, E::BinaryBigEndian, E::Ascii}) {
        lodbake::LoadedMesh loaded;
        const std::vector<uint8_t> bytes = surfaceBytes(e, &loaded);
        for (size_t window : {size_t(64), size_t(1000), size_t(1) << 20}) {
            const Streamed s = streamBytes(bytes, MeshFormat::Ply, tinyWindow(window, 100));
            ASSERT_TRUE(s.status.ok()) << s.status.message();
            EXPECT_EQ(s.positions, loaded.mesh.positions) << "encoding " << int(e) << " window " << window;
            EXPECT_EQ(s.indices, loaded.mesh.indices) << "encoding " << int(e) << " window " << window;
            EXPECT_LE(s.largest_vertex_chunk, 100u);
            EXPECT_LE(s.largest_triangle_chunk, 100u);
        }
    }
}

TEST(MeshStreamTest, ObjMatchesReadMeshAndTheFileReaderMatchesMemory) {
    lodbake::LoadedMesh loaded;
    surfaceBytes(lodbake::scansim::SurfaceOptions::Encoding::BinaryLittleEndian, &loaded);
    const std::string obj = scratch("surface.obj");
    lodbake::Diagnostics d;
    ASSERT_TRUE(lodbake::writeMesh(loaded.mesh, obj, lodbake::WriteOptions(), d).ok());
    auto bytes = lodbake::readFileBytes(obj);
    ASSERT_TRUE(bytes.ok());
    for (size_t window : {size_t(64), size_t(4096)}) {
        const Streamed s = streamBytes(*bytes, MeshFormat::Obj, tinyWindow(window, 77));
        ASSERT_TRUE(s.status.ok()) << s.status.message();
        EXPECT_EQ(s.positions, loaded.mesh.positions);
        EXPECT_EQ(s.indices, loaded.mesh.indices);
    }
    // The file reader (pread windows) gives the same.
    auto reader = lodbake::openMeshStream(obj, tinyWindow(128, 50), d);
    ASSERT_TRUE(reader.ok()) << reader.status().message();
    size_t vertices = 0, triangles = 0;
    ASSERT_TRUE((*reader)->forEachVertexChunk([&](uint64_t, const Vec3f*, size_t n) {
        vertices += n;
        return Status();
    }).ok());
    ASSERT_TRUE((*reader)->forEachTriangleChunk([&](uint64_t, const uint32_t*, size_t n) {
        triangles += n;
        return Status();
    }).ok());
    EXPECT_EQ(vertices, loaded.mesh.vertexCount());
    EXPECT_EQ(triangles, loaded.mesh.faceCount());
    EXPECT_EQ((*reader)->info().vertex_count, vertices);
    EXPECT_EQ((*reader)->info().triangle_estimate, triangles);
}

TEST(MeshStreamTest, PolygonsBecomeFansAndObjSyntaxIsTheInMemoryReaders) {
    // Quad and pentagon, negative and v/vt/vn corners, a continued line and comments.
    const std::string obj = "# c\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0 # four\nv -1 0.5 0\nvt 0 0\nvn 0 0 1\n"
                            "f 1/1/1 2/1/1 3/1/1 4/1/1\nf -5 -4 \\\n -3 -2 -1\n";
    const Streamed s = streamBytes(bytesOf(obj), MeshFormat::Obj, tinyWindow(64, 2));
    ASSERT_TRUE(s.status.ok()) << s.status.message();
    EXPECT_EQ(s.positions.size(), 5u);
    EXPECT_EQ(s.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 0, 1, 2, 0, 2, 3, 0, 3, 4}));
    const std::string ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                            "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
                            "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n2 0 1\n";
    const Streamed p = streamBytes(bytesOf(ply), MeshFormat::Ply, tinyWindow(64, 8));
    ASSERT_TRUE(p.status.ok()) << p.status.message();
    EXPECT_EQ(p.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3})); // the 2-corner face is dropped
}

TEST(MeshStreamTest, EveryTruncationIsAOneLineErrorNamingTheFile) {
    using E = lodbake::scansim::SurfaceOptions::Encoding;
    for (E e : {E::BinaryLittleEndian, E::Ascii}) {
        const std::vector<uint8_t> bytes = surfaceBytes(e, nullptr);
        // Every cut loses at least one value the header's counts promise (the last byte, an ascii
        // line break, is not cut).
        size_t failures = 0, cuts = 0;
        for (size_t cut = 0; cut + 1 < bytes.size(); cut += 97) {
            ++cuts;
            const std::vector<uint8_t> part(bytes.begin(), bytes.begin() + std::ptrdiff_t(cut));
            const Streamed s = streamBytes(part, MeshFormat::Ply, tinyWindow(256, 64), "cut.ply");
            if (s.status.ok()) continue;
            ++failures;
            const std::string& m = s.status.message();
            EXPECT_EQ(m.rfind("cut.ply: ", 0), 0u) << m;
            EXPECT_EQ(m.find('\n'), std::string::npos) << m;
        }
        EXPECT_EQ(failures, cuts) << "every truncated file must fail";
    }
}

TEST(MeshStreamTest, CorruptionsNameTheElementAndWhatWasExpected) {
    const std::string head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                             "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    struct Case {
        std::string body, expected;
    };
    const Case cases[] = {
        {"0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "bad.ply: face 0: vertex index 7 out of range (3 vertices)"},
        {"0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n", "bad.ply: vertex 1: coordinate is not finite"},
        {"0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n", "bad.ply: vertex 1 property 'y': expected a number, got 'x'"},
        {"0 0 0\n1 0 0\n0 1 0\n3 0 1.5 2\n", "bad.ply: face 0 property 'vertex_indices': expected an integer"},
        {"0 0 0\n1 0 0\n0 1 0\n3 0 1\n", "bad.ply: face 0 property 'vertex_indices': file ends early"},
    };
    for (const Case& c : cases) {
        const Streamed s = streamBytes(bytesOf(head + c.body), MeshFormat::Ply, tinyWindow(64, 8), "bad.ply");
        ASSERT_FALSE(s.status.ok()) << c.expected;
        EXPECT_NE(s.status.message().find(c.expected), std::string::npos) << s.status.message();
    }
    const Streamed strips = streamBytes(
        bytesOf("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                "element tristrips 1\nproperty list int int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
        MeshFormat::Ply, tinyWindow(64, 8), "strips.ply");
    EXPECT_EQ(strips.status.code(), lodbake::StatusCode::Unsupported) << strips.status.message();
    // One record longer than the window may grow to.
    StreamReadOptions small = tinyWindow(64, 8);
    small.max_record_bytes = 128;
    const Streamed wide = streamBytes(bytesOf(head + "0 0 0\n1 0 0\n" + std::string(300, '0') + " 1 0\n3 0 1 2\n"),
                                      MeshFormat::Ply, small, "wide.ply");
    ASSERT_FALSE(wide.status.ok());
    EXPECT_NE(wide.status.message().find("wide.ply: vertex 2: record longer than 128 bytes"), std::string::npos)
        << wide.status.message();
    const Streamed obj = streamBytes(bytesOf("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"), MeshFormat::Obj,
                                     tinyWindow(64, 8), "bad.obj");
    EXPECT_EQ(obj.status.message(), "bad.obj: line 4: f: vertex index 4 out of range (3 defined so far)");
}

TEST(MeshStreamTest, MalformedCorpusFailsCleanly) {
    // The in-memory readers' malformed corpus: the stream either refuses a file with one line naming
    // it, or (for files whose fault is in what the stream does not read: materials, range grids of
    // the wrong size are refused as unsupported) reads it.
    for (const char* format : {"ply", "obj"}) {
        const fs::path dir = fs::path(lodbake_test::sourceDir()) / "tests/malformed" / format;
        size_t refused = 0, files = 0;
        for (const auto& entry : fs::directory_iterator(dir)) {
            if (entry.path().extension() != std::string(".") + format) continue;
            ++files;
            auto bytes = lodbake::readFileBytes(entry.path().string());
            ASSERT_TRUE(bytes.ok());
            const std::string name = entry.path().filename().string();
            const Streamed s = streamBytes(*bytes, format == std::string("ply") ? MeshFormat::Ply : MeshFormat::Obj,
                                           tinyWindow(64, 16), name);
            if (s.status.ok()) continue;
            ++refused;
            EXPECT_EQ(s.status.message().rfind(name + ": ", 0), 0u) << s.status.message();
            EXPECT_EQ(s.status.message().find('\n'), std::string::npos) << s.status.message();
        }
        EXPECT_GT(files, 10u);
        EXPECT_GT(refused, files / 2) << format;
    }
}

TEST(MeshStreamTest, FuzzSeedsStreamCompletely) {
    // The stream fuzz target's seeds (tests/fuzz/seeds/stream): every one is a valid file.
    const fs::path dir = fs::path(lodbake_test::sourceDir()) / "tests/fuzz/seeds/stream";
    size_t files = 0;
    for (const auto& entry : fs::directory_iterator(dir)) {
        ++files;
        auto bytes = lodbake::readFileBytes(entry.path().string());
        ASSERT_TRUE(bytes.ok());
        const bool ply = entry.path().extension() == ".ply";
        const Streamed s = streamBytes(*bytes, ply ? MeshFormat::Ply : MeshFormat::Obj, tinyWindow(64, 5));
        EXPECT_TRUE(s.status.ok()) << entry.path() << ": " << s.status.message();
        if (entry.path().filename() == "faces_first.ply") {
            EXPECT_EQ(s.positions.size(), 4u);
            EXPECT_EQ(s.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 0, 2, 3}));
        }
    }
    EXPECT_EQ(files, 6u);
}
