// lodbake simplify and lodbake lods.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
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
#include "lodbake/core/math.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/pfrep/pfrep_builder.h"
#include "lodbake/simplify/lod_chain.h"
#include "lodbake/simplify/mesh_distance.h"
#include "lodbake/simplify/multilevel.h"
#include "lodbake/simplify/simplify.h"
#include "lodbake/version.h"
#include "lodrt/pfrep.h"

#include "cli_common.h"

namespace lodbake::cli {

namespace {

const char* kSimplifyHelp = R"(usage: lodbake simplify IN -o OUT (--ratio R | --triangles N | --error E) [--json]
       lodbake simplify IN -o OUT --method multilevel (--percentage P | --ratio R | --triangles N) [options]

Simplifies IN and writes OUT (format from its extension). Prints the result's size and its
measured two-sided distance to IN.

--method qem (default): quadric-error edge collapse. Open borders, UV/normal seams and sub-mesh
borders are preserved; non-manifold spots are left as they are.
--method multilevel: Guerra 2012's multilevel simplification for scanner meshes: each outer
iteration smooths with a p-Laplacian flow, then collapses the shortest, flattest edges, placing
each new vertex between the endpoints by their curvature. Geometry only (attributes are dropped);
open borders stay fixed.

options:
  -o, --output OUT   output path (required)
  --method M         qem (default) or multilevel
  --ratio R          keep this fraction of the triangles, 0 < R <= 1
  --triangles N      keep about N triangles
  --error E          collapse while the estimated error stays below E (object units; qem only)
  --remove-covered-components
                     qem only: may remove a whole connected component whose points all lie within
                     the error already accepted of the rest of the surface (overlapping scans);
                     changes the component count, so off by default
  --json             print one JSON object instead of text

multilevel options:
  --percentage P     percentage of the edges to remove, 0 <= P < 100 (--ratio R means P = 100(1-R))
  --iterations K     outer iterations, each one smoothing + decimation step (default 4)
  --smoothing-iterations S  p-Laplacian steps per outer iteration (default 3)
  --ple P            p-Laplacian exponent (default 0.5; 2 = plain Laplacian, < 1 gathers vertices
                     toward high curvature)
  --lambda L         fidelity of the smoothing to each level's input (default 10)
  --no-adaptive      do not scale lambda by the initial curvature of each vertex
  --no-sort          no ordering: collapse every edge under the histogram length threshold
  --no-smoothing     skip the smoothing step of each iteration
  --no-decimation    skip the decimation step of each iteration (smoothing only)
)";

const char* kLodsHelp = R"(usage: lodbake lods IN -o PREFIX [--levels 0.5,0.25,0.1,0.03,0.01] [--json]

Builds a chain of levels in one simplification pass and writes PREFIX_lod<i>.<ext> per level
plus PREFIX.json (triangles, vertices, Hausdorff and mean error, absolute and relative to the
bounding-box diagonal, and the switch distance at which each level's Hausdorff error projects to
--pixels pixels). <ext> is PREFIX's extension if it has a mesh one (out/bunny.glb), else --format.

options:
  -o, --output PREFIX  output prefix (required)
  --levels LIST        comma-separated triangle ratios in (0, 1]
  --format EXT         ply (default), obj, off, gltf or glb
  --pixels P           screen-space error threshold in pixels (default 1)
  --viewport H         viewport height in pixels (default 1080)
  --fov DEG            vertical field of view in degrees (default 60)
  --remove-covered-components
                       a level may lose whole connected components that lie within the error it
                       already accepts of the rest of the surface (overlapping scans; off by default)
  --json               print PREFIX.json's content instead of text
)";

void printDistance(const Result<DistanceResult>& distance) {
    if (distance.ok())
        std::printf("distance to input: hausdorff %.4g (%.3e of diagonal), mean %.4g (%.3e)\n", distance->hausdorff,
                    distance->hausdorffRel(), distance->mean, distance->meanRel());
}

