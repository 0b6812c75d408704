// loddump: prints a summary of a pack (GLB or .gltf) using only the runtime. The only lodrt program
// that opens files; everything it shows comes from lodrt::loadPack and the lodrt stream decoders.
// --render draws a contact sheet (contact_sheet.h), shaded with the pack's textures
// (sheet_materials.h), decoding them and writing the picture through an image module loaded with
// dlopen (png_module.cpp), so OpenImageIO costs nothing unless a picture is asked for.
#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "contact_sheet.h"
#include "dump_clusters.h"
#include "sheet_materials.h"
#include "tool_module.h"
#include "lodrt/format.h"
#include "lodrt/lodrt.h"
#include "lodrt/pfrep.h"
#include "lodrt/valence.h"

namespace {

constexpr int kExitOk = 0;
constexpr int kExitBadPack = 1;
constexpr int kExitUsage = 2;

void printUsage(std::FILE* out) {
    std::fprintf(out, "usage: loddump PACK [--json] [--level N] [--render OUT.png [--wireframe]]\n"
                      "Prints the LOD groups (%s + %s: per level triangles, vertices,\n"
                      "errors, screen coverage, switch distance, bytes per stream: plain accessors,\n"
                      "%s, %s, each with its ratio to the same\n"
                      "data as float32/uint32), then meshes, primitives, accessors and problems of a .glb/.gltf\n"
                      "pack. --level N shows only level N of each group (and only those meshes).\n"
                      "Checks: %s ids in range and without cycles, screen coverage not increasing and\n"
                      "errors not decreasing from one level to the next, no two neighbouring levels with the\n"
                      "same triangle count (a Hausdorff error more than 4 times the finer level's is a\n"
                      "warning), no level after LOD0 that selection never picks (its switch distance is\n"
                      "the next level's), every compressed stream decodes and\n"
                      "matches the plain accessors, each PFRep level the extension lists is what the blob\n"
                      "extracts and no finer than the chain level it stands for.\n"
                      "--render OUT.png draws every level of every group side by side (shaded with each\n"
                      "level's base colour texture and normal map, or flat without materials; with\n"
                      "--wireframe the triangle edges too) and writes the picture with OpenImageIO.\n"
                      "Exit status: 0 ok, 1 bad pack or failed check, 2 usage.\n",
                 lodrt::format::kExtMsftLod, lodrt::format::kExtLodMetrics, lodrt::format::kExtValenceCompression,
                 lodrt::format::kExtProgressiveFans, lodrt::format::kExtMsftLod);
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
    double coverage = 0; // MSFT_screencoverage: the level is shown while the coverage is at least this
    // Bytes stored per stream, and the same data as float32 components / uint32 indices ("raw").
    uint64_t plain_bytes = 0, plain_raw = 0;
    uint64_t valence_bytes = 0, valence_raw = 0;
    uint64_t pfrep_bytes = 0, pfrep_raw = 0;
    bool has_valence = false, has_pfrep = false;
};

struct LodGroup {
    uint32_t root = 0;
    std::vector<LodLevelRow> levels;
    lodrt::SelectionParams screen; // the screen LODBAKE_lod_metrics was baked for (defaults without it)
    uint64_t input_triangles = 0; // LODBAKE_lod_metrics inputTriangles; 0 when absent
};

struct Problem {
    std::string pointer;
    std::string message;
};

struct LodReport {
    std::vector<LodGroup> groups;
    std::vector<Problem> problems;
    std::vector<Problem> warnings; // listed with the problems; they do not fail the check
    std::vector<loddump::ClusterSummary> clusters; // per mesh with LODBAKE_cluster_lod that checks out
};

constexpr std::string_view kValence = lodrt::format::kExtValenceCompression;
constexpr std::string_view kPfrep = lodrt::format::kExtProgressiveFans;

// The accessor's data as float32 components / uint32 indices.
uint64_t rawBytes(const lodrt::AccessorInfo& acc) {
    return acc.count * lodrt::componentCount(acc.type) * 4;
}

// The bytes of buffer view `index` when lodrt can see them (the GLB BIN chunk); null otherwise.
const uint8_t* viewBytes(const lodrt::Pack& pack, uint64_t index, uint64_t* size) {
    if (index >= pack.bufferViewCount()) return nullptr;
    const lodrt::BufferViewInfo& view = pack.bufferView(uint32_t(index));
    const lodrt::BufferInfo& buffer = pack.buffer(view.buffer);
    const lodrt::GlbView& c = pack.container();
    if (!buffer.is_glb_bin || !c.bin || view.byte_offset + view.byte_length > c.bin_size) return nullptr;
    *size = view.byte_length;
    return c.bin + view.byte_offset;
}

// The buffer view an extension object names in `member`, or kNoIndex when absent or not an index.
uint32_t extensionView(const lodrt::Pack& pack, lodrt::JsonValue object, std::string_view member) {
    uint64_t view = 0;
    if (!object.find(member).asUint64(&view) || view >= pack.bufferViewCount()) return lodrt::kNoIndex;
    return uint32_t(view);
}

// Element e of an accessor, component k, as uint32 (indices) or float; false when lodrt cannot see
// the data (no buffer view, or an external buffer).
const uint8_t* accessorBase(const lodrt::Pack& pack, uint32_t index, uint64_t* stride) {
    const lodrt::AccessorInfo& acc = pack.accessor(index);
    if (acc.buffer_view == lodrt::kNoIndex || acc.is_sparse) return nullptr;
    uint64_t size = 0;
    const uint8_t* view = viewBytes(pack, acc.buffer_view, &size);
    if (!view) return nullptr;
    const uint32_t view_stride = pack.bufferView(acc.buffer_view).byte_stride;
    *stride = view_stride ? view_stride : acc.element_size;
    if (acc.count > 0 && acc.byte_offset + (acc.count - 1) * *stride + acc.element_size > size) return nullptr;
    return view + acc.byte_offset;
}

bool readIndices(const lodrt::Pack& pack, uint32_t index, std::vector<uint32_t>* out) {
    uint64_t stride = 0;
    const uint8_t* base = accessorBase(pack, index, &stride);
    const lodrt::AccessorInfo& acc = pack.accessor(index);
    if (!base || acc.type != lodrt::AccessorType::Scalar) return false;
    out->resize(acc.count);
    for (uint64_t i = 0; i < acc.count; ++i) {
        const uint8_t* p = base + i * stride;
        switch (acc.component_type) {
        case lodrt::ComponentType::UnsignedByte:
            (*out)[i] = p[0];
            break;
        case lodrt::ComponentType::UnsignedShort:
            (*out)[i] = uint32_t(p[0]) | uint32_t(p[1]) << 8;
            break;
        case lodrt::ComponentType::UnsignedInt:
            (*out)[i] = uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
            break;
        default:
            return false;
        }
    }
    return true;
}

bool readPositions(const lodrt::Pack& pack, uint32_t index, std::vector<float>* out) {
    uint64_t stride = 0;
    const uint8_t* base = accessorBase(pack, index, &stride);
    const lodrt::AccessorInfo& acc = pack.accessor(index);
    if (!base || acc.type != lodrt::AccessorType::Vec3 || acc.component_type != lodrt::ComponentType::Float)
        return false;
    out->resize(acc.count * 3);
    for (uint64_t i = 0; i < acc.count; ++i) std::memcpy(&(*out)[i * 3], base + i * stride, 12);
    return true;
}

uint32_t findAttribute(const lodrt::Pack& pack, const lodrt::PrimitiveInfo& prim, std::string_view name) {
    for (uint32_t a = 0; a < prim.attribute_count; ++a)
        if (pack.attribute(prim.first_attribute + a).name == name)
            return pack.attribute(prim.first_attribute + a).accessor;
    return lodrt::kNoIndex;
}

// Sizes of a mesh: vertices and bytes count each accessor once (primitives of one level share streams).
void measureMesh(const lodrt::Pack& pack, uint32_t mesh_index, LodLevelRow& row) {
    const lodrt::MeshInfo& mesh = pack.mesh(mesh_index);
    std::vector<uint32_t> seen, seen_valence;
    auto once = [](std::vector<uint32_t>& list, uint32_t accessor) {
        for (uint32_t a : list)
            if (a == accessor) return false;
        list.push_back(accessor);
        return true;
    };
    auto count = [&](uint32_t accessor) {
        if (!once(seen, accessor)) return false;
        const lodrt::AccessorInfo& acc = pack.accessor(accessor);
        row.bytes += acc.byte_length;
        if (acc.buffer_view != lodrt::kNoIndex) {
            row.plain_bytes += acc.byte_length;
            row.plain_raw += rawBytes(acc);
        }
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
        const lodrt::JsonValue valence = prim.json.find("extensions").find(kValence);
        if (valence.isObject()) {
            row.has_valence = true;
            const uint32_t view = extensionView(pack, valence, "bufferView");
            if (view != lodrt::kNoIndex) row.valence_bytes += pack.bufferView(view).byte_length;
            // What the stream replaces: the attributes it supplies and the indices.
            const lodrt::JsonValue attributes = valence.find("attributes");
            for (uint32_t k = 0; k < attributes.size(); ++k) {
                const uint32_t accessor = findAttribute(pack, prim, attributes.keyAt(k));
                if (accessor != lodrt::kNoIndex && once(seen_valence, accessor))
                    row.valence_raw += rawBytes(pack.accessor(accessor));
            }
            if (prim.indices != lodrt::kNoIndex && once(seen_valence, prim.indices))
                row.valence_raw += rawBytes(pack.accessor(prim.indices));
        }
    }
    const lodrt::JsonValue pfrep = mesh.json.find("extensions").find(kPfrep);
    if (pfrep.isObject()) {
        row.has_pfrep = true;
        const uint32_t view = extensionView(pack, pfrep, "bufferView");
        if (view != lodrt::kNoIndex) row.pfrep_bytes += pack.bufferView(view).byte_length;
        // A PFRep codes the whole refinement of this mesh: compare it with its positions and indices.
        for (uint32_t p = 0; p < mesh.primitive_count; ++p) {
            const lodrt::PrimitiveInfo& prim = pack.primitive(mesh.first_primitive + p);
            const uint32_t position = findAttribute(pack, prim, "POSITION");
            if (position != lodrt::kNoIndex) row.pfrep_raw += rawBytes(pack.accessor(position));
            row.pfrep_raw += prim.triangle_count * 12;
        }
    }
}

// A level's triangles, from the plain accessors or, when they have no data, from the valence stream.
struct DecodedPrimitive {
    std::vector<float> positions;
    std::vector<uint32_t> indices;
    loddump::StreamShading shading; // decoded from the stream only (compact packs)
};

// Decodes primitive `p` of mesh `m`'s LODBAKE_valence_compression stream. Returns false with *error
// set when it fails to decode or contradicts the primitive; *seen is false when there is no stream
// or its bytes are not visible to lodrt (external buffer), which is not an error.
bool decodeValencePrimitive(const lodrt::Pack& pack, uint32_t prim_index, DecodedPrimitive* out, bool* seen,
                            std::string* error) {
    *seen = false;
    const lodrt::PrimitiveInfo& prim = pack.primitive(prim_index);
    const lodrt::JsonValue ext = prim.json.find("extensions").find(kValence);
    if (!ext.isObject()) return true;
    const uint32_t view = extensionView(pack, ext, "bufferView");
    if (view == lodrt::kNoIndex) {
        *seen = true;
        *error = "bufferView: expected a buffer view index below " + std::to_string(pack.bufferViewCount());
        return false;
    }
    uint64_t size = 0;
    const uint8_t* data = viewBytes(pack, view, &size);
    if (!data) return true;
    *seen = true;
    lodrt::ValenceInfo info;
    lodrt::Result r = lodrt::valenceReadInfo(data, size_t(size), &info);
    if (r != lodrt::Result::Ok) {
        *error = std::string("stream fails to decode: header: ") + lodrt::resultName(r);
        return false;
    }
    // The extension object repeats the header's bit depths and says whether the stream has normals
    // (schemas/LODBAKE_valence_compression/README.md): a reader may trust either, so they must agree.
    uint64_t bits = 0;
    if (!ext.find("positionBits").asUint64(&bits) || bits != info.position_bits) {
        *error = "positionBits: " + (ext.find("positionBits").isNumber() ? std::to_string(bits) : std::string("missing")) +
                 "; the stream header says " + std::to_string(info.position_bits);
        return false;
    }
    const bool names_normal = ext.find("attributes").find("NORMAL").isValid();
    if (names_normal != info.has_normals) {
        *error = info.has_normals ? "attributes: the stream has normals but NORMAL is not named"
                                  : "attributes: NORMAL is named but the stream has no normals";
        return false;
    }
    bits = 0;
    if (info.has_normals && (!ext.find("normalBits").asUint64(&bits) || bits != info.normal_bits)) {
        *error = "normalBits: " + (ext.find("normalBits").isNumber() ? std::to_string(bits) : std::string("missing")) +
                 "; the stream header says " + std::to_string(info.normal_bits);
        return false;
    }
    if (info.triangle_count != prim.triangle_count || info.vertex_count != prim.vertex_count) {
        *error = "stream has " + std::to_string(info.vertex_count) + " vertices and " +
                 std::to_string(info.triangle_count) + " triangles, the primitive " +
                 std::to_string(prim.vertex_count) + " and " + std::to_string(prim.triangle_count);
        return false;
    }
    out->positions.assign(size_t(info.vertex_count) * 3, 0.0f);
    out->indices.assign(size_t(info.triangle_count) * 3, 0);
    std::vector<float>& normals = out->shading.normals;
    normals.assign(info.has_normals ? size_t(info.vertex_count) * 3 : 0, 0.0f);
    std::vector<uint64_t> scratch((lodrt::valenceScratchSize(info) + 7) / 8);
    lodrt::ValenceOutput output;
    output.indices = out->indices.data();
    output.index_capacity = out->indices.size();
    output.positions = out->positions.data();
    output.position_capacity = out->positions.size();
    output.normals = normals.empty() ? nullptr : normals.data();
    output.normal_capacity = normals.size();
    // The attributes the contact sheet shades with: UV sets 0 and 1 and the tangents.
    for (uint32_t a = 0; a < info.attribute_count; ++a) {
        const lodrt::ValenceAttribute& attribute = info.attributes[a];
        std::vector<float>* target = nullptr;
        if (attribute.kind == lodrt::format::kValenceAttributeUv && attribute.set < 2)
            target = &out->shading.uvs[attribute.set];
        else if (attribute.kind == lodrt::format::kValenceAttributeTangent)
            target = &out->shading.tangents;
        if (!target || !target->empty()) continue;
        target->assign(size_t(info.vertex_count) * attribute.components, 0.0f);
        output.attributes[a] = target->data();
        output.attribute_capacity[a] = target->size();
    }
    output.scratch = scratch.data();
    output.scratch_size = scratch.size() * 8;
    r = lodrt::valenceDecode(data, size_t(size), output);
    if (r != lodrt::Result::Ok) {
        *error = std::string("stream fails to decode: ") + lodrt::resultName(r);
        return false;
    }
    // Where the plain accessors have data, they must hold the same triangles (each possibly rotated)
    // in the same order, and the same positions up to the quantization step.
    std::vector<uint32_t> plain;
    if (prim.indices != lodrt::kNoIndex && readIndices(pack, prim.indices, &plain) &&
        plain.size() == out->indices.size()) {
        for (size_t t = 0; t < plain.size(); t += 3) {
            const uint32_t* d = &out->indices[t];
            bool same = false;
            for (int k = 0; k < 3 && !same; ++k)
                same = d[0] == plain[t + size_t(k)] && d[1] == plain[t + size_t(k + 1) % 3] &&
                       d[2] == plain[t + size_t(k + 2) % 3];
            if (!same) {
                *error = "decoded triangle " + std::to_string(t / 3) + " differs from the plain indices";
                return false;
            }
        }
    }
    std::vector<float> plain_positions;
    const uint32_t position = findAttribute(pack, prim, "POSITION");
    if (position != lodrt::kNoIndex && readPositions(pack, position, &plain_positions) &&
        plain_positions.size() == out->positions.size()) {
        const double step = double(info.cube_size) / double((1u << info.position_bits) - 1);
        for (size_t i = 0; i < plain_positions.size(); ++i) {
            const double diff = std::fabs(double(plain_positions[i]) - double(out->positions[i]));
            if (!(diff <= step + 1e-6 * double(info.cube_size))) {
                char buf[160];
                std::snprintf(buf, sizeof(buf), "decoded vertex %zu is %.3g from the plain position (step %.3g)", i / 3,
                              diff, step);
                *error = buf;
                return false;
            }
        }
    }
    return true;
}

// An opened PFRep blob on a group's full-detail mesh against the group's chain: the extension's
// header fields are the blob's, its `levels` has one entry per chain level, each entry's removal
// count is in order and within the blob, its `triangles` is what the blob extracts at that count, and that
// count is not above the chain level's own triangle count (equal when the blob comes from the
// chain's collapses; the blob's own half-edge sequence stops at the first level within the level's
// budget, which the chain level reaches too, a step of one or two triangles away: 1 % and 2
// triangles are allowed).
void checkPfrepLevels(const lodrt::JsonValue& pfrep, const lodrt::PfrepModel& model, const std::string& where,
                      const LodGroup& group, std::vector<Problem>& problems) {
    auto field = [&](const char* name, uint64_t want) {
        uint64_t got = 0;
        if (!pfrep.find(name).asUint64(&got) || got != want)
            problems.push_back(
                {where + "/" + name, std::string(name) + ": expected the blob's " + std::to_string(want)});
    };
    field("vertexCount", model.vertex_count);
    field("removedCount", model.removed_count);
    field("triangleCount", model.level0_triangles);
    const lodrt::JsonValue levels = pfrep.find("levels");
    if (levels.size() != group.levels.size()) {
        problems.push_back({where + "/levels", "expected " + std::to_string(group.levels.size()) +
                                                   " levels (one per level of the LOD group), got " +
                                                   std::to_string(levels.size())});
        return;
    }
    std::vector<uint32_t> indices(size_t(model.level0_triangles) * 3);
    uint64_t previous_removals = 0;
    for (uint32_t l = 0; l < levels.size(); ++l) {
        const std::string at = where + "/levels/" + std::to_string(l);
        uint64_t removals = 0, triangles = 0;
        if (!levels.at(l).find("removals").asUint64(&removals) ||
            !levels.at(l).find("triangles").asUint64(&triangles)) {
            problems.push_back({at, "expected integer removals and triangles"});
            continue;
        }
        if (removals > model.removed_count || removals < previous_removals || (l == 0 && removals != 0)) {
            problems.push_back({at + "/removals", "PFRep level " + std::to_string(removals) +
                                                      (l == 0 ? ": the first level must be 0"
                                                              : ": expected at least the previous level's and at most "
                                                                "removedCount (" +
                                                                    std::to_string(model.removed_count) + ")")});
            continue;
        }
        size_t extracted = 0;
        if (lodrt::pfrepExtractLevel(model, uint32_t(removals), indices.data(), model.level0_triangles, &extracted) !=
                lodrt::Result::Ok ||
            extracted != triangles) {
            problems.push_back({at + "/triangles", "PFRep level " + std::to_string(removals) + " has " +
                                                       std::to_string(extracted) + " triangles, the extension says " +
                                                       std::to_string(triangles)});
            continue;
        }
        // Finer than the chain level it stands for: it would not fit that level's triangle budget.
        // (Coarser is allowed: a chain that cannot reach a level's budget, held by UV seams or locked
        // points, keeps more triangles than it, while the blob's sequence reaches it.)
        const uint64_t chain = group.levels[l].triangles;
        if (triangles > chain && double(triangles - chain) > 0.01 * double(chain) + 2.0)
            problems.push_back({at, "PFRep level " + std::to_string(removals) + " (" + std::to_string(triangles) +
                                        " triangles) disagrees with chain level " + std::to_string(l) + " (" +
                                        std::to_string(chain) + " triangles): finer than the level it stands for"});
        previous_removals = removals;
    }
}

// A region blob (format 5) with every block loaded, which makes `decoded` the format 2 blob.
lodrt::Result loadAllRegions(const uint8_t* data, size_t size, std::vector<uint8_t>& decoded) {
    lodrt::PfrepRegionInfo info;
    lodrt::Result r = lodrt::pfrepRegionInfo(data, size, &info);
    if (r != lodrt::Result::Ok) return r;
    if (info.blob_size != size) return lodrt::Result::BadStructure;
    decoded.assign(info.decoded_bytes, 0);
    std::vector<uint64_t> state((info.state_bytes + 7) / 8);
    lodrt::PfrepRegions regions;
    r = lodrt::pfrepRegionOpen(data, size, decoded.data(), decoded.size(), state.data(), state.size() * 8, &regions);
    for (uint32_t k = 0; r == lodrt::Result::Ok && k < regions.block_count; ++k)
        r = lodrt::pfrepRegionLoadBlock(&regions, k, data + regions.blocks[k].offset, regions.blocks[k].size);
    return r;
}

// The extension's blob as a model: format 2 opened in place, format 3 decoded first (into `decoded`),
// format 4 decoded against the mesh's (one) primitive's valence stream, format 5 (region blocks)
// with every block loaded.
lodrt::Result openPackPfrep(const lodrt::Pack& pack, const lodrt::MeshInfo& mesh, uint32_t format, const uint8_t* data,
                            size_t size, std::vector<uint8_t>& decoded, lodrt::PfrepModel* model) {
    if (format == lodrt::format::kPfrepVersion) return lodrt::openPfrep(data, size, model);
    if (format == lodrt::format::kPfrepFormatRegions) {
        const lodrt::Result r = loadAllRegions(data, size, decoded);
        return r == lodrt::Result::Ok ? lodrt::openPfrep(decoded.data(), decoded.size(), model) : r;
    }
    if (format == lodrt::format::kPfrepVersionLod0) {
        if (mesh.primitive_count != 1) return lodrt::Result::BadStructure;
        const lodrt::JsonValue ext = pack.primitive(mesh.first_primitive).json.find("extensions").find(kValence);
        const uint32_t view = ext.isObject() ? extensionView(pack, ext, "bufferView") : lodrt::kNoIndex;
        uint64_t stream_size = 0;
        const uint8_t* stream = view == lodrt::kNoIndex ? nullptr : viewBytes(pack, view, &stream_size);
        if (!stream) return lodrt::Result::BadStructure;
        lodrt::PfrepPackFormat4Info info;
        lodrt::Result r = lodrt::pfrepPackFormat4Info(data, size, stream, size_t(stream_size), &info);
        if (r != lodrt::Result::Ok) return r;
        decoded.resize(info.decoded_bytes);
        std::vector<uint64_t> scratch((info.scratch_bytes + 7) / 8);
        return lodrt::pfrepDecodePackFormat4(data, size, stream, size_t(stream_size), decoded.data(), decoded.size(),
                                             scratch.data(), scratch.size() * 8, model);
    }
    lodrt::PfrepCompressedInfo info;
    lodrt::Result r = lodrt::pfrepCompressedInfo(data, size, &info);
    if (r != lodrt::Result::Ok) return r;
    decoded.resize(info.decoded_bytes);
    std::vector<uint64_t> scratch((info.scratch_bytes + 7) / 8);
    return lodrt::pfrepDecompress(data, size, decoded.data(), decoded.size(), scratch.data(), info.scratch_bytes, model);
}

// Checks every compressed stream of the pack: valence streams decode and agree with the primitive;
// PFRep blobs open and code the same full-detail triangle count as the mesh they sit on, and on a
// group's full-detail mesh agree with the group's levels (checkPfrepLevels).
void checkStreams(const lodrt::Pack& pack, const std::vector<LodGroup>& groups, std::vector<Problem>& problems) {
    for (uint32_t m = 0; m < pack.meshCount(); ++m) {
        const lodrt::MeshInfo& mesh = pack.mesh(m);
        const std::string mesh_pointer = "/meshes/" + std::to_string(m);
        uint64_t mesh_triangles = 0;
        for (uint32_t p = 0; p < mesh.primitive_count; ++p) {
            mesh_triangles += pack.primitive(mesh.first_primitive + p).triangle_count;
            DecodedPrimitive decoded;
            bool seen = false;
            std::string error;
            if (!decodeValencePrimitive(pack, mesh.first_primitive + p, &decoded, &seen, &error))
                problems.push_back(
                    {mesh_pointer + "/primitives/" + std::to_string(p) + "/extensions/" + std::string(kValence),
                     error});
        }
        const lodrt::JsonValue pfrep = mesh.json.find("extensions").find(kPfrep);
        if (!pfrep.isObject()) continue;
        const std::string where = mesh_pointer + "/extensions/" + std::string(kPfrep);
        const uint32_t view = extensionView(pack, pfrep, "bufferView");
        uint64_t size = 0;
        const uint8_t* data = view == lodrt::kNoIndex ? nullptr : viewBytes(pack, view, &size);
        if (view == lodrt::kNoIndex) {
            problems.push_back({where, "bufferView: expected a buffer view index"});
            continue;
        }
        if (!data) continue;
        uint64_t format = lodrt::format::kPfrepVersion;
        const lodrt::JsonValue format_member = pfrep.find(lodrt::format::kPfrepExtensionFormatMember);
        if (format_member.isValid() &&
            (!format_member.asUint64(&format) || !lodrt::format::isPfrepPackFormat(format))) {
            problems.push_back({where + "/format", "format: expected 2, 3, 4 or 5"});
            continue;
        }
        lodrt::PfrepModel model;
        std::vector<uint8_t> decoded; // format 3, 4, 5: the format 2 bytes it decodes to (model points into them)
        const lodrt::Result r = openPackPfrep(pack, mesh, uint32_t(format), data, size_t(size), decoded, &model);
        if (r != lodrt::Result::Ok) {
            problems.push_back(
                {where, std::string("stream fails to decode") +
                            (format == lodrt::format::kPfrepVersion ? std::string(": ")
                                                                    : " (format " + std::to_string(format) + "): ") +
                            lodrt::resultName(r)});
            continue;
        }
        if (model.level0_triangles != mesh_triangles)
            problems.push_back({where, "PFRep full detail has " + std::to_string(model.level0_triangles) +
                                           " triangles, the mesh (chain level 0) " + std::to_string(mesh_triangles)});
        for (const LodGroup& group : groups)
            if (!group.levels.empty() && group.levels[0].mesh == m)
                checkPfrepLevels(pfrep, model, where, group, problems);
    }
}

// LODBAKE_cluster_lod on any mesh: read, every page decoded, the hierarchy checked (dump_clusters.h).
void checkClusters(const lodrt::Pack& pack, LodReport& report) {
    for (uint32_t m = 0; m < pack.meshCount(); ++m) {
        if (!pack.mesh(m).json.find("extensions").find(lodrt::format::kExtClusterLod).isValid()) continue;
        loddump::ClusterSummary summary;
        std::string error;
        if (loddump::checkClusterLod(pack, m, &summary, &error))
            report.clusters.push_back(std::move(summary));
        else
            report.problems.push_back(
                {"/meshes/" + std::to_string(m) + "/extensions/" + std::string(lodrt::format::kExtClusterLod), error});
    }
}

// The hierarchy per depth and its bytes.
void printClusterText(const LodReport& report) {
    for (const loddump::ClusterSummary& s : report.clusters) {
        std::printf("cluster LOD on mesh %u (%s): %u clusters, %u groups, %u roots, %u pages, %u with a normal "
                    "cone; grid %u bits, quantization error %.4g\n",
                    s.mesh, lodrt::format::kExtClusterLod, s.clusters, s.groups, s.roots, s.pages, s.cone_clusters,
                    s.position_bits, s.quantization_error);
        std::printf("  bytes: table %llu, pages %llu (%.2f per LOD0 triangle; page %llu..%llu)\n", ull(s.table_bytes),
                    ull(s.page_bytes),
                    s.lod0_triangles ? double(s.table_bytes + s.page_bytes) / double(s.lod0_triangles) : 0.0,
                    ull(s.min_page_bytes), ull(s.max_page_bytes));
        std::printf("  %5s %9s %11s %12s\n", "depth", "clusters", "triangles", "max error");
        for (const loddump::ClusterDepthRow& r : s.depths)
            std::printf("  %5u %9llu %11llu %12.4g\n", r.depth, ull(r.clusters), ull(r.triangles), r.max_error);
        std::printf("  checks: pages decode, errors and LOD spheres grow up the DAG, every cluster reachable, %u cuts "
                    "crack-free\n",
                    s.cuts_checked);
    }
}

std::string nodePointer(uint32_t node) {
    return "/nodes/" + std::to_string(node);
}

// A chain whose simplifier stopped early can repeat a level or leap from a good level to a ruined
// one: two neighbours with the same triangle count (an error: a level that adds nothing), or a
// Hausdorff error more than kMaxErrorStep times the finer level's (a warning: a coarse level of a
// hard input, or one after a much better finer level, can step that far legitimately). Checked after
// everything else, so a pack with a broken stream or id still reports that first.
constexpr double kMaxErrorStep = 4.0;

// The bake's default lod_min_switch_ratio (BakeSettings): a level taken over by the next one less
// than this many times farther than its own switch distance is drawn over almost no distances.
constexpr double kMinSwitchRatio = 1.05;

// lodrt's selection takes the coarsest level whose switch distance (its Hausdorff error in float
// times K / pixel threshold, runtime/src/selection.cpp) has been passed: a level whose switch distance
// is the next level's is never selected (an error: dead weight the bake drops, docs/bake.md "Dead
// levels"), and LOD0 is never selected when level 1's is 0 (a warning: viewers without MSFT_lod
// still show it). A level after LOD0 whose next level is taken less than kMinSwitchRatio times
// farther is a warning (a pack baked with a smaller lod_min_switch_ratio, or before the rule).
// Computed as the runtime does, for the screen the pack was baked for.
void checkNeverSelected(const LodGroup& group, LodReport& report) {
    const float k = lodrt::pixelsPerUnitAtDistanceOne(group.screen);
    const float p = group.screen.pixel_threshold == 0 ? 1.0f : group.screen.pixel_threshold;
    if (!(k > 0) || !std::isfinite(k)) return; // a screen the runtime refuses: other checks report it
    auto distance = [&](const LodLevelRow& row) { return float(row.hausdorff) * k / p; };
    for (uint32_t l = 0; l + 1 < group.levels.size(); ++l) {
        const LodLevelRow& a = group.levels[l];
        const LodLevelRow& b = group.levels[l + 1];
        if (!b.has_metrics || (l > 0 && !a.has_metrics)) continue;
        const float da = l == 0 ? 0.0f : distance(a), db = distance(b);
        if (l > 0 && db > da && double(db) <= kMinSwitchRatio * double(da)) {
            char band[96];
            std::snprintf(band, sizeof band, "%.7g to %.7g, a factor %.5g", double(da), double(db), double(db / da));
            report.warnings.push_back({nodePointer(a.node), "level " + std::to_string(l) + " is selected only from " +
                                                                band + " (at most 1.05)"});
        }
        if (!(db <= da)) continue;
        char text[64];
        std::snprintf(text, sizeof text, "%.7g", double(db));
        const std::string msg = "level " + std::to_string(l) + " is never selected: level " + std::to_string(l + 1) +
                                " is taken at the same switch distance (" + text + ")";
        if (l == 0)
            report.warnings.push_back({nodePointer(b.node), msg});
        else
            report.problems.push_back({nodePointer(a.node), msg});
    }
}

void checkLevelSteps(LodReport& report) {
    for (const LodGroup& group : report.groups) {
        checkNeverSelected(group, report);
        for (uint32_t l = 1; l < group.levels.size(); ++l) {
            const LodLevelRow& a = group.levels[l - 1];
            const LodLevelRow& b = group.levels[l];
            const std::string where = nodePointer(b.node);
            const std::string lvl = "level " + std::to_string(l);
            if (a.mesh != lodrt::kNoIndex && b.mesh != lodrt::kNoIndex && a.triangles == b.triangles)
                report.problems.push_back({where, lvl + ": the same " + std::to_string(b.triangles) +
                                                      " triangles as level " + std::to_string(l - 1) +
                                                      " (a repeated level)"});
            if (a.has_metrics && b.has_metrics && a.hausdorff > 0.0 && b.hausdorff > kMaxErrorStep * a.hausdorff) {
                char step[32];
                std::snprintf(step, sizeof step, "%.3g", b.hausdorff / a.hausdorff);
                report.warnings.push_back({where, lvl + ": Hausdorff error " + step + " times level " +
                                                      std::to_string(l - 1) + "'s (more than 4 times)"});
            }
        }
    }
}

LodReport analyseLods(const lodrt::Pack& pack) {
    LodReport report;
    const uint32_t node_count = pack.nodeCount();
    // Nodes referenced as a lower level are not group roots.
    std::vector<bool> is_lower(node_count, false);
    for (uint32_t n = 0; n < node_count; ++n) {
        const lodrt::JsonValue ids = pack.node(n).json.find("extensions").find(lodrt::format::kExtMsftLod).find("ids");
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
            const lodrt::JsonValue ids = pack.node(n).json.find("extensions").find(lodrt::format::kExtMsftLod).find("ids");
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
                     std::string(lodrt::format::kExtMsftLod) + " cycle: node " + std::to_string(id) + " leads back to node " + std::to_string(n)});
            } else if (state[size_t(id)] == 0) {
                state[size_t(id)] = 1;
                stack.push_back({uint32_t(id), 0});
            }
        }
    }
    for (uint32_t n = 0; n < node_count; ++n) {
        const lodrt::JsonValue lod = pack.node(n).json.find("extensions").find(lodrt::format::kExtMsftLod);
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
                        {where, std::string(lodrt::format::kExtMsftLod) + " cycle: node " + std::to_string(id) + " is already a level of this group"});
                    ok = false;
                }
            if (ok) chain.push_back(uint32_t(id));
        }
        const lodrt::JsonValue metrics_object =
            pack.node(n).json.find("extensions").find(lodrt::format::kExtLodMetrics);
        const lodrt::JsonValue metrics = metrics_object.find("levels");
        group.screen.pixel_threshold = float(metrics_object.find("pixelThreshold").number());
        group.screen.viewport_height = float(metrics_object.find("viewportHeight").number());
        group.screen.vertical_fov = float(metrics_object.find("verticalFov").number());
        const lodrt::JsonValue input_triangles = metrics_object.find(lodrt::format::kLodMetricsInputTriangles);
        const lodrt::JsonValue coverage = pack.node(n).json.find("extras").find(lodrt::format::kMsftScreenCoverage);
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
            uint64_t listed = 0;
            if (m.isObject() && row.mesh != lodrt::kNoIndex &&
                (!m.find("triangles").asUint64(&listed) || listed != row.triangles))
                report.problems.push_back({nodePointer(n) + "/extensions/LODBAKE_lod_metrics/levels/" +
                                               std::to_string(l) + "/triangles",
                                           "level " + std::to_string(l) + ": " + std::to_string(listed) +
                                               " triangles, the level's mesh has " + std::to_string(row.triangles)});
            if (coverage.at(l).isNumber()) {
                row.has_coverage = true;
                row.coverage = coverage.at(l).number();
            }
            group.levels.push_back(row);
        }
        if (input_triangles.isValid() &&
            (!input_triangles.asUint64(&group.input_triangles) || group.levels.empty() ||
             group.input_triangles < group.levels[0].triangles))
            report.problems.push_back({nodePointer(n) + "/extensions/LODBAKE_lod_metrics/" +
                                           lodrt::format::kLodMetricsInputTriangles,
                                       "expected an integer at least level 0's triangle count"});
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
    checkStreams(pack, report.groups, report.problems);
    checkClusters(pack, report);
    checkLevelSteps(report);
    return report;
}

