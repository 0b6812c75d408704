// Wavefront OBJ and MTL reading and writing. The statement set follows the "Object Files (.obj)"
// chapter of the Wavefront Advanced Visualizer manual (Appendix B1) and its MTL chapter (B2);
// free-form geometry, lines and points are recognised and skipped.
//
// Reading: corners are unified per distinct (v, vt, vn) triple, in order of first use, because a GPU
// vertex carries all three. Faces are then grouped by material so that every sub-mesh is one
// contiguous index range, materials ordered by first use and faces kept in file order inside each.
//
// Material mapping (MTL → metallic-roughness):
//   Kd → base colour (sRGB → linear), d or 1 - Tr → base colour alpha (Blend when below 1),
//   Ke → emissive (sRGB → linear), Pm → metallic (0 when absent), Pr → roughness; without Pr the
//   Blinn-Phong exponent maps as roughness = sqrt(2 / (Ns + 2)), the usual Beckmann-to-Phong
//   correspondence (Walter et al. 2007, "Microfacet models for refraction", eq. 33 inverted), so
//   Ns 0 → 1 (matte), Ns 1000 → 0.045 (polished); no Ns → roughness 1.
//   map_Kd → base colour texture, map_Bump / bump / norm → normal texture (-bm → normal scale),
//   map_Ke → emissive texture.

#include "lodbake/io/obj.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>

#include "io/obj_syntax.h"
#include "io/polygon_triangulation.h"
#include "io/text_scan.h"
#include "lodbake/core/file_io.h"

namespace lodbake {

namespace {

using detail::excerpt;
using detail::nextToken;
using detail::parseFloat;
using detail::parseInt;
using detail::trim;
using namespace detail::obj;

std::string lower(std::string_view s) {
    std::string out(s);
    for (char& c : out)
        if (c >= 'A' && c <= 'Z') c = char(c - 'A' + 'a');
    return out;
}

bool endsWithIgnoreCase(std::string_view s, std::string_view suffix) {
    return s.size() >= suffix.size() && lower(s.substr(s.size() - suffix.size())) == suffix;
}

// Side-file names as written; backslashes (Windows exporters) become slashes.
std::string normalizeRelativePath(std::string_view s) {
    std::string out(s);
    std::replace(out.begin(), out.end(), '\\', '/');
    return out;
}

std::string mimeFromBytes(const std::vector<uint8_t>& b) {
    if (b.size() >= 8 && b[0] == 0x89 && b[1] == 'P' && b[2] == 'N' && b[3] == 'G') return "image/png";
    if (b.size() >= 3 && b[0] == 0xff && b[1] == 0xd8 && b[2] == 0xff) return "image/jpeg";
    return "";
}

std::string mimeFromName(const std::string& name) {
    const std::string ext = lowerExtension(name);
    if (ext == ".png") return "image/png";
    if (ext == ".jpg" || ext == ".jpeg") return "image/jpeg";
    return "";
}

std::string stemOf(const std::string& path) {
    const size_t slash = path.find_last_of('/');
    std::string file = slash == std::string::npos ? path : path.substr(slash + 1);
    const size_t dot = file.find_last_of('.');
    return dot == std::string::npos || dot == 0 ? file : file.substr(0, dot);
}

// ---------------------------------------------------------------------------------------------------
// MTL

struct PendingTexture {
    std::string path; // as written, slashes normalised
    uint64_t line = 0;
};

struct MtlMaterial {
    Material material;
    PendingTexture base_color;
    PendingTexture normal;
    PendingTexture emissive;
    bool has_pr = false;
    float ns = -1.0f; // -1: not given
    std::string mtl_display;
};

class MtlParser {
public:
    MtlParser(const std::string& obj_name, std::string mtl_display, Diagnostics& diagnostics)
        : obj_name_(obj_name), mtl_display_(std::move(mtl_display)), diagnostics_(diagnostics) {}

