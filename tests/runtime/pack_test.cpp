#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "glb_builder.h"
#include "lodrt/pack.h"

using lodrt::AccessorType;
using lodrt::ComponentType;
using lodrt::kNoIndex;
using lodrt::Pack;
using lodrt::Result;
using lodrt_test::makeGlb;
using lodrt_test::quadBin;
using lodrt_test::quadGlb;
using lodrt_test::quadJson;

namespace {

struct Loaded {
    Result result;
    std::string message;
};

Loaded load(const std::vector<uint8_t>& bytes, Pack* pack, const lodrt::LoadOptions* options = nullptr) {
    char message[512];
    std::memset(message, 'X', sizeof(message));
    Loaded out;
    out.result = lodrt::loadPack(bytes.data(), bytes.size(), options, pack, message, sizeof(message));
    out.message = message;
    return out;
}

Loaded loadJson(const std::string& json, const std::vector<uint8_t>& bin = quadBin()) {
    Pack pack;
    return load(makeGlb(json, bin), &pack);
}

// Replaces the first occurrence of `from` in the quad JSON; the test fails if it is absent.
std::string quadWith(const std::string& from, const std::string& to) {
    std::string json = quadJson();
    const size_t at = json.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) json.replace(at, from.size(), to);
    return json;
}

// What loadPack promises about a pack it accepts, checked independently of its code: every index
// in range, every byte range inside the bytes that exist, counts that agree. Returns the first broken
// promise, or "" when all hold. It reads every name, accessor range and index value, so ASan also
// sees any dangling span.
std::string packViolation(const Pack& pack) {
    const auto where = [](const char* kind, uint32_t i) { return std::string(kind) + " " + std::to_string(i) + ": "; };
    for (uint32_t b = 0; b < pack.bufferCount(); ++b)
        if (pack.buffer(b).is_glb_bin && pack.buffer(b).byte_length > pack.container().bin_size)
            return where("buffer", b) + "longer than the BIN chunk";
    for (uint32_t v = 0; v < pack.bufferViewCount(); ++v) {
        const lodrt::BufferViewInfo& view = pack.bufferView(v);
        if (view.buffer >= pack.bufferCount()) return where("bufferView", v) + "buffer out of range";
        if (view.byte_length == 0 || view.byte_offset + view.byte_length > pack.buffer(view.buffer).byte_length)
            return where("bufferView", v) + "bytes outside its buffer";
        if (view.byte_stride != 0 && (view.byte_stride < 4 || view.byte_stride > 252 || view.byte_stride % 4 != 0))
            return where("bufferView", v) + "bad byteStride";
    }
    for (uint32_t a = 0; a < pack.accessorCount(); ++a) {
        const lodrt::AccessorInfo& accessor = pack.accessor(a);
        if (accessor.byte_length != accessor.count * accessor.element_size)
            return where("accessor", a) + "byte_length is not count x element size";
        if (accessor.buffer_view == kNoIndex || accessor.count == 0) continue;
        if (accessor.buffer_view >= pack.bufferViewCount()) return where("accessor", a) + "bufferView out of range";
        const lodrt::BufferViewInfo& view = pack.bufferView(accessor.buffer_view);
        const uint64_t stride = view.byte_stride ? view.byte_stride : accessor.element_size;
        if (accessor.byte_offset + stride * (accessor.count - 1) + accessor.element_size > view.byte_length)
            return where("accessor", a) + "elements outside its bufferView";
    }
    for (uint32_t m = 0; m < pack.meshCount(); ++m) {
        const lodrt::MeshInfo& mesh = pack.mesh(m);
        const std::string name(mesh.name);
        if (uint64_t(mesh.first_primitive) + mesh.primitive_count > pack.primitiveCount())
            return where("mesh", m) + "primitives out of range";
    }
    for (uint32_t p = 0; p < pack.primitiveCount(); ++p) {
        const lodrt::PrimitiveInfo& prim = pack.primitive(p);
        if (prim.attribute_count == 0 || uint64_t(prim.first_attribute) + prim.attribute_count > pack.attributeCount())
            return where("primitive", p) + "attributes out of range";
        for (uint32_t k = 0; k < prim.attribute_count; ++k) {
            const lodrt::AttributeInfo& attribute = pack.attribute(prim.first_attribute + k);
            const std::string name(attribute.name);
            if (attribute.accessor >= pack.accessorCount()) return where("primitive", p) + name + " out of range";
            if (pack.accessor(attribute.accessor).count != prim.vertex_count)
                return where("primitive", p) + name + " count differs from vertex_count";
        }
        if (prim.material != kNoIndex && prim.material >= pack.materialCount())
            return where("primitive", p) + "material out of range";
        if (prim.mode > 6) return where("primitive", p) + "mode above 6";
        uint64_t index_count = prim.vertex_count;
        if (prim.indices != kNoIndex) {
            if (prim.indices >= pack.accessorCount()) return where("primitive", p) + "indices out of range";
            const lodrt::AccessorInfo& indices = pack.accessor(prim.indices);
            index_count = indices.count;
            const uint32_t size = lodrt::componentSize(indices.component_type);
            if (indices.type != AccessorType::Scalar || (size != 1 && size != 2 && size != 4) ||
                indices.component_type == ComponentType::Float || indices.normalized)
                return where("primitive", p) + "indices not SCALAR u8/u16/u32";
            const bool in_bin = indices.buffer_view != kNoIndex && !indices.is_sparse &&
                                pack.buffer(pack.bufferView(indices.buffer_view).buffer).is_glb_bin;
            if (in_bin) {
                const lodrt::BufferViewInfo& view = pack.bufferView(indices.buffer_view);
                const uint64_t stride = view.byte_stride ? view.byte_stride : size;
                const uint8_t* base = pack.container().bin + view.byte_offset + indices.byte_offset;
                for (uint64_t i = 0; i < indices.count; ++i) {
                    uint32_t value = 0;
                    std::memcpy(&value, base + i * stride, size); // little-endian host
                    if (value >= prim.vertex_count)
                        return where("primitive", p) + "index " + std::to_string(value) + " out of range";
                }
            }
        }
        if (prim.index_count != index_count) return where("primitive", p) + "index_count";
        const uint64_t triangles = prim.mode == 4                     ? index_count / 3
                                   : prim.mode == 5 || prim.mode == 6 ? (index_count >= 3 ? index_count - 2 : 0)
                                                                      : 0;
        if ((prim.mode == 4 && index_count % 3 != 0) || prim.triangle_count != triangles)
            return where("primitive", p) + "triangle_count does not follow from the mode and index count";
    }
    for (uint32_t n = 0; n < pack.nodeCount(); ++n) {
        const lodrt::NodeInfo& node = pack.node(n);
        const std::string name(node.name);
        if ((node.mesh != kNoIndex && node.mesh >= pack.meshCount()) ||
            (node.parent != kNoIndex && node.parent >= pack.nodeCount()))
            return where("node", n) + "mesh or parent out of range";
    }
    if (pack.warningCount() > lodrt::kMaxPackWarnings) return "more warnings than kMaxPackWarnings";
    for (uint32_t w = 0; w < pack.warningCount(); ++w)
        if (!pack.warning(w).pointer || !pack.warning(w).message || !*pack.warning(w).message ||
            std::strlen(pack.warning(w).pointer) > 4096)
            return where("warning", w) + "without a pointer or message";
    return std::string();
}

