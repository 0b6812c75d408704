#pragma once
// lodrt: the level-of-detail runtime a game engine links. C++17, standard library only, no
// exceptions, no file IO: the engine passes bytes in (STYLE.md §5).

#include <cstddef>
#include <cstdint>

#include "lodrt/allocator.h"
#include "lodrt/export.h"
#include "lodrt/frustum.h"
#include "lodrt/glb.h"
#include "lodrt/json.h"
#include "lodrt/model.h"
#include "lodrt/pack.h"
#include "lodrt/pfrep.h"
#include "lodrt/pfrep_instance.h"
#include "lodrt/result.h"
#include "lodrt/selection.h"
#include "lodrt/streaming.h"

namespace lodrt {

/// Library version as "MAJOR.MINOR.PATCH".
LODRT_API const char* versionString();

} // namespace lodrt