// The `coverage` column: the screen coverage at which level `l` takes over, the value the bake's
// report lists (LODBAKE_lod_metrics screenCoverage, at the level's switch distance), so the column
// sits with switch_dist. Without the metrics, the finer level's MSFT_screencoverage (where it hands
// over), 1 for level 0. False when the pack says neither.
bool levelCoverage(const LodGroup& g, uint32_t l, double* coverage) {
    const LodLevelRow& r = g.levels[l];
    if (r.has_metrics) {
        *coverage = r.metric_coverage;
        return true;
    }
    if (l == 0 && r.has_coverage) {
        *coverage = 1.0;
        return true;
    }
    if (l > 0 && g.levels[l - 1].has_coverage) {
        *coverage = g.levels[l - 1].coverage;
        return true;
    }
    return false;
}

bool levelSelected(int level_filter, uint32_t level) {
    return level_filter < 0 || uint32_t(level_filter) == level;
}

// "BYTES RATIO" for one stream column, "-" when the level has no such stream.
std::string streamCell(bool present, uint64_t bytes, uint64_t raw) {
    if (!present) return "-";
    char buf[48];
    if (raw > 0)
        std::snprintf(buf, sizeof(buf), "%llu %.3f", ull(bytes), double(bytes) / double(raw));
    else
        std::snprintf(buf, sizeof(buf), "%llu -", ull(bytes));
    return buf;
}

