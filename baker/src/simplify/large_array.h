#pragma once
// Moved to core (the valence encoder uses it too); kept so the simplifier's includes stay valid.
#include "core/large_array.h"
