// lodbake_scansim: writes simulated turntable range scans (Stanford range-grid PLYs + .conf).
// Argument parsing, printing and exit codes only; the simulation is in scansim.cpp.
// Exit codes: 0 ok, 1 error, 2 usage.

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "lodbake/core/file_io.h"
#include "lodbake/core/temp_files.h"
#include "scansim.h"

namespace {

using namespace lodbake;
using namespace lodbake::scansim;

const char* kHelp = R"(usage: lodbake_scansim -o DIR [options]
       lodbake_scansim --surface FILE.ply --triangles N [--seed N] [--ascii | --big-endian]

Scans a procedural rock on a plinth from several turntable positions, the way a Cyberware or
structured-light scanner does, and writes DIR/<name>_<deg>.ply (Stanford `element range_grid`
PLYs in scanner coordinates) and DIR/<name>.conf (`bmesh name tx ty tz qx qy qz qw`, meaning
p_world = R(q)^T * p + t). The output is a pure function of the options.

options:
  -o, --output DIR     output folder (created if missing)
  --preset NAME        start from a named option set (rock: the bundled sample); later options override
  --name NAME          file name stem (default rock)
  --seed N             seed of the shape noise and every scanner random choice (default 1)
  --views N            turntable positions, 360/N degrees apart (default 6)
  --cols N, --rows N   rays per view (default 160 x 120)
  --sigma M            Gaussian range noise along the view ray, metres (default 0.0002)
  --grazing DEG        drop samples seen further than DEG from the surface normal (default 75)
  --speckle P          probability that a good sample is dropped anyway (default 0.01)
  --no-shadows         keep samples the projector cannot see
  --confidence         add `property float confidence` (cosine of the view angle)
  --ascii              ascii PLY instead of binary little endian
  --atlas K            also write <name>_atlas.obj: the rock as a textured mesh whose UVs form an
                       atlas of 6*K*K charts (K in [1, 64]; 6 gives 216 charts)
  --atlas-quads M      quads per chart edge of that mesh (default 5)
  -h, --help           this help

surface mode (a procedural scan of any size, for the out-of-core bake):
  --surface FILE.ply   write a displaced torus with fractal relief and Gaussian range noise to
                       FILE.ply while generating it, one grid row in memory at a time
  --triangles N        about N triangles (the grid gives 2 x rows x cols; 18 .. 2^36)
  --seed N             seed of the relief and the noise (default 1)
  --ascii              ascii PLY (default binary little endian)
  --big-endian         binary big endian PLY
)";

int usage(const std::string& message) {
    std::fprintf(stderr, "error: %s (see lodbake_scansim --help)\n", message.c_str());
    return 2;
}

bool parseDouble(const std::string& s, double& out) {
    errno = 0;
    char* end = nullptr;
    out = std::strtod(s.c_str(), &end);
    return !s.empty() && errno == 0 && end && *end == '\0';
}

bool parseUnsigned(const std::string& s, uint64_t& out) {
    if (s.empty() || s[0] == '-' || s[0] == '+') return false;
    errno = 0;
    char* end = nullptr;
    out = std::strtoull(s.c_str(), &end, 10);
    return errno == 0 && end && *end == '\0';
}