    Status parse(const std::vector<uint8_t>& bytes, std::vector<MtlMaterial>& out) {
        LineReader reader(bytes.data(), bytes.size());
        std::string_view line;
        std::string read_error;
        while (reader.next(line, line_, read_error)) {
            std::string_view rest = line;
            const std::string_view key = nextToken(rest);
            if (key.empty()) continue;
            if (!isPlainKeyword(key)) return fail("expected an MTL statement, got '" + excerpt(key) + "'");
            const std::string k = lower(key);
            if (k == "newmtl") {
                const std::string_view name = trim(rest);
                if (name.empty()) return fail("newmtl: expected a material name");
                out.emplace_back();
                out.back().material.name = std::string(name);
                out.back().material.metallic_factor = 0.0f;
                out.back().mtl_display = mtl_display_;
                continue;
            }
            const bool known = k == "kd" || k == "d" || k == "tr" || k == "ke" || k == "ns" || k == "pr" || k == "pm" ||
                               k == "map_kd" || k == "map_bump" || k == "bump" || k == "norm" || k == "map_ke";
            if (!known) {
                // Ka, Ks, Ni, illum, Tf, map_Ks, map_d, disp, refl, ... have no glTF counterpart.
                ++ignored_;
                continue;
            }
            if (out.empty()) return fail(std::string(key) + ": statement before any newmtl");
            MtlMaterial& m = out.back();
            Material& mat = m.material;
            if (k == "kd" || k == "ke") {
                if (trim(rest).rfind("spectral", 0) == 0 || trim(rest).rfind("xyz", 0) == 0) {
                    ++ignored_;
                    continue;
                }
                float c[3];
                LODBAKE_RETURN_IF_ERROR(readColor(key, rest, c));
                if (k == "kd") {
                    mat.base_color_factor.x = detail::srgbToLinear(c[0]);
                    mat.base_color_factor.y = detail::srgbToLinear(c[1]);
                    mat.base_color_factor.z = detail::srgbToLinear(c[2]);
                } else {
                    mat.emissive_factor = {detail::srgbToLinear(c[0]), detail::srgbToLinear(c[1]),
                                           detail::srgbToLinear(c[2])};
                }
            } else if (k == "d" || k == "tr") {
                std::string_view r = rest;
                std::string_view tok = nextToken(r);
                if (tok == "-halo") rest = r;
                float a = 1.0f;
                LODBAKE_RETURN_IF_ERROR(readNumber(key, rest, a));
                a = std::clamp(a, 0.0f, 1.0f);
                if (k == "tr") a = 1.0f - a;
                mat.base_color_factor.w = a;
                mat.alpha_mode = a < 1.0f ? AlphaMode::Blend : AlphaMode::Opaque;
            } else if (k == "ns") {
                LODBAKE_RETURN_IF_ERROR(readNumber(key, rest, m.ns));
                if (!m.has_pr) mat.roughness_factor = std::sqrt(2.0f / (std::max(m.ns, 0.0f) + 2.0f));
            } else if (k == "pr") {
                LODBAKE_RETURN_IF_ERROR(readNumber(key, rest, mat.roughness_factor));
                mat.roughness_factor = std::clamp(mat.roughness_factor, 0.0f, 1.0f);
                m.has_pr = true;
            } else if (k == "pm") {
                LODBAKE_RETURN_IF_ERROR(readNumber(key, rest, mat.metallic_factor));
                mat.metallic_factor = std::clamp(mat.metallic_factor, 0.0f, 1.0f);
            } else {
                PendingTexture& slot = k == "map_kd" ? m.base_color : (k == "map_ke" ? m.emissive : m.normal);
                float bump_scale = 1.0f;
                LODBAKE_RETURN_IF_ERROR(readMap(key, rest, slot, bump_scale));
                if (&slot == &m.normal) mat.normal_scale = bump_scale;
            }
        }
        if (!read_error.empty()) return invalidInput(obj_name_ + ": " + mtl_display_ + " " + read_error);
        if (ignored_ > 0)
            diagnostics_.note(obj_name_ + ": " + mtl_display_ + ": ignored " + std::to_string(ignored_) +
                              " statements without a glTF counterpart (Ka, Ks, Ni, illum, ...)");
        return Status();
    }

private:
    const std::string& obj_name_;
    std::string mtl_display_;
    Diagnostics& diagnostics_;
    uint64_t line_ = 0;
    uint64_t ignored_ = 0;

    Status fail(const std::string& what) const {
        return invalidInput(obj_name_ + ": " + mtl_display_ + " line " + std::to_string(line_) + ": " + what);
    }

    Status readNumber(std::string_view key, std::string_view& rest, float& out) const {
        const std::string_view tok = nextToken(rest);
        if (tok.empty()) return fail(std::string(key) + ": expected a number, got end of line");
        if (!parseFloat(tok, out) || !std::isfinite(out))
            return fail(std::string(key) + ": expected a number, got '" + excerpt(tok) + "'");
        return Status();
    }

    // "Kd r [g b]": a single value means grey.
    Status readColor(std::string_view key, std::string_view& rest, float c[3]) const {
        LODBAKE_RETURN_IF_ERROR(readNumber(key, rest, c[0]));
        if (trim(rest).empty()) {
            c[1] = c[2] = c[0];
            return Status();
        }
        LODBAKE_RETURN_IF_ERROR(readNumber(key, rest, c[1]));
        LODBAKE_RETURN_IF_ERROR(readNumber(key, rest, c[2]));
        return Status();
    }

