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
    std::fprintf(out, "usage: loddump PACK [--json] [--level N]\n"
                      "Prints the LOD groups (MSFT_lod + LODBAKE_lod_metrics: per level triangles, vertices,\n"
                      "errors, screen coverage, switch distance, bytes), then meshes, primitives, accessors and\n"
                      "problems of a .glb/.gltf pack. --level N shows only level N of each group (and only\n"
                      "those meshes). Checks: MSFT_lod ids in range and without cycles, screen coverage not\n"
                      "increasing and errors not decreasing from one level to the next.\n"
                      "Exit status: 0 ok, 1 bad pack or failed LOD check, 2 usage.\n");
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

// One LOD group: a node with MSFT_lod (or a scene node with a mesh and no MSFT_lod: one level).
struct LodLevelRow {
    uint32_t node = lodrt::kNoIndex;
    uint32_t mesh = lodrt::kNoIndex;
    uint64_t triangles = 0, vertices = 0, bytes = 0;
    bool has_metrics = false;
    double hausdorff = 0, mean = 0, hausdorff_rel = 0, mean_rel = 0, switch_distance = 0, metric_coverage = 0;
    bool has_coverage = false;
    double coverage = 0; // MSFT_screencoverage
};

struct LodGroup {
    uint32_t root = 0;
    std::vector<LodLevelRow> levels;
};

struct Problem {
    std::string pointer;
    std::string message;
};

struct LodReport {
    std::vector<LodGroup> groups;
    std::vector<Problem> problems;
};

// Sizes of a mesh: vertices and bytes count each accessor once (primitives of one level share streams).
void measureMesh(const lodrt::Pack& pack, uint32_t mesh_index, LodLevelRow& row) {
    const lodrt::MeshInfo& mesh = pack.mesh(mesh_index);
    std::vector<uint32_t> seen;
    auto count = [&](uint32_t accessor) {
        for (uint32_t a : seen)
            if (a == accessor) return false;
        seen.push_back(accessor);
        row.bytes += pack.accessor(accessor).byte_length;
        return true;
    };
    for (uint32_t p = 0; p < mesh.primitive_count; ++p) {
        const lodrt::PrimitiveInfo& prim = pack.primitive(mesh.first_primitive + p);
        row.triangles += prim.triangle_count;
        if (prim.indices != lodrt::kNoIndex) count(prim.indices);
        for (uint32_t a = 0; a < prim.attribute_count; ++a) {
            const lodrt::AttributeInfo& attr = pack.attribute(prim.first_attribute + a);
            if (count(attr.accessor) && attr.name == "POSITION") row.vertices += pack.accessor(attr.accessor).count;
        }
    }
}

std::string nodePointer(uint32_t node) {
    return "/nodes/" + std::to_string(node);
}

