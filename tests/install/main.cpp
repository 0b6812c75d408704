// Install-tree consumer: parses an embedded GLB through the installed lodrt and checks the result.
#include <cstdio>
#include <cstring>
#include <string>

#include "lodrt/lodrt.h"

namespace {

// 12-byte header (magic, version 2, total 48 = '0'), one JSON chunk of 28 bytes (0x1C) padded with
// a space. Spelled as a string literal; the terminating NUL is not part of the file.
const char kGlb[] = "glTF\x02\x00\x00\x00"
                    "0\x00\x00\x00"
                    "\x1C\x00\x00\x00JSON"
                    "{\"asset\":{\"version\":\"2.0\"}} ";

} // namespace

int main() {
    const auto* bytes = reinterpret_cast<const uint8_t*>(kGlb);
    const size_t size = sizeof(kGlb) - 1;
    lodrt::GlbView view;
    const lodrt::Result result = lodrt::parseGlb(bytes, size, &view);
    if (result != lodrt::Result::Ok || !view.is_binary || view.json_size != 28 || view.bin != nullptr) {
        std::fprintf(stderr, "parseGlb: %s\n", lodrt::resultName(result));
        return 1;
    }
    lodrt::Pack pack;
    char message[256];
    const lodrt::Result loaded = lodrt::loadPack(bytes, size, nullptr, &pack, message, sizeof(message));
    if (loaded != lodrt::Result::Ok || pack.meshCount() != 0) {
        std::fprintf(stderr, "loadPack: %s: %s\n", lodrt::resultName(loaded), message);
        return 1;
    }
    if (lodrt::parseGlb(bytes, size - 1, &view) != lodrt::Result::Truncated) {
        std::fprintf(stderr, "a truncated GLB was accepted\n");
        return 1;
    }
    std::printf("lodrt %s: GLB ok, JSON chunk %zu bytes, asset.version %s\n", lodrt::versionString(), view.json_size,
                std::string(pack.document().root().find("asset").find("version").string()).c_str());
    return 0;
}
