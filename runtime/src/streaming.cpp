// Pack sources (bytes or range reads) and the level streamer (see lodrt/streaming.h).

#include "lodrt/streaming.h"

#include <algorithm>
#include <cmath>
#include <cassert>
#include <cstdio>
#include <cstring>
#include <new>
#include <thread>

#include "lodrt/detail/pfrep_region.h"
#include "lodrt/format.h"
#include "little_endian.h"
#include "memory.h"

namespace lodrt {

namespace {

void setError(char* error, size_t error_size, const char* text) {
    if (error && error_size > 0) std::snprintf(error, error_size, "%s", text);
}

// Checks the index values of every primitive of `mesh` whose index accessor lies in the level bytes.
Result checkLevelIndices(const Pack& pack, const LevelInfo& level, const uint8_t* bytes) {
    const MeshInfo& mesh = pack.mesh(level.mesh);
    for (uint32_t p = 0; p < mesh.primitive_count; ++p) {
        const PrimitiveInfo& prim = pack.primitive(mesh.first_primitive + p);
        if (prim.indices == kNoIndex) continue;
        const AccessorInfo& acc = pack.accessor(prim.indices);
        if (acc.buffer_view == kNoIndex || acc.is_sparse) continue;
        const BufferViewInfo& view = pack.bufferView(acc.buffer_view);
        // Compressed indices (EXT_meshopt_compression) are checked when decoded (readAccessorIndices).
        if (!pack.buffer(view.buffer).is_glb_bin) continue;
        const uint32_t size = componentSize(acc.component_type);
        const uint64_t stride = view.byte_stride ? view.byte_stride : size;
        // The level range covers the view (model.cpp); the Pack checked the accessor fits the view.
        const uint8_t* base = bytes + (view.byte_offset - level.data_offset) + acc.byte_offset;
        const uint64_t vertex_count = prim.vertex_count;
        for (uint64_t k = 0; k < acc.count; ++k) {
            const uint8_t* q = base + k * stride;
            uint32_t value = q[0];
            if (size >= 2) value |= uint32_t(q[1]) << 8;
            if (size == 4) value |= (uint32_t(q[2]) << 16) | (uint32_t(q[3]) << 24);
            if (value >= vertex_count) return Result::OutOfBounds;
        }
    }
    return Result::Ok;
}

} // namespace

// ---- PackSource ----

PackSource::~PackSource() {
    release();
}

PackSource::PackSource(PackSource&& other) noexcept {
    *this = static_cast<PackSource&&>(other);
}

PackSource& PackSource::operator=(PackSource&& other) noexcept {
    if (this == &other) return *this;
    release();
    pack_ = static_cast<Pack&&>(other.pack_);
    models_ = static_cast<ModelSet&&>(other.models_);
    allocator_ = other.allocator_;
    bin_ = other.bin_;
    reader_ = other.reader_;
    bin_offset_ = other.bin_offset_;
    json_ = other.json_;
    other.json_ = nullptr;
    other.bin_ = nullptr;
    other.reader_ = RangeReader();
    return *this;
}

void PackSource::release() {
    models_ = ModelSet();
    pack_ = Pack();
    detail::deallocateBytes(allocator_, json_);
    json_ = nullptr;
    bin_ = nullptr;
    reader_ = RangeReader();
    bin_offset_ = 0;
}

Result PackSource::openBytes(const uint8_t* data, size_t size, const LoadOptions* options, char* error,
                             size_t error_size) {
    release();
    LoadOptions opts = options ? *options : LoadOptions();
    opts.skip_index_check = true;
    allocator_ = opts.allocator;
    Result r = loadPack(data, size, &opts, &pack_, error, error_size);
    if (r != Result::Ok) return r;
    ModelOptions model_options;
    model_options.allocator = allocator_;
    r = buildModels(pack_, &model_options, &models_, error, error_size);
    if (r != Result::Ok) {
        release();
        return r;
    }
    bin_ = pack_.container().bin;
    return Result::Ok;
}

Result PackSource::openReader(const RangeReader& reader, uint64_t file_size, const LoadOptions* options, char* error,
                              size_t error_size) {
    release();
    if (!reader.read) return Result::InvalidArgument;
    const LoadOptions opts = options ? *options : LoadOptions();
    allocator_ = opts.allocator;
    uint8_t header[format::kGlbHeaderSize + format::kGlbChunkHeaderSize];
    if (file_size < sizeof(header)) {
        setError(error, error_size, "container: truncated: shorter than a GLB header and its first chunk header");
        return Result::Truncated;
    }
    Result r = reader.read(reader.user, 0, header, sizeof(header));
    if (r != Result::Ok) {
        setError(error, error_size, "container: the range reader failed on the GLB header");
        return r;
    }
    if (detail::loadU32(header) != format::kGlbMagic) {
        setError(error, error_size, "container: expected the GLB magic \"glTF\"");
        return Result::BadMagic;
    }
    if (detail::loadU32(header + 4) != format::kGlbVersion) {
        setError(error, error_size, "container: GLB container version is not 2");
        return Result::UnsupportedVersion;
    }
    const uint64_t length = detail::loadU32(header + 8);
    if (length != file_size) {
        setError(error, error_size, "container: the GLB header's length differs from the file size");
        return length > file_size ? Result::Truncated : Result::TrailingBytes;
    }
    const uint64_t json_size = detail::loadU32(header + 12);
    if (detail::loadU32(header + 16) != format::kGlbChunkJson || json_size == 0 || json_size % 4 != 0) {
        setError(error, error_size, "container: expected a non-empty JSON chunk first, 4-byte aligned");
        return Result::BadChunk;
    }
    const uint64_t json_end = sizeof(header) + json_size;
    if (json_end > file_size) {
        setError(error, error_size, "container: truncated: the JSON chunk runs past the end of the file");
        return Result::Truncated;
    }
    uint64_t bin_size = 0, bin_offset = 0;
    if (json_end < file_size) {
        uint8_t chunk[format::kGlbChunkHeaderSize];
        if (json_end + sizeof(chunk) > file_size) {
            setError(error, error_size, "container: truncated: a chunk header runs past the end of the file");
            return Result::Truncated;
        }
        r = reader.read(reader.user, json_end, chunk, sizeof(chunk));
        if (r != Result::Ok) {
            setError(error, error_size, "container: the range reader failed on the BIN chunk header");
            return r;
        }
        const uint64_t chunk_size = detail::loadU32(chunk);
        if (chunk_size % 4 != 0 || json_end + sizeof(chunk) + chunk_size > file_size) {
            setError(error, error_size, "container: chunk length not a multiple of 4 or past the end of the file");
            return chunk_size % 4 != 0 ? Result::BadChunk : Result::Truncated;
        }
        if (detail::loadU32(chunk + 4) == format::kGlbChunkJson) {
            setError(error, error_size, "container: a second JSON chunk");
            return Result::BadChunk;
        }
        if (detail::loadU32(chunk + 4) == format::kGlbChunkBin) {
            if (chunk_size == 0) {
                setError(error, error_size, "container: empty BIN chunk");
                return Result::BadChunk;
            }
            bin_size = chunk_size;
            bin_offset = json_end + sizeof(chunk);
        }
    }
    json_ = detail::allocateArray<uint8_t>(allocator_, size_t(json_size));
    if (!json_) return Result::OutOfMemory;
    r = reader.read(reader.user, sizeof(header), json_, size_t(json_size));
    if (r != Result::Ok) {
        setError(error, error_size, "container: the range reader failed on the JSON chunk");
        release();
        return r;
    }
    r = loadPackJson(json_, size_t(json_size), bin_size, &opts, &pack_, error, error_size);
    if (r == Result::Ok) {
        ModelOptions model_options;
        model_options.allocator = allocator_;
        r = buildModels(pack_, &model_options, &models_, error, error_size);
    }
    if (r != Result::Ok) {
        release();
        return r;
    }
    reader_ = reader;
    bin_offset_ = bin_offset;
    return Result::Ok;
}

Result PackSource::readLevel(uint32_t model, uint32_t level, uint8_t* dst, size_t capacity) const {
    if (model >= models_.modelCount() || level >= models_.model(model).level_count) return Result::InvalidArgument;
    const LevelInfo& info = models_.modelLevel(model, level);
    if (info.data_size == 0) return Result::BadGltf;
    if (!dst || capacity < info.data_size) return Result::BufferTooSmall;
    if (bin_) {
        std::memcpy(dst, bin_ + info.data_offset, size_t(info.data_size));
    } else if (reader_.read) {
        Result r = reader_.read(reader_.user, bin_offset_ + info.data_offset, dst, size_t(info.data_size));
        if (r != Result::Ok) return r;
    } else {
        return Result::InvalidArgument;
    }
    return checkLevelIndices(pack_, info, dst);
}

namespace {

// The LODBAKE_progressive_fans object of model m (on its level 0 mesh), or an invalid value.
JsonValue pfrepExtension(const Pack& pack, const ModelSet& models, uint32_t m) {
    const LevelInfo& level0 = models.level(models.model(m).first_level);
    if (level0.mesh == kNoIndex || level0.mesh >= pack.meshCount()) return JsonValue();
    return pack.mesh(level0.mesh).json.find("extensions").find(format::kExtProgressiveFans);
}

// Format 4: LOD0's one primitive's valence stream, inside level 0's bytes (docs/format/pfrep.md "In a
// glTF pack"). False when LOD0 has another layout (the stream then fails).
bool findLod0Stream(const Pack& pack, const ModelSet& models, uint32_t m, uint64_t* offset, uint64_t* size,
                    uint32_t* slot) {
    const LevelInfo& level0 = models.level(models.model(m).first_level);
    if (level0.mesh == kNoIndex || level0.mesh >= pack.meshCount() || level0.data_size == 0) return false;
    const MeshInfo& mesh = pack.mesh(level0.mesh);
    if (mesh.primitive_count != 1) return false;
    const JsonValue ext =
        pack.primitive(mesh.first_primitive).json.find("extensions").find(format::kExtValenceCompression);
    uint64_t view = 0;
    if (!ext.find("bufferView").asUint64(&view) || view >= pack.bufferViewCount()) return false;
    const BufferViewInfo& v = pack.bufferView(uint32_t(view));
    if (!pack.buffer(v.buffer).is_glb_bin || v.byte_offset < level0.data_offset ||
        v.byte_offset + v.byte_length > level0.data_offset + level0.data_size || v.byte_length == 0)
        return false;
    *offset = v.byte_offset - level0.data_offset;
    *size = v.byte_length;
    *slot = models.model(m).first_level;
    return true;
}

} // namespace

namespace {

size_t alignUp8(uint64_t n) {
    return size_t((n + 7) & ~uint64_t(7));
}

// Format 5: the one allocation a Streamer keeps for a region blob, offsets in order: the format 2
// buffer (from 0), the region state, the claimed bits (one per vertex) and three per-block arrays
// (priority, LevelState, needed); `total` bytes in all.
struct RegionStreamLayout {
    uint64_t state, claimed, priority, block_state, needed, total;
};

RegionStreamLayout regionStreamLayout(const PfrepRegionInfo& info) {
    RegionStreamLayout l;
    l.state = alignUp8(info.decoded_bytes);
    l.claimed = l.state + alignUp8(info.state_bytes);
    l.priority = l.claimed + alignUp8((uint64_t(info.vertex_count) + 7) / 8);
    l.block_state = l.priority + alignUp8(uint64_t(info.block_count) * sizeof(float));
    l.needed = l.block_state + alignUp8(info.block_count);
    l.total = l.needed + alignUp8(uint64_t(info.block_count) * sizeof(uint32_t));
    return l;
}

} // namespace

Result PackSource::pfrepDecodeMemory(uint32_t model, uint64_t* decoded_bytes, uint64_t* scratch_bytes) const {
    if (model >= models_.modelCount() || !decoded_bytes || !scratch_bytes) return Result::InvalidArgument;
    *decoded_bytes = 0;
    *scratch_bytes = 0;
    const JsonValue ext = pfrepExtension(pack_, models_, model);
    uint64_t view = 0, blob_format = 0;
    if (!ext.isObject() || !ext.find(format::kPfrepExtensionFormatMember).asUint64(&blob_format) ||
        (blob_format != format::kPfrepVersionCompressed && blob_format != format::kPfrepVersionLod0 &&
         blob_format != format::kPfrepFormatRegions))
        return Result::Ok;
    if (!ext.find("bufferView").asUint64(&view) || view >= pack_.bufferViewCount()) return Result::BadStructure;
    uint8_t header[format::kPfrepHeaderSize];
    Result r = readBufferView(uint32_t(view), 0, header, sizeof(header));
    if (r != Result::Ok) return r;
    if (blob_format == format::kPfrepFormatRegions) {
        PfrepRegionInfo info;
        r = pfrepRegionInfo(header, sizeof(header), &info);
        if (r != Result::Ok) return r;
        *decoded_bytes = regionStreamLayout(info).total;
        *scratch_bytes = info.open_bytes;
        return Result::Ok;
    }
    if (blob_format == format::kPfrepVersionLod0)
        return format4DecodeMemory(model, header, decoded_bytes, scratch_bytes);
    PfrepCompressedInfo info;
    r = pfrepCompressedInfo(header, sizeof(header), &info);
    if (r != Result::Ok) return r;
    *decoded_bytes = info.decoded_bytes;
    *scratch_bytes = info.scratch_bytes;
    return Result::Ok;
}

// Format 4: the scratch depends on LOD0's stream too, which is read once (a transient buffer).
Result PackSource::format4DecodeMemory(uint32_t model, const uint8_t* header, uint64_t* decoded_bytes,
                                       uint64_t* scratch_bytes) const {
    uint64_t offset = 0, size = 0;
    uint32_t slot = 0;
    if (!findLod0Stream(pack_, models_, model, &offset, &size, &slot) || size > SIZE_MAX) return Result::BadStructure;
    const LevelInfo& level0 = models_.modelLevel(model, 0);
    uint8_t* stream = static_cast<uint8_t*>(detail::allocateBytes(allocator_, size_t(size)));
    if (!stream) return Result::OutOfMemory;
    Result r = Result::Ok;
    if (bin_)
        std::memcpy(stream, bin_ + level0.data_offset + offset, size_t(size));
    else if (reader_.read)
        r = reader_.read(reader_.user, bin_offset_ + level0.data_offset + offset, stream, size_t(size));
    else
        r = Result::InvalidArgument;
    PfrepPackFormat4Info info;
    if (r == Result::Ok) r = pfrepPackFormat4Info(header, format::kPfrepHeaderSize, stream, size_t(size), &info);
    detail::deallocateBytes(allocator_, stream);
    if (r != Result::Ok) return r;
    *decoded_bytes = info.decoded_bytes;
    *scratch_bytes = info.scratch_bytes;
    return Result::Ok;
}

Result PackSource::readBufferView(uint32_t view, uint64_t offset, uint8_t* dst, size_t size) const {
    if (view >= pack_.bufferViewCount() || (!dst && size > 0)) return Result::InvalidArgument;
    const BufferViewInfo& info = pack_.bufferView(view);
    if (!pack_.buffer(info.buffer).is_glb_bin) return Result::BadGltf;
    if (offset > info.byte_length || size > info.byte_length - offset) return Result::OutOfBounds;
    if (size == 0) return Result::Ok;
    if (bin_) {
        std::memcpy(dst, bin_ + info.byte_offset + offset, size);
        return Result::Ok;
    }
    if (reader_.read) return reader_.read(reader_.user, bin_offset_ + info.byte_offset + offset, dst, size);
    return Result::InvalidArgument;
}

const uint8_t* PackSource::accessorData(uint32_t model, uint32_t level, const uint8_t* level_bytes,
                                        uint32_t accessor) const {
    if (!level_bytes || model >= models_.modelCount() || level >= models_.model(model).level_count ||
        accessor >= pack_.accessorCount())
        return nullptr;
    const LevelInfo& info = models_.modelLevel(model, level);
    const AccessorInfo& acc = pack_.accessor(accessor);
    if (acc.buffer_view == kNoIndex) return nullptr;
    const BufferViewInfo& view = pack_.bufferView(acc.buffer_view);
    if (!pack_.buffer(view.buffer).is_glb_bin || view.byte_offset < info.data_offset ||
        view.byte_offset + view.byte_length > info.data_offset + info.data_size)
        return nullptr;
    return level_bytes + (view.byte_offset - info.data_offset) + acc.byte_offset;
}

uint64_t PackSource::levelIndexCount(uint32_t model, uint32_t level) const {
    if (model >= models_.modelCount() || level >= models_.model(model).level_count) return 0;
    const MeshInfo& mesh = pack_.mesh(models_.modelLevel(model, level).mesh);
    uint64_t count = 0;
    for (uint32_t p = 0; p < mesh.primitive_count; ++p) {
        const PrimitiveInfo& prim = pack_.primitive(mesh.first_primitive + p);
        if (prim.mode == 4) count += prim.index_count;
    }
    return count;
}

Result PackSource::copyLevelIndices(uint32_t model, uint32_t level, const uint8_t* level_bytes, uint32_t* out,
                                    size_t capacity, size_t* written) const {
    if (written) *written = 0;
    if (!level_bytes || model >= models_.modelCount() || level >= models_.model(model).level_count)
        return Result::InvalidArgument;
    const uint64_t needed = levelIndexCount(model, level);
    if (!out || capacity < needed) return Result::BufferTooSmall;
    const MeshInfo& mesh = pack_.mesh(models_.modelLevel(model, level).mesh);
    size_t n = 0;
    for (uint32_t p = 0; p < mesh.primitive_count; ++p) {
        const PrimitiveInfo& prim = pack_.primitive(mesh.first_primitive + p);
        if (prim.mode != 4) continue;
        if (prim.indices == kNoIndex) {
            for (uint64_t k = 0; k < prim.index_count; ++k) out[n++] = uint32_t(k);
            continue;
        }
        const AccessorInfo& acc = pack_.accessor(prim.indices);
        const uint8_t* base = accessorData(model, level, level_bytes, prim.indices);
        if (!base) return Result::InvalidArgument; // not in the level's range (sparse or external)
        const uint32_t size = componentSize(acc.component_type);
        const uint32_t stride = pack_.bufferView(acc.buffer_view).byte_stride;
        const uint64_t step = stride ? stride : size;
        for (uint64_t k = 0; k < acc.count; ++k) {
            const uint8_t* q = base + k * step;
            uint32_t value = q[0];
            if (size >= 2) value |= uint32_t(q[1]) << 8;
            if (size == 4) value |= (uint32_t(q[2]) << 16) | (uint32_t(q[3]) << 24);
            out[n++] = value;
        }
    }
    if (written) *written = n;
    return Result::Ok;
}

// ---- Streamer ----

struct Streamer::Task {
    enum class Kind : uint8_t {
        Level,
        PfrepHeader,
        PfrepStep,
        PfrepWhole,
        PfrepRegionOpen,
        PfrepRegionBlocks,
        ClusterRead,
        ClusterDecode
    };
    const PackSource* source = nullptr;
    Kind kind = Kind::Level;
    uint32_t model = 0, level = 0;
    uint8_t* dst = nullptr;
    size_t size = 0;
    uint32_t slot = 0; // level slot, or the model of a PFRep task
    // PFRep step: buffer view, the prefix held so far (copied into dst first) and its validated model.
    uint32_t view = 0;
    const uint8_t* old_data = nullptr;
    size_t old_size = 0;
    bool has_prefix = false;
    PfrepModel pfrep; // in: the model of old_data (has_prefix); out: the model of dst
    // PFRep format 3 (PfrepWhole): the coded blob and the decoder's scratch (one buffer, freed in
    // collect), the stream's chain levels, and out: every step's prefix bytes and model in dst.
    uint8_t* coded = nullptr;
    size_t coded_size = 0, scratch_bytes = 0;
    const uint32_t* removals = nullptr;
    uint32_t step_count = 0;
    size_t lod0_size = 0; // format 4: LOD0's valence stream, copied after the scratch in `coded`
    uint64_t step_bytes[kMaxLevels + 1] = {};
    PfrepModel steps[kMaxLevels + 1];
    // Cluster page (ClusterRead, then ClusterDecode): the page's coded bytes are read into `coded`
    // (coded_size bytes); the decode writes positions and then indices into dst (vertex_count * 3
    // floats, triangle_count * 3 indices) with `scratch` (scratch_bytes).
    const ClusterLodPack* cluster_pack = nullptr;
    uint32_t page = 0, vertex_count = 0, triangle_count = 0;
    void* scratch = nullptr;
    // PFRep format 5: the opening reads open_bytes (coded_size) into `coded` and opens them into the
    // stream's format 2 buffer (region_decoded, size) and state (region_state, scratch_bytes),
    // giving `regions`; a block request reads its blocks back to back into `coded` and stages each
    // against the stream's `regions_in`, leaving `staged` and `block_results` for the commit.
    uint8_t* region_decoded = nullptr;
    uint8_t* region_state = nullptr;
    PfrepRegions regions;
    const PfrepRegions* regions_in = nullptr;
    uint8_t* claimed = nullptr;
    uint32_t blocks[kMaxPfrepBlocksPerRequest] = {};
    uint32_t block_count = 0;
    detail::PfrepRegionStaged staged[kMaxPfrepBlocksPerRequest];
    Result block_results[kMaxPfrepBlocksPerRequest] = {};
    bool is_busy = false; // frame-thread view
    Result result = Result::Ok;
    std::atomic<uint32_t> done{0};

