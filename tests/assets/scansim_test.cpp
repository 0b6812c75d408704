// lodbake_scansim: determinism, the committed samples are exactly what the simulator makes now, the
// .conf convention brings every view onto the object, noise and holes follow the options, and the
// atlased mesh has its charts and seams.

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "lodbake/core/file_io.h"
#include "lodbake/io/mesh_io.h"
#include "scansim.h"
#include "test_paths.h"

namespace fs = std::filesystem;
using namespace lodbake::scansim;

namespace {

// A small configuration that still exercises everything (shadows, grazing, speckle, noise).
ScanOptions smallOptions() {
    ScanOptions o;
    o.name = "t";
    o.view_count = 3;
    o.num_cols = 64;
    o.num_rows = 48;
    return o;
}

ScanSet simulate(const ScanOptions& o) {
    lodbake::Result<ScanSet> r = simulateScans(o);
    EXPECT_TRUE(r.ok()) << r.status().message();
    return r.ok() ? std::move(r).value() : ScanSet();
}

struct ConfLine {
    std::string name;
    double t[3];
    double q[4];
};

std::vector<ConfLine> parseConf(const std::string& text) {
    std::vector<ConfLine> lines;
    std::istringstream in(text);
    std::string word;
    while (in >> word) {
        EXPECT_EQ(word, "bmesh");
        ConfLine c;
        in >> c.name >> c.t[0] >> c.t[1] >> c.t[2] >> c.q[0] >> c.q[1] >> c.q[2] >> c.q[3];
        lines.push_back(c);
    }
    return lines;
}

// p_world = R(q)^T * p + t, written out here independently of the simulator.
Vec3d confToWorld(const ConfLine& c, const Vec3d& p) {
    const double x = c.q[0], y = c.q[1], z = c.q[2], w = c.q[3];
    const double r[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                            {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                            {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}};
    return {r[0][0] * p.x + r[1][0] * p.y + r[2][0] * p.z + c.t[0],
            r[0][1] * p.x + r[1][1] * p.y + r[2][1] * p.z + c.t[1],
            r[0][2] * p.x + r[1][2] * p.y + r[2][2] * p.z + c.t[2]};
}

Vec3d point(const ScanView& v, size_t i) {
    return {double(v.points[i * 3]), double(v.points[i * 3 + 1]), double(v.points[i * 3 + 2])};
}

double distance(const Vec3d& a, const Vec3d& b) {
    return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z));
}

std::string headerOf(const std::vector<uint8_t>& bytes) {
    const std::string s(bytes.begin(), bytes.end());
    const size_t end = s.find("end_header\n");
    return end == std::string::npos ? std::string() : s.substr(0, end + 11);
}

} // namespace

TEST(ScanSimTest, SameSeedGivesSameBytes) {
    const ScanOptions o = smallOptions();
    const ScanSet a = simulate(o);
    const ScanSet b = simulate(o);
    ASSERT_EQ(a.views.size(), 3u);
    ASSERT_EQ(b.views.size(), 3u);
    for (size_t v = 0; v < a.views.size(); ++v) {
        EXPECT_EQ(rangeGridPlyBytes(a.views[v], o), rangeGridPlyBytes(b.views[v], o)) << v;
        EXPECT_GT(a.views[v].stats.kept, 500u);
    }
    EXPECT_EQ(confText(a), confText(b));

    ScanOptions other = o;
    other.seed = 2;
    const ScanSet c = simulate(other);
    EXPECT_NE(rangeGridPlyBytes(a.views[0], o), rangeGridPlyBytes(c.views[0], other));
}