// Writes the simplified mesh, measures its distance to the input and reports both, as text or as
// one JSON object (`extra_json` adds the method's own fields after the common ones).
int finishSimplified(const std::string& in, const std::string& out, const Mesh& input, const Mesh& output,
                     size_t input_triangles, bool reached_target, bool json, Diagnostics& diagnostics,
                     const std::string& text_extra, const std::function<void(JsonWriter&)>& extra_json) {
    const Status written = writeMesh(output, out, WriteOptions(), diagnostics);
    if (!written.ok()) {
        printDiagnostics(diagnostics);
        return reportError(written);
    }
    Result<DistanceResult> distance = measureSurfaceDistance(input, output);
    printDiagnostics(diagnostics);
    if (json) {
        JsonWriter j;
        j.beginObject();
        j.field("input", in).field("output", out);
        j.field("input_triangles", uint64_t(input_triangles));
        j.field("triangles", uint64_t(output.faceCount()));
        j.field("vertices", uint64_t(output.vertexCount()));
        j.field("reached_target", reached_target);
        extra_json(j);
        if (distance.ok()) writeDistanceJson(j, *distance);
        j.endObject();
        std::fputs(j.str().c_str(), stdout);
        return kExitOk;
    }
    std::printf("wrote %s: %zu vertices, %zu triangles (from %zu)%s%s\n", out.c_str(), output.vertexCount(),
                output.faceCount(), input_triangles, text_extra.c_str(), reached_target ? "" : ", target not reached");
    printDistance(distance);
    return kExitOk;
}

int runMultilevel(Args& args, const std::string& in, const std::string& out) {
    if (args.values.count("--error")) return usageError("--error applies to --method qem only");
    if (args.flags.count("--remove-covered-components"))
        return usageError("--remove-covered-components applies to --method qem only");
    const int targets =
        int(args.values.count("--ratio") + args.values.count("--triangles") + args.values.count("--percentage"));
    if (targets != 1) return usageError("simplify --method multilevel needs exactly one of --percentage, --ratio, --triangles");
    MultilevelOptions options;
    double value = 0;
    if (args.values.count("--percentage")) {
        if (!parseNumber(args.values["--percentage"], value) || !(value >= 0.0 && value < 100.0))
            return usageError("--percentage expects a number in [0, 100), got '" + args.values["--percentage"] + "'");
        options.percentage = value;
    } else if (args.values.count("--ratio")) {
        if (!parseNumber(args.values["--ratio"], value) || !(value > 0.0 && value <= 1.0))
            return usageError("--ratio expects a number in (0, 1], got '" + args.values["--ratio"] + "'");
        options.percentage = 100.0 * (1.0 - value);
    } else if (!parseNumber(args.values["--triangles"], value) || !(value >= 1.0 && value <= 4e9) ||
               value != std::floor(value)) {
        return usageError("--triangles expects a positive integer, got '" + args.values["--triangles"] + "'");
    }
    const double triangles_wanted = args.values.count("--triangles") ? value : 0.0;
    struct Count {
        const char* name;
        uint32_t* target;
        double min;
    };
    for (const Count& c : {Count{"--iterations", &options.iterations, 1.0},
                           Count{"--smoothing-iterations", &options.smoothing_iterations, 0.0}}) {
        if (!args.values.count(c.name)) continue;
        if (!parseNumber(args.values[c.name], value) || !(value >= c.min && value <= 1000.0) ||
            value != std::floor(value))
            return usageError(std::string(c.name) + " expects an integer in [" + std::to_string(int(c.min)) +
                              ", 1000], got '" + args.values[c.name] + "'");
        *c.target = uint32_t(value);
    }
    if (args.values.count("--ple")) {
        if (!parseNumber(args.values["--ple"], value) || !(value > -10.0 && value <= 10.0))
            return usageError("--ple expects a number in (-10, 10], got '" + args.values["--ple"] + "'");
        options.ple = value;
    }
    if (args.values.count("--lambda")) {
        if (!parseNumber(args.values["--lambda"], value) || !(value >= 0.0 && value <= 1e6))
            return usageError("--lambda expects a number in [0, 1e6], got '" + args.values["--lambda"] + "'");
        options.lambda = value;
    }
    options.is_adaptive = !args.flags.count("--no-adaptive");
    options.is_sorted = !args.flags.count("--no-sort");
    options.has_smoothing = !args.flags.count("--no-smoothing");
    options.has_decimation = !args.flags.count("--no-decimation");

    Diagnostics diagnostics;
    Result<LoadedMesh> loaded = readMesh(in, args.read, diagnostics);
    if (!loaded.ok()) {
        printDiagnostics(diagnostics);
        return reportError(loaded.status());
    }
    if (triangles_wanted > 0.0) {
        const double faces = double(loaded->mesh.faceCount());
        options.percentage = faces > 0.0 ? std::max(0.0, std::min(99.0, 100.0 * (1.0 - triangles_wanted / faces))) : 0.0;
    }
    Result<MultilevelOutput> result = simplifyMultilevel(loaded->mesh, options, diagnostics);
    if (!result.ok()) {
        printDiagnostics(diagnostics);
        return reportError(result.status().withPrefix(in));
    }
    char summary[160];
    std::snprintf(summary, sizeof summary, ", %zu of %zu collapses", result->collapses, result->collapses_requested);
    return finishSimplified(in, out, loaded->mesh, result->mesh, result->input_triangles, result->reached_target,
                            args.flags.count("--json") > 0, diagnostics, summary, [&](JsonWriter& j) {
                                j.field("method", "multilevel");
                                j.field("percentage", options.percentage);
                                j.field("collapses", uint64_t(result->collapses));
                                j.field("collapses_requested", uint64_t(result->collapses_requested));
                                j.field("collapses_refused", uint64_t(result->collapses_refused));
                                j.field("length_threshold", result->length_threshold);
                            });
}

} // namespace

