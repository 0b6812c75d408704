// lodbake bake.

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

} // namespace lodbake::cli
