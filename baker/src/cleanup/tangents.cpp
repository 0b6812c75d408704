// MikkTSpace tangents, written from the algorithm's description (Mikkelsen 2008 and the reference
// implementation's documented rules), in single precision as the reference computes them:
//  1. corners are welded by bit-identical position, normal and UV;
//  2. each triangle gets its UV gradients (the unnormalised dP/ds and dP/dt, "vOs" and "vOt", with the
//     sign of its UV area folded in), their magnitudes, and its UV winding ("orientation preserving");
//     a triangle with no usable gradient (zero UV area, zero gradient) groups with anything;
//  3. triangles are neighbours across an edge of two welded vertices (pairs found in sorted edge order);
//  4. around each welded vertex, corners are grouped across neighbouring triangles of the same winding
//     (depth first, left edge before right; an any-triangle takes the winding of the first group that
//     reaches it);
//  5. within a group, corners whose projected gradients are not exactly opposite share one tangent: the
//     corner-angle-weighted mean of their triangles' gradients projected onto the normal's plane;
//  6. corners of degenerate triangles copy the first non-degenerate corner of their welded vertex.
// Where the reference leaves a zero tangent (no triangle with a usable gradient), any unit vector
// perpendicular to the normal is used, so that every tangent is unit length as glTF requires.
#include "lodbake/cleanup/tangents.h"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <tuple>
#include <unordered_map>

#include "cleanup/mesh_edit.h"

