// lodbake: command-line front end. Argument parsing, printing and exit codes only; every piece of
// work is a library call (STYLE.md §1). Exit codes: 0 ok, 1 input or bake error, 2 usage.

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

namespace {

using namespace lodbake;

constexpr int kExitOk = 0;
constexpr int kExitError = 1;
constexpr int kExitUsage = 2;

const char* kMainHelp = R"(lodbake - offline level-of-detail asset baker

usage: lodbake <command> [options]

commands:
  info IN            print format, counts, attributes, bounds and topology of a mesh file
  convert IN -o OUT  convert between .ply .obj .off .gltf .glb (.conf scan sets as input)
  repair IN -o OUT   weld, remove degenerate faces, make manifold, orient, drop speckle, fill holes, normals
  simplify IN -o OUT simplify to a triangle ratio, count or error (quadric edge collapse)
  lods IN -o PREFIX  build a discrete LOD chain with measured errors and switch distances
  pfrep IN -o OUT.lbp  build a progressive-fans (PFRep) blob; pfrep --extract K IN.lbp -o OUT extracts level K
  bake IN... -o OUT.glb  repair, LOD chain, texture levels: one glTF pack (MSFT_lod + metrics)
  encode IN -o OUT.lbm  compress triangles, positions and normals (docs/format/valence.md)
  decode IN.lbm -o OUT  decompress an .lbm file to .ply .obj .off .gltf or .glb

options:
  -h, --help         show help (also: lodbake <command> --help)
  --version          print the version

exit codes: 0 success, 1 input or processing error, 2 usage error
)";

const char* kInfoHelp = R"(usage: lodbake info IN [--json]

Prints what IN holds: format and encoding, vertex and face counts as stored and as loaded
(triangulated), attribute streams, sub-meshes and materials, bounds, and topology (boundary
edges and loops, components, non-manifold edges and vertices, duplicate and degenerate faces,
unreferenced vertices). Topology is given as stored and, when it differs, with vertices welded
by identical position (UV or normal seams split vertices in most glTF files).

options:
  --json     print one JSON object instead of text
)";

const char* kConvertHelp = R"(usage: lodbake convert IN -o OUT [--ascii]

Reads IN (.ply .obj .off .gltf .glb, or a Stanford .conf range-scan set) and writes OUT in the
format its extension names. Output is written atomically: on any error no output file is left
behind. OUT may not be IN.

options:
  -o, --output OUT   output path (required)
  --ascii            PLY output: ascii instead of binary little endian
)";

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
  --min-component-faces N     drop components with fewer faces (default 50)
  --min-component-area F      drop components under this fraction of the total area (default 0.002)
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

const char* kSimplifyHelp = R"(usage: lodbake simplify IN -o OUT (--ratio R | --triangles N | --error E) [--json]

Simplifies IN by quadric-error edge collapse and writes OUT (format from its extension). Open
borders, UV/normal seams and sub-mesh borders are preserved; non-manifold spots are left as they
are. Prints the result's size and its measured two-sided distance to IN.

options:
  -o, --output OUT   output path (required)
  --ratio R          keep this fraction of the triangles, 0 < R <= 1
  --triangles N      keep about N triangles
  --error E          collapse while the estimated error stays below E (object units)
  --json             print one JSON object instead of text
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
  --json               print PREFIX.json's content instead of text
)";

const char* kBakeHelp = R"(usage: lodbake bake IN... -o OUT.glb [--preset FILE] [options]

Per input: repair -> LOD chain (errors measured against the repaired input, switch distances) ->
texture levels (each level's textures downscaled to its on-screen size) -> one GLB pack. Each input
becomes a LOD group: an MSFT_lod node (highest detail first) with MSFT_screencoverage in its extras
and LODBAKE_lod_metrics; every level is a plain glTF mesh. See docs/bake.md.

options:
  -o, --output OUT.glb  output path (required; written atomically)
  --preset FILE         bake preset (configs/desktop.json, mobile.json, vr.json, archive.json)
  --threads N           worker threads (default: all; the output bytes do not depend on it)
  --levels LIST         override lod_ratios: comma-separated triangle ratios in (0, 1]
  --pixels P            override pixel_threshold
  --compact             put the compressed-stream extensions in extensionsRequired
  --report R.json       write per-level metrics and texture sizes as JSON
  --print-config        print the resolved settings (sorted keys) and exit
)";

/// Parsed command line of one subcommand: flags with optional values and positional arguments.
struct Args {
    std::vector<std::string> positional;
    std::map<std::string, std::string> values;
    std::map<std::string, bool> flags;
};

struct OptionSpec {
    const char* long_name;
    const char* short_name; // may be null
    bool takes_value;
};

