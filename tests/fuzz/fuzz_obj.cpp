// libFuzzer target for the OBJ and MTL readers (lodbake/io/obj.h), straight from memory. The input
// is the OBJ text, optionally followed by a line "#lodbake-fuzz-mtl" and the text served for every
// .mtl the OBJ asks for; any other side file (a texture) is served the same bytes, so one input
// exercises both parsers and their cross references. Run with scripts/fuzz.sh obj SECONDS.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "fuzz_support.h"
#include "lodbake/io/obj.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const char kSplit[] = "\n#lodbake-fuzz-mtl\n";
    const size_t split_len = sizeof(kSplit) - 1;
    size_t obj_size = size;
    for (size_t i = 0; i + split_len <= size; ++i) {
        if (std::memcmp(data + i, kSplit, split_len) == 0) {
            obj_size = i;
            break;
        }
    }
    const std::vector<uint8_t> side(data + (obj_size == size ? size : obj_size + split_len), data + size);
    // An exactly sized copy, so ASan sees any read past the OBJ's end.
    const std::vector<uint8_t> obj(data, data + obj_size);
    int side_requests = 0;
    const lodbake::SideFileLoader loader = [&](const std::string& path) -> lodbake::Result<std::vector<uint8_t>> {
        if (++side_requests > 64) return lodbake::ioError(path + ": too many side files requested by one input");
        return side;
    };
    lodbake::Diagnostics diagnostics;
    const lodbake::ReadOptions options = lodbake_fuzz::smallLimits();
    lodbake_fuzz::checkLoaded(
        lodbake::readObjFromMemory(obj.data(), obj.size(), "fuzz/model.obj", loader, options, diagnostics));
    return 0;
}