    // map_* [options] filename: options are skipped with their arguments; the file name is the rest
    // of the line, so names with spaces survive.
    Status readMap(std::string_view key, std::string_view rest, PendingTexture& slot, float& bump_scale) const {
        static const std::map<std::string, int> kFixedArity = {
            {"-blendu", 1}, {"-blendv", 1},  {"-boost", 1}, {"-mm", 2}, {"-texres", 1}, {"-clamp", 1},
            {"-bm", 1},     {"-imfchan", 1}, {"-type", 1},  {"-cc", 1}, {"-halo", 0}};
        for (;;) {
            std::string_view probe = rest;
            const std::string_view opt = nextToken(probe);
            if (opt.empty() || opt.front() != '-') break;
            const std::string o = lower(opt);
            if (o == "-o" || o == "-s" || o == "-t") {
                // One to three numbers follow.
                rest = probe;
                for (int i = 0; i < 3; ++i) {
                    std::string_view look = rest;
                    float v = 0.0f;
                    if (!parseFloat(nextToken(look), v)) break;
                    rest = look;
                }
                continue;
            }
            const auto it = kFixedArity.find(o);
            if (it == kFixedArity.end()) break; // a file name that starts with '-'
            rest = probe;
            for (int i = 0; i < it->second; ++i) {
                const std::string_view arg = nextToken(rest);
                if (arg.empty()) return fail(std::string(key) + ": option " + o + " needs a value");
                if (o == "-bm" && (!parseFloat(arg, bump_scale) || !std::isfinite(bump_scale)))
                    return fail(std::string(key) + ": -bm: expected a number, got '" + excerpt(arg) + "'");
            }
        }
        const std::string_view file = trim(rest);
        if (file.empty()) return fail(std::string(key) + ": expected a texture file name");
        slot.path = normalizeRelativePath(file);
        slot.line = line_;
        return Status();
    }
};

// ---------------------------------------------------------------------------------------------------
// OBJ

struct UnifiedVertex {
    Corner corner;
    uint32_t next = kNone; // next unified vertex sharing the same position index
};

struct UseMtl {
    std::string name;
    uint64_t line = 0;
};

class ObjReader {
public:
    ObjReader(const std::string& name, const SideFileLoader& loader, const ReadOptions& options,
              Diagnostics& diagnostics)
        : name_(name), loader_(loader), options_(options), diagnostics_(diagnostics), base_dir_(parentDirectory(name)) {
    }

    Result<LoadedMesh> read(const uint8_t* data, size_t size) {
        LineReader reader(data, size);
        std::string_view line;
        std::string read_error;
        // Slot 0: faces before any usemtl.
        usemtl_.push_back({"", 0});
        while (reader.next(line, line_, read_error)) LODBAKE_RETURN_IF_ERROR(statement(line));
        if (!read_error.empty()) return invalidInput(name_ + ": " + read_error);
        if (positions_.empty()) return invalidInput(name_ + ": no vertices (no 'v' statements)");
        return finish();
    }

private:
    const std::string& name_;
    const SideFileLoader& loader_;
    const ReadOptions& options_;
    Diagnostics& diagnostics_;
    std::string base_dir_;
    uint64_t line_ = 0;

    std::vector<Vec3f> positions_;
    std::vector<Vec4f> colors_;        // as written, one per position once any colour was seen
    std::vector<uint8_t> color_given_; // parallel to colors_: 0 where the v line had no colour
    uint64_t colored_count_ = 0;
    std::vector<Vec2f> texcoords_; // already flipped to the glTF convention
    std::vector<Vec3f> normals_;

    std::vector<uint32_t> chain_head_; // per position: first unified vertex using it
    std::vector<UnifiedVertex> unified_;
    std::vector<uint32_t> indices_;  // unified vertex per triangle corner
    std::vector<uint32_t> tri_slot_; // usemtl slot per triangle

    std::vector<UseMtl> usemtl_;
    std::map<std::string, uint32_t> slot_by_name_;
    uint32_t current_slot_ = 0;

    std::vector<MtlMaterial> materials_;
    std::map<std::string, uint32_t> material_by_name_;

    uint64_t face_count_ = 0;
    bool all_triangles_ = true;
    uint64_t line_statements_ = 0, point_statements_ = 0, ignored_statements_ = 0;
    uint64_t fallback_triangulations_ = 0;
    uint64_t w_coordinates_ = 0;

    std::vector<Corner> face_;
    std::vector<Vec3f> face_positions_;
    std::vector<uint32_t> face_tris_;

    Status fail(const std::string& what) const {
        return invalidInput(name_ + ": line " + std::to_string(line_) + ": " + what);
    }

    Status readFloats(std::string_view key, std::string_view rest, float* out, size_t min_count, size_t max_count,
                      size_t& count) const {
        const std::string what = readObjFloats(key, rest, out, min_count, max_count, count);
        return what.empty() ? Status() : fail(what);
    }