int usageError(const std::string& message) {
    std::fprintf(stderr, "error: %s (see lodbake --help)\n", message.c_str());
    return kExitUsage;
}

// Returns false (after printing) on a usage error.
bool parseArgs(int argc, char** argv, int first, const std::vector<OptionSpec>& specs, Args& args, int& exit_code) {
    for (int i = first; i < argc; ++i) {
        const std::string a = argv[i];
        if (a.size() > 1 && a[0] == '-') {
            const OptionSpec* spec = nullptr;
            for (const OptionSpec& s : specs)
                if (a == s.long_name || (s.short_name && a == s.short_name)) spec = &s;
            if (!spec) {
                exit_code = usageError("unknown option '" + a + "'");
                return false;
            }
            if (spec->takes_value) {
                if (i + 1 >= argc) {
                    exit_code = usageError(std::string("option ") + spec->long_name + " needs a value");
                    return false;
                }
                args.values[spec->long_name] = argv[++i];
            } else {
                args.flags[spec->long_name] = true;
            }
        } else {
            args.positional.push_back(a);
        }
    }
    return true;
}

void printDiagnostics(const Diagnostics& diagnostics) {
    for (const Diagnostic& d : diagnostics.items())
        std::fprintf(stderr, "%s: %s\n", d.severity == Severity::Warning ? "warning" : "note", d.message.c_str());
}

int reportError(const Status& status) {
    std::fprintf(stderr, "error: %s\n", status.message().c_str());
    return kExitError;
}

std::string attributeList(const Mesh& mesh) {
    std::string s = "POSITION";
    if (mesh.hasNormals()) s += " NORMAL";
    if (mesh.hasTangents()) s += " TANGENT";
    for (size_t i = 0; i < mesh.uvs.size(); ++i) s += " TEXCOORD_" + std::to_string(i);
    if (mesh.hasColors()) s += " COLOR_0";
    return s;
}

void writeTopologyJson(JsonWriter& j, const TopologyStats& t) {
    j.beginObject();
    j.field("vertices", t.vertex_count);
    j.field("referenced_vertices", t.referenced_vertex_count);
    j.field("unreferenced_vertices", t.unreferenced_vertex_count);
    j.field("faces", t.face_count);
    j.field("edges", t.edge_count);
    j.field("boundary_edges", t.boundary_edge_count);
    j.field("boundary_loops", t.boundary_loop_count);
    j.field("components", t.component_count);
    j.field("non_manifold_edges", t.non_manifold_edge_count);
    j.field("non_manifold_vertices", t.non_manifold_vertex_count);
    j.field("inconsistent_orientation_edges", t.inconsistent_edge_count);
    j.field("degenerate_faces", t.degenerate_face_count);
    j.field("duplicate_faces", t.duplicate_face_count);
    j.field("non_finite_vertices", t.non_finite_vertex_count);
    j.field("euler_characteristic", t.euler_characteristic);
    j.endObject();
}

void printTopologyText(const char* title, const TopologyStats& t) {
    std::printf("%s\n", title);
    std::printf("  vertices            %llu referenced, %llu unreferenced\n",
                (unsigned long long)t.referenced_vertex_count, (unsigned long long)t.unreferenced_vertex_count);
    std::printf("  edges               %llu\n", (unsigned long long)t.edge_count);
    std::printf("  boundary            %llu edges in %llu loops\n", (unsigned long long)t.boundary_edge_count,
                (unsigned long long)t.boundary_loop_count);
    std::printf("  components          %llu\n", (unsigned long long)t.component_count);
    std::printf("  non-manifold        %llu edges, %llu vertices\n", (unsigned long long)t.non_manifold_edge_count,
                (unsigned long long)t.non_manifold_vertex_count);
    std::printf("  orientation         %llu inconsistent edges\n", (unsigned long long)t.inconsistent_edge_count);
    std::printf("  degenerate faces    %llu\n", (unsigned long long)t.degenerate_face_count);
    std::printf("  duplicate faces     %llu\n", (unsigned long long)t.duplicate_face_count);
    std::printf("  non-finite vertices %llu\n", (unsigned long long)t.non_finite_vertex_count);
    std::printf("  euler               %lld\n", (long long)t.euler_characteristic);
}

bool sameTopology(const TopologyStats& a, const TopologyStats& b) {
    return a.vertex_count == b.vertex_count && a.edge_count == b.edge_count &&
           a.boundary_edge_count == b.boundary_edge_count && a.component_count == b.component_count &&
           a.non_manifold_edge_count == b.non_manifold_edge_count &&
           a.non_manifold_vertex_count == b.non_manifold_vertex_count &&
           a.inconsistent_edge_count == b.inconsistent_edge_count;
}