void printLodText(const lodrt::Pack& pack, const LodReport& report, int level_filter) {
    for (const LodGroup& g : report.groups) {
        std::printf("lod group \"%s\" (node %u): %zu levels\n", printable(pack.node(g.root).name).c_str(), g.root,
                    g.levels.size());
        if (g.input_triangles > 0 && !g.levels.empty())
            std::printf("  input: %llu triangles; the chain starts %s\n", ull(g.input_triangles),
                        g.input_triangles > g.levels[0].triangles
                            ? "below it (level 0 is a cut of the cluster hierarchy)"
                            : "at it");
        std::printf("  %-5s %5s %5s %10s %10s %11s %11s %9s %11s %17s %17s %17s\n", "level", "node", "mesh",
                    "triangles", "vertices", "hausdorff", "mean", "coverage", "switch_dist", "plain  ratio",
                    "valence  ratio", "pfrep  ratio");
        for (uint32_t l = 0; l < g.levels.size(); ++l) {
            if (!levelSelected(level_filter, l)) continue;
            const LodLevelRow& r = g.levels[l];
            char hd[32] = "-", mn[32] = "-", cov[32] = "-", sw[32] = "-";
            if (r.has_metrics) {
                std::snprintf(hd, sizeof(hd), "%.4g", r.hausdorff);
                std::snprintf(mn, sizeof(mn), "%.4g", r.mean);
                std::snprintf(sw, sizeof(sw), "%.4g", r.switch_distance);
            }
            double coverage = 0;
            if (levelCoverage(g, l, &coverage)) std::snprintf(cov, sizeof(cov), "%.4g", coverage);
            std::printf("  %-5u %5u %5d %10llu %10llu %11s %11s %9s %11s %17s %17s %17s\n", l, r.node,
                        r.mesh == lodrt::kNoIndex ? -1 : int(r.mesh), ull(r.triangles), ull(r.vertices), hd, mn, cov,
                        sw, streamCell(true, r.plain_bytes, r.plain_raw).c_str(),
                        streamCell(r.has_valence, r.valence_bytes, r.valence_raw).c_str(),
                        streamCell(r.has_pfrep, r.pfrep_bytes, r.pfrep_raw).c_str());
        }
        uint64_t plain = 0, plain_raw = 0, valence = 0, valence_raw = 0;
        for (const LodLevelRow& r : g.levels) {
            plain += r.plain_bytes;
            plain_raw += r.plain_raw;
            valence += r.valence_bytes;
            valence_raw += r.valence_raw;
        }
        std::printf("  all levels: plain %s, valence %s\n", streamCell(true, plain, plain_raw).c_str(),
                    streamCell(valence > 0, valence, valence_raw).c_str());
    }
}

