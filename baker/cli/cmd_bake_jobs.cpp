// lodbake bake --plan / --run-job (cmd_bake_jobs.h): the out-of-core bake's job list written and
// extended, and one job run, each in its own process, so that a build farm can spread the jobs over
// machines (docs/pipeline.md, "Job list"; docs/cli.md).

#include "cmd_bake_jobs.h"

#include <cstdio>
#include <filesystem>
#include <string>

#include "lodbake/bake/memory_budget.h"
#include "lodbake/core/temp_files.h"
#include "lodbake/ooc/jobs.h"

namespace lodbake::cli {

namespace {

uint64_t memoryLimit(const BakeSettings& settings) {
    return settings.memory_limit_mib > 0 ? uint64_t(settings.memory_limit_mib) << 20 : defaultBakeMemoryLimit();
}

// The out-of-core options of the bake's settings: every option that shapes the tree at its default,
// so the plan's files are the in-process driver's.
ooc::OutOfCoreOptions outOfCoreOptions(const BakeSettings& settings, const std::string& work_dir) {
    ooc::OutOfCoreOptions o;
    o.work_dir = work_dir;
    o.memory_limit_bytes = memoryLimit(settings);
    o.threads = int(settings.threads);
    return o;
}

// The end of a finished plan: its pages and table as buildOutOfCore returns them. The GLB around
// them (the out-of-core pack writer) is written from this result; until then the two blobs are
// reported.
int finishPlannedBake(const std::string& work_dir, bool quiet) {
    Result<ooc::OutOfCoreResult> result = ooc::plannedResult(work_dir);
    if (!result.ok()) return reportError(result.status());
    if (!quiet)
        std::fprintf(stderr, "lodbake: plan done: %llu clusters; pages %s (%llu bytes), table %zu bytes\n",
                     static_cast<unsigned long long>(result->cluster_count), result->output.c_str(),
                     static_cast<unsigned long long>(result->stats.page_bytes), result->table.size());
    return kExitOk;
}

int runPlan(Args& args, const BakeSettings& settings, const std::string& work_dir, bool quiet) {
    if (!settings.cluster_lod) return usageError("--plan bakes the cluster LOD pages out of core: add --clusters");
    if (args.positional.size() > 1) return usageError("--plan takes one input file");
    const std::string input = args.positional.empty() ? std::string() : args.positional[0];
    if (input.empty() && !std::filesystem::exists(ooc::jobPlanPath(work_dir)))
        return usageError("--plan needs the input file the first time (no " + ooc::jobPlanPath(work_dir) + " yet)");
    Diagnostics diagnostics;
    Result<ooc::JobPlan> plan = ooc::planOutOfCore(input, work_dir, outOfCoreOptions(settings, work_dir), diagnostics);
    if (!quiet) printDiagnostics(diagnostics);
    if (!plan.ok()) return reportError(plan.status());
    const ooc::JobProgress progress = ooc::jobProgress(work_dir, *plan);
    // stdout: the plan's path, then the jobs that can run now, one id a line (what a farm reads).
    std::printf("%s\n", ooc::jobPlanPath(work_dir).c_str());
    for (const std::string& id : progress.ready) std::printf("%s\n", id.c_str());
    if (!quiet)
        std::fprintf(stderr, "lodbake: plan: %zu jobs, %zu done, %zu ready%s\n", progress.total, progress.done.size(),
                     progress.ready.size(),
                     plan->complete ? "" : "; run --plan again once they are done for the next ones");
    if (plan->complete && progress.done.size() == progress.total) return finishPlannedBake(work_dir, quiet);
    return kExitOk;
}

int runOneJob(const BakeSettings& settings, const std::string& work_dir, const std::string& id, bool quiet) {
    installTempFileSignalCleanup();
    ooc::JobRunOptions options;
    options.memory_limit_bytes = memoryLimit(settings);
    options.threads = int(settings.threads);
    Diagnostics diagnostics;
    Result<ooc::JobRecord> record = ooc::runJob(work_dir, id, options, diagnostics);
    if (!quiet) printDiagnostics(diagnostics);
    if (!record.ok()) return reportError(record.status());
    std::printf("%s\n", ooc::jobRecordPath(work_dir, id).c_str());
    if (!quiet)
        std::fprintf(stderr, "lodbake: job %s (%s): wrote %s\n", id.c_str(), ooc::jobKindName(record->kind),
                     record->output.c_str());
    if (record->kind == ooc::JobKind::Pages) return finishPlannedBake(work_dir, quiet);
    return kExitOk;
}

} // namespace

bool isBakeJobCommand(const Args& args) {
    return args.flags.count("--plan") > 0 || args.values.count("--run-job") > 0;
}

int runBakeJobCommand(Args& args, const BakeSettings& settings) {
    const bool plan = args.flags.count("--plan") > 0;
    if (plan && args.values.count("--run-job")) return usageError("--plan and --run-job exclude each other");
    if (!args.values.count("--work-dir") || args.values["--work-dir"].empty())
        return usageError(std::string(plan ? "--plan" : "--run-job") + " needs --work-dir DIR");
    for (const char* other : {"--output", "--manifest", "--report", "--depfile", "--cache-dir", "--print-config"})
        if (args.values.count(other) || args.flags.count(other))
            return usageError(std::string(other) + " does not go with " + (plan ? "--plan" : "--run-job"));
    const std::string work_dir = args.values["--work-dir"];
    const bool quiet = args.flags.count("--quiet") > 0;
    if (plan) return runPlan(args, settings, work_dir, quiet);
    if (!args.positional.empty()) return usageError("--run-job takes no input file (the plan names every input)");
    return runOneJob(settings, work_dir, args.values["--run-job"], quiet);
}

} // namespace lodbake::cli
