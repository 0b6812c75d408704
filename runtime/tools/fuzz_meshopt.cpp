// libFuzzer target for the EXT_meshopt_compression decoders (lodrt/meshopt.h). Input: one byte
// choosing the mode (bits 0-1: attributes, triangles, index sequence) and filter (bits 2-3), one byte
// for the element stride (attributes: 4 * (1 + b % 64); indices: 2 or 4), a little-endian u16 element
// count, then the compressed stream. The output buffer has exactly the decoded size plus a guard
// area, so ASan catches a write past the elements and the guard check any write into the guard.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "lodrt/meshopt.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 4) return 0;
    lodrt::MeshoptViewInfo info;
    const uint32_t mode = data[0] & 3;
    info.mode = mode == 1 ? lodrt::MeshoptMode::Triangles
                          : (mode == 2 ? lodrt::MeshoptMode::Indices : lodrt::MeshoptMode::Attributes);
    info.filter = static_cast<lodrt::MeshoptFilter>((data[0] >> 2) & 3);
    if (info.mode == lodrt::MeshoptMode::Attributes) {
        info.stride = 4 * (1 + data[1] % 64);
    } else {
        info.stride = (data[1] & 1) ? 4 : 2;
        info.filter = lodrt::MeshoptFilter::None;
    }
    info.count = uint64_t(data[2]) | uint64_t(data[3]) << 8;
    if (info.mode == lodrt::MeshoptMode::Triangles) info.count -= info.count % 3;
    const size_t bytes = size_t(info.count) * info.stride;
    constexpr size_t kGuard = 64;
    std::vector<uint8_t> out(bytes + kGuard, 0xA5);
    (void)lodrt::meshoptDecodeView(info, data + 4, size - 4, out.data(), bytes);
    for (size_t i = bytes; i < out.size(); ++i)
        if (out[i] != 0xA5) __builtin_trap();
    return 0;
}