    static Result runPfrepStep(Task& t) {
        if (t.old_size > 0) std::memcpy(t.dst, t.old_data, t.old_size);
        Result r = t.source->readBufferView(t.view, t.old_size, t.dst + t.old_size, t.size - t.old_size);
        if (r != Result::Ok) return r;
        if (!t.has_prefix) return openPfrepPrefix(t.dst, t.size, &t.pfrep);
        return pfrepExtendPrefix(&t.pfrep, t.dst, t.size); // leaves t.pfrep unchanged on error
    }

    // Format 3: the whole coded blob in one read, decoded into dst (the format 2 bytes), then the
    // prefix of each step of the decoded blob, as a format 2 stream's steps would be.
    static Result runPfrepWhole(Task& t) {
        Result r = t.source->readBufferView(t.view, 0, t.coded, t.coded_size);
        if (r != Result::Ok) return r;
        uint8_t* scratch = t.coded + ((t.coded_size + 7) & ~size_t(7));
        if (t.lod0_size > 0)
            r = pfrepDecodePackFormat4(t.coded, t.coded_size, scratch + t.scratch_bytes, t.lod0_size, t.dst, t.size,
                                       scratch, t.scratch_bytes, &t.pfrep);
        else
            r = pfrepDecompress(t.coded, t.coded_size, t.dst, t.size, scratch, t.scratch_bytes, &t.pfrep);
        if (r != Result::Ok) return r;
        if (t.pfrep.blob_size != t.size) return Result::BadStructure;
        const uint64_t directory = pfrepDirectoryBytes(t.dst, t.size);
        if (directory == 0) return Result::BadStructure;
        const uint32_t top = t.step_count - 1;
        t.step_bytes[0] = directory;
        for (uint32_t p = 1; p <= top; ++p) {
            const uint32_t removals = t.removals[top - p];
            if (removals > t.pfrep.removed_count) return Result::BadStructure;
            const uint64_t bytes = pfrepPrefixBytesForLevel(t.pfrep, removals);
            t.step_bytes[p] = bytes > t.step_bytes[p - 1] ? bytes : t.step_bytes[p - 1];
            if (t.step_bytes[p] > t.size) return Result::BadStructure;
        }
        for (uint32_t p = 0; p < top; ++p) {
            r = openPfrepPrefix(t.dst, size_t(t.step_bytes[p]), &t.steps[p]);
            if (r != Result::Ok) return r;
        }
        t.steps[top] = t.pfrep;
        return Result::Ok;
    }