int runSimplify(int argc, char** argv) {
    Args args;
    int code = 0;
    if (!parseArgs(argc, argv, 2,
                   {{"--output", "-o", true},
                    {"--ratio", nullptr, true},
                    {"--triangles", nullptr, true},
                    {"--error", nullptr, true},
                    {"--method", nullptr, true},
                    {"--percentage", nullptr, true},
                    {"--iterations", nullptr, true},
                    {"--smoothing-iterations", nullptr, true},
                    {"--ple", nullptr, true},
                    {"--lambda", nullptr, true},
                    {"--no-adaptive", nullptr, false},
                    {"--no-sort", nullptr, false},
                    {"--no-smoothing", nullptr, false},
                    {"--no-decimation", nullptr, false},
                    {"--remove-covered-components", nullptr, false},
                    {"--json", nullptr, false},
                    {"--help", "-h", false}},
                   args, code))
        return code;
    if (args.flags.count("--help")) {
        std::fputs(kSimplifyHelp, stdout);
        std::fputs(kReaderLimitHelp, stdout);
        return kExitOk;
    }
    std::string in, out;
    if (const int c = meshInputAndOutput(args, "simplify", &in, &out); c != kExitOk) return c;
    const std::string method = args.values.count("--method") ? args.values["--method"] : "qem";
    if (method == "multilevel") return runMultilevel(args, in, out);
    if (method != "qem") return usageError("--method expects qem or multilevel, got '" + method + "'");
    for (const char* flag : {"--percentage", "--iterations", "--smoothing-iterations", "--ple", "--lambda",
                             "--no-adaptive", "--no-sort", "--no-smoothing", "--no-decimation"})
        if (args.values.count(flag) || args.flags.count(flag))
            return usageError(std::string(flag) + " applies to --method multilevel only");
    const int targets =
        int(args.values.count("--ratio") + args.values.count("--triangles") + args.values.count("--error"));
    if (targets != 1) return usageError("simplify needs exactly one of --ratio, --triangles, --error");
    SimplifyOptions options;
    options.remove_covered_components = args.flags.count("--remove-covered-components") > 0;
    double value = 0;
    if (args.values.count("--ratio")) {
        if (!parseNumber(args.values["--ratio"], value) || !(value > 0.0 && value <= 1.0))
            return usageError("--ratio expects a number in (0, 1], got '" + args.values["--ratio"] + "'");
        options.target_ratio = float(value);
    } else if (args.values.count("--triangles")) {
        if (!parseNumber(args.values["--triangles"], value) || !(value >= 1.0 && value <= 4e9) ||
            value != std::floor(value))
            return usageError("--triangles expects a positive integer, got '" + args.values["--triangles"] + "'");
        options.target_triangles = uint32_t(value);
    } else {
        if (!parseNumber(args.values["--error"], value) || !(value >= 0.0))
            return usageError("--error expects a non-negative number, got '" + args.values["--error"] + "'");
        options.target_ratio = 0.0f;
        options.max_error = value;
    }

    Diagnostics diagnostics;
    Result<LoadedMesh> loaded = readMesh(in, args.read, diagnostics);
    if (!loaded.ok()) {
        printDiagnostics(diagnostics);
        return reportError(loaded.status());
    }
    Result<SimplifyOutput> result = simplify(loaded->mesh, options, diagnostics);
    if (!result.ok()) {
        printDiagnostics(diagnostics);
        return reportError(result.status().withPrefix(in));
    }
    return finishSimplified(in, out, loaded->mesh, result->mesh, result->input_triangles, result->reached_target,
                            args.flags.count("--json") > 0, diagnostics, "",
                            [&](JsonWriter& j) { j.field("quadric_error", result->max_collapse_error); });
}