namespace lodbake {

namespace {

using cleanup_detail::duplicateVertex;
using cleanup_detail::kNone;

constexpr int32_t kUnset = -1;
// Groups larger than this skip the pairwise test of step 5 (quadratic in the group size) and form one
// set: the test only ever separates corners whose gradients are exactly opposite.
constexpr size_t kMaxPairwiseGroup = 4096;

float dot(const Vec3f& a, const Vec3f& b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

bool notZero(float x) {
    return std::fabs(x) > FLT_MIN;
}

bool notZero(const Vec3f& v) {
    return notZero(v.x) || notZero(v.y) || notZero(v.z);
}

Vec3f normalised(const Vec3f& v) {
    return v * (1.0f / std::sqrt(dot(v, v)));
}

// v minus its component along n, normalised when not zero.
Vec3f projected(const Vec3f& v, const Vec3f& n) {
    const Vec3f p = v - n * dot(n, v);
    return notZero(p) ? normalised(p) : p;
}

struct TriangleInfo {
    Vec3f os, ot;             // unit UV gradients (zero when unusable)
    float mag_s = 0, mag_t = 0;
    std::array<int32_t, 3> neighbour{kUnset, kUnset, kUnset}; // across edge corner i -> corner i + 1
    std::array<int32_t, 3> group{kUnset, kUnset, kUnset};     // of corner i
    bool is_orient_preserving = false;
    bool groups_with_any = true;
    bool is_degenerate = false;
};

struct Group {
    uint32_t vertex = 0; // welded vertex
    bool is_orient_preserving = false;
    size_t first = 0, count = 0; // range of Frame::group_faces
};

// Everything the steps share: welded corner vertices, triangle data and the groups.
struct Frame {
    const Mesh& mesh;
    const std::vector<Vec2f>& uv;
    std::vector<uint32_t> weld; // per corner: the welded vertex (lowest vertex with the same data)
    std::vector<TriangleInfo> tri;
    std::vector<Group> groups;
    std::vector<uint32_t> group_faces;

    Vec2f st(uint32_t v) const { return {uv[v].x, 1.0f - uv[v].y}; } // glTF's v down -> MikkTSpace's t up
    int cornerOf(uint32_t f, uint32_t vertex) const {
        for (int i = 0; i < 3; ++i)
            if (weld[size_t(f) * 3 + size_t(i)] == vertex) return i;
        return kUnset;
    }
};

std::vector<uint32_t> weldCorners(const Mesh& mesh, const std::vector<Vec2f>& uv) {
    using Key = std::array<uint32_t, 8>;
    struct KeyHash {
        size_t operator()(const Key& k) const {
            uint64_t h = 0xcbf29ce484222325ull;
            for (uint32_t w : k) h = (h ^ w) * 0x100000001b3ull;
            return size_t(h ^ (h >> 32));
        }
    };
    auto bits = [](float f) {
        uint32_t b;
        std::memcpy(&b, &f, 4);
        return b;
    };
    std::unordered_map<Key, uint32_t, KeyHash> first;
    std::vector<uint32_t> rep(mesh.vertexCount());
    for (uint32_t v = 0; v < mesh.vertexCount(); ++v) {
        const Vec3f& p = mesh.positions[v];
        const Vec3f& n = mesh.normals[v];
        const Key key{bits(p.x), bits(p.y), bits(p.z), bits(n.x), bits(n.y), bits(n.z), bits(uv[v].x), bits(uv[v].y)};
        rep[v] = first.emplace(key, v).first->second;
    }
    std::vector<uint32_t> corners(mesh.indices.size());
    for (size_t c = 0; c < corners.size(); ++c) corners[c] = rep[mesh.indices[c]];
    return corners;
}

void initTriangles(Frame& fr) {
    const size_t face_count = fr.mesh.faceCount();
    fr.tri.assign(face_count, TriangleInfo());
    for (size_t f = 0; f < face_count; ++f) {
        TriangleInfo& t = fr.tri[f];
        const uint32_t i0 = fr.weld[f * 3], i1 = fr.weld[f * 3 + 1], i2 = fr.weld[f * 3 + 2];
        t.is_degenerate = i0 == i1 || i0 == i2 || i1 == i2;
        if (t.is_degenerate) continue;
        const Vec3f& v1 = fr.mesh.positions[i0];
        const Vec2f t1 = fr.st(i0), t2 = fr.st(i1), t3 = fr.st(i2);
        const float t21x = t2.x - t1.x, t21y = t2.y - t1.y, t31x = t3.x - t1.x, t31y = t3.y - t1.y;
        const Vec3f d1 = fr.mesh.positions[i1] - v1, d2 = fr.mesh.positions[i2] - v1;
        const float signed_area = t21x * t31y - t21y * t31x;
        const Vec3f os = d1 * t31y - d2 * t21y;
        const Vec3f ot = d1 * -t31x + d2 * t21x;
        t.is_orient_preserving = signed_area > 0;
        if (!notZero(signed_area)) continue;
        const float abs_area = std::fabs(signed_area);
        const float len_os = std::sqrt(dot(os, os)), len_ot = std::sqrt(dot(ot, ot));
        const float sign = t.is_orient_preserving ? 1.0f : -1.0f;
        if (notZero(len_os)) t.os = os * (sign / len_os);
        if (notZero(len_ot)) t.ot = ot * (sign / len_ot);
        t.mag_s = len_os / abs_area;
        t.mag_t = len_ot / abs_area;
        if (notZero(t.mag_s) && notZero(t.mag_t)) t.groups_with_any = false;
    }
}

// Edges of non-degenerate triangles sorted by (lower vertex, higher vertex, face); each unpaired edge
// pairs with the first later one of the same vertices, running the other way, that is unpaired too.
void findNeighbours(Frame& fr) {
    struct Edge {
        uint32_t lo, hi, face, corner;
    };
    std::vector<Edge> edges;
    for (uint32_t f = 0; f < fr.tri.size(); ++f) {
        if (fr.tri[f].is_degenerate) continue;
        for (uint32_t i = 0; i < 3; ++i) {
            const uint32_t a = fr.weld[size_t(f) * 3 + i], b = fr.weld[size_t(f) * 3 + (i + 1) % 3];
            edges.push_back({std::min(a, b), std::max(a, b), f, i});
        }
    }
    std::sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) {
        return std::tie(x.lo, x.hi, x.face, x.corner) < std::tie(y.lo, y.hi, y.face, y.corner);
    });
    auto from = [&](const Edge& e) { return fr.weld[size_t(e.face) * 3 + e.corner]; };
    for (size_t i = 0; i < edges.size(); ++i) {
        const Edge& a = edges[i];
        if (fr.tri[a.face].neighbour[a.corner] != kUnset) continue;
        for (size_t j = i + 1; j < edges.size() && edges[j].lo == a.lo && edges[j].hi == a.hi; ++j) {
            const Edge& b = edges[j];
            if (from(b) == from(a) || fr.tri[b.face].neighbour[b.corner] != kUnset) continue;
            fr.tri[a.face].neighbour[a.corner] = int32_t(b.face);
            fr.tri[b.face].neighbour[b.corner] = int32_t(a.face);
            break;
        }
    }
}

// Adds to group g every triangle reachable from `start` across edges at the group's vertex whose
// winding matches (depth first, the left edge's side before the right's).
void growGroup(Frame& fr, uint32_t g, int32_t start, std::vector<int32_t>& stack) {
    stack.assign(1, start);
    while (!stack.empty()) {
        const uint32_t f = uint32_t(stack.back());
        stack.pop_back();
        TriangleInfo& t = fr.tri[f];
        const int i = fr.cornerOf(f, fr.groups[g].vertex);
        if (i == kUnset || t.group[size_t(i)] != kUnset) continue;
        // The first group to reach a triangle without a gradient of its own decides its winding.
        if (t.groups_with_any && t.group[0] == kUnset && t.group[1] == kUnset && t.group[2] == kUnset)
            t.is_orient_preserving = fr.groups[g].is_orient_preserving;
        if (t.is_orient_preserving != fr.groups[g].is_orient_preserving) continue;
        fr.group_faces.push_back(f);
        ++fr.groups[g].count;
        t.group[size_t(i)] = int32_t(g);
        const int32_t right = t.neighbour[size_t((i + 2) % 3)], left = t.neighbour[size_t(i)];
        if (right != kUnset) stack.push_back(right);
        if (left != kUnset) stack.push_back(left);
    }
}

void buildGroups(Frame& fr) {
    std::vector<int32_t> stack;
    for (uint32_t f = 0; f < fr.tri.size(); ++f) {
        if (fr.tri[f].is_degenerate) continue;
        for (size_t i = 0; i < 3; ++i) {
            if (fr.tri[f].group[i] != kUnset) continue;
            const uint32_t g = uint32_t(fr.groups.size());
            fr.groups.push_back({fr.weld[size_t(f) * 3 + i], fr.tri[f].is_orient_preserving, fr.group_faces.size(), 1});
            fr.group_faces.push_back(f);
            fr.tri[f].group[i] = int32_t(g);
            const int32_t left = fr.tri[f].neighbour[i], right = fr.tri[f].neighbour[(i + 2) % 3];
            if (left != kUnset) growGroup(fr, g, left, stack);
            if (right != kUnset) growGroup(fr, g, right, stack);
        }
    }
}

// The angle-weighted mean gradient of `faces` at welded vertex `vertex` (triangles with a usable
// gradient only), normalised; zero when none contributes.
Vec3f meanTangent(const Frame& fr, const std::vector<uint32_t>& faces, uint32_t vertex) {
    Vec3f sum;
    for (uint32_t f : faces) {
        const TriangleInfo& t = fr.tri[f];
        if (t.groups_with_any) continue;
        const int i = fr.cornerOf(f, vertex);
        const Vec3f& n = fr.mesh.normals[vertex];
        const Vec3f os = projected(t.os, n);
        const Vec3f& p0 = fr.mesh.positions[fr.weld[size_t(f) * 3 + size_t((i + 2) % 3)]];
        const Vec3f& p1 = fr.mesh.positions[vertex];
        const Vec3f& p2 = fr.mesh.positions[fr.weld[size_t(f) * 3 + size_t((i + 1) % 3)]];
        const Vec3f e1 = projected(p0 - p1, n), e2 = projected(p2 - p1, n);
        const float angle = std::acos(std::clamp(dot(e1, e2), -1.0f, 1.0f));
        sum += os * angle;
    }
    return notZero(sum) ? normalised(sum) : sum;
}

// Step 5 for group g: writes the tangent of each of its corners into `corner_tangent`.
void groupTangents(const Frame& fr, const Group& g, std::vector<Vec4f>& corner_tangent,
                   std::vector<uint8_t>& has_tangent) {
    const std::vector<uint32_t> members(fr.group_faces.begin() + long(g.first),
                                        fr.group_faces.begin() + long(g.first + g.count));
    const Vec3f& n = fr.mesh.normals[g.vertex];
    std::vector<Vec3f> os(members.size()), ot(members.size());
    for (size_t k = 0; k < members.size(); ++k) {
        os[k] = projected(fr.tri[members[k]].os, n);
        ot[k] = projected(fr.tri[members[k]].ot, n);
    }
    std::vector<std::pair<std::vector<uint32_t>, Vec3f>> sets; // member faces (sorted) -> tangent
    for (size_t l = 0; l < members.size(); ++l) {
        std::vector<uint32_t> set;
        if (members.size() > kMaxPairwiseGroup) {
            set = members;
        } else {
            for (size_t j = 0; j < members.size(); ++j) {
                const bool any = fr.tri[members[l]].groups_with_any || fr.tri[members[j]].groups_with_any;
                if (any || l == j || (dot(os[l], os[j]) > -1.0f && dot(ot[l], ot[j]) > -1.0f))
                    set.push_back(members[j]);
            }
        }
        std::sort(set.begin(), set.end());
        const Vec3f* tangent = nullptr;
        for (const auto& known : sets)
            if (known.first == set) tangent = &known.second;
        if (!tangent) {
            const Vec3f mean = meanTangent(fr, set, g.vertex);
            sets.emplace_back(std::move(set), mean);
            tangent = &sets.back().second;
        }
        const size_t corner = size_t(members[l]) * 3 + size_t(fr.cornerOf(members[l], g.vertex));
        corner_tangent[corner] = Vec4f(tangent->x, tangent->y, tangent->z, g.is_orient_preserving ? 1.0f : -1.0f);
        has_tangent[corner] = notZero(*tangent) ? 1 : 0;
    }
}

// Any unit vector perpendicular to n (the axis least aligned with it, projected), handedness +1.
Vec4f fallbackTangent(const Vec3f& n) {
    const float ax = std::fabs(n.x), ay = std::fabs(n.y), az = std::fabs(n.z);
    const Vec3f axis = ax <= ay && ax <= az ? Vec3f(1, 0, 0) : (ay <= az ? Vec3f(0, 1, 0) : Vec3f(0, 0, 1));
    Vec3f t = projected(axis, n);
    if (!notZero(t)) t = Vec3f(1, 0, 0);
    return Vec4f(t.x, t.y, t.z, 1.0f);
}

bool sameBits(const Vec4f& a, const Vec4f& b) {
    return std::memcmp(&a, &b, sizeof(Vec4f)) == 0;
}

// Writes the per-corner tangents into the mesh, splitting vertices whose corners disagree.
uint64_t storeTangents(Mesh& mesh, const std::vector<Vec4f>& corner_tangent) {
    const uint32_t original = uint32_t(mesh.vertexCount());
    mesh.tangents.assign(original, Vec4f());
    std::vector<uint8_t> is_set(original, 0);
    std::vector<std::vector<uint32_t>> copies(original); // split copies of each vertex
    uint64_t added = 0;
    for (size_t c = 0; c < mesh.indices.size(); ++c) {
        const uint32_t v = mesh.indices[c];
        const Vec4f& t = corner_tangent[c];
        if (!is_set[v]) {
            mesh.tangents[v] = t;
            is_set[v] = 1;
            continue;
        }
        if (sameBits(mesh.tangents[v], t)) continue;
        uint32_t target = kNone;
        for (uint32_t copy : copies[v])
            if (sameBits(mesh.tangents[copy], t)) target = copy;
        if (target == kNone) {
            target = duplicateVertex(mesh, v);
            mesh.tangents[target] = t;
            copies[v].push_back(target);
            ++added;
        }
        mesh.indices[c] = target;
    }
    for (uint32_t v = 0; v < original; ++v)
        if (!is_set[v]) mesh.tangents[v] = fallbackTangent(mesh.normals[v]);
    return added;
}

} // namespace

