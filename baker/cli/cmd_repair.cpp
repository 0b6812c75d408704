// lodbake repair.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "lodbake/bake/bake.h"
#include "lodbake/cleanup/repair.h"
#include "lodbake/codec/valence_encoder.h"
#include "lodbake/config/bake_config.h"
#include "lodbake/cleanup/topology.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/core/file_io.h"
#include "lodbake/core/json_writer.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/pfrep/pfrep_builder.h"
#include "lodbake/simplify/lod_chain.h"
#include "lodbake/simplify/mesh_distance.h"
#include "lodbake/simplify/simplify.h"
#include "lodbake/version.h"
#include "lodrt/pfrep.h"

#include "cli_common.h"

namespace lodbake::cli {

namespace {

const char* kRepairHelp = R"(usage: lodbake repair IN -o OUT [--json] [options]

Runs the repair pipeline: weld -> degenerate/duplicate faces -> unreferenced vertices -> manifold
-> orientation -> small components -> hole filling -> (denoise, off unless asked) -> normals, and
prints what each pass changed with validate() before and after. Output is written atomically.

options:
  -o, --output OUT            output path (required; .ply .obj .off .gltf .glb)
  --json                      print the report as one JSON object
  --weld-tolerance R          weld distance as a fraction of the bbox diagonal (default 1e-6; 0: exact)
  --weld-ignore-attributes    weld across UV/normal seams
  --no-weld                   skip welding
  --non-manifold cut|remove   faces beyond the best pair on an over-used edge (default cut)
  --min-component-faces N     drop components with fewer faces (default 20)
  --min-component-area F      drop components under this fraction of the total area (default 0.0003)
  --max-hole-edges N          fill holes of at most N edges (default 100); 0 disables filling
  --no-refine                 fill holes with the bare triangulation (no refinement or fairing)
  --denoise METHOD            taubin | laplacian | plaplacian (default: no denoising)
  --weights W                 umbrella | cotangent | fujiwara (laplacian, taubin; default umbrella)
  --iterations N              denoise iterations (default 5; plaplacian: outer iterations, default 2)
  --p P                       plaplacian exponent (default 1)
  --fidelity F                plaplacian pull toward the input (default 0.3)
  --preserve-features         keep creases sharp while denoising
  --crease-angle DEG          normals: split vertices at edges sharper than DEG (default 180: never)
  --no-normals                keep the input normals
)";

void writePassesJson(JsonWriter& j, const RepairReport& report) {
    j.key("passes").beginArray();
    for (const PassSummary& p : report.passes) {
        j.beginObject();
        j.field("pass", p.name);
        for (const auto& [name, count] : p.counters) j.field(name, count);
        j.key("notes").beginArray();
        for (const std::string& n : p.notes) j.value(n);
        j.endArray();
        j.endObject();
    }
    j.endArray();
}

void writeValidationJson(JsonWriter& j, const ValidationReport& v) {
    j.beginObject();
    j.key("topology");
    writeTopologyJson(j, v.topology);
    j.key("boundary_loop_lengths").beginArray();
    for (uint32_t l : v.boundary_loop_lengths) j.value(uint64_t(l));
    j.endArray();
    j.key("component_face_counts").beginArray();
    for (size_t i = 0; i < v.component_face_counts.size() && i < 50; ++i) j.value(uint64_t(v.component_face_counts[i]));
    j.endArray();
    j.field("manifold", v.isManifold());
    j.field("closed_manifold", v.isClosedManifold());
    j.endObject();
}

} // namespace