TEST(ScanSimTest, CommittedSamplesAreCurrent) {
    lodbake::Result<ScanOptions> preset = presetOptions("rock");
    ASSERT_TRUE(preset.ok()) << preset.status().message();
    const ScanSet scans = simulate(*preset);
    const fs::path dir = fs::path(lodbake_test::sourceDir()) / "assets" / "samples" / "rock_scan";
    std::set<std::string> expected;
    for (const ScanView& v : scans.views) {
        expected.insert(v.file_name);
        auto bytes = lodbake::readFileBytes((dir / v.file_name).string());
        ASSERT_TRUE(bytes.ok()) << bytes.status().message();
        EXPECT_TRUE(*bytes == rangeGridPlyBytes(v, *preset))
            << v.file_name << " is stale: regenerate it with the command in assets/README.md";
    }
    expected.insert(confFileName(*preset));
    auto conf = lodbake::readFileBytes((dir / confFileName(*preset)).string());
    ASSERT_TRUE(conf.ok()) << conf.status().message();
    EXPECT_EQ(std::string(conf->begin(), conf->end()), confText(scans));

    std::set<std::string> present;
    for (const auto& e : fs::directory_iterator(dir)) present.insert(e.path().filename().string());
    EXPECT_EQ(present, expected) << "assets/samples/rock_scan holds files the simulator does not make";
    uintmax_t total = 0;
    for (const auto& e : fs::directory_iterator(dir)) total += e.file_size();
    EXPECT_LT(total, 400u * 1024u) << "the bundled sample must stay small";
}

TEST(ScanSimTest, PlyLayoutMatchesStanfordRangeGrid) {
    ScanOptions o = smallOptions();
    o.view_count = 1;
    o.write_confidence = true;
    const ScanSet s = simulate(o);
    const ScanView& v = s.views[0];
    const std::vector<uint8_t> bin = rangeGridPlyBytes(v, o);
    const std::string header = headerOf(bin);
    const uint64_t n = v.stats.kept, cells = v.stats.cells;
    EXPECT_NE(header.find("format binary_little_endian 1.0\n"), std::string::npos);
    EXPECT_NE(header.find("obj_info num_cols 64\nobj_info num_rows 48\n"), std::string::npos);
    EXPECT_NE(header.find("element vertex " + std::to_string(n) +
                          "\nproperty float x\nproperty float y\nproperty float z\nproperty float confidence\n"
                          "element range_grid 3072\nproperty list uchar int vertex_indices\nend_header\n"),
              std::string::npos)
        << header;
    EXPECT_EQ(bin.size(), header.size() + n * 16 + cells + n * 4);
    // Vertices are numbered in cell order, as in the Stanford scans.
    int32_t next = 0;
    for (int32_t index : v.cell_vertex) {
        if (index >= 0) {
            EXPECT_EQ(index, next++);
        }
    }
    EXPECT_EQ(uint64_t(next), n);

    o.binary = false;
    const std::vector<uint8_t> text = rangeGridPlyBytes(v, o);
    const std::string ascii(text.begin(), text.end());
    EXPECT_NE(ascii.find("format ascii 1.0\n"), std::string::npos);
    const size_t body_lines =
        size_t(std::count(ascii.begin(), ascii.end(), '\n')) - size_t(std::count(header.begin(), header.end(), '\n'));
    EXPECT_EQ(body_lines, n + cells);
}

TEST(ScanSimTest, ConfBringsEveryViewOntoTheObject) {
    ScanOptions o = smallOptions();
    o.range_noise_sigma = 0.0;
    const ScanSet s = simulate(o);
    const std::vector<ConfLine> conf = parseConf(confText(s));
    ASSERT_EQ(conf.size(), s.views.size());
    const Shape shape(o.shape, o.seed);
    for (size_t v = 0; v < s.views.size(); ++v) {
        EXPECT_EQ(conf[v].name, s.views[v].file_name);
        double worst = 0.0;
        for (size_t i = 0; i < s.views[v].stats.kept; ++i)
            worst = std::max(worst, std::fabs(shape.field(confToWorld(conf[v], point(s.views[v], i)))));
        // Points are stored as float (about 1e-8 m here) and the conf with 9 digits.
        EXPECT_LT(worst, 2e-6) << s.views[v].file_name;
    }
    // Views 120 degrees apart really are rotated: in scanner coordinates they differ.
    EXPECT_NE(s.views[0].points, s.views[1].points);
}