LodReport analyseLods(const lodrt::Pack& pack) {
    LodReport report;
    const uint32_t node_count = pack.nodeCount();
    // Nodes referenced as a lower level are not group roots.
    std::vector<bool> is_lower(node_count, false);
    for (uint32_t n = 0; n < node_count; ++n) {
        const lodrt::JsonValue ids = pack.node(n).json.find("extensions").find("MSFT_lod").find("ids");
        for (uint32_t i = 0; i < ids.size(); ++i) {
            uint64_t id = 0;
            if (ids.at(i).asUint64(&id) && id < node_count && id != n) is_lower[size_t(id)] = true;
        }
    }
    // Cycles through several groups (a lower level whose own MSFT_lod leads back): depth-first search
    // over the id graph; an edge into a node still on the stack closes a cycle.
    std::vector<uint8_t> state(node_count, 0); // 0 new, 1 on stack, 2 done
    for (uint32_t start = 0; start < node_count; ++start) {
        if (state[start] != 0) continue;
        std::vector<std::pair<uint32_t, uint32_t>> stack{{start, 0}}; // node, next id position
        state[start] = 1;
        while (!stack.empty()) {
            const uint32_t n = stack.back().first;
            const lodrt::JsonValue ids = pack.node(n).json.find("extensions").find("MSFT_lod").find("ids");
            if (stack.back().second >= ids.size()) {
                state[n] = 2;
                stack.pop_back();
                continue;
            }
            const uint32_t i = stack.back().second++;
            uint64_t id = 0;
            if (!ids.at(i).asUint64(&id) || id >= node_count || id == n) continue; // reported per group
            if (state[size_t(id)] == 1) {
                report.problems.push_back(
                    {nodePointer(n) + "/extensions/MSFT_lod/ids/" + std::to_string(i),
                     "MSFT_lod cycle: node " + std::to_string(id) + " leads back to node " + std::to_string(n)});
            } else if (state[size_t(id)] == 0) {
                state[size_t(id)] = 1;
                stack.push_back({uint32_t(id), 0});
            }
        }
    }
    for (uint32_t n = 0; n < node_count; ++n) {
        const lodrt::JsonValue lod = pack.node(n).json.find("extensions").find("MSFT_lod");
        if (!lod.isValid() || is_lower[n]) continue;
        LodGroup group;
        group.root = n;
        std::vector<uint32_t> chain{n};
        const lodrt::JsonValue ids = lod.find("ids");
        bool ok = true;
        for (uint32_t i = 0; i < ids.size() && ok; ++i) {
            uint64_t id = 0;
            const std::string where = nodePointer(n) + "/extensions/MSFT_lod/ids/" + std::to_string(i);
            if (!ids.at(i).asUint64(&id) || id >= node_count) {
                report.problems.push_back({where, "expected a node index below " + std::to_string(node_count)});
                ok = false;
                break;
            }
            for (uint32_t c : chain)
                if (c == id) {
                    report.problems.push_back(
                        {where, "MSFT_lod cycle: node " + std::to_string(id) + " is already a level of this group"});
                    ok = false;
                }
            if (ok) chain.push_back(uint32_t(id));
        }
        const lodrt::JsonValue metrics =
            pack.node(n).json.find("extensions").find("LODBAKE_lod_metrics").find("levels");
        const lodrt::JsonValue coverage = pack.node(n).json.find("extras").find("MSFT_screencoverage");
        if (metrics.isValid() && metrics.size() != chain.size())
            report.problems.push_back({nodePointer(n) + "/extensions/LODBAKE_lod_metrics/levels",
                                       "expected " + std::to_string(chain.size()) + " levels (MSFT_lod ids + 1), got " +
                                           std::to_string(metrics.size())});
        for (uint32_t l = 0; l < chain.size(); ++l) {
            LodLevelRow row;
            row.node = chain[l];
            row.mesh = pack.node(chain[l]).mesh;
            if (row.mesh != lodrt::kNoIndex) measureMesh(pack, row.mesh, row);
            const lodrt::JsonValue m = metrics.at(l);
            if (m.isObject()) {
                row.has_metrics = true;
                row.hausdorff = m.find("hausdorffError").number();
                row.mean = m.find("meanError").number();
                row.hausdorff_rel = m.find("hausdorffErrorRelative").number();
                row.mean_rel = m.find("meanErrorRelative").number();
                row.switch_distance = m.find("switchDistance").number();
                row.metric_coverage = m.find("screenCoverage").number();
            }
            if (coverage.at(l).isNumber()) {
                row.has_coverage = true;
                row.coverage = coverage.at(l).number();
            }
            group.levels.push_back(row);
        }
        for (uint32_t l = 1; l < group.levels.size(); ++l) {
            const LodLevelRow& a = group.levels[l - 1];
            const LodLevelRow& b = group.levels[l];
            const std::string lvl = "level " + std::to_string(l);
            if (a.has_coverage && b.has_coverage && b.coverage > a.coverage)
                report.problems.push_back({nodePointer(n) + "/extras/MSFT_screencoverage/" + std::to_string(l),
                                           lvl + ": screen coverage increases (" + std::to_string(a.coverage) + " -> " +
                                               std::to_string(b.coverage) + ")"});
            if (a.has_metrics && b.has_metrics && (b.hausdorff < a.hausdorff || b.mean < a.mean))
                report.problems.push_back(
                    {nodePointer(n) + "/extensions/LODBAKE_lod_metrics/levels/" + std::to_string(l),
                     lvl + ": error decreases from the finer level"});
            if (a.has_metrics && b.has_metrics && b.switch_distance < a.switch_distance)
                report.problems.push_back(
                    {nodePointer(n) + "/extensions/LODBAKE_lod_metrics/levels/" + std::to_string(l),
                     lvl + ": switch distance decreases"});
        }
        report.groups.push_back(std::move(group));
    }
    return report;
}

