#include "lodbake/io/conf.h"

#include <charconv>
#include <cmath>
#include <sstream>
#include <vector>

#include "lodbake/core/file_io.h"

namespace lodbake {

namespace {

// Rows of R(q) for a unit quaternion (x, y, z, w).
void rotationFromQuaternion(const double q[4], double r[3][3]) {
    const double x = q[0], y = q[1], z = q[2], w = q[3];
    r[0][0] = 1 - 2 * (y * y + z * z);
    r[0][1] = 2 * (x * y - z * w);
    r[0][2] = 2 * (x * z + y * w);
    r[1][0] = 2 * (x * y + z * w);
    r[1][1] = 1 - 2 * (x * x + z * z);
    r[1][2] = 2 * (y * z - x * w);
    r[2][0] = 2 * (x * z - y * w);
    r[2][1] = 2 * (y * z + x * w);
    r[2][2] = 1 - 2 * (x * x + y * y);
}

// R^T · v
Vec3d rotateTransposed(const double r[3][3], const Vec3d& v) {
    return {r[0][0] * v.x + r[1][0] * v.y + r[2][0] * v.z, r[0][1] * v.x + r[1][1] * v.y + r[2][1] * v.z,
            r[0][2] * v.x + r[1][2] * v.y + r[2][2] * v.z};
}

bool parseDouble(const std::string& token, double& out) {
    const char* end = token.data() + token.size();
    const auto r = std::from_chars(token.data(), end, out);
    return r.ec == std::errc() && r.ptr == end && std::isfinite(out);
}

} // namespace

void applyConfTransform(Mesh& mesh, const Vec3d& t, const double q_in[4]) {
    const double len = std::sqrt(q_in[0] * q_in[0] + q_in[1] * q_in[1] + q_in[2] * q_in[2] + q_in[3] * q_in[3]);
    const double q[4] = {q_in[0] / len, q_in[1] / len, q_in[2] / len, q_in[3] / len};
    double r[3][3];
    rotationFromQuaternion(q, r);
    for (Vec3f& p : mesh.positions) p = Vec3f(rotateTransposed(r, toDouble(p)) + t);
    for (Vec3f& n : mesh.normals) n = Vec3f(rotateTransposed(r, toDouble(n)));
    for (Vec4f& tg : mesh.tangents) {
        const Vec3d v = rotateTransposed(r, Vec3d(tg.x, tg.y, tg.z));
        tg = {float(v.x), float(v.y), float(v.z), tg.w};
    }
}

Result<LoadedMesh> readConf(const std::string& path, const ReadOptions& options, Diagnostics& diagnostics) {
    LODBAKE_ASSIGN_OR_RETURN(std::vector<uint8_t> bytes, readFileBytes(path, uint64_t(1) << 24));
    const std::string dir = parentDirectory(path);
    LoadedMesh out;
    out.source.format = MeshFormat::Conf;
    out.source.encoding = "range scans";
    out.source.face_kind = "scans";
    out.source.files_read.push_back(path);

    std::istringstream text(std::string(bytes.begin(), bytes.end()));
    std::string line;
    size_t line_number = 0;
    while (std::getline(text, line)) {
        ++line_number;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        std::istringstream words(line);
        std::vector<std::string> w;
        for (std::string s; words >> s;) w.push_back(s);
        const std::string where = path + ": line " + std::to_string(line_number);
        if (w.empty() || w[0][0] == '#' || w[0] == "camera") continue;
        if (w[0] == "mesh") {
            diagnostics.note(where + ": skipped calibration mesh '" + (w.size() > 1 ? w[1] : "") + "'");
            continue;
        }
        if (w[0] != "bmesh")
            return invalidInput(where + ": expected 'bmesh', 'mesh' or 'camera', got '" + w[0].substr(0, 40) + "'");
        if (w.size() != 9)
            return invalidInput(where + ": expected 'bmesh FILE tx ty tz qx qy qz qw' (9 fields), got " +
                                std::to_string(w.size()));
        double v[7];
        for (int i = 0; i < 7; ++i)
            if (!parseDouble(w[size_t(i) + 2], v[i]))
                return invalidInput(where + ": field " + std::to_string(i + 3) + ": expected a finite number, got '" +
                                    w[size_t(i) + 2].substr(0, 40) + "'");
        if (v[3] * v[3] + v[4] * v[4] + v[5] * v[5] + v[6] * v[6] < 1e-12)
            return invalidInput(where + ": quaternion is zero, expected a rotation");
        const std::string scan_path = joinPath(dir, w[1]);
        if (formatFromPath(scan_path) == MeshFormat::Conf)
            return invalidInput(where + ": scan '" + w[1] + "' is itself a .conf, expected a mesh file");
        Result<LoadedMesh> scan = readMesh(scan_path, options, diagnostics);
        if (!scan.ok()) return scan.status().withPrefix(where);
        Mesh& mesh = scan->mesh;
        applyConfTransform(mesh, Vec3d(v[0], v[1], v[2]), v + 3);
        // Every reader refuses non-finite positions; a finite scan must not become one through a
        // translation near the double range (it would overflow the float positions).
        for (const Vec3f& p : mesh.positions)
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                return invalidInput(where + ": the transform moves scan '" + w[1].substr(0, 80) +
                                    "' outside the float range");
        if (out.mesh.vertexCount() + mesh.vertexCount() > options.max_vertex_count)
            return resourceLimit(where + ": the scans add up to more than " + std::to_string(options.max_vertex_count) +
                                 " vertices");
        for (SubMesh& sm : mesh.submeshes)
            if (sm.name.empty()) sm.name = w[1];
        if (mesh.submeshes.empty() && !mesh.indices.empty())
            mesh.submeshes.push_back({w[1], 0, uint32_t(mesh.indices.size()), MaterialId::invalid()});
        appendMesh(out.mesh, mesh);
        out.source.file_vertex_count += scan->source.file_vertex_count;
        out.source.file_face_count += 1;
        for (const std::string& f : scan->source.files_read) out.source.files_read.push_back(f);
    }
    if (out.source.file_face_count == 0) return invalidInput(path + ": no 'bmesh' lines, expected at least one scan");
    return out;
}

} // namespace lodbake