    Status statement(std::string_view line) {
        std::string_view rest = line;
        const std::string_view key = nextToken(rest);
        if (key.empty()) return Status();
        if (key == "v") return vertex(rest);
        if (key == "f" || key == "fo") return face(rest);
        if ((key == "vt" || key == "vn") && std::max(texcoords_.size(), normals_.size()) >= options_.max_vertex_count)
            return resourceLimit(name_ + ": line " + std::to_string(line_) + ": more than " +
                                 std::to_string(options_.max_vertex_count) + " " + std::string(key) +
                                 " entries (ReadOptions limit)");
        if (key == "vt") {
            float t[3];
            size_t n = 0;
            LODBAKE_RETURN_IF_ERROR(readFloats("vt", rest, t, 1, 3, n));
            texcoords_.push_back({t[0], 1.0f - (n > 1 ? t[1] : 0.0f)});
            return Status();
        }
        if (key == "vn") {
            float t[3];
            size_t n = 0;
            LODBAKE_RETURN_IF_ERROR(readFloats("vn", rest, t, 3, 3, n));
            normals_.push_back({t[0], t[1], t[2]});
            return Status();
        }
        if (key == "usemtl") {
            const std::string_view mat = trim(rest);
            if (mat.empty()) return fail("usemtl: expected a material name");
            const auto it = slot_by_name_.find(std::string(mat));
            if (it != slot_by_name_.end()) {
                current_slot_ = it->second;
            } else {
                current_slot_ = uint32_t(usemtl_.size());
                usemtl_.push_back({std::string(mat), line_});
                slot_by_name_.emplace(std::string(mat), current_slot_);
            }
            return Status();
        }
        if (key == "mtllib") return mtllib(rest);
        if (key == "o" || key == "g" || key == "s" || key == "mg") return Status();
        if (key == "l") {
            ++line_statements_;
            return Status();
        }
        if (key == "p") {
            ++point_statements_;
            return Status();
        }
        if (!isPlainKeyword(key)) return fail("expected an OBJ statement, got '" + excerpt(key) + "'");
        // vp, cstype, curv, surf, lod, usemap, ...: free-form geometry and display attributes.
        ++ignored_statements_;
        return Status();
    }

    Status vertex(std::string_view rest) {
        float t[7];
        size_t n = 0;
        LODBAKE_RETURN_IF_ERROR(readFloats("v", rest, t, 3, 7, n));
        if (n == 5)
            return fail("v: expected 3 (x y z), 4 (x y z w), 6 (x y z r g b) or 7 (x y z r g b a) numbers, got 5");
        if (positions_.size() >= options_.max_vertex_count)
            return resourceLimit(name_ + ": line " + std::to_string(line_) + ": more than " +
                                 std::to_string(options_.max_vertex_count) + " vertices (ReadOptions limit)");
        positions_.push_back({t[0], t[1], t[2]});
        if (n == 4) ++w_coordinates_;
        if (n >= 6) {
            if (colors_.empty()) {
                colors_.resize(positions_.size() - 1, Vec4f(1.0f, 1.0f, 1.0f, 1.0f));
                color_given_.resize(positions_.size() - 1, 0);
            }
            colors_.push_back({t[3], t[4], t[5], n == 7 ? t[6] : 1.0f});
            color_given_.push_back(1);
            ++colored_count_;
        } else if (!colors_.empty()) {
            colors_.push_back({1.0f, 1.0f, 1.0f, 1.0f});
            color_given_.push_back(0);
        }
        return Status();
    }

    Status parseCorner(std::string_view tok, Corner& c) const {
        const std::string what = parseObjCorner(tok, positions_.size(), texcoords_.size(), normals_.size(), c);
        return what.empty() ? Status() : fail(what);
    }

    uint32_t unify(const Corner& c) {
        if (chain_head_.size() < positions_.size()) chain_head_.resize(positions_.size(), kNone);
        uint32_t* link = &chain_head_[c.v];
        while (*link != kNone) {
            const UnifiedVertex& u = unified_[*link];
            if (u.corner.vt == c.vt && u.corner.vn == c.vn) return *link;
            link = &unified_[*link].next;
        }
        const uint32_t id = uint32_t(unified_.size());
        *link = id; // taken before push_back: the pointer may be into unified_
        unified_.push_back({c, kNone});
        return id;
    }

    Status face(std::string_view rest) {
        face_.clear();
        for (;;) {
            const std::string_view tok = nextToken(rest);
            if (tok.empty()) break;
            if (face_.size() >= options_.max_polygon_vertices)
                return fail("f: polygon has more than " + std::to_string(options_.max_polygon_vertices) +
                            " vertices (ReadOptions::max_polygon_vertices)");
            Corner c;
            LODBAKE_RETURN_IF_ERROR(parseCorner(tok, c));
            face_.push_back(c);
        }
        if (face_.size() < 3) return fail("f: expected at least 3 vertices, got " + std::to_string(face_.size()));
        ++face_count_;
        const uint32_t n = uint32_t(face_.size());
        if (n != 3) all_triangles_ = false;
        if (indices_.size() / 3 + (n - 2) > options_.max_face_count)
            return resourceLimit(name_ + ": line " + std::to_string(line_) + ": more than " +
                                 std::to_string(options_.max_face_count) + " triangles (ReadOptions limit)");
        face_tris_.clear();
        if (n == 3) {
            face_tris_.insert(face_tris_.end(), {0u, 1u, 2u});
        } else {
            face_positions_.resize(n);
            for (uint32_t i = 0; i < n; ++i) face_positions_[i] = positions_[face_[i].v];
            if (!detail::triangulatePolygon(face_positions_.data(), n, face_tris_)) ++fallback_triangulations_;
        }
        for (uint32_t corner : face_tris_) indices_.push_back(unify(face_[corner]));
        tri_slot_.insert(tri_slot_.end(), face_tris_.size() / 3, current_slot_);
        return Status();
    }