int tangentUvSet(const Mesh& mesh) {
    if (mesh.hasTangents() || !mesh.hasNormals()) return -1;
    for (const SubMesh& s : mesh.submeshes) {
        if (s.index_count == 0 || !s.material.isValid() || size_t(s.material.value) >= mesh.materials.size()) continue;
        const TextureSlot& slot = mesh.materials[size_t(s.material.value)].normal_texture;
        if (!slot.isSet()) continue;
        return slot.texcoord < mesh.uvs.size() ? int(slot.texcoord) : -1;
    }
    return -1;
}

Result<TangentReport> generateTangents(Mesh& mesh, uint32_t uv_set, const std::string& name) {
    if (!mesh.hasNormals()) return invalidInput(name + ": tangents: expected vertex normals");
    if (uv_set >= mesh.uvs.size() || mesh.uvs[uv_set].size() != mesh.vertexCount())
        return invalidInput(name + ": tangents: expected texture coordinate set " + std::to_string(uv_set));
    Frame fr{mesh, mesh.uvs[uv_set], weldCorners(mesh, mesh.uvs[uv_set]), {}, {}, {}};
    initTriangles(fr);
    findNeighbours(fr);
    buildGroups(fr);
    std::vector<Vec4f> corner_tangent(mesh.indices.size());
    std::vector<uint8_t> has_tangent(mesh.indices.size(), 0);
    for (const Group& g : fr.groups) groupTangents(fr, g, corner_tangent, has_tangent);
    // Corners of degenerate triangles: the first non-degenerate corner of the same welded vertex.
    std::vector<int64_t> first_corner(mesh.vertexCount(), -1);
    for (size_t c = 0; c < mesh.indices.size(); ++c)
        if (!fr.tri[c / 3].is_degenerate && first_corner[fr.weld[c]] < 0) first_corner[fr.weld[c]] = int64_t(c);
    TangentReport report;
    for (size_t c = 0; c < mesh.indices.size(); ++c) {
        if (fr.tri[c / 3].is_degenerate && first_corner[fr.weld[c]] >= 0) {
            corner_tangent[c] = corner_tangent[size_t(first_corner[fr.weld[c]])];
            has_tangent[c] = has_tangent[size_t(first_corner[fr.weld[c]])];
        }
        if (!has_tangent[c]) {
            corner_tangent[c] = fallbackTangent(mesh.normals[mesh.indices[c]]);
            ++report.corners_without_uv_frame;
        }
    }
    report.vertices_added = storeTangents(mesh, corner_tangent);
    return report;
}

} // namespace lodbake
