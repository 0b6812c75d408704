// The procedural scan of any size (scansim.h, writeSurfacePly): a displaced torus generated one
// grid row at a time straight into a PLY, so a 100 M-triangle scan needs no more memory than a
// 1,000-triangle one.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "lodbake/core/math.h"
#include "lodbake/core/spill_file.h"
#include "scansim.h"

namespace lodbake::scansim {

namespace {

constexpr uint64_t kStreamRangeNoise1 = 11;
constexpr uint64_t kStreamRangeNoise2 = 12;
constexpr uint64_t kMaxTriangles = uint64_t(1) << 36;

Status checkSurfaceOptions(const SurfaceOptions& o) {
    auto bad = [](const std::string& field, const std::string& expected) {
        return invalidInput("scansim surface option " + field + ": expected " + expected);
    };
    if (o.triangles < 18 || o.triangles > kMaxTriangles) return bad("triangles", "18..2^36");
    if (!(o.minor_radius > 0.0 && o.major_radius > o.minor_radius && std::isfinite(o.major_radius)))
        return bad("radii", "0 < minor_radius < major_radius");
    if (!(o.relief >= 0.0 && o.relief <= 0.5)) return bad("relief", "0..0.5");
    if (!(o.relief_frequency >= 0.0 && o.relief_frequency <= 1e6)) return bad("relief_frequency", "0..1e6");
    if (o.relief_octaves < 0 || o.relief_octaves > 16) return bad("relief_octaves", "0..16");
    if (!(o.range_noise >= 0.0 && o.range_noise <= 1.0)) return bad("range_noise", "0..1 grid spacings");
    return Status::okStatus();
}

// Writes float and index values in the file's encoding into a row buffer.
class RowWriter {
public:
    explicit RowWriter(SurfaceOptions::Encoding e) : encoding_(e) {}
    void clear() { bytes_.clear(); }
    const std::vector<uint8_t>& bytes() const { return bytes_; }

    void vertex(float x, float y, float z) {
        if (encoding_ == SurfaceOptions::Encoding::Ascii) {
            const float v[3] = {x, y, z};
            for (int k = 0; k < 3; ++k) {
                char buf[32];
                const auto r = std::to_chars(buf, buf + sizeof buf, v[k]);
                bytes_.insert(bytes_.end(), buf, r.ptr);
                bytes_.push_back(k == 2 ? '\n' : ' ');
            }
            return;
        }
        for (float f : {x, y, z}) {
            uint32_t bits = 0;
            std::memcpy(&bits, &f, 4);
            word(bits);
        }
    }

    void triangle(uint32_t a, uint32_t b, uint32_t c) {
        if (encoding_ == SurfaceOptions::Encoding::Ascii) {
            bytes_.push_back('3');
            for (uint32_t v : {a, b, c}) {
                char buf[16];
                const auto r = std::to_chars(buf, buf + sizeof buf, v);
                bytes_.push_back(' ');
                bytes_.insert(bytes_.end(), buf, r.ptr);
            }
            bytes_.push_back('\n');
            return;
        }
        bytes_.push_back(3);
        for (uint32_t v : {a, b, c}) word(v);
    }

private:
    SurfaceOptions::Encoding encoding_;
    std::vector<uint8_t> bytes_;

