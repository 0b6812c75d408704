// lodbake info and lodbake convert.

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

bool sameTopology(const TopologyStats& a, const TopologyStats& b) {
    return a.vertex_count == b.vertex_count && a.edge_count == b.edge_count &&
           a.boundary_edge_count == b.boundary_edge_count && a.component_count == b.component_count &&
           a.non_manifold_edge_count == b.non_manifold_edge_count &&
           a.non_manifold_vertex_count == b.non_manifold_vertex_count &&
           a.inconsistent_edge_count == b.inconsistent_edge_count;
}

} // namespace

int runInfo(int argc, char** argv) {
    Args args;
    int code = 0;
    if (!parseArgs(argc, argv, 2, {{"--json", nullptr, false}, {"--help", "-h", false}}, args, code)) return code;
    if (args.flags.count("--help")) {
        std::fputs(kInfoHelp, stdout);
        std::fputs(kReaderLimitHelp, stdout);
        return kExitOk;
    }
    if (args.positional.size() != 1) return usageError("info takes exactly one input file");
    const std::string& path = args.positional[0];

    Diagnostics diagnostics;
    Result<LoadedMesh> loaded = readMesh(path, args.read, diagnostics);
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
        std::fputs(kReaderLimitHelp, stdout);
        return kExitOk;
    }
    std::string in, out;
    if (const int c = meshInputAndOutput(args, "convert", &in, &out); c != kExitOk) return c;

    Diagnostics diagnostics;
    Result<LoadedMesh> loaded = readMesh(in, args.read, diagnostics);
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

} // namespace lodbake::cli