TEST(ScanSimTest, RangeNoiseHasConfiguredSigma) {
    ScanOptions clean = smallOptions();
    clean.range_noise_sigma = 0.0;
    ScanOptions noisy = clean;
    noisy.range_noise_sigma = 0.0005;
    const ScanSet a = simulate(clean);
    const ScanSet b = simulate(noisy);
    const Vec3d camera{0.0, 0.0, clean.camera_distance};
    double sum = 0.0, sum_sq = 0.0;
    size_t n = 0;
    for (size_t v = 0; v < a.views.size(); ++v) {
        // Noise never changes which cells have samples: it has its own random stream.
        ASSERT_EQ(a.views[v].cell_vertex, b.views[v].cell_vertex);
        for (size_t i = 0; i < a.views[v].stats.kept; ++i) {
            const double err = distance(point(b.views[v], i), camera) - distance(point(a.views[v], i), camera);
            sum += err;
            sum_sq += err * err;
            ++n;
        }
    }
    ASSERT_GT(n, 2000u);
    const double mean = sum / double(n);
    const double sigma = std::sqrt(sum_sq / double(n) - mean * mean);
    EXPECT_NEAR(sigma, 0.0005, 0.0005 * 0.05);
    EXPECT_LT(std::fabs(mean), 4.0 * 0.0005 / std::sqrt(double(n)));
}

TEST(ScanSimTest, SpeckleRateIsAsConfigured) {
    ScanOptions o = smallOptions();
    o.speckle_probability = 0.2;
    const ScanSet s = simulate(o);
    uint64_t speckled = 0, candidates = 0;
    for (const ScanView& v : s.views) {
        const ViewStats& st = v.stats;
        EXPECT_EQ(st.hits, st.dropped_shadow + st.dropped_grazing + st.dropped_speckle + st.kept);
        EXPECT_EQ(uint64_t(std::count(v.cell_vertex.begin(), v.cell_vertex.end(), -1)), st.cells - st.kept);
        speckled += st.dropped_speckle;
        candidates += st.dropped_speckle + st.kept;
    }
    const double p = double(speckled) / double(candidates);
    const double tolerance = 4.0 * std::sqrt(0.2 * 0.8 / double(candidates));
    EXPECT_NEAR(p, 0.2, tolerance) << speckled << " of " << candidates;

    o.speckle_probability = 0.0;
    for (const ScanView& v : simulate(o).views) EXPECT_EQ(v.stats.dropped_speckle, 0u);
}

TEST(ScanSimTest, GrazingLimitAndShadowsDropSamples) {
    ScanOptions o = smallOptions();
    o.range_noise_sigma = 0.0;
    o.speckle_probability = 0.0;
    o.grazing_limit_deg = 60.0;
    const Shape shape(o.shape, o.seed);
    const ScanSet limited = simulate(o);
    ScanOptions open = o;
    open.grazing_limit_deg = 90.0;
    open.simulate_shadows = false;
    const ScanSet unlimited = simulate(open);

    auto worstAngleDeg = [&](const ScanSet& s) {
        const std::vector<ConfLine> conf = parseConf(confText(s));
        double worst = 0.0;
        for (size_t v = 0; v < s.views.size(); ++v) {
            const Vec3d camera = confToWorld(conf[v], {0.0, 0.0, o.camera_distance});
            for (size_t i = 0; i < s.views[v].stats.kept; ++i) {
                const Vec3d p = confToWorld(conf[v], point(s.views[v], i));
                const Vec3d n = shape.normal(p);
                const double d = distance(camera, p);
                const double c = (n.x * (camera.x - p.x) + n.y * (camera.y - p.y) + n.z * (camera.z - p.z)) / d;
                worst = std::max(worst, std::acos(std::min(1.0, c)) * 180.0 / 3.14159265358979323846);
            }
        }
        return worst;
    };
    EXPECT_LE(worstAngleDeg(limited), 60.01);
    EXPECT_GT(worstAngleDeg(unlimited), 75.0);

    uint64_t grazing = 0, shadowed = 0;
    for (size_t v = 0; v < limited.views.size(); ++v) {
        // The same rays hit either way; only what is kept differs.
        EXPECT_EQ(limited.views[v].stats.hits, unlimited.views[v].stats.hits);
        EXPECT_EQ(unlimited.views[v].stats.kept, unlimited.views[v].stats.hits);
        grazing += limited.views[v].stats.dropped_grazing;
        shadowed += limited.views[v].stats.dropped_shadow;
    }
    EXPECT_GT(grazing, 50u);
    EXPECT_GT(shadowed, 20u);
}