    Status mtllib(std::string_view rest) {
        std::vector<std::string> files;
        std::string_view probe = rest;
        bool all_mtl = true;
        for (std::string_view tok = nextToken(probe); !tok.empty(); tok = nextToken(probe)) {
            files.emplace_back(tok);
            if (!endsWithIgnoreCase(tok, ".mtl")) all_mtl = false;
        }
        if (files.empty()) return fail("mtllib: expected a file name");
        if (!all_mtl) files = {std::string(trim(rest))}; // one name containing spaces
        for (const std::string& f : files) {
            const std::string rel = normalizeRelativePath(f);
            Result<std::vector<uint8_t>> bytes = loader_(joinPath(base_dir_, rel));
            if (!bytes.ok()) return fail("mtllib: cannot read '" + rel + "': " + bytes.status().message());
            std::vector<MtlMaterial> parsed;
            MtlParser parser(name_, rel, diagnostics_);
            LODBAKE_RETURN_IF_ERROR(parser.parse(*bytes, parsed));
            const std::string mtl_dir = parentDirectory(rel);
            for (MtlMaterial& m : parsed) {
                for (PendingTexture* t : {&m.base_color, &m.normal, &m.emissive})
                    if (!t->path.empty()) t->path = joinPath(mtl_dir, t->path);
                if (material_by_name_.count(m.material.name)) {
                    diagnostics_.warn(name_ + ": " + rel + ": material '" + m.material.name +
                                      "' defined again; the first definition is used");
                    continue;
                }
                material_by_name_.emplace(m.material.name, uint32_t(materials_.size()));
                materials_.push_back(std::move(m));
            }
        }
        return Status();
    }

    // Loads a texture once per distinct path; returns its index in `textures`.
    Status loadTexture(const PendingTexture& pending, const std::string& mtl_display, std::vector<Texture>& textures,
                       std::map<std::string, int32_t>& by_path, int32_t& out) {
        const auto it = by_path.find(pending.path);
        if (it != by_path.end()) {
            out = it->second;
            return Status();
        }
        Texture tex;
        tex.name = stemOf(pending.path);
        tex.uri = pending.path;
        tex.mime_type = mimeFromName(pending.path);
        if (options_.load_textures) {
            Result<std::vector<uint8_t>> bytes = loader_(joinPath(base_dir_, pending.path));
            if (!bytes.ok())
                return invalidInput(name_ + ": " + mtl_display + " line " + std::to_string(pending.line) +
                                    ": cannot read texture '" + pending.path + "': " + bytes.status().message());
            tex.bytes = std::move(bytes).value();
            const std::string sniffed = mimeFromBytes(tex.bytes);
            if (!sniffed.empty()) tex.mime_type = sniffed;
        }
        detail::sanitizeUtf8(tex.name);
        detail::sanitizeUtf8(tex.uri);
        out = int32_t(textures.size());
        by_path.emplace(pending.path, out);
        textures.push_back(std::move(tex));
        return Status();
    }

    Result<LoadedMesh> finish() {
        LoadedMesh loaded;
        Mesh& mesh = loaded.mesh;
        loaded.source.format = MeshFormat::Obj;
        loaded.source.encoding = "ascii";
        loaded.source.file_vertex_count = positions_.size();
        loaded.source.file_face_count = face_count_;
        loaded.source.face_kind = all_triangles_ ? "triangles" : "polygons";

        LODBAKE_ASSIGN_OR_RETURN(const std::vector<MaterialId> slot_material, resolveUsemtlSlots());
        LODBAKE_RETURN_IF_ERROR(loadMaterials(mesh));
        addUnreferencedPositions();
        orderVertices();
        fillVertexAttributes(mesh);
        fillVertexColors(mesh);
        groupTrianglesByMaterial(slot_material, mesh);
        noteSkippedStatements();
        return loaded;
    }

    // Materials that usemtl names, checked now so mtllib may come anywhere in the file.
    Result<std::vector<MaterialId>> resolveUsemtlSlots() {
        std::vector<MaterialId> slot_material(usemtl_.size(), MaterialId::invalid());
        for (size_t s = 1; s < usemtl_.size(); ++s) {
            const auto it = material_by_name_.find(usemtl_[s].name);
            if (it == material_by_name_.end()) {
                line_ = usemtl_[s].line;
                return fail("usemtl: unknown material '" + excerpt(usemtl_[s].name) + "'" +
                            (materials_.empty() ? std::string(" (no mtllib defines materials)") : std::string()));
            }
            slot_material[s] = MaterialId(it->second);
        }
        return slot_material;
    }

    // Moves the MTL materials into the mesh, loading the textures they name (each file once).
    Status loadMaterials(Mesh& mesh) {
        std::map<std::string, int32_t> texture_by_path;
        for (MtlMaterial& m : materials_) {
            Material& mat = m.material;
            if (!m.base_color.path.empty())
                LODBAKE_RETURN_IF_ERROR(loadTexture(m.base_color, m.mtl_display, mesh.textures, texture_by_path,
                                                    mat.base_color_texture.texture));
            if (!m.normal.path.empty())
                LODBAKE_RETURN_IF_ERROR(
                    loadTexture(m.normal, m.mtl_display, mesh.textures, texture_by_path, mat.normal_texture.texture));
            if (!m.emissive.path.empty())
                LODBAKE_RETURN_IF_ERROR(loadTexture(m.emissive, m.mtl_display, mesh.textures, texture_by_path,
                                                    mat.emissive_texture.texture));
            if (mat.emissive_texture.isSet() && mat.emissive_factor == Vec3f(0.0f, 0.0f, 0.0f))
                mat.emissive_factor = {1.0f, 1.0f, 1.0f};
            if (detail::sanitizeUtf8(mat.name))
                diagnostics_.warn(name_ +
                                  ": material name is not valid UTF-8; invalid bytes replaced by '?': " + mat.name);
            mesh.materials.push_back(std::move(mat));
        }
        return Status();
    }

