// codec_bench: the .lbm codec (lodbake::codec::encodeValence + lodrt::valenceDecode) against Draco
// (draco::Encoder, speed 0 = draco_encoder -cl 10, edgebreaker, same quantization bits) in the same run.
// Both get the same input: the scan with unreferenced vertices removed; "+n" rows add area/angle
// weighted vertex normals coded at 10 bits by both. Times are the median of --runs (default 9)
// alternating runs in thread CPU time (the machine is shared: CPU time leaves out the time slices
// other processes take), single thread. The position error of both sides is measured the same way:
// each stream is decoded (ours by lodrt::valenceDecode, Draco's by draco::Decoder) and every decoded
// point's largest per-coordinate distance to its nearest input vertex is taken.
// Bars (docs/format/valence.md), over every cell, each judged on the worst cell: total size <= 0.9x
// Draco's, decode time <= 0.5x, encode time <= 1.0x, maximum position error <= Draco's.
// Attribute rows (textured spot, LeePerrySmith, the textured Nefertiti with tangents, and
// bunny_zipper with scanner-like 8-bit vertex colours): every attribute through both codecs at
// -qp 14 -qt 12 -qn 10 -qg 8 (our tangents octahedral at 10 bits), Draco's mesh deduplicated as
// draco_encoder does (UV seams become attribute seams there); Draco's bytes per attribute are its
// total minus its total without that attribute. Bars, worst asset: total size <= 0.9x Draco's (and
// <= 1.0x), UV bytes <= Draco's, each attribute's largest error <= Draco's, decode time with every
// attribute <= 0.8x Draco's (and <= 1.0x), our triangles decode exactly.
//
// usage: codec_bench [--runs N] [--check] [--attributes-only | --no-attributes] [DIR] [FILE...]
//        (DIR defaults to the shared meshes folder)

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <cstdio>
#include <ctime>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <type_traits>
#include <vector>

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>

#include "bench_bar.h"
#include "bench_timing.h"
#include "lodbake/cleanup/normals.h"
#include "lodbake/codec/valence_encoder.h"
#include "lodbake/io/mesh_io.h"
#include "lodrt/format.h"
#include "lodrt/valence.h"

