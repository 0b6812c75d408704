// lodbake pfrep (build a PFRep blob, or extract a level from one).

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
#include "lodbake/pfrep/pfrep_compress.h"
#include "lodbake/pfrep/pfrep_region.h"
#include "lodbake/simplify/lod_chain.h"
#include "lodbake/simplify/mesh_distance.h"
#include "lodbake/simplify/simplify.h"
#include "lodbake/version.h"
#include "lodrt/format.h"
#include "lodrt/pfrep.h"

#include "cli_common.h"

namespace lodbake::cli {

namespace {

const char* kPfrepHelp = R"(usage: lodbake pfrep IN -o OUT.lbp [--ratio R] [--format 2|3 | --regions]
       lodbake pfrep --extract K IN.lbp -o OUT

Builds a PFRep blob (progressive fans, docs/format/pfrep.md) from a half-edge-collapse
simplification of IN down to R of its triangles (default 0: as far as valid collapses go), or
extracts from a blob (format 2, 3 or region blocks) the mesh after K vertex removals (0: full detail) and writes
it as a mesh file (.ply .obj .off .gltf .glb; positions only, dequantized).

options:
  -o, --output OUT   output file
  --ratio R          target fraction of triangles in [0, 1] (build only)
  --format F         3 (default): range-coded; 2: the uncompressed, prefix-streamable layout
  --regions          region blocks: the format 2 table in spatially coherent blocks that load
                     independently (docs/format/pfrep.md "Region blocks"; 1,024 vertices each, cut
                     for views of 1080 px, 60 degrees, 1 px; lodbake bake --pfrep-format 5 sets them)
  --extract K        extract level K instead of building
)";

// Opens a region blob with every block loaded (the decoded buffer is then the format 2 blob).
lodrt::Result openRegionPfrep(const std::vector<uint8_t>& bytes, std::vector<uint8_t>& decoded,
                              lodrt::PfrepModel* model) {
    lodrt::PfrepRegionInfo info;
    lodrt::Result r = lodrt::pfrepRegionInfo(bytes.data(), bytes.size(), &info);
    if (r != lodrt::Result::Ok) return r;
    if (info.blob_size != bytes.size())
        return info.blob_size > bytes.size() ? lodrt::Result::Truncated : lodrt::Result::TrailingBytes;
    decoded.resize(info.decoded_bytes);
    std::vector<uint64_t> state((info.state_bytes + 7) / 8);
    lodrt::PfrepRegions g;
    r = lodrt::pfrepRegionOpen(bytes.data(), bytes.size(), decoded.data(), decoded.size(), state.data(),
                               info.state_bytes, &g);
    for (uint32_t k = 0; k < g.block_count && r == lodrt::Result::Ok; ++k)
        r = lodrt::pfrepRegionLoadBlock(&g, k, bytes.data() + g.blocks[k].offset, g.blocks[k].size);
    // Complete: the decoded bytes are a format 2 blob; open them as one (no residency bits needed).
    if (r == lodrt::Result::Ok) r = lodrt::openPfrep(decoded.data(), decoded.size(), model);
    return r;
}

// Opens a blob of format 2 or 3 or a region blob; a format 3 or region blob is decoded into `decoded`.
lodrt::Result openAnyPfrep(const std::vector<uint8_t>& bytes, std::vector<uint8_t>& decoded, lodrt::PfrepModel* model) {
    if (bytes.size() >= 4 && uint32_t(bytes[0] | bytes[1] << 8 | bytes[2] << 16 | uint32_t(bytes[3]) << 24) ==
                                 lodrt::format::kPfrepRegionMagic)
        return openRegionPfrep(bytes, decoded, model);
    lodrt::PfrepCompressedInfo info;
    const lodrt::Result header = lodrt::pfrepCompressedInfo(bytes.data(), bytes.size(), &info);
    if (header == lodrt::Result::UnsupportedVersion) return lodrt::openPfrep(bytes.data(), bytes.size(), model);
    if (header != lodrt::Result::Ok) return header;
    decoded.resize(info.decoded_bytes);
    std::vector<uint64_t> scratch((info.scratch_bytes + 7) / 8);
    return lodrt::pfrepDecompress(bytes.data(), bytes.size(), decoded.data(), decoded.size(), scratch.data(),
                                  scratch.size() * 8, model);
}

} // namespace