struct CountingHeap {
    long live = 0;
    long total = 0;
    long fail_at = 0;
    static void* allocate(void* user, size_t size) {
        auto* heap = static_cast<CountingHeap*>(user);
        ++heap->total;
        if (heap->fail_at && heap->total == heap->fail_at) return nullptr;
        ++heap->live;
        return std::malloc(size);
    }
    static void deallocate(void* user, void* ptr) {
        --static_cast<CountingHeap*>(user)->live;
        std::free(ptr);
    }
};

} // namespace

TEST(PackTest, SummarisesQuad) {
    const std::vector<uint8_t> bytes = quadGlb();
    Pack pack;
    const Loaded loaded = load(bytes, &pack);
    ASSERT_EQ(loaded.result, Result::Ok) << loaded.message;
    EXPECT_EQ(loaded.message, "");
    EXPECT_TRUE(pack.container().is_binary);
    ASSERT_EQ(pack.bufferCount(), 1u);
    EXPECT_TRUE(pack.buffer(0).is_glb_bin);
    EXPECT_EQ(pack.buffer(0).byte_length, 108u);
    ASSERT_EQ(pack.bufferViewCount(), 2u);
    EXPECT_EQ(pack.bufferView(0).byte_stride, 12u);
    ASSERT_EQ(pack.accessorCount(), 3u);
    EXPECT_EQ(pack.accessor(0).type, AccessorType::Vec3);
    EXPECT_EQ(pack.accessor(0).component_type, ComponentType::Float);
    EXPECT_EQ(pack.accessor(0).byte_length, 48u);
    EXPECT_EQ(pack.accessor(2).component_type, ComponentType::UnsignedShort);
    EXPECT_EQ(pack.accessor(2).byte_length, 12u);
    ASSERT_EQ(pack.meshCount(), 1u);
    EXPECT_EQ(pack.mesh(0).name, "Quad");
    ASSERT_EQ(pack.mesh(0).primitive_count, 1u);
    const lodrt::PrimitiveInfo& prim = pack.primitive(pack.mesh(0).first_primitive);
    EXPECT_EQ(prim.mode, 4u);
    EXPECT_EQ(prim.vertex_count, 4u);
    EXPECT_EQ(prim.index_count, 6u);
    EXPECT_EQ(prim.triangle_count, 2u);
    EXPECT_EQ(prim.indices, 2u);
    EXPECT_EQ(prim.material, 0u);
    ASSERT_EQ(prim.attribute_count, 2u);
    EXPECT_EQ(pack.attribute(prim.first_attribute).name, "POSITION");
    EXPECT_EQ(pack.attribute(prim.first_attribute + 1).name, "NORMAL");
    EXPECT_EQ(pack.attribute(prim.first_attribute + 1).accessor, 1u);
    EXPECT_EQ(pack.materialCount(), 1u);
    ASSERT_EQ(pack.nodeCount(), 2u);
    EXPECT_EQ(pack.node(1).mesh, 0u);
    EXPECT_EQ(pack.node(1).parent, 0u);
    EXPECT_EQ(pack.node(0).parent, kNoIndex);
    EXPECT_EQ(pack.warningCount(), 0u);
}