namespace {

constexpr uint32_t kNormalBits = 10;

double threadCpuMs() {
    return 1e3 * lodbake_bench::threadCpuSeconds();
}

// Runs a and b alternately, `runs` times each, and returns each one's median time. Alternating gives
// both the same history of heap and caches: timed one after the other, whichever ran first on a mesh
// paid for growing the heap on every run (our encode of the first cell of bunny_zipper and igea took
// 1.6x as long as the same encode in the next cell, whichever bit count came first).
template <class A, class B> std::pair<double, double> medianMsAlternating(int runs, A&& a, B&& b) {
    std::vector<double> times_a, times_b;
    for (int i = 0; i < runs; ++i) {
        double t0 = threadCpuMs();
        a();
        times_a.push_back(threadCpuMs() - t0);
        t0 = threadCpuMs();
        b();
        times_b.push_back(threadCpuMs() - t0);
    }
    return {lodbake_bench::median(times_a), lodbake_bench::median(times_b)};
}

// The worst cell of one bar: the largest ours / anchor seen, with the cell it came from.
struct Worst {
    double ours = 0, anchor = 0, ratio = -1;
    std::string cell;
    bool measured = true;
    void take(double o, double a, const std::string& where) {
        if (!(a > 0) || !(o >= 0)) {
            measured = false;
            cell = where;
            return;
        }
        if (o / a > ratio) {
            ratio = o / a;
            ours = o;
            anchor = a;
            cell = where;
        }
    }
    void judge(lodbake_bench::Bars& bars, const std::string& name, double limit) const {
        if (!measured || ratio < 0)
            bars.unmeasured(name + " (not measured: " + cell + ")", limit, lodbake_bench::Limit::AtMost, true);
        else
            bars.ratio(name + " (worst: " + cell + ")", ours, anchor, limit, lodbake_bench::Limit::AtMost);
    }
};

// Keeps only the vertices some triangle references, in their original order.
lodbake::Mesh compact(const lodbake::Mesh& in) {
    lodbake::Mesh out;
    std::vector<uint32_t> remap(in.vertexCount(), 0xFFFFFFFFu);
    for (uint32_t v : in.indices) {
        if (remap[v] != 0xFFFFFFFFu) continue;
        remap[v] = 0;
    }
    uint32_t n = 0;
    for (size_t v = 0; v < in.vertexCount(); ++v) {
        if (remap[v] == 0xFFFFFFFFu) continue;
        remap[v] = n++;
        out.positions.push_back(in.positions[v]);
    }
    for (uint32_t v : in.indices) out.indices.push_back(remap[v]);
    return out;
}

std::unique_ptr<draco::Mesh> toDraco(const lodbake::Mesh& m) {
    auto dm = std::make_unique<draco::Mesh>();
    const uint32_t vn = uint32_t(m.vertexCount());
    dm->set_num_points(vn);
    draco::GeometryAttribute ga;
    ga.Init(draco::GeometryAttribute::POSITION, nullptr, 3, draco::DT_FLOAT32, false, sizeof(float) * 3, 0);
    const int pos = dm->AddAttribute(ga, true, vn);
    for (uint32_t i = 0; i < vn; ++i)
        dm->attribute(pos)->SetAttributeValue(draco::AttributeValueIndex(i), &m.positions[i].x);
    if (m.hasNormals()) {
        draco::GeometryAttribute gn;
        gn.Init(draco::GeometryAttribute::NORMAL, nullptr, 3, draco::DT_FLOAT32, false, sizeof(float) * 3, 0);
        const int nrm = dm->AddAttribute(gn, true, vn);
        for (uint32_t i = 0; i < vn; ++i)
            dm->attribute(nrm)->SetAttributeValue(draco::AttributeValueIndex(i), &m.normals[i].x);
    }
    for (size_t f = 0; f < m.faceCount(); ++f)
        dm->AddFace({draco::PointIndex(m.indices[3 * f]), draco::PointIndex(m.indices[3 * f + 1]),
                     draco::PointIndex(m.indices[3 * f + 2])});
    return dm;
}

// Largest per-coordinate distance from each decoded point to its nearest input vertex (grid lookup;
// exact because every decoded point lies within one cell of its source).
double maxErrorToNearest(const lodbake::Mesh& in, const std::vector<float>& decoded, double cell) {
    std::map<std::tuple<long, long, long>, std::vector<uint32_t>> grid;
    auto key = [&](double x, double y, double z) {
        return std::make_tuple(long(std::floor(x / cell)), long(std::floor(y / cell)), long(std::floor(z / cell)));
    };
    for (uint32_t i = 0; i < in.vertexCount(); ++i)
        grid[key(in.positions[i].x, in.positions[i].y, in.positions[i].z)].push_back(i);
    double worst = 0.0;
    for (size_t i = 0; i + 2 < decoded.size(); i += 3) {
        auto k = key(decoded[i], decoded[i + 1], decoded[i + 2]);
        double best = 1e300;
        for (long dx = -1; dx <= 1; ++dx)
            for (long dy = -1; dy <= 1; ++dy)
                for (long dz = -1; dz <= 1; ++dz) {
                    auto it = grid.find({std::get<0>(k) + dx, std::get<1>(k) + dy, std::get<2>(k) + dz});
                    if (it == grid.end()) continue;
                    for (uint32_t v : it->second) {
                        const auto& p = in.positions[v];
                        double d = std::max({std::fabs(p.x - decoded[i]), std::fabs(p.y - decoded[i + 1]),
                                             std::fabs(p.z - decoded[i + 2])});
                        best = std::min(best, d);
                    }
                }
        worst = std::max(worst, best);
    }
    return worst;
}

// ---- Attribute rows: textured and coloured assets, every attribute through both codecs ----

constexpr uint32_t kAttrPositionBits = 14, kAttrUvBits = 12, kAttrColorBits = 8, kAttrGenericBits = 8;
// Tangents: ours octahedral (two components), Draco's generic quantization of the four floats at
// kAttrGenericBits (-qg 8); ours at this depth has the smaller error (the bench measures both).
constexpr uint32_t kAttrTangentBits = 10;

// Keeps only referenced vertices, with every attribute stream.
lodbake::Mesh compactAll(const lodbake::Mesh& in) {
    lodbake::Mesh out;
    std::vector<uint32_t> remap(in.vertexCount(), 0xFFFFFFFFu), old;
    for (uint32_t v : in.indices) remap[v] = 0;
    for (size_t v = 0; v < in.vertexCount(); ++v)
        if (remap[v] == 0) {
            remap[v] = uint32_t(old.size());
            old.push_back(uint32_t(v));
        }
    auto gather = [&](const auto& s) {
        std::decay_t<decltype(s)> o;
        if (s.empty()) return o;
        for (uint32_t v : old) o.push_back(s[v]);
        return o;
    };
    out.positions = gather(in.positions);
    out.normals = gather(in.normals);
    out.tangents = gather(in.tangents);
    out.colors = gather(in.colors);
    for (const auto& uv : in.uvs) out.uvs.push_back(gather(uv));
    for (uint32_t v : in.indices) out.indices.push_back(remap[v]);
    return out;
}

// A smooth albedo with fine speckle, rounded to 8 bits per channel as a scanner's colours are.
void colourScan(lodbake::Mesh& m) {
    lodbake::Aabb box;
    for (const auto& p : m.positions) box.expand(p);
    const double s = 1.0 / std::max(1e-9, box.diagonal());
    uint32_t rng = 12345;
    m.colors.clear();
    for (const auto& p : m.positions) {
        rng = rng * 1664525u + 1013904223u;
        const double noise = double(rng >> 24) / 255.0 - 0.5;
        const double x = (p.x - box.min.x) * s, y = (p.y - box.min.y) * s, z = (p.z - box.min.z) * s;
        double c[3] = {0.55 + 0.3 * std::sin(9.0 * x + 2.0 * y) + 0.03 * noise,
                       0.45 + 0.25 * std::sin(7.0 * y + 3.0 * z) + 0.03 * noise,
                       0.40 + 0.2 * std::cos(11.0 * z - 4.0 * x) + 0.03 * noise};
        for (double& v : c) v = std::round(std::clamp(v, 0.0, 1.0) * 255.0) / 255.0;
        m.colors.push_back(lodbake::Vec4f{float(c[0]), float(c[1]), float(c[2]), 1.0f});
    }
}

// Draco's mesh of every attribute, deduplicated as draco_encoder does after reading a file: equal
// positions become one vertex of its connectivity and a UV seam an attribute seam.
std::unique_ptr<draco::Mesh> toDracoAll(const lodbake::Mesh& m, bool uvs, bool colors, bool tangents) {
    auto dm = std::make_unique<draco::Mesh>();
    const uint32_t vn = uint32_t(m.vertexCount());
    dm->set_num_points(vn);
    auto add = [&](draco::GeometryAttribute::Type type, int comps, auto value) {
        draco::GeometryAttribute ga;
        ga.Init(type, nullptr, comps, draco::DT_FLOAT32, false, sizeof(float) * comps, 0);
        const int id = dm->AddAttribute(ga, true, vn);
        std::vector<float> buf(static_cast<size_t>(comps));
        for (uint32_t i = 0; i < vn; ++i) {
            value(i, buf.data());
            dm->attribute(id)->SetAttributeValue(draco::AttributeValueIndex(i), buf.data());
        }
    };
    add(draco::GeometryAttribute::POSITION, 3, [&](uint32_t i, float* o) { std::memcpy(o, &m.positions[i].x, 12); });
    if (m.hasNormals())
        add(draco::GeometryAttribute::NORMAL, 3, [&](uint32_t i, float* o) { std::memcpy(o, &m.normals[i].x, 12); });
    if (uvs)
        for (const auto& uv : m.uvs)
            add(draco::GeometryAttribute::TEX_COORD, 2, [&](uint32_t i, float* o) { std::memcpy(o, &uv[i].x, 8); });
    const bool rgba = std::any_of(m.colors.begin(), m.colors.end(), [](const lodbake::Vec4f& c) { return c.w != 1.0f; });
    if (colors && m.hasColors())
        add(draco::GeometryAttribute::COLOR, rgba ? 4 : 3,
            [&](uint32_t i, float* o) { std::memcpy(o, &m.colors[i].x, rgba ? 16 : 12); });
    if (tangents && m.hasTangents())
        add(draco::GeometryAttribute::GENERIC, 4, [&](uint32_t i, float* o) { std::memcpy(o, &m.tangents[i].x, 16); });
    for (size_t f = 0; f < m.faceCount(); ++f)
        dm->AddFace({draco::PointIndex(m.indices[3 * f]), draco::PointIndex(m.indices[3 * f + 1]),
                     draco::PointIndex(m.indices[3 * f + 2])});
    dm->DeduplicateAttributeValues();
    dm->DeduplicatePointIds();
    return dm;
}

size_t dracoBytes(const draco::Mesh& dm, draco::EncoderBuffer* out = nullptr) {
    draco::Encoder encoder;
    encoder.SetSpeedOptions(0, 0);
    encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, int(kAttrPositionBits));
    encoder.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, int(kNormalBits));
    encoder.SetAttributeQuantization(draco::GeometryAttribute::TEX_COORD, int(kAttrUvBits));
    encoder.SetAttributeQuantization(draco::GeometryAttribute::COLOR, int(kAttrColorBits));
    encoder.SetAttributeQuantization(draco::GeometryAttribute::GENERIC, int(kAttrGenericBits));
    encoder.SetEncodingMethod(draco::MESH_EDGEBREAKER_ENCODING);
    draco::EncoderBuffer local;
    draco::EncoderBuffer* buf = out ? out : &local;
    buf->Clear();
    if (!encoder.EncodeMeshToBuffer(dm, buf).ok()) return 0;
    return buf->size();
}