int runRepair(int argc, char** argv) {
    Args args;
    int code = 0;
    const std::vector<OptionSpec> specs = {
        {"--output", "-o", true},           {"--json", nullptr, false},
        {"--weld-tolerance", nullptr, true}, {"--weld-ignore-attributes", nullptr, false},
        {"--no-weld", nullptr, false},      {"--non-manifold", nullptr, true},
        {"--min-component-faces", nullptr, true}, {"--min-component-area", nullptr, true},
        {"--max-hole-edges", nullptr, true}, {"--no-refine", nullptr, false},
        {"--denoise", nullptr, true},       {"--weights", nullptr, true},
        {"--iterations", nullptr, true},    {"--preserve-features", nullptr, false},
        {"--p", nullptr, true},             {"--fidelity", nullptr, true},
        {"--crease-angle", nullptr, true},  {"--no-normals", nullptr, false},
        {"--help", "-h", false}};
    if (!parseArgs(argc, argv, 2, specs, args, code)) return code;
    if (args.flags.count("--help")) {
        std::fputs(kRepairHelp, stdout);
        std::fputs(kReaderLimitHelp, stdout);
        return kExitOk;
    }
    std::string in, out;
    if (const int usage = meshInputAndOutput(args, "repair", &in, &out); usage != kExitOk) return usage;

    RepairOptions opt;
    auto number = [&](const char* flag, double lo, double hi, double& v) {
        if (!args.values.count(flag)) return true;
        if (!parseNumber(args.values[flag], v) || !(v >= lo && v <= hi)) {
            code = usageError(std::string(flag) + " expects a number in [" + JsonWriter::formatNumber(lo) + ", " +
                              JsonWriter::formatNumber(hi) + "], got '" + args.values[flag] + "'");
            return false;
        }
        return true;
    };
    double v = opt.weld_options.tolerance_rel;
    if (!number("--weld-tolerance", 0.0, 0.1, v)) return code;
    opt.weld_options.tolerance_rel = v;
    opt.weld_options.respect_attributes = !args.flags.count("--weld-ignore-attributes");
    opt.weld = !args.flags.count("--no-weld");
    if (args.values.count("--non-manifold")) {
        const std::string& m = args.values["--non-manifold"];
        if (m == "cut") opt.manifold_options.edge_mode = NonManifoldEdgeMode::Cut;
        else if (m == "remove") opt.manifold_options.edge_mode = NonManifoldEdgeMode::Remove;
        else return usageError("--non-manifold expects cut or remove, got '" + m + "'");
    }
    v = opt.component_options.min_face_count;
    if (!number("--min-component-faces", 0, 1e9, v)) return code;
    opt.component_options.min_face_count = uint32_t(v);
    v = opt.component_options.min_area_fraction;
    if (!number("--min-component-area", 0, 1, v)) return code;
    opt.component_options.min_area_fraction = v;
    v = opt.hole_options.max_hole_edges;
    if (!number("--max-hole-edges", 0, 1e7, v)) return code;
    opt.hole_options.max_hole_edges = uint32_t(v);
    opt.fill_holes = opt.hole_options.max_hole_edges > 0;
    opt.hole_options.refine = opt.hole_options.fair = !args.flags.count("--no-refine");
    if (args.values.count("--denoise")) {
        const std::string& m = args.values["--denoise"];
        opt.denoise = true;
        if (m == "taubin") opt.denoise_options.method = DenoiseMethod::Taubin;
        else if (m == "laplacian") opt.denoise_options.method = DenoiseMethod::Laplacian;
        else if (m == "plaplacian") opt.denoise_options.method = DenoiseMethod::PLaplacian;
        else return usageError("--denoise expects taubin, laplacian or plaplacian, got '" + m + "'");
    }
    if (args.values.count("--weights")) {
        const std::string& m = args.values["--weights"];
        if (m == "umbrella") opt.denoise_options.weights = LaplacianWeights::Umbrella;
        else if (m == "cotangent") opt.denoise_options.weights = LaplacianWeights::Cotangent;
        else if (m == "fujiwara") opt.denoise_options.weights = LaplacianWeights::Fujiwara;
        else return usageError("--weights expects umbrella, cotangent or fujiwara, got '" + m + "'");
    }
    const bool plaplacian = opt.denoise_options.method == DenoiseMethod::PLaplacian;
    v = plaplacian ? opt.denoise_options.outer_iterations : opt.denoise_options.iterations;
    if (!number("--iterations", 0, 10000, v)) return code;
    (plaplacian ? opt.denoise_options.outer_iterations : opt.denoise_options.iterations) = uint32_t(v);
    v = opt.denoise_options.p;
    if (!number("--p", 0.1, 2.0, v)) return code;
    opt.denoise_options.p = v;
    v = opt.denoise_options.fidelity;
    if (!number("--fidelity", 0.0, 10.0, v)) return code;
    opt.denoise_options.fidelity = v;
    opt.denoise_options.preserve_features = args.flags.count("--preserve-features") > 0;
    v = opt.normal_options.crease_angle_deg;
    if (!number("--crease-angle", 0, 180, v)) return code;
    opt.normal_options.crease_angle_deg = v;
    opt.normals = !args.flags.count("--no-normals");

    Diagnostics diagnostics;
    Result<LoadedMesh> loaded = readMesh(in, args.read, diagnostics);
    if (!loaded.ok()) {
        printDiagnostics(diagnostics);
        return reportError(loaded.status());
    }
    Mesh& mesh = loaded->mesh;
    Result<RepairReport> report = repairMesh(mesh, opt, in, diagnostics);
    if (!report.ok()) {
        printDiagnostics(diagnostics);
        return reportError(report.status());
    }
    if (mesh.faceCount() == 0) {
        printDiagnostics(diagnostics);
        return reportError(invalidInput(in + ": repair: no triangles left to write"));
    }
    WriteOptions wopt;
    const Status written = writeMesh(mesh, out, wopt, diagnostics);
    printDiagnostics(diagnostics);
    if (!written.ok()) return reportError(written);

    if (args.flags.count("--json")) {
        JsonWriter j;
        j.beginObject();
        j.field("input", in);
        j.field("output", out);
        j.key("before");
        writeValidationJson(j, report->before);
        writePassesJson(j, *report);
        j.key("after");
        writeValidationJson(j, report->after);
        j.key("after_welded_by_position");
        writeValidationJson(j, report->after_welded);
        j.key("unresolved").beginArray();
        for (const std::string& u : report->unresolved) j.value(u);
        j.endArray();
        j.endObject();
        std::fputs(j.str().c_str(), stdout);
        std::fputs("\n", stdout);
        return kExitOk;
    }
    for (const PassSummary& p : report->passes) {
        std::printf("%-17s", p.name.c_str());
        for (const auto& [name, count] : p.counters)
            if (count) std::printf(" %s=%llu", name.c_str(), (unsigned long long)count);
        std::printf("\n");
        for (const std::string& n : p.notes) std::printf("  %s\n", n.c_str());
    }
    printTopologyText("topology before", report->before.topology);
    printTopologyText("topology after", report->after.topology);
    std::printf("wrote %s: %zu vertices, %zu triangles\n", out.c_str(), mesh.vertexCount(), mesh.faceCount());
    return kExitOk;
}

} // namespace lodbake::cli
