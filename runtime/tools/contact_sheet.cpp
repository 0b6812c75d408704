// Contact sheet rasteriser for loddump --render: orthographic projection, a depth buffer, a headlight
// Lambert term (one flat colour per triangle for untextured levels; per pixel from the interpolated
// normal, perturbed by the normal map, for levels with materials, whose base colour comes from the
// texture), edge-distance wireframe (the pixel's distance to the nearest edge from its barycentric
// coordinates, as in Bærentzen et al., "Single-pass wireframe rendering", SIGGRAPH 2006 sketches).
#include "contact_sheet.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace loddump {

namespace {

constexpr float kPi = 3.14159265358979f;
constexpr uint8_t kBackground[3] = {236, 236, 240};
constexpr float kBaseColour[3] = {0.72f, 0.78f, 0.88f};
constexpr float kWireColour[3] = {0.12f, 0.14f, 0.2f};

// 5x7 glyphs, one byte per row (low 5 bits, bit 4 = leftmost column).
struct Glyph {
    char c;
    uint8_t rows[7];
};
constexpr Glyph kFont[] = {
    {'0', {14, 17, 19, 21, 25, 17, 14}}, {'1', {4, 12, 4, 4, 4, 4, 14}},     {'2', {14, 17, 1, 2, 4, 8, 31}},
    {'3', {31, 2, 4, 2, 1, 17, 14}},     {'4', {2, 6, 10, 18, 31, 2, 2}},    {'5', {31, 16, 30, 1, 1, 17, 14}},
    {'6', {6, 8, 16, 30, 17, 17, 14}},   {'7', {31, 1, 2, 4, 8, 8, 8}},      {'8', {14, 17, 17, 14, 17, 17, 14}},
    {'9', {14, 17, 17, 15, 1, 2, 12}},   {'L', {16, 16, 16, 16, 16, 16, 31}}, {'t', {8, 8, 28, 8, 8, 9, 6}},
    {'r', {0, 0, 22, 25, 16, 16, 16}},   {'i', {4, 0, 12, 4, 4, 4, 14}},     {'s', {0, 0, 14, 16, 14, 1, 30}},
    {'v', {0, 0, 17, 17, 17, 10, 4}},    {'c', {0, 0, 14, 16, 16, 17, 14}},  {'k', {16, 16, 18, 20, 24, 20, 18}},
    {'.', {0, 0, 0, 0, 0, 12, 12}},      {'-', {0, 0, 0, 31, 0, 0, 0}},      {'?', {14, 17, 1, 2, 4, 0, 4}},
};

void drawText(SheetImage& image, uint32_t x0, uint32_t y0, const std::string& text) {
    constexpr uint32_t kScale = 2;
    uint32_t x = x0;
    for (char c : text) {
        const Glyph* glyph = nullptr;
        for (const Glyph& g : kFont)
            if (g.c == c) glyph = &g;
        if (glyph) {
            for (uint32_t row = 0; row < 7; ++row)
                for (uint32_t col = 0; col < 5; ++col) {
                    if (!(glyph->rows[row] & (16u >> col))) continue;
                    for (uint32_t dy = 0; dy < kScale; ++dy)
                        for (uint32_t dx = 0; dx < kScale; ++dx) {
                            const uint32_t px = x + col * kScale + dx, py = y0 + row * kScale + dy;
                            if (px >= image.width || py >= image.height) continue;
                            uint8_t* p = &image.rgb[(size_t(py) * image.width + px) * 3];
                            p[0] = p[1] = p[2] = 20;
                        }
                }
        }
        x += 6 * kScale;
    }
}

struct View {
    float right[3], up[3], forward[3]; // camera basis; forward points from the camera into the scene
    float centre[3];
    float scale; // pixels per object unit
};

float dot3(const float* a, const float* b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

View frame(const SheetMesh& mesh, uint32_t cell_px) {
    View v;
    const float azimuth = 30.0f * kPi / 180.0f, elevation = 20.0f * kPi / 180.0f;
    // Camera on the +Z side, turned by the azimuth towards +X and raised by the elevation.
    const float to_camera[3] = {std::sin(azimuth) * std::cos(elevation), std::sin(elevation),
                                std::cos(azimuth) * std::cos(elevation)};
    for (int k = 0; k < 3; ++k) v.forward[k] = -to_camera[k];
    v.right[0] = std::cos(azimuth);
    v.right[1] = 0;
    v.right[2] = -std::sin(azimuth);
    // up = right x forward... computed as to_camera x right so it points towards +Y.
    v.up[0] = to_camera[1] * v.right[2] - to_camera[2] * v.right[1];
    v.up[1] = to_camera[2] * v.right[0] - to_camera[0] * v.right[2];
    v.up[2] = to_camera[0] * v.right[1] - to_camera[1] * v.right[0];
    float lo[3] = {std::numeric_limits<float>::max(), std::numeric_limits<float>::max(),
                   std::numeric_limits<float>::max()};
    float hi[3] = {-lo[0], -lo[1], -lo[2]};
    for (uint32_t i : mesh.indices) {
        if (size_t(i) * 3 + 2 >= mesh.positions.size()) continue;
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], mesh.positions[size_t(i) * 3 + size_t(k)]);
            hi[k] = std::max(hi[k], mesh.positions[size_t(i) * 3 + size_t(k)]);
        }
    }
    if (lo[0] > hi[0]) lo[0] = lo[1] = lo[2] = hi[0] = hi[1] = hi[2] = 0;
    float radius = 0;
    for (int k = 0; k < 3; ++k) {
        v.centre[k] = 0.5f * (lo[k] + hi[k]);
        radius += 0.25f * (hi[k] - lo[k]) * (hi[k] - lo[k]);
    }
    radius = std::sqrt(radius);
    v.scale = radius > 0 ? 0.46f * float(cell_px) / radius : 1.0f;
    return v;
}

