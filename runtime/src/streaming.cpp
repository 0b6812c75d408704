// Pack sources (bytes or range reads) and the level streamer (see lodrt/streaming.h).

#include "lodrt/streaming.h"

#include <algorithm>
#include <cmath>
#include <cassert>
#include <cstdio>
#include <cstring>
#include <new>
#include <thread>

#include "lodrt/format.h"
#include "memory.h"

namespace lodrt {

namespace {

uint32_t readU32(const uint8_t* p) {
    return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}

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
    if (readU32(header) != format::kGlbMagic) {
        setError(error, error_size, "container: expected the GLB magic \"glTF\"");
        return Result::BadMagic;
    }
    if (readU32(header + 4) != format::kGlbVersion) {
        setError(error, error_size, "container: GLB container version is not 2");
        return Result::UnsupportedVersion;
    }
    const uint64_t length = readU32(header + 8);
    if (length != file_size) {
        setError(error, error_size, "container: the GLB header's length differs from the file size");
        return length > file_size ? Result::Truncated : Result::TrailingBytes;
    }
    const uint64_t json_size = readU32(header + 12);
    if (readU32(header + 16) != format::kGlbChunkJson || json_size == 0 || json_size % 4 != 0) {
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
        const uint64_t chunk_size = readU32(chunk);
        if (chunk_size % 4 != 0 || json_end + sizeof(chunk) + chunk_size > file_size) {
            setError(error, error_size, "container: chunk length not a multiple of 4 or past the end of the file");
            return chunk_size % 4 != 0 ? Result::BadChunk : Result::Truncated;
        }
        if (readU32(chunk + 4) == format::kGlbChunkJson) {
            setError(error, error_size, "container: a second JSON chunk");
            return Result::BadChunk;
        }
        if (readU32(chunk + 4) == format::kGlbChunkBin) {
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
    const PackSource* source = nullptr;
    uint32_t model = 0, level = 0;
    uint8_t* dst = nullptr;
    size_t size = 0;
    uint32_t slot = 0;
    bool is_busy = false; // frame-thread view
    Result result = Result::Ok;
    std::atomic<uint32_t> done{0};

    static void run(void* task) {
        Task* t = static_cast<Task*>(task);
        t->result = t->source->readLevel(t->model, t->level, t->dst, t->size);
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
    for (uint32_t i = 0; i < task_count_; ++i) tasks_[i].~Task();
    detail::deallocateBytes(a, tasks_);
    detail::deallocateBytes(a, slots_);
    detail::deallocateBytes(a, slot_model_);
    detail::deallocateBytes(a, candidates_);
    detail::deallocateBytes(a, resident_table_);
    tasks_ = nullptr;
    slots_ = nullptr;
    slot_model_ = nullptr;
    candidates_ = nullptr;
    resident_table_ = nullptr;
    task_count_ = slot_count_ = busy_tasks_ = 0;
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
    candidates_ = detail::allocateArray<uint32_t>(a, slot_count_);
    resident_table_ = detail::allocateArray<uint8_t>(a, model_count * kMaxLevels);
    void* task_memory = detail::allocateBytes(a, sizeof(Task) * options_.max_in_flight);
    if (!slots_ || !slot_model_ || !candidates_ || !resident_table_ || !task_memory) {
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
    rebuildResidentTable();
    return Result::Ok;
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

void Streamer::collect() {
    for (uint32_t i = 0; i < task_count_; ++i) {
        Task& t = tasks_[i];
        if (!t.is_busy || t.done.load(std::memory_order_acquire) == 0) continue;
        Slot& s = slots_[t.slot];
        stats_.in_flight_bytes -= s.size;
        if (t.result == Result::Ok) {
            s.state = LevelState::Resident;
            stats_.resident_bytes += s.size;
            stats_.streamed_bytes += s.size;
            ++stats_.resident_levels;
        } else {
            detail::deallocateBytes(options_.allocator, s.data);
            s.data = nullptr;
            s.state = LevelState::Failed;
            ++stats_.failures;
        }
        t.is_busy = false;
        --busy_tasks_;
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

void Streamer::update(const ModelDemand* demand) {
    if (!slots_) return;
    collect();
    const ModelSet& models = source_->models();
    // Usefulness: coarsest levels are pinned (infinite); a level at or coarser than the wanted one
    // gets the model's priority divided by its distance in levels from the wanted one; finer levels
    // than wanted are worth nothing.
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
    uint32_t candidate_count = 0;
    for (uint32_t i = 0; i < slot_count_; ++i)
        if (slots_[i].state == LevelState::Absent && slots_[i].usefulness > 0 && slots_[i].size > 0)
            candidates_[candidate_count++] = i;
    // Most useful first; ties by slot index so the order does not depend on the sort.
    std::sort(candidates_, candidates_ + candidate_count, [this](uint32_t a, uint32_t b) {
        if (slots_[a].usefulness != slots_[b].usefulness) return slots_[a].usefulness > slots_[b].usefulness;
        return a < b;
    });
    uint32_t next_task = 0;
    for (uint32_t c = 0; c < candidate_count; ++c) {
        while (next_task < task_count_ && tasks_[next_task].is_busy) ++next_task;
        if (next_task == task_count_) break;
        const uint32_t slot = candidates_[c];
        Slot& s = slots_[slot];
        const uint64_t budget = options_.budget_bytes;
        if (budget > 0 && !s.is_coarsest) {
            // Evict the least useful resident levels that are worth less than this one, but only when
            // that makes enough room: evicting and then skipping would reload the victims next frame.
            uint64_t reclaimable = 0;
            for (uint32_t i = 0; i < slot_count_; ++i) {
                const Slot& v = slots_[i];
                if (v.state == LevelState::Resident && !v.is_coarsest && v.usefulness < s.usefulness)
                    reclaimable += v.size;
            }
            const uint64_t used = stats_.resident_bytes + stats_.in_flight_bytes;
            if (used + s.size > budget + reclaimable) continue;
            while (stats_.resident_bytes + stats_.in_flight_bytes + s.size > budget) {
                uint32_t victim = slot_count_;
                for (uint32_t i = 0; i < slot_count_; ++i) {
                    const Slot& v = slots_[i];
                    if (v.state != LevelState::Resident || v.is_coarsest || !(v.usefulness < s.usefulness)) continue;
                    if (victim == slot_count_ || v.usefulness < slots_[victim].usefulness) victim = i;
                }
                if (victim == slot_count_) break;
                evict(victim);
            }
            if (stats_.resident_bytes + stats_.in_flight_bytes + s.size > budget) continue;
        }
        uint8_t* data = static_cast<uint8_t*>(detail::allocateBytes(options_.allocator, size_t(s.size)));
        if (!data) {
            s.state = LevelState::Failed;
            ++stats_.failures;
            continue;
        }
        s.data = data;
        s.state = LevelState::Loading;
        s.task = next_task;
        stats_.in_flight_bytes += s.size;
        ++stats_.requests;
        Task& t = tasks_[next_task];
        t.source = source_;
        t.model = slot_model_[slot];
        t.level = slot - models.model(t.model).first_level;
        t.dst = data;
        t.size = size_t(s.size);
        t.slot = slot;
        t.result = Result::Ok;
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
}

} // namespace lodrt
