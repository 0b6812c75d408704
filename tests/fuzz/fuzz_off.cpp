// libFuzzer target for the OFF reader (lodbake/io/off.h), straight from memory. Build with
// -DLODBAKE_BUILD_FUZZERS=ON and Clang; run with scripts/fuzz.sh off SECONDS.
#include <cstddef>
#include <cstdint>

#include "fuzz_support.h"
#include "lodbake/io/off.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    lodbake::Diagnostics diagnostics;
    const lodbake::ReadOptions options = lodbake_fuzz::smallLimits();
    lodbake_fuzz::checkLoaded(lodbake::readOffFromMemory(data, size, "fuzz.off", options, diagnostics));
    return 0;
}