int runInfo(int argc, char** argv) {
    Args args;
    int code = 0;
    if (!parseArgs(argc, argv, 2, {{"--json", nullptr, false}, {"--help", "-h", false}}, args, code)) return code;
    if (args.flags.count("--help")) {
        std::fputs(kInfoHelp, stdout);
        return kExitOk;
    }
    if (args.positional.size() != 1) return usageError("info takes exactly one input file");
    const std::string& path = args.positional[0];

    Diagnostics diagnostics;
    Result<LoadedMesh> loaded = readMesh(path, ReadOptions(), diagnostics);
    printDiagnostics(diagnostics);
    if (!loaded.ok()) return reportError(loaded.status());
    const Mesh& mesh = loaded->mesh;
    const SourceInfo& src = loaded->source;
    const Aabb box = computeBounds(mesh);
    const TopologyStats stored = computeTopologyStats(mesh);
    TopologyOptions weld;
    weld.weld_by_position = true;
    const TopologyStats welded = computeTopologyStats(mesh, weld);

    if (args.flags.count("--json")) {
        JsonWriter j;
        j.beginObject();
        j.field("file", path);
        j.field("format", formatName(src.format));
        j.field("encoding", src.encoding);
        j.key("file_counts").beginObject();
        j.field("vertices", src.file_vertex_count).field("faces", src.file_face_count).field("face_kind", src.face_kind);
        j.endObject();
        j.field("vertices", uint64_t(mesh.vertexCount()));
        j.field("triangles", uint64_t(mesh.faceCount()));
        j.key("attributes").beginArray();
        j.value("POSITION");
        if (mesh.hasNormals()) j.value("NORMAL");
        if (mesh.hasTangents()) j.value("TANGENT");
        for (size_t i = 0; i < mesh.uvs.size(); ++i) j.value("TEXCOORD_" + std::to_string(i));
        if (mesh.hasColors()) j.value("COLOR_0");
        j.endArray();
        j.field("submeshes", uint64_t(mesh.submeshes.size()));
        j.field("materials", uint64_t(mesh.materials.size()));
        j.field("textures", uint64_t(mesh.textures.size()));
        j.key("bounds").beginObject();
        j.key("min").beginArray().value(box.min.x).value(box.min.y).value(box.min.z).endArray();
        j.key("max").beginArray().value(box.max.x).value(box.max.y).value(box.max.z).endArray();
        j.field("diagonal", box.diagonal());
        j.endObject();
        j.key("topology");
        writeTopologyJson(j, stored);
        j.key("topology_welded_by_position");
        writeTopologyJson(j, welded);
        j.key("files_read").beginArray();
        for (const std::string& f : src.files_read) j.value(f);
        j.endArray();
        j.endObject();
        std::fputs(j.str().c_str(), stdout);
        return kExitOk;
    }

    std::printf("file                %s\n", path.c_str());
    std::printf("format              %s %s\n", formatName(src.format), src.encoding.c_str());
    std::printf("in file             %llu vertices, %llu %s\n", (unsigned long long)src.file_vertex_count,
                (unsigned long long)src.file_face_count, src.face_kind.c_str());
    std::printf("loaded              %zu vertices, %zu triangles\n", mesh.vertexCount(), mesh.faceCount());
    std::printf("attributes          %s\n", attributeList(mesh).c_str());
    std::printf("sub-meshes          %zu (%zu materials, %zu textures)\n", mesh.submeshes.size(), mesh.materials.size(),
                mesh.textures.size());
    for (size_t m = 0; m < mesh.materials.size(); ++m)
        std::printf("  material %zu        %s\n", m, mesh.materials[m].name.c_str());
    std::printf("bounds              [%g %g %g] .. [%g %g %g]  diagonal %g\n", box.min.x, box.min.y, box.min.z, box.max.x,
                box.max.y, box.max.z, box.diagonal());
    printTopologyText("topology (as stored)", stored);
    if (!sameTopology(stored, welded)) printTopologyText("topology (vertices welded by position)", welded);
    return kExitOk;
}