// Largest distance (largest per-component difference) from each decoded point's attribute value to
// the nearest value among the input vertices within one position cell of it: both codecs' outputs are
// measured this way, whatever order and welding they chose (seam copies share a position, so the
// nearest value is the one of the same side).
double attributeErrorToNearest(const std::vector<float>& in_pos, const std::vector<float>& in_attr,
                               const std::vector<float>& pos, const std::vector<float>& attr, int c, double cell) {
    std::map<std::tuple<long, long, long>, std::vector<uint32_t>> grid;
    auto key = [&](const float* p) {
        return std::make_tuple(long(std::floor(p[0] / cell)), long(std::floor(p[1] / cell)), long(std::floor(p[2] / cell)));
    };
    for (uint32_t i = 0; 3 * size_t(i) < in_pos.size(); ++i) grid[key(&in_pos[3 * size_t(i)])].push_back(i);
    double worst = 0.0;
    for (size_t i = 0; 3 * i < pos.size(); ++i) {
        const auto k = key(&pos[3 * i]);
        double best = 1e300;
        for (long dx = -1; dx <= 1; ++dx)
            for (long dy = -1; dy <= 1; ++dy)
                for (long dz = -1; dz <= 1; ++dz) {
                    auto it = grid.find({std::get<0>(k) + dx, std::get<1>(k) + dy, std::get<2>(k) + dz});
                    if (it == grid.end()) continue;
                    for (uint32_t v : it->second) {
                        double d = 0.0;
                        for (int j = 0; j < c; ++j)
                            d = std::max(d, double(std::fabs(in_attr[size_t(c) * v + size_t(j)] - attr[size_t(c) * i + size_t(j)])));
                        best = std::min(best, d);
                    }
                }
        worst = std::max(worst, best);
    }
    return worst;
}

