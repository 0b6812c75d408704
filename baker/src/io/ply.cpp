// PLY reader and writer (Turk 1994, "The PLY Polygon File Format"; the Stanford range-image
// conventions of the 3D Scanning Repository: `element range_grid` with obj_info num_cols/num_rows).
//
// The reader parses the header into elements and properties, then walks the body once, element by
// element, through a cursor that hides the encoding (ascii tokens or binary scalars of either byte
// order). Every count is checked against the bytes still present before anything is allocated.
// Faces, strips and grids are collected raw and turned into triangles after the whole body is read,
// because the element order in a PLY is free and triangulation needs the positions.

#include "lodbake/io/ply.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>

#include "io/ply_format.h"
#include "io/polygon_triangulation.h"

namespace lodbake {

namespace {

using namespace ply_detail;

// What a vertex property feeds.
enum Slot { kX, kY, kZ, kNx, kNy, kNz, kRed, kGreen, kBlue, kAlpha, kU, kV, kSlotCount, kIgnore = kSlotCount };

Slot vertexSlot(const std::string& n) {
    if (n == "x") return kX;
    if (n == "y") return kY;
    if (n == "z") return kZ;
    if (n == "nx") return kNx;
    if (n == "ny") return kNy;
    if (n == "nz") return kNz;
    if (n == "red" || n == "diffuse_red" || n == "r") return kRed;
    if (n == "green" || n == "diffuse_green" || n == "g") return kGreen;
    if (n == "blue" || n == "diffuse_blue" || n == "b") return kBlue;
    if (n == "alpha" || n == "diffuse_alpha" || n == "a") return kAlpha;
    if (n == "s" || n == "u" || n == "texture_u" || n == "texture_s") return kU;
    if (n == "t" || n == "v" || n == "texture_v" || n == "texture_t") return kV;
    return kIgnore;
}

const char* kSlotNames[kSlotCount] = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue", "alpha", "u", "v"};

float srgbToLinear(double c) {
    c = std::clamp(c, 0.0, 1.0);
    return float(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
}

// sRGB decode of the 256 byte values, computed once so every uchar colour maps identically.
const std::array<float, 256>& srgbByteTable() {
    static const std::array<float, 256> table = [] {
        std::array<float, 256> t{};
        for (int i = 0; i < 256; ++i) t[size_t(i)] = srgbToLinear(i / 255.0);
        return t;
    }();
    return table;
}

uint8_t linearToSrgbByte(float c) {
    if (!(c > 0.0f)) return 0;
    if (c >= 1.0f) return 255;
    // Nearest byte by its decoded value, so decode(encode(decode(b))) == decode(b) for every byte.
    const std::array<float, 256>& t = srgbByteTable();
    const auto it = std::lower_bound(t.begin(), t.end(), c);
    size_t i = size_t(it - t.begin());
    if (i > 0 && (i == 256 || c - t[i - 1] <= t[i] - c)) --i;
    return uint8_t(i);
}

uint8_t unitToByte(float c) {
    if (!(c > 0.0f)) return 0;
    if (c >= 1.0f) return 255;
    return uint8_t(std::lround(double(c) * 255.0));
}

// Raw face data as the file has it, triangulated once the whole body is read.
struct RawFaces {
    std::vector<uint32_t> offsets{0}; // polygon i is indices[offsets[i], offsets[i+1])
    std::vector<uint32_t> indices;
};

struct BodyData {
    RawFaces polygons;
    std::vector<int64_t> strips;  // concatenated strips, -1 separates them
    std::vector<int32_t> grid;    // rows*cols, -1 for no sample
    bool has_faces = false;
    bool has_strips = false;
    bool has_grid = false;
    uint64_t face_element_count = 0;
    size_t short_faces = 0;       // faces with fewer than 3 vertices, dropped
};

// Polygons go through the triangulation OBJ and OFF share; it returns corner numbers of the polygon.
void triangulatePolygon(const Mesh& mesh, const uint32_t* idx, size_t n, std::vector<uint32_t>& out) {
    if (n == 3) {
        out.insert(out.end(), idx, idx + 3);
        return;
    }
    thread_local std::vector<Vec3f> corners;
    thread_local std::vector<uint32_t> local;
    corners.resize(n);
    for (size_t i = 0; i < n; ++i) corners[i] = mesh.positions[idx[i]];
    local.clear();
    detail::triangulatePolygon(corners.data(), uint32_t(n), local);
    for (uint32_t c : local) out.push_back(idx[c]);
}

// Median of a list (mean of the two middle values for an even count); 0 for an empty list.
double medianOf(std::vector<double>& v) {
    if (v.empty()) return 0.0;
    const size_t mid = v.size() / 2;
    std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(mid), v.end());
    double m = v[mid];
    if (v.size() % 2 == 0) m = 0.5 * (m + *std::max_element(v.begin(), v.begin() + std::ptrdiff_t(mid)));
    return m;
}

bool isDegenerate(uint32_t a, uint32_t b, uint32_t c) { return a == b || b == c || a == c; }

// Row-major range grid (Stanford range images): cells with 4 samples give 2 triangles split on the
// shorter diagonal, cells with 3 give 1; triangles with an edge longer than `max_edge_factor` × the
// grid spacing bridge depth discontinuities and are dropped. Winding makes the normals face the scanner.
void triangulateRangeGrid(const Mesh& mesh, const std::vector<int32_t>& grid, size_t rows, size_t cols,
                          double max_edge_factor, std::vector<uint32_t>& out) {
    auto dist = [&](int32_t a, int32_t b) {
        return length(toDouble(mesh.positions[size_t(a)]) - toDouble(mesh.positions[size_t(b)]));
    };
    // Spacing is measured separately along rows and along columns, and the coarser of the two medians
    // is the grid spacing: scanners sample the two directions at different rates (for the Cyberware
    // scans about 0.55 mm within a row and 0.8 mm between rows), and a threshold tied to the finer one
    // would cut ordinary cells of the coarser direction.
    std::vector<double> along_row, along_col;
    for (size_t r = 0; r < rows; ++r)
        for (size_t c = 0; c < cols; ++c) {
            const int32_t a = grid[r * cols + c];
            if (a < 0) continue;
            if (c + 1 < cols && grid[r * cols + c + 1] >= 0) along_row.push_back(dist(a, grid[r * cols + c + 1]));
            if (r + 1 < rows && grid[(r + 1) * cols + c] >= 0) along_col.push_back(dist(a, grid[(r + 1) * cols + c]));
        }
    const double median = std::max(medianOf(along_row), medianOf(along_col));
    if (!(median > 0.0)) return;
    const double max_edge = max_edge_factor * median;
    auto emit = [&](int32_t a, int32_t b, int32_t c) {
        if (dist(a, b) > max_edge || dist(b, c) > max_edge || dist(c, a) > max_edge) return;
        out.push_back(uint32_t(a));
        out.push_back(uint32_t(b));
        out.push_back(uint32_t(c));
    };
    for (size_t r = 0; r + 1 < rows; ++r)
        for (size_t c = 0; c + 1 < cols; ++c) {
            // Corners in the cyclic order that faces the scanner: top-left, top-right, bottom-right,
            // bottom-left (rows grow downwards in the image).
            const int32_t tl = grid[r * cols + c], tr = grid[r * cols + c + 1];
            const int32_t bl = grid[(r + 1) * cols + c], br = grid[(r + 1) * cols + c + 1];
            const int present = (tl >= 0) + (tr >= 0) + (bl >= 0) + (br >= 0);
            if (present == 4) {
                if (dist(tl, br) <= dist(tr, bl)) {
                    emit(tl, tr, br);
                    emit(tl, br, bl);
                } else {
                    emit(tl, tr, bl);
                    emit(tr, br, bl);
                }
            } else if (present == 3) {
                int32_t q[3];
                int k = 0;
                for (int32_t v : {tl, tr, br, bl})
                    if (v >= 0) q[k++] = v;
                emit(q[0], q[1], q[2]);
            }
        }
}

// Which slot each vertex property fills (kIgnore for none), and which attributes are complete.
struct VertexLayout {
    std::vector<int> slots;
    std::array<bool, kSlotCount> present{};
    std::array<ScalarType, kSlotCount> slot_type{};
    bool has_normals = false, has_colors = false, has_uvs = false;
};

VertexLayout mapVertexProperties(const Element& el, const std::string& name, Diagnostics& diagnostics) {
    VertexLayout layout;
    layout.slots.assign(el.properties.size(), kIgnore);
    std::array<bool, kSlotCount>& present = layout.present;
    for (size_t pi = 0; pi < el.properties.size(); ++pi) {
        const Property& p = el.properties[pi];
        if (p.is_list) continue;
        const Slot s = vertexSlot(p.name);
        if (s == kIgnore || present[s]) continue;
        layout.slots[pi] = s;
        present[s] = true;
        layout.slot_type[s] = p.value_type;
    }
    layout.has_normals = present[kNx] && present[kNy] && present[kNz];
    layout.has_colors = present[kRed] && present[kGreen] && present[kBlue];
    layout.has_uvs = present[kU] && present[kV];
    if ((present[kNx] || present[kNy] || present[kNz]) && !layout.has_normals)
        diagnostics.warn(name + ": vertex: incomplete normal (needs nx, ny, nz); normals ignored");
    if ((present[kRed] || present[kGreen] || present[kBlue]) && !layout.has_colors)
        diagnostics.warn(name + ": vertex: incomplete colour (needs red, green, blue); colours ignored");
    if ((present[kU] || present[kV]) && !layout.has_uvs)
        diagnostics.warn(name + ": vertex: incomplete texture coordinate; texture coordinates ignored");
    return layout;
}

// Reads the vertex element's records into the mesh's positions and complete attributes.
Status readVertexElement(const Element& el, size_t n, BodyCursor& cursor, const std::string& name,
                         Diagnostics& diagnostics, Mesh& mesh) {
    const VertexLayout layout = mapVertexProperties(el, name, diagnostics);
    const std::array<bool, kSlotCount>& present = layout.present;
    const std::array<ScalarType, kSlotCount>& slot_type = layout.slot_type;
    const bool has_normals = layout.has_normals, has_colors = layout.has_colors, has_uvs = layout.has_uvs;
    mesh.positions.resize(n);
    if (has_normals) mesh.normals.resize(n);
    if (has_colors) mesh.colors.resize(n);
    if (has_uvs) mesh.uvs.assign(1, std::vector<Vec2f>(n));
    std::array<double, kSlotCount + 1> value{};
    const std::array<float, 256>& srgb = srgbByteTable();
    auto colorChannel = [&](int s) -> float {
        const double v = value[size_t(s)];
        if (slot_type[size_t(s)] == ScalarType::Uint8) return srgb[size_t(v)];
        if (isIntegerType(slot_type[size_t(s)])) return srgbToLinear(v / integerTypeMax(slot_type[size_t(s)]));
        return srgbToLinear(v);
    };
    auto alphaChannel = [&]() -> float {
        if (!present[kAlpha]) return 1.0f;
        const double v = value[kAlpha];
        if (isIntegerType(slot_type[kAlpha])) return float(std::clamp(v / integerTypeMax(slot_type[kAlpha]), 0.0, 1.0));
        return float(std::clamp(v, 0.0, 1.0));
    };
    for (size_t vi = 0; vi < n; ++vi) {
        for (size_t pi = 0; pi < el.properties.size(); ++pi) {
            const Property& p = el.properties[pi];
            ReadError e;
            if (p.is_list) {
                double count = 0;
                e = cursor.read(p.count_type, count);
                if (e == ReadError::None && count < 0)
                    return invalidInput(name + ": vertex " + std::to_string(vi) + " property '" + p.name +
                                        "': negative list count");
                if (e == ReadError::None) e = cursor.skip(p.value_type, uint64_t(count));
            } else if (layout.slots[pi] == kIgnore) {
                e = cursor.skip(p.value_type, 1);
            } else {
                e = cursor.read(p.value_type, value[size_t(layout.slots[pi])]);
            }
            if (e != ReadError::None)
                return invalidInput(name + ": vertex " + std::to_string(vi) + " property '" + p.name +
                                    "': " + describeError(e, cursor, p.value_type));
        }
        const Vec3f pos{float(value[kX]), float(value[kY]), float(value[kZ])};
        if (!isFinite(pos))
            return invalidInput(name + ": vertex " + std::to_string(vi) + ": coordinate is not finite (" +
                                std::to_string(pos.x) + ", " + std::to_string(pos.y) + ", " +
                                std::to_string(pos.z) + ")");
        mesh.positions[vi] = pos;
        if (has_normals) {
            const Vec3f nrm{float(value[kNx]), float(value[kNy]), float(value[kNz])};
            if (!isFinite(nrm)) return invalidInput(name + ": vertex " + std::to_string(vi) + ": normal is not finite");
            mesh.normals[vi] = normalize(nrm);
        }
        if (has_colors) {
            for (int s : {kRed, kGreen, kBlue, kAlpha})
                if (present[size_t(s)] && !std::isfinite(value[size_t(s)]))
                    return invalidInput(name + ": vertex " + std::to_string(vi) + " property '" + kSlotNames[s] +
                                        "': colour is not finite");
            mesh.colors[vi] = {colorChannel(kRed), colorChannel(kGreen), colorChannel(kBlue), alphaChannel()};
        }
        if (has_uvs) {
            if (!std::isfinite(value[kU]) || !std::isfinite(value[kV]))
                return invalidInput(name + ": vertex " + std::to_string(vi) + ": texture coordinate is not finite");
            mesh.uvs[0][vi] = {float(value[kU]), float(1.0 - double(float(value[kV])))};
        }
    }
    return Status::okStatus();
}

// A face-like element (face, tristrips or range_grid) about to be read: which list holds its vertex
// indices (-1: none, the element is skipped) and whether the vertex positions are already known.
struct FaceElement {
    const Element& el;
    bool is_face, is_strip, is_grid;
    int index_prop = -1;
    bool after_vertices = false;
};

// Finds the element's vertex index list and prepares `body` and `mesh` for its records.
Status prepareFaceElement(FaceElement& fe, const Header& header, const std::string& name,
                          const ReadOptions& options, Diagnostics& diagnostics, BodyData& body, LoadedMesh& loaded) {
    const Element& el = fe.el;
    if (fe.is_face || fe.is_strip || fe.is_grid) {
        fe.index_prop = el.findProperty("vertex_indices");
        if (fe.index_prop < 0) fe.index_prop = el.findProperty("vertex_index");
        if (fe.index_prop < 0 || !el.properties[size_t(fe.index_prop)].is_list) {
            diagnostics.warn(name + ": element " + el.name + ": no 'vertex_indices' list; element skipped");
            fe.index_prop = -1;
        } else if (!isIntegerType(el.properties[size_t(fe.index_prop)].value_type)) {
            return invalidInput(name + ": header: element " + el.name + " property '" +
                                el.properties[size_t(fe.index_prop)].name + "': vertex indices must be integers");
        }
    }
    if (fe.index_prop < 0) return Status::okStatus();
    if (body.has_faces || body.has_strips || body.has_grid)
        diagnostics.warn(name + ": element " + el.name + ": a second face-like element; its faces are kept too");
    if (fe.is_face) {
        if (el.count > options.max_face_count)
            return resourceLimit(name + ": header: element face count " + std::to_string(el.count) +
                                 " exceeds the limit of " + std::to_string(options.max_face_count));
        body.has_faces = true;
        body.face_element_count += el.count;
        if (fe.after_vertices) {
            loaded.mesh.indices.reserve(loaded.mesh.indices.size() + size_t(el.count) * 3);
        } else {
            body.polygons.offsets.reserve(body.polygons.offsets.size() + size_t(el.count));
            body.polygons.indices.reserve(body.polygons.indices.size() + size_t(el.count) * 3);
        }
    }
    if (fe.is_grid) {
        if (header.num_cols < 0 || header.num_rows < 0)
            return invalidInput(name + ": header: element range_grid needs 'obj_info num_cols' and 'obj_info num_rows'");
        const size_t rows = size_t(header.num_rows), cols = size_t(header.num_cols);
        if (uint64_t(rows) * uint64_t(cols) != el.count)
            return invalidInput(name + ": header: element range_grid count " + std::to_string(el.count) +
                                " is not num_rows x num_cols = " + std::to_string(rows) + " x " +
                                std::to_string(cols));
        body.has_grid = true;
        body.grid.assign(size_t(el.count), -1);
    }
    if (fe.is_strip) body.has_strips = true;
    loaded.source.file_face_count += el.count;
    return Status::okStatus();
}

// Reads the records of a non-vertex element: lists other than the vertex indices and scalars are
// skipped; indices go to the strips, the grid, the mesh (triangulated, when positions are known) or
// the raw polygons.
Status readFaceElementRecords(const FaceElement& fe, uint64_t vertex_count, const Header& header,
                              const std::string& name, const ReadOptions& options, BodyCursor& cursor,
                              BodyData& body, Mesh& mesh) {
    const Element& el = fe.el;
    const bool is_face = fe.is_face, is_strip = fe.is_strip, is_grid = fe.is_grid;
    std::vector<uint32_t> poly;
    for (uint64_t ri = 0; ri < el.count; ++ri) {
        for (size_t pi = 0; pi < el.properties.size(); ++pi) {
            const Property& p = el.properties[pi];
            auto where = [&]() { return name + ": " + el.name + " " + std::to_string(ri) + " property '" + p.name + "': "; };
            if (!p.is_list) {
                const ReadError e = cursor.skip(p.value_type, 1);
                if (e != ReadError::None) return invalidInput(where() + describeError(e, cursor, p.value_type));
                continue;
            }
            double count_d = 0;
            ReadError e = cursor.read(p.count_type, count_d);
            if (e != ReadError::None) return invalidInput(where() + describeError(e, cursor, p.count_type));
            if (count_d < 0) return invalidInput(where() + "negative list count " + std::to_string(int64_t(count_d)));
            const uint64_t count = uint64_t(count_d);
            if (int(pi) == fe.index_prop && is_face && count > options.max_polygon_vertices)
                return resourceLimit(where() + "polygon has " + std::to_string(count) +
                                     " vertices, more than the limit of " +
                                     std::to_string(options.max_polygon_vertices));
            const uint64_t value_bytes = header.encoding == Encoding::Ascii ? 2 : scalarSize(p.value_type);
            const uint64_t slack = header.encoding == Encoding::Ascii ? 1 : 0; // last ascii value needs no separator
            if (count > cursor.remaining() / value_bytes + slack)
                return invalidInput(where() + "list of " + std::to_string(count) +
                                    " values runs past the end of the file");
            if (int(pi) != fe.index_prop) {
                e = cursor.skip(p.value_type, count);
                if (e != ReadError::None) return invalidInput(where() + describeError(e, cursor, p.value_type));
                continue;
            }
            if (is_grid && count > 1)
                return invalidInput(where() + "expected 0 or 1 vertex indices per grid cell, got " +
                                    std::to_string(count));
            poly.clear();
            for (uint64_t k = 0; k < count; ++k) {
                double v = 0;
                e = cursor.read(p.value_type, v);
                if (e != ReadError::None) return invalidInput(where() + describeError(e, cursor, p.value_type));
                if (is_strip && v == -1.0) {
                    body.strips.push_back(-1);
                    continue;
                }
                if (v < 0 || v >= double(vertex_count))
                    return invalidInput(name + ": " + el.name + " " + std::to_string(ri) + ": vertex index " +
                                        std::to_string(int64_t(v)) + " out of range (" +
                                        std::to_string(vertex_count) + " vertices)");
                if (is_strip) body.strips.push_back(int64_t(v));
                else poly.push_back(uint32_t(v));
            }
            if (is_strip) {
                body.strips.push_back(-1);
            } else if (is_grid) {
                if (count == 1) body.grid[size_t(ri)] = int32_t(poly[0]);
            } else if (fe.after_vertices) {
                // Positions are known: triangulate now instead of keeping the raw lists.
                if (poly.size() < 3) ++body.short_faces;
                else triangulatePolygon(mesh, poly.data(), poly.size(), mesh.indices);
            } else {
                body.polygons.indices.insert(body.polygons.indices.end(), poly.begin(), poly.end());
                if (body.polygons.indices.size() > std::numeric_limits<uint32_t>::max())
                    return resourceLimit(where() + "too many face indices");
                body.polygons.offsets.push_back(uint32_t(body.polygons.indices.size()));
            }
        }
    }
    return Status::okStatus();
}

// Strips: triangle k of a strip is (s[k], s[k+1], s[k+2]) for even k and (s[k+1], s[k], s[k+2]) for
// odd k, which keeps every triangle's winding the same. Strips use repeated indices on purpose to
// turn corners, so the degenerate triangles they make are dropped silently.
void triangulateStrips(const std::vector<int64_t>& strips, std::vector<uint32_t>& out) {
    size_t begin = 0;
    for (size_t i = 0; i <= strips.size(); ++i) {
        if (i < strips.size() && strips[i] >= 0) continue;
        for (size_t k = begin; k + 2 < i; ++k) {
            uint32_t a = uint32_t(strips[k]), b = uint32_t(strips[k + 1]);
            const uint32_t c = uint32_t(strips[k + 2]);
            if ((k - begin) % 2 == 1) std::swap(a, b);
            if (isDegenerate(a, b, c)) continue;
            out.push_back(a);
            out.push_back(b);
            out.push_back(c);
        }
        begin = i + 1;
    }
}

// Turns what the body held into triangles: raw polygons, strips and the range grid, in that order.
void triangulateBody(BodyData& body, const Header& header, const std::string& name, const ReadOptions& options,
                     Diagnostics& diagnostics, LoadedMesh& loaded) {
    Mesh& mesh = loaded.mesh;
    SourceInfo& source = loaded.source;
    if (body.has_faces) {
        // Faces of an element that came before the vertex element (rare) were kept raw until now.
        source.face_kind = "polygons";
        const RawFaces& rf = body.polygons;
        mesh.indices.reserve(mesh.indices.size() + rf.indices.size());
        for (size_t f = 0; f + 1 < rf.offsets.size(); ++f) {
            const size_t n = rf.offsets[f + 1] - rf.offsets[f];
            if (n < 3) {
                ++body.short_faces;
                continue;
            }
            triangulatePolygon(mesh, rf.indices.data() + rf.offsets[f], n, mesh.indices);
        }
        if (body.short_faces > 0)
            diagnostics.warn(name + ": face: " + std::to_string(body.short_faces) +
                             " faces with fewer than 3 vertices dropped");
    }
    if (body.has_strips) {
        if (!body.has_faces) source.face_kind = "tristrips";
        triangulateStrips(body.strips, mesh.indices);
    }
    if (body.has_grid) {
        if (!body.has_faces && !body.has_strips) source.face_kind = "range_grid";
        triangulateRangeGrid(mesh, body.grid, size_t(header.num_rows), size_t(header.num_cols),
                             options.range_grid_max_edge_factor, mesh.indices);
    }
}

} // namespace

Result<LoadedMesh> readPlyFromMemory(const uint8_t* data, size_t size, const std::string& name,
                                     const ReadOptions& options, Diagnostics& diagnostics) {
    LODBAKE_ASSIGN_OR_RETURN(Header header, parseHeader(data, size, name, diagnostics));
    // Roles of the elements we understand; everything else is skipped.
    LODBAKE_ASSIGN_OR_RETURN(const size_t vertex_element, findVertexElement(header, name, options));
    const uint64_t vertex_count = header.elements[vertex_element].count;
    LODBAKE_RETURN_IF_ERROR(checkBodyHoldsCounts(header, size, name));

    LoadedMesh loaded;
    Mesh& mesh = loaded.mesh;
    SourceInfo& source = loaded.source;
    source.format = MeshFormat::Ply;
    source.encoding = encodingName(header.encoding);
    source.file_vertex_count = vertex_count;
    source.face_kind = "none";

    BodyData body;
    BodyCursor cursor(data, size, header.body_offset, header.encoding);
    for (size_t ei = 0; ei < header.elements.size(); ++ei) {
        const Element& el = header.elements[ei];
        if (el.properties.empty()) continue;
        if (ei == vertex_element) {
            LODBAKE_RETURN_IF_ERROR(readVertexElement(el, size_t(vertex_count), cursor, name, diagnostics, mesh));
            continue;
        }
        FaceElement fe{el, el.name == "face", el.name == "tristrips", el.name == "range_grid"};
        fe.after_vertices = ei > vertex_element;
        LODBAKE_RETURN_IF_ERROR(prepareFaceElement(fe, header, name, options, diagnostics, body, loaded));
        LODBAKE_RETURN_IF_ERROR(
            readFaceElementRecords(fe, vertex_count, header, name, options, cursor, body, mesh));
    }
    if (const size_t extra = cursor.trailingBytes(); extra > 0)
        diagnostics.warn(name + ": body: " + std::to_string(extra) + " bytes after the last element ignored");

    triangulateBody(body, header, name, options, diagnostics, loaded);
    if (mesh.faceCount() > options.max_face_count)
        return resourceLimit(name + ": face: " + std::to_string(mesh.faceCount()) +
                             " triangles after triangulation exceed the limit of " +
                             std::to_string(options.max_face_count));
    return loaded;
}

namespace {

void appendText(std::vector<uint8_t>& out, const std::string& s) { out.insert(out.end(), s.begin(), s.end()); }

template <class T> void appendLittleEndian(std::vector<uint8_t>& out, T v) {
    uint8_t b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    // The baker only runs on little-endian hosts today; keep the byte order explicit anyway.
    const uint16_t probe = 1;
    uint8_t first = 0;
    std::memcpy(&first, &probe, 1);
    if (first == 0) std::reverse(b, b + sizeof(T));
    out.insert(out.end(), b, b + sizeof(T));
}

void appendFloatText(std::vector<uint8_t>& out, float v) {
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof(buf), v); // shortest text that reads back exactly
    out.insert(out.end(), buf, r.ptr);
}

void appendUintText(std::vector<uint8_t>& out, uint32_t v) {
    char buf[16];
    const auto r = std::to_chars(buf, buf + sizeof(buf), v);
    out.insert(out.end(), buf, r.ptr);
}

} // namespace

