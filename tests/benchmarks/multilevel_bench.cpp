// multilevel_bench: document 003's multilevel simplification (simplifyMultilevel, default options)
// against the QEM simplifier (simplify, default options) on the shared meshes, at the same triangle
// ratios. Prints each method's time (best of 3) and triangle count, with multilevel time / QEM time
// as the ratio, and writes both results as PLY into the output folder so meshdist.py can measure
// them against the input:
//   /usr/bin/python3 ../shared/eval/meshdist.py <mesh> <out>/<stem>_<method>_<ratio>.ply
//
// usage: multilevel_bench [--out DIR] [--ratios 0.5,0.1,0.02] [FILE...]   (FILEs in the shared folder)

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench_bar.h"
#include "bench_timing.h"

#include "lodbake/io/mesh_io.h"
#include "lodbake/simplify/multilevel.h"
#include "lodbake/simplify/simplify.h"

namespace {

constexpr int kRuns = 3;

std::string stem(const std::string& name) {
    const size_t dot = name.rfind('.');
    return dot == std::string::npos ? name : name.substr(0, dot);
}

} // namespace

int main(int argc, char** argv) {
    // --check is accepted so that scripts/bench.sh can pass it to every bench; there is no bar.
    (void)lodbake_bench::takeCheckFlag(argc, argv);
    lodbake_bench::Bars::printNone(
        "multilevel_bench", "the multilevel method against QEM (docs/simplify.md); no bar in the docs or issues");
    using namespace lodbake;
    std::string out_dir = LODBAKE_BENCH_OUT_DIR;
    std::vector<double> ratios = {0.5, 0.1, 0.02};
    std::vector<std::string> names;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--out" && i + 1 < argc) {
            out_dir = argv[++i];
        } else if (a == "--ratios" && i + 1 < argc) {
            ratios.clear();
            for (char* p = argv[++i]; *p;) {
                char* end = nullptr;
                ratios.push_back(std::strtod(p, &end));
                if (end == p) break;
                p = *end == ',' ? end + 1 : end;
            }
        } else {
            names.push_back(a);
        }
    }
    if (names.empty()) names = {"bunny_zipper.ply", "igea.ply", "lucy100k.ply", "nefertiti.obj", "fandisk.obj"};
    std::printf("%-20s %6s %10s %10s %10s %10s %8s\n", "file", "ratio", "qem tris", "qem ms", "ml tris", "ml ms",
                "ml/qem");
    int failures = 0;
    for (const std::string& name : names) {
        Diagnostics diagnostics;
        Result<LoadedMesh> loaded = readMesh(std::string(LODBAKE_BENCH_MESHES_DIR) + "/" + name, ReadOptions(), diagnostics);
        if (!loaded.ok()) {
            std::printf("%-20s skipped: %s\n", name.c_str(), loaded.status().message().c_str());
            ++failures;
            continue;
        }
        const Mesh& input = loaded->mesh;
        for (double ratio : ratios) {
            SimplifyOptions qo;
            qo.target_ratio = float(ratio);
            MultilevelOptions mo;
            mo.percentage = 100.0 * (1.0 - ratio);
            Mesh qem, ml;
            const double qem_ms = lodbake_bench::bestMs(kRuns, [&] {
                Diagnostics d;
                Result<SimplifyOutput> r = simplify(input, qo, d);
                if (r.ok()) qem = std::move(r->mesh);
            });
            const double ml_ms = lodbake_bench::bestMs(kRuns, [&] {
                Diagnostics d;
                Result<MultilevelOutput> r = simplifyMultilevel(input, mo, d);
                if (r.ok()) ml = std::move(r->mesh);
            });
            char suffix[32];
            std::snprintf(suffix, sizeof suffix, "_%g.ply", ratio);
            for (const auto& [method, mesh] : {std::make_pair("qem", &qem), std::make_pair("multilevel", &ml)}) {
                Diagnostics d;
                const Status s = writeMesh(*mesh, out_dir + "/" + stem(name) + "_" + method + suffix, WriteOptions(), d);
                if (!s.ok()) {
                    std::printf("    write failed: %s\n", s.message().c_str());
                    ++failures;
                }
            }
            std::printf("%-20s %6g %10zu %10.1f %10zu %10.1f %8.2f\n", name.c_str(), ratio, qem.faceCount(), qem_ms,
                        ml.faceCount(), ml_ms, ml_ms / qem_ms);
        }
    }
    return failures ? 1 : 0;
}