TEST(ScanSimTest, RejectsBadOptions) {
    ScanOptions o = smallOptions();
    o.speckle_probability = 1.5;
    lodbake::Status s = validateOptions(o);
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.message().find("speckle"), std::string::npos) << s.message();
    o = smallOptions();
    o.name = "a/b";
    EXPECT_FALSE(simulateScans(o).ok());
    o = smallOptions();
    o.range_noise_sigma = -1.0;
    EXPECT_FALSE(validateOptions(o).ok());
    EXPECT_FALSE(presetOptions("no_such_preset").ok());
}

namespace {

// The atlas mesh through the OBJ reader: 6·K² charts, closed once welded by position.
lodbake::Mesh readAtlas(const AtlasOptions& atlas, const std::string& file) {
    lodbake::Result<std::string> obj = atlasObjText(smallOptions(), atlas);
    EXPECT_TRUE(obj.ok()) << obj.status().message();
    if (!obj.ok()) return {};
    const std::string path = (fs::temp_directory_path() / file).string();
    EXPECT_TRUE(lodbake::writeFileAtomic(path, obj->data(), obj->size()).ok());
    lodbake::Diagnostics d;
    auto loaded = lodbake::readMesh(path, lodbake::ReadOptions(), d);
    fs::remove(path);
    EXPECT_TRUE(loaded.ok()) << loaded.status().message();
    return loaded.ok() ? std::move(loaded->mesh) : lodbake::Mesh();
}

} // namespace

TEST(ScanSimTest, AtlasHasItsChartsAndIsClosed) {
    AtlasOptions atlas;
    atlas.charts_per_edge = 6;
    atlas.quads_per_chart = 2;
    lodbake::Result<std::string> a = atlasObjText(smallOptions(), atlas);
    lodbake::Result<std::string> b = atlasObjText(smallOptions(), atlas);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(*a, *b);
    const lodbake::Mesh m = readAtlas(atlas, "lodbake_scansim_atlas_test.obj");
    ASSERT_EQ(m.faceCount(), size_t(6 * 36 * 4 * 2));
    ASSERT_EQ(m.uvs.size(), 1u);
    // One wedge per chart corner: (quads + 1)² UVs per chart; positions shared across charts.
    EXPECT_EQ(m.vertexCount(), size_t(216 * 9));
    // Welded by position every edge has two faces (closed); by position and UV, every chart border
    // edge is open: 216 charts of 2×2 quads have 216·8 border edges.
    std::map<std::pair<std::tuple<float, float, float>, std::tuple<float, float, float>>, int> by_position;
    std::map<std::pair<uint32_t, uint32_t>, int> by_vertex;
    auto key = [&](uint32_t v) { return std::make_tuple(m.positions[v].x, m.positions[v].y, m.positions[v].z); };
    for (size_t f = 0; f < m.faceCount(); ++f)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a0 = m.indices[f * 3 + k], b0 = m.indices[f * 3 + (k + 1) % 3];
            ++by_position[{std::min(key(a0), key(b0)), std::max(key(a0), key(b0))}];
            ++by_vertex[{std::min(a0, b0), std::max(a0, b0)}];
        }
    for (const auto& [edge, count] : by_position) EXPECT_EQ(count, 2);
    size_t open = 0;
    for (const auto& [edge, count] : by_vertex) open += count == 1;
    EXPECT_EQ(open, size_t(216 * 8));
    EXPECT_FALSE(atlasObjText(smallOptions(), AtlasOptions{0, 5}).ok());
    EXPECT_FALSE(atlasObjText(smallOptions(), AtlasOptions{6, 65}).ok());
}
