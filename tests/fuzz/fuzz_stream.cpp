// libFuzzer target for the streaming PLY and OBJ readers (lodbake/io/mesh_stream.h): the format
// follows the content ("ply" magic, else OBJ), the window is tiny so that every record and line
// crosses window boundaries, and both passes run. Build with -DLODBAKE_BUILD_FUZZERS=ON and Clang;
// run with scripts/fuzz.sh stream SECONDS.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include "lodbake/io/mesh_stream.h"

namespace {

void checkError(const lodbake::Status& s) {
    const std::string& m = s.message();
    if (m.rfind("fuzz", 0) != 0 || m.find('\n') != std::string::npos) __builtin_trap();
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const bool ply = size >= 3 && std::memcmp(data, "ply", 3) == 0;
    lodbake::StreamReadOptions options;
    options.buffer_bytes = 64;
    options.max_record_bytes = 1 << 16;
    options.vertex_chunk = 7;
    options.triangle_chunk = 5;
    options.max_polygon_vertices = 256;
    lodbake::Diagnostics diagnostics;
    auto reader = lodbake::openMeshStreamFromMemory(data, size, ply ? "fuzz.ply" : "fuzz.obj",
                                                    ply ? lodbake::MeshFormat::Ply : lodbake::MeshFormat::Obj, options,
                                                    diagnostics);
    if (!reader.ok()) {
        checkError(reader.status());
        return 0;
    }
    uint64_t vertices = 0;
    lodbake::Status s = (*reader)->forEachVertexChunk([&](uint64_t first, const lodbake::Vec3f*, size_t n) {
        if (first != vertices || n == 0 || n > options.vertex_chunk) __builtin_trap();
        vertices += n;
        return lodbake::Status();
    });
    if (!s.ok()) {
        checkError(s);
        return 0;
    }
    if (vertices != (*reader)->info().vertex_count) __builtin_trap();
    s = (*reader)->forEachTriangleChunk([&](uint64_t, const uint32_t* corners, size_t n) {
        if (n == 0 || n > options.triangle_chunk) __builtin_trap();
        for (size_t i = 0; i < 3 * n; ++i)
            if (corners[i] >= vertices) __builtin_trap();
        return lodbake::Status();
    });
    if (!s.ok()) checkError(s);
    return 0;
}