struct AttrBars {
    Worst size, uv_size, decode, uv_error, color_error, tangent_error;
    int triangle_failures = 0, measured_assets = 0;
};

// One attribute asset: sizes per attribute (Draco's by leaving the attribute out), errors measured on
// both decoded outputs, decode times, and whether our triangles decode exactly.
bool attributeRow(const std::string& label, const lodbake::Mesh& m, int runs, AttrBars& bars) {
    using namespace lodbake;
    codec::ValenceEncodeOptions o;
    o.position_bits = kAttrPositionBits;
    o.normal_bits = kNormalBits;
    o.uv_bits = kAttrUvBits;
    o.color_bits = kAttrColorBits;
    o.tangent_bits = kAttrTangentBits;
    auto enc = codec::encodeValence(m, o);
    if (!enc.ok()) {
        std::fprintf(stderr, "%s: %s\n", label.c_str(), enc.status().message().c_str());
        return false;
    }
    const bool has_uv = !m.uvs.empty(), has_col = m.hasColors(), has_tan = m.hasTangents();
    auto dm = toDracoAll(m, true, true, true);
    draco::EncoderBuffer dbuf;
    const size_t draco_total = dracoBytes(*dm, &dbuf);
    const size_t draco_uv = has_uv ? draco_total - dracoBytes(*toDracoAll(m, false, true, true)) : 0;
    const size_t draco_col = has_col ? draco_total - dracoBytes(*toDracoAll(m, true, false, true)) : 0;
    const size_t draco_tan = has_tan ? draco_total - dracoBytes(*toDracoAll(m, true, true, false)) : 0;
    size_t our_uv = 0, our_col = 0, our_tan = 0;
    for (const auto& a : enc->attributes) {
        if (a.kind == lodrt::format::kValenceAttributeUv) our_uv += a.bytes;
        if (a.kind == lodrt::format::kValenceAttributeColor) our_col += a.bytes;
        if (a.kind == lodrt::format::kValenceAttributeTangent) our_tan += a.bytes;
    }
    // Our decode with every attribute.
    lodrt::ValenceInfo info;
    lodrt::valenceReadInfo(enc->bytes.data(), enc->bytes.size(), &info);
    std::vector<uint32_t> indices(3 * size_t(info.triangle_count));
    std::vector<float> positions(3 * size_t(info.vertex_count)), nrm(positions.size());
    std::vector<std::vector<float>> attrs(info.attribute_count);
    std::vector<uint64_t> scratch(lodrt::valenceScratchSize(info) / 8 + 1);
    lodrt::ValenceOutput out;
    out.indices = indices.data();
    out.index_capacity = indices.size();
    out.positions = positions.data();
    out.position_capacity = positions.size();
    out.normals = info.has_normals ? nrm.data() : nullptr;
    out.normal_capacity = nrm.size();
    for (uint32_t i = 0; i < info.attribute_count; ++i) {
        attrs[i].resize(size_t(info.attributes[i].components) * info.vertex_count);
        out.attributes[i] = attrs[i].data();
        out.attribute_capacity[i] = attrs[i].size();
    }
    out.scratch = scratch.data();
    out.scratch_size = scratch.size() * 8;
    lodrt::Result r = lodrt::Result::Ok;
    std::unique_ptr<draco::Mesh> decoded;
    const auto [dec_ms, ddec_ms] = medianMsAlternating(
        runs, [&] { r = lodrt::valenceDecode(enc->bytes.data(), enc->bytes.size(), out); },
        [&] {
            draco::DecoderBuffer in;
            in.Init(dbuf.data(), dbuf.size());
            draco::Decoder decoder;
            auto res = decoder.DecodeMeshFromBuffer(&in);
            if (res.ok()) decoded = std::move(res).value();
        });
    if (r != lodrt::Result::Ok || !decoded) {
        std::fprintf(stderr, "%s: decode failed\n", label.c_str());
        return false;
    }
    // Triangles: decoded triangle t is input triangle old_face_of[t] over new_vertex_of, rotated at most.
    bool same = indices.size() == m.indices.size();
    for (size_t t = 0; same && t < enc->old_face_of.size(); ++t) {
        const uint32_t f = enc->old_face_of[t];
        uint32_t w[3];
        for (int k = 0; k < 3; ++k) w[k] = enc->new_vertex_of[m.indices[3 * size_t(f) + size_t(k)]];
        bool hit = false;
        for (int k = 0; k < 3 && !hit; ++k)
            hit = indices[3 * t] == w[k] && indices[3 * t + 1] == w[(k + 1) % 3] && indices[3 * t + 2] == w[(k + 2) % 3];
        same = hit;
    }
    if (!same) ++bars.triangle_failures;
    ++bars.measured_assets;
    // Errors on both decoded outputs.
    std::vector<float> in_pos;
    for (const auto& p : m.positions) in_pos.insert(in_pos.end(), {p.x, p.y, p.z});
    const double cell = double(info.cube_size) / double((1u << kAttrPositionBits) - 1);
    const uint32_t dn = uint32_t(decoded->num_points());
    std::vector<float> dpos(3 * size_t(dn));
    const draco::PointAttribute* dpa = decoded->GetNamedAttribute(draco::GeometryAttribute::POSITION);
    for (uint32_t i = 0; i < dn; ++i) dpa->GetMappedValue(draco::PointIndex(i), &dpos[3 * size_t(i)]);
    auto dracoValues = [&](draco::GeometryAttribute::Type type, int comps) {
        std::vector<float> v(size_t(comps) * dn);
        const draco::PointAttribute* a = decoded->GetNamedAttribute(type);
        if (a)
            for (uint32_t i = 0; i < dn; ++i) a->GetMappedValue(draco::PointIndex(i), &v[size_t(comps) * i]);
        return v;
    };
    double err[3][2] = {{0, 0}, {0, 0}, {0, 0}}; // uv, colour, tangent xyz: ours, Draco's
    for (uint32_t i = 0; i < info.attribute_count; ++i) {
        const lodrt::ValenceAttribute& at = info.attributes[i];
        std::vector<float> in_attr;
        int c = int(at.components), slot = 0;
        draco::GeometryAttribute::Type type = draco::GeometryAttribute::TEX_COORD;
        if (at.kind == lodrt::format::kValenceAttributeUv) {
            if (at.set != 0) continue; // Draco's named attribute is the first UV set
            for (const auto& t : m.uvs[0]) in_attr.insert(in_attr.end(), {t.x, t.y});
        } else if (at.kind == lodrt::format::kValenceAttributeColor) {
            slot = 1;
            type = draco::GeometryAttribute::COLOR;
            for (const auto& col : m.colors) {
                in_attr.insert(in_attr.end(), {col.x, col.y, col.z});
                if (c == 4) in_attr.push_back(col.w);
            }
        } else {
            slot = 2;
            c = 3;
            type = draco::GeometryAttribute::GENERIC;
            for (const auto& t : m.tangents) in_attr.insert(in_attr.end(), {t.x, t.y, t.z});
        }
        std::vector<float> ours = attrs[i];
        if (slot == 2) { // xyz of ours (xyzw) only
            std::vector<float> xyz;
            for (size_t v = 0; v < info.vertex_count; ++v) xyz.insert(xyz.end(), {ours[4 * v], ours[4 * v + 1], ours[4 * v + 2]});
            ours = std::move(xyz);
        }
        err[slot][0] = attributeErrorToNearest(in_pos, in_attr, positions, ours, c, cell);
        std::vector<float> theirs = dracoValues(type, slot == 2 ? 4 : c);
        if (slot == 2) {
            std::vector<float> xyz;
            for (size_t v = 0; v < dn; ++v) xyz.insert(xyz.end(), {theirs[4 * v], theirs[4 * v + 1], theirs[4 * v + 2]});
            theirs = std::move(xyz);
        }
        err[slot][1] = attributeErrorToNearest(in_pos, in_attr, dpos, theirs, c, cell);
    }
    bars.size.take(double(enc->bytes.size()), double(draco_total), label);
    if (has_uv) bars.uv_size.take(double(our_uv), double(draco_uv), label);
    bars.decode.take(dec_ms, ddec_ms, label);
    if (has_uv) bars.uv_error.take(err[0][0], err[0][1], label);
    if (has_col) bars.color_error.take(err[1][0], err[1][1], label);
    if (has_tan) bars.tangent_error.take(err[2][0], err[2][1], label);
    std::printf("%-28s %6u | %8zu %8zu %5.3f | uv %7zu %7zu %5.3f | col %7zu %7zu | tan %7zu %7zu | %7.2f %7.2f "
                "%5.2f | err uv %.3g/%.3g col %.3g/%.3g tan %.3g/%.3g | tri %s\n",
                label.c_str(), info.vertex_count, enc->bytes.size(), draco_total,
                double(enc->bytes.size()) / double(draco_total), our_uv, draco_uv,
                draco_uv ? double(our_uv) / double(draco_uv) : 0.0, our_col, draco_col, our_tan, draco_tan, dec_ms,
                ddec_ms, dec_ms / ddec_ms, err[0][0], err[0][1], err[1][0], err[1][1], err[2][0], err[2][1],
                same ? "same" : "DIFFER");
    std::printf("%-28s        | twins %zu of %zu decisions | bits/vertex: conn %.2f pos %.2f nrm %.2f uv %.2f col %.2f "
                "tan %.2f\n",
                "", enc->twin_vertices, enc->twin_decisions, enc->connectivity_bytes * 8.0 / info.vertex_count, enc->position_bytes * 8.0 / info.vertex_count,
                enc->normal_bytes * 8.0 / info.vertex_count, our_uv * 8.0 / info.vertex_count,
                our_col * 8.0 / info.vertex_count, our_tan * 8.0 / info.vertex_count);
    std::fflush(stdout);
    return true;
}

