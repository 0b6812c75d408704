// Shared pieces of the lodbake command-line front end: argument parsing, error printing and the
// JSON/text writers more than one subcommand uses. Each subcommand lives in its own cmd_*.cpp.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "lodbake/cleanup/topology.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/core/json_writer.h"
#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/simplify/mesh_distance.h"

namespace lodbake::cli {

constexpr int kExitOk = 0;
constexpr int kExitError = 1;
constexpr int kExitUsage = 2;

/// Parsed command line of one subcommand: flags with optional values and positional arguments.
struct Args {
    std::vector<std::string> positional;
    std::map<std::string, std::string> values;
    std::map<std::string, bool> flags;
    /// Reader limits, from the options every subcommand accepts (kReaderLimitHelp); defaults otherwise.
    ReadOptions read;
};

/// Help text of the reader-limit options parseArgs accepts for every subcommand.
extern const char* const kReaderLimitHelp;

struct OptionSpec {
    const char* long_name;
    const char* short_name; // may be null
    bool takes_value;
};

int usageError(const std::string& message);
/// The one input file and the output `-o OUT` of a command that reads a file and writes one:
/// kExitOk with *in and *out set, or the exit code of the usage error it printed (not one input,
/// no -o, named `output_form` in the message, or the output is the input).
int inputAndOutput(const Args& args, const char* command, const char* output_form, std::string* in,
                   std::string* out);
/// inputAndOutput for a mesh output (convert, repair, merge, simplify, decode): also a usage error
/// when the output's extension is not a mesh format that can be written.
int meshInputAndOutput(const Args& args, const char* command, std::string* in, std::string* out);
// Returns false (after printing) on a usage error.
bool parseArgs(int argc, char** argv, int first, const std::vector<OptionSpec>& specs, Args& args, int& exit_code);
void printDiagnostics(const Diagnostics& diagnostics);
int reportError(const Status& status);
std::string attributeList(const Mesh& mesh);
void writeTopologyJson(JsonWriter& j, const TopologyStats& t);
void printTopologyText(const char* title, const TopologyStats& t);
bool parseNumber(const std::string& text, double& out);
// Splits "1,0.5" into numbers; false on any malformed item.
bool parseList(const std::string& text, std::vector<double>& out);
void writeDistanceJson(JsonWriter& j, const DistanceResult& d);

/// True when `text` is a bundled preset's name (letters, digits, '_' and '-'), not a path.
bool isPresetName(const std::string& text);
/// `--preset NAME|FILE`: a name is looked up among the presets installed with lodbake
/// (share/lodbake/presets/NAME.json, found relative to the executable), anything else is a path.
/// kExitOk with *path set, or the exit code of the error it printed (an unknown name lists the
/// bundled ones).
int resolvePreset(const std::string& preset, std::string* path);

// Subcommands: each returns the process exit code.
int runInfo(int argc, char** argv);
int runConvert(int argc, char** argv);
int runRepair(int argc, char** argv);
int runSimplify(int argc, char** argv);
int runLods(int argc, char** argv);
int runPfrep(int argc, char** argv);
int runEncode(int argc, char** argv);
int runDecode(int argc, char** argv);
int runBake(int argc, char** argv);
int runMerge(int argc, char** argv);

} // namespace lodbake::cli