int runConvert(int argc, char** argv) {
    Args args;
    int code = 0;
    if (!parseArgs(argc, argv, 2, {{"--output", "-o", true}, {"--ascii", nullptr, false}, {"--help", "-h", false}},
                   args, code))
        return code;
    if (args.flags.count("--help")) {
        std::fputs(kConvertHelp, stdout);
        return kExitOk;
    }
    if (args.positional.size() != 1) return usageError("convert takes exactly one input file");
    if (!args.values.count("--output")) return usageError("convert needs -o OUT");
    const std::string& in = args.positional[0];
    const std::string& out = args.values["--output"];
    if (formatFromPath(out) == MeshFormat::Unknown || formatFromPath(out) == MeshFormat::Conf)
        return usageError("output '" + out + "' has an unknown extension, expected .ply .obj .off .gltf or .glb");
    if (isSameFile(in, out)) return usageError("output '" + out + "' is the input file; the input is never modified");

    Diagnostics diagnostics;
    Result<LoadedMesh> loaded = readMesh(in, ReadOptions(), diagnostics);
    if (!loaded.ok()) {
        printDiagnostics(diagnostics);
        return reportError(loaded.status());
    }
    WriteOptions wopt;
    wopt.ply_binary = !args.flags.count("--ascii");
    const Status written = writeMesh(loaded->mesh, out, wopt, diagnostics);
    printDiagnostics(diagnostics);
    if (!written.ok()) return reportError(written);
    std::printf("wrote %s: %zu vertices, %zu triangles\n", out.c_str(), loaded->mesh.vertexCount(),
                loaded->mesh.faceCount());
    return kExitOk;
}

bool parseNumber(const std::string& text, double& out) {
    char* end = nullptr;
    out = std::strtod(text.c_str(), &end);
    return !text.empty() && end && *end == '\0' && std::isfinite(out);
}

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
        return kExitOk;
    }
    if (args.positional.size() != 1) return usageError("repair takes exactly one input file");
    if (!args.values.count("--output")) return usageError("repair needs -o OUT");
    const std::string& in = args.positional[0];
    const std::string& out = args.values["--output"];
    if (formatFromPath(out) == MeshFormat::Unknown)
        return usageError("output '" + out + "' has an unknown extension, expected .ply .obj .off .gltf or .glb");
    if (isSameFile(in, out)) return usageError("output '" + out + "' is the input file; the input is never modified");

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
    Result<LoadedMesh> loaded = readMesh(in, ReadOptions(), diagnostics);
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

void writeDistanceJson(JsonWriter& j, const DistanceResult& d) {
    j.field("hausdorff", d.hausdorff).field("hausdorff_rel", d.hausdorffRel());
    j.field("mean", d.mean).field("mean_rel", d.meanRel());
    j.field("rms", d.rms).field("rms_rel", d.rmsRel());
}

int runSimplify(int argc, char** argv) {
    Args args;
    int code = 0;
    if (!parseArgs(argc, argv, 2,
                   {{"--output", "-o", true},
                    {"--ratio", nullptr, true},
                    {"--triangles", nullptr, true},
                    {"--error", nullptr, true},
                    {"--json", nullptr, false},
                    {"--help", "-h", false}},
                   args, code))
        return code;
    if (args.flags.count("--help")) {
        std::fputs(kSimplifyHelp, stdout);
        return kExitOk;
    }
    if (args.positional.size() != 1) return usageError("simplify takes exactly one input file");
    if (!args.values.count("--output")) return usageError("simplify needs -o OUT");
    const std::string& in = args.positional[0];
    const std::string& out = args.values["--output"];
    if (formatFromPath(out) == MeshFormat::Unknown)
        return usageError("output '" + out + "' has an unknown extension, expected .ply .obj .off .gltf or .glb");
    if (isSameFile(in, out)) return usageError("output '" + out + "' is the input file; the input is never modified");
    const int targets =
        int(args.values.count("--ratio") + args.values.count("--triangles") + args.values.count("--error"));
    if (targets != 1) return usageError("simplify needs exactly one of --ratio, --triangles, --error");
    SimplifyOptions options;
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
    Result<LoadedMesh> loaded = readMesh(in, ReadOptions(), diagnostics);
    if (!loaded.ok()) {
        printDiagnostics(diagnostics);
        return reportError(loaded.status());
    }
    Result<SimplifyOutput> result = simplify(loaded->mesh, options, diagnostics);
    if (!result.ok()) {
        printDiagnostics(diagnostics);
        return reportError(result.status().withPrefix(in));
    }
    const Status written = writeMesh(result->mesh, out, WriteOptions(), diagnostics);
    if (!written.ok()) {
        printDiagnostics(diagnostics);
        return reportError(written);
    }
    Result<DistanceResult> distance = measureSurfaceDistance(loaded->mesh, result->mesh);
    printDiagnostics(diagnostics);
    if (args.flags.count("--json")) {
        JsonWriter j;
        j.beginObject();
        j.field("input", in).field("output", out);
        j.field("input_triangles", uint64_t(result->input_triangles));
        j.field("triangles", uint64_t(result->mesh.faceCount()));
        j.field("vertices", uint64_t(result->mesh.vertexCount()));
        j.field("reached_target", result->reached_target);
        j.field("quadric_error", result->max_collapse_error);
        if (distance.ok()) writeDistanceJson(j, *distance);
        j.endObject();
        std::fputs(j.str().c_str(), stdout);
        return kExitOk;
    }
    std::printf("wrote %s: %zu vertices, %zu triangles (from %zu)%s\n", out.c_str(), result->mesh.vertexCount(),
                result->mesh.faceCount(), result->input_triangles,
                result->reached_target ? "" : ", target not reached");
    if (distance.ok())
        std::printf("distance to input: hausdorff %.4g (%.3e of diagonal), mean %.4g (%.3e)\n", distance->hausdorff,
                    distance->hausdorffRel(), distance->mean, distance->meanRel());
    return kExitOk;
}