    // Positions no face uses still become vertices (a point cloud keeps all of them).
    void addUnreferencedPositions() {
        uint64_t unreferenced = 0;
        if (chain_head_.size() < positions_.size()) chain_head_.resize(positions_.size(), kNone);
        for (uint32_t v = 0; v < positions_.size(); ++v) {
            if (chain_head_[v] != kNone) continue;
            Corner c;
            c.v = v;
            unify(c);
            ++unreferenced;
        }
        if (unreferenced > 0 && face_count_ > 0)
            diagnostics_.note(name_ + ": " + std::to_string(unreferenced) + " vertices are used by no face (kept)");
    }

    // Number vertices by position index, then by first use: a file without vt/vn keeps its
    // vertex order, and unreferenced positions stay where the file has them.
    void orderVertices() {
        const size_t vertex_count = unified_.size();
        std::vector<uint32_t> new_id(vertex_count);
        std::vector<UnifiedVertex> ordered;
        ordered.reserve(vertex_count);
        for (uint32_t head : chain_head_)
            for (uint32_t u = head; u != kNone; u = unified_[u].next) {
                new_id[u] = uint32_t(ordered.size());
                ordered.push_back(unified_[u]);
            }
        for (uint32_t& i : indices_) i = new_id[i];
        unified_ = std::move(ordered);
    }

    // Positions, texture coordinates (missing ones set to (0, 0)) and normals (dropped for the whole
    // mesh when a used corner has none) of the unified vertices.
    void fillVertexAttributes(Mesh& mesh) {
        const size_t vertex_count = unified_.size();
        std::vector<uint8_t> used(vertex_count, 0);
        for (uint32_t i : indices_) used[i] = 1;
        bool any_vt = false, any_vn = false;
        uint64_t missing_vt = 0, missing_vn = 0;
        for (const UnifiedVertex& u : unified_) {
            any_vt |= u.corner.vt != kNone;
            any_vn |= u.corner.vn != kNone;
        }
        mesh.positions.resize(vertex_count);
        if (any_vt) mesh.uvs.emplace_back(vertex_count, Vec2f(0.0f, 0.0f));
        if (any_vn) mesh.normals.resize(vertex_count);
        for (size_t i = 0; i < vertex_count; ++i) {
            const Corner& c = unified_[i].corner;
            mesh.positions[i] = positions_[c.v];
            if (any_vt) {
                if (c.vt != kNone)
                    mesh.uvs[0][i] = texcoords_[c.vt];
                else if (used[i])
                    ++missing_vt;
            }
            if (any_vn) {
                if (c.vn != kNone)
                    mesh.normals[i] = normalize(normals_[c.vn]);
                else if (used[i])
                    ++missing_vn;
            }
        }
        if (missing_vt > 0)
            diagnostics_.warn(name_ + ": " + std::to_string(missing_vt) +
                              " face corners have no texture coordinate; set to (0, 0)");
        if (missing_vn > 0) {
            diagnostics_.warn(name_ + ": " + std::to_string(missing_vn) +
                              " face corners have no normal; normals dropped for the whole mesh");
            mesh.normals.clear();
        }
    }

    // Vertex colours (the `v x y z r g b` extension), linearised; vertices without one are white.
    void fillVertexColors(Mesh& mesh) {
        if (colors_.empty()) return;
        const size_t vertex_count = unified_.size();
        float max_component = 0.0f;
        for (size_t i = 0; i < colors_.size(); ++i)
            if (color_given_[i]) max_component = std::max({max_component, colors_[i].x, colors_[i].y, colors_[i].z});
        // Some exporters write 0..255 although the de-facto convention is 0..1.
        const float scale = max_component > 1.0f ? 1.0f / 255.0f : 1.0f;
        if (scale != 1.0f) diagnostics_.note(name_ + ": vertex colours exceed 1; read as 0..255 values");
        if (colored_count_ < positions_.size())
            diagnostics_.warn(name_ + ": " + std::to_string(positions_.size() - colored_count_) + " of " +
                              std::to_string(positions_.size()) + " vertices have no colour; set to white");
        mesh.colors.resize(vertex_count);
        for (size_t i = 0; i < vertex_count; ++i) {
            const uint32_t v = unified_[i].corner.v;
            if (!color_given_[v]) {
                mesh.colors[i] = {1.0f, 1.0f, 1.0f, 1.0f};
                continue;
            }
            const Vec4f& c = colors_[v];
            mesh.colors[i] = {detail::srgbToLinear(c.x * scale), detail::srgbToLinear(c.y * scale),
                              detail::srgbToLinear(c.z * scale), std::clamp(c.w, 0.0f, 1.0f)};
        }
    }

