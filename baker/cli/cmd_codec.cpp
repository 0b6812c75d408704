// lodbake encode and lodbake decode (the .lbm valence codec).

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
#include "lodrt/format.h"
#include "lodrt/pfrep.h"

#include "cli_common.h"

namespace lodbake::cli {

namespace {

const char* kEncodeHelp = R"(usage: lodbake encode IN -o OUT.lbm [--bits 14] [--normal-bits 10] [--uv-bits 12]
                      [--color-bits 8] [--tangent-bits 10] [--no-normals] [--no-attributes] [--json]

Compresses IN's triangles, positions (quantized in the bounding cube), normals (octahedral), UV
sets, vertex colours and tangents into the .lbm format (docs/format/valence.md). Triangles come back
exactly, as index triples over the decoded vertex order (vertices and triangles may be reordered,
triangles rotated). Materials are not coded (a warning says so).

options:
  --bits N          position quantization bits, 8..16 (default 14)
  --normal-bits N   octahedral normal bits per component, 4..16 (default 10)
  --uv-bits N       UV quantization bits per component, 4..16 (default 12)
  --color-bits N    colour quantization bits per channel, 4..16 (default 8)
  --tangent-bits N  octahedral tangent bits per component, 4..16 (default 10)
  --no-normals      do not code normals even if IN has them
  --no-attributes   do not code UV sets, colours and tangents
  --json            print bytes and bits per vertex of each stream and attribute as JSON
)";

const char* kDecodeHelp = R"(usage: lodbake decode IN.lbm -o OUT

Decodes an .lbm file (positions, normals, UV sets, colours, tangents) and writes it as .ply .obj .off
.gltf or .glb (each format keeps the attributes it can hold).
)";

// The --json name of an attribute kind (lodrt/format.h).
const char* attributeName(uint32_t kind) {
    if (kind == lodrt::format::kValenceAttributeUv) return "uv";
    if (kind == lodrt::format::kValenceAttributeColor) return "color";
    return "tangent";
}

} // namespace

int runEncode(int argc, char** argv) {
    Args args;
    int code = 0;
    if (!parseArgs(argc, argv, 2,
                   {{"--output", "-o", true}, {"--bits", nullptr, true}, {"--normal-bits", nullptr, true},
                    {"--uv-bits", nullptr, true}, {"--color-bits", nullptr, true}, {"--tangent-bits", nullptr, true},
                    {"--no-normals", nullptr, false}, {"--no-attributes", nullptr, false}, {"--json", nullptr, false},
                    {"--help", "-h", false}},
                   args, code))
        return code;
    if (args.flags.count("--help")) {
        std::fputs(kEncodeHelp, stdout);
        std::fputs(kReaderLimitHelp, stdout);
        return kExitOk;
    }
    std::string in, out;
    if (const int c = inputAndOutput(args, "encode", "OUT.lbm", &in, &out); c != kExitOk) return c;
    if (lowerExtension(out) != ".lbm") return usageError("output '" + out + "' must end in .lbm");
    codec::ValenceEncodeOptions options;
    for (auto [flag, field, lo, hi] : {std::make_tuple("--bits", &options.position_bits, 8u, 16u),
                                       std::make_tuple("--normal-bits", &options.normal_bits, 4u, 16u),
                                       std::make_tuple("--uv-bits", &options.uv_bits, 4u, 16u),
                                       std::make_tuple("--color-bits", &options.color_bits, 4u, 16u),
                                       std::make_tuple("--tangent-bits", &options.tangent_bits, 4u, 16u)}) {
        if (!args.values.count(flag)) continue;
        double v = 0.0;
        if (!parseNumber(args.values[flag], v) || v != std::floor(v) || v < lo || v > hi)
            return usageError(std::string(flag) + " expects an integer in [" + std::to_string(lo) + ", " +
                              std::to_string(hi) + "], got '" + args.values[flag] + "'");
        *field = uint32_t(v);
    }
    options.encode_normals = !args.flags.count("--no-normals");
    options.encode_attributes = !args.flags.count("--no-attributes");

    Diagnostics diagnostics;
    Result<LoadedMesh> loaded = readMesh(in, args.read, diagnostics);
    printDiagnostics(diagnostics);
    if (!loaded.ok()) return reportError(loaded.status());
    const Mesh& mesh = loaded->mesh;
    if (!mesh.materials.empty())
        std::fprintf(stderr, "warning: %s: materials are not coded in .lbm\n", in.c_str());
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
        j.key("attributes").beginArray();
        for (const codec::ValenceAttributeReport& a : encoded->attributes) {
            j.beginObject();
            j.field("kind", attributeName(a.kind));
            j.field("set", uint64_t(a.set));
            j.field("bits", uint64_t(a.bits));
            j.field("bytes", uint64_t(a.bytes));
            j.field("bits_per_vertex", double(a.bytes) * 8.0 / vn);
            j.field("max_error", a.max_error);
            j.endObject();
        }
        j.endArray();
        j.endObject();
        std::fputs(j.str().c_str(), stdout);
        std::fputs("\n", stdout);
        return kExitOk;
    }
    std::printf("wrote %s: %zu bytes (%.2f bits/vertex: connectivity %.2f, positions %.2f, normals %.2f",
                out.c_str(), encoded->bytes.size(), double(encoded->bytes.size()) * 8.0 / vn,
                double(encoded->connectivity_bytes) * 8.0 / vn, double(encoded->position_bytes) * 8.0 / vn,
                double(encoded->normal_bytes) * 8.0 / vn);
    for (const codec::ValenceAttributeReport& a : encoded->attributes)
        std::printf(", %s %u: %.2f", attributeName(a.kind), a.set, double(a.bytes) * 8.0 / vn);
    std::printf(")\n");
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
    std::string in, out;
    if (const int c = meshInputAndOutput(args, "decode", &in, &out); c != kExitOk) return c;
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

} // namespace lodbake::cli