TEST(PackTest, KeepsExtensionsJsonReachable) {
    Pack pack;
    ASSERT_EQ(load(quadGlb(), &pack).result, Result::Ok);
    const lodrt::JsonValue ext = pack.primitive(0).json.find("extensions").find("LODBAKE_test");
    ASSERT_TRUE(ext.isObject());
    EXPECT_EQ(ext.find("level").number(), 3.0);
    EXPECT_EQ(pack.accessor(0).json.find("max").at(1).number(), 1.0);
    // Moving the pack keeps every JsonValue valid (the document has its own allocation).
    Pack moved(static_cast<Pack&&>(pack));
    EXPECT_EQ(pack.meshCount(), 0u);
    EXPECT_FALSE(pack.document().root().isValid());
    EXPECT_EQ(moved.primitive(0).json.find("extensions").find("LODBAKE_test").find("level").number(), 3.0);
    EXPECT_EQ(moved.mesh(0).name, "Quad");
}

TEST(PackTest, LoadsPlainGltfWithUriBufferAndWarns) {
    std::string json = quadWith(R"("buffers":[{"byteLength":108}])", R"("buffers":[{"byteLength":108,"uri":"q.bin"}])");
    Pack pack;
    const Loaded loaded = load(std::vector<uint8_t>(json.begin(), json.end()), &pack);
    ASSERT_EQ(loaded.result, Result::Ok) << loaded.message;
    EXPECT_FALSE(pack.container().is_binary);
    EXPECT_TRUE(pack.buffer(0).has_uri);
    EXPECT_FALSE(pack.buffer(0).is_glb_bin);
    ASSERT_EQ(pack.warningCount(), 1u);
    EXPECT_STREQ(pack.warning(0).pointer, "/buffers/0");
    EXPECT_EQ(pack.primitive(0).triangle_count, 2u);
}

