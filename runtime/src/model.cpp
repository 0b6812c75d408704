// Model layer: MSFT_lod chains -> models with levels, bounds and measured errors (see lodrt/model.h).
// Rules of LODBAKE_lod_metrics: schemas/LODBAKE_lod_metrics/README.md (checked here with the same
// wording as loddump).

#include "lodrt/model.h"
#include "lodrt/meshopt.h"

#include <cassert>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <limits>
#include <new>

#include "lodrt/format.h"
#include "memory.h"

namespace lodrt {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
// Reference view of MSFT_screencoverage when no measured errors exist (the desktop preset's).
constexpr double kReferenceTanHalfFov = 0.57735026918962573; // tan(30 degrees)
constexpr double kReferenceViewportPx = 1080.0;

// A POSITION bound as the accessor's elements mean it: min and max hold the stored values, so a
// normalized integer accessor's (KHR_mesh_quantization) are mapped as its elements are.
double boundValue(double v, const AccessorInfo& acc) {
    if (!acc.normalized) return v;
    switch (acc.component_type) {
    case ComponentType::Byte:
        return std::fmax(v / 127.0, -1.0);
    case ComponentType::UnsignedByte:
        return v / 255.0;
    case ComponentType::Short:
        return std::fmax(v / 32767.0, -1.0);
    case ComponentType::UnsignedShort:
        return v / 65535.0;
    case ComponentType::UnsignedInt:
        return v / 4294967295.0;
    case ComponentType::Float:
        break;
    }
    return v;
}

// A compact primitive's data is its LODBAKE_valence_compression stream (the accessors it supplies
// have no buffer view): widens [lo, hi) over the stream's view so streaming the level loads it.
// Plain primitives (every accessor with its own view) are left as they are.
void addValenceStreamRange(const Pack& pack, const PrimitiveInfo& prim, uint64_t* lo, uint64_t* hi) {
    bool supplied = prim.indices != kNoIndex && pack.accessor(prim.indices).buffer_view == kNoIndex;
    for (uint32_t a = 0; a < prim.attribute_count; ++a)
        supplied = supplied || pack.accessor(pack.attribute(prim.first_attribute + a).accessor).buffer_view == kNoIndex;
    if (!supplied) return;
    const JsonValue stream = prim.json.find("extensions").find(format::kExtValenceCompression);
    uint64_t stream_view = 0;
    if (!stream.isObject() || !stream.find("bufferView").asUint64(&stream_view) ||
        stream_view >= pack.bufferViewCount())
        return;
    const BufferViewInfo& view = pack.bufferView(uint32_t(stream_view));
    if (!pack.buffer(view.buffer).is_glb_bin) return;
    if (view.byte_offset < *lo) *lo = view.byte_offset;
    if (view.byte_offset + view.byte_length > *hi) *hi = view.byte_offset + view.byte_length;
}

bool finiteFloat(double v) {
    return std::isfinite(v) && std::fabs(v) <= double(std::numeric_limits<float>::max());
}

// Column-major 4x4 product out = a * b (doubles, so chains of transforms round once, at the end).
void multiply(const double a[16], const double b[16], double out[16]) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) {
            double v = 0;
            for (int k = 0; k < 4; ++k) v += a[k * 4 + r] * b[c * 4 + k];
            out[c * 4 + r] = v;
        }
}

void identity(double m[16]) {
    for (int k = 0; k < 16; ++k) m[k] = (k % 5 == 0) ? 1.0 : 0.0;
}

// Reads `count` finite numbers of `array` into out; false when it is not such an array.
bool readNumbers(JsonValue array, uint32_t count, double* out) {
    if (!array.isArray() || array.size() != count) return false;
    for (uint32_t k = 0; k < count; ++k) {
        if (!array.at(k).isNumber() || !finiteFloat(array.at(k).number())) return false;
        out[k] = array.at(k).number();
    }
    return true;
}

} // namespace

float maxAxisScale(const float m[16]) {
    float best = 0;
    for (int c = 0; c < 3; ++c) {
        const float x = m[c * 4], y = m[c * 4 + 1], z = m[c * 4 + 2];
        best = std::fmax(best, std::sqrt(x * x + y * y + z * z));
    }
    return best;
}

