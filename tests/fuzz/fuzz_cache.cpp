// libFuzzer target for the bake cache's files (lodbake/bake/cache.h): the input is read both as an
// entry (v2/packs/*.bin) and as a side-file list (v2/deps/*.txt, for one to three inputs). A
// damaged file must be refused (a cache miss), never half-read: an accepted entry serializes back
// to exactly its bytes, and an accepted list has one line per listed side file, none empty.
// Run with scripts/fuzz.sh cache SECONDS.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/bake/cache.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::vector<uint8_t> bytes(data, data + size);
    lodbake::CacheEntry entry;
    if (lodbake::parseCacheEntry(bytes, entry)) {
        if (lodbake::serializeCacheEntry(entry) != bytes) __builtin_trap();
        if (entry.summary.size() + entry.report_json.size() + entry.glb.size() > size) __builtin_trap();
    }
    const std::string text(bytes.begin(), bytes.end());
    for (size_t inputs = 1; inputs <= 3; ++inputs) {
        std::vector<std::vector<std::string>> side;
        if (!lodbake::parseCacheDeps(text, inputs, side)) continue;
        if (side.size() != inputs) __builtin_trap();
        size_t lines = 1 + inputs, chars = 0;
        for (const auto& list : side)
            for (const std::string& file : list) {
                if (file.empty() || file.find('\n') != std::string::npos) __builtin_trap();
                ++lines;
                chars += file.size();
            }
        if (chars + lines > size + 1) __builtin_trap(); // every line came from the text
    }
    return 0;
}