// `--surface FILE --triangles N [--seed N] [--ascii | --big-endian]`: the surface generator.
int surfaceMain(int argc, char** argv) {
    SurfaceOptions options;
    std::string path;
    bool have_triangles = false;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const bool has_value = i + 1 < argc;
        uint64_t u = 0;
        if (a == "--surface" && has_value) {
            path = argv[++i];
        } else if ((a == "--triangles" || a == "--seed") && has_value) {
            if (!parseUnsigned(argv[++i], u)) return usage(a + " needs a non-negative integer");
            (a == "--seed" ? options.seed : options.triangles) = u;
            have_triangles |= a == "--triangles";
        } else if (a == "--ascii") {
            options.encoding = SurfaceOptions::Encoding::Ascii;
        } else if (a == "--big-endian") {
            options.encoding = SurfaceOptions::Encoding::BinaryBigEndian;
        } else {
            return usage("surface mode: unexpected argument '" + a + "'");
        }
    }
    if (path.empty() || !have_triangles) return usage("surface mode needs --surface FILE.ply and --triangles N");
    installTempFileSignalCleanup();
    Result<SurfaceStats> stats = writeSurfacePly(options, path);
    if (!stats.ok()) {
        std::fprintf(stderr, "error: %s\n", stats.status().message().c_str());
        return stats.status().code() == StatusCode::InvalidInput ? 2 : 1;
    }
    std::printf("%s: %llu vertices, %llu triangles (grid %llu x %llu), %llu bytes\n", path.c_str(),
                (unsigned long long)stats->vertices, (unsigned long long)stats->triangles,
                (unsigned long long)stats->rows, (unsigned long long)stats->cols, (unsigned long long)stats->bytes);
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    for (int i = 1; i < argc; ++i)
        if (std::string(argv[i]) == "--surface") return surfaceMain(argc, argv);
    ScanOptions options;
    AtlasOptions atlas;
    bool write_atlas = false;
    std::string out_dir;
    // A preset is applied first wherever it appears, so that the other flags override it.
    for (int i = 1; i + 1 < argc; ++i) {
        if (std::string(argv[i]) == "--preset") {
            Result<ScanOptions> preset = presetOptions(argv[i + 1]);
            if (!preset.ok()) return usage(preset.status().message());
            options = *preset;
        }
    }
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&](std::string& v) {
            if (i + 1 >= argc) return false;
            v = argv[++i];
            return true;
        };
        std::string v;
        uint64_t u = 0;
        double d = 0.0;
        if (a == "-h" || a == "--help") {
            std::fputs(kHelp, stdout);
            return 0;
        } else if (a == "-o" || a == "--output") {
            if (!value(out_dir)) return usage(a + " needs a value");
        } else if (a == "--preset") {
            if (!value(v)) return usage(a + " needs a value");
        } else if (a == "--name") {
            if (!value(options.name)) return usage(a + " needs a value");
        } else if (a == "--seed") {
            if (!value(v) || !parseUnsigned(v, u)) return usage("--seed needs a non-negative integer");
            options.seed = u;
        } else if (a == "--views" || a == "--cols" || a == "--rows") {
            if (!value(v) || !parseUnsigned(v, u) || u > 100000) return usage(a + " needs a positive integer");
            if (a == "--views") options.view_count = int(u);
            if (a == "--cols") options.num_cols = uint32_t(u);
            if (a == "--rows") options.num_rows = uint32_t(u);
        } else if (a == "--sigma" || a == "--grazing" || a == "--speckle") {
            if (!value(v) || !parseDouble(v, d)) return usage(a + " needs a number");
            if (a == "--sigma") options.range_noise_sigma = d;
            if (a == "--grazing") options.grazing_limit_deg = d;
            if (a == "--speckle") options.speckle_probability = d;
        } else if (a == "--no-shadows") {
            options.simulate_shadows = false;
        } else if (a == "--confidence") {
            options.write_confidence = true;
        } else if (a == "--ascii") {
            options.binary = false;
        } else if (a == "--atlas" || a == "--atlas-quads") {
            if (!value(v) || !parseUnsigned(v, u) || u < 1 || u > 64) return usage(a + " needs an integer in [1, 64]");
            (a == "--atlas" ? atlas.charts_per_edge : atlas.quads_per_chart) = uint32_t(u);
            if (a == "--atlas") write_atlas = true;
        } else {
            return usage("unknown argument '" + a + "'");
        }
    }
    if (out_dir.empty()) return usage("-o DIR is required");
    const Status valid = validateOptions(options);
    if (!valid.ok()) return usage(valid.message());

    Result<ScanSet> scans = simulateScans(options);
    if (!scans.ok()) {
        std::fprintf(stderr, "error: %s\n", scans.status().message().c_str());
        return 1;
    }
    const Status written = writeScanSet(*scans, options, out_dir);
    if (!written.ok()) {
        std::fprintf(stderr, "error: %s\n", written.message().c_str());
        return 1;
    }
    for (const ScanView& view : scans->views) {
        const ViewStats& s = view.stats;
        std::printf("%s: %llu samples of %llu cells (%llu hits; dropped %llu shadowed, %llu grazing, %llu speckle)\n",
                    view.file_name.c_str(), (unsigned long long)s.kept, (unsigned long long)s.cells,
                    (unsigned long long)s.hits, (unsigned long long)s.dropped_shadow,
                    (unsigned long long)s.dropped_grazing, (unsigned long long)s.dropped_speckle);
    }
    std::printf("%s: %zu views\n", confFileName(options).c_str(), scans->views.size());
    if (write_atlas) {
        Result<std::string> obj = atlasObjText(options, atlas);
        const std::string path = out_dir + "/" + options.name + "_atlas.obj";
        const Status atlas_written =
            obj.ok() ? writeFileAtomic(path, obj->data(), obj->size()) : obj.status();
        if (!atlas_written.ok()) {
            std::fprintf(stderr, "error: %s\n", atlas_written.message().c_str());
            return 1;
        }
        std::printf("%s: %u charts\n", path.c_str(), 6 * atlas.charts_per_edge * atlas.charts_per_edge);
    }
    return 0;
}
