// lodbake merge.

#include <cstdio>
#include <string>
#include <vector>

#include "lodbake/core/diagnostics.h"
#include "lodbake/core/file_io.h"
#include "lodbake/core/json_writer.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/reconstruct/merge.h"

#include "cli_common.h"

namespace lodbake::cli {

namespace {

const char* kMergeHelp = R"(usage: lodbake merge IN -o OUT [--depth N] [--trim OCTAVES] [--json]

Merges aligned range views (a .conf scan set, or a mesh whose components overlap as sheets) into one
surface: per-sample normals facing the scanner, screened Poisson reconstruction at an octree depth
chosen from the sampling density, the surface far from every sample trimmed away (so real holes stay
open), colours carried over from the nearest samples. Prints what was merged and the distance from
the input samples to the merged surface. Output is written atomically. See docs/bake.md.

options:
  -o, --output OUT      output path (required; .ply .obj .off .gltf .glb)
  --depth N             octree depth, 1..11 (default: from the sample spacing)
  --trim OCTAVES        trim surface whose sample density is this many octaves below the median
                        (default 1.5; 0 keeps only the denser half; a large value trims nothing)
  --json                print the report as one JSON object
)";

void printReport(const std::string& out, const MergeReport& r, const Mesh& mesh, bool json) {
    const double diag = r.diagonal > 0.0 ? r.diagonal : 1.0;
    if (json) {
        JsonWriter j;
        j.beginObject();
        j.field("output", out);
        j.field("views", uint64_t(r.views));
        j.field("views_are_scans", r.views_are_scans);
        j.field("points", uint64_t(r.points));
        j.field("depth", int64_t(r.depth));
        j.field("sample_spacing", r.sample_spacing);
        j.field("faces_before_trim", uint64_t(r.faces_before_trim));
        j.field("faces", uint64_t(r.faces));
        j.field("area", r.area);
        j.field("trimmed_area", r.trimmed_area);
        j.field("diagonal", r.diagonal);
        j.field("mean_distance", r.mean_distance);
        j.field("p95_distance", r.p95_distance);
        j.field("mean_distance_rel", r.mean_distance / diag);
        j.field("p95_distance_rel", r.p95_distance / diag);
        j.endObject();
        std::printf("%s\n", j.str().c_str());
        return;
    }
    for (const std::string& line : mergeReportLines(r)) std::printf("%s\n", line.c_str());
    std::printf("wrote %s: %zu vertices, %zu triangles\n", out.c_str(), mesh.vertexCount(), mesh.faceCount());
}

} // namespace

int runMerge(int argc, char** argv) {
    Args args;
    int code = 0;
    const std::vector<OptionSpec> specs = {{"--output", "-o", true}, {"--depth", nullptr, true},
                                           {"--trim", nullptr, true},  {"--json", nullptr, false},
                                           {"--help", "-h", false}};
    if (!parseArgs(argc, argv, 2, specs, args, code)) return code;
    if (args.flags.count("--help")) {
        std::fputs(kMergeHelp, stdout);
        std::fputs(kReaderLimitHelp, stdout);
        return kExitOk;
    }
    std::string in, out;
    if (const int usage = meshInputAndOutput(args, "merge", &in, &out); usage != kExitOk) return usage;
    MergeOptions options;
    if (args.values.count("--depth")) {
        double d = 0;
        if (!parseNumber(args.values["--depth"], d) || d != double(int(d)) || d < 1 || d > options.max_depth)
            return usageError("--depth expects an integer in [1, " + std::to_string(options.max_depth) + "], got '" +
                              args.values["--depth"] + "'");
        options.depth = int(d);
    }
    if (args.values.count("--trim")) {
        double t = 0;
        if (!parseNumber(args.values["--trim"], t) || !(t >= 0.0 && t <= 64.0))
            return usageError("--trim expects a number in [0, 64], got '" + args.values["--trim"] + "'");
        options.trim_log2 = t;
    }

    Diagnostics diagnostics;
    Result<LoadedMesh> loaded = readMesh(in, args.read, diagnostics);
    if (!loaded.ok()) {
        printDiagnostics(diagnostics);
        return reportError(loaded.status());
    }
    Mesh& mesh = loaded->mesh;
    Result<MergeReport> report = mergeRangeViews(mesh, options, in);
    if (!report.ok()) {
        printDiagnostics(diagnostics);
        return reportError(report.status());
    }
    const Status written = writeMesh(mesh, out, WriteOptions(), diagnostics);
    printDiagnostics(diagnostics);
    if (!written.ok()) return reportError(written);
    printReport(out, *report, mesh, args.flags.count("--json") > 0);
    return kExitOk;
}

} // namespace lodbake::cli