void multiplyTransforms(const float a[16], const float b[16], float out[16]) {
    double da[16], db[16], dout[16];
    for (int k = 0; k < 16; ++k) {
        da[k] = a[k];
        db[k] = b[k];
    }
    multiply(da, db, dout);
    for (int k = 0; k < 16; ++k) out[k] = float(dout[k]);
}

void transformSphere(const float m[16], const float center[3], float radius, float out_center[3], float* out_radius) {
    float c[3];
    for (int r = 0; r < 3; ++r) c[r] = m[r] * center[0] + m[4 + r] * center[1] + m[8 + r] * center[2] + m[12 + r];
    for (int r = 0; r < 3; ++r) out_center[r] = c[r];
    *out_radius = radius * maxAxisScale(m);
}

struct ModelBuilder {
    const Pack* pack;
    Allocator allocator;
    char* error;
    size_t error_size;
    uint32_t* owner = nullptr; // per node: chain root owning it, or kNoIndex
    double* world = nullptr;   // per node: 16 doubles, its world transform

#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    Result
    fail(Result code, const char* format, ...) {
        if (error && error_size > 0) {
            va_list args;
            va_start(args, format);
            std::vsnprintf(error, error_size, format, args);
            va_end(args);
        }
        return code;
    }

    static JsonValue lodIds(const NodeInfo& node) {
        return node.json.find("extensions").find(format::kExtMsftLod).find("ids");
    }
    static bool hasLod(const NodeInfo& node) {
        return node.json.find("extensions").find(format::kExtMsftLod).isValid();
    }