// Splits "1,0.5" into numbers; false on any malformed item.
bool parseList(const std::string& text, std::vector<double>& out) {
    size_t start = 0;
    while (start <= text.size()) {
        const size_t comma = text.find(',', start);
        const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        double v = 0;
        if (!parseNumber(item, v)) return false;
        out.push_back(v);
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    return !out.empty();
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
                    {"--json", nullptr, false},
                    {"--help", "-h", false}},
                   args, code))
        return code;
    if (args.flags.count("--help")) {
        std::fputs(kLodsHelp, stdout);
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
    options.screen.vertical_fov_rad = fov_deg * 3.14159265358979323846 / 180.0;

    Diagnostics diagnostics;
    Result<LoadedMesh> loaded = readMesh(in, ReadOptions(), diagnostics);
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

const char* kPfrepHelp = R"(usage: lodbake pfrep IN -o OUT.lbp [--ratio R]
       lodbake pfrep --extract K IN.lbp -o OUT

Builds a PFRep blob (progressive fans, docs/format/pfrep.md) from a half-edge-collapse
simplification of IN down to R of its triangles (default 0: as far as valid collapses go), or
extracts from a blob the mesh after K vertex removals (0: full detail) and writes it as a mesh
file (.ply .obj .off .gltf .glb; positions only, dequantized).

options:
  -o, --output OUT   output file
  --ratio R          target fraction of triangles in [0, 1] (build only)
  --extract K        extract level K instead of building
)";

int runPfrep(int argc, char** argv) {
    Args args;
    int code = 0;
    if (!parseArgs(argc, argv, 2,
                   {{"--output", "-o", true}, {"--ratio", nullptr, true}, {"--extract", nullptr, true},
                    {"--help", "-h", false}},
                   args, code))
        return code;
    if (args.flags.count("--help")) {
        std::fputs(kPfrepHelp, stdout);
        return kExitOk;
    }
    if (args.positional.size() != 1) return usageError("pfrep takes exactly one input file");
    if (!args.values.count("--output")) return usageError("pfrep needs -o OUT");
    const std::string& in = args.positional[0];
    const std::string& out = args.values["--output"];
    if (isSameFile(in, out)) return usageError("output '" + out + "' is the input file; the input is never modified");
    Diagnostics diagnostics;
    if (args.values.count("--extract")) {
        if (args.values.count("--ratio")) return usageError("--ratio applies to building, not to --extract");
        double level = 0;
        if (!parseNumber(args.values["--extract"], level) || !(level >= 0 && level <= 4e9) || level != std::floor(level))
            return usageError("--extract expects a non-negative integer, got '" + args.values["--extract"] + "'");
        if (formatFromPath(out) == MeshFormat::Unknown)
            return usageError("output '" + out + "' has an unknown extension, expected .ply .obj .off .gltf or .glb");
        Result<std::vector<uint8_t>> bytes = readFileBytes(in);
        if (!bytes.ok()) return reportError(bytes.status());
        lodrt::PfrepModel model;
        const lodrt::Result opened = lodrt::openPfrep(bytes->data(), bytes->size(), &model);
        if (opened != lodrt::Result::Ok)
            return reportError(invalidInput(in + ": pfrep blob: " + lodrt::resultName(opened)));
        if (level > model.removed_count)
            return reportError(invalidInput(in + ": --extract " + args.values["--extract"] + ": the blob has levels 0.." +
                                            std::to_string(model.removed_count)));
        Mesh mesh;
        std::vector<float> positions(size_t(model.vertex_count) * 3);
        lodrt::pfrepDecodePositions(model, positions.data(), positions.size());
        std::vector<uint32_t> indices(lodrt::pfrepMaxTriangles(model) * 3);
        size_t count = 0;
        const lodrt::Result extracted =
            lodrt::pfrepExtractLevel(model, uint32_t(level), indices.data(), indices.size() / 3, &count);
        if (extracted != lodrt::Result::Ok)
            return reportError(invalidInput(in + ": pfrep level " + args.values["--extract"] + ": " +
                                            lodrt::resultName(extracted)));
        // Only the vertices the level references, in first-use order.
        std::vector<uint32_t> remap(model.vertex_count, 0xffffffffu);
        for (size_t c = 0; c < count * 3; ++c) {
            uint32_t& r = remap[indices[c]];
            if (r == 0xffffffffu) {
                r = uint32_t(mesh.positions.size());
                const float* p = &positions[size_t(indices[c]) * 3];
                mesh.positions.push_back(Vec3f(p[0], p[1], p[2]));
            }
            mesh.indices.push_back(r);
        }
        const Status written = writeMesh(mesh, out, WriteOptions(), diagnostics);
        printDiagnostics(diagnostics);
        if (!written.ok()) return reportError(written);
        std::printf("%s: level %u of %u: %zu triangles, %zu vertices\n", out.c_str(), unsigned(level),
                    unsigned(model.removed_count), count, mesh.positions.size());
        return kExitOk;
    }
    PfrepOptions options;
    if (args.values.count("--ratio")) {
        double value = 0;
        if (!parseNumber(args.values["--ratio"], value) || !(value >= 0.0 && value <= 1.0))
            return usageError("--ratio expects a number in [0, 1], got '" + args.values["--ratio"] + "'");
        options.target_ratio = float(value);
    }
    Result<LoadedMesh> loaded = readMesh(in, ReadOptions(), diagnostics);
    if (!loaded.ok()) {
        printDiagnostics(diagnostics);
        return reportError(loaded.status());
    }
    Result<PfrepBuild> build = buildPfrep(loaded->mesh, options, diagnostics);
    if (!build.ok()) {
        printDiagnostics(diagnostics);
        return reportError(build.status().withPrefix(in));
    }
    const Status written = writeFileAtomic(out, build->blob.data(), build->blob.size());
    printDiagnostics(diagnostics);
    if (!written.ok()) return reportError(written);
    const size_t vertices = build->rank_point.size();
    std::printf("%s: %zu vertices (%zu removable), %zu triangles at level 0, %zu stored, %zu bytes (%.2f bytes/vertex)\n",
                out.c_str(), vertices, build->removed, build->level0_triangles, build->stored_triangles,
                build->blob.size(), vertices ? double(build->blob.size()) / double(vertices) : 0.0);
    return kExitOk;
}