void cross3(const float* a, const float* b, float* out) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

// Normalises v in place; false (v unchanged) when it has no length.
bool normalise3(float* v) {
    const float length = std::sqrt(dot3(v, v));
    if (!(length > 1e-20f) || !std::isfinite(length)) return false;
    for (int k = 0; k < 3; ++k) v[k] /= length;
    return true;
}

float srgbToLinear(float c) {
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

float linearToSrgb(float l) {
    l = std::clamp(l, 0.0f, 1.0f);
    return l <= 0.0031308f ? l * 12.92f : 1.055f * std::pow(l, 1.0f / 2.4f) - 0.055f;
}

// Bilinear sample with repeat wrapping (glTF's default sampler), texel centres at half-integers;
// sRGB texels are converted to linear light before they are blended.
void sampleTexture(const SheetTexture& t, float u, float v, bool is_srgb, float out[4]) {
    static const std::vector<float> srgb_table = [] {
        std::vector<float> table(256);
        for (int i = 0; i < 256; ++i) table[size_t(i)] = srgbToLinear(float(i) / 255.0f);
        return table;
    }();
    for (int k = 0; k < 4; ++k) out[k] = 0;
    if (t.width == 0 || t.height == 0 || t.rgba.size() < size_t(t.width) * t.height * 4) return;
    float x = u * float(t.width) - 0.5f, y = v * float(t.height) - 0.5f;
    if (!std::isfinite(x) || !std::isfinite(y)) x = y = 0;
    const float fx = std::floor(x), fy = std::floor(y);
    const float ax = x - fx, ay = y - fy;
    auto wrap = [](double i, uint32_t n) { return size_t(int64_t(std::fmod(std::fmod(i, double(n)) + n, double(n)))); };
    for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
            const float weight = (dx ? ax : 1 - ax) * (dy ? ay : 1 - ay);
            const uint8_t* texel = &t.rgba[(wrap(fy + dy, t.height) * t.width + wrap(fx + dx, t.width)) * 4];
            for (int k = 0; k < 4; ++k) {
                const float value = is_srgb && k < 3 ? srgb_table[texel[k]] : float(texel[k]) / 255.0f;
                out[k] += weight * value;
            }
        }
}

// Per-pixel shading of one triangle of a level with materials: base colour from the factor and the
// texture, normal from the interpolated vertex normals (or the face's) perturbed by the normal map in
// the tangent frame (interpolated TANGENT, or the face's UV gradient), then the headlight term.
class TexturedShader {
public:
    TexturedShader(const SheetMesh& mesh, const View& view) : mesh_(mesh), view_(view) {}