TEST(PackTest, WarnsAboutRequiredExtensionsAndNonTriangles) {
    std::string json = quadWith(R"("indices":2,)", R"("mode":1,)");
    json.insert(json.size() - 1, R"(,"extensionsRequired":["KHR_draco_mesh_compression"])");
    Pack pack;
    const Loaded loaded = load(makeGlb(json, quadBin()), &pack);
    ASSERT_EQ(loaded.result, Result::Ok) << loaded.message;
    ASSERT_EQ(pack.warningCount(), 2u);
    EXPECT_STREQ(pack.warning(0).pointer, "/extensionsRequired/0");
    EXPECT_NE(std::strstr(pack.warning(0).message, "KHR_draco_mesh_compression"), nullptr);
    EXPECT_STREQ(pack.warning(1).pointer, "/meshes/0/primitives/0/mode");
    EXPECT_EQ(pack.primitive(0).triangle_count, 0u);
    EXPECT_EQ(pack.primitive(0).index_count, 4u);
}

TEST(PackTest, CapsWarnings) {
    std::string names;
    for (int i = 0; i < 100; ++i) names += (i ? ",\"EXT_" : "\"EXT_") + std::to_string(i) + "\"";
    std::string json = quadJson(",\"extensionsRequired\":[" + names + "]");
    Pack pack;
    ASSERT_EQ(load(makeGlb(json, quadBin()), &pack).result, Result::Ok);
    ASSERT_EQ(pack.warningCount(), lodrt::kMaxPackWarnings);
    EXPECT_NE(std::strstr(pack.warning(lodrt::kMaxPackWarnings - 1).message, "and 36 more warnings"), nullptr);
}

TEST(PackTest, ErrorsNameTheJsonPointer) {
    struct Case {
        std::string from, to;
        Result result;
        const char* prefix;
    };
    const Case cases[] = {
        {R"("count":6,)", R"("count":60,)", Result::OutOfBounds, "/accessors/2/count: 60 elements"},
        {R"("count":4,"type":"VEC3","min")", R"("count":9,"type":"VEC3","min")", Result::OutOfBounds,
         "/accessors/0/count: 9 elements of 12 bytes (stride 12) from byte 0 need 108 bytes but bufferView 0 has 96"},
        {R"("count":6,)", R"("count":-6,)", Result::BadGltf, "/accessors/2/count: expected a non-negative integer"},
        {R"("count":6,)", R"("count":6.5,)", Result::BadGltf, "/accessors/2/count"},
        {R"("count":6,)", R"("count":"6",)", Result::BadGltf, "/accessors/2/count"},
        {R"("count":6,)", R"("count":0,)", Result::BadGltf, "/accessors/2/count: expected at least 1"},
        {R"("count":6,)", R"("count":9007199254740992,)", Result::OutOfBounds, "/accessors/2/count"},
        {R"("count":6,)", R"("count":1e300,)", Result::BadGltf, "/accessors/2/count"},
        {R"("count":6,)", R"("count":7,)", Result::OutOfBounds, "/accessors/2/count"},
        {R"("componentType":5123)", R"("componentType":5124)", Result::BadGltf, "/accessors/2/componentType"},
        {R"("type":"SCALAR")", R"("type":"VEC5")", Result::BadGltf, "/accessors/2/type"},
        {R"("bufferView":1,)", R"("bufferView":2,)", Result::BadGltf, "/accessors/2/bufferView: index 2 out of range"},
        {R"("byteOffset":48,)", R"("byteOffset":50,)", Result::BadGltf, "/accessors/1/byteOffset"},
        {R"("byteOffset":96,"byteLength":12)", R"("byteOffset":100,"byteLength":12)", Result::OutOfBounds,
         "/bufferViews/1: bytes [100, 112) exceed buffer 0"},
        {R"("byteStride":12)", R"("byteStride":13)", Result::BadGltf, "/bufferViews/0/byteStride"},
        {R"("byteStride":12)", R"("byteStride":8)", Result::BadGltf, "/accessors/0: elements of 12 bytes"},
        {R"("byteLength":108})", R"("byteLength":200})", Result::OutOfBounds, "/buffers/0/byteLength"},
        {R"("buffer":0,"byteOffset":96)", R"("buffer":3,"byteOffset":96)", Result::BadGltf, "/bufferViews/1/buffer"},
        {R"("version":"2.0")", R"("version":"1.0")", Result::UnsupportedVersion, "/asset/version"},
        {R"("asset":{"version":"2.0","generator":"lodrt tests"},)", "", Result::BadGltf, "/asset"},
        {R"("POSITION":0,)", R"("POSITION":9,)", Result::BadGltf, "/meshes/0/primitives/0/attributes/POSITION"},
        {R"("NORMAL":1})", R"("NORMAL":2})", Result::BadGltf,
         "/meshes/0/primitives/0/attributes/NORMAL: count 6 differs from POSITION count 4"},
        {R"("attributes":{"POSITION":0,"NORMAL":1})", R"("attributes":{})", Result::BadGltf,
         "/meshes/0/primitives/0/attributes"},
        {R"("indices":2,)", R"("indices":0,)", Result::BadGltf, "/meshes/0/primitives/0/indices"},
        {R"("material":0,)", R"("material":1,)", Result::BadGltf, "/meshes/0/primitives/0/material"},
        {R"("primitives":[{)", R"("primitives":[],"x":[{)", Result::BadGltf, "/meshes/0/primitives"},
        {R"("mesh":0)", R"("mesh":1)", Result::BadGltf, "/nodes/1/mesh"},
        {R"("children":[1])", R"("children":[0])", Result::BadGltf, "/nodes/0/children/0: a node cannot be"},
        {R"("children":[1])", R"("children":[1,1])", Result::BadGltf,
         "/nodes/0/children/1: node 1 already has parent 0"},
        {R"("name":"quad","mesh":0)", R"("name":"quad","mesh":0,"children":[0])", Result::BadGltf,
         "/nodes/1/children: node hierarchy contains a cycle"},
        {R"("accessors":[)", R"("accessors":{},"x":[)", Result::BadGltf, "/accessors: expected an array"},
        {R"("asset")", R"("asset":1,"y")", Result::BadGltf, "/asset"},
        {R"("NORMAL":1)", R"("NOR/MAL~":1)", Result::Ok, ""},
    };
    for (const Case& c : cases) {
        const Loaded loaded = loadJson(quadWith(c.from, c.to));
        EXPECT_EQ(loaded.result, c.result) << c.to << " -> " << loaded.message;
        EXPECT_EQ(loaded.message.compare(0, std::strlen(c.prefix), c.prefix), 0) << c.to << " -> " << loaded.message;
    }
}