    // Group triangles by usemtl slot, slots in order of first use, triangles in file order.
    void groupTrianglesByMaterial(const std::vector<MaterialId>& slot_material, Mesh& mesh) {
        const size_t tri_count = tri_slot_.size();
        std::vector<uint32_t> slot_order;
        std::vector<uint32_t> slot_tris(usemtl_.size(), 0);
        for (uint32_t s : tri_slot_)
            if (slot_tris[s]++ == 0) slot_order.push_back(s);
        const bool any_material = slot_order.size() > 1 || (slot_order.size() == 1 && slot_order[0] != 0);
        if (!any_material) {
            mesh.indices = std::move(indices_);
            return;
        }
        std::vector<uint32_t> slot_start(usemtl_.size(), 0);
        uint32_t start = 0;
        for (uint32_t s : slot_order) {
            slot_start[s] = start;
            SubMesh sub;
            sub.material = slot_material[s];
            sub.name = sub.material.isValid() ? mesh.materials[sub.material.value].name : std::string();
            sub.first_index = start * 3;
            sub.index_count = slot_tris[s] * 3;
            mesh.submeshes.push_back(sub);
            start += slot_tris[s];
        }
        mesh.indices.resize(indices_.size());
        for (size_t t = 0; t < tri_count; ++t) {
            const uint32_t dst = slot_start[tri_slot_[t]]++;
            std::copy_n(&indices_[t * 3], 3, &mesh.indices[size_t(dst) * 3]);
        }
    }

