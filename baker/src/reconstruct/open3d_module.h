#pragma once
// Internal to the reconstruct module: the interface of liblodbake_open3d, the shared module that
// holds every Open3D call. Debian's libOpen3D pulls in about a hundred libraries (GUI, GL, codecs)
// whose loading would slow every process start, although only a merge needs it; the module is
// loaded with dlopen on first use. Module and library are built by the same toolchain, so C++
// types cross the boundary.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace lodbake {
namespace open3d_module {

constexpr int kApiVersion = 1;

struct PoissonInput {
    const float* positions = nullptr; // 3 per point
    const float* normals = nullptr;   // 3 per point, unit, oriented outwards
    size_t point_count = 0;
    int depth = 8;       // octree depth
    float scale = 1.1f;  // the octree cube / the points' bounding cube
    int threads = 1;     // Open3D's thread count (1: its reduction order is fixed)
};

struct PoissonOutput {
    std::vector<float> positions;  // 3 per vertex
    std::vector<uint32_t> indices; // 3 per triangle
    std::vector<double> density;   // per vertex: Open3D's sample density estimate
};

struct Api {
    int version;
    /// Screened Poisson reconstruction (Kazhdan & Hoppe 2013, Open3D's port). false with *error set on
    /// failure. Never throws, never prints.
    bool (*poisson)(const PoissonInput* input, PoissonOutput* out, std::string* error);
};

} // namespace open3d_module
} // namespace lodbake

/// The module's only exported symbol.
extern "C" const lodbake::open3d_module::Api* lodbake_open3d_api();
