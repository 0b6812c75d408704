#pragma once
// Test helper: a small LOD pack in the layout `lodbake bake` writes (one MSFT_lod chain whose levels
// are separate meshes with LODBAKE_lod_metrics), built in code so every field can be broken.

#include <cstdint>
#include <string>
#include <vector>

#include "glb_builder.h"

namespace lodrt_test {

struct LodPackSpec {
    std::vector<double> errors = {0, 0.001, 0.004, 0.016}; // Hausdorff error per level
    double hysteresis = 0.1;                               // baked band [s (1 - h), s (1 + h)]
    double switch_scale = 500;                             // baked switchDistance = error * scale
    int chains = 1;                                        // copies of the chain (models)
    std::string node0_lod_ids;                             // overrides MSFT_lod ids of chain 0 ("[1,2]")
    std::string node0_metrics;                             // overrides LODBAKE_lod_metrics of chain 0 ("none": omit)
    std::string node0_extras;                              // extras object of chain 0's root
    std::string position_min_max = R"("min":[-1,-1,-1],"max":[1,1,1])";
    uint16_t bad_index_level = 0xFFFF; // level whose index buffer gets index 7
};

/// Per level: 3 positions (36 B) then 3 u16 indices padded to 8 B, i.e. 44 bytes per level.
inline std::vector<uint8_t> lodPackBin(const LodPackSpec& spec) {
    std::vector<uint8_t> bin;
    const size_t levels = spec.errors.size() * size_t(spec.chains);
    for (size_t l = 0; l < levels; ++l) {
        appendValues<float>(bin, {-1, -1, -1, 1, -1, 1, 0, 1, 0});
        const uint16_t bad = (l % spec.errors.size()) == spec.bad_index_level ? 7 : 2;
        appendValues<uint16_t>(bin, {0, 1, bad, 0});
    }
    return bin;
}

inline std::string lodPackJson(const LodPackSpec& spec) {
    const size_t n = spec.errors.size();
    const size_t levels = n * size_t(spec.chains);
    std::string views, accessors, meshes, nodes, scene;
    for (size_t l = 0; l < levels; ++l) {
        const std::string off = std::to_string(l * 44);
        const std::string ioff = std::to_string(l * 44 + 36);
        if (l) views += ",", accessors += ",", meshes += ",", nodes += ",";
        views += R"({"buffer":0,"byteOffset":)" + off + R"(,"byteLength":36},{"buffer":0,"byteOffset":)" + ioff +
                 R"(,"byteLength":6})";
        accessors += R"({"bufferView":)" + std::to_string(2 * l) + R"(,"componentType":5126,"count":3,"type":"VEC3",)" +
                     spec.position_min_max + R"(},{"bufferView":)" + std::to_string(2 * l + 1) +
                     R"(,"componentType":5123,"count":3,"type":"SCALAR"})";
        meshes += R"({"name":"m)" + std::to_string(l) + R"(","primitives":[{"attributes":{"POSITION":)" +
                  std::to_string(2 * l) + R"(},"indices":)" + std::to_string(2 * l + 1) + "}]}";
        std::string node = R"({"name":"n)" + std::to_string(l) + R"(","mesh":)" + std::to_string(l);
        if (l % n == 0 && n > 1) {
            const size_t chain = l / n;
            std::string ids = "[";
            for (size_t k = 1; k < n; ++k) ids += (k > 1 ? "," : "") + std::to_string(l + k);
            ids += "]";
            if (chain == 0 && !spec.node0_lod_ids.empty()) ids = spec.node0_lod_ids;
            std::string metrics = R"({"boundingRadius":1.7,"pixelThreshold":1,"viewportHeight":1000,)"
                                  R"("verticalFov":1.5707963,"levels":[)";
            for (size_t k = 0; k < n; ++k) {
                const double e = spec.errors[k], s = e * spec.switch_scale;
                metrics += (k ? "," : "") + std::string(R"({"triangles":1,"vertices":3,"hausdorffError":)") +
                           std::to_string(e) + R"(,"hausdorffErrorRelative":0,"meanError":)" + std::to_string(e / 4) +
                           R"(,"meanErrorRelative":0,"switchDistance":)" + std::to_string(s) +
                           R"(,"screenCoverage":1,"hysteresisBand":[)" + std::to_string(s * (1 - spec.hysteresis)) +
                           "," + std::to_string(s * (1 + spec.hysteresis)) + "]}";
            }
            metrics += "]}";
            if (chain == 0 && !spec.node0_metrics.empty()) metrics = spec.node0_metrics;
            node += R"(,"extensions":{"MSFT_lod":{"ids":)" + ids + "}";
            if (metrics != "none") node += R"(,"LODBAKE_lod_metrics":)" + metrics;
            node += "}";
            if (chain == 0 && !spec.node0_extras.empty()) node += R"(,"extras":)" + spec.node0_extras;
            scene += (scene.empty() ? "" : ",") + std::to_string(l);
        }
        node += "}";
        nodes += node;
    }
    return R"({"asset":{"version":"2.0"},"extensionsUsed":["MSFT_lod","LODBAKE_lod_metrics"],)"
           R"("scenes":[{"nodes":[)" +
           scene + R"(]}],"buffers":[{"byteLength":)" + std::to_string(levels * 44) + R"(}],"bufferViews":[)" + views +
           R"(],"accessors":[)" + accessors + R"(],"meshes":[)" + meshes + R"(],"nodes":[)" + nodes + "]}";
}

inline std::vector<uint8_t> lodPackGlb(const LodPackSpec& spec = LodPackSpec()) {
    return makeGlb(lodPackJson(spec), lodPackBin(spec));
}

} // namespace lodrt_test
