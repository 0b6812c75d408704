// lodbake: command-line front end. Argument parsing, printing and exit codes only; every piece of
// work is a library call (STYLE.md §1). Exit codes: 0 ok, 1 input or bake error, 2 usage.

#include <cstdio>
#include <string>

#include "cli_common.h"
#include "lodbake/version.h"

namespace {

using namespace lodbake::cli;

const char* kMainHelp = R"(lodbake - offline level-of-detail asset baker

usage: lodbake <command> [options]

commands:
  info IN            print format, counts, attributes, bounds and topology of a mesh file
  convert IN -o OUT  convert between .ply .obj .off .gltf .glb (.conf scan sets as input)
  repair IN -o OUT   weld, remove degenerate faces, make manifold, orient, drop speckle, fill holes, normals
  merge IN -o OUT    merge aligned range views (.conf set or overlapping sheets) into one surface (Poisson)
  simplify IN -o OUT simplify to a triangle ratio, count or error (quadric edge collapse)
  lods IN -o PREFIX  build a discrete LOD chain with measured errors and switch distances
  pfrep IN -o OUT.lbp  build a progressive-fans (PFRep) blob; pfrep --extract K IN.lbp -o OUT extracts level K
  bake IN... -o OUT.glb  repair, LOD chain, texture levels: one glTF pack (MSFT_lod + metrics)
  encode IN -o OUT.lbm  compress triangles, positions and normals (docs/format/valence.md)
  decode IN.lbm -o OUT  decompress an .lbm file to .ply .obj .off .gltf or .glb

options:
  -h, --help         show help (also: lodbake <command> --help)
  --version          print the version
  --max-vertices N, --max-faces N
                     refuse inputs that declare more (every command that reads a mesh; default 2^28 each)

exit codes: 0 success, 1 input or processing error, 2 usage error
)";

} // namespace

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
    if (cmd == "merge") return runMerge(argc, argv);
    if (cmd == "encode") return runEncode(argc, argv);
    if (cmd == "decode") return runDecode(argc, argv);
    return usageError("unknown command '" + cmd + "'");
}
