// libFuzzer target for the PLY reader (lodbake/io/ply.h), straight from memory. Build with
// -DLODBAKE_BUILD_FUZZERS=ON and Clang; run with scripts/fuzz.sh ply SECONDS.
#include <cstddef>
#include <cstdint>

#include "fuzz_support.h"
#include "lodbake/io/ply.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    lodbake::Diagnostics diagnostics;
    const lodbake::ReadOptions options = lodbake_fuzz::smallLimits();
    lodbake_fuzz::checkLoaded(lodbake::readPlyFromMemory(data, size, "fuzz.ply", options, diagnostics));
    return 0;
}
