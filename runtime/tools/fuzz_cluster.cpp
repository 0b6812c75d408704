// libFuzzer target for the LODBAKE_cluster_lod reader (lodrt/cluster_pack.h): the table and every
// page, in two ways. An input that starts like a GLB is loaded as a pack and every mesh's extension
// is found, opened and decoded page by page; any other input is split into a table and a pages blob
// (the first four bytes give the table's length) and opened and decoded the same way, and every
// opened hierarchy is cut once (selectClusterCut with cone culling). Build with
// -DLODRT_BUILD_FUZZERS=ON and Clang; run as `lodrt_fuzz_cluster CORPUS_DIR` (packs baked with
// `lodbake bake --clusters`, and their table and pages views, make a good seed corpus).
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "lodrt/cluster_pack.h"
#include "lodrt/lodrt.h"

namespace {

void decodeAll(const uint8_t* table, size_t table_size, const uint8_t* pages, size_t pages_size) {
    char message[256];
    lodrt::ClusterPackInfo info;
    if (lodrt::clusterPackReadInfo(table, table_size, &info, message, sizeof(message)) != lodrt::Result::Ok) {
        if (message[0] == '\0') __builtin_trap(); // every refusal explains itself
        return;
    }
    if (info.memory_bytes > (256u << 20)) return;
    std::vector<uint64_t> memory(info.memory_bytes / 8 + 1);
    lodrt::ClusterLodPack pack;
    message[0] = '\0';
    if (lodrt::clusterPackOpen(table, table_size, pages_size, memory.data(), memory.size() * 8, &pack, message,
                               sizeof(message)) != lodrt::Result::Ok) {
        if (message[0] == '\0') __builtin_trap();
        return;
    }
    // One cut with culling: the hierarchy passed validation, so the walk must stay in bounds.
    std::vector<uint32_t> scratch(lodrt::clusterCutScratchBytes(pack.view) / 4 + 1, 0), out(pack.view.cluster_count);
    lodrt::ClusterCutScratch cut{scratch.data(), scratch.size() * 4, 0};
    lodrt::Frustum frustum;
    for (int i = 0; i < 6; ++i) {
        frustum.planes[i][i / 2] = i % 2 ? -1.0f : 1.0f;
        frustum.planes[i][3] = 10.0f;
    }
    const float eye[3] = {0.5f, 2.0f, -3.0f};
    (void)lodrt::selectClusterCut(pack.view, lodrt::ClusterInstance(), eye, &frustum, lodrt::SelectionParams(), cut,
                                  out.data(), uint32_t(out.size()), nullptr);
    // And with every other page resident (the closure runs over the hostile hierarchy too).
    std::vector<uint8_t> pages_in(pack.page_count), groups_in(pack.view.group_count + 1);
    for (uint32_t p = 0; p < pack.page_count; ++p) pages_in[p] = uint8_t(p % 2);
    lodrt::clusterGroupResidency(pack, pages_in.data(), groups_in.data());
    std::vector<uint32_t> missing(pack.view.group_count / 2 + 1);
    lodrt::ClusterResidency residency{groups_in.data(), missing.data(), uint32_t(missing.size()), 0};
    (void)lodrt::selectClusterCutResident(pack.view, lodrt::ClusterInstance(), eye, &frustum, lodrt::SelectionParams(),
                                          cut, &residency, out.data(), uint32_t(out.size()), nullptr);
    for (uint32_t p = 0; p < pack.page_count; ++p) {
        const lodrt::ClusterPage& page = pack.pages[p];
        // A copy of exactly the page's bytes, so ASan sees any read past its end.
        std::vector<uint8_t> bytes(pages + page.byte_offset, pages + page.byte_offset + page.byte_length);
        lodrt::ClusterPageInfo pi;
        if (lodrt::clusterPageReadInfo(pack, p, bytes.data(), bytes.size(), &pi) != lodrt::Result::Ok) continue;
        if (pi.scratch_bytes > (64u << 20) || pi.vertex_count > (1u << 20)) continue;
        std::vector<uint64_t> page_scratch(pi.scratch_bytes / 8 + 1);
        std::vector<float> positions(size_t(pi.vertex_count) * 3);
        std::vector<uint32_t> indices(size_t(pi.triangle_count) * 3);
        (void)lodrt::clusterPageDecode(pack, p, bytes.data(), bytes.size(), positions.data(), positions.size(),
                                       indices.data(), indices.size(), page_scratch.data(), page_scratch.size() * 8);
    }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size >= 4 && std::memcmp(data, "glTF", 4) == 0) {
        lodrt::Pack pack;
        if (lodrt::loadPack(data, size, nullptr, &pack) != lodrt::Result::Ok) return 0;
        for (uint32_t m = 0; m < pack.meshCount(); ++m) {
            lodrt::ClusterPackSource source;
            if (lodrt::clusterPackFind(pack, m, &source) != lodrt::Result::Ok || !source.table) continue;
            std::vector<uint8_t> table(source.table, source.table + source.table_size);
            decodeAll(table.data(), table.size(), source.pages, size_t(source.pages_size));
        }
        return 0;
    }
    if (size < 4) return 0;
    uint32_t table_size = 0;
    std::memcpy(&table_size, data, 4);
    if (table_size > size - 4) table_size = uint32_t(size - 4);
    std::vector<uint8_t> table(data + 4, data + 4 + table_size);
    std::vector<uint8_t> pages(data + 4 + table_size, data + size);
    decodeAll(table.data(), table.size(), pages.data(), pages.size());
    return 0;
}