bool levelSelected(int level_filter, uint32_t level) {
    return level_filter < 0 || uint32_t(level_filter) == level;
}

void printLodText(const lodrt::Pack& pack, const LodReport& report, int level_filter) {
    for (const LodGroup& g : report.groups) {
        std::printf("lod group \"%s\" (node %u): %zu levels\n", printable(pack.node(g.root).name).c_str(), g.root,
                    g.levels.size());
        std::printf("  %-5s %5s %5s %10s %10s %12s %12s %10s %12s %10s\n", "level", "node", "mesh", "triangles",
                    "vertices", "hausdorff", "mean", "coverage", "switch_dist", "bytes");
        for (uint32_t l = 0; l < g.levels.size(); ++l) {
            if (!levelSelected(level_filter, l)) continue;
            const LodLevelRow& r = g.levels[l];
            char hd[32] = "-", mn[32] = "-", cov[32] = "-", sw[32] = "-";
            if (r.has_metrics) {
                std::snprintf(hd, sizeof(hd), "%.4g", r.hausdorff);
                std::snprintf(mn, sizeof(mn), "%.4g", r.mean);
                std::snprintf(sw, sizeof(sw), "%.4g", r.switch_distance);
            }
            if (r.has_coverage) std::snprintf(cov, sizeof(cov), "%.4g", r.coverage);
            std::printf("  %-5u %5u %5d %10llu %10llu %12s %12s %10s %12s %10llu\n", l, r.node,
                        r.mesh == lodrt::kNoIndex ? -1 : int(r.mesh), ull(r.triangles), ull(r.vertices), hd, mn, cov,
                        sw, ull(r.bytes));
        }
    }
}

std::string lodJson(const lodrt::Pack& pack, const LodReport& report, int level_filter) {
    std::string out = "  \"lodGroups\": [";
    char buf[512];
    for (size_t gi = 0; gi < report.groups.size(); ++gi) {
        const LodGroup& g = report.groups[gi];
        out += gi ? ",\n    " : "\n    ";
        out += "{\"node\": " + std::to_string(g.root) + ", \"name\": " + jsonString(pack.node(g.root).name) +
               ", \"levels\": [";
        bool first = true;
        for (uint32_t l = 0; l < g.levels.size(); ++l) {
            if (!levelSelected(level_filter, l)) continue;
            const LodLevelRow& r = g.levels[l];
            std::snprintf(buf, sizeof(buf),
                          "{\"level\": %u, \"node\": %u, \"triangles\": %llu, \"vertices\": %llu, \"bytes\": %llu, "
                          "\"hausdorffError\": %.17g, \"meanError\": %.17g, \"switchDistance\": %.17g, "
                          "\"screenCoverage\": %.17g}",
                          l, r.node, ull(r.triangles), ull(r.vertices), ull(r.bytes), r.hausdorff, r.mean,
                          r.switch_distance, r.coverage);
            out += first ? "\n      " : ",\n      ";
            out += buf;
            first = false;
        }
        out += "]}";
    }
    out += report.groups.empty() ? "],\n" : "\n  ],\n";
    return out;
}

// Meshes shown with --level N: the level-N meshes of every group (all meshes without a filter).
std::vector<bool> meshFilter(const lodrt::Pack& pack, const LodReport& report, int level_filter) {
    std::vector<bool> shown(pack.meshCount(), level_filter < 0);
    for (const LodGroup& g : report.groups)
        for (uint32_t l = 0; l < g.levels.size(); ++l)
            if (levelSelected(level_filter, l) && g.levels[l].mesh != lodrt::kNoIndex) shown[g.levels[l].mesh] = true;
    return shown;
}

void printAccessorRow(const lodrt::Pack& pack, uint32_t index, std::string_view semantic) {
    const lodrt::AccessorInfo& acc = pack.accessor(index);
    std::printf("      %-6u %-12s %-7s %-4s %10llu %12llu%s\n", index, printable(semantic).c_str(),
                lodrt::accessorTypeName(acc.type), lodrt::componentTypeName(acc.component_type), ull(acc.count),
                ull(acc.byte_length), acc.is_sparse ? "  sparse" : "");
}