// The attribute rows and their bars; false when an asset cannot be read.
bool runAttributeRows(const std::string& dir, int runs, lodbake_bench::Bars& bars) {
    using namespace lodbake;
    std::printf("\nattributes: -qp %u -qt %u -qn %u -qg %u (our tangents octahedral %u bits); bytes ours / draco\n",
                kAttrPositionBits, kAttrUvBits, kNormalBits, kAttrGenericBits, kAttrTangentBits);
    std::printf("%-28s %6s | %8s %8s %5s | uv %7s %7s %5s | col %7s %7s | tan %7s %7s | %7s %7s %5s | max errors "
                "ours/draco\n",
                "asset", "V", "ours B", "draco B", "ratio", "ours", "draco", "ratio", "ours", "draco", "ours", "draco",
                "dec ms", "draco", "ratio");
    AttrBars ab;
    const struct {
        const char* file;
        bool colour;
    } assets[] = {{"spot.obj", false},
                  {"lee_perry_smith/LeePerrySmith.glb", false},
                  {"nefertiti_fraunhofer_textured.glb", false},
                  {"bunny_zipper.ply", true}};
    for (const auto& asset : assets) {
        Diagnostics diag;
        auto loaded = readMesh(dir + "/" + asset.file, {}, diag);
        if (!loaded.ok()) {
            std::fprintf(stderr, "%s\n", loaded.status().message().c_str());
            return false;
        }
        Mesh m = compactAll(loaded->mesh);
        if (!m.hasNormals()) computeNormals(m);
        if (asset.colour) colourScan(m);
        const std::string label = std::string(asset.file) + (asset.colour ? " +colour" : "");
        if (!attributeRow(label, m, runs, ab)) return false;
    }
    ab.size.judge(bars, "attributes: total size / Draco -cl 10 (bytes)", 0.9);
    ab.size.judge(bars, "attributes: total size / Draco -cl 10 (bytes), must", 1.0);
    ab.uv_size.judge(bars, "attributes: UV bytes / Draco's UV bytes", 1.0);
    ab.uv_error.judge(bars, "attributes: max UV error / Draco's", 1.0);
    ab.color_error.judge(bars, "attributes: max colour error / Draco's", 1.0);
    ab.tangent_error.judge(bars, "attributes: max tangent error / Draco's", 1.0);
    ab.decode.judge(bars, "attributes: decode time, all attributes / Draco (thread CPU ms)", 0.8);
    ab.decode.judge(bars, "attributes: decode time, all attributes / Draco (thread CPU ms), must", 1.0);
    bars.absolute("attributes: assets whose triangles do not decode exactly", double(ab.triangle_failures), 0.0,
                  lodbake_bench::Limit::AtMost);
    return ab.measured_assets == 4;
}

} // namespace