    static Result runRegionOpen(Task& t) {
        const Result r = t.source->readBufferView(t.view, 0, t.coded, t.coded_size);
        if (r != Result::Ok) return r;
        return pfrepRegionOpen(t.coded, t.coded_size, t.region_decoded, t.size, t.region_state, t.scratch_bytes,
                               &t.regions);
    }

    // Each block's read and stage has its own result: a bad block fails alone.
    static Result runRegionBlocks(Task& t) {
        uint8_t* at = t.coded;
        for (uint32_t i = 0; i < t.block_count; ++i) {
            const PfrepRegionBlock& b = t.regions_in->blocks[t.blocks[i]];
            Result r = t.source->readBufferView(t.view, b.offset, at, b.size);
            if (r == Result::Ok)
                r = detail::pfrepRegionStageBlock(*t.regions_in, t.blocks[i], at, b.size, t.claimed, &t.staged[i]);
            t.block_results[i] = r;
            at += b.size;
        }
        return Result::Ok;
    }

    static void run(void* task) {
        Task* t = static_cast<Task*>(task);
        switch (t->kind) {
        case Kind::Level:
            t->result = t->source->readLevel(t->model, t->level, t->dst, t->size);
            break;
        case Kind::PfrepHeader:
            t->result = t->source->readBufferView(t->view, 0, t->dst, t->size);
            break;
        case Kind::PfrepStep:
            t->result = runPfrepStep(*t);
            break;
        case Kind::PfrepWhole:
            t->result = runPfrepWhole(*t);
            break;
        case Kind::PfrepRegionOpen:
            t->result = runRegionOpen(*t);
            break;
        case Kind::PfrepRegionBlocks:
            t->result = runRegionBlocks(*t);
            break;
        case Kind::ClusterRead:
            t->result = t->source->readBufferView(t->view, t->cluster_pack->pages[t->page].byte_offset, t->coded,
                                                  t->coded_size);
            break;
        case Kind::ClusterDecode: {
            float* positions = reinterpret_cast<float*>(t->dst);
            uint32_t* indices = reinterpret_cast<uint32_t*>(t->dst + size_t(t->vertex_count) * 3 * sizeof(float));
            t->result = clusterPageDecode(*t->cluster_pack, t->page, t->coded, t->coded_size, positions,
                                          size_t(t->vertex_count) * 3, indices, size_t(t->triangle_count) * 3,
                                          t->scratch, t->scratch_bytes);
            break;
        }
        }
        t->done.store(1, std::memory_order_release);
    }
};

Streamer::~Streamer() {
    release();
}

void Streamer::release() {
    // Jobs write into level buffers: they must finish before anything is freed.
    for (uint32_t i = 0; i < task_count_; ++i)
        while (tasks_[i].is_busy && tasks_[i].done.load(std::memory_order_acquire) == 0) std::this_thread::yield();
    const Allocator& a = options_.allocator;
    for (uint32_t i = 0; i < slot_count_; ++i) detail::deallocateBytes(a, slots_[i].data);
    // A finished but uncollected PFRep step owns its new buffer.
    for (uint32_t i = 0; i < task_count_; ++i)
        if (tasks_[i].is_busy && tasks_[i].kind != Task::Kind::Level && tasks_[i].kind != Task::Kind::PfrepHeader) {
            detail::deallocateBytes(a, tasks_[i].dst);
            detail::deallocateBytes(a, tasks_[i].coded);
            detail::deallocateBytes(a, tasks_[i].scratch);
        }
    for (uint32_t i = 0; i < page_count_; ++i) detail::deallocateBytes(a, pages_[i].data);
    for (uint32_t i = 0; clusters_ && i < pfrep_count_; ++i) detail::deallocateBytes(a, clusters_[i].memory);
    detail::deallocateBytes(a, clusters_);
    detail::deallocateBytes(a, pages_);
    clusters_ = nullptr;
    pages_ = nullptr;
    page_count_ = 0;
    cluster_frame_ = 1;
    for (uint32_t i = 0; i < pfrep_count_; ++i) detail::deallocateBytes(a, pfrep_[i].data);
    for (uint32_t i = 0; i < task_count_; ++i) tasks_[i].~Task();
    detail::deallocateBytes(a, tasks_);
    detail::deallocateBytes(a, slots_);
    detail::deallocateBytes(a, slot_model_);
    detail::deallocateBytes(a, candidates_);
    detail::deallocateBytes(a, resident_table_);
    detail::deallocateBytes(a, pfrep_);
    tasks_ = nullptr;
    slots_ = nullptr;
    slot_model_ = nullptr;
    candidates_ = nullptr;
    resident_table_ = nullptr;
    pfrep_ = nullptr;
    task_count_ = slot_count_ = busy_tasks_ = pfrep_count_ = 0;
    stats_ = StreamStats();
}

Result Streamer::init(const PackSource* source, const JobSystem* jobs, const StreamerOptions* options) {
    release();
    if (!source) return Result::InvalidArgument;
    source_ = source;
    jobs_ = jobs ? *jobs : JobSystem();
    options_ = options ? *options : StreamerOptions();
    if (options_.max_in_flight == 0) options_.max_in_flight = 4;
    const Allocator& a = options_.allocator;
    const ModelSet& models = source->models();
    slot_count_ = models.levelCount();
    const size_t model_count = models.modelCount();
    slots_ = detail::allocateArray<Slot>(a, slot_count_);
    slot_model_ = detail::allocateArray<uint32_t>(a, slot_count_);
    candidates_ = detail::allocateArray<uint32_t>(a, slot_count_ + model_count);
    resident_table_ = detail::allocateArray<uint8_t>(a, model_count * kMaxLevels);
    pfrep_ = detail::allocateArray<PfrepStream>(a, model_count);
    void* task_memory = detail::allocateBytes(a, sizeof(Task) * options_.max_in_flight);
    if (!slots_ || !slot_model_ || !candidates_ || !resident_table_ || !pfrep_ || !task_memory) {
        detail::deallocateBytes(a, task_memory);
        slot_count_ = 0;
        release();
        return Result::OutOfMemory;
    }
    tasks_ = static_cast<Task*>(task_memory);
    task_count_ = options_.max_in_flight;
    for (uint32_t i = 0; i < task_count_; ++i) new (&tasks_[i]) Task();
    for (uint32_t m = 0; m < model_count; ++m) {
        const ModelInfo& model = models.model(m);
        for (uint32_t l = 0; l < model.level_count; ++l) {
            Slot& s = slots_[model.first_level + l];
            s = Slot{nullptr,
                     models.level(model.first_level + l).data_size,
                     0,
                     0,
                     LevelState::Absent,
                     uint8_t(l + 1 == model.level_count)};
            slot_model_[model.first_level + l] = m;
        }
    }
    pfrep_count_ = uint32_t(model_count);
    for (uint32_t m = 0; m < pfrep_count_; ++m) initPfrepStream(m);
    if (!initClusters()) {
        release();
        return Result::OutOfMemory;
    }
    rebuildResidentTable();
    return Result::Ok;
}

void Streamer::initPfrepStream(uint32_t m) {
    PfrepStream& ps = *new (&pfrep_[m]) PfrepStream();
    ps.data = nullptr;
    ps.step = -1;
    ps.state = PfrepStreamState::None;
    const ModelSet& models = source_->models();
    const Pack& pack = source_->pack();
    const ModelInfo& info = models.model(m);
    const JsonValue ext = pfrepExtension(pack, models, m);
    if (!ext.isObject()) return;
    ps.state = PfrepStreamState::Absent;
    ps.step_count = info.level_count + 1;
    ps.format = uint8_t(format::kPfrepVersion);
    ps.scratch_bytes = 0;
    ps.lod0_offset = 0;
    ps.lod0_size = 0;
    ps.lod0_slot = 0;
    ps.is_open = 0;
    ps.batch_count = 0;
    ps.batch_bytes = 0;
    // The extension object is as hostile as the blob: a bad one fails the stream, not the model.
    uint64_t view = 0;
    bool is_ok = ext.find("bufferView").asUint64(&view) && view < pack.bufferViewCount();
    const JsonValue format_member = ext.find(format::kPfrepExtensionFormatMember);
    if (format_member.isValid()) {
        uint64_t f = 0;
        is_ok = is_ok && format_member.asUint64(&f) && format::isPfrepPackFormat(f);
        ps.format = uint8_t(f);
    }
    is_ok = is_ok && (ps.format != format::kPfrepVersionLod0 ||
                      findLod0Stream(pack, models, m, &ps.lod0_offset, &ps.lod0_size, &ps.lod0_slot));
    const JsonValue levels = ext.find("levels");
    is_ok = is_ok && levels.isArray() && levels.size() >= info.level_count;
    for (uint32_t l = 0; is_ok && l < info.level_count; ++l) {
        uint64_t removals = 0;
        is_ok = levels.at(l).find("removals").asUint64(&removals) && removals <= 0xffffffffu;
        ps.removals[l] = uint32_t(removals);
    }
    if (is_ok) {
        const BufferViewInfo& info_view = pack.bufferView(uint32_t(view));
        ps.view = uint32_t(view);
        ps.view_size = info_view.byte_length;
        is_ok = pack.buffer(info_view.buffer).is_glb_bin && ps.view_size >= format::kPfrepHeaderSize;
    }
    if (!is_ok) {
        ps.state = PfrepStreamState::Failed;
        ps.is_failed = 1;
        ++stats_.failures;
    }
}

void Streamer::rebuildResidentTable() {
    const ModelSet& models = source_->models();
    for (uint32_t m = 0; m < models.modelCount(); ++m) {
        const ModelInfo& model = models.model(m);
        uint8_t* row = resident_table_ + size_t(m) * kMaxLevels;
        uint8_t best = kNoLevel;
        for (uint32_t l = kMaxLevels; l-- > 0;) {
            if (l < model.level_count && slots_[model.first_level + l].state == LevelState::Resident) best = uint8_t(l);
            row[l] = l < model.level_count ? best : kNoLevel;
        }
    }
}

LevelState Streamer::state(uint32_t model, uint32_t level) const {
    const ModelSet& models = source_->models();
    if (model >= models.modelCount() || level >= models.model(model).level_count) return LevelState::Absent;
    return slots_[models.model(model).first_level + level].state;
}

const uint8_t* Streamer::levelData(uint32_t model, uint32_t level, size_t* size) const {
    const ModelSet& models = source_->models();
    if (model >= models.modelCount() || level >= models.model(model).level_count) return nullptr;
    const Slot& s = slots_[models.model(model).first_level + level];
    if (s.state != LevelState::Resident) return nullptr;
    if (size) *size = size_t(s.size);
    return s.data;
}

const PfrepModel* Streamer::pfrepModel(uint32_t model) const {
    if (model >= pfrep_count_ || pfrep_[model].step < 0) return nullptr;
    if (pfrep_[model].format == format::kPfrepFormatRegions) return &pfrep_[model].regions.model;
    return &pfrep_[model].steps[pfrep_[model].step];
}

const PfrepRegions* Streamer::pfrepRegions(uint32_t model) const {
    if (model >= pfrep_count_ || pfrep_[model].format != format::kPfrepFormatRegions || !pfrep_[model].is_open)
        return nullptr;
    return &pfrep_[model].regions;
}

PfrepStreamState Streamer::pfrepState(uint32_t model) const {
    return model < pfrep_count_ ? pfrep_[model].state : PfrepStreamState::None;
}

uint8_t Streamer::pfrepLevel(uint32_t model) const {
    if (model < pfrep_count_ && pfrep_[model].format == format::kPfrepFormatRegions && pfrep_[model].step == 0) {
        // Level k extracts once k >= loaded_from: the finest chain level whose removals reach it.
        const PfrepStream& ps = pfrep_[model];
        for (uint32_t l = 0; l + 1 < ps.step_count; ++l)
            if (ps.removals[l] >= ps.regions.model.loaded_from) return uint8_t(l);
        return kNoLevel;
    }
    if (model >= pfrep_count_ || pfrep_[model].step <= 0) return kNoLevel;
    return uint8_t(pfrep_[model].step_count - 1 - uint32_t(pfrep_[model].step));
}

namespace {

void pointStepsAt(PfrepModel* steps, int32_t top, const uint8_t* data) {
    for (int32_t p = 0; p <= top; ++p) steps[p].data = data;
}

} // namespace

// Format 3: the header gives the decoded size (the bytes the stream holds once resident, its
// "directory" request: the decoded blob's directory exists only once all of it is decoded) and the
// decoder's scratch.
Result Streamer::readCompressedHeader(PfrepStream& ps) {
    PfrepCompressedInfo info;
    Result r = Result::Ok;
    if (ps.format == format::kPfrepVersionLod0) {
        // Format 4: the scratch also depends on LOD0's stream; it is sized when the decode starts.
        PfrepFormat4Info info4;
        r = pfrepFormat4Info(ps.header, format::kPfrepHeaderSize, &info4);
        info.decoded_bytes = info4.decoded_bytes;
        info.scratch_bytes = 0;
    } else {
        r = pfrepCompressedInfo(ps.header, format::kPfrepHeaderSize, &info);
    }
    if (r != Result::Ok) return r;
    // Every vertex has a 10-byte record and a 2-byte offset in the decoded blob and every slot at
    // least one bit, so the vertex and slot counts (and the scratch they size) are bounded by it.
    const uint32_t vertices = detail::loadU32(ps.header + 8), slots = detail::loadU32(ps.header + 56);
    if (info.decoded_bytes < format::kPfrepHeaderSize || ps.view_size <= format::kPfrepHeaderSize ||
        info.decoded_bytes > ps.view_size * format::kPfrepMaxExpansion ||
        uint64_t(vertices) * (format::kPfrepVertexRecordSize + 2) > info.decoded_bytes ||
        uint64_t(slots) > uint64_t(info.decoded_bytes) * 8)
        return Result::BadStructure;
    ps.directory_bytes = info.decoded_bytes;
    ps.scratch_bytes = info.scratch_bytes;
    return Result::Ok;
}

// A format 3 stream decoded whole: every step is resident at once (replacing a shorter prefix held
// after a shrink); budget accounting counts the decoded bytes.
void Streamer::collectPfrepWhole(Task& t, Result& r) {
    const Allocator& a = options_.allocator;
    PfrepStream& ps = pfrep_[t.slot];
    stats_.in_flight_bytes -= t.size;
    detail::deallocateBytes(a, t.coded);
    t.coded = nullptr;
    if (r != Result::Ok) {
        detail::deallocateBytes(a, t.dst);
        return;
    }
    const uint64_t held = ps.step >= 0 ? ps.step_bytes[ps.step] : 0;
    detail::deallocateBytes(a, ps.data);
    stats_.streamed_bytes += t.coded_size;
    stats_.resident_bytes += t.size - held;
    stats_.pfrep_resident_bytes += t.size - held;
    ps.data = t.dst;
    ps.step = int32_t(ps.step_count - 1);
    for (uint32_t p = 0; p < ps.step_count; ++p) {
        ps.step_bytes[p] = t.step_bytes[p];
        ps.steps[p] = t.steps[p];
        ps.steps[p].criterion_table = nullptr;
    }
    pointStepsAt(ps.steps, ps.step, ps.data);
}

// Format 5: the header gives the opening's read and the one allocation the stream keeps (the format
// 2 buffer, the region state, the claimed bits and three per-block arrays), bounded by the blob's
// size before anything is allocated.
Result Streamer::readRegionHeader(PfrepStream& ps) {
    PfrepRegionInfo info;
    const Result r = pfrepRegionInfo(ps.header, format::kPfrepHeaderSize, &info);
    if (r != Result::Ok) return r;
    if (info.blob_size != ps.view_size || info.open_bytes > ps.view_size ||
        uint64_t(info.decoded_bytes) > ps.view_size * format::kPfrepMaxExpansion)
        return Result::BadStructure;
    ps.open_bytes = info.open_bytes;
    ps.block_count = info.block_count;
    ps.directory_bytes = regionStreamLayout(info).total;
    return Result::Ok;
}

// The opening arrived: the stream keeps its allocation and the directory; the root block is next.
void Streamer::collectRegionOpen(Task& t, Result& r) {
    PfrepStream& ps = pfrep_[t.slot];
    // The allocation was sized from the header read first: a source that served another header
    // with the opening fails the stream (nothing beyond the buffers' capacities was written).
    if (r == Result::Ok && std::memcmp(t.coded, ps.header, format::kPfrepRegionHeaderSize) != 0)
        r = Result::BadStructure;
    stats_.in_flight_bytes -= ps.directory_bytes + t.coded_size;
    detail::deallocateBytes(options_.allocator, t.coded);
    t.coded = nullptr;
    if (r != Result::Ok) {
        detail::deallocateBytes(options_.allocator, ps.data);
        ps.data = nullptr;
        return;
    }
    stats_.streamed_bytes += t.coded_size;
    stats_.resident_bytes += ps.directory_bytes;
    stats_.pfrep_resident_bytes += ps.directory_bytes;
    ps.regions = t.regions;
    ps.is_open = 1;
}

// Blocks staged on the job are made resident here, in order; a block that failed to read, stage or
// commit is never read again, and the stream fails only with its root block.
void Streamer::collectRegionBlocks(Task& t, Result& r) {
    PfrepStream& ps = pfrep_[t.slot];
    stats_.in_flight_bytes -= t.coded_size;
    stats_.streamed_bytes += t.coded_size;
    const uint8_t* bytes = t.coded;
    for (uint32_t i = 0; i < t.block_count; ++i) {
        const uint32_t block = t.blocks[i];
        Result b = r == Result::Ok ? t.block_results[i] : r;
        if (b == Result::Ok) {
            b = detail::pfrepRegionCommitBlock(&ps.regions, block, bytes, t.staged[i]);
            detail::pfrepRegionUnclaim(ps.regions, block, ps.claimed);
        }
        bytes += ps.regions.blocks[block].size;
        if (b == Result::Ok) {
            ps.block_state[block] = uint8_t(LevelState::Resident);
            ++stats_.pfrep_blocks_loaded;
            if (block == 0) ps.step = 0;
        } else if (block == 0) {
            r = b;
        } else {
            ps.block_state[block] = uint8_t(LevelState::Failed);
            ++stats_.failures;
        }
    }
    detail::deallocateBytes(options_.allocator, t.coded);
    t.coded = nullptr;
    if (r != Result::Ok) {
        // Without its root the stream never serves a model: its allocation goes now.
        stats_.resident_bytes -= ps.directory_bytes;
        stats_.pfrep_resident_bytes -= ps.directory_bytes;
        detail::deallocateBytes(options_.allocator, ps.data);
        ps.data = nullptr;
        ps.is_open = 0;
    }
}

// Format 5's usefulness: the opening and the root block are pinned; then the blocks this frame's
// views want (wantPfrepBlocks) and that are not resident, the most wanted first, are the next request.
void Streamer::scoreRegionStream(PfrepStream& ps) {
    ps.batch_count = 0;
    ps.batch_bytes = 0;
    if (!ps.is_open || ps.step < 0) {
        ps.usefulness = INFINITY;
        if (ps.is_open) {
            ps.batch[0] = 0;
            ps.batch_count = 1;
            ps.batch_bytes = ps.regions.blocks[0].size;
        }
        return;
    }
    uint32_t n = 0;
    for (uint32_t b = 1; b < ps.block_count; ++b)
        if (ps.block_priority[b] > 0 && ps.block_state[b] == uint8_t(LevelState::Absent)) ps.needed[n++] = b;
    if (n == 0) return;
    const uint32_t per_request = std::min(options_.pfrep_blocks_per_request ? options_.pfrep_blocks_per_request : 16u,
                                          kMaxPfrepBlocksPerRequest);
    const float* priority = ps.block_priority;
    const auto more_wanted = [priority](uint32_t a, uint32_t b) {
        return priority[a] != priority[b] ? priority[a] > priority[b] : a < b;
    };
    if (n > per_request) {
        std::partial_sort(ps.needed, ps.needed + per_request, ps.needed + n, more_wanted);
        n = per_request;
    } else {
        std::sort(ps.needed, ps.needed + n, more_wanted);
    }
    // The most wanted block always; then more while the budget has room beside what is held and
    // in flight, so that a tight budget still gets one block per request rather than none.
    const uint64_t held = stats_.resident_bytes + stats_.in_flight_bytes;
    const uint64_t room = options_.budget_bytes == 0     ? UINT64_MAX
                          : options_.budget_bytes > held ? options_.budget_bytes - held
                                                         : 0;
    uint32_t taken = 0;
    for (; taken < n; ++taken) {
        const uint64_t size = ps.regions.blocks[ps.needed[taken]].size;
        if (taken > 0 && ps.batch_bytes + size > room) break;
        ps.batch_bytes += size;
    }
    std::sort(ps.needed, ps.needed + taken);
    for (uint32_t i = 0; i < taken; ++i) {
        ps.batch[i] = ps.needed[i];
        ps.usefulness = std::max(ps.usefulness, priority[ps.needed[i]]);
    }
    ps.batch_count = taken;
}

void Streamer::wantPfrepBlocks(uint32_t model, const PfrepView& view, float priority) {
    if (model >= pfrep_count_ || !(priority > 0)) return;
    PfrepStream& ps = pfrep_[model];
    if (ps.format != format::kPfrepFormatRegions || !ps.is_open) return;
    // Blocks are never evicted, so the vertices a view keeps stay resident from when they were
    // inserted: the insert threshold's blocks are enough (docs/format/pfrep.md "Region blocks").
    PfrepView insert = view;
    insert.hysteresis = 1.0f;
    insert.cull_hysteresis = 0.0f;
    size_t count = 0;
    if (pfrepRegionBlocksNeeded(ps.regions, insert, ps.needed, ps.block_count, &count) != Result::Ok) return;
    for (size_t k = 0; k < count; ++k)
        ps.block_priority[ps.needed[k]] = std::max(ps.block_priority[ps.needed[k]], priority);
}

// The opening: the stream's allocation (the format 2 buffer, the state and the arrays, counted in
// flight until it is collected) and a transient buffer for the opening's bytes; then block requests,
// read back to back into one transient buffer.
bool Streamer::prepareRegionTask(Task& t, PfrepStream& ps, uint64_t size) {
    const Allocator& a = options_.allocator;
    t.coded = nullptr;
    if (!ps.is_open) {
        if (ps.directory_bytes <= SIZE_MAX && ps.open_bytes <= SIZE_MAX) {
            ps.data = static_cast<uint8_t*>(detail::allocateBytes(a, size_t(ps.directory_bytes)));
            t.coded = static_cast<uint8_t*>(detail::allocateBytes(a, size_t(ps.open_bytes)));
        }
        if (!ps.data || !t.coded) {
            detail::deallocateBytes(a, ps.data);
            detail::deallocateBytes(a, t.coded);
            ps.data = nullptr;
            t.coded = nullptr;
            return false;
        }
        // The header was validated when it arrived (readRegionHeader).
        PfrepRegionInfo info;
        (void)pfrepRegionInfo(ps.header, format::kPfrepHeaderSize, &info);
        const RegionStreamLayout l = regionStreamLayout(info);
        // pfrepRegionOpen zeroes the format 2 buffer on the job; the claimed bits and the block
        // arrays start zero (LevelState::Absent, no priority).
        std::memset(ps.data + l.claimed, 0, size_t(l.total - l.claimed));
        t.region_decoded = ps.data;
        t.region_state = ps.data + l.state;
        ps.claimed = ps.data + l.claimed;
        ps.block_priority = reinterpret_cast<float*>(ps.data + l.priority);
        ps.block_state = ps.data + l.block_state;
        ps.needed = reinterpret_cast<uint32_t*>(ps.data + l.needed);
        t.kind = Task::Kind::PfrepRegionOpen;
        t.dst = nullptr;
        t.size = size_t(l.state);
        t.scratch_bytes = size_t(l.claimed - l.state);
        t.coded_size = size_t(ps.open_bytes);
        stats_.in_flight_bytes += ps.directory_bytes + ps.open_bytes;
        return true;
    }
    if (ps.batch_count == 0 || size > SIZE_MAX - detail::kPfrepRegionStagePadding) return false;
    // Staging validates the blocks where they were read: the last one's entries need the padding.
    t.coded = static_cast<uint8_t*>(detail::allocateBytes(a, size_t(size) + detail::kPfrepRegionStagePadding));
    if (!t.coded) return false;
    t.kind = Task::Kind::PfrepRegionBlocks;
    t.dst = nullptr;
    t.coded_size = size_t(size);
    t.regions_in = &ps.regions;
    t.claimed = ps.claimed;
    t.block_count = ps.batch_count;
    for (uint32_t i = 0; i < ps.batch_count; ++i) {
        t.blocks[i] = ps.batch[i];
        ps.block_state[ps.batch[i]] = uint8_t(LevelState::Loading);
    }
    stats_.in_flight_bytes += size;
    return true;
}

void Streamer::collect() {
    const Allocator& a = options_.allocator;
    for (uint32_t i = 0; i < task_count_; ++i) {
        Task& t = tasks_[i];
        if (!t.is_busy || t.done.load(std::memory_order_acquire) == 0) continue;
        t.is_busy = false;
        --busy_tasks_;
        if (t.kind == Task::Kind::ClusterRead) {
            collectClusterRead(t);
            if (t.is_busy) --i; // resubmitted as its decode: collect it now if it already ran inline
            continue;
        }
        if (t.kind == Task::Kind::ClusterDecode) {
            collectClusterDecode(t);
            continue;
        }
        if (t.kind == Task::Kind::Level) {
            Slot& s = slots_[t.slot];
            stats_.in_flight_bytes -= s.size;
            if (t.result == Result::Ok) {
                s.state = LevelState::Resident;
                stats_.resident_bytes += s.size;
                stats_.streamed_bytes += s.size;
                ++stats_.resident_levels;
            } else {
                detail::deallocateBytes(a, s.data);
                s.data = nullptr;
                s.state = LevelState::Failed;
                ++stats_.failures;
            }
            continue;
        }
        PfrepStream& ps = pfrep_[t.slot];
        Result r = t.result;
        if (t.kind == Task::Kind::PfrepHeader) {
            if (r == Result::Ok) {
                stats_.streamed_bytes += t.size;
                r = ps.format == format::kPfrepVersion         ? Result::Ok
                    : ps.format == format::kPfrepFormatRegions ? readRegionHeader(ps)
                                                               : readCompressedHeader(ps);
                if (ps.format == format::kPfrepVersion) {
                    ps.directory_bytes = pfrepDirectoryBytes(ps.header, sizeof(ps.header));
                    if (ps.directory_bytes == 0 || ps.directory_bytes > ps.view_size) r = Result::BadStructure;
                }
            }
        } else if (t.kind == Task::Kind::PfrepWhole) {
            collectPfrepWhole(t, r);
        } else if (t.kind == Task::Kind::PfrepRegionOpen) {
            collectRegionOpen(t, r);
        } else if (t.kind == Task::Kind::PfrepRegionBlocks) {
            collectRegionBlocks(t, r);
        } else {
            stats_.in_flight_bytes -= t.size;
            if (r == Result::Ok && !t.has_prefix) {
                // The directory arrived: the prefix each chain level needs, in step order (coarse first).
                const PfrepModel& d = t.pfrep;
                if (d.blob_size != ps.view_size) r = Result::BadStructure;
                ps.step_bytes[0] = t.size;
                for (uint32_t p = 1; r == Result::Ok && p < ps.step_count; ++p) {
                    const uint32_t removals = ps.removals[ps.step_count - 1 - p];
                    if (removals > d.removed_count) {
                        r = Result::BadStructure;
                        break;
                    }
                    const uint64_t bytes = pfrepPrefixBytesForLevel(d, removals);
                    ps.step_bytes[p] = bytes > ps.step_bytes[p - 1] ? bytes : ps.step_bytes[p - 1];
                    if (ps.step_bytes[p] > ps.view_size) r = Result::BadStructure;
                }
            }
            if (r == Result::Ok) {
                stats_.streamed_bytes += t.size - t.old_size;
                detail::deallocateBytes(a, ps.data);
                stats_.resident_bytes += t.size - t.old_size;
                stats_.pfrep_resident_bytes += t.size - t.old_size;
                ps.data = t.dst;
                ++ps.step;
                ps.steps[ps.step] = t.pfrep;
                ps.steps[ps.step].criterion_table = nullptr;
                pointStepsAt(ps.steps, ps.step, ps.data);
            } else {
                detail::deallocateBytes(a, t.dst);
            }
        }
        t.dst = nullptr;
        if (r == Result::Ok) {
            ps.state = ps.step < 0 ? PfrepStreamState::Absent : PfrepStreamState::Resident;
        } else {
            ps.state = PfrepStreamState::Failed;
            ps.is_failed = 1;
            ++stats_.failures;
        }
    }
}

void Streamer::evict(uint32_t slot) {
    Slot& s = slots_[slot];
    assert(s.state == LevelState::Resident);
    detail::deallocateBytes(options_.allocator, s.data);
    s.data = nullptr;
    s.state = LevelState::Absent;
    stats_.resident_bytes -= s.size;
    --stats_.resident_levels;
    ++stats_.evictions;
}

bool Streamer::shrinkPfrep(uint32_t stream) {
    PfrepStream& ps = pfrep_[stream];
    assert(ps.step > 0 && ps.state != PfrepStreamState::Loading);
    const uint64_t from = ps.step_bytes[ps.step], to = ps.step_bytes[ps.step - 1];
    if (to < from) {
        // The shorter prefix is the same bytes: move them to a buffer of the shorter size.
        uint8_t* data = static_cast<uint8_t*>(detail::allocateBytes(options_.allocator, size_t(to)));
        if (!data) return false;
        std::memcpy(data, ps.data, size_t(to));
        detail::deallocateBytes(options_.allocator, ps.data);
        ps.data = data;
        stats_.resident_bytes -= from - to;
        stats_.pfrep_resident_bytes -= from - to;
    }
    --ps.step;
    pointStepsAt(ps.steps, ps.step, ps.data);
    ++stats_.pfrep_shrinks;
    return true;
}

// Usefulness: coarsest levels are pinned (infinite); a level at or coarser than the wanted one
// gets the model's priority divided by its distance in levels from the wanted one; finer levels
// than wanted are worth nothing.
void Streamer::scoreLevels(const ModelDemand* demand) {
    const ModelSet& models = source_->models();
    for (uint32_t i = 0; i < slot_count_; ++i) {
        Slot& s = slots_[i];
        s.usefulness = s.is_coarsest ? INFINITY : 0.0f;
        if (s.is_coarsest || !demand) continue;
        const uint32_t m = slot_model_[i];
        const ModelDemand& d = demand[m];
        const uint32_t l = i - models.model(m).first_level;
        if (d.wanted_level == kNoLevel || l < d.wanted_level || !(d.priority > 0)) continue;
        s.usefulness = d.priority / float(1 + l - d.wanted_level);
    }
}

// PFRep prefixes: the directory is pinned; every step up to the one the wanted chain level needs
// is worth the model's priority (each is a prerequisite of the next, so they are not discounted
// by distance like levels); steps beyond it are worth nothing and are shrunk first.
void Streamer::scorePfrepStreams(const ModelDemand* demand) {
    for (uint32_t m = 0; m < pfrep_count_; ++m) {
        PfrepStream& ps = pfrep_[m];
        ps.usefulness = 0;
        ps.held_usefulness = 0;
        if (ps.state == PfrepStreamState::None) continue;
        uint32_t target = 0;
        float priority = 0;
        if (demand && demand[m].wanted_level != kNoLevel && demand[m].priority > 0) {
            const uint32_t wanted =
                demand[m].wanted_level < ps.step_count - 1 ? demand[m].wanted_level : ps.step_count - 2;
            target = ps.step_count - 1 - wanted;
            priority = demand[m].priority;
        }
        if (ps.state == PfrepStreamState::Loading) continue;
        if (ps.format == format::kPfrepFormatRegions) {
            if (!ps.is_failed) scoreRegionStream(ps);
            continue;
        }
        // A step that adds no bytes (two chain levels in one block) needs no read.
        while (!ps.is_failed && ps.step >= 0 && uint32_t(ps.step) < target &&
               ps.step_bytes[ps.step + 1] == ps.step_bytes[ps.step]) {
            ps.steps[ps.step + 1] = ps.steps[ps.step];
            ++ps.step;
        }
        ps.held_usefulness = ps.step > 0 && uint32_t(ps.step) <= target ? priority : 0.0f;
        if (ps.is_failed) continue;
        // Format 4 is decoded against LOD0's stream: past its header it waits for level 0.
        if (ps.format == format::kPfrepVersionLod0 && ps.directory_bytes != 0 &&
            slots_[ps.lod0_slot].state != LevelState::Resident)
            continue;
        if (ps.step < 0)
            ps.usefulness = INFINITY;
        else if (uint32_t(ps.step) < target)
            ps.usefulness = priority;
    }
}

// Request ids: levels are slots [0, slot_count_), PFRep streams follow, then cluster pages.
float Streamer::usefulness(uint32_t id) const {
    if (id < slot_count_) return slots_[id].usefulness;
    if (id < slot_count_ + pfrep_count_) return pfrep_[id - slot_count_].usefulness;
    return pages_[id - slot_count_ - pfrep_count_].usefulness;
}

// Fills candidates_ with the absent levels and the streams worth loading; returns their count.
uint32_t Streamer::rankCandidates() {
    uint32_t candidate_count = 0;
    for (uint32_t i = 0; i < slot_count_; ++i)
        if (slots_[i].state == LevelState::Absent && slots_[i].usefulness > 0 && slots_[i].size > 0)
            candidates_[candidate_count++] = i;
    for (uint32_t m = 0; m < pfrep_count_; ++m)
        if (pfrep_[m].usefulness > 0) candidates_[candidate_count++] = slot_count_ + m;
    for (uint32_t p = 0; p < page_count_; ++p)
        if (pages_[p].state == LevelState::Absent && pages_[p].usefulness > 0)
            candidates_[candidate_count++] = slot_count_ + pfrep_count_ + p;
    // Most useful first; ties by id (levels before prefixes) so the order does not depend on the sort.
    std::sort(candidates_, candidates_ + candidate_count, [this](uint32_t a, uint32_t b) {
        const float ua = usefulness(a), ub = usefulness(b);
        if (ua != ub) return ua > ub;
        return a < b;
    });
    return candidate_count;
}

// Bytes held while the request runs: a level's buffer, or a prefix step's whole new buffer.
// Coarsest levels and the PFRep directory are pinned (loaded whatever the budget).
uint64_t Streamer::requestBytes(uint32_t id, bool* is_pinned) const {
    *is_pinned = false;
    if (id < slot_count_) {
        *is_pinned = slots_[id].is_coarsest != 0;
        return slots_[id].size;
    }
    if (id >= slot_count_ + pfrep_count_) {
        const PageSlot& page = pages_[id - slot_count_ - pfrep_count_];
        *is_pinned = page.is_pinned != 0;
        return page.estimate;
    }
    const PfrepStream& ps = pfrep_[id - slot_count_];
    if (ps.format == format::kPfrepFormatRegions) {
        // The header, the opening (the stream's allocation and its read) and the root block are pinned.
        *is_pinned = ps.step < 0;
        if (ps.directory_bytes == 0) return 0;
        return ps.is_open ? ps.batch_bytes : ps.directory_bytes + ps.open_bytes;
    }
    if (ps.step < 0) {
        *is_pinned = true;
        return ps.directory_bytes; // 0 for the header, which lives in the stream itself
    }
    // Format 3 grows back (after a shrink) only by decoding the whole blob again.
    return ps.format != format::kPfrepVersion ? ps.step_bytes[ps.step_count - 1] : ps.step_bytes[ps.step + 1];
}

// The resident level (or shrinkable PFRep stream) least useful and worth less than `useful`;
// UINT32_MAX when there is none.
uint32_t Streamer::leastUsefulVictim(float useful) const {
    uint32_t victim = UINT32_MAX;
    float victim_usefulness = 0;
    for (uint32_t i = 0; i < slot_count_; ++i) {
        const Slot& v = slots_[i];
        if (v.state != LevelState::Resident || v.is_coarsest || !(v.usefulness < useful)) continue;
        if (victim == UINT32_MAX || v.usefulness < victim_usefulness) {
            victim = i;
            victim_usefulness = v.usefulness;
        }
    }
    for (uint32_t m = 0; m < pfrep_count_; ++m) {
        const PfrepStream& v = pfrep_[m];
        if (v.step <= 0 || v.state == PfrepStreamState::Loading || !(v.held_usefulness < useful)) continue;
        if (victim == UINT32_MAX || v.held_usefulness < victim_usefulness) {
            victim = slot_count_ + m;
            victim_usefulness = v.held_usefulness;
        }
    }
    // Pages: the least useful, then the least recently wanted, then the finest.
    uint32_t page_victim = UINT32_MAX;
    for (uint32_t p = 0; p < page_count_; ++p) {
        const PageSlot& v = pages_[p];
        if (v.state != LevelState::Resident || v.is_pinned || !(v.usefulness < useful)) continue;
        if (page_victim != UINT32_MAX) {
            const PageSlot& w = pages_[page_victim];
            if (v.usefulness != w.usefulness ? v.usefulness > w.usefulness
                : v.last_wanted != w.last_wanted ? v.last_wanted > w.last_wanted
                                                 : v.depth >= w.depth)
                continue;
        }
        page_victim = p;
    }
    if (page_victim != UINT32_MAX && (victim == UINT32_MAX || pages_[page_victim].usefulness <= victim_usefulness))
        victim = slot_count_ + pfrep_count_ + page_victim;
    return victim;
}

// Evicts the least useful resident levels (or shrinks prefixes) that are worth less than `useful`
// until `size` more bytes fit the budget, but only when that makes enough room: evicting and then
// skipping would reload the victims next frame. Returns whether the request fits.
bool Streamer::makeRoom(uint64_t size, float useful) {
    const uint64_t budget = options_.budget_bytes;
    uint64_t reclaimable = 0;
    for (uint32_t i = 0; i < slot_count_; ++i) {
        const Slot& v = slots_[i];
        if (v.state == LevelState::Resident && !v.is_coarsest && v.usefulness < useful) reclaimable += v.size;
    }
    for (uint32_t m = 0; m < pfrep_count_; ++m) {
        const PfrepStream& v = pfrep_[m];
        if (v.step > 0 && v.state != PfrepStreamState::Loading && v.held_usefulness < useful)
            reclaimable += v.step_bytes[v.step] - v.step_bytes[0];
    }
    for (uint32_t p = 0; p < page_count_; ++p) {
        const PageSlot& v = pages_[p];
        if (v.state == LevelState::Resident && !v.is_pinned && v.usefulness < useful) reclaimable += v.size;
    }
    const uint64_t used = stats_.resident_bytes + stats_.in_flight_bytes;
    if (used + size > budget + reclaimable) return false;
    while (stats_.resident_bytes + stats_.in_flight_bytes + size > budget) {
        const uint32_t victim = leastUsefulVictim(useful);
        if (victim == UINT32_MAX) break;
        if (victim < slot_count_) {
            evict(victim);
        } else if (victim >= slot_count_ + pfrep_count_) {
            evictPage(victim - slot_count_ - pfrep_count_);
        } else if (!shrinkPfrep(victim - slot_count_)) {
            break;
        }
    }
    return stats_.resident_bytes + stats_.in_flight_bytes + size <= budget;
}

// A format 3 stream's whole decode: the decoded blob (counted in flight) and, beside it, the coded
// blob and the decoder's scratch (transient, freed when the task is collected).
bool Streamer::preparePfrepWhole(Task& t, PfrepStream& ps, uint64_t size) {
    const uint64_t coded_room = (ps.view_size + 7) & ~uint64_t(7);
    uint8_t* data = nullptr;
    uint8_t* coded = nullptr;
    const uint8_t* lod0 = nullptr;
    if (ps.format == format::kPfrepVersionLod0) {
        // Format 4 decodes against LOD0's stream: level 0 must be resident (scorePfrepStreams waits
        // for it; another request of this update may have evicted it since). Its stream is copied
        // into the task, so level 0 may go while the job runs.
        const Slot& s = slots_[ps.lod0_slot];
        if (s.state != LevelState::Resident) return false;
        lod0 = s.data + ps.lod0_offset;
        PfrepPackFormat4Info info;
        if (pfrepPackFormat4Info(ps.header, format::kPfrepHeaderSize, lod0, size_t(ps.lod0_size), &info) !=
            Result::Ok) {
            ps.state = PfrepStreamState::Failed;
            ps.is_failed = 1;
            ++stats_.failures;
            return false;
        }
        ps.scratch_bytes = (info.scratch_bytes + 7) & ~size_t(7);
    }
    const uint64_t lod0_room = lod0 ? ps.lod0_size : 0;
    if (size <= SIZE_MAX && coded_room + ps.scratch_bytes + lod0_room <= SIZE_MAX) {
        data = static_cast<uint8_t*>(detail::allocateBytes(options_.allocator, size_t(size)));
        coded = static_cast<uint8_t*>(
            detail::allocateBytes(options_.allocator, size_t(coded_room + ps.scratch_bytes + lod0_room)));
    }
    if (!data || !coded) {
        detail::deallocateBytes(options_.allocator, data);
        detail::deallocateBytes(options_.allocator, coded);
        ps.state = PfrepStreamState::Failed;
        ps.is_failed = 1;
        ++stats_.failures;
        return false;
    }
    t.kind = Task::Kind::PfrepWhole;
    t.dst = data;
    t.size = size_t(size);
    t.coded = coded;
    t.coded_size = size_t(ps.view_size);
    t.scratch_bytes = ps.scratch_bytes;
    t.removals = ps.removals;
    t.step_count = ps.step_count;
    t.lod0_size = size_t(lod0_room);
    if (lod0) std::memcpy(coded + coded_room + ps.scratch_bytes, lod0, size_t(lod0_room));
    stats_.in_flight_bytes += size;
    ++stats_.pfrep_decodes;
    return true;
}

// Sets task `task_index` up to read request `id` (`size` bytes) and marks the level or stream
// Loading; false (the level or stream marked Failed) when its buffer cannot be allocated.
bool Streamer::prepareTask(uint32_t task_index, uint32_t id, uint64_t size) {
    Task& t = tasks_[task_index];
    t.source = source_;
    t.result = Result::Ok;
    if (id < slot_count_) {
        Slot& s = slots_[id];
        uint8_t* data = static_cast<uint8_t*>(detail::allocateBytes(options_.allocator, size_t(s.size)));
        if (!data) {
            s.state = LevelState::Failed;
            ++stats_.failures;
            return false;
        }
        s.data = data;
        s.state = LevelState::Loading;
        s.task = task_index;
        t.kind = Task::Kind::Level;
        t.model = slot_model_[id];
        t.level = id - source_->models().model(t.model).first_level;
        t.dst = data;
        t.size = size_t(s.size);
        t.slot = id;
        stats_.in_flight_bytes += size;
        return true;
    }
    if (id >= slot_count_ + pfrep_count_) return prepareClusterTask(t, id - slot_count_ - pfrep_count_, size);
    PfrepStream* ps = &pfrep_[id - slot_count_];
    t.slot = id - slot_count_;
    t.view = ps->view;
    if (ps->step < 0 && ps->directory_bytes == 0) {
        t.kind = Task::Kind::PfrepHeader;
        t.dst = ps->header;
        t.size = sizeof(ps->header);
    } else if (ps->format == format::kPfrepFormatRegions) {
        if (!prepareRegionTask(t, *ps, size)) {
            // A batch of blocks that cannot be read now is asked for again; the opening and the
            // root cannot wait.
            if (ps->is_open && ps->step >= 0) return false;
            ps->state = PfrepStreamState::Failed;
            ps->is_failed = 1;
            ++stats_.failures;
            return false;
        }
    } else if (ps->format != format::kPfrepVersion) {
        if (!preparePfrepWhole(t, *ps, size)) return false;
    } else {
        uint8_t* data = static_cast<uint8_t*>(detail::allocateBytes(options_.allocator, size_t(size)));
        if (!data) {
            ps->state = PfrepStreamState::Failed;
            ps->is_failed = 1;
            ++stats_.failures;
            return false;
        }
        t.kind = Task::Kind::PfrepStep;
        t.dst = data;
        t.size = size_t(size);
        t.has_prefix = ps->step >= 0;
        t.old_data = t.has_prefix ? ps->data : nullptr;
        t.old_size = t.has_prefix ? size_t(ps->step_bytes[ps->step]) : 0;
        if (t.has_prefix) t.pfrep = ps->steps[ps->step];
        stats_.in_flight_bytes += size;
    }
    ps->state = PfrepStreamState::Loading;
    return true;
}

void Streamer::update(const ModelDemand* demand) {
    if (!slots_) return;
    collect();
    scoreLevels(demand);
    scorePfrepStreams(demand);
    scoreClusterPages();
    const uint32_t candidate_count = rankCandidates();
    uint32_t next_task = 0;
    for (uint32_t c = 0; c < candidate_count; ++c) {
        while (next_task < task_count_ && tasks_[next_task].is_busy) ++next_task;
        if (next_task == task_count_) break;
        const uint32_t id = candidates_[c];
        if (id >= slot_count_ && id < slot_count_ + pfrep_count_ &&
            pfrep_[id - slot_count_].state == PfrepStreamState::Loading)
            continue; // collected inline and resubmitted
        bool is_pinned = false;
        const uint64_t size = requestBytes(id, &is_pinned);
        if (options_.budget_bytes > 0 && !is_pinned && !makeRoom(size, usefulness(id))) continue;
        if (!prepareTask(next_task, id, size)) continue;
        Task& t = tasks_[next_task];
        ++stats_.requests;
        t.done.store(0, std::memory_order_relaxed);
        t.is_busy = true;
        ++busy_tasks_;
        if (jobs_.submit) {
            jobs_.submit(jobs_.user, &Task::run, &t);
        } else {
            // Inline: the task is done now; free its slot for the next candidate.
            Task::run(&t);
            collect();
            next_task = 0;
        }
    }
    // Levels that are no longer wanted stay resident while the budget allows (they cost nothing to
    // keep and the camera may come back); eviction happens only to make room above.
    collect();
    rebuildResidentTable();
    rebuildClusterResidency();
    for (uint32_t m = 0; m < pfrep_count_; ++m)
        if (pfrep_[m].format == format::kPfrepFormatRegions && pfrep_[m].is_open)
            std::memset(pfrep_[m].block_priority, 0, sizeof(float) * pfrep_[m].block_count);
    if (++cluster_frame_ == 0) cluster_frame_ = 1; // stamps of frame 0 mean "never"
}

// ---- Cluster pages ----

namespace {

size_t align8(size_t n) {
    return (n + 7) & ~size_t(7);
}

} // namespace

// Reads and opens model m's cluster table. Returns NotLoaded (no extension), OutOfMemory, or the
// find / read / open error (the model then streams its levels only).
Result Streamer::initClusterModel(uint32_t m, uint32_t* page_count) {
    ClusterModel& cm = clusters_[m];
    *page_count = 0;
    const ModelSet& models = source_->models();
    const Pack& pack = source_->pack();
    const LevelInfo& level0 = models.level(models.model(m).first_level);
    if (level0.mesh == kNoIndex || level0.mesh >= pack.meshCount()) return Result::NotLoaded;
    Result r = clusterPackFind(pack, level0.mesh, &cm.source);
    if (r != Result::Ok) return r;
    const Allocator& a = options_.allocator;
    uint8_t* table = detail::allocateArray<uint8_t>(a, cm.source.table_size);
    if (!table) return Result::OutOfMemory;
    ClusterPackInfo info;
    r = source_->readBufferView(cm.source.table_view, 0, table, cm.source.table_size);
    if (r == Result::Ok) r = clusterPackReadInfo(table, cm.source.table_size, &info);
    size_t bytes = 0;
    if (r == Result::Ok) {
        const size_t groups = info.group_count, pages = info.page_count;
        bytes = align8(info.memory_bytes) + align8(pages) + align8(groups) + 2 * align8(groups * sizeof(uint32_t)) +
                align8((groups + 1) * sizeof(uint32_t)) + align8(size_t(info.cluster_count) * sizeof(uint32_t));
        cm.memory = detail::allocateBytes(a, bytes);
        if (!cm.memory) r = Result::OutOfMemory;
    }
    if (r == Result::Ok) {
        std::memset(cm.memory, 0, bytes);
        r = clusterPackOpen(table, cm.source.table_size, cm.source.pages_size, cm.memory, info.memory_bytes, &cm.pack);
    }
    detail::deallocateBytes(a, table);
    if (r != Result::Ok) {
        detail::deallocateBytes(a, cm.memory);
        cm.memory = nullptr;
        return r;
    }
    uint8_t* at = static_cast<uint8_t*>(cm.memory) + align8(info.memory_bytes);
    const size_t groups = info.group_count;
    auto take = [&at](size_t n) {
        uint8_t* p = at;
        at += align8(n);
        return p;
    };
    cm.page_resident = take(info.page_count);
    cm.group_resident = take(groups);
    cm.group_stamp = reinterpret_cast<uint32_t*>(take(groups * sizeof(uint32_t)));
    cm.stack = reinterpret_cast<uint32_t*>(take(groups * sizeof(uint32_t)));
    cm.output_first = reinterpret_cast<uint32_t*>(take((groups + 1) * sizeof(uint32_t)));
    cm.output_parent = reinterpret_cast<uint32_t*>(take(size_t(info.cluster_count) * sizeof(uint32_t)));
    // Each group's outputs' parent groups (the groups whose residency the closure ties it to).
    const ClusterLodView& v = cm.pack.view;
    for (uint32_t c = 0; c < v.cluster_count; ++c)
        if (v.clusters[c].self_group != kClusterNone && v.clusters[c].parent_group != kClusterNone)
            ++cm.output_first[v.clusters[c].self_group + 1];
    for (uint32_t g = 0; g < v.group_count; ++g) cm.output_first[g + 1] += cm.output_first[g];
    for (uint32_t c = 0; c < v.cluster_count; ++c) {
        const ClusterLodCluster& cl = v.clusters[c];
        if (cl.self_group == kClusterNone || cl.parent_group == kClusterNone) continue;
        cm.output_parent[cm.output_first[cl.self_group] + cm.stack[cl.self_group]++] = cl.parent_group;
    }
    std::memset(cm.stack, 0, groups * sizeof(uint32_t));
    cm.has_table = 1;
    cm.is_dirty = 1;
    *page_count = cm.pack.page_count;
    return Result::Ok;
}

// Opens every model's table, then sets up one slot per page of every table.
bool Streamer::initClusters() {
    const Allocator& a = options_.allocator;
    clusters_ = detail::allocateArray<ClusterModel>(a, pfrep_count_);
    if (!clusters_) return false;
    std::memset(static_cast<void*>(clusters_), 0, sizeof(ClusterModel) * pfrep_count_);
    uint32_t total = 0;
    for (uint32_t m = 0; m < pfrep_count_; ++m) {
        uint32_t pages = 0;
        const Result r = initClusterModel(m, &pages);
        if (r == Result::OutOfMemory) return false;
        if (r != Result::Ok && r != Result::NotLoaded) ++stats_.failures;
        clusters_[m].first_page = total;
        total += pages;
    }
    page_count_ = total;
    pages_ = detail::allocateArray<PageSlot>(a, total);
    uint32_t* candidates = detail::allocateArray<uint32_t>(a, size_t(slot_count_) + pfrep_count_ + total);
    if (!pages_ || !candidates) {
        detail::deallocateBytes(a, candidates);
        page_count_ = 0;
        return false;
    }
    detail::deallocateBytes(a, candidates_);
    candidates_ = candidates;
    for (uint32_t m = 0; m < pfrep_count_; ++m) {
        const ClusterModel& cm = clusters_[m];
        if (!cm.has_table) continue;
        const ClusterLodView& v = cm.pack.view;
        for (uint32_t p = 0; p < cm.pack.page_count; ++p) {
            PageSlot& slot = pages_[cm.first_page + p];
            std::memset(static_cast<void*>(&slot), 0, sizeof(slot));
            slot.state = LevelState::Absent;
            slot.model = m;
            const ClusterPage& page = cm.pack.pages[p];
            uint64_t vertices = 0;
            for (uint32_t i = 0; i < page.cluster_count; ++i) {
                const ClusterLodCluster& cl = v.clusters[cm.pack.page_clusters[page.first_cluster + i]];
                vertices += cm.pack.places[cm.pack.page_clusters[page.first_cluster + i]].vertex_count;
                if (cl.parent_group == kClusterNone) slot.is_pinned = 1;
                else if (v.groups[cl.parent_group].depth > slot.depth) slot.depth = v.groups[cl.parent_group].depth;
            }
            slot.vertex_bound = vertices > 0xffffffffu ? 0xffffffffu : uint32_t(vertices);
            slot.estimate = (uint64_t(slot.vertex_bound) + page.triangle_count) * 3 * 4;
        }
    }
    return true;
}

const ClusterLodPack* Streamer::clusterPack(uint32_t model) const {
    return clusters_ && model < pfrep_count_ && clusters_[model].has_table ? &clusters_[model].pack : nullptr;
}

const uint8_t* Streamer::clusterGroupResident(uint32_t model) const {
    if (!clusterPack(model) || !clusters_[model].is_drawable) return nullptr;
    return clusters_[model].group_resident;
}

LevelState Streamer::clusterPageState(uint32_t model, uint32_t page) const {
    const ClusterLodPack* pack = clusterPack(model);
    if (!pack || page >= pack->page_count) return LevelState::Absent;
    return pages_[clusters_[model].first_page + page].state;
}

bool Streamer::clusterPageData(uint32_t model, uint32_t page, ClusterPageData* out) const {
    if (clusterPageState(model, page) != LevelState::Resident || !out) return false;
    const PageSlot& slot = pages_[clusters_[model].first_page + page];
    out->positions = reinterpret_cast<const float*>(slot.data);
    out->indices = reinterpret_cast<const uint32_t*>(slot.data + size_t(slot.vertex_count) * 3 * sizeof(float));
    out->vertex_count = slot.vertex_count;
    out->triangle_count = slot.triangle_count;
    return true;
}

void Streamer::markClusterPage(uint32_t page, float priority) {
    PageSlot& slot = pages_[page];
    if (slot.last_wanted != cluster_frame_) {
        slot.last_wanted = cluster_frame_;
        slot.priority = priority;
    } else if (priority > slot.priority) {
        slot.priority = priority;
    }
}

// Marks the pages of `group`'s inputs and of every group above it wanted this frame: a group's
// residency needs its outputs' parent groups resident (the closure), up to the roots.
void Streamer::markClusterGroup(ClusterModel& cm, uint32_t group, float priority) {
    const ClusterLodView& v = cm.pack.view;
    if (group >= v.group_count || cm.group_stamp[group] == cluster_frame_) return;
    cm.group_stamp[group] = cluster_frame_;
    uint32_t size = 0;
    cm.stack[size++] = group;
    while (size > 0) {
        const uint32_t g = cm.stack[--size];
        const ClusterLodGroup& gr = v.groups[g];
        for (uint32_t i = 0; i < gr.child_count; ++i)
            markClusterPage(cm.first_page + cm.pack.places[v.group_children[gr.first_child + i]].page, priority);
        for (uint32_t i = cm.output_first[g]; i < cm.output_first[g + 1]; ++i) {
            const uint32_t parent = cm.output_parent[i];
            if (cm.group_stamp[parent] == cluster_frame_) continue;
            cm.group_stamp[parent] = cluster_frame_;
            cm.stack[size++] = parent;
        }
    }
}

void Streamer::wantClusterPages(uint32_t model, const uint32_t* drawn, uint32_t drawn_count, const uint32_t* missing,
                                uint32_t missing_count, float priority) {
    if (!clusterPack(model) || !(priority > 0)) return;
    ClusterModel& cm = clusters_[model];
    const ClusterLodView& v = cm.pack.view;
    for (uint32_t i = 0; drawn && i < drawn_count; ++i) {
        if (drawn[i] >= v.cluster_count) continue;
        markClusterPage(cm.first_page + cm.pack.places[drawn[i]].page, priority);
        markClusterGroup(cm, v.clusters[drawn[i]].parent_group, priority);
    }
    for (uint32_t i = 0; missing && i < missing_count; ++i) markClusterGroup(cm, missing[i], priority);
}

// Root pages are pinned; pages wanted this frame are worth their priority, coarser groups' more (a
// finer page is useless until the pages above it arrive); the others nothing (evicted first).
void Streamer::scoreClusterPages() {
    for (uint32_t p = 0; p < page_count_; ++p) {
        PageSlot& slot = pages_[p];
        if (slot.is_pinned)
            slot.usefulness = INFINITY;
        else if (slot.last_wanted == cluster_frame_)
            slot.usefulness = slot.priority * float(1 + slot.depth);
        else
            slot.usefulness = 0;
    }
}

void Streamer::evictPage(uint32_t page) {
    PageSlot& slot = pages_[page];
    assert(slot.state == LevelState::Resident);
    detail::deallocateBytes(options_.allocator, slot.data);
    slot.data = nullptr;
    slot.state = LevelState::Absent;
    stats_.resident_bytes -= slot.size;
    stats_.cluster_resident_bytes -= slot.size;
    --stats_.cluster_resident_pages;
    ++stats_.cluster_page_evictions;
    clusters_[slot.model].is_dirty = 1;
}

// The read job: the page's coded bytes (transient); `size`, the page's estimate, counts in flight.
bool Streamer::prepareClusterTask(Task& t, uint32_t page, uint64_t size) {
    PageSlot& slot = pages_[page];
    const ClusterModel& cm = clusters_[slot.model];
    const uint32_t local = page - cm.first_page;
    const uint32_t length = cm.pack.pages[local].byte_length;
    t.coded = static_cast<uint8_t*>(detail::allocateBytes(options_.allocator, length));
    if (!t.coded) {
        slot.state = LevelState::Failed;
        ++stats_.failures;
        return false;
    }
    t.kind = Task::Kind::ClusterRead;
    t.coded_size = length;
    t.cluster_pack = &cm.pack;
    t.page = local;
    t.slot = page;
    t.view = cm.source.pages_view;
    t.dst = nullptr;
    t.scratch = nullptr;
    t.size = size_t(size);
    slot.state = LevelState::Loading;
    stats_.in_flight_bytes += size;
    ++stats_.cluster_page_reads;
    return true;
}

// The page's bytes arrived: check its header here, size the decode (never above the estimate the
// budget reserved) and submit it; a bad page fails alone.
void Streamer::collectClusterRead(Task& t) {
    PageSlot& slot = pages_[t.slot];
    const Allocator& a = options_.allocator;
    Result r = t.result;
    ClusterPageInfo info;
    if (r == Result::Ok) r = clusterPageReadInfo(*t.cluster_pack, t.page, t.coded, t.coded_size, &info);
    if (r == Result::Ok && info.vertex_count > slot.vertex_bound) r = Result::BadStructure;
    if (r == Result::Ok) {
        stats_.streamed_bytes += t.coded_size;
        t.dst = static_cast<uint8_t*>(
            detail::allocateBytes(a, (size_t(info.vertex_count) + info.triangle_count) * 3 * sizeof(uint32_t)));
        t.scratch = detail::allocateBytes(a, info.scratch_bytes);
        if (!t.dst || !t.scratch) r = Result::OutOfMemory;
    }
    if (r != Result::Ok) {
        detail::deallocateBytes(a, t.dst);
        detail::deallocateBytes(a, t.scratch);
        detail::deallocateBytes(a, t.coded);
        t.dst = t.coded = nullptr;
        t.scratch = nullptr;
        stats_.in_flight_bytes -= t.size;
        slot.state = LevelState::Failed;
        ++stats_.failures;
        return;
    }
    t.kind = Task::Kind::ClusterDecode;
    t.vertex_count = info.vertex_count;
    t.triangle_count = info.triangle_count;
    t.scratch_bytes = info.scratch_bytes;
    t.result = Result::Ok;
    t.done.store(0, std::memory_order_relaxed);
    t.is_busy = true;
    ++busy_tasks_;
    if (jobs_.submit)
        jobs_.submit(jobs_.user, &Task::run, &t);
    else
        Task::run(&t);
}

void Streamer::collectClusterDecode(Task& t) {
    PageSlot& slot = pages_[t.slot];
    const Allocator& a = options_.allocator;
    detail::deallocateBytes(a, t.coded);
    detail::deallocateBytes(a, t.scratch);
    t.coded = nullptr;
    t.scratch = nullptr;
    stats_.in_flight_bytes -= t.size;
    if (t.result != Result::Ok) {
        detail::deallocateBytes(a, t.dst);
        t.dst = nullptr;
        slot.state = LevelState::Failed;
        ++stats_.failures;
        return;
    }
    slot.data = t.dst;
    t.dst = nullptr;
    slot.vertex_count = t.vertex_count;
    slot.triangle_count = t.triangle_count;
    slot.size = (uint64_t(t.vertex_count) + t.triangle_count) * 3 * 4;
    slot.state = LevelState::Resident;
    stats_.resident_bytes += slot.size;
    stats_.cluster_resident_bytes += slot.size;
    ++stats_.cluster_resident_pages;
    clusters_[slot.model].is_dirty = 1;
}

// Group residency from page residency, for the models whose pages changed since the last update.
void Streamer::rebuildClusterResidency() {
    for (uint32_t m = 0; clusters_ && m < pfrep_count_; ++m) {
        ClusterModel& cm = clusters_[m];
        if (!cm.has_table || !cm.is_dirty) continue;
        cm.is_dirty = 0;
        uint8_t drawable = 1;
        for (uint32_t p = 0; p < cm.pack.page_count; ++p) {
            const PageSlot& slot = pages_[cm.first_page + p];
            cm.page_resident[p] = slot.state == LevelState::Resident ? 1 : 0;
            if (slot.is_pinned && !cm.page_resident[p]) drawable = 0;
        }
        clusterGroupResidency(cm.pack, cm.page_resident, cm.group_resident);
        cm.is_drawable = drawable;
    }
}

} // namespace lodrt
