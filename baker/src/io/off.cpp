// Object File Format, as Geomview's OFF(5) manual page defines it: the keyword [ST][C][N][4][n]OFF,
// then "vertex_count face_count edge_count", the vertices
//   x y z [nx ny nz] [r g b [a]] [s t]
// one per line, and the faces "k i1 .. ik [colour]" one per line. Colour components that are
// integers are 0..255, those with a decimal point or exponent are 0..1 (Geomview's rule), taken as
// sRGB. 4OFF and nOFF (other dimensions) and binary OFF are refused; per-face colours are skipped.

#include "lodbake/io/off.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "io/polygon_triangulation.h"
#include "io/text_scan.h"

namespace lodbake {

namespace {

using detail::excerpt;
using detail::nextToken;
using detail::parseFloat;
using detail::parseInt;

constexpr size_t kMaxLineBytes = size_t(1) << 20;
// Smallest text a vertex ("0 0 0\n") and a face ("3 0 0 0\n") can take, to refuse inflated counts.
constexpr uint64_t kMinVertexBytes = 6;
constexpr uint64_t kMinFaceBytes = 8;

class OffReader {
public:
    OffReader(const uint8_t* data, size_t size, const std::string& name, const ReadOptions& options,
              Diagnostics& diagnostics)
        : p_(reinterpret_cast<const char*>(data)), end_(p_ + size), name_(name), options_(options),
          diagnostics_(diagnostics) {}

