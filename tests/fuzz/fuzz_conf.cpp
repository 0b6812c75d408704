// libFuzzer target for Stanford .conf scan sets (lodbake/io/conf.h). The input is the .conf text,
// written to a scratch folder that also holds two small scans it may name (scan.ply, scan.off), so
// the fuzzer reaches the transform and concatenation code as well as the line parser. A failure
// must be one line starting with the .conf's path; a success a consistent mesh with finite
// positions. Run with scripts/fuzz.sh conf SECONDS.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <unistd.h>

#include "fuzz_support.h"
#include "lodbake/core/file_io.h"
#include "lodbake/io/conf.h"

namespace {

std::string g_scratch_dir; // for the exit handler

void removeScratch() {
    for (const char* name : {"/fuzz.conf", "/scan.ply", "/scan.off"}) std::remove((g_scratch_dir + name).c_str());
    std::remove(g_scratch_dir.c_str());
}

// The scratch folder, made once per process and removed when it exits normally (a crash leaves it
// for the post-mortem).
const std::string& scratch() {
    static const std::string dir = [] {
        char templ[] = "/tmp/lodbake_fuzz_conf_XXXXXX";
        const char* made = mkdtemp(templ);
        if (!made) __builtin_trap();
        const std::string d = made;
        const std::string ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                                "property float z\nelement face 2\nproperty list uchar int vertex_indices\n"
                                "end_header\n0 0 0\n1 0 0\n0 1 0\n1 1 0.5\n3 0 1 2\n3 1 3 2\n";
        const std::string off = "OFF\n3 1 0\n0 0 0\n0 0 1\n0 1 0\n3 0 1 2\n";
        if (!lodbake::writeFileAtomic(d + "/scan.ply", ply.data(), ply.size()).ok() ||
            !lodbake::writeFileAtomic(d + "/scan.off", off.data(), off.size()).ok())
            __builtin_trap();
        g_scratch_dir = d;
        std::atexit(removeScratch);
        return d;
    }();
    return dir;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = scratch() + "/fuzz.conf";
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) __builtin_trap();
    if (size > 0 && std::fwrite(data, 1, size, f) != size) __builtin_trap();
    std::fclose(f);
    lodbake::Diagnostics diagnostics;
    const lodbake::Result<lodbake::LoadedMesh> result = lodbake::readConf(path, lodbake_fuzz::smallLimits(), diagnostics);
    if (!result.ok()) {
        const std::string& m = result.status().message();
        if (m.rfind(path, 0) != 0 || m.find('\n') != std::string::npos) __builtin_trap();
        return 0;
    }
    if (!lodbake::checkMeshConsistency(result->mesh, "fuzz").ok()) __builtin_trap();
    for (const lodbake::Vec3f& p : result->mesh.positions)
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) __builtin_trap();
    return 0;
}
