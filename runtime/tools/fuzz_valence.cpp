// libFuzzer target for the .lbm decoder (lodrt/valence.h). Build with -DLODRT_BUILD_FUZZERS=ON and
// Clang; scripts/fuzz-valence.sh seeds a corpus with encoded meshes and runs it for a set time.
// Buffers are sized exactly from the header so ASan catches any write past them.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "lodrt/valence.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    lodrt::ValenceInfo info;
    if (lodrt::valenceReadInfo(data, size, &info) != lodrt::Result::Ok) return 0;
    // Header counts are bounded by the stream lengths (at most 128 per byte), so this stays small.
    std::vector<uint32_t> indices(3 * size_t(info.triangle_count));
    std::vector<float> positions(3 * size_t(info.vertex_count));
    std::vector<float> normals(info.has_normals ? 3 * size_t(info.vertex_count) : 0);
    std::vector<uint64_t> scratch(lodrt::valenceScratchSize(info) / 8);
    lodrt::ValenceOutput out;
    out.indices = indices.data();
    out.index_capacity = indices.size();
    out.positions = positions.data();
    out.position_capacity = positions.size();
    out.normals = normals.empty() ? nullptr : normals.data();
    out.normal_capacity = normals.size();
    out.scratch = scratch.data();
    out.scratch_size = scratch.size() * 8;
    // Every attribute of the table (UV sets, colours, tangents) into a buffer of its exact size.
    std::vector<std::vector<float>> attributes(info.attribute_count);
    for (uint32_t i = 0; i < info.attribute_count; ++i) {
        attributes[i].resize(size_t(info.attributes[i].components) * info.vertex_count);
        out.attributes[i] = attributes[i].data();
        out.attribute_capacity[i] = attributes[i].size();
    }
    if (lodrt::valenceDecode(data, size, out) == lodrt::Result::Ok) {
        for (uint32_t i : indices)
            if (i >= info.vertex_count) __builtin_trap();
    }
    return 0;
}