    void noteSkippedStatements() {
        if (line_statements_ + point_statements_ > 0)
            diagnostics_.note(name_ + ": skipped " + std::to_string(line_statements_) + " line (l) and " +
                              std::to_string(point_statements_) + " point (p) statements");
        if (ignored_statements_ > 0)
            diagnostics_.note(name_ + ": skipped " + std::to_string(ignored_statements_) +
                              " unsupported statements (free-form geometry or display attributes)");
        if (w_coordinates_ > 0)
            diagnostics_.note(name_ + ": ignored the w coordinate of " + std::to_string(w_coordinates_) + " vertices");
        if (fallback_triangulations_ > 0)
            diagnostics_.warn(name_ + ": " + std::to_string(fallback_triangulations_) +
                              " polygons are degenerate or self-intersecting; triangulated as fans");
    }
};

// ---------------------------------------------------------------------------------------------------
// Writer

std::string extensionForTexture(const Texture& t) {
    std::string mime = t.mime_type.empty() ? mimeFromBytes(t.bytes) : t.mime_type;
    if (mime == "image/png") return "png";
    if (mime == "image/jpeg") return "jpg";
    if (mime == "image/webp") return "webp";
    if (mime == "image/ktx2") return "ktx2";
    return "bin";
}

// MTL names are the rest of the line: keep them single-line and without surrounding blanks.
std::string sanitizeName(const std::string& name, const std::string& fallback) {
    std::string out;
    for (char c : name) out += (static_cast<unsigned char>(c) < 0x20 || c == '#') ? '_' : c;
    std::string_view t = trim(out);
    return t.empty() ? fallback : std::string(t);
}

void appendVec(std::string& out, const char* key, const float* v, int n) {
    out += key;
    for (int i = 0; i < n; ++i) {
        out += ' ';
        detail::appendFloat(out, v[i]);
    }
    out += '\n';
}

} // namespace

Result<LoadedMesh> readObjFromMemory(const uint8_t* data, size_t size, const std::string& name,
                                     const SideFileLoader& load_side_file, const ReadOptions& options,
                                     Diagnostics& diagnostics) {
    ObjReader reader(name, load_side_file, options, diagnostics);
    return reader.read(data, size);
}

ObjFiles writeObjToMemory(const Mesh& mesh, const std::string& base_name) {
    ObjFiles files;
    std::string& o = files.obj_text;
    const size_t vertex_count = mesh.vertexCount();
    const bool has_uv = !mesh.uvs.empty() && mesh.uvs[0].size() == vertex_count;
    const bool has_normals = mesh.hasNormals();
    const bool has_colors = mesh.hasColors();

    // Unique, single-line material names; a stand-in when a sub-mesh has none but others do.
    std::vector<std::string> names;
    std::map<std::string, int> used;
    for (size_t i = 0; i < mesh.materials.size(); ++i) {
        std::string n = sanitizeName(mesh.materials[i].name, "material_" + std::to_string(i));
        if (used.count(n)) n += "_" + std::to_string(i);
        used[n] = 1;
        names.push_back(n);
    }
    bool need_default = false;
    for (const SubMesh& s : mesh.submeshes) need_default |= !s.material.isValid();
    need_default = need_default && !mesh.materials.empty();
    std::string default_name = "lodbake_default";
    while (used.count(default_name)) default_name += "_";
    const bool has_mtl = !mesh.materials.empty();

    o += "# lodbake OBJ\n";
    if (has_mtl) {
        files.mtl_name = base_name + ".mtl";
        o += "mtllib " + files.mtl_name + "\n";
    }
    o.reserve(vertex_count * 40 + mesh.indices.size() * 10);
    for (size_t i = 0; i < vertex_count; ++i) {
        const Vec3f& p = mesh.positions[i];
        float v[6] = {p.x, p.y, p.z, 0, 0, 0};
        if (has_colors) {
            v[3] = detail::linearToSrgb(mesh.colors[i].x);
            v[4] = detail::linearToSrgb(mesh.colors[i].y);
            v[5] = detail::linearToSrgb(mesh.colors[i].z);
        }
        appendVec(o, "v", v, has_colors ? 6 : 3);
    }
    if (has_uv)
        for (const Vec2f& t : mesh.uvs[0]) {
            const float v[2] = {t.x, 1.0f - t.y};
            appendVec(o, "vt", v, 2);
        }
    if (has_normals)
        for (const Vec3f& n : mesh.normals) {
            const float v[3] = {n.x, n.y, n.z};
            appendVec(o, "vn", v, 3);
        }
    auto write_faces = [&](size_t first_index, size_t index_count) {
        for (size_t i = first_index; i + 3 <= first_index + index_count && i + 3 <= mesh.indices.size(); i += 3) {
            o += 'f';
            for (int k = 0; k < 3; ++k) {
                const uint64_t idx = uint64_t(mesh.indices[i + k]) + 1;
                o += ' ';
                detail::appendUint(o, idx);
                if (has_uv || has_normals) {
                    o += '/';
                    if (has_uv) detail::appendUint(o, idx);
                    if (has_normals) {
                        o += '/';
                        detail::appendUint(o, idx);
                    }
                }
            }
            o += '\n';
        }
    };
    if (mesh.submeshes.empty()) {
        write_faces(0, mesh.indices.size());
    } else {
        for (const SubMesh& s : mesh.submeshes) {
            if (s.material.isValid())
                o += "usemtl " + names[s.material.value] + "\n";
            else if (need_default)
                o += "usemtl " + default_name + "\n";
            write_faces(s.first_index, s.index_count);
        }
    }

    if (!has_mtl) return files;
    std::vector<std::string> texture_file(mesh.textures.size());
    for (size_t i = 0; i < mesh.textures.size(); ++i) {
        const Texture& t = mesh.textures[i];
        if (!t.bytes.empty()) {
            texture_file[i] = base_name + "_" + std::to_string(i) + "." + extensionForTexture(t);
            files.textures.emplace_back(texture_file[i], t.bytes);
        } else {
            texture_file[i] = t.uri; // only referenced, nothing to write
        }
    }
    auto texture_name = [&](const TextureSlot& slot) -> std::string {
        if (!slot.isSet() || size_t(slot.texture) >= texture_file.size()) return "";
        return texture_file[size_t(slot.texture)];
    };
    std::string& m = files.mtl_text;
    m += "# lodbake MTL\n";
    for (size_t i = 0; i < mesh.materials.size(); ++i) {
        const Material& mat = mesh.materials[i];
        m += "\nnewmtl " + names[i] + "\n";
        const float kd[3] = {detail::linearToSrgb(mat.base_color_factor.x),
                             detail::linearToSrgb(mat.base_color_factor.y),
                             detail::linearToSrgb(mat.base_color_factor.z)};
        appendVec(m, "Kd", kd, 3);
        if (mat.base_color_factor.w != 1.0f) appendVec(m, "d", &mat.base_color_factor.w, 1);
        if (mat.emissive_factor != Vec3f(0.0f, 0.0f, 0.0f)) {
            const float ke[3] = {detail::linearToSrgb(mat.emissive_factor.x),
                                 detail::linearToSrgb(mat.emissive_factor.y),
                                 detail::linearToSrgb(mat.emissive_factor.z)};
            appendVec(m, "Ke", ke, 3);
        }
        // Ns for viewers that ignore Pr, from the inverse of roughness = sqrt(2 / (Ns + 2)).
        const float r = std::clamp(mat.roughness_factor, 0.0447f, 1.0f);
        const float ns = std::min(1000.0f, 2.0f / (r * r) - 2.0f);
        appendVec(m, "Ns", &ns, 1);
        appendVec(m, "Pr", &mat.roughness_factor, 1);
        appendVec(m, "Pm", &mat.metallic_factor, 1);
        const std::string kd_map = texture_name(mat.base_color_texture);
        if (!kd_map.empty()) m += "map_Kd " + kd_map + "\n";
        const std::string norm_map = texture_name(mat.normal_texture);
        if (!norm_map.empty()) {
            m += "norm ";
            if (mat.normal_scale != 1.0f) {
                m += "-bm ";
                detail::appendFloat(m, mat.normal_scale);
                m += ' ';
            }
            m += norm_map + "\n";
        }
        const std::string ke_map = texture_name(mat.emissive_texture);
        if (!ke_map.empty()) m += "map_Ke " + ke_map + "\n";
    }
    if (need_default) m += "\nnewmtl " + default_name + "\nKd 1 1 1\nPm 0\n";
    return files;
}

} // namespace lodbake