    void word(uint32_t v) {
        if (encoding_ == SurfaceOptions::Encoding::BinaryBigEndian)
            for (int i = 3; i >= 0; --i) bytes_.push_back(uint8_t(v >> (8 * i)));
        else
            for (int i = 0; i < 4; ++i) bytes_.push_back(uint8_t(v >> (8 * i)));
    }
};

std::string surfaceHeader(const SurfaceOptions& o, const SurfaceStats& g) {
    const char* format = o.encoding == SurfaceOptions::Encoding::Ascii               ? "ascii"
                         : o.encoding == SurfaceOptions::Encoding::BinaryBigEndian ? "binary_big_endian"
                                                                                   : "binary_little_endian";
    std::string h = "ply\nformat " + std::string(format) + " 1.0\n";
    h += "comment made by lodbake_scansim (procedural scan, no third-party data)\n";
    h += "comment displaced torus seed " + std::to_string(o.seed) + " grid " + std::to_string(g.rows) + " x " +
         std::to_string(g.cols) + "\n";
    h += "element vertex " + std::to_string(g.vertices) + "\n";
    h += "property float x\nproperty float y\nproperty float z\n";
    h += "element face " + std::to_string(g.triangles) + "\n";
    h += "property list uchar int vertex_indices\nend_header\n";
    return h;
}

// Grid vertex (row, col): row turns around the tube, col around the torus axis.
void appendVertexRow(const SurfaceOptions& o, const SurfaceStats& g, uint64_t row, RowWriter& out) {
    const double phi = 2.0 * kPi * double(row) / double(g.rows);
    const double spacing = 2.0 * kPi * o.minor_radius / double(g.rows);
    const double cos_phi = std::cos(phi), sin_phi = std::sin(phi);
    for (uint64_t col = 0; col < g.cols; ++col) {
        const double theta = 2.0 * kPi * double(col) / double(g.cols);
        const double ct = std::cos(theta), st = std::sin(theta);
        const double ring = o.major_radius + o.minor_radius * cos_phi;
        const Vec3d base{ring * ct, o.minor_radius * sin_phi, ring * st};
        const Vec3d normal{cos_phi * ct, sin_phi, cos_phi * st};
        double fbm = 0.0, amp = 1.0, amp_sum = 0.0, freq = o.relief_frequency;
        for (int k = 0; k < o.relief_octaves; ++k) {
            fbm += amp * valueNoise(o.seed, uint64_t(k), {base.x * freq, base.y * freq, base.z * freq});
            amp_sum += amp;
            amp *= 0.5;
            freq *= 2.0;
        }
        if (amp_sum > 0.0) fbm /= amp_sum;
        double noise = 0.0;
        if (o.range_noise > 0.0) {
            // Box-Muller from two counter-based uniforms of this vertex.
            const uint64_t id = row * g.cols + col;
            const double u1 = hashUniform(o.seed, kStreamRangeNoise1, id, 0);
            const double u2 = hashUniform(o.seed, kStreamRangeNoise2, id, 0);
            noise = std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2) * o.range_noise * spacing;
        }
        const double d = o.minor_radius * o.relief * fbm + noise;
        out.vertex(float(base.x + normal.x * d), float(base.y + normal.y * d), float(base.z + normal.z * d));
    }
}

// The two triangles of each cell between grid rows `row` and `row + 1` (wrapping), facing outwards;
// the diagonal alternates like a checkerboard so that no direction is favoured.
void appendTriangleRow(const SurfaceStats& g, uint64_t row, RowWriter& out) {
    const uint64_t next = (row + 1) % g.rows;
    for (uint64_t col = 0; col < g.cols; ++col) {
        const uint64_t col1 = (col + 1) % g.cols;
        const uint32_t v00 = uint32_t(row * g.cols + col), v01 = uint32_t(row * g.cols + col1);
        const uint32_t v10 = uint32_t(next * g.cols + col), v11 = uint32_t(next * g.cols + col1);
        if ((row + col) % 2 == 0) {
            out.triangle(v00, v10, v11);
            out.triangle(v00, v11, v01);
        } else {
            out.triangle(v00, v10, v01);
            out.triangle(v01, v10, v11);
        }
    }
}

} // namespace

Result<SurfaceStats> surfaceGrid(const SurfaceOptions& o) {
    LODBAKE_RETURN_IF_ERROR(checkSurfaceOptions(o));
    const double aspect = o.major_radius / o.minor_radius; // circumference around the axis / around the tube
    SurfaceStats g;
    g.rows = std::max<uint64_t>(3, uint64_t(std::llround(std::sqrt(double(o.triangles) / (2.0 * aspect)))));
    g.cols = std::max<uint64_t>(3, uint64_t(std::llround(double(o.triangles) / (2.0 * double(g.rows)))));
    g.vertices = g.rows * g.cols;
    g.triangles = 2 * g.vertices;
    if (g.vertices > uint64_t(0xffffffffu))
        return invalidInput("scansim surface option triangles: " + std::to_string(o.triangles) +
                            " needs vertex ids beyond 32 bits");
    return g;
}

Result<SurfaceStats> writeSurfacePly(const SurfaceOptions& o, const std::string& path) {
    LODBAKE_ASSIGN_OR_RETURN(SurfaceStats g, surfaceGrid(o));
    SpillFile file;
    LODBAKE_RETURN_IF_ERROR(file.open(path, size_t(4) << 20));
    const std::string header = surfaceHeader(o, g);
    LODBAKE_RETURN_IF_ERROR(file.write(header.data(), header.size()));
    RowWriter row_bytes(o.encoding);
    for (uint64_t row = 0; row < g.rows; ++row) {
        row_bytes.clear();
        appendVertexRow(o, g, row, row_bytes);
        LODBAKE_RETURN_IF_ERROR(file.write(row_bytes.bytes().data(), row_bytes.bytes().size()));
    }
    for (uint64_t row = 0; row < g.rows; ++row) {
        row_bytes.clear();
        appendTriangleRow(g, row, row_bytes);
        LODBAKE_RETURN_IF_ERROR(file.write(row_bytes.bytes().data(), row_bytes.bytes().size()));
    }
    g.bytes = file.bytesWritten();
    LODBAKE_RETURN_IF_ERROR(file.commit());
    return g;
}

} // namespace lodbake::scansim
