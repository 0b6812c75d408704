#pragma once
// The out-of-core route of `lodbake bake` (docs/bake.md, "The memory limit"): the batch runner's
// OutOfCoreBake hook over the out-of-core pack writer (lodbake/ooc/ooc_pack.h).

#include <string>

#include "lodbake/bake/batch.h"
#include "lodbake/ooc/ooc_pack.h"

namespace lodbake::cli {

/// The hook: bakes a job out of core with its settings (LOD ratios, screen parameters, hysteresis,
/// stream precision, --compact), its partitions in a hidden folder inside `work_dir`, or inside the
/// output's folder when `work_dir` is empty; the folder is removed however the bake ends.
/// The out-of-core pack's options of a bake of `input` into `output` under `limit`: the partition
/// size for the limit (leafTrianglesForLimit), the chain's settings, the error measurement's samples.
/// The in-process route and the job list (cmd_bake_jobs.cpp) share it, so their packs are the same bytes.
ooc::OocPackOptions outOfCorePackOptions(const BakeSettings& settings, const std::string& input,
                                         const std::string& output, const std::string& work_dir,
                                         const ReadOptions& read, uint64_t limit, uint32_t threads);

OutOfCoreBake outOfCoreBaker(const std::string& work_dir, const ReadOptions& read);

} // namespace lodbake::cli
