#pragma once
// PFRep format 3: the range-coded form of a format 2 blob (docs/format/pfrep.md, "Format 3").

#include <cstdint>
#include <vector>

#include "lodbake/core/status.h"

namespace lodbake {

/// Codes a format 2 blob (as buildPfrep writes it) as format 3. The blob is validated first
/// (lodrt::openPfrep), and the result is decoded again and compared, so what this returns decodes
/// to exactly `blob`. InvalidInput for a blob that is not valid or not canonical (an entry not
/// written the way the builder writes it: smallest widths, one group per slot).
Result<std::vector<uint8_t>> compressPfrep(const std::vector<uint8_t>& blob);

} // namespace lodbake