    void prepare(size_t triangle, const uint32_t* v, const float* face_normal) {
        for (int k = 0; k < 3; ++k) v_[k] = v[k];
        const uint32_t m = triangle < mesh_.triangle_material.size() ? mesh_.triangle_material[triangle] : 0;
        material_ = m < mesh_.materials.size() ? &mesh_.materials[m] : &kDefault;
        for (int k = 0; k < 3; ++k) face_normal_[k] = face_normal[k];
        faceTangent();
    }

    // Display-space RGB in [0, 1] at barycentric weights w.
    void shade(const float w[3], float out[3]) const {
        float albedo[4] = {1, 1, 1, 1};
        if (material_->base_colour_texture) {
            float uv[2];
            interpolate(uvSet(material_->base_colour_uv), 2, w, uv);
            sampleTexture(*material_->base_colour_texture, uv[0], uv[1], true, albedo);
        }
        float n[3];
        bool has_normal = false;
        if (mesh_.normals.size() == mesh_.positions.size()) {
            interpolate(&mesh_.normals, 3, w, n);
            has_normal = normalise3(n); // a zero normal (a primitive without NORMAL) takes the face's
        }
        if (!has_normal)
            for (int k = 0; k < 3; ++k) n[k] = face_normal_[k];
        if (material_->normal_texture) perturb(w, n);
        const float shade_term = 0.25f + 0.75f * std::fabs(dot3(n, view_.forward));
        for (int k = 0; k < 3; ++k) out[k] = linearToSrgb(albedo[k] * material_->base_colour[k] * shade_term);
    }

private:
    const std::vector<float>* uvSet(uint32_t set) const {
        return set < mesh_.uvs.size() && mesh_.uvs[set].size() / 2 == mesh_.positions.size() / 3 ? &mesh_.uvs[set]
                                                                                                  : nullptr;
    }

    void interpolate(const std::vector<float>* stream, int width, const float w[3], float* out) const {
        for (int k = 0; k < width; ++k) {
            out[k] = 0;
            if (!stream) continue;
            for (int c = 0; c < 3; ++c) out[k] += w[c] * (*stream)[size_t(v_[c]) * size_t(width) + size_t(k)];
        }
    }