    // Local transform of a node (glTF 2.0 §5.25: matrix, or T * R * S), column-major.
    Result localTransform(uint32_t i, double out[16]) {
        const JsonValue node = pack->node(i).json;
        const JsonValue matrix = node.find("matrix"), t = node.find("translation"), r = node.find("rotation"),
                        s = node.find("scale");
        identity(out);
        if (matrix.isValid()) {
            if (t.isValid() || r.isValid() || s.isValid())
                return fail(Result::BadGltf, "/nodes/%u: expected either matrix or translation/rotation/scale, not both",
                            i);
            if (!readNumbers(matrix, 16, out))
                return fail(Result::BadGltf, "/nodes/%u/matrix: expected 16 finite numbers", i);
            if (out[3] != 0 || out[7] != 0 || out[11] != 0 || out[15] != 1)
                return fail(Result::BadGltf, "/nodes/%u/matrix: expected an affine matrix (last row 0 0 0 1)", i);
            return Result::Ok;
        }
        double tv[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, sv[3] = {1, 1, 1};
        if (t.isValid() && !readNumbers(t, 3, tv))
            return fail(Result::BadGltf, "/nodes/%u/translation: expected 3 finite numbers", i);
        if (s.isValid() && !readNumbers(s, 3, sv))
            return fail(Result::BadGltf, "/nodes/%u/scale: expected 3 finite numbers", i);
        if (r.isValid()) {
            if (!readNumbers(r, 4, q)) return fail(Result::BadGltf, "/nodes/%u/rotation: expected 4 finite numbers", i);
            const double len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
            if (!(std::fabs(len - 1.0) <= 1e-3))
                return fail(Result::BadGltf, "/nodes/%u/rotation: expected a unit quaternion (length %g)", i, len);
            for (double& c : q) c /= len;
        }
        const double x = q[0], y = q[1], z = q[2], w = q[3];
        const double rot[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w),     2 * (x * z - y * w),
                               2 * (x * y - z * w),     1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                               2 * (x * z + y * w),     2 * (y * z - x * w),     1 - 2 * (x * x + y * y)};
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 3; ++k) out[c * 4 + k] = rot[c * 3 + k] * sv[c];
        for (int k = 0; k < 3; ++k) out[12 + k] = tv[k];
        return Result::Ok;
    }

    // World transforms of every node, composed through the parents. The pack refuses cyclic
    // hierarchies already; the walk refuses them again rather than trusting it (a path longer than
    // the node count, or a node met twice on one path).
    Result computeWorldTransforms() {
        const uint32_t node_count = pack->nodeCount();
        world = detail::allocateArray<double>(allocator, size_t(node_count) * 16);
        uint8_t* state = detail::allocateArray<uint8_t>(allocator, node_count); // 0 todo, 1 on path, 2 done
        uint32_t* path = detail::allocateArray<uint32_t>(allocator, node_count);
        Result result = Result::Ok;
        if (!world || !state || !path) result = Result::OutOfMemory;
        if (result == Result::Ok) std::memset(state, 0, node_count);
        for (uint32_t i = 0; i < node_count && result == Result::Ok; ++i) {
            uint32_t depth = 0;
            uint32_t k = i;
            while (k != kNoIndex && state[k] != 2) {
                if (state[k] == 1 || depth == node_count) {
                    result = fail(Result::BadGltf, "/nodes/%u: node hierarchy contains a cycle", k);
                    break;
                }
                state[k] = 1;
                path[depth++] = k;
                k = pack->node(k).parent;
                if (k != kNoIndex && k >= node_count) {
                    result = fail(Result::BadGltf, "/nodes/%u: parent out of range", path[depth - 1]);
                    break;
                }
            }
            // path[depth - 1] is the topmost node not yet done; its parent (k) is done or none.
            while (result == Result::Ok && depth > 0) {
                const uint32_t n = path[--depth];
                double local[16];
                result = localTransform(n, local);
                if (result != Result::Ok) break;
                const uint32_t parent = pack->node(n).parent;
                if (parent == kNoIndex)
                    std::memcpy(world + size_t(n) * 16, local, sizeof(local));
                else
                    multiply(world + size_t(parent) * 16, local, world + size_t(n) * 16);
                for (int c = 0; c < 16; ++c)
                    if (!finiteFloat(world[size_t(n) * 16 + c])) {
                        result = fail(Result::BadGltf, "/nodes/%u: world transform overflows", n);
                        break;
                    }
                state[n] = 2;
            }
        }
        detail::deallocateBytes(allocator, state);
        detail::deallocateBytes(allocator, path);
        return result;
    }

    // Validates the chain rooted at `root` and marks its nodes as owned.
    Result claimChain(uint32_t root) {
        const uint32_t node_count = pack->nodeCount();
        JsonValue lod = pack->node(root).json.find("extensions").find(format::kExtMsftLod);
        if (!lod.isObject()) return fail(Result::BadGltf, "/nodes/%u/extensions/MSFT_lod: expected an object", root);
        JsonValue ids = lod.find("ids");
        if (!ids.isArray()) return fail(Result::BadGltf, "/nodes/%u/extensions/MSFT_lod/ids: expected an array", root);
        if (ids.size() + 1 > kMaxLevels)
            return fail(Result::BadGltf, "/nodes/%u/extensions/MSFT_lod/ids: %u ids; lodrt supports at most %u levels",
                        root, ids.size(), kMaxLevels);
        if (owner[root] != kNoIndex)
            return fail(Result::BadGltf, "/nodes/%u/extensions/MSFT_lod: node %u is already a level of node %u", root,
                        root, owner[root]);
        owner[root] = root;
        for (uint32_t k = 0; k < ids.size(); ++k) {
            uint64_t id = 0;
            if (!ids.at(k).asUint64(&id) || id >= node_count)
                return fail(Result::BadGltf, "/nodes/%u/extensions/MSFT_lod/ids/%u: expected a node index below %u",
                            root, k, node_count);
            const uint32_t j = uint32_t(id);
            if (j == root)
                return fail(Result::BadGltf, "/nodes/%u/extensions/MSFT_lod/ids/%u: cyclic: the node lists itself",
                            root, k);
            if (hasLod(pack->node(j))) {
                JsonValue inner = lodIds(pack->node(j));
                for (uint32_t q = 0; q < inner.size(); ++q) {
                    uint64_t back = 0;
                    if (inner.at(q).asUint64(&back) && back == root)
                        return fail(Result::BadGltf,
                                    "/nodes/%u/extensions/MSFT_lod/ids/%u: cyclic: node %u lists node %u back", root, k,
                                    j, root);
                }
                return fail(
                    Result::BadGltf,
                    "/nodes/%u/extensions/MSFT_lod/ids/%u: node %u has MSFT_lod too; expected a plain level node", root,
                    k, j);
            }
            if (owner[j] != kNoIndex)
                return fail(Result::BadGltf,
                            "/nodes/%u/extensions/MSFT_lod/ids/%u: node %u is already a level of node %u", root, k, j,
                            owner[j]);
            owner[j] = root;
        }
        return Result::Ok;
    }

    Result fillLevelGeometry(uint32_t model_index, uint32_t level_index, uint32_t node, LevelInfo* level,
                             ModelInfo* model) {
        const NodeInfo& n = pack->node(node);
        if (n.mesh == kNoIndex)
            return fail(Result::BadGltf, "/nodes/%u/mesh: missing; level %u of model %u needs a mesh", node,
                        level_index, model_index);
        level->node = node;
        level->mesh = n.mesh;
        for (int k = 0; k < 16; ++k) level->world_transform[k] = float(world[size_t(node) * 16 + k]);
        const MeshInfo& mesh = pack->mesh(n.mesh);
        uint64_t lo = UINT64_MAX, hi = 0;
        bool streamable = true;
        bool has_bounds = false;
        float bmin[3] = {kInf, kInf, kInf}, bmax[3] = {-kInf, -kInf, -kInf};
        for (uint32_t p = 0; p < mesh.primitive_count; ++p) {
            const PrimitiveInfo& prim = pack->primitive(mesh.first_primitive + p);
            level->triangle_count += prim.triangle_count;
            level->vertex_count += prim.vertex_count;
            // Accessors of this primitive: the index accessor, then every attribute.
            for (uint32_t a = 0; a <= prim.attribute_count; ++a) {
                uint32_t acc_index = kNoIndex;
                if (a == prim.attribute_count) {
                    acc_index = prim.indices;
                } else {
                    const AttributeInfo& attribute = pack->attribute(prim.first_attribute + a);
                    acc_index = attribute.accessor;
                    if (level_index == 0 && attribute.name == "POSITION") {
                        JsonValue json = pack->accessor(acc_index).json;
                        JsonValue mn = json.find("min"), mx = json.find("max");
                        if (mn.size() != 3 || mx.size() != 3)
                            return fail(Result::BadGltf, "/accessors/%u: POSITION needs min and max of 3 numbers",
                                        acc_index);
                        const AccessorInfo& position = pack->accessor(acc_index);
                        for (uint32_t c = 0; c < 3; ++c) {
                            const double lo_c = boundValue(mn.at(c).number(), position);
                            const double hi_c = boundValue(mx.at(c).number(), position);
                            if (!mn.at(c).isNumber() || !mx.at(c).isNumber() || !finiteFloat(lo_c) ||
                                !finiteFloat(hi_c) || lo_c > hi_c)
                                return fail(Result::BadGltf,
                                            "/accessors/%u/min: expected finite numbers with min <= max (component %u)",
                                            acc_index, c);
                            bmin[c] = std::fmin(bmin[c], float(lo_c));
                            bmax[c] = std::fmax(bmax[c], float(hi_c));
                        }
                        has_bounds = true;
                    }
                }
                if (acc_index == kNoIndex) continue;
                const AccessorInfo& acc = pack->accessor(acc_index);
                if (acc.buffer_view == kNoIndex) continue;
                const BufferViewInfo& view = pack->bufferView(acc.buffer_view);
                // A compressed view's bytes are its EXT_meshopt_compression range (lodrt/meshopt.h).
                MeshoptViewInfo compressed;
                const bool is_compressed = meshoptViewInfo(*pack, acc.buffer_view, &compressed) == Result::Ok;
                const uint32_t buffer = is_compressed ? compressed.buffer : view.buffer;
                const uint64_t first = is_compressed ? compressed.byte_offset : view.byte_offset;
                const uint64_t end = first + (is_compressed ? compressed.byte_length : view.byte_length);
                if (!pack->buffer(buffer).is_glb_bin || acc.is_sparse) {
                    streamable = false;
                    continue;
                }
                if (first < lo) lo = first;
                if (end > hi) hi = end;
            }
            addValenceStreamRange(*pack, prim, &lo, &hi);
        }
        if (streamable && hi > lo) {
            level->data_offset = lo;
            level->data_size = hi - lo;
        }
        if (level_index == 0) {
            if (!has_bounds)
                return fail(Result::BadGltf, "/meshes/%u: level 0 of model %u has no POSITION attribute", n.mesh,
                            model_index);
            double r2 = 0;
            for (int c = 0; c < 3; ++c) {
                model->aabb_min[c] = bmin[c];
                model->aabb_max[c] = bmax[c];
                model->sphere_center[c] = 0.5f * (bmin[c] + bmax[c]);
                const double half = 0.5 * (double(bmax[c]) - double(bmin[c]));
                r2 += half * half;
            }
            model->sphere_radius = float(std::sqrt(r2));
            std::memcpy(model->world_transform, level->world_transform, sizeof(model->world_transform));
            model->max_axis_scale = maxAxisScale(model->world_transform);
            transformSphere(model->world_transform, model->sphere_center, model->sphere_radius,
                            model->world_sphere_center, &model->world_sphere_radius);
        }
        return Result::Ok;
    }

    Result readMetric(JsonValue level, const char* path, uint32_t l, const char* key, double* out) {
        JsonValue v = level.find(key);
        if (!v.isNumber() || !finiteFloat(v.number()) || v.number() < 0)
            return fail(Result::BadGltf, "%s/levels/%u/%s: expected a finite number >= 0", path, l, key);
        *out = v.number();
        return Result::Ok;
    }

    // extras.MSFT_screencoverage: at least one number per level after the first, each in [0, 1] and
    // none above the one before. Checked whether or not measured metrics are present (a pack must
    // not hold two contradicting descriptions of its switches); used only without them.
    Result checkCoverage(uint32_t root, const ModelInfo& model, JsonValue coverage) {
        if (!coverage.isArray() || coverage.size() < model.level_count - 1)
            return fail(Result::BadGltf, "/nodes/%u/extras/MSFT_screencoverage: expected at least %u numbers", root,
                        model.level_count - 1);
        double prev = 1;
        for (uint32_t k = 0; k < coverage.size(); ++k) {
            const JsonValue v = coverage.at(k);
            const double c = v.number();
            if (!v.isNumber() || !(c >= 0 && c <= prev))
                return fail(Result::BadGltf,
                            "/nodes/%u/extras/MSFT_screencoverage/%u: expected a number in [0, 1] that does not "
                            "increase",
                            root, k);
            prev = c;
        }
        return Result::Ok;
    }

    // inputTriangles (an out-of-core chain that may start below the input): an integer at least
    // level 0's triangle count. Level 0 may then carry errors (a cut of the cluster hierarchy).
    Result readInputTriangles(const char* path, JsonValue metrics, ModelInfo* model, const LevelInfo* levels) {
        const JsonValue v = metrics.find(format::kLodMetricsInputTriangles);
        if (!v.isValid()) return Result::Ok;
        uint64_t n = 0;
        if (!v.asUint64(&n) || n < levels[0].triangle_count)
            return fail(Result::BadGltf, "%s/%s: expected an integer >= level 0's %llu triangles", path,
                        format::kLodMetricsInputTriangles, static_cast<unsigned long long>(levels[0].triangle_count));
        model->input_triangle_count = n;
        return Result::Ok;
    }

    Result fillMeasured(const char* path, JsonValue metrics, ModelInfo& model, LevelInfo* levels) {
        JsonValue array = metrics.find("levels");
        if (!array.isArray() || array.size() != model.level_count)
            return fail(Result::BadGltf, "%s/levels: expected %u entries (MSFT_lod ids + 1)", path, model.level_count);
        Result ir = readInputTriangles(path, metrics, &model, levels);
        if (ir != Result::Ok) return ir;
        const bool cut_level0 = model.input_triangle_count > 0;
        static const char* const kKeys[3] = {"hausdorffError", "meanError", "switchDistance"};
        double prev[3] = {0, 0, 0};
        for (uint32_t l = 0; l < model.level_count; ++l) {
            JsonValue entry = array.at(l);
            double v[3] = {0, 0, 0};
            for (int k = 0; k < 3; ++k) {
                Result r = readMetric(entry, path, l, kKeys[k], &v[k]);
                if (r != Result::Ok) return r;
            }
            JsonValue band = entry.find("hysteresisBand");
            if (band.size() != 2 || !band.at(0).isNumber() || !band.at(1).isNumber() ||
                !finiteFloat(band.at(0).number()) || !finiteFloat(band.at(1).number()))
                return fail(Result::BadGltf, "%s/levels/%u/hysteresisBand: expected two finite numbers", path, l);
            const double near_d = band.at(0).number(), far_d = band.at(1).number();
            // The entry must describe this level's mesh, not another one (a writer that shifted
            // its entries against the levels would pass every ordering rule).
            uint64_t triangles = 0;
            if (!entry.find("triangles").asUint64(&triangles))
                return fail(Result::BadGltf, "%s/levels/%u/triangles: expected an integer", path, l);
            if (triangles != levels[l].triangle_count)
                return fail(Result::BadGltf, "%s/levels/%u/triangles: %llu; the level's mesh has %llu", path, l,
                            static_cast<unsigned long long>(triangles),
                            static_cast<unsigned long long>(levels[l].triangle_count));
            if (l == 0 && !cut_level0 && (v[0] != 0 || v[1] != 0 || v[2] != 0))
                return fail(Result::BadGltf, "%s/levels/0: level 0 must have zero errors and switchDistance 0", path);
            if (l == 0 && cut_level0 && v[2] != 0)
                return fail(Result::BadGltf, "%s/levels/0: level 0 must have switchDistance 0 (with inputTriangles)",
                            path);
            for (int k = 0; k < 3; ++k)
                if (v[k] < prev[k])
                    return fail(Result::BadGltf, "%s/levels/%u/%s: level %u: decreases from level %u (%g after %g)",
                                path, l, kKeys[k], l, l - 1, v[k], prev[k]);
            if (!(near_d <= v[2] && v[2] <= far_d))
                return fail(Result::BadGltf, "%s/levels/%u/hysteresisBand: level %u: expected near <= %g <= far",
                            path, l, l, v[2]);
            for (int k = 0; k < 3; ++k) prev[k] = v[k];
            levels[l].hausdorff_error = float(v[0]);
            levels[l].mean_error = float(v[1]);
            levels[l].switch_distance = float(v[2]);
            levels[l].band_near = float(near_d);
            levels[l].band_far = float(far_d);
        }
        return Result::Ok;
    }

    Result fillMetrics(uint32_t root, ModelInfo* model, LevelInfo* levels) {
        const NodeInfo& node = pack->node(root);
        char path[96];
        std::snprintf(path, sizeof(path), "/nodes/%u/extensions/LODBAKE_lod_metrics", root);
        JsonValue metrics = node.json.find("extensions").find(format::kExtLodMetrics);
        JsonValue coverage = node.json.find("extras").find(format::kMsftScreenCoverage);
        if (coverage.isValid() && model->level_count > 1) {
            Result r = checkCoverage(root, *model, coverage);
            if (r != Result::Ok) return r;
        }
        if (metrics.isValid()) {
            Result r = fillMeasured(path, metrics, *model, levels);
            if (r != Result::Ok) return r;
            model->error_source = ErrorSource::Measured;
            return Result::Ok;
        }
        if (coverage.isValid() && model->level_count > 1) {
            for (uint32_t l = 1; l < model->level_count; ++l) {
                const double c = coverage.at(l - 1).number();
                // Level l takes over where the previous level's coverage ends.
                const double d = c > 0 ? double(model->sphere_radius) / (c * kReferenceTanHalfFov) : double(kInf);
                const double e = d * 2.0 * kReferenceTanHalfFov / kReferenceViewportPx;
                levels[l].switch_distance = finiteFloat(d) ? float(d) : kInf;
                levels[l].band_near = levels[l].band_far = levels[l].switch_distance;
                levels[l].hausdorff_error = finiteFloat(e) ? float(e) : kInf;
            }
            model->error_source = ErrorSource::ScreenCoverage;
            return Result::Ok;
        }
        for (uint32_t l = 1; l < model->level_count; ++l) {
            levels[l].hausdorff_error = kInf;
            levels[l].switch_distance = levels[l].band_near = levels[l].band_far = kInf;
        }
        model->error_source = model->level_count > 1 ? ErrorSource::Unknown : ErrorSource::Measured;
        return Result::Ok;
    }

    Result build(ModelSet* out) {
        out->release();
        out->allocator_ = allocator;
        Result r = run(out);
        detail::deallocateBytes(allocator, owner);
        owner = nullptr;
        detail::deallocateBytes(allocator, world);
        world = nullptr;
        if (r == Result::OutOfMemory && error && error_size > 0 && error[0] == '\0') fail(r, "out of memory");
        if (r != Result::Ok) out->release();
        return r;
    }

    Result run(ModelSet* out) {
        const uint32_t node_count = pack->nodeCount();
        if (node_count == 0) return Result::Ok;
        owner = detail::allocateArray<uint32_t>(allocator, node_count);
        if (!owner) return Result::OutOfMemory;
        for (uint32_t i = 0; i < node_count; ++i) owner[i] = kNoIndex;
        Result wr = computeWorldTransforms();
        if (wr != Result::Ok) return wr;
        for (uint32_t i = 0; i < node_count; ++i) {
            if (!hasLod(pack->node(i))) continue;
            Result r = claimChain(i);
            if (r != Result::Ok) return r;
        }
        uint32_t model_count = 0, level_count = 0;
        for (uint32_t i = 0; i < node_count; ++i) {
            const NodeInfo& node = pack->node(i);
            if (owner[i] == i) {
                ++model_count;
                level_count += lodIds(node).size() + 1;
            } else if (owner[i] == kNoIndex && node.mesh != kNoIndex) {
                ++model_count;
                ++level_count;
            }
        }
        if (model_count == 0) return Result::Ok;
        out->models_ = detail::allocateArray<ModelInfo>(allocator, model_count);
        out->levels_ = detail::allocateArray<LevelInfo>(allocator, level_count);
        if (!out->models_ || !out->levels_) return Result::OutOfMemory;
        for (uint32_t i = 0; i < model_count; ++i) out->models_[i] = ModelInfo();
        for (uint32_t i = 0; i < level_count; ++i) out->levels_[i] = LevelInfo();
        uint32_t m = 0, first = 0;
        for (uint32_t i = 0; i < node_count; ++i) {
            const NodeInfo& node = pack->node(i);
            const bool is_chain = owner[i] == i;
            if (!is_chain && !(owner[i] == kNoIndex && node.mesh != kNoIndex)) continue;
            ModelInfo& model = out->models_[m];
            model.name = node.name;
            model.root_node = i;
            model.first_level = first;
            model.level_count = is_chain ? lodIds(node).size() + 1 : 1;
            LevelInfo* levels = out->levels_ + first;
            for (uint32_t l = 0; l < model.level_count; ++l) {
                uint64_t id = i;
                if (l > 0) lodIds(node).at(l - 1).asUint64(&id); // validated in claimChain
                Result r = fillLevelGeometry(m, l, uint32_t(id), &levels[l], &model);
                if (r != Result::Ok) return r;
            }
            Result r = fillMetrics(i, &model, levels);
            if (r != Result::Ok) return r;
            first += model.level_count;
            ++m;
        }
        out->model_count_ = model_count;
        out->level_count_ = level_count;
        return Result::Ok;
    }
};

