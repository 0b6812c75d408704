#pragma once
// Shared by the baker reader fuzz targets: small limits so that huge claimed counts hit the refusal
// paths instead of exhausting the fuzzer's memory, and the checks every reader result must pass.
#include <string>

#include "lodbake/core/mesh.h"
#include "lodbake/io/mesh_io.h"

namespace lodbake_fuzz {

inline lodbake::ReadOptions smallLimits() {
    lodbake::ReadOptions options;
    options.max_vertex_count = 1u << 20;
    options.max_face_count = 1u << 20;
    options.max_polygon_vertices = 256;
    options.load_textures = true;
    return options;
}

// A reader either fails with a one-line message naming the input, or returns a consistent mesh.
inline void checkLoaded(const lodbake::Result<lodbake::LoadedMesh>& result) {
    if (!result.ok()) {
        const std::string& m = result.status().message();
        if (m.rfind("fuzz", 0) != 0 || m.find('\n') != std::string::npos) __builtin_trap();
        return;
    }
    if (!lodbake::checkMeshConsistency(result->mesh, "fuzz").ok()) __builtin_trap();
}

} // namespace lodbake_fuzz