TEST(PackTest, EscapesAttributeNamesInPointers) {
    const Loaded loaded = loadJson(quadWith(R"("NORMAL":1})", R"("N/OR~M":2})"));
    EXPECT_EQ(loaded.result, Result::BadGltf);
    EXPECT_EQ(loaded.message.rfind("/meshes/0/primitives/0/attributes/N~1OR~0M:", 0), 0u) << loaded.message;
}

TEST(PackTest, RejectsIndexValuesOutOfRange) {
    std::vector<uint8_t> bin = quadBin();
    bin[96 + 2 * 4] = 4; // fifth index: 2 -> 4, with 4 vertices
    Pack pack;
    const Loaded loaded = load(makeGlb(quadJson(), bin), &pack);
    EXPECT_EQ(loaded.result, Result::OutOfBounds);
    EXPECT_EQ(loaded.message, "/meshes/0/primitives/0/indices: index 4 at position 4 out of range (4 vertices)");
    lodrt::LoadOptions options;
    options.skip_index_check = true;
    const std::vector<uint8_t> bad = makeGlb(quadJson(), bin); // the pack points into these bytes
    EXPECT_EQ(load(bad, &pack, &options).result, Result::Ok);
    // The mutation tests' oracle sees what the skipped check would have: it is able to fail.
    EXPECT_EQ(packViolation(pack), "primitive 0: index 4 out of range");
    const std::vector<uint8_t> good = quadGlb();
    ASSERT_EQ(lodrt::loadPack(good.data(), good.size(), nullptr, &pack), Result::Ok);
    EXPECT_EQ(packViolation(pack), "");
}