ModelSet::~ModelSet() {
    release();
}

ModelSet::ModelSet(ModelSet&& other) noexcept {
    *this = static_cast<ModelSet&&>(other);
}

ModelSet& ModelSet::operator=(ModelSet&& other) noexcept {
    if (this == &other) return *this;
    release();
    allocator_ = other.allocator_;
    models_ = other.models_;
    levels_ = other.levels_;
    model_count_ = other.model_count_;
    level_count_ = other.level_count_;
    other.models_ = nullptr;
    other.levels_ = nullptr;
    other.model_count_ = other.level_count_ = 0;
    return *this;
}

void ModelSet::release() {
    detail::deallocateBytes(allocator_, models_);
    detail::deallocateBytes(allocator_, levels_);
    models_ = nullptr;
    levels_ = nullptr;
    model_count_ = level_count_ = 0;
}

const ModelInfo& ModelSet::model(uint32_t i) const {
    assert(i < model_count_);
    return models_[i];
}

const LevelInfo& ModelSet::level(uint32_t i) const {
    assert(i < level_count_);
    return levels_[i];
}

const LevelInfo& ModelSet::modelLevel(uint32_t model_index, uint32_t level_index) const {
    assert(model_index < model_count_ && level_index < models_[model_index].level_count);
    return levels_[models_[model_index].first_level + level_index];
}

Result buildModels(const Pack& pack, const ModelOptions* options, ModelSet* out, char* error_message,
                   size_t error_message_size) {
    if (error_message && error_message_size > 0) error_message[0] = '\0';
    if (!out) return Result::InvalidArgument;
    ModelBuilder builder{};
    builder.pack = &pack;
    builder.allocator = options ? options->allocator : Allocator();
    builder.error = error_message;
    builder.error_size = error_message_size;
    return builder.build(out);
}

} // namespace lodrt