const char* kEncodeHelp = R"(usage: lodbake encode IN -o OUT.lbm [--bits 14] [--normal-bits 10] [--no-normals] [--json]

Compresses IN's triangles, positions (quantized in the bounding cube) and normals (octahedral)
into the .lbm format (docs/format/valence.md). Triangles come back exactly, as index triples over
the decoded vertex order (vertices and triangles may be reordered, triangles rotated). UV sets,
colours, tangents and materials are not coded (a warning says so).

options:
  --bits N          position quantization bits, 8..16 (default 14)
  --normal-bits N   octahedral normal bits per component, 4..16 (default 10)
  --no-normals      do not code normals even if IN has them
  --json            print bytes and bits per vertex of each stream as JSON
)";

const char* kDecodeHelp = R"(usage: lodbake decode IN.lbm -o OUT

Decodes an .lbm file and writes it as .ply .obj .off .gltf or .glb.
)";

int runEncode(int argc, char** argv) {
    Args args;
    int code = 0;
    if (!parseArgs(argc, argv, 2,
                   {{"--output", "-o", true}, {"--bits", nullptr, true}, {"--normal-bits", nullptr, true},
                    {"--no-normals", nullptr, false}, {"--json", nullptr, false}, {"--help", "-h", false}},
                   args, code))
        return code;
    if (args.flags.count("--help")) {
        std::fputs(kEncodeHelp, stdout);
        return kExitOk;
    }
    if (args.positional.size() != 1) return usageError("encode takes exactly one input file");
    if (!args.values.count("--output")) return usageError("encode needs -o OUT.lbm");
    const std::string& in = args.positional[0];
    const std::string& out = args.values["--output"];
    if (lowerExtension(out) != ".lbm") return usageError("output '" + out + "' must end in .lbm");
    if (isSameFile(in, out)) return usageError("output '" + out + "' is the input file; the input is never modified");
    codec::ValenceEncodeOptions options;
    for (auto [flag, field, lo, hi] : {std::make_tuple("--bits", &options.position_bits, 8u, 16u),
                                       std::make_tuple("--normal-bits", &options.normal_bits, 4u, 16u)}) {
        if (!args.values.count(flag)) continue;
        double v = 0.0;
        if (!parseNumber(args.values[flag], v) || v != std::floor(v) || v < lo || v > hi)
            return usageError(std::string(flag) + " expects an integer in [" + std::to_string(lo) + ", " +
                              std::to_string(hi) + "], got '" + args.values[flag] + "'");
        *field = uint32_t(v);
    }
    options.encode_normals = !args.flags.count("--no-normals");

    Diagnostics diagnostics;
    Result<LoadedMesh> loaded = readMesh(in, ReadOptions(), diagnostics);
    printDiagnostics(diagnostics);
    if (!loaded.ok()) return reportError(loaded.status());
    const Mesh& mesh = loaded->mesh;
    if (!mesh.uvs.empty() || mesh.hasColors() || mesh.hasTangents() || !mesh.materials.empty())
        std::fprintf(stderr, "warning: %s: UV sets, colours, tangents and materials are not coded in .lbm\n",
                     in.c_str());
    Result<codec::ValenceEncodeResult> encoded = codec::encodeValence(mesh, options);
    if (!encoded.ok()) return reportError(encoded.status().withPrefix(in));
    const Status written = writeFileAtomic(out, encoded->bytes.data(), encoded->bytes.size());
    if (!written.ok()) return reportError(written);
    const double vn = mesh.vertexCount() > 0 ? double(mesh.vertexCount()) : 1.0;
    if (args.flags.count("--json")) {
        JsonWriter j;
        j.beginObject();
        j.field("output", out);
        j.field("vertices", uint64_t(mesh.vertexCount()));
        j.field("triangles", uint64_t(mesh.faceCount()));
        j.field("position_bits", uint64_t(options.position_bits));
        j.field("bytes", uint64_t(encoded->bytes.size()));
        j.field("bits_per_vertex", double(encoded->bytes.size()) * 8.0 / vn);
        j.field("header_bytes", uint64_t(encoded->header_bytes));
        for (auto [name, bytes] : {std::make_pair("connectivity", encoded->connectivity_bytes),
                                   std::make_pair("positions", encoded->position_bytes),
                                   std::make_pair("normals", encoded->normal_bytes)}) {
            j.key(name).beginObject();
            j.field("bytes", uint64_t(bytes));
            j.field("bits_per_vertex", double(bytes) * 8.0 / vn);
            j.endObject();
        }
        j.field("max_position_error", encoded->max_position_error);
        j.endObject();
        std::fputs(j.str().c_str(), stdout);
        std::fputs("\n", stdout);
        return kExitOk;
    }
    std::printf("wrote %s: %zu bytes (%.2f bits/vertex: connectivity %.2f, positions %.2f, normals %.2f)\n",
                out.c_str(), encoded->bytes.size(), double(encoded->bytes.size()) * 8.0 / vn,
                double(encoded->connectivity_bytes) * 8.0 / vn, double(encoded->position_bytes) * 8.0 / vn,
                double(encoded->normal_bytes) * 8.0 / vn);
    return kExitOk;
}

