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
//
// usage: codec_bench [--runs N] [--check] [DIR] [FILE...]   (DIR defaults to the shared meshes folder)

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <cstdio>
#include <ctime>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>

#include "bench_bar.h"
#include "bench_timing.h"
#include "lodbake/cleanup/normals.h"
#include "lodbake/codec/valence_encoder.h"
#include "lodbake/io/mesh_io.h"
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

} // namespace

int main(int argc, char** argv) {
    using namespace lodbake;
    const bool check = lodbake_bench::takeCheckFlag(argc, argv);
    int runs = 9;
    std::vector<std::string> positional;
    for (int i = 1; i < argc; ++i) {
        if (std::strcmp(argv[i], "--runs") == 0 && i + 1 < argc) {
            runs = std::max(1, std::atoi(argv[++i]));
        } else if (argv[i][0] == '-') {
            std::fprintf(stderr, "usage: codec_bench [--runs N] [--check] [DIR] [FILE...]\n");
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
    worst_size.judge(bars, "size / Draco -cl 10 (bytes)", 0.9);
    worst_decode.judge(bars, "decode time / Draco (thread CPU ms)", 0.5);
    worst_encode.judge(bars, "encode time / Draco (thread CPU ms)", 1.0);
    worst_error.judge(bars, "max position error / Draco's (decoded, same measure)", 1.0);
    return bars.finish(check);
}
