#pragma once
// lodrt: the level-of-detail runtime a game engine links. C++17, standard library only, no
// exceptions, no file IO: the engine passes bytes in (STYLE.md §5).

#include <cstddef>
#include <cstdint>

#include "lodrt/export.h"

namespace lodrt {

/// Library version as "MAJOR.MINOR.PATCH".
LODRT_API const char* versionString();

} // namespace lodrt