int runDecode(int argc, char** argv) {
    Args args;
    int code = 0;
    if (!parseArgs(argc, argv, 2, {{"--output", "-o", true}, {"--help", "-h", false}}, args, code)) return code;
    if (args.flags.count("--help")) {
        std::fputs(kDecodeHelp, stdout);
        return kExitOk;
    }
    if (args.positional.size() != 1) return usageError("decode takes exactly one input file");
    if (!args.values.count("--output")) return usageError("decode needs -o OUT");
    const std::string& in = args.positional[0];
    const std::string& out = args.values["--output"];
    if (formatFromPath(out) == MeshFormat::Unknown || formatFromPath(out) == MeshFormat::Conf)
        return usageError("output '" + out + "' has an unknown extension, expected .ply .obj .off .gltf or .glb");
    if (isSameFile(in, out)) return usageError("output '" + out + "' is the input file; the input is never modified");
    Result<std::vector<uint8_t>> bytes = readFileBytes(in);
    if (!bytes.ok()) return reportError(bytes.status());
    Result<Mesh> mesh = codec::decodeValence(*bytes, in);
    if (!mesh.ok()) return reportError(mesh.status());
    Diagnostics diagnostics;
    const Status written = writeMesh(*mesh, out, WriteOptions(), diagnostics);
    printDiagnostics(diagnostics);
    if (!written.ok()) return reportError(written);
    std::printf("wrote %s: %zu vertices, %zu triangles\n", out.c_str(), mesh->vertexCount(), mesh->faceCount());
    return kExitOk;
}

} // namespace

