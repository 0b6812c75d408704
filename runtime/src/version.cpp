#include "lodrt/lodrt.h"

namespace lodrt {

const char* versionString() { return LODRT_VERSION_STRING; }

} // namespace lodrt