TEST(PackTest, RejectsNodeCycles) {
    const Loaded loaded = loadJson(quadWith(R"("nodes":[{"name":"root","children":[1]},{"name":"quad","mesh":0}])",
                                            R"("nodes":[{"children":[1]},{"children":[2]},{"children":[1]}])"));
    EXPECT_EQ(loaded.result, Result::BadGltf) << loaded.message;
    const Loaded cycle = loadJson(quadWith(R"("nodes":[{"name":"root","children":[1]},{"name":"quad","mesh":0}])",
                                           R"("nodes":[{"children":[1]},{"children":[2]},{"children":[0]}])"));
    EXPECT_EQ(cycle.result, Result::BadGltf);
    EXPECT_NE(cycle.message.find("cycle"), std::string::npos) << cycle.message;
}

TEST(PackTest, RejectsBinSizeMismatch) {
    std::vector<uint8_t> bin = quadBin();
    bin.resize(bin.size() + 8, 0); // more than the 3 bytes of padding the spec allows
    EXPECT_EQ(loadJson(quadJson(), bin).result, Result::OutOfBounds);
    // A buffer without uri needs the GLB BIN chunk.
    const std::string json = quadJson();
    Pack pack;
    const Loaded loaded = load(std::vector<uint8_t>(json.begin(), json.end()), &pack);
    EXPECT_EQ(loaded.result, Result::BadGltf);
    EXPECT_EQ(loaded.message.rfind("/buffers/0: no uri", 0), 0u) << loaded.message;
}

TEST(PackTest, TruncatesLongErrorMessages) {
    const std::vector<uint8_t> bytes = makeGlb(quadWith(R"("count":6,)", R"("count":60,)"), quadBin());
    char small[12];
    std::memset(small, 'X', sizeof(small));
    Pack pack;
    EXPECT_EQ(lodrt::loadPack(bytes.data(), bytes.size(), nullptr, &pack, small, sizeof(small)), Result::OutOfBounds);
    EXPECT_STREQ(small, "/accessors/");
    EXPECT_EQ(lodrt::loadPack(bytes.data(), bytes.size(), nullptr, &pack, nullptr, 0), Result::OutOfBounds);
}

TEST(PackTest, EveryTruncatedPrefixFailsCleanly) {
    const std::vector<uint8_t> glb = quadGlb();
    for (size_t size = 0; size < glb.size(); ++size) {
        std::vector<uint8_t> prefix(glb.begin(), glb.begin() + size);
        Pack pack;
        char message[256];
        const Result result =
            lodrt::loadPack(size ? prefix.data() : nullptr, size, nullptr, &pack, message, sizeof(message));
        EXPECT_EQ(result, Result::Truncated) << size;
        EXPECT_EQ(pack.meshCount(), 0u);
        EXPECT_EQ(std::strncmp(message, "container: ", 11), 0) << message;
    }
    // Every prefix of the plain JSON form fails too (it is no longer one complete JSON value).
    const std::string json =
        quadWith(R"("buffers":[{"byteLength":108}])", R"("buffers":[{"byteLength":108,"uri":"a"}])");
    for (size_t size = 1; size < json.size(); ++size) {
        std::vector<uint8_t> prefix(json.begin(), json.begin() + size);
        Pack pack;
        EXPECT_NE(load(prefix, &pack).result, Result::Ok) << size;
    }
}

TEST(PackTest, RejectsTrailingBytesBadMagicAndVersion) {
    std::vector<uint8_t> glb = quadGlb();
    Pack pack;
    std::vector<uint8_t> trailing = glb;
    trailing.push_back(0);
    EXPECT_EQ(load(trailing, &pack).result, Result::TrailingBytes);
    std::vector<uint8_t> magic = glb;
    magic[0] = 'G';
    EXPECT_EQ(load(magic, &pack).result, Result::BadMagic);
    std::vector<uint8_t> version = glb;
    version[4] = 1;
    const Loaded loaded = load(version, &pack);
    EXPECT_EQ(loaded.result, Result::UnsupportedVersion);
    EXPECT_EQ(loaded.message, "container: GLB container version is not 2");
    std::vector<uint8_t> bad_json = makeGlb("{\"asset\":", quadBin());
    EXPECT_EQ(load(bad_json, &pack).result, Result::BadJson);
}

