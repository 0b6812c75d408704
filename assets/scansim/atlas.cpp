// The atlased reconstruction of the simulated object (scansim.h, atlasObjText): a cube-sphere mesh
// of the rock cut into square charts, each mapped by a central projection into its own atlas cell,
// as automatic photogrammetry atlases are (hundreds of small charts with seams everywhere).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "scansim.h"

namespace lodbake::scansim {

namespace {

// Distance from `centre` to the rock's surface along the unit direction d: the first sign change
// of the field, stepped finely and then bisected.
double surfaceDistance(const Shape& shape, const Vec3d& centre, const Vec3d& d) {
    auto at = [&](double t) { return shape.field({centre.x + d.x * t, centre.y + d.y * t, centre.z + d.z * t}); };
    const double limit = 2.0 * shape.boundingRadius();
    const double step = limit / 2048.0;
    double lo = 0.0, hi = step;
    while (hi < limit && at(hi) < 0.0) {
        lo = hi;
        hi += step;
    }
    for (int i = 0; i < 48; ++i) {
        const double mid = 0.5 * (lo + hi);
        (at(mid) < 0.0 ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

void appendLine(std::string& out, const char* format, double a, double b, double c) {
    char buf[128];
    std::snprintf(buf, sizeof buf, format, a, b, c);
    out += buf;
}

} // namespace

Result<std::string> atlasObjText(const ScanOptions& options, const AtlasOptions& atlas) {
    if (atlas.charts_per_edge < 1 || atlas.charts_per_edge > 64 || atlas.quads_per_chart < 1 ||
        atlas.quads_per_chart > 64)
        return invalidInput("scansim atlas: expected charts per cube edge and quads per chart in [1, 64]");
    // The rock alone: the plinth is shrunk to nothing so that every direction from the rock's centre
    // meets the surface once (a star-shaped object, one vertex per lattice direction).
    ShapeOptions shape_options = options.shape;
    shape_options.base_radius = 1e-6;
    shape_options.base_height = 1e-6;
    const Shape shape(shape_options, options.seed);
    const Vec3d centre{0.0, shape_options.rock_center_y, 0.0};
    const int k = int(atlas.charts_per_edge), m = int(atlas.quads_per_chart), n = k * m;
    const int charts = 6 * k * k;
    const int grid = int(std::ceil(std::sqrt(double(charts))));
    const double cell = 1.0 / grid, margin = 0.08 * cell;

    // Cube face (axis, sign): lattice point (i, j) in [0, n]² lies at 2i − n along u and 2j − n along
    // v, n along the axis (u × v points outwards, so the faces are counter-clockwise from outside).
    // The lattice is integer, so a point shared by two faces gets the same bits from either.
    auto latticePoint = [&](int face, int i, int j, int out[3]) {
        const int axis = face / 2, sign = face % 2 == 0 ? 1 : -1;
        const int u = sign > 0 ? (axis + 1) % 3 : (axis + 2) % 3, v = sign > 0 ? (axis + 2) % 3 : (axis + 1) % 3;
        out[axis] = sign * n;
        out[u] = 2 * i - n;
        out[v] = 2 * j - n;
        return std::pair<int, int>(u, v);
    };
    std::string text = "# lodbake_scansim atlas: " + std::to_string(charts) + " charts\n";
    std::string positions, uvs, faces;
    int position_count = 0, uv_count = 0;
    // Positions: one per distinct lattice point (faces share their border rows, found by coordinates).
    std::vector<std::vector<int>> face_ids(6, std::vector<int>(size_t(n + 1) * size_t(n + 1), 0));
    std::vector<std::pair<std::vector<int>, int>> seen; // lattice point -> id, only for border points
    for (int face = 0; face < 6; ++face) {
        for (int j = 0; j <= n; ++j)
            for (int i = 0; i <= n; ++i) {
                int p[3];
                latticePoint(face, i, j, p);
                const bool border = i == 0 || j == 0 || i == n || j == n;
                int id = -1;
                if (border)
                    for (const auto& s : seen)
                        if (s.first[0] == p[0] && s.first[1] == p[1] && s.first[2] == p[2]) id = s.second;
                if (id < 0) {
                    id = ++position_count;
                    if (border) seen.push_back({{p[0], p[1], p[2]}, id});
                    const double len = std::sqrt(double(p[0]) * p[0] + double(p[1]) * p[1] + double(p[2]) * p[2]);
                    const Vec3d d{p[0] / len, p[1] / len, p[2] / len};
                    const double t = surfaceDistance(shape, centre, d);
                    appendLine(positions, "v %.9g %.9g %.9g\n", centre.x + d.x * t, centre.y + d.y * t,
                               centre.z + d.z * t);
                }
                face_ids[size_t(face)][size_t(j) * size_t(n + 1) + size_t(i)] = id;
            }
    }
    // Charts: m×m quads of a face each. A chart's UVs are its lattice coordinates (the central
    // projection of the surface onto the cube face), scaled into its own atlas cell.
    for (int face = 0; face < 6; ++face)
        for (int cj = 0; cj < k; ++cj)
            for (int ci = 0; ci < k; ++ci) {
                const int chart = (face * k + cj) * k + ci;
                const double x0 = (chart % grid) * cell + margin, y0 = (chart / grid) * cell + margin;
                const double span = cell - 2.0 * margin;
                const int first_uv = uv_count + 1;
                for (int j = 0; j <= m; ++j)
                    for (int i = 0; i <= m; ++i) {
                        char buf[64];
                        std::snprintf(buf, sizeof buf, "vt %.9g %.9g\n", x0 + span * double(i) / m,
                                      y0 + span * double(j) / m);
                        uvs += buf;
                        ++uv_count;
                    }
                auto corner = [&](int i, int j) {
                    const int gi = ci * m + i, gj = cj * m + j;
                    return std::to_string(face_ids[size_t(face)][size_t(gj) * size_t(n + 1) + size_t(gi)]) + "/" +
                           std::to_string(first_uv + j * (m + 1) + i);
                };
                for (int j = 0; j < m; ++j)
                    for (int i = 0; i < m; ++i) {
                        faces += "f " + corner(i, j) + " " + corner(i + 1, j) + " " + corner(i + 1, j + 1) + "\n";
                        faces += "f " + corner(i, j) + " " + corner(i + 1, j + 1) + " " + corner(i, j + 1) + "\n";
                    }
            }
    return text + positions + uvs + faces;
}

} // namespace lodbake::scansim