    Result<LoadedMesh> read() {
        std::string_view line;
        LODBAKE_RETURN_IF_ERROR(nextLine(line, "header"));
        std::string_view rest = line;
        const std::string_view keyword = nextToken(rest);
        LODBAKE_RETURN_IF_ERROR(parseKeyword(keyword));
        {
            std::string_view probe = rest;
            const std::string_view tok = nextToken(probe);
            if (tok == "BINARY" || tok == "binary")
                return unsupported(name_ + ": header: binary OFF is not supported, convert it to ascii OFF");
        }
        // The counts may follow the keyword on the same line or come on the next line.
        if (detail::trim(rest).empty()) LODBAKE_RETURN_IF_ERROR(nextLine(rest, "header counts"));
        int64_t counts[3] = {0, 0, 0};
        for (int i = 0; i < 3; ++i) {
            const std::string_view tok = nextToken(rest);
            if (tok.empty() && i == 2) break; // the edge count is often left out
            if (!parseInt(tok, counts[i]) || counts[i] < 0)
                return invalidInput(
                    name_ + ": header: expected " +
                    std::string(i == 0 ? "the vertex count" : (i == 1 ? "the face count" : "the edge count")) +
                    " (a non-negative integer), got '" + excerpt(tok) + "'");
        }
        if (!nextToken(rest).empty())
            return invalidInput(name_ + ": header: expected 'vertex_count face_count edge_count', got extra values");
        const uint64_t vertex_count = uint64_t(counts[0]);
        const uint64_t face_count = uint64_t(counts[1]);
        LODBAKE_RETURN_IF_ERROR(checkCounts(vertex_count, face_count));

        LoadedMesh loaded;
        Mesh& mesh = loaded.mesh;
        loaded.source.format = MeshFormat::Off;
        loaded.source.encoding = "ascii";
        loaded.source.file_vertex_count = vertex_count;
        loaded.source.file_face_count = face_count;

        mesh.positions.resize(vertex_count);
        if (has_normals_) mesh.normals.resize(vertex_count);
        if (has_colors_) mesh.colors.resize(vertex_count);
        if (has_uvs_) mesh.uvs.emplace_back(vertex_count);
        for (uint64_t v = 0; v < vertex_count; ++v) LODBAKE_RETURN_IF_ERROR(readVertex(v, mesh));

        bool all_triangles = true;
        uint64_t face_colors = 0, fallbacks = 0;
        std::vector<uint32_t> polygon;
        std::vector<Vec3f> corners;
        std::vector<uint32_t> local;
        mesh.indices.reserve(face_count * 3);
        for (uint64_t f = 0; f < face_count; ++f) {
            const std::string element = "face " + std::to_string(f);
            LODBAKE_RETURN_IF_ERROR(nextLine(line, element.c_str()));
            rest = line;
            const std::string_view count_tok = nextToken(rest);
            int64_t k = 0;
            if (!parseInt(count_tok, k))
                return invalidInput(name_ + ": " + element + ": expected the vertex count, got '" + excerpt(count_tok) +
                                    "'");
            if (k < 3)
                return invalidInput(name_ + ": " + element + ": expected at least 3 vertices, got " +
                                    std::to_string(k));
            if (uint64_t(k) > options_.max_polygon_vertices)
                return invalidInput(name_ + ": " + element + ": " + std::to_string(k) + " vertices, more than " +
                                    std::to_string(options_.max_polygon_vertices) +
                                    " (ReadOptions::max_polygon_vertices)");
            polygon.clear();
            for (int64_t i = 0; i < k; ++i) {
                const std::string_view tok = nextToken(rest);
                int64_t idx = 0;
                if (tok.empty())
                    return invalidInput(name_ + ": " + element + ": expected " + std::to_string(k) +
                                        " vertex indices, got " + std::to_string(i));
                if (!parseInt(tok, idx))
                    return invalidInput(name_ + ": " + element + ": expected a vertex index, got '" + excerpt(tok) +
                                        "'");
                if (idx < 0 || uint64_t(idx) >= vertex_count)
                    return invalidInput(name_ + ": " + element + ": vertex index " + std::to_string(idx) +
                                        " out of range (" + std::to_string(vertex_count) + " vertices)");
                polygon.push_back(uint32_t(idx));
            }
            if (!detail::trim(rest).empty()) ++face_colors;
            if (k != 3) all_triangles = false;
            if (mesh.indices.size() / 3 + uint64_t(k - 2) > options_.max_face_count)
                return resourceLimit(name_ + ": " + element + ": more than " + std::to_string(options_.max_face_count) +
                                     " triangles (ReadOptions limit)");
            if (k == 3) {
                mesh.indices.insert(mesh.indices.end(), polygon.begin(), polygon.end());
                continue;
            }
            corners.resize(polygon.size());
            for (size_t i = 0; i < polygon.size(); ++i) corners[i] = mesh.positions[polygon[i]];
            local.clear();
            if (!detail::triangulatePolygon(corners.data(), uint32_t(corners.size()), local)) ++fallbacks;
            for (uint32_t c : local) mesh.indices.push_back(polygon[c]);
        }
        loaded.source.face_kind = all_triangles ? "triangles" : "polygons";

        std::string_view trailing;
        uint64_t trailing_lines = 0;
        while (nextLineOrEnd(trailing)) ++trailing_lines;
        if (!line_error_.empty()) return invalidInput(name_ + ": " + line_error_);
        if (trailing_lines > 0)
            diagnostics_.warn(name_ + ": ignored " + std::to_string(trailing_lines) + " lines after the last face");
        if (face_colors > 0)
            diagnostics_.note(name_ + ": ignored the colours of " + std::to_string(face_colors) + " faces");
        if (fallbacks > 0)
            diagnostics_.warn(name_ + ": " + std::to_string(fallbacks) +
                              " polygons are degenerate or self-intersecting; triangulated as fans");
        return loaded;
    }

private:
    const char* p_;
    const char* end_;
    const std::string& name_;
    const ReadOptions& options_;
    Diagnostics& diagnostics_;
    uint64_t line_number_ = 0;
    std::string line_error_;
    bool has_uvs_ = false, has_colors_ = false, has_normals_ = false;