int runBake(int argc, char** argv) {
    Args args;
    int code = 0;
    if (!parseArgs(argc, argv, 2,
                   {{"--output", "-o", true},
                    {"--preset", nullptr, true},
                    {"--threads", nullptr, true},
                    {"--levels", nullptr, true},
                    {"--pixels", nullptr, true},
                    {"--compact", nullptr, false},
                    {"--report", nullptr, true},
                    {"--print-config", nullptr, false},
                    {"--help", "-h", false}},
                   args, code))
        return code;
    if (args.flags.count("--help")) {
        std::fputs(kBakeHelp, stdout);
        return kExitOk;
    }
    BakeSettings settings;
    if (args.values.count("--preset")) {
        const Status status = applyPresetFile(args.values["--preset"], settings);
        if (!status.ok()) return reportError(status);
    }
    if (args.values.count("--threads")) {
        double n = 0;
        if (!parseNumber(args.values["--threads"], n) || n < 0 || n > 1024 || n != std::floor(n))
            return usageError("--threads expects an integer in [0, 1024], got '" + args.values["--threads"] + "'");
        settings.threads = uint32_t(n);
    }
    if (args.values.count("--levels")) {
        std::vector<double> ratios;
        if (!parseList(args.values["--levels"], ratios) || ratios.empty())
            return usageError("--levels expects comma-separated numbers, got '" + args.values["--levels"] + "'");
        for (double r : ratios)
            if (!(r > 0.0 && r <= 1.0))
                return usageError("--levels: every ratio must lie in (0, 1], got '" + args.values["--levels"] + "'");
        settings.lod_ratios = ratios;
    }
    if (args.values.count("--pixels")) {
        double p = 0;
        if (!parseNumber(args.values["--pixels"], p) || !(p > 0))
            return usageError("--pixels expects a positive number, got '" + args.values["--pixels"] + "'");
        settings.pixel_threshold = p;
    }
    if (args.flags.count("--compact")) settings.compact = true;
    if (args.flags.count("--print-config")) {
        std::fputs(settingsToJson(settings).c_str(), stdout);
        return kExitOk;
    }
    if (args.positional.empty()) return usageError("bake needs at least one input file");
    if (!args.values.count("--output")) return usageError("bake needs -o OUT.glb");
    const std::string out = args.values["--output"];
    if (lowerExtension(out) != ".glb") return usageError("bake writes a .glb pack, got '" + out + "'");
    Diagnostics diagnostics;
    std::vector<BakeInput> inputs;
    for (const std::string& in : args.positional) {
        if (isSameFile(in, out)) return usageError("output '" + out + "' is also an input");
        Result<LoadedMesh> loaded = readMesh(in, ReadOptions{}, diagnostics);
        if (!loaded.ok()) {
            printDiagnostics(diagnostics);
            return reportError(loaded.status());
        }
        std::string stem = in.substr(in.find_last_of("/\\") == std::string::npos ? 0 : in.find_last_of("/\\") + 1);
        stem = stem.substr(0, stem.find_last_of('.'));
        inputs.push_back({stem, std::move(loaded->mesh)});
    }
    Result<BakeOutput> baked = bake(std::move(inputs), settings, diagnostics);
    printDiagnostics(diagnostics);
    if (!baked.ok()) return reportError(baked.status());
    AtomicFileWriter writer;
    Status status = writer.add(out, baked->glb.data(), baked->glb.size());
    std::string report;
    if (status.ok() && args.values.count("--report")) {
        report = bakeReportJson(*baked, settings);
        status = writer.add(args.values["--report"], report.data(), report.size());
    }
    if (status.ok()) status = writer.commit();
    if (!status.ok()) return reportError(status);
    for (const BakeAssetReport& a : baked->assets) {
        std::printf("%s: %llu triangles -> %zu levels:", a.name.c_str(),
                    static_cast<unsigned long long>(a.input_triangles), a.metrics.levels.size());
        for (const LodMetricsLevel& l : a.metrics.levels)
            std::printf(" %llu", static_cast<unsigned long long>(l.triangles));
        std::printf("\n");
    }
    std::printf("wrote %s (%zu bytes)\n", out.c_str(), baked->glb.size());
    return kExitOk;
}

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fputs(kMainHelp, stderr);
        return kExitUsage;
    }
    const std::string cmd = argv[1];
    if (cmd == "--help" || cmd == "-h" || cmd == "help") {
        std::fputs(kMainHelp, stdout);
        return kExitOk;
    }
    if (cmd == "--version") {
        std::printf("lodbake %s\n", lodbake::kVersionString);
        return kExitOk;
    }
    if (cmd == "info") return runInfo(argc, argv);
    if (cmd == "convert") return runConvert(argc, argv);
    if (cmd == "simplify") return runSimplify(argc, argv);
    if (cmd == "lods") return runLods(argc, argv);
    if (cmd == "pfrep") return runPfrep(argc, argv);
    if (cmd == "repair") return runRepair(argc, argv);
    if (cmd == "bake") return runBake(argc, argv);
    if (cmd == "encode") return runEncode(argc, argv);
    if (cmd == "decode") return runDecode(argc, argv);
    return usageError("unknown command '" + cmd + "'");
}