int runLods(int argc, char** argv) {
    Args args;
    int code = 0;
    if (!parseArgs(argc, argv, 2,
                   {{"--output", "-o", true},
                    {"--levels", nullptr, true},
                    {"--format", nullptr, true},
                    {"--pixels", nullptr, true},
                    {"--viewport", nullptr, true},
                    {"--fov", nullptr, true},
                    {"--remove-covered-components", nullptr, false},
                    {"--json", nullptr, false},
                    {"--help", "-h", false}},
                   args, code))
        return code;
    if (args.flags.count("--help")) {
        std::fputs(kLodsHelp, stdout);
        std::fputs(kReaderLimitHelp, stdout);
        return kExitOk;
    }
    if (args.positional.size() != 1) return usageError("lods takes exactly one input file");
    if (!args.values.count("--output")) return usageError("lods needs -o PREFIX");
    const std::string& in = args.positional[0];
    std::string prefix = args.values["--output"];
    std::string ext = args.values.count("--format") ? "." + args.values["--format"] : ".ply";
    if (formatFromPath(prefix) != MeshFormat::Unknown) {
        ext = lowerExtension(prefix);
        prefix = prefix.substr(0, prefix.size() - ext.size());
    }
    if (formatFromPath("x" + ext) == MeshFormat::Unknown)
        return usageError("--format '" + ext.substr(1) + "' is unknown, expected ply, obj, off, gltf or glb");
    LodChainOptions options;
    if (args.values.count("--levels")) {
        options.ratios.clear();
        if (!parseList(args.values["--levels"], options.ratios))
            return usageError("--levels expects comma-separated numbers, got '" + args.values["--levels"] + "'");
        for (double r : options.ratios)
            if (!(r > 0.0 && r <= 1.0))
                return usageError("--levels: every ratio must lie in (0, 1], got '" + args.values["--levels"] + "'");
    }
    struct NumberOption {
        const char* name;
        double* target;
    };
    double fov_deg = 60.0;
    for (const NumberOption& n :
         {NumberOption{"--pixels", &options.screen.pixel_threshold},
          NumberOption{"--viewport", &options.screen.viewport_height_px}, NumberOption{"--fov", &fov_deg}}) {
        if (!args.values.count(n.name)) continue;
        if (!parseNumber(args.values[n.name], *n.target) || !(*n.target > 0.0))
            return usageError(std::string(n.name) + " expects a positive number, got '" + args.values[n.name] + "'");
    }
    if (!(fov_deg < 180.0)) return usageError("--fov must be below 180 degrees");
    options.screen.vertical_fov_rad = fov_deg * lodbake::kPi / 180.0;
    options.simplify.remove_covered_components = args.flags.count("--remove-covered-components") > 0;

    Diagnostics diagnostics;
    Result<LoadedMesh> loaded = readMesh(in, args.read, diagnostics);
    if (!loaded.ok()) {
        printDiagnostics(diagnostics);
        return reportError(loaded.status());
    }
    Result<LodChain> chain = buildLodChain(loaded->mesh, options, diagnostics);
    if (!chain.ok()) {
        printDiagnostics(diagnostics);
        return reportError(chain.status().withPrefix(in));
    }
    std::vector<std::string> files;
    for (size_t i = 0; i < chain->levels.size(); ++i) {
        files.push_back(prefix + "_lod" + std::to_string(i) + ext);
        if (isSameFile(in, files.back())) return usageError("output '" + files.back() + "' is the input file");
    }
    for (size_t i = 0; i < chain->levels.size(); ++i) {
        const Status written = writeMesh(chain->levels[i].mesh, files[i], WriteOptions(), diagnostics);
        if (!written.ok()) {
            printDiagnostics(diagnostics);
            return reportError(written);
        }
    }
    JsonWriter j;
    j.beginObject();
    j.field("input", in);
    j.field("input_triangles", uint64_t(loaded->mesh.faceCount()));
    j.field("bounding_radius", chain->bounding_radius);
    j.key("screen").beginObject();
    j.field("pixel_threshold", options.screen.pixel_threshold);
    j.field("viewport_height_px", options.screen.viewport_height_px);
    j.field("vertical_fov_deg", fov_deg);
    j.endObject();
    j.key("levels").beginArray();
    for (size_t i = 0; i < chain->levels.size(); ++i) {
        const LodLevel& level = chain->levels[i];
        j.beginObject();
        j.field("file", files[i]);
        j.field("ratio", level.target_ratio);
        j.field("triangles", uint64_t(level.mesh.faceCount()));
        j.field("vertices", uint64_t(level.mesh.vertexCount()));
        j.field("reached_target", level.reached_target);
        j.field("quadric_error", level.quadric_error);
        if (level.has_distance) writeDistanceJson(j, level.distance);
        j.field("switch_distance", level.switch_distance);
        j.field("screen_coverage", level.screen_coverage);
        j.endObject();
    }
    j.endArray();
    j.endObject();
    const std::string json_path = prefix + ".json";
    const Status json_written = writeFileAtomic(json_path, j.str().data(), j.str().size());
    printDiagnostics(diagnostics);
    if (!json_written.ok()) return reportError(json_written);
    if (args.flags.count("--json")) {
        std::fputs(j.str().c_str(), stdout);
        return kExitOk;
    }
    for (size_t i = 0; i < chain->levels.size(); ++i) {
        const LodLevel& level = chain->levels[i];
        std::printf("%s: %zu triangles, %zu vertices", files[i].c_str(), level.mesh.faceCount(),
                    level.mesh.vertexCount());
        if (level.has_distance)
            std::printf(", hausdorff %.3e mean %.3e (of diagonal)", level.distance.hausdorffRel(),
                        level.distance.meanRel());
        std::printf(", switch at %.4g\n", level.switch_distance);
    }
    std::printf("wrote %s\n", json_path.c_str());
    return kExitOk;
}

} // namespace lodbake::cli