TEST(PackTest, RandomCorruptionNeverCrashes) {
    const std::vector<uint8_t> glb = quadGlb();
    std::mt19937 rng(20261122u);
    int ok = 0, failed = 0;
    for (int iteration = 0; iteration < 4000; ++iteration) {
        std::vector<uint8_t> bytes = glb;
        const int flips = 1 + int(rng() % 4);
        for (int f = 0; f < flips; ++f) {
            const size_t at = rng() % bytes.size();
            switch (rng() % 4) {
            case 0:
                bytes[at] = uint8_t(rng());
                break; // random byte
            case 1:
                bytes[at] ^= uint8_t(1u << (rng() % 8));
                break; // bit flip
            case 2:
                bytes[at] = uint8_t("0123456789{}[]\",:"[rng() % 17]);
                break; // JSON-ish byte
            default:
                bytes[at] = uint8_t(bytes[at] + 1);
                break;
            }
        }
        Pack pack;
        char message[256];
        const Result result = lodrt::loadPack(bytes.data(), bytes.size(), nullptr, &pack, message, sizeof(message));
        if (result == Result::Ok) {
            ++ok;
            EXPECT_EQ(packViolation(pack), "") << iteration;
        } else {
            ++failed;
            EXPECT_GT(std::strlen(message), 0u) << iteration;
            EXPECT_EQ(pack.meshCount(), 0u);
        }
    }
    // Both outcomes must occur, or the mutations are not exercising the loader.
    EXPECT_GT(ok, 0);
    EXPECT_GT(failed, 1000);
}

TEST(PackTest, StructuredJsonMutationsNeverCrash) {
    // Edits that keep the container valid and often the JSON too, so the glTF checks get exercised:
    // digit changes, insertions, deletions, copied spans, BIN byte changes.
    std::mt19937 rng(7u);
    int counts[16] = {};
    for (int iteration = 0; iteration < 3000; ++iteration) {
        std::string json = quadJson();
        std::vector<uint8_t> bin = quadBin();
        const int edits = 1 + int(rng() % 3);
        for (int e = 0; e < edits; ++e) {
            const size_t at = rng() % json.size();
            const char digit = char('0' + rng() % 10);
            switch (rng() % 5) {
            case 0: json[at] = digit; break;
            case 1: json.insert(at, 1, digit); break;
            case 2: json.erase(at, 1); break;
            case 3: json.insert(at, json.substr(rng() % json.size(), rng() % 20)); break;
            default: bin[rng() % bin.size()] = uint8_t(rng()); break;
            }
        }
        Pack pack;
        const std::vector<uint8_t> glb = makeGlb(json, bin); // the pack points into these bytes
        const Loaded loaded = load(glb, &pack);
        ++counts[int(loaded.result) & 15];
        if (loaded.result == Result::Ok) {
            EXPECT_EQ(packViolation(pack), "") << iteration;
        } else {
            EXPECT_FALSE(loaded.message.empty());
        }
    }
    EXPECT_GT(counts[int(Result::Ok)], 100);
    EXPECT_GT(counts[int(Result::BadJson)], 100);
    EXPECT_GT(counts[int(Result::BadGltf)], 100);
    EXPECT_GT(counts[int(Result::OutOfBounds)], 10);
}

TEST(PackTest, AllocationFailureAtEveryStepIsCleanOutOfMemory) {
    const std::vector<uint8_t> glb = quadGlb();
    CountingHeap probe;
    lodrt::LoadOptions options;
    options.allocator.allocate = &CountingHeap::allocate;
    options.allocator.deallocate = &CountingHeap::deallocate;
    options.allocator.user = &probe;
    {
        Pack pack;
        ASSERT_EQ(load(glb, &pack, &options).result, Result::Ok);
        EXPECT_GT(probe.live, 0);
    }
    EXPECT_EQ(probe.live, 0);
    for (long fail_at = 1; fail_at <= probe.total; ++fail_at) {
        CountingHeap heap;
        heap.fail_at = fail_at;
        options.allocator.user = &heap;
        Pack pack;
        const Loaded loaded = load(glb, &pack, &options);
        EXPECT_EQ(loaded.result, Result::OutOfMemory) << fail_at;
        EXPECT_EQ(heap.live, 0) << fail_at;
        EXPECT_NE(loaded.message.find("out of memory"), std::string::npos) << loaded.message;
    }
}