int main(int argc, char** argv) {
    using namespace lodbake;
    const bool check = lodbake_bench::takeCheckFlag(argc, argv);
    int runs = 9;
    bool position_rows = true, attribute_rows = true;
    std::vector<std::string> positional;
    for (int i = 1; i < argc; ++i) {
        if (std::strcmp(argv[i], "--runs") == 0 && i + 1 < argc) {
            runs = std::max(1, std::atoi(argv[++i]));
        } else if (std::strcmp(argv[i], "--attributes-only") == 0) {
            position_rows = false;
        } else if (std::strcmp(argv[i], "--no-attributes") == 0) {
            attribute_rows = false;
        } else if (argv[i][0] == '-') {
            std::fprintf(stderr, "usage: codec_bench [--runs N] [--check] [--attributes-only | --no-attributes] [DIR] "
                                 "[FILE...]\n");
            return 2;
        } else {
            positional.push_back(argv[i]);
        }
    }
    const std::string dir = !positional.empty() ? positional[0] : LODBAKE_BENCH_MESHES_DIR;
    std::vector<std::string> names;
    for (size_t i = 1; i < positional.size(); ++i) names.push_back(positional[i]);
    Worst worst_size, worst_decode, worst_encode, worst_error;
    if (names.empty()) names = {"bunny_zipper.ply", "igea.ply", "lucy100k.ply", "nefertiti.obj", "dragon_poisson.ply"};
    if (!position_rows) names.clear();

    std::printf("%-20s %4s %2s %7s | %9s %9s %5s | %6s %6s %6s | %8s %8s %5s | %8s %8s %5s | %9s %9s\n", "mesh", "bits",
                "n", "V", "ours B", "draco B", "ratio", "conn", "pos", "nrm", "dec ms", "draco", "ratio", "enc ms",
                "draco", "ratio", "err ours", "err draco");
    std::printf("(err: largest per-coordinate distance of a decoded point to its nearest input vertex, both "
                "sides decoded and measured the same way; err enc: what our encoder reports)\n");
    for (const std::string& name : names) {
        Diagnostics diag;
        auto loaded = readMesh(dir + "/" + name, {}, diag);
        if (!loaded.ok()) {
            std::fprintf(stderr, "%s\n", loaded.status().message().c_str());
            return 1;
        }
        Mesh base = compact(loaded->mesh);
        Mesh with_normals = base;
        computeNormals(with_normals);
        for (bool normals : {false, true}) {
            const Mesh& m = normals ? with_normals : base;
            const double vn = double(m.vertexCount());
            std::unique_ptr<draco::Mesh> dm = toDraco(m);
            for (uint32_t bits : {12u, 14u}) {
                codec::ValenceEncodeOptions o;
                o.position_bits = bits;
                o.encode_normals = normals;
                o.normal_bits = kNormalBits;
                codec::ValenceEncodeResult ours;
                draco::Encoder encoder;
                encoder.SetSpeedOptions(0, 0);
                encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, int(bits));
                encoder.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, int(kNormalBits));
                encoder.SetEncodingMethod(draco::MESH_EDGEBREAKER_ENCODING);
                draco::EncoderBuffer dbuf;
                const auto [enc_ms, denc_ms] = medianMsAlternating(
                    runs, [&] { ours = std::move(*codec::encodeValence(m, o)); },
                    [&] {
                        dbuf.Clear();
                        if (!encoder.EncodeMeshToBuffer(*dm, &dbuf).ok()) std::fprintf(stderr, "draco encode failed\n");
                    });

                lodrt::ValenceInfo info;
                lodrt::valenceReadInfo(ours.bytes.data(), ours.bytes.size(), &info);
                std::vector<uint32_t> indices(3 * size_t(info.triangle_count));
                std::vector<float> positions(3 * size_t(info.vertex_count)), nrm(positions.size());
                std::vector<uint64_t> scratch(lodrt::valenceScratchSize(info) / 8 + 1);
                lodrt::ValenceOutput out;
                out.indices = indices.data();
                out.index_capacity = indices.size();
                out.positions = positions.data();
                out.position_capacity = positions.size();
                out.normals = normals ? nrm.data() : nullptr;
                out.normal_capacity = nrm.size();
                out.scratch = scratch.data();
                out.scratch_size = scratch.size() * 8;
                lodrt::Result r = lodrt::Result::Ok;
                std::unique_ptr<draco::Mesh> decoded;
                const auto [dec_ms, ddec_ms] = medianMsAlternating(
                    runs, [&] { r = lodrt::valenceDecode(ours.bytes.data(), ours.bytes.size(), out); },
                    [&] {
                        draco::DecoderBuffer in;
                        in.Init(dbuf.data(), dbuf.size());
                        draco::Decoder decoder;
                        auto res = decoder.DecodeMeshFromBuffer(&in);
                        if (res.ok()) decoded = std::move(res).value();
                    });
                // The lookup grid of both measurements: one quantization step of our cube at these
                // bits (exactness needs only that each decoded point lies within one cell of its source).
                const double cell = info.cube_size / double((1u << bits) - 1);
                double our_err = -1.0;
                if (r != lodrt::Result::Ok)
                    std::fprintf(stderr, "decode failed: %s\n", lodrt::resultName(r));
                else
                    our_err = maxErrorToNearest(m, positions, cell);
                double draco_err = -1.0;
                if (decoded) {
                    const draco::PointAttribute* pa = decoded->GetNamedAttribute(draco::GeometryAttribute::POSITION);
                    std::vector<float> dp(3 * size_t(decoded->num_points()));
                    for (uint32_t i = 0; i < decoded->num_points(); ++i)
                        pa->GetMappedValue(draco::PointIndex(i), &dp[3 * size_t(i)]);
                    draco_err = maxErrorToNearest(m, dp, cell);
                }
                char where[96];
                std::snprintf(where, sizeof(where), "%s %u bits%s", name.c_str(), bits, normals ? " +n" : "");
                worst_size.take(double(ours.bytes.size()), double(dbuf.size()), where);
                worst_decode.take(dec_ms, ddec_ms, where);
                worst_encode.take(enc_ms, denc_ms, where);
                worst_error.take(our_err, draco_err, where);
                std::printf("%-20s %4u %2s %7.0f | %9zu %9zu %5.3f | %6.2f %6.2f %6.2f | %8.2f %8.2f %5.2f | %8.1f "
                            "%8.1f %5.2f | %9.6g %9.6g  (err enc %.6g)\n",
                            name.c_str(), bits, normals ? "+n" : "", vn, ours.bytes.size(), dbuf.size(),
                            double(ours.bytes.size()) / double(dbuf.size()), ours.connectivity_bytes * 8.0 / vn,
                            ours.position_bytes * 8.0 / vn, ours.normal_bytes * 8.0 / vn, dec_ms, ddec_ms,
                            dec_ms / ddec_ms, enc_ms, denc_ms, enc_ms / denc_ms, our_err, draco_err,
                            ours.max_position_error);
                std::fflush(stdout);
            }
        }
    }
    std::printf("conn/pos/nrm: our bits per vertex; ratios are ours / draco; times: median of %d, thread CPU ms\n",
                runs);
    lodbake_bench::Bars bars("codec_bench");
    if (position_rows) {
        worst_size.judge(bars, "size / Draco -cl 10 (bytes)", 0.9);
        worst_decode.judge(bars, "decode time / Draco (thread CPU ms)", 0.5);
        worst_encode.judge(bars, "encode time / Draco (thread CPU ms)", 1.0);
        worst_error.judge(bars, "max position error / Draco's (decoded, same measure)", 1.0);
    }
    if (attribute_rows && !runAttributeRows(dir, runs, bars)) return 1;
    return bars.finish(check);
}