    // Next line with content, comments removed; false at the end of the input or on a bad line.
    bool nextLineOrEnd(std::string_view& line) {
        while (p_ < end_) {
            const char* nl = static_cast<const char*>(std::memchr(p_, '\n', size_t(end_ - p_)));
            const char* stop = nl ? nl : end_;
            std::string_view s(p_, size_t(stop - p_));
            p_ = nl ? nl + 1 : end_;
            ++line_number_;
            if (s.size() > kMaxLineBytes) {
                line_error_ = "line " + std::to_string(line_number_) + ": longer than " +
                              std::to_string(kMaxLineBytes) + " bytes";
                return false;
            }
            const size_t hash = s.find('#');
            if (hash != std::string_view::npos) s = s.substr(0, hash);
            s = detail::trim(s);
            if (!s.empty()) {
                line = s;
                return true;
            }
        }
        return false;
    }

    Status nextLine(std::string_view& line, const char* element) {
        if (nextLineOrEnd(line)) return Status();
        if (!line_error_.empty()) return invalidInput(name_ + ": " + line_error_);
        return invalidInput(name_ + ": " + element + ": expected more data, the file ends at line " +
                            std::to_string(line_number_));
    }

    Status parseKeyword(std::string_view keyword) {
        std::string_view k = keyword;
        if (k.size() < 3 || k.substr(k.size() - 3) != "OFF")
            return invalidInput(name_ + ": header: expected an OFF keyword ([ST][C][N]OFF), got '" + excerpt(keyword) +
                                "'");
        k.remove_suffix(3);
        if (k.size() >= 2 && k.substr(0, 2) == "ST") {
            has_uvs_ = true;
            k.remove_prefix(2);
        }
        if (!k.empty() && k.front() == 'C') {
            has_colors_ = true;
            k.remove_prefix(1);
        }
        if (!k.empty() && k.front() == 'N') {
            has_normals_ = true;
            k.remove_prefix(1);
        }
        if (!k.empty() && (k.front() == '4' || k.front() == 'n'))
            return unsupported(name_ + ": header: '" + excerpt(keyword) +
                               "' is unsupported (only 3D OFF is read; 4OFF and nOFF are not)");
        if (!k.empty())
            return invalidInput(name_ + ": header: expected an OFF keyword ([ST][C][N]OFF), got '" + excerpt(keyword) +
                                "'");
        return Status();
    }

    Status checkCounts(uint64_t vertex_count, uint64_t face_count) const {
        if (vertex_count == 0) return invalidInput(name_ + ": header: no vertices (vertex count is 0)");
        if (vertex_count > options_.max_vertex_count)
            return resourceLimit(name_ + ": header: vertex count " + std::to_string(vertex_count) +
                                 " is over the limit of " + std::to_string(options_.max_vertex_count));
        if (face_count > options_.max_face_count)
            return resourceLimit(name_ + ": header: face count " + std::to_string(face_count) +
                                 " is over the limit of " + std::to_string(options_.max_face_count));
        const uint64_t left = uint64_t(end_ - p_);
        // Computed in long double: with raised limits the products could overflow 64 bits.
        const long double needed_exact =
            (long double)vertex_count * kMinVertexBytes + (long double)face_count * kMinFaceBytes;
        const uint64_t needed = needed_exact > 1.8e19L ? UINT64_MAX : uint64_t(needed_exact);
        if (needed_exact > (long double)left + 1) // the last line may lack its newline
            return invalidInput(name_ + ": header: " + std::to_string(vertex_count) + " vertices and " +
                                std::to_string(face_count) + " faces need at least " + std::to_string(needed) +
                                " bytes but the file has " + std::to_string(left) + " after the header");
        return Status();
    }