std::vector<uint8_t> writePlyToMemory(const Mesh& mesh, bool binary) {
    const size_t n = mesh.vertexCount();
    const bool has_normals = mesh.normals.size() == n && n > 0;
    const bool has_uvs = !mesh.uvs.empty() && mesh.uvs[0].size() == n && n > 0;
    const bool has_colors = mesh.colors.size() == n && n > 0;
    const size_t face_count = mesh.faceCount();

    std::vector<uint8_t> out;
    std::string h = "ply\n";
    h += binary ? "format binary_little_endian 1.0\n" : "format ascii 1.0\n";
    h += "comment written by lodbake\n";
    h += "element vertex " + std::to_string(n) + "\n";
    h += "property float x\nproperty float y\nproperty float z\n";
    if (has_normals) h += "property float nx\nproperty float ny\nproperty float nz\n";
    if (has_uvs) h += "property float s\nproperty float t\n";
    if (has_colors) h += "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n";
    h += "element face " + std::to_string(face_count) + "\n";
    h += "property list uchar int vertex_indices\n";
    h += "end_header\n";
    appendText(out, h);

    size_t per_vertex = 12 + (has_normals ? 12 : 0) + (has_uvs ? 8 : 0) + (has_colors ? 4 : 0);
    out.reserve(out.size() + (binary ? n * per_vertex + face_count * 13 : n * per_vertex * 3 + face_count * 24));

    for (size_t v = 0; v < n; ++v) {
        float f[8];
        size_t nf = 0;
        f[nf++] = mesh.positions[v].x;
        f[nf++] = mesh.positions[v].y;
        f[nf++] = mesh.positions[v].z;
        if (has_normals) {
            f[nf++] = mesh.normals[v].x;
            f[nf++] = mesh.normals[v].y;
            f[nf++] = mesh.normals[v].z;
        }
        if (has_uvs) {
            f[nf++] = mesh.uvs[0][v].x;
            f[nf++] = float(1.0 - double(mesh.uvs[0][v].y)); // back to PLY's v-up convention
        }
        uint8_t rgba[4] = {0, 0, 0, 0};
        if (has_colors) {
            const Vec4f& c = mesh.colors[v];
            rgba[0] = linearToSrgbByte(c.x);
            rgba[1] = linearToSrgbByte(c.y);
            rgba[2] = linearToSrgbByte(c.z);
            rgba[3] = unitToByte(c.w);
        }
        if (binary) {
            for (size_t i = 0; i < nf; ++i) appendLittleEndian(out, f[i]);
            if (has_colors) out.insert(out.end(), rgba, rgba + 4);
        } else {
            for (size_t i = 0; i < nf; ++i) {
                if (i > 0) out.push_back(' ');
                appendFloatText(out, f[i]);
            }
            if (has_colors)
                for (uint8_t c : rgba) {
                    out.push_back(' ');
                    appendUintText(out, c);
                }
            out.push_back('\n');
        }
    }
    for (size_t t = 0; t < face_count; ++t) {
        const uint32_t* idx = &mesh.indices[t * 3];
        if (binary) {
            out.push_back(3);
            for (int k = 0; k < 3; ++k) appendLittleEndian(out, int32_t(idx[k]));
        } else {
            out.push_back('3');
            for (int k = 0; k < 3; ++k) {
                out.push_back(' ');
                appendUintText(out, idx[k]);
            }
            out.push_back('\n');
        }
    }
    return out;
}

} // namespace lodbake