void printText(const char* path, const lodrt::Pack& pack, const LodReport& lods, int level_filter) {
    const lodrt::GlbView& c = pack.container();
    std::printf("pack %s: %s, JSON %zu bytes, BIN %zu bytes\n", path, c.is_binary ? "GLB" : "glTF JSON", c.json_size,
                c.bin_size);
    printLodText(pack, lods, level_filter);
    const std::vector<bool> shown = meshFilter(pack, lods, level_filter);
    for (uint32_t m = 0; m < pack.meshCount(); ++m) {
        if (!shown[m]) continue;
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
    if (pack.warningCount() == 0 && lods.problems.empty()) std::printf(" none");
    std::printf("\n");
    for (uint32_t w = 0; w < pack.warningCount(); ++w)
        std::printf("  warning %s: %s\n", pack.warning(w).pointer, pack.warning(w).message);
    for (const Problem& p : lods.problems) std::printf("  error %s: %s\n", p.pointer.c_str(), p.message.c_str());
}

std::string accessorJson(const lodrt::Pack& pack, uint32_t index, std::string_view semantic) {
    const lodrt::AccessorInfo& acc = pack.accessor(index);
    return "{\"accessor\": " + std::to_string(index) + ", \"semantic\": " + jsonString(semantic) + ", \"type\": \"" +
           lodrt::accessorTypeName(acc.type) + "\", \"componentType\": \"" +
           lodrt::componentTypeName(acc.component_type) + "\", \"count\": " + std::to_string(acc.count) +
           ", \"bytes\": " + std::to_string(acc.byte_length) + ", \"sparse\": " + (acc.is_sparse ? "true" : "false") +
           "}";
}

void printJson(const char* path, const lodrt::Pack* pack, const char* error, const LodReport* lods, int level_filter) {
    std::string out = "{\n  \"file\": " + jsonString(path) + ",\n  \"ok\": " + (pack ? "true" : "false") + ",\n";
    if (pack) {
        const lodrt::GlbView& c = pack->container();
        char buf[256];
        std::snprintf(buf, sizeof(buf), "  \"container\": {\"binary\": %s, \"jsonBytes\": %zu, \"binBytes\": %zu},\n",
                      c.is_binary ? "true" : "false", c.json_size, c.bin_size);
        out += buf;
        out += lodJson(*pack, *lods, level_filter);
        const std::vector<bool> shown = meshFilter(*pack, *lods, level_filter);
        out += "  \"meshes\": [";
        bool first_mesh = true;
        for (uint32_t m = 0; m < pack->meshCount(); ++m) {
            if (!shown[m]) continue;
            const lodrt::MeshInfo& mesh = pack->mesh(m);
            out += first_mesh ? "\n    " : ",\n    ";
            first_mesh = false;
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
        out += first_mesh ? "],\n" : "\n  ],\n";
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
        for (const Problem& p : lods->problems) addProblem("error", p.pointer.c_str(), p.message.c_str());
    }
    out += problem_count ? "\n  ]\n}\n" : "]\n}\n";
    std::fwrite(out.data(), 1, out.size(), stdout);
}

} // namespace

int main(int argc, char** argv) {
    const char* path = nullptr;
    bool as_json = false;
    int level_filter = -1;
    for (int i = 1; i < argc; ++i) {
        const std::string_view arg = argv[i];
        if (arg == "--json") {
            as_json = true;
        } else if (arg == "--level") {
            char* end = nullptr;
            const long value = i + 1 < argc ? std::strtol(argv[i + 1], &end, 10) : -1;
            if (i + 1 >= argc || *argv[i + 1] == '\0' || *end != '\0' || value < 0 || value > 1000000) {
                std::fprintf(stderr, "error: --level expects a level number (0 = highest detail)\n");
                printUsage(stderr);
                return kExitUsage;
            }
            level_filter = int(value);
            ++i;
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
            printJson(path, nullptr, message, nullptr, level_filter);
        } else {
            std::printf("problems:\n  error %s\n", message);
        }
        std::fprintf(stderr, "error: %s: %s\n", path, message);
        return kExitBadPack;
    }
    const LodReport lods = analyseLods(pack);
    if (as_json) {
        printJson(path, &pack, nullptr, &lods, level_filter);
    } else {
        printText(path, pack, lods, level_filter);
    }
    if (!lods.problems.empty()) {
        std::fprintf(stderr, "error: %s: %s: %s\n", path, lods.problems[0].pointer.c_str(),
                     lods.problems[0].message.c_str());
        return kExitBadPack;
    }
    return kExitOk;
}