    // The face's tangent frame from the normal map's UVs: T along +u, handedness so that
    // cross(N, T) * w points up the image (towards -v).
    void faceTangent() {
        face_tangent_[0] = 1, face_tangent_[1] = face_tangent_[2] = 0, face_tangent_[3] = 1;
        const std::vector<float>* uv = material_->normal_texture ? uvSet(material_->normal_uv) : nullptr;
        if (!uv) return;
        const float* p[3];
        const float* t[3];
        for (int k = 0; k < 3; ++k) {
            p[k] = &mesh_.positions[size_t(v_[k]) * 3];
            t[k] = &(*uv)[size_t(v_[k]) * 2];
        }
        const float e1[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
        const float e2[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
        const float du1 = t[1][0] - t[0][0], dv1 = t[1][1] - t[0][1], du2 = t[2][0] - t[0][0], dv2 = t[2][1] - t[0][1];
        const float r = du1 * dv2 - du2 * dv1;
        if (!(std::fabs(r) > 1e-20f)) return;
        float dpdu[3], dpdv[3], side[3];
        for (int k = 0; k < 3; ++k) {
            dpdu[k] = (e1[k] * dv2 - e2[k] * dv1) / r;
            dpdv[k] = (e2[k] * du1 - e1[k] * du2) / r;
        }
        if (!normalise3(dpdu)) return;
        cross3(face_normal_, dpdu, side);
        for (int k = 0; k < 3; ++k) face_tangent_[k] = dpdu[k];
        face_tangent_[3] = dot3(side, dpdv) <= 0 ? 1.0f : -1.0f;
    }

    void perturb(const float w[3], float* n) const {
        float tangent[4];
        for (int k = 0; k < 4; ++k) tangent[k] = face_tangent_[k];
        if (mesh_.tangents.size() / 4 == mesh_.positions.size() / 3) {
            interpolate(&mesh_.tangents, 4, w, tangent);
            tangent[3] = mesh_.tangents[size_t(v_[0]) * 4 + 3] < 0 ? -1.0f : 1.0f;
            if (!normalise3(tangent))
                for (int k = 0; k < 4; ++k) tangent[k] = face_tangent_[k];
        }
        // Gram-Schmidt against the shading normal, then the bitangent glTF defines.
        const float along = dot3(n, tangent);
        for (int k = 0; k < 3; ++k) tangent[k] -= along * n[k];
        if (!normalise3(tangent)) return;
        float bitangent[3];
        cross3(n, tangent, bitangent);
        float uv[2], texel[4];
        interpolate(uvSet(material_->normal_uv), 2, w, uv);
        sampleTexture(*material_->normal_texture, uv[0], uv[1], false, texel);
        const float tx = (2 * texel[0] - 1) * material_->normal_scale, ty = (2 * texel[1] - 1) * material_->normal_scale,
                    tz = 2 * texel[2] - 1;
        float perturbed[3];
        for (int k = 0; k < 3; ++k) perturbed[k] = tangent[k] * tx + bitangent[k] * tangent[3] * ty + n[k] * tz;
        if (normalise3(perturbed))
            for (int k = 0; k < 3; ++k) n[k] = perturbed[k];
    }

    static const SheetMaterial kDefault;
    const SheetMesh& mesh_;
    const View& view_;
    const SheetMaterial* material_ = &kDefault;
    uint32_t v_[3] = {0, 0, 0};
    float face_normal_[3] = {0, 0, 1};
    float face_tangent_[4] = {1, 0, 0, 1};
};

const SheetMaterial TexturedShader::kDefault{};

void drawMesh(SheetImage& image, std::vector<float>& depth, uint32_t cell_x, uint32_t cell_y, uint32_t cell_px,
              const SheetMesh& mesh, const View& view, bool wireframe) {
    const size_t vertex_count = mesh.positions.size() / 3;
    std::vector<float> sx(vertex_count), sy(vertex_count), sz(vertex_count);
    for (size_t v = 0; v < vertex_count; ++v) {
        float p[3];
        for (int k = 0; k < 3; ++k) p[k] = mesh.positions[v * 3 + size_t(k)] - view.centre[k];
        sx[v] = float(cell_x) + 0.5f * float(cell_px) + dot3(p, view.right) * view.scale;
        sy[v] = float(cell_y) + 0.5f * float(cell_px) - dot3(p, view.up) * view.scale;
        sz[v] = dot3(p, view.forward);
    }
    const bool is_textured = !mesh.triangle_material.empty();
    TexturedShader textured(mesh, view);
    const float x_end = float(cell_x + cell_px), y_end = float(cell_y + cell_px);
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
        const uint32_t a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
        if (a >= vertex_count || b >= vertex_count || c >= vertex_count) continue;
        // Flat shading: |cos| between the face normal and the view direction (two-sided headlight).
        const float* pa = &mesh.positions[size_t(a) * 3];
        const float* pb = &mesh.positions[size_t(b) * 3];
        const float* pc = &mesh.positions[size_t(c) * 3];
        const float e1[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]};
        const float e2[3] = {pc[0] - pa[0], pc[1] - pa[1], pc[2] - pa[2]};
        const float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        const float n_len = std::sqrt(dot3(n, n));
        if (!(n_len > 0)) continue;
        const float lambert = std::fabs(dot3(n, view.forward)) / n_len;
        const float shade = 0.25f + 0.75f * lambert;
        if (is_textured) {
            const uint32_t corners[3] = {a, b, c};
            const float unit[3] = {n[0] / n_len, n[1] / n_len, n[2] / n_len};
            textured.prepare(t / 3, corners, unit);
        }

        const float x0 = sx[a], y0 = sy[a], x1 = sx[b], y1 = sy[b], x2 = sx[c], y2 = sy[c];
        const float area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
        if (std::fabs(area) < 1e-12f) continue;
        const float min_x = std::max(float(cell_x), std::floor(std::min({x0, x1, x2})));
        const float max_x = std::min(x_end - 1, std::ceil(std::max({x0, x1, x2})));
        const float min_y = std::max(float(cell_y), std::floor(std::min({y0, y1, y2})));
        const float max_y = std::min(y_end - 1, std::ceil(std::max({y0, y1, y2})));
        if (min_x > max_x || min_y > max_y) continue;
        // Lengths of the edges opposite each corner, for the pixel distance to each edge.
        const float len0 = std::hypot(x2 - x1, y2 - y1), len1 = std::hypot(x0 - x2, y0 - y2),
                    len2 = std::hypot(x1 - x0, y1 - y0);
        for (float py = min_y; py <= max_y; ++py)
            for (float px = min_x; px <= max_x; ++px) {
                const float cx = px + 0.5f, cy = py + 0.5f;
                const float w0 = ((x1 - cx) * (y2 - cy) - (x2 - cx) * (y1 - cy)) / area;
                const float w1 = ((x2 - cx) * (y0 - cy) - (x0 - cx) * (y2 - cy)) / area;
                const float w2 = 1.0f - w0 - w1;
                if (w0 < 0 || w1 < 0 || w2 < 0) continue;
                const float z = w0 * sz[a] + w1 * sz[b] + w2 * sz[c];
                const size_t pixel = size_t(py) * image.width + size_t(px);
                if (!(z < depth[pixel])) continue;
                depth[pixel] = z;
                float colour[3];
                if (is_textured) {
                    const float w[3] = {w0, w1, w2};
                    textured.shade(w, colour);
                } else {
                    for (int k = 0; k < 3; ++k) colour[k] = kBaseColour[k] * shade;
                }
                if (wireframe) {
                    const float d = std::min({w0 * std::fabs(area) / std::max(len0, 1e-6f),
                                              w1 * std::fabs(area) / std::max(len1, 1e-6f),
                                              w2 * std::fabs(area) / std::max(len2, 1e-6f)});
                    const float ink = std::clamp(1.0f - d / 0.75f, 0.0f, 1.0f) * 0.8f;
                    for (int k = 0; k < 3; ++k) colour[k] = colour[k] * (1 - ink) + kWireColour[k] * ink;
                }
                uint8_t* out = &image.rgb[pixel * 3];
                for (int k = 0; k < 3; ++k) out[k] = uint8_t(std::clamp(colour[k], 0.0f, 1.0f) * 255.0f + 0.5f);
            }
    }
}

} // namespace

