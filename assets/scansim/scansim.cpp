// The range-scan simulator (see scansim.h). Ray casting is sphere tracing (Hart 1996, "Sphere
// tracing: a geometric method for the antialiased ray tracing of implicit surfaces") with a
// Lipschitz bound on the implicit function, refined by bisection once the ray is inside; the noise is
// lattice value noise summed over octaves (fractional Brownian motion, as in Perlin 1985 / Ebert et
// al., "Texturing and Modeling").

#include "scansim.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <system_error>

#include "lodbake/core/file_io.h"
#include "lodbake/core/math.h"

namespace lodbake::scansim {
namespace {

// The scanner reports coordinates in its own frame, centred near the object rather than on the
// turntable axis, so the .conf translations are not zero and a reader that ignores them is caught.
constexpr Vec3d kScannerOffset{0.0015, -0.045, 0.001};
constexpr double kMinStep = 2e-5;         // metres; sphere tracing never steps less than this
constexpr int kMaxSteps = 20000;          // per ray; far more than any ray needs
constexpr double kShadowRayOffset = 6e-5; // metres along the normal, so a shadow ray does not re-hit its start
constexpr double kNormalDelta = 1e-5;     // metres, central differences
// Per-cell random streams (counter-based, so one setting never shifts another's random choices).
constexpr uint64_t kStreamSpeckle = 1;
constexpr uint64_t kStreamNoise1 = 2;
constexpr uint64_t kStreamNoise2 = 3;

Vec3d operator+(const Vec3d& a, const Vec3d& b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
Vec3d operator-(const Vec3d& a, const Vec3d& b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
Vec3d operator*(const Vec3d& a, double s) {
    return {a.x * s, a.y * s, a.z * s};
}
double dot(const Vec3d& a, const Vec3d& b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
double length(const Vec3d& a) {
    return std::sqrt(dot(a, a));
}
Vec3d normalized(const Vec3d& a) {
    const double l = length(a);
    return l > 0.0 ? a * (1.0 / l) : Vec3d{0.0, 0.0, 0.0};
}

// splitmix64's finaliser: a bijective 64-bit mix.
uint64_t mix64(uint64_t z) {
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

uint64_t hash4(uint64_t a, uint64_t b, uint64_t c, uint64_t d) {
    return mix64(mix64(mix64(mix64(a) ^ b) ^ c) ^ d);
}

// Uniform in (0, 1), never exactly 0 or 1.
double unitFromHash(uint64_t h) {
    return (double(h >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

double cellUniform(uint64_t seed, uint64_t view, uint64_t cell, uint64_t stream) {
    return unitFromHash(hash4(seed, view, cell, stream));
}

// 3x3 rotation matrix of a unit quaternion (x, y, z, w), row-major.
void quaternionToMatrix(const double q[4], double m[9]) {
    const double x = q[0], y = q[1], z = q[2], w = q[3];
    m[0] = 1 - 2 * (y * y + z * z);
    m[1] = 2 * (x * y - z * w);
    m[2] = 2 * (x * z + y * w);
    m[3] = 2 * (x * y + z * w);
    m[4] = 1 - 2 * (x * x + z * z);
    m[5] = 2 * (y * z - x * w);
    m[6] = 2 * (x * z - y * w);
    m[7] = 2 * (y * z + x * w);
    m[8] = 1 - 2 * (x * x + y * y);
}

Vec3d mul(const double m[9], const Vec3d& p) {
    return {m[0] * p.x + m[1] * p.y + m[2] * p.z, m[3] * p.x + m[4] * p.y + m[5] * p.z,
            m[6] * p.x + m[7] * p.y + m[8] * p.z};
}
Vec3d mulTransposed(const double m[9], const Vec3d& p) {
    return {m[0] * p.x + m[3] * p.y + m[6] * p.z, m[1] * p.x + m[4] * p.y + m[7] * p.z,
            m[2] * p.x + m[5] * p.y + m[8] * p.z};
}

double quintic(double t) {
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

bool finitePositive(double v) {
    return std::isfinite(v) && v > 0.0;
}

} // namespace

// Lattice value noise in [-1, 1], smooth (C2) thanks to the quintic fade.
double valueNoise(uint64_t seed, uint64_t octave, const Vec3d& p) {
    const double fx = std::floor(p.x), fy = std::floor(p.y), fz = std::floor(p.z);
    const int64_t ix = int64_t(fx), iy = int64_t(fy), iz = int64_t(fz);
    const double tx = quintic(p.x - fx), ty = quintic(p.y - fy), tz = quintic(p.z - fz);
    const uint64_t base = hash4(seed, 0x6e6f697365ull, octave, 0);
    double corner[8];
    for (int c = 0; c < 8; ++c) {
        const uint64_t cx = uint64_t(ix + (c & 1)), cy = uint64_t(iy + ((c >> 1) & 1)), cz = uint64_t(iz + (c >> 2));
        corner[c] = unitFromHash(hash4(base, cx, cy, cz)) * 2.0 - 1.0;
    }
    const double x00 = corner[0] + (corner[1] - corner[0]) * tx;
    const double x10 = corner[2] + (corner[3] - corner[2]) * tx;
    const double x01 = corner[4] + (corner[5] - corner[4]) * tx;
    const double x11 = corner[6] + (corner[7] - corner[6]) * tx;
    const double y0 = x00 + (x10 - x00) * ty;
    const double y1 = x01 + (x11 - x01) * ty;
    return y0 + (y1 - y0) * tz;
}

double hashUniform(uint64_t a, uint64_t b, uint64_t c, uint64_t d) {
    return unitFromHash(hash4(a, b, c, d));
}

Shape::Shape(const ShapeOptions& options, uint64_t seed) : options_(options), seed_(seed) {
    const ShapeOptions& o = options_;
    const double a_min = std::min({o.radius_x, o.radius_y, o.radius_z});
    const double a_len = std::sqrt(o.radius_x * o.radius_x + o.radius_y * o.radius_y + o.radius_z * o.radius_z);
    // For a superquadric with exponent >= 2, min(a) <= radius(d) <= |a| over all directions d.
    const double r_max = a_len * (1.0 + o.noise_amplitude);
    const double r_min = a_min * (1.0 - o.noise_amplitude);
    // A provable bound (worst-case value-noise slopes in every octave at once) is about ten times the
    // real slope and makes tracing ten times slower, so the bound is measured instead: the largest
    // central-difference slope of the rock's field over a dense, fixed set of directions and radii
    // spanning the displaced surface, times a safety factor of 2. It is a pure function of the
    // options and the seed, so tracing stays deterministic.
    constexpr int kDirections = 16384;
    constexpr double kGoldenAngle = 2.39996322972865332;
    const double h = 1e-6;
    double slope = 1.0;
    for (int i = 0; i < kDirections; ++i) {
        const double y = 1.0 - 2.0 * (double(i) + 0.5) / kDirections;
        const double ring = std::sqrt(std::max(0.0, 1.0 - y * y));
        const double phi = kGoldenAngle * double(i);
        const Vec3d d{ring * std::cos(phi), y, ring * std::sin(phi)};
        for (int k = 0; k < 4; ++k) {
            const double radius = r_min + (r_max - r_min) * (double(k) + 0.5) / 4.0;
            const Vec3d p{d.x * radius, d.y * radius + o.rock_center_y, d.z * radius};
            const Vec3d g{rockField({p.x + h, p.y, p.z}) - rockField({p.x - h, p.y, p.z}),
                          rockField({p.x, p.y + h, p.z}) - rockField({p.x, p.y - h, p.z}),
                          rockField({p.x, p.y, p.z + h}) - rockField({p.x, p.y, p.z - h})};
            slope = std::max(slope, length(g) / (2.0 * h));
        }
    }
    lipschitz_ = 2.0 * slope;
    const double rock_reach = std::fabs(o.rock_center_y) + r_max;
    const double base_reach = std::sqrt(o.base_radius * o.base_radius + o.base_height * o.base_height);
    bounding_radius_ = std::max(rock_reach, base_reach) * 1.01;
}

double Shape::rockField(const Vec3d& p) const {
    const ShapeOptions& o = options_;
    const Vec3d q{p.x, p.y - o.rock_center_y, p.z};
    const double len = length(q);
    if (len < 1e-12) return -std::min({o.radius_x, o.radius_y, o.radius_z});
    const Vec3d d = q * (1.0 / len);
    const double e = o.exponent;
    const double g = std::pow(std::fabs(d.x / o.radius_x), e) + std::pow(std::fabs(d.y / o.radius_y), e) +
                     std::pow(std::fabs(d.z / o.radius_z), e);
    const double s = std::pow(g, -1.0 / e);
    double fbm = 0.0, amp = 1.0, amp_sum = 0.0, freq = o.noise_frequency;
    for (int k = 0; k < o.noise_octaves; ++k) {
        fbm += amp * valueNoise(seed_, uint64_t(k), d * freq);
        amp_sum += amp;
        amp *= 0.5;
        freq *= 2.0;
    }
    if (amp_sum > 0.0) fbm /= amp_sum;
    return len - s * (1.0 + o.noise_amplitude * fbm);
}

double Shape::field(const Vec3d& p) const {
    const ShapeOptions& o = options_;
    // Exact signed distance to the capped cylinder 0 <= y <= base_height, radius base_radius.
    const double dx = std::sqrt(p.x * p.x + p.z * p.z) - o.base_radius;
    const double dy = std::fabs(p.y - 0.5 * o.base_height) - 0.5 * o.base_height;
    const double ox = std::max(dx, 0.0), oy = std::max(dy, 0.0);
    const double base = std::sqrt(ox * ox + oy * oy) + std::min(std::max(dx, dy), 0.0);
    return std::min(rockField(p), base);
}

Vec3d Shape::normal(const Vec3d& p) const {
    const double h = kNormalDelta;
    const Vec3d g{field({p.x + h, p.y, p.z}) - field({p.x - h, p.y, p.z}),
                  field({p.x, p.y + h, p.z}) - field({p.x, p.y - h, p.z}),
                  field({p.x, p.y, p.z + h}) - field({p.x, p.y, p.z - h})};
    return normalized(g);
}

namespace {

// First t in [0, t_limit] where the ray enters the object, clipped to the bounding sphere.
bool traceFirstHit(const Shape& shape, const Vec3d& origin, const Vec3d& dir, double t_limit, double& t_hit) {
    const double r = shape.boundingRadius();
    const double b = dot(origin, dir);
    const double c = dot(origin, origin) - r * r;
    const double disc = b * b - c;
    if (disc <= 0.0) return false;
    const double root = std::sqrt(disc);
    const double t_exit = std::min(-b + root, t_limit);
    double t = std::max(-b - root, 0.0);
    if (t >= t_exit) return false;
    double f = shape.field(origin + dir * t);
    if (f < 0.0) {
        t_hit = t;
        return true;
    }
    const double inv_l = 1.0 / shape.lipschitz();
    for (int step = 0; step < kMaxSteps; ++step) {
        const double t_next = t + std::max(f * inv_l, kMinStep);
        if (t_next > t_exit) return false;
        const double f_next = shape.field(origin + dir * t_next);
        if (f_next < 0.0) {
            double lo = t, hi = t_next;
            for (int i = 0; i < 40; ++i) {
                const double mid = 0.5 * (lo + hi);
                if (shape.field(origin + dir * mid) < 0.0)
                    hi = mid;
                else
                    lo = mid;
            }
            t_hit = 0.5 * (lo + hi);
            return true;
        }
        t = t_next;
        f = f_next;
    }
    return false;
}

std::string fileNameForView(const std::string& name, double degrees) {
    char buf[32];
    std::snprintf(buf, sizeof(buf), "_%03ld.ply", std::lround(degrees));
    return name + buf;
}

void appendText(std::vector<uint8_t>& out, const std::string& s) {
    out.insert(out.end(), s.begin(), s.end());
}

void appendU32le(std::vector<uint8_t>& out, uint32_t v) {
    for (int i = 0; i < 4; ++i) out.push_back(uint8_t(v >> (8 * i)));
}

void appendF32le(std::vector<uint8_t>& out, float f) {
    uint32_t bits = 0;
    std::memcpy(&bits, &f, sizeof(bits));
    appendU32le(out, bits);
}

std::string formatDouble(const char* fmt, double v) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), fmt, v);
    return buf;
}

} // namespace

Vec3d scannerToWorld(const Vec3d& p, const double quaternion[4], const double translation[3]) {
    double m[9];
    quaternionToMatrix(quaternion, m);
    return mulTransposed(m, p) + Vec3d{translation[0], translation[1], translation[2]};
}

Status validateOptions(const ScanOptions& o) {
    const ShapeOptions& s = o.shape;
    auto bad = [](const std::string& field, const std::string& expected) {
        return invalidInput("scansim option " + field + ": expected " + expected);
    };
    if (o.name.empty() || o.name.find_first_of("/\\") != std::string::npos)
        return bad("name", "a non-empty file name stem without slashes");
    if (o.view_count < 1 || o.view_count > 360) return bad("views", "1..360");
    if (o.num_cols < 2 || o.num_cols > 4096) return bad("cols", "2..4096");
    if (o.num_rows < 2 || o.num_rows > 4096) return bad("rows", "2..4096");
    if (!finitePositive(o.camera_distance)) return bad("camera_distance", "a positive number");
    if (!finitePositive(o.frame_height)) return bad("frame_height", "a positive number");
    if (!std::isfinite(o.projector_baseline)) return bad("projector_baseline", "a finite number");
    if (!(o.range_noise_sigma >= 0.0) || !std::isfinite(o.range_noise_sigma)) return bad("sigma", "a number >= 0");
    if (!(o.grazing_limit_deg > 0.0 && o.grazing_limit_deg <= 90.0)) return bad("grazing", "degrees in (0, 90]");
    if (!(o.speckle_probability >= 0.0 && o.speckle_probability <= 1.0))
        return bad("speckle", "a probability in [0, 1]");
    if (!(finitePositive(s.radius_x) && finitePositive(s.radius_y) && finitePositive(s.radius_z)))
        return bad("shape radii", "positive numbers");
    if (!(s.exponent >= 2.0 && s.exponent <= 8.0)) return bad("shape exponent", "2..8");
    if (!(s.noise_amplitude >= 0.0 && s.noise_amplitude <= 0.5)) return bad("shape noise_amplitude", "0..0.5");
    if (!(s.noise_frequency >= 0.0 && s.noise_frequency <= 64.0)) return bad("shape noise_frequency", "0..64");
    if (s.noise_octaves < 0 || s.noise_octaves > 10) return bad("shape noise_octaves", "0..10");
    if (!(finitePositive(s.base_radius) && finitePositive(s.base_height))) return bad("shape base", "positive sizes");
    if (!std::isfinite(s.rock_center_y)) return bad("shape rock_center_y", "a finite number");
    return Status::okStatus();
}

Result<ScanSet> simulateScans(const ScanOptions& o) {
    LODBAKE_RETURN_IF_ERROR(validateOptions(o));
    const Shape shape(o.shape, o.seed);
    const double cos_grazing = std::cos(o.grazing_limit_deg * (kPi / 180.0));
    const double pitch = o.frame_height / double(o.num_rows);
    const Vec3d camera_s{0.0, 0.0, o.camera_distance};
    const Vec3d projector_s{o.projector_baseline, 0.0, o.camera_distance};

    ScanSet set;
    set.views.resize(size_t(o.view_count));
    for (int v = 0; v < o.view_count; ++v) {
        ScanView& view = set.views[size_t(v)];
        view.turntable_deg = 360.0 * double(v) / double(o.view_count);
        view.file_name = fileNameForView(o.name, view.turntable_deg);
        // The turntable turns the object by -angle about +y; scanner = R * world + offset.
        const double half = -0.5 * view.turntable_deg * (kPi / 180.0);
        view.quaternion[0] = 0.0;
        view.quaternion[1] = v == 0 ? 0.0 : std::sin(half);
        view.quaternion[2] = 0.0;
        view.quaternion[3] = v == 0 ? 1.0 : std::cos(half);
        double m[9];
        quaternionToMatrix(view.quaternion, m);
        const Vec3d t = mulTransposed(m, kScannerOffset) * -1.0;
        view.translation[0] = t.x;
        view.translation[1] = t.y;
        view.translation[2] = t.z;
        const Vec3d camera_w = scannerToWorld(camera_s, view.quaternion, view.translation);
        const Vec3d projector_w = scannerToWorld(projector_s, view.quaternion, view.translation);

        const size_t cells = size_t(o.num_cols) * o.num_rows;
        view.cell_vertex.assign(cells, -1);
        view.stats.cells = cells;
        for (uint32_t row = 0; row < o.num_rows; ++row) {
            for (uint32_t col = 0; col < o.num_cols; ++col) {
                const size_t cell = size_t(row) * o.num_cols + col;
                const Vec3d target_s{(double(col) + 0.5 - 0.5 * o.num_cols) * pitch,
                                     (double(row) + 0.5 - 0.5 * o.num_rows) * pitch, 0.0};
                const Vec3d dir_s = normalized(target_s - camera_s);
                const Vec3d dir_w = mulTransposed(m, dir_s);
                double t_hit = 0.0;
                if (!traceFirstHit(shape, camera_w, dir_w, 1e30, t_hit)) continue;
                ++view.stats.hits;
                const Vec3d hit = camera_w + dir_w * t_hit;
                const Vec3d n = shape.normal(hit);
                if (o.simulate_shadows) {
                    const Vec3d start = hit + n * kShadowRayOffset;
                    const Vec3d to_projector = projector_w - start;
                    double t_block = 0.0;
                    if (dot(n, to_projector) <= 0.0 ||
                        traceFirstHit(shape, start, normalized(to_projector), length(to_projector), t_block)) {
                        ++view.stats.dropped_shadow;
                        continue;
                    }
                }
                const double cos_view = -dot(n, dir_w);
                if (cos_view < cos_grazing) {
                    ++view.stats.dropped_grazing;
                    continue;
                }
                if (cellUniform(o.seed, uint64_t(v), cell, kStreamSpeckle) < o.speckle_probability) {
                    ++view.stats.dropped_speckle;
                    continue;
                }
                double range_error = 0.0;
                if (o.range_noise_sigma > 0.0) {
                    // Box-Muller; the two uniforms come from their own streams.
                    const double u1 = cellUniform(o.seed, uint64_t(v), cell, kStreamNoise1);
                    const double u2 = cellUniform(o.seed, uint64_t(v), cell, kStreamNoise2);
                    range_error = std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2) * o.range_noise_sigma;
                }
                const Vec3d measured_w = hit + dir_w * range_error;
                const Vec3d measured_s = mul(m, measured_w) + kScannerOffset;
                view.cell_vertex[cell] = int32_t(view.stats.kept);
                view.points.push_back(float(measured_s.x));
                view.points.push_back(float(measured_s.y));
                view.points.push_back(float(measured_s.z));
                view.confidence.push_back(float(cos_view));
                ++view.stats.kept;
            }
        }
    }
    return set;
}

std::vector<uint8_t> rangeGridPlyBytes(const ScanView& view, const ScanOptions& o) {
    std::vector<uint8_t> out;
    const size_t vertex_count = view.points.size() / 3;
    std::string header = "ply\n";
    header += o.binary ? "format binary_little_endian 1.0\n" : "format ascii 1.0\n";
    header += "comment made by lodbake_scansim (simulated turntable range scan, no third-party data)\n";
    header += "comment seed " + std::to_string(o.seed) + " view " + view.file_name + " turntable " +
              formatDouble("%g", view.turntable_deg) + " deg, range noise sigma " +
              formatDouble("%g", o.range_noise_sigma) + " m, grazing limit " + formatDouble("%g", o.grazing_limit_deg) +
              " deg, speckle " + formatDouble("%g", o.speckle_probability) + "\n";
    header += "obj_info is_mesh 0\n";
    header += "obj_info num_cols " + std::to_string(o.num_cols) + "\n";
    header += "obj_info num_rows " + std::to_string(o.num_rows) + "\n";
    header += "element vertex " + std::to_string(vertex_count) + "\n";
    header += "property float x\nproperty float y\nproperty float z\n";
    if (o.write_confidence) header += "property float confidence\n";
    header += "element range_grid " + std::to_string(view.cell_vertex.size()) + "\n";
    header += "property list uchar int vertex_indices\n";
    header += "end_header\n";
    appendText(out, header);
    for (size_t i = 0; i < vertex_count; ++i) {
        if (o.binary) {
            for (int k = 0; k < 3; ++k) appendF32le(out, view.points[i * 3 + size_t(k)]);
            if (o.write_confidence) appendF32le(out, view.confidence[i]);
        } else {
            std::string line;
            for (int k = 0; k < 3; ++k)
                line += (k ? " " : "") + formatDouble("%.9g", double(view.points[i * 3 + size_t(k)]));
            if (o.write_confidence) line += " " + formatDouble("%.9g", double(view.confidence[i]));
            appendText(out, line + "\n");
        }
    }
    for (int32_t index : view.cell_vertex) {
        if (o.binary) {
            if (index < 0) {
                out.push_back(0);
            } else {
                out.push_back(1);
                appendU32le(out, uint32_t(index));
            }
        } else {
            appendText(out, index < 0 ? std::string("0\n") : "1 " + std::to_string(index) + "\n");
        }
    }
    return out;
}

std::string confText(const ScanSet& scans) {
    std::string text;
    for (const ScanView& v : scans.views) {
        text += "bmesh " + v.file_name;
        for (double t : v.translation) text += " " + formatDouble("%.9g", t);
        for (double q : v.quaternion) text += " " + formatDouble("%.9g", q);
        text += "\n";
    }
    return text;
}

std::string confFileName(const ScanOptions& options) {
    return options.name + ".conf";
}

Status writeScanSet(const ScanSet& scans, const ScanOptions& options, const std::string& directory) {
    std::error_code ec;
    std::filesystem::create_directories(directory, ec);
    if (ec) return ioError(directory + ": cannot create the folder: " + ec.message());
    AtomicFileWriter writer;
    for (const ScanView& v : scans.views)
        LODBAKE_RETURN_IF_ERROR(writer.add(joinPath(directory, v.file_name), rangeGridPlyBytes(v, options)));
    LODBAKE_RETURN_IF_ERROR(writer.add(joinPath(directory, confFileName(options)), confText(scans)));
    return writer.commit();
}

Result<ScanOptions> presetOptions(const std::string& name) {
    if (name == "rock") {
        // The bundled sample (assets/samples/rock_scan): small enough to commit, detailed enough that
        // simplification has something to remove.
        ScanOptions o;
        o.name = "rock";
        o.seed = 1;
        o.view_count = 6;
        o.num_cols = 96;
        o.num_rows = 72;
        return o;
    }
    return invalidInput("unknown preset '" + name + "' (known: rock)");
}

} // namespace lodbake::scansim
