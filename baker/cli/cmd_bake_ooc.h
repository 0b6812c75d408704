#pragma once
// The out-of-core route of `lodbake bake` (docs/bake.md, "The memory limit"): the batch runner's
// OutOfCoreBake hook over the out-of-core pack writer (lodbake/ooc/ooc_pack.h).

#include <string>

#include "lodbake/bake/batch.h"

namespace lodbake::cli {

/// The hook: bakes a job out of core with its settings (LOD ratios, screen parameters, hysteresis,
/// stream precision, --compact), its partitions in a hidden folder inside `work_dir`, or inside the
/// output's folder when `work_dir` is empty; the folder is removed however the bake ends.
OutOfCoreBake outOfCoreBaker(const std::string& work_dir, const ReadOptions& read);

} // namespace lodbake::cli
