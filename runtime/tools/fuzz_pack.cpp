// libFuzzer target for every lodrt entry point that reads untrusted bytes (STYLE.md §9): the
// container reader, the JSON parser and the pack loader. Build with -DLODRT_BUILD_FUZZERS=ON and
// Clang; run as `lodrt_fuzz_pack CORPUS_DIR` (any .glb or .gltf files make a good seed corpus).
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "lodrt/lodrt.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    lodrt::GlbView view;
    (void)lodrt::parseGlb(data, size, &view);

    // Small limits so deep or wide inputs hit the refusal paths quickly.
    lodrt::JsonLimits limits;
    limits.max_depth = 16;
    limits.max_nodes = 1u << 16;
    lodrt::JsonDocument doc;
    if (lodrt::parseJson(reinterpret_cast<const char*>(data), size, nullptr, &limits, &doc) == lodrt::Result::Ok) {
        const lodrt::JsonValue root = doc.root();
        for (uint32_t i = 0; i < root.size(); ++i) (void)root.keyAt(i).size();
    }

    lodrt::Pack pack;
    char message[128];
    if (lodrt::loadPack(data, size, nullptr, &pack, message, sizeof(message)) == lodrt::Result::Ok) {
        uint64_t sum = 0;
        for (uint32_t p = 0; p < pack.primitiveCount(); ++p) {
            const lodrt::PrimitiveInfo& prim = pack.primitive(p);
            for (uint32_t a = 0; a < prim.attribute_count; ++a)
                sum += pack.accessor(pack.attribute(prim.first_attribute + a).accessor).byte_length;
        }
        for (uint32_t w = 0; w < pack.warningCount(); ++w) sum += std::strlen(pack.warning(w).message);
        (void)sum;
    } else if (message[0] == '\0') {
        __builtin_trap(); // every failure must explain itself
    }
    return 0;
}
