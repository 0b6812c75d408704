// lodbake bake --plan / --run-job: the out-of-core bake as a job list (docs/pipeline.md, "Job list").
#pragma once

#include "lodbake/config/bake_config.h"

#include "cli_common.h"

namespace lodbake::cli {

/// True when the command line asks for the job list (--plan or --run-job).
bool isBakeJobCommand(const Args& args);

/// Runs `lodbake bake --plan` or `--run-job` with the resolved settings; returns the exit code.
int runBakeJobCommand(Args& args, const BakeSettings& settings);

} // namespace lodbake::cli
