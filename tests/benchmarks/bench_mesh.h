#pragma once
// Input set-up shared by the benchmark programs that time the bake's stages on one scan.

#include <cstdio>
#include <string>
#include <utility>

#include "lodbake/cleanup/repair.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/core/mesh.h"
#include "lodbake/io/mesh_io.h"

namespace lodbake_bench {

/// Reads `path` and repairs it as `lodbake bake` does (default pipeline, without the report-only
/// passes). Prints the error and returns false on failure.
inline bool loadRepaired(const std::string& path, lodbake::Mesh& mesh, lodbake::Diagnostics& diagnostics) {
    lodbake::Result<lodbake::LoadedMesh> loaded = lodbake::readMesh(path, lodbake::ReadOptions{}, diagnostics);
    if (!loaded.ok()) {
        std::fprintf(stderr, "error: %s\n", loaded.status().message().c_str());
        return false;
    }
    mesh = std::move(loaded->mesh);
    lodbake::RepairOptions repair_options;
    repair_options.report_welded = false;
    repair_options.report_before = false;
    const auto repaired = lodbake::repairMesh(mesh, repair_options, "input", diagnostics);
    if (!repaired.ok()) {
        std::fprintf(stderr, "error: %s\n", repaired.status().message().c_str());
        return false;
    }
    return true;
}

} // namespace lodbake_bench