SheetImage renderContactSheet(const std::vector<std::vector<SheetMesh>>& rows, const SheetOptions& options) {
    SheetImage image;
    size_t columns = 0;
    for (const auto& row : rows) columns = std::max(columns, row.size());
    const uint32_t cell = std::max<uint32_t>(options.cell_px, 32);
    image.width = uint32_t(std::max<size_t>(columns, 1)) * cell;
    image.height = uint32_t(std::max<size_t>(rows.size(), 1)) * cell;
    image.rgb.resize(size_t(image.width) * image.height * 3);
    for (size_t p = 0; p < size_t(image.width) * image.height; ++p)
        for (int k = 0; k < 3; ++k) image.rgb[p * 3 + size_t(k)] = kBackground[k];
    std::vector<float> depth(size_t(image.width) * image.height, std::numeric_limits<float>::infinity());
    for (size_t r = 0; r < rows.size(); ++r) {
        if (rows[r].empty()) continue;
        const View view = frame(rows[r][0], cell);
        for (size_t c = 0; c < rows[r].size(); ++c) {
            const uint32_t x = uint32_t(c) * cell, y = uint32_t(r) * cell;
            drawMesh(image, depth, x, y, cell, rows[r][c], view, options.wireframe);
            // Cell border, one pixel on the right and bottom.
            for (uint32_t i = 0; i < cell; ++i) {
                uint8_t* right = &image.rgb[(size_t(y + i) * image.width + x + cell - 1) * 3];
                uint8_t* bottom = &image.rgb[(size_t(y + cell - 1) * image.width + x + i) * 3];
                right[0] = right[1] = right[2] = 180;
                bottom[0] = bottom[1] = bottom[2] = 180;
            }
            drawText(image, x + 6, y + 6, rows[r][c].label);
        }
    }
    return image;
}

} // namespace loddump