std::string lodJson(const lodrt::Pack& pack, const LodReport& report, int level_filter) {
    std::string out = "  \"lodGroups\": [";
    char buf[512];
    for (size_t gi = 0; gi < report.groups.size(); ++gi) {
        const LodGroup& g = report.groups[gi];
        out += gi ? ",\n    " : "\n    ";
        out += "{\"node\": " + std::to_string(g.root) + ", \"name\": " + jsonString(pack.node(g.root).name);
        if (g.input_triangles > 0) out += ", \"inputTriangles\": " + std::to_string(g.input_triangles);
        out += ", \"levels\": [";
        bool first = true;
        for (uint32_t l = 0; l < g.levels.size(); ++l) {
            if (!levelSelected(level_filter, l)) continue;
            const LodLevelRow& r = g.levels[l];
            double coverage = 0;
            levelCoverage(g, l, &coverage);
            std::snprintf(buf, sizeof(buf),
                          "{\"level\": %u, \"node\": %u, \"triangles\": %llu, \"vertices\": %llu, \"bytes\": %llu, "
                          "\"hausdorffError\": %.17g, \"meanError\": %.17g, \"switchDistance\": %.17g, "
                          "\"screenCoverage\": %.17g, \"streams\": {\"plain\": {\"bytes\": %llu, \"rawBytes\": %llu}",
                          l, r.node, ull(r.triangles), ull(r.vertices), ull(r.bytes), r.hausdorff, r.mean,
                          r.switch_distance, coverage, ull(r.plain_bytes), ull(r.plain_raw));
            std::string streams = buf;
            if (r.has_coverage) {
                std::snprintf(buf, sizeof(buf), ", \"msftScreenCoverage\": %.17g", r.coverage);
                streams.insert(streams.find(", \"streams\""), buf);
            }
            if (r.has_valence) {
                std::snprintf(buf, sizeof(buf), ", \"valence\": {\"bytes\": %llu, \"rawBytes\": %llu}",
                              ull(r.valence_bytes), ull(r.valence_raw));
                streams += buf;
            }
            if (r.has_pfrep) {
                std::snprintf(buf, sizeof(buf), ", \"pfrep\": {\"bytes\": %llu, \"rawBytes\": %llu}",
                              ull(r.pfrep_bytes), ull(r.pfrep_raw));
                streams += buf;
            }
            out += first ? "\n      " : ",\n      ";
            out += streams + "}}";
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
    printClusterText(lods);
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
    if (pack.warningCount() == 0 && lods.problems.empty() && lods.warnings.empty()) std::printf(" none");
    std::printf("\n");
    for (uint32_t w = 0; w < pack.warningCount(); ++w)
        std::printf("  warning %s: %s\n", pack.warning(w).pointer, pack.warning(w).message);
    for (const Problem& p : lods.warnings) std::printf("  warning %s: %s\n", p.pointer.c_str(), p.message.c_str());
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
        for (const Problem& p : lods->warnings) addProblem("warning", p.pointer.c_str(), p.message.c_str());
        for (const Problem& p : lods->problems) addProblem("error", p.pointer.c_str(), p.message.c_str());
    }
    out += problem_count ? "\n  ]\n}\n" : "]\n}\n";
    std::fwrite(out.data(), 1, out.size(), stdout);
}

// The level's triangles for the picture: every primitive's plain data, or its decoded valence stream
// when the plain accessors carry none (compact packs).
loddump::SheetMesh levelTriangles(const lodrt::Pack& pack, const LodLevelRow& row, uint32_t level,
                                  loddump::SheetTextures& textures) {
    loddump::SheetMesh out;
    out.label = "L" + std::to_string(level) + " " + std::to_string(row.triangles) + " tris";
    if (row.mesh == lodrt::kNoIndex) return out;
    const lodrt::MeshInfo& mesh = pack.mesh(row.mesh);
    for (uint32_t p = 0; p < mesh.primitive_count; ++p) {
        const lodrt::PrimitiveInfo& prim = pack.primitive(mesh.first_primitive + p);
        if (prim.mode != 4) continue;
        DecodedPrimitive d;
        const uint32_t position = findAttribute(pack, prim, "POSITION");
        bool ok = position != lodrt::kNoIndex && readPositions(pack, position, &d.positions);
        if (ok) {
            if (prim.indices != lodrt::kNoIndex) {
                ok = readIndices(pack, prim.indices, &d.indices);
            } else {
                d.indices.resize(d.positions.size() / 3);
                for (size_t i = 0; i < d.indices.size(); ++i) d.indices[i] = uint32_t(i);
            }
        }
        if (!ok) {
            bool seen = false;
            std::string error;
            d = DecodedPrimitive();
            if (!decodeValencePrimitive(pack, mesh.first_primitive + p, &d, &seen, &error) || !seen) continue;
        }
        const uint32_t base = uint32_t(out.positions.size() / 3);
        out.positions.insert(out.positions.end(), d.positions.begin(), d.positions.end());
        for (uint32_t i : d.indices) out.indices.push_back(base + i);
        loddump::appendShading(pack, prim, d.positions.size() / 3, d.indices.size() / 3, d.shading, textures, &out);
    }
    return out;
}

using WriteRgb8 = int (*)(const char*, const uint8_t*, uint32_t, uint32_t, char*, size_t);
using ReadRgba8 = int (*)(const uint8_t*, size_t, uint8_t**, uint32_t*, uint32_t*, char*, size_t);
using FreeFn = void (*)(void*);

// The image module's entry points (png_module.cpp).
struct ImageModule {
    WriteRgb8 write = nullptr;
    ReadRgba8 read = nullptr;
    FreeFn release = nullptr;
};

// Loads the image module: $LODDUMP_OIIO_MODULE, then beside the executable (installed:
// ../lib/lodbake/), then the build tree.
bool loadImageModule(ImageModule* module, std::string* error) {
#ifdef LODDUMP_OIIO_MODULE_NAME
    const auto resolve = [module](void* handle) {
        module->write = reinterpret_cast<WriteRgb8>(dlsym(handle, "loddump_write_rgb8"));
        module->read = reinterpret_cast<ReadRgba8>(dlsym(handle, "loddump_read_rgba8"));
        module->release = reinterpret_cast<FreeFn>(dlsym(handle, "loddump_free"));
        return module->write && module->read && module->release;
    };
    if (lodtools::openToolModule("LODDUMP_OIIO_MODULE", LODDUMP_OIIO_MODULE_NAME, LODDUMP_OIIO_MODULE_BUILD_PATH,
                                 "loddump's image module (OpenImageIO: loddump_write_rgb8, loddump_read_rgba8, "
                                 "loddump_free)",
                                 resolve, error))
        return true;
#else
    (void)module;
    *error = "this loddump was built without OpenImageIO, so --render is not available";
#endif
    return false;
}

int renderSheet(const lodrt::Pack& pack, const LodReport& report, int level_filter, const char* out_path,
                bool wireframe) {
    ImageModule module;
    std::string error;
    if (!loadImageModule(&module, &error)) {
        std::fprintf(stderr, "error: %s: %s\n", out_path, error.c_str());
        return kExitBadPack;
    }
    // The levels are shaded with their textures, decoded once each through the image module.
    loddump::SheetTextures textures(pack, [&](const uint8_t* data, size_t size, loddump::SheetTexture* out,
                                              std::string* why) {
        uint8_t* pixels = nullptr;
        char message[512] = "";
        if (module.read(data, size, &pixels, &out->width, &out->height, message, sizeof(message)) != 0) {
            *why = message;
            return false;
        }
        out->rgba.assign(pixels, pixels + size_t(out->width) * out->height * 4);
        module.release(pixels);
        return true;
    });
    std::vector<std::vector<loddump::SheetMesh>> rows;
    for (const LodGroup& g : report.groups) {
        rows.emplace_back();
        for (uint32_t l = 0; l < g.levels.size(); ++l)
            if (levelSelected(level_filter, l)) rows.back().push_back(levelTriangles(pack, g.levels[l], l, textures));
        // A cluster hierarchy on the group's LOD0 mesh: a row of its cuts beside the chain's.
        const uint32_t lod0 = g.levels.empty() ? lodrt::kNoIndex : g.levels[0].mesh;
        if (lod0 != lodrt::kNoIndex &&
            pack.mesh(lod0).json.find("extensions").find(lodrt::format::kExtClusterLod).isValid()) {
            std::vector<loddump::SheetMesh> cuts;
            std::string why;
            if (!loddump::clusterCutSheets(pack, lod0, &cuts, &why)) {
                std::fprintf(stderr, "error: %s: /meshes/%u/extensions/%s: %s\n", out_path, lod0,
                             lodrt::format::kExtClusterLod, why.c_str());
                return kExitBadPack;
            }
            rows.push_back(std::move(cuts));
        }
    }
    if (report.groups.empty()) {
        // No LOD group: one row of every mesh instanced by a node.
        rows.emplace_back();
        for (uint32_t n = 0; n < pack.nodeCount(); ++n) {
            LodLevelRow row;
            row.mesh = pack.node(n).mesh;
            if (row.mesh == lodrt::kNoIndex) continue;
            measureMesh(pack, row.mesh, row);
            rows.back().push_back(levelTriangles(pack, row, uint32_t(rows.back().size()), textures));
        }
    }
    loddump::SheetOptions options;
    options.wireframe = wireframe;
    const loddump::SheetImage image = loddump::renderContactSheet(rows, options);
    // A texture that does not decode is drawn with its material's factor alone, and said.
    for (const std::string& problem : textures.problems())
        std::fprintf(stderr, "warning: %s: %s: drawn without this texture\n", out_path, problem.c_str());
    char message[512] = "";
    if (module.write(out_path, image.rgb.data(), image.width, image.height, message, sizeof(message)) != 0) {
        std::fprintf(stderr, "error: %s: %s\n", out_path, message);
        return kExitBadPack;
    }
    return kExitOk;
}

} // namespace

int main(int argc, char** argv) {
    const char* path = nullptr;
    bool as_json = false;
    bool wireframe = false;
    const char* render_path = nullptr;
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
        } else if (arg == "--render") {
            if (i + 1 >= argc || *argv[i + 1] == '\0') {
                std::fprintf(stderr, "error: --render expects an output image path (OUT.png)\n");
                printUsage(stderr);
                return kExitUsage;
            }
            render_path = argv[++i];
        } else if (arg == "--wireframe") {
            wireframe = true;
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
    if (wireframe && !render_path) {
        std::fprintf(stderr, "error: --wireframe needs --render OUT.png\n");
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
    int status = kExitOk;
    if (render_path) status = renderSheet(pack, lods, level_filter, render_path, wireframe);
    if (!lods.problems.empty()) {
        std::fprintf(stderr, "error: %s: %s: %s\n", path, lods.problems[0].pointer.c_str(),
                     lods.problems[0].message.c_str());
        return kExitBadPack;
    }
    return status;
}