int runPfrep(int argc, char** argv) {
    Args args;
    int code = 0;
    if (!parseArgs(argc, argv, 2,
                   {{"--output", "-o", true}, {"--ratio", nullptr, true}, {"--extract", nullptr, true},
                    {"--format", nullptr, true}, {"--regions", nullptr, false}, {"--help", "-h", false}},
                   args, code))
        return code;
    if (args.flags.count("--help")) {
        std::fputs(kPfrepHelp, stdout);
        std::fputs(kReaderLimitHelp, stdout);
        return kExitOk;
    }
    std::string in, out;
    if (const int c = inputAndOutput(args, "pfrep", "OUT", &in, &out); c != kExitOk) return c;
    Diagnostics diagnostics;
    if (args.values.count("--extract")) {
        if (args.values.count("--ratio")) return usageError("--ratio applies to building, not to --extract");
        if (args.values.count("--format")) return usageError("--format applies to building, not to --extract");
        if (args.flags.count("--regions")) return usageError("--regions applies to building, not to --extract");
        double level = 0;
        if (!parseNumber(args.values["--extract"], level) || !(level >= 0 && level <= 4e9) || level != std::floor(level))
            return usageError("--extract expects a non-negative integer, got '" + args.values["--extract"] + "'");
        if (formatFromPath(out) == MeshFormat::Unknown)
            return usageError("output '" + out + "' has an unknown extension, expected .ply .obj .off .gltf or .glb");
        Result<std::vector<uint8_t>> bytes = readFileBytes(in);
        if (!bytes.ok()) return reportError(bytes.status());
        lodrt::PfrepModel model;
        std::vector<uint8_t> decoded;
        const lodrt::Result opened = openAnyPfrep(*bytes, decoded, &model);
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
    bool compressed = true;
    if (args.values.count("--format")) {
        const std::string& f = args.values["--format"];
        if (f != "2" && f != "3") return usageError("--format expects 2 or 3, got '" + f + "'");
        compressed = f == "3";
    }
    const bool regions = args.flags.count("--regions") > 0;
    if (regions && args.values.count("--format")) return usageError("--regions and --format exclude each other");
    if (regions) compressed = false;
    Result<LoadedMesh> loaded = readMesh(in, args.read, diagnostics);
    if (!loaded.ok()) {
        printDiagnostics(diagnostics);
        return reportError(loaded.status());
    }
    Result<PfrepBuild> build = buildPfrep(loaded->mesh, options, diagnostics);
    if (!build.ok()) {
        printDiagnostics(diagnostics);
        return reportError(build.status().withPrefix(in));
    }
    if (compressed) {
        Result<std::vector<uint8_t>> coded = compressPfrep(build->blob);
        if (!coded.ok()) {
            printDiagnostics(diagnostics);
            return reportError(coded.status().withPrefix(in));
        }
        build->blob = std::move(*coded);
    }
    if (regions) {
        Result<std::vector<uint8_t>> blocked = writePfrepRegions(build->blob, PfrepRegionOptions());
        if (!blocked.ok()) {
            printDiagnostics(diagnostics);
            return reportError(blocked.status().withPrefix(in));
        }
        build->blob = std::move(*blocked);
    }
    const Status written = writeFileAtomic(out, build->blob.data(), build->blob.size());
    printDiagnostics(diagnostics);
    if (!written.ok()) return reportError(written);
    const size_t vertices = build->rank_point.size();
    std::printf("%s: %zu vertices (%zu removable), %zu triangles at level 0, %zu stored, format %d%s, %zu bytes (%.2f "
                "bytes/vertex)\n",
                out.c_str(), vertices, build->removed, build->level0_triangles, build->stored_triangles,
                compressed ? 3 : 2, regions ? " in region blocks" : "", build->blob.size(), vertices ? double(build->blob.size()) / double(vertices) : 0.0);
    return kExitOk;
}

} // namespace lodbake::cli
