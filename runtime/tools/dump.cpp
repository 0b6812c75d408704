// loddump: prints a summary of a pack (GLB or .gltf) using only the runtime. The only lodrt program
// that opens files; everything it shows comes from lodrt::loadPack.
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "lodrt/lodrt.h"

namespace {

constexpr int kExitOk = 0;
constexpr int kExitBadPack = 1;
constexpr int kExitUsage = 2;

void printUsage(std::FILE* out) {
    std::fprintf(out, "usage: loddump PACK [--json]\n"
                      "Prints meshes, primitives, accessors and problems of a .glb/.gltf pack.\n"
                      "Exit status: 0 ok, 1 bad pack, 2 usage.\n");
}

bool readFile(const char* path, std::vector<uint8_t>* bytes, std::string* error) {
    std::FILE* file = std::fopen(path, "rb");
    if (!file) {
        *error = std::string("cannot open: ") + std::strerror(errno);
        return false;
    }
    uint8_t chunk[65536];
    size_t n;
    while ((n = std::fread(chunk, 1, sizeof(chunk), file)) > 0) bytes->insert(bytes->end(), chunk, chunk + n);
    const bool failed = std::ferror(file) != 0;
    std::fclose(file);
    if (failed) *error = "read error";
    return !failed;
}

std::string jsonString(std::string_view text) {
    std::string out = "\"";
    for (char c : text) {
        switch (c) {
        case '"':
            out += "\\\"";
            break;
        case '\\':
            out += "\\\\";
            break;
        case '\n':
            out += "\\n";
            break;
        case '\r':
            out += "\\r";
            break;
        case '\t':
            out += "\\t";
            break;
        default:
            if (uint8_t(c) < 0x20) {
                char buf[8];
                std::snprintf(buf, sizeof(buf), "\\u%04x", unsigned(uint8_t(c)));
                out += buf;
            } else {
                out += c;
            }
        }
    }
    return out + "\"";
}

// Names shown in the text table: control characters replaced so one name stays on one line.
std::string printable(std::string_view text) {
    std::string out;
    for (char c : text) out += uint8_t(c) < 0x20 ? '?' : c;
    return out;
}

const char* modeName(uint32_t mode) {
    static const char* const kNames[] = {"POINTS",    "LINES",          "LINE_LOOP",   "LINE_STRIP",
                                         "TRIANGLES", "TRIANGLE_STRIP", "TRIANGLE_FAN"};
    return mode < 7 ? kNames[mode] : "?";
}

unsigned long long ull(uint64_t v) {
    return static_cast<unsigned long long>(v);
}

struct Totals {
    uint64_t primitives = 0, vertices = 0, triangles = 0, bytes = 0;
};

Totals computeTotals(const lodrt::Pack& pack) {
    Totals totals;
    for (uint32_t p = 0; p < pack.primitiveCount(); ++p) {
        const lodrt::PrimitiveInfo& prim = pack.primitive(p);
        ++totals.primitives;
        totals.vertices += prim.vertex_count;
        totals.triangles += prim.triangle_count;
        for (uint32_t a = 0; a < prim.attribute_count; ++a)
            totals.bytes += pack.accessor(pack.attribute(prim.first_attribute + a).accessor).byte_length;
        if (prim.indices != lodrt::kNoIndex) totals.bytes += pack.accessor(prim.indices).byte_length;
    }
    return totals;
}

void printAccessorRow(const lodrt::Pack& pack, uint32_t index, std::string_view semantic) {
    const lodrt::AccessorInfo& acc = pack.accessor(index);
    std::printf("      %-6u %-12s %-7s %-4s %10llu %12llu%s\n", index, printable(semantic).c_str(),
                lodrt::accessorTypeName(acc.type), lodrt::componentTypeName(acc.component_type), ull(acc.count),
                ull(acc.byte_length), acc.is_sparse ? "  sparse" : "");
}

void printText(const char* path, const lodrt::Pack& pack) {
    const lodrt::GlbView& c = pack.container();
    std::printf("pack %s: %s, JSON %zu bytes, BIN %zu bytes\n", path, c.is_binary ? "GLB" : "glTF JSON", c.json_size,
                c.bin_size);
    for (uint32_t m = 0; m < pack.meshCount(); ++m) {
        const lodrt::MeshInfo& mesh = pack.mesh(m);
        std::printf("mesh %u \"%s\": %u primitive%s\n", m, printable(mesh.name).c_str(), mesh.primitive_count,
                    mesh.primitive_count == 1 ? "" : "s");
        for (uint32_t p = 0; p < mesh.primitive_count; ++p) {
            const lodrt::PrimitiveInfo& prim = pack.primitive(mesh.first_primitive + p);
            std::printf("  primitive %u: %s, %llu vertices, %llu triangles", p, modeName(prim.mode),
                        ull(prim.vertex_count), ull(prim.triangle_count));
            if (prim.material != lodrt::kNoIndex) std::printf(", material %u", prim.material);
            std::printf("\n      %-6s %-12s %-7s %-4s %10s %12s\n", "acc", "semantic", "type", "comp", "count",
                        "bytes");
            if (prim.indices != lodrt::kNoIndex) printAccessorRow(pack, prim.indices, "(indices)");
            for (uint32_t a = 0; a < prim.attribute_count; ++a) {
                const lodrt::AttributeInfo& attr = pack.attribute(prim.first_attribute + a);
                printAccessorRow(pack, attr.accessor, attr.name);
            }
        }
    }
    const Totals t = computeTotals(pack);
    std::printf("totals: %u meshes, %llu primitives, %llu vertices, %llu triangles, %llu accessor bytes, %u "
                "materials, %u nodes\n",
                pack.meshCount(), ull(t.primitives), ull(t.vertices), ull(t.triangles), ull(t.bytes),
                pack.materialCount(), pack.nodeCount());
    std::printf("problems:");
    if (pack.warningCount() == 0) std::printf(" none");
    std::printf("\n");
    for (uint32_t w = 0; w < pack.warningCount(); ++w)
        std::printf("  warning %s: %s\n", pack.warning(w).pointer, pack.warning(w).message);
}

std::string accessorJson(const lodrt::Pack& pack, uint32_t index, std::string_view semantic) {
    const lodrt::AccessorInfo& acc = pack.accessor(index);
    return "{\"accessor\": " + std::to_string(index) + ", \"semantic\": " + jsonString(semantic) + ", \"type\": \"" +
           lodrt::accessorTypeName(acc.type) + "\", \"componentType\": \"" +
           lodrt::componentTypeName(acc.component_type) + "\", \"count\": " + std::to_string(acc.count) +
           ", \"bytes\": " + std::to_string(acc.byte_length) + ", \"sparse\": " + (acc.is_sparse ? "true" : "false") +
           "}";
}

void printJson(const char* path, const lodrt::Pack* pack, const char* error) {
    std::string out = "{\n  \"file\": " + jsonString(path) + ",\n  \"ok\": " + (pack ? "true" : "false") + ",\n";
    if (pack) {
        const lodrt::GlbView& c = pack->container();
        char buf[256];
        std::snprintf(buf, sizeof(buf), "  \"container\": {\"binary\": %s, \"jsonBytes\": %zu, \"binBytes\": %zu},\n",
                      c.is_binary ? "true" : "false", c.json_size, c.bin_size);
        out += buf;
        out += "  \"meshes\": [";
        for (uint32_t m = 0; m < pack->meshCount(); ++m) {
            const lodrt::MeshInfo& mesh = pack->mesh(m);
            out += m ? ",\n    " : "\n    ";
            out += "{\"mesh\": " + std::to_string(m) + ", \"name\": " + jsonString(mesh.name) + ", \"primitives\": [";
            for (uint32_t p = 0; p < mesh.primitive_count; ++p) {
                const lodrt::PrimitiveInfo& prim = pack->primitive(mesh.first_primitive + p);
                out += p ? ",\n      " : "\n      ";
                std::snprintf(buf, sizeof(buf),
                              "{\"mode\": \"%s\", \"vertices\": %llu, \"triangles\": %llu, \"material\": %s, "
                              "\"accessors\": [",
                              modeName(prim.mode), ull(prim.vertex_count), ull(prim.triangle_count),
                              prim.material == lodrt::kNoIndex ? "null" : std::to_string(prim.material).c_str());
                out += buf;
                bool first = true;
                if (prim.indices != lodrt::kNoIndex) {
                    out += "\n        " + accessorJson(*pack, prim.indices, "(indices)");
                    first = false;
                }
                for (uint32_t a = 0; a < prim.attribute_count; ++a) {
                    const lodrt::AttributeInfo& attr = pack->attribute(prim.first_attribute + a);
                    out += first ? "\n        " : ",\n        ";
                    out += accessorJson(*pack, attr.accessor, attr.name);
                    first = false;
                }
                out += "]}";
            }
            out += "]}";
        }
        out += pack->meshCount() ? "\n  ],\n" : "],\n";
        const Totals t = computeTotals(*pack);
        std::snprintf(buf, sizeof(buf),
                      "  \"totals\": {\"meshes\": %u, \"primitives\": %llu, \"vertices\": %llu, \"triangles\": %llu, "
                      "\"bytes\": %llu, \"materials\": %u, \"nodes\": %u},\n",
                      pack->meshCount(), ull(t.primitives), ull(t.vertices), ull(t.triangles), ull(t.bytes),
                      pack->materialCount(), pack->nodeCount());
        out += buf;
    }
    out += "  \"problems\": [";
    uint32_t problem_count = 0;
    auto addProblem = [&](const char* severity, const char* pointer, const char* message) {
        out += problem_count++ ? ",\n    " : "\n    ";
        out += std::string("{\"severity\": \"") + severity + "\", \"pointer\": " + jsonString(pointer) +
               ", \"message\": " + jsonString(message) + "}";
    };
    if (error) addProblem("error", "", error);
    if (pack) {
        for (uint32_t w = 0; w < pack->warningCount(); ++w)
            addProblem("warning", pack->warning(w).pointer, pack->warning(w).message);
    }
    out += problem_count ? "\n  ]\n}\n" : "]\n}\n";
    std::fwrite(out.data(), 1, out.size(), stdout);
}

} // namespace

