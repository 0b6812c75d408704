// Pack size benchmark: `lodbake bake MESH --preset configs/desktop.json --compact` (in process, the
// same pipeline as the CLI; texture levels off, since only geometry is compared) against gltfpack -cc
// (npm gltfpack from scripts/node-bench, meshopt compression, its default quantization) writing the
// same levels as one file per level with -si R for R in 1.0 0.5 0.25 0.1 0.03 0.01, the sizes summed.
// gltfpack reads the repaired scan (the pack's LOD0: repairMesh, as bake runs it) as a plain GLB
// written by lodbake, so both sides code the same streams (positions, the normals repair computes,
// UVs where the scan has them; textures and materials dropped on both sides). Prints both totals and
// our/gltfpack per scan; the bar is <= 0.5. With --levels, also each level's stream: triangles, position
// and normal bits (adaptive precision, docs/bake.md), bytes, the largest distance quantization can move
// a vertex (sqrt(3)/2 * cube / (2^bits - 1), from the stream header) relative to the level's reported
// mean and Hausdorff error, and the largest angle the normal quantization can turn a normal.
//
// The bar (docs/bake.md) is judged on the worst scan; --check exits 1 when it is not met.
// The same bake with --web instead of --compact (EXT_meshopt_compression + KHR_mesh_quantization,
// docs/format/web.md) is measured against the same gltfpack files: bar <= 1.0 on the worst scan
// (goal 0.9).
// The same --compact bake with the PFRep blob (LODBAKE_progressive_fans, format 4 as the bake writes it
// by default; pfrep_from_chain as the preset says) is measured against them too: bar <= 0.7 on the
// worst scan, must <= 1.0 (issue 30). --pfrep-format F bakes that blob as format F instead (2, 3, 4 or 5).
//
// usage: pack_size_bench [--levels] [--preset FILE] [--no-adaptive] [--pfrep-format F] [--check] [MESH...]
//        (default: configs/desktop.json, the untextured shared scans)
// Not a ctest. Needs `npm ci` in scripts/node-bench.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "bench_bar.h"
#include "lodbake/bake/bake.h"
#include "lodbake/cleanup/repair.h"
#include "lodbake/config/bake_config.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/core/file_io.h"
#include "lodbake/io/gltf.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/pack/pack.h"
#include "lodbake/stream/stream.h"
#include "lodrt/pack.h"
#include "lodrt/valence.h"

