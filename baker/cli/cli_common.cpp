// Shared pieces of the lodbake command-line front end (see cli_common.h).

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

int usageError(const std::string& message) {
    std::fprintf(stderr, "error: %s (see lodbake --help)\n", message.c_str());
    return kExitUsage;
}

int inputAndOutput(const Args& args, const char* command, const char* output_form, std::string* in,
                   std::string* out) {
    if (args.positional.size() != 1) return usageError(std::string(command) + " takes exactly one input file");
    const auto output = args.values.find("--output");
    if (output == args.values.end()) return usageError(std::string(command) + " needs -o " + output_form);
    *in = args.positional[0];
    *out = output->second;
    if (isSameFile(*in, *out)) return usageError("output '" + *out + "' is the input file; the input is never modified");
    return kExitOk;
}

int meshInputAndOutput(const Args& args, const char* command, std::string* in, std::string* out) {
    if (const int code = inputAndOutput(args, command, "OUT", in, out); code != kExitOk) return code;
    const MeshFormat format = formatFromPath(*out);
    if (format == MeshFormat::Unknown || format == MeshFormat::Conf) // .conf scan sets are read, never written
        return usageError("output '" + *out + "' has an unknown extension, expected .ply .obj .off .gltf or .glb");
    return kExitOk;
}

// Returns false (after printing) on a usage error.
const char* const kReaderLimitHelp =
    "Input limits (any subcommand; files claiming more are refused before anything is allocated):\n"
    "  --max-vertices N            most vertices an input may declare (default 268435456)\n"
    "  --max-faces N               most faces an input may declare, after triangulation (default 268435456)\n";

namespace {

// "--max-vertices N" / "--max-faces N": a whole number from 1 to 2^32.
bool parseReaderLimit(const std::string& name, const std::string& text, uint64_t& out, int& exit_code) {
    double v = 0;
    if (!parseNumber(text, v) || v < 1 || v > 4294967296.0 || v != double(uint64_t(v))) {
        exit_code = usageError(name + " expects a whole number from 1 to 4294967296, got '" + text + "'");
        return false;
    }
    out = uint64_t(v);
    return true;
}

} // namespace

bool parseArgs(int argc, char** argv, int first, const std::vector<OptionSpec>& specs, Args& args, int& exit_code) {
    for (int i = first; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--max-vertices" || a == "--max-faces") {
            if (i + 1 >= argc) {
                exit_code = usageError("option " + a + " needs a value");
                return false;
            }
            uint64_t& limit = a == "--max-vertices" ? args.read.max_vertex_count : args.read.max_face_count;
            if (!parseReaderLimit(a, argv[++i], limit, exit_code)) return false;
            continue;
        }
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

bool parseNumber(const std::string& text, double& out) {
    char* end = nullptr;
    out = std::strtod(text.c_str(), &end);
    return !text.empty() && end && *end == '\0' && std::isfinite(out);
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

void writeDistanceJson(JsonWriter& j, const DistanceResult& d) {
    j.field("hausdorff", d.hausdorff).field("hausdorff_rel", d.hausdorffRel());
    j.field("mean", d.mean).field("mean_rel", d.meanRel());
    j.field("rms", d.rms).field("rms_rel", d.rmsRel());
}

} // namespace lodbake::cli