int main(int argc, char** argv) {
    const char* path = nullptr;
    bool as_json = false;
    for (int i = 1; i < argc; ++i) {
        const std::string_view arg = argv[i];
        if (arg == "--json") {
            as_json = true;
        } else if (arg == "-h" || arg == "--help") {
            printUsage(stdout);
            return kExitOk;
        } else if (arg.size() > 1 && arg[0] == '-') {
            std::fprintf(stderr, "error: unknown option '%s'\n", argv[i]);
            printUsage(stderr);
            return kExitUsage;
        } else if (path) {
            std::fprintf(stderr, "error: more than one PACK given ('%s' and '%s')\n", path, argv[i]);
            printUsage(stderr);
            return kExitUsage;
        } else {
            path = argv[i];
        }
    }
    if (!path) {
        printUsage(stderr);
        return kExitUsage;
    }
    std::vector<uint8_t> bytes;
    std::string io_error;
    if (!readFile(path, &bytes, &io_error)) {
        std::fprintf(stderr, "error: %s: %s\n", path, io_error.c_str());
        return kExitBadPack;
    }
    lodrt::Pack pack;
    char message[512];
    const lodrt::Result result = lodrt::loadPack(bytes.data(), bytes.size(), nullptr, &pack, message, sizeof(message));
    if (result != lodrt::Result::Ok) {
        if (as_json) {
            printJson(path, nullptr, message);
        } else {
            std::printf("problems:\n  error %s\n", message);
        }
        std::fprintf(stderr, "error: %s: %s\n", path, message);
        return kExitBadPack;
    }
    if (as_json) {
        printJson(path, &pack, nullptr);
    } else {
        printText(path, pack);
    }
    return kExitOk;
}
