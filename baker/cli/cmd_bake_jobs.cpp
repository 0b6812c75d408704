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
#include "lodbake/ooc/ooc_pack.h"

#include "cmd_bake_ooc.h"

namespace lodbake::cli {

namespace {

uint64_t memoryLimit(const BakeSettings& settings) {
    return settings.memory_limit_mib > 0 ? uint64_t(settings.memory_limit_mib) << 20 : defaultBakeMemoryLimit();
}

// The out-of-core options of the bake's settings, as the in-process route (`lodbake bake --clusters
// --memory-limit N`) takes them: the partition size for the limit and every other option that
// shapes the tree at its default, so the plan's files, and the pack, are that route's.
ooc::OocPackOptions packOptions(const Args& args, const BakeSettings& settings, const std::string& input,
                                const std::string& output, const std::string& work_dir) {
    ooc::OocPackOptions o = outOfCorePackOptions(settings, input, output, work_dir, args.read, memoryLimit(settings),
                                                 settings.threads);
    o.driver.work_dir = work_dir;
    return o;
}

// The end of a finished plan: with -o, the GLB around its pages and table (the out-of-core pack
// writer, as the in-process route writes it), after which the plan's files are removed; without it,
// the two blobs are reported.
int finishPlannedBake(const Args& args, const BakeSettings& settings, const std::string& work_dir, bool quiet) {
    const auto out = args.values.find("--output");
    if (out == args.values.end() || out->second.empty()) {
        Result<ooc::OutOfCoreResult> result = ooc::plannedResult(work_dir);
        if (!result.ok()) return reportError(result.status());
        if (!quiet)
            std::fprintf(stderr,
                         "lodbake: plan done: %llu clusters; pages %s (%llu bytes), table %zu bytes; "
                         "write the pack with --plan --work-dir %s -o OUT.glb\n",
                         static_cast<unsigned long long>(result->cluster_count), result->output.c_str(),
                         static_cast<unsigned long long>(result->stats.page_bytes), result->table.size(),
                         work_dir.c_str());
        return kExitOk;
    }
    Result<ooc::JobPlan> plan = ooc::readJobPlan(ooc::jobPlanPath(work_dir));
    if (!plan.ok()) return reportError(plan.status());
    installTempFileSignalCleanup();
    Diagnostics diagnostics;
    Result<ooc::OocPackResult> made = ooc::writePlannedPack(
        work_dir, out->second, packOptions(args, settings, plan->input, out->second, work_dir), diagnostics);
    if (!quiet) printDiagnostics(diagnostics);
    if (!made.ok()) return reportError(made.status());
    if (!quiet)
        std::fprintf(stderr, "lodbake: wrote %s (%llu bytes, %zu levels, %llu measured)\n", out->second.c_str(),
                     static_cast<unsigned long long>(made->pack_bytes), made->metrics.levels.size(),
                     static_cast<unsigned long long>(made->measured_levels));
    return kExitOk;
}

int runPlan(Args& args, const BakeSettings& settings, const std::string& work_dir, bool quiet) {
    if (!settings.cluster_lod) return usageError("--plan bakes the cluster LOD pages out of core: add --clusters");
    if (args.positional.size() > 1) return usageError("--plan takes one input file");
    const std::string input = args.positional.empty() ? std::string() : args.positional[0];
    if (input.empty() && !std::filesystem::exists(ooc::jobPlanPath(work_dir)))
        return usageError("--plan needs the input file the first time (no " + ooc::jobPlanPath(work_dir) + " yet)");
    Diagnostics diagnostics;
    Result<ooc::JobPlan> plan = ooc::planOutOfCore(input, work_dir, packOptions(args, settings, input, std::string(), work_dir).driver, diagnostics);
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
    if (plan->complete && progress.done.size() == progress.total) return finishPlannedBake(args, settings, work_dir, quiet);
    return kExitOk;
}

int runOneJob(const Args& args, const BakeSettings& settings, const std::string& work_dir, const std::string& id,
              bool quiet) {
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
    if (record->kind == ooc::JobKind::Pages) return finishPlannedBake(args, settings, work_dir, quiet);
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
    if (!plan && args.values.count("--output"))
        return usageError("--output goes with --plan (the pack of a finished plan), not with --run-job");
    for (const char* other : {"--manifest", "--report", "--depfile", "--cache-dir", "--print-config"})
        if (args.values.count(other) || args.flags.count(other))
            return usageError(std::string(other) + " does not go with " + (plan ? "--plan" : "--run-job"));
    const std::string work_dir = args.values["--work-dir"];
    const bool quiet = args.flags.count("--quiet") > 0;
    if (plan) return runPlan(args, settings, work_dir, quiet);
    if (!args.positional.empty()) return usageError("--run-job takes no input file (the plan names every input)");
    return runOneJob(args, settings, work_dir, args.values["--run-job"], quiet);
}

} // namespace lodbake::cli
