#pragma once

namespace lodbake {

/// Baker version; part of every cache key and written into pack metadata.
inline constexpr const char* kVersionString = "0.1.0";

} // namespace lodbake