namespace {

namespace fs = std::filesystem;

std::string shellQuote(const std::string& s) {
    std::string out = "'";
    for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

void stripMaterials(lodbake::Mesh& mesh) {
    mesh.textures.clear();
    mesh.materials.clear();
    for (lodbake::SubMesh& s : mesh.submeshes) s.material = lodbake::MaterialId::invalid();
}

// One line per level of the pack: its streams' precision and what it costs in accuracy.
void printLevels(const std::vector<uint8_t>& glb, const lodbake::LodMetrics& metrics) {
    lodrt::Pack pack;
    if (lodrt::loadPack(glb.data(), glb.size(), nullptr, &pack) != lodrt::Result::Ok) {
        std::printf("  (the pack does not load)\n");
        return;
    }
    const double pi = 3.14159265358979323846;
    std::printf("  %5s %9s %5s %5s %9s %11s %11s %11s %10s\n", "level", "triangles", "pbits", "nbits", "bytes",
                "q/diagonal", "q/mean_err", "q/hausdorff", "normal_deg");
    for (uint32_t m = 0; m < pack.meshCount() && m < metrics.levels.size(); ++m) {
        const lodrt::MeshInfo& mesh = pack.mesh(m);
        for (uint32_t p = mesh.first_primitive; p < mesh.first_primitive + mesh.primitive_count; ++p) {
            uint64_t view = 0;
            if (!pack.primitive(p)
                     .json.find("extensions")
                     .find("LODBAKE_valence_compression")
                     .find("bufferView")
                     .asUint64(&view))
                continue;
            const lodrt::BufferViewInfo& v = pack.bufferView(uint32_t(view));
            lodrt::ValenceInfo info;
            if (lodrt::valenceReadInfo(pack.container().bin + v.byte_offset, size_t(v.byte_length), &info) !=
                lodrt::Result::Ok)
                continue;
            const lodbake::LodMetricsLevel& l = metrics.levels[m];
            const double q = std::sqrt(3.0) / 2.0 * double(info.cube_size) / double((1u << info.position_bits) - 1);
            const double diagonal = 2.0 * metrics.bounding_radius;
            auto ratio = [q](double e) { return e > 0.0 ? q / e : 0.0; };
            std::printf("  %5u %9llu %5u %5u %9llu %11.3g %11.3g %11.3g %10.3g\n", m,
                        static_cast<unsigned long long>(pack.primitive(p).triangle_count), info.position_bits,
                        info.normal_bits, static_cast<unsigned long long>(v.byte_length), q / diagonal,
                        ratio(l.mean_error), ratio(l.hausdorff_error),
                        info.has_normals ? lodbake::octahedralMaxAngle(info.normal_bits) * 180.0 / pi : 0.0);
        }
    }
}

} // namespace

int main(int argc, char** argv) {
    const bool check = lodbake_bench::takeCheckFlag(argc, argv);
    std::vector<std::string> meshes;
    bool levels = false, no_adaptive = false;
    uint32_t pfrep_format = 0; // 0: the bake's default
    std::string preset_path = std::string(LODBAKE_BENCH_SOURCE_DIR) + "/configs/desktop.json";
    for (int i = 1; i < argc; ++i) {
        if (std::strcmp(argv[i], "--levels") == 0) {
            levels = true;
        } else if (std::strcmp(argv[i], "--no-adaptive") == 0) {
            no_adaptive = true;
        } else if (std::strcmp(argv[i], "--preset") == 0 && i + 1 < argc) {
            preset_path = argv[++i];
        } else if (std::strcmp(argv[i], "--pfrep-format") == 0 && i + 1 < argc &&
                   (std::strcmp(argv[i + 1], "2") == 0 || std::strcmp(argv[i + 1], "3") == 0 ||
                    std::strcmp(argv[i + 1], "4") == 0 || std::strcmp(argv[i + 1], "5") == 0)) {
            pfrep_format = uint32_t(argv[++i][0] - '0');
        } else if (argv[i][0] == '-') {
            std::fprintf(
                stderr,
                "usage: pack_size_bench [--levels] [--preset FILE] [--no-adaptive] [--pfrep-format F] [--check] "
                "[MESH...]\n");
            return 2;
        } else {
            meshes.push_back(argv[i]);
        }
    }
    if (meshes.empty())
        for (const char* name : {"bunny_zipper.ply", "igea.ply", "lucy100k.ply", "nefertiti.obj", "rocker_arm.obj",
                                 "bunny_scan_bun000_tri.ply", "dragon_scan_stand0_tri.ply", "dragon_poisson.ply",
                                 "dragon_stand_merged.ply", "fandisk.obj"})
            meshes.push_back(std::string(LODBAKE_BENCH_MESHES_DIR) + "/" + name);
    const std::string gltfpack = std::string(LODBAKE_BENCH_NODE_DIR) + "/node_modules/.bin/gltfpack";
    if (!fs::exists(gltfpack)) {
        std::fprintf(stderr, "error: %s missing: run `npm ci` in scripts/node-bench\n", gltfpack.c_str());
        return 1;
    }
    const std::string out_dir = LODBAKE_BENCH_OUT_DIR;
    fs::create_directories(out_dir);

    lodbake::BakeSettings settings;
    const lodbake::Status preset = lodbake::applyPresetFile(preset_path, settings);
    if (!preset.ok()) {
        std::fprintf(stderr, "error: %s\n", preset.message().c_str());
        return 1;
    }
    settings.compact = true;
    // gltfpack writes the levels only; PFRep (LODBAKE_progressive_fans) is extra data with no
    // counterpart there, so the like-for-like pack leaves it out.
    settings.progressive_fans = false;
    settings.textures.enabled = false;
    // gltfpack's files are one per ratio; the like-for-like pack keeps every ratio's level, dead
    // ones too (docs/bake.md, "Dead levels").
    settings.lod_min_switch_ratio = 0.0;
    if (no_adaptive) settings.stream_precision.adaptive = false;
    const double ratios[] = {1.0, 0.5, 0.25, 0.1, 0.03, 0.01};

    lodbake::BakeSettings pfrep_settings = settings;
    pfrep_settings.progressive_fans = true;
    if (pfrep_format != 0) pfrep_settings.pfrep_format = pfrep_format;

    lodbake::BakeSettings web_settings = settings;
    web_settings.compact = false;
    web_settings.web = true;

    std::printf("%-28s %10s %12s %12s %8s %12s %8s %12s %8s\n", "scan", "triangles", "ours_bytes", "gltfpack",
                "ratio", "web_bytes", "web/gp", "pfrep_bytes", "pfrep/gp");
    double worst = 0, worst_ours = 0, worst_theirs = 0;
    double worst_web = 0, worst_web_ours = 0, worst_web_theirs = 0;
    double worst_pfrep = 0, worst_pfrep_ours = 0, worst_pfrep_theirs = 0;
    std::string worst_scan, worst_web_scan, worst_pfrep_scan;
    for (const std::string& path : meshes) {
        lodbake::Diagnostics diagnostics;
        lodbake::Result<lodbake::LoadedMesh> loaded = lodbake::readMesh(path, lodbake::ReadOptions{}, diagnostics);
        if (!loaded.ok()) {
            std::fprintf(stderr, "error: %s\n", loaded.status().message().c_str());
            return 1;
        }
        stripMaterials(loaded->mesh);
        const std::string stem = fs::path(path).stem().string();
        lodbake::Mesh repaired = loaded->mesh;
        if (settings.repair) {
            lodbake::Result<lodbake::RepairReport> repair =
                lodbake::repairMesh(repaired, lodbake::RepairOptions{}, stem, diagnostics);
            if (!repair.ok()) {
                std::fprintf(stderr, "error: %s\n", repair.status().message().c_str());
                return 1;
            }
        }
        const size_t triangles = repaired.faceCount();
        lodbake::Result<lodbake::GltfFiles> source = lodbake::writeGltfToMemory(repaired, {});
        if (!source.ok()) {
            std::fprintf(stderr, "error: %s: %s\n", path.c_str(), source.status().message().c_str());
            return 1;
        }
        const std::string source_path = out_dir + "/" + stem + "_source.glb";
        if (!lodbake::writeFileAtomic(source_path, source->main.data(), source->main.size()).ok()) return 1;

        std::vector<lodbake::BakeInput> inputs(1);
        inputs[0].name = stem;
        inputs[0].mesh = std::move(loaded->mesh);
        std::vector<lodbake::BakeInput> web_inputs = inputs;
        std::vector<lodbake::BakeInput> pfrep_inputs = inputs;
        lodbake::Result<lodbake::BakeOutput> with_pfrep =
            lodbake::bake(std::move(pfrep_inputs), pfrep_settings, diagnostics);
        if (!with_pfrep.ok()) {
            std::fprintf(stderr, "error: %s: %s\n", path.c_str(), with_pfrep.status().message().c_str());
            return 1;
        }
        lodbake::Result<lodbake::BakeOutput> web = lodbake::bake(std::move(web_inputs), web_settings, diagnostics);
        if (!web.ok()) {
            std::fprintf(stderr, "error: %s: %s\n", path.c_str(), web.status().message().c_str());
            return 1;
        }
        if (!lodbake::writeFileAtomic(out_dir + "/" + stem + "_web.glb", web->glb.data(), web->glb.size()).ok())
            return 1;
        lodbake::Result<lodbake::BakeOutput> ours = lodbake::bake(std::move(inputs), settings, diagnostics);
        if (!ours.ok()) {
            std::fprintf(stderr, "error: %s: %s\n", path.c_str(), ours.status().message().c_str());
            return 1;
        }
        if (!lodbake::writeFileAtomic(out_dir + "/" + stem + "_compact.glb", ours->glb.data(), ours->glb.size()).ok())
            return 1;

        uintmax_t theirs = 0;
        for (double r : ratios) {
            char name[64];
            std::snprintf(name, sizeof(name), "_gltfpack_%g.glb", r);
            const std::string out = out_dir + "/" + stem + name;
            char si[32];
            std::snprintf(si, sizeof(si), "%g", r);
            const std::string command = shellQuote(gltfpack) + " -i " + shellQuote(source_path) + " -o " +
                                        shellQuote(out) + " -cc -si " + si + " > /dev/null 2>&1";
            if (std::system(command.c_str()) != 0 || !fs::exists(out)) {
                std::fprintf(stderr, "error: gltfpack failed: %s\n", command.c_str());
                return 1;
            }
            theirs += fs::file_size(out);
        }
        const double ratio = double(ours->glb.size()) / double(theirs);
        if (ratio > worst) {
            worst = ratio;
            worst_ours = double(ours->glb.size());
            worst_theirs = double(theirs);
            worst_scan = stem;
        }
        const double web_ratio = double(web->glb.size()) / double(theirs);
        if (web_ratio > worst_web) {
            worst_web = web_ratio;
            worst_web_ours = double(web->glb.size());
            worst_web_theirs = double(theirs);
            worst_web_scan = stem;
        }
        const double pfrep_ratio = double(with_pfrep->glb.size()) / double(theirs);
        if (pfrep_ratio > worst_pfrep) {
            worst_pfrep = pfrep_ratio;
            worst_pfrep_ours = double(with_pfrep->glb.size());
            worst_pfrep_theirs = double(theirs);
            worst_pfrep_scan = stem;
        }
        std::printf("%-28s %10zu %12zu %12ju %8.3f %12zu %8.3f %12zu %8.3f\n", stem.c_str(), triangles,
                    ours->glb.size(), theirs, ratio, web->glb.size(), web_ratio, with_pfrep->glb.size(), pfrep_ratio);
        if (levels && !ours->assets.empty()) printLevels(ours->glb, ours->assets[0].metrics);
        std::fflush(stdout);
    }
    lodbake_bench::Bars bars("pack_size_bench");
    bars.ratio("--compact pack / gltfpack -cc, same 6 levels (bytes; worst: " + worst_scan + ")", worst_ours,
               worst_theirs, 0.5, lodbake_bench::Limit::AtMost);
    bars.ratio("--web pack / gltfpack -cc, same 6 levels (bytes; worst: " + worst_web_scan + ")", worst_web_ours,
               worst_web_theirs, 1.0, lodbake_bench::Limit::AtMost);
    bars.ratio("--compact pack with PFRep / gltfpack -cc, same 6 levels (bytes; worst: " + worst_pfrep_scan +
                   "; must <= 1.0)",
               worst_pfrep_ours, worst_pfrep_theirs, 0.7, lodbake_bench::Limit::AtMost);
    return bars.finish(check);
}