    Status readVertex(uint64_t v, Mesh& mesh) {
        const std::string element = "vertex " + std::to_string(v);
        std::string_view line;
        LODBAKE_RETURN_IF_ERROR(nextLine(line, element.c_str()));
        std::string_view toks[12];
        size_t n = 0;
        std::string_view rest = line;
        for (std::string_view t = nextToken(rest); !t.empty(); t = nextToken(rest)) {
            if (n == 12) return invalidInput(name_ + ": " + element + ": too many values on the line");
            toks[n++] = t;
        }
        const size_t fixed = 3 + (has_normals_ ? 3 : 0) + (has_uvs_ ? 2 : 0);
        size_t color_count = 0;
        if (has_colors_) {
            if (n == fixed + 3 || n == fixed + 4)
                color_count = n - fixed;
            else
                return invalidInput(name_ + ": " + element + ": expected " + std::to_string(fixed + 3) + " or " +
                                    std::to_string(fixed + 4) + " values, got " + std::to_string(n));
        } else if (n != fixed) {
            return invalidInput(name_ + ": " + element + ": expected " + std::to_string(fixed) + " values, got " +
                                std::to_string(n));
        }
        float values[12];
        for (size_t i = 0; i < n; ++i) {
            if (!parseFloat(toks[i], values[i]))
                return invalidInput(name_ + ": " + element + ": expected a number, got '" + excerpt(toks[i]) + "'");
            if (!std::isfinite(values[i]))
                return invalidInput(name_ + ": " + element + ": value is not finite ('" + excerpt(toks[i]) + "')");
        }
        size_t i = 0;
        mesh.positions[v] = {values[0], values[1], values[2]};
        i = 3;
        if (has_normals_) {
            mesh.normals[v] = normalize(Vec3f(values[3], values[4], values[5]));
            i = 6;
        }
        if (has_colors_) {
            float c[4] = {1.0f, 1.0f, 1.0f, 1.0f};
            for (size_t j = 0; j < color_count; ++j) {
                const std::string_view t = toks[i + j];
                const bool is_float = t.find_first_of(".eE") != std::string_view::npos;
                c[j] = std::clamp(is_float ? values[i + j] : values[i + j] / 255.0f, 0.0f, 1.0f);
            }
            mesh.colors[v] = {detail::srgbToLinear(c[0]), detail::srgbToLinear(c[1]), detail::srgbToLinear(c[2]), c[3]};
            i += color_count;
        }
        if (has_uvs_) mesh.uvs[0][v] = {values[i], 1.0f - values[i + 1]};
        return Status();
    }
};

} // namespace

Result<LoadedMesh> readOffFromMemory(const uint8_t* data, size_t size, const std::string& name,
                                     const ReadOptions& options, Diagnostics& diagnostics) {
    OffReader reader(data, size, name, options, diagnostics);
    return reader.read();
}

std::string writeOffToMemory(const Mesh& mesh) {
    std::string out;
    const bool has_colors = mesh.hasColors();
    out += has_colors ? "COFF\n" : "OFF\n";
    detail::appendUint(out, mesh.vertexCount());
    out += ' ';
    detail::appendUint(out, mesh.faceCount());
    out += " 0\n";
    out.reserve(out.size() + mesh.vertexCount() * 32 + mesh.indices.size() * 8);
    for (size_t i = 0; i < mesh.vertexCount(); ++i) {
        const Vec3f& p = mesh.positions[i];
        detail::appendFloat(out, p.x);
        out += ' ';
        detail::appendFloat(out, p.y);
        out += ' ';
        detail::appendFloat(out, p.z);
        if (has_colors) {
            // 0..255 integers, sRGB-encoded: what OFF viewers expect.
            const Vec4f& c = mesh.colors[i];
            const float rgba[4] = {detail::linearToSrgb(c.x), detail::linearToSrgb(c.y), detail::linearToSrgb(c.z),
                                   std::clamp(c.w, 0.0f, 1.0f)};
            for (float ch : rgba) {
                out += ' ';
                detail::appendUint(out, uint64_t(std::lround(ch * 255.0f)));
            }
        }
        out += '\n';
    }
    for (size_t t = 0; t + 3 <= mesh.indices.size(); t += 3) {
        out += '3';
        for (int k = 0; k < 3; ++k) {
            out += ' ';
            detail::appendUint(out, mesh.indices[t + k]);
        }
        out += '\n';
    }
    return out;
}

} // namespace lodbake
