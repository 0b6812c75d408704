// libFuzzer target over the LOD runtime's input path: PackSource (bytes and range reads), models,
// and a streamer that fetches and checks every level (-DLODRT_BUILD_FUZZERS=ON with Clang).

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "lodrt/streaming.h"

namespace {

struct Bytes {
    const uint8_t* data;
    size_t size;
};

lodrt::Result readRange(void* user, uint64_t offset, void* dst, size_t size) {
    const Bytes* b = static_cast<const Bytes*>(user);
    if (offset > b->size || size > b->size - offset) return lodrt::Result::Truncated;
    std::memcpy(dst, b->data + offset, size);
    return lodrt::Result::Ok;
}

void stream(const lodrt::PackSource& source) {
    lodrt::Streamer streamer;
    if (streamer.init(&source, nullptr, nullptr) != lodrt::Result::Ok) return;
    lodrt::ModelDemand demand[64];
    const uint32_t count = source.models().modelCount() < 64 ? source.models().modelCount() : 64;
    if (count != source.models().modelCount()) return;
    for (uint32_t m = 0; m < count; ++m) demand[m] = lodrt::ModelDemand{0, 1.0f};
    streamer.update(demand);
    streamer.update(demand);
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    lodrt::PackSource source;
    if (source.openBytes(data, size, nullptr) == lodrt::Result::Ok) stream(source);
    Bytes bytes{data, size};
    lodrt::PackSource ranged;
    if (ranged.openReader(lodrt::RangeReader{&readRange, &bytes}, size, nullptr) == lodrt::Result::Ok) stream(ranged);
    return 0;
}
