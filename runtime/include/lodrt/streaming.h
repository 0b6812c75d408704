#pragma once
// Pack sources and level streaming.
//
// PackSource opens a pack either from bytes the engine already holds or through a caller-provided
// range-read callback: then only the GLB header and the JSON chunk are read up front, and each
// level's BIN range is read when the streamer asks for it. Index values are checked per level when
// its bytes arrive (lazy validation), so opening never scans geometry.
//
// Streamer keeps a memory budget of resident levels. Every model's coarsest level is requested
// first and never evicted (so every model becomes drawable as early as possible); finer levels are
// requested in order of usefulness (the model's demand priority, screen size x proximity, divided
// by how far the level is from the wanted one) and the least useful resident levels are evicted
// to make room. Reads and copies run through the engine's job callback on its worker threads;
// the frame only calls update() (request/poll), which never waits.
//
// A model whose level-0 mesh carries LODBAKE_progressive_fans also gets its PFRep blob streamed
// as a growing prefix (format v2 stores the coarse end first): the header and block directory are
// read first (pinned, like coarsest levels), then one step per job towards the prefix that holds
// the PFRep level of the chain level the demand wants (pfrepPrefixBytesForLevel of that level's
// `removals`). Each step is read with PackSource::readBufferView and validated by pfrepExtendPrefix
// on the job. Prefix bytes count towards the budget; to make room the least useful prefix is
// shrunk one step at a time (a shorter prefix stays valid), never below the directory.
// A format 3 blob (the extension object's `format` is 3: range-coded, not prefix-streamable) is read
// whole after its header and decoded on the job (pfrepDecompress) into the format 2 bytes, which
// hold every step at once; the budget counts the decoded bytes, and growing back after a shrink
// decodes it whole again.
// A format 5 blob (region blocks, docs/format/pfrep.md "Region blocks") is loaded by view instead of
// as a prefix: its header, then its directory and skeleton (pfrepRegionOpen, into one allocation
// holding the format 2 buffer the blocks are laid into and the region state; pinned and counted),
// then its root block (pinned); from then on the engine reports each instance's view before update()
// (wantPfrepBlocks) and the streamer reads the blocks those views need (pfrepRegionBlocksNeeded),
// most wanted first, up to StreamerOptions::pfrep_blocks_per_request per job (fewer when the
// budget's room is smaller), each validated on the job where it was read
// (detail::pfrepRegionStageBlock) and laid out and made resident in update(). Refinement may run
// on the model while a job stages blocks: a job writes nothing the model's readers see. Loaded
// blocks stay: the format 2 buffer is allocated whole when the blob opens, so
// evicting a block would free no memory; the budget counts that buffer and the block reads in flight.
//
// A model whose level-0 mesh carries LODBAKE_cluster_lod (lodrt/cluster_pack.h) gets its cluster
// table read and opened at init (one allocation per model) and its pages streamed: the pages holding
// the roots are pinned (requested first, never evicted); the others are requested when the engine
// reports, after its cut, the clusters it drew and the groups it could not enter (wantClusterPages).
// A page is read by range on a job, its stream header checked on the frame thread, then decoded
// (clusterPageDecode) on a second job into one buffer of positions and indices. Decoded page bytes
// count towards the same budget as levels and PFRep prefixes (the coded page and the decoder's
// scratch are transient, freed when the decode is collected, and not counted); to make room the
// pages not wanted this frame go first, least recently wanted first, then the finer ones. The group
// residency the cut needs is rebuilt (clusterGroupResidency) whenever a page arrives or leaves, so a
// cut made after update() draws the finest resident ancestor wherever a page is missing.

#include <atomic>
#include <cstddef>
#include <cstdint>

#include "lodrt/allocator.h"
#include "lodrt/cluster_pack.h"
#include "lodrt/format.h"
#include "lodrt/export.h"
#include "lodrt/model.h"
#include "lodrt/pack.h"
#include "lodrt/pfrep.h"
#include "lodrt/result.h"
#include "lodrt/selection.h"

namespace lodrt {

/// Reads file bytes [offset, offset + size) into dst. Returns Ok, or any error (passed through).
/// Called from the thread that opens the source, and from job threads for level reads, possibly
/// concurrently: it must be thread-safe (pread-style, no shared file position).
struct RangeReader {
    Result (*read)(void* user, uint64_t offset, void* dst, size_t size) = nullptr;
    void* user = nullptr;
};

/// A pack plus its models and where its BIN bytes come from. Move-only.
class LODRT_API PackSource {
public:
    PackSource() = default;
    ~PackSource();
    PackSource(PackSource&& other) noexcept;
    PackSource& operator=(PackSource&& other) noexcept;
    PackSource(const PackSource&) = delete;
    PackSource& operator=(const PackSource&) = delete;

    /// The whole pack in memory (GLB or .gltf); the bytes must outlive the source. Index values are
    /// not scanned here (options->skip_index_check is forced on); readLevel checks them.
    /// Returns loadPack's and buildModels' results; the message says which step failed.
    Result openBytes(const uint8_t* data, size_t size, const LoadOptions* options, char* error_message = nullptr,
                     size_t error_message_size = 0);
    /// A GLB of file_size bytes read through `reader`: reads the 12-byte header and the JSON chunk
    /// (two or three calls), loads it with loadPackJson and builds the models. Returns BadMagic,
    /// UnsupportedVersion, Truncated, TrailingBytes, BadChunk for a broken container; the reader's
    /// error; loadPackJson's and buildModels' results.
    Result openReader(const RangeReader& reader, uint64_t file_size, const LoadOptions* options,
                      char* error_message = nullptr, size_t error_message_size = 0);

    const Pack& pack() const { return pack_; }
    const ModelSet& models() const { return models_; }
    /// Bytes readLevel writes for a level (its LevelInfo::data_size).
    uint64_t levelBytes(uint32_t model, uint32_t level) const { return models_.modelLevel(model, level).data_size; }

    /// Reads (or copies) the level's BIN range into dst[0, capacity) and checks every index value of
    /// the level's primitives against their vertex counts. Thread-safe (const; the reader must be).
    /// Returns Ok; BufferTooSmall; BadGltf when the level has no data in the BIN chunk; OutOfBounds
    /// for an index out of range; the reader's error.
    Result readLevel(uint32_t model, uint32_t level, uint8_t* dst, size_t capacity) const;

    /// Reads bytes [offset, offset + size) of buffer view `view` into dst: part of a blob fetched on
    /// demand, e.g. a growing prefix of a LODBAKE_progressive_fans PFRep blob (openPfrepPrefix /
    /// pfrepExtendPrefix). Thread-safe like readLevel. Returns Ok; InvalidArgument (view out of
    /// range, null dst with size > 0); OutOfBounds when the range leaves the view; BadGltf when the
    /// view's bytes are not in the GLB BIN chunk; the reader's error.
    Result readBufferView(uint32_t view, uint64_t offset, uint8_t* dst, size_t size) const;

    /// Pointer to accessor `accessor`'s first element inside a level's bytes as readLevel wrote them
    /// (`level_bytes`); null when the accessor has no buffer view or lies outside the level's range.
    const uint8_t* accessorData(uint32_t model, uint32_t level, const uint8_t* level_bytes, uint32_t accessor) const;

    /// Index values of a level (every TRIANGLES primitive of its mesh, in primitive order; a
    /// non-indexed primitive contributes 0, 1, 2, ...), the bound copyLevelIndices needs.
    uint64_t levelIndexCount(uint32_t model, uint32_t level) const;
    /// Widens the level's index buffers (u8/u16/u32) from `level_bytes` (as readLevel wrote them)
    /// into out[0, capacity) as uint32, concatenated in primitive order; `*written` receives the
    /// count. Indices keep their per-primitive meaning (primitives of one baked level share one
    /// vertex stream). Returns Ok, BufferTooSmall, InvalidArgument (bad ids or null bytes).
    Result copyLevelIndices(uint32_t model, uint32_t level, const uint8_t* level_bytes, uint32_t* out, size_t capacity,
                            size_t* written) const;

    /// Memory a Streamer allocates for the model's format 3 or 4 PFRep blob (docs/format/pfrep.md
    /// "Format 3", "In a glTF pack"): the decoded format 2 bytes it keeps resident, and the scratch
    /// one decode takes meanwhile, read from the blob's header (one readBufferView of its first
    /// bytes; format 4 also reads LOD0's valence stream once, into a transient buffer from the
    /// pack's allocator). Format 5 (region blocks): the allocation it keeps (format 2 buffer and
    /// region state) and, as scratch, the opening's read; block reads in flight come on top, at
    /// most pfrep_blocks_per_request blocks per request. Both 0 when the model has no PFRep or a
    /// format 2 one. Returns Ok;
    /// InvalidArgument (bad model id, null outputs); BadStructure (an extension without a valid
    /// bufferView); the read's or pfrepCompressedInfo's error (the streamer fails such a stream too).
    Result pfrepDecodeMemory(uint32_t model, uint64_t* decoded_bytes, uint64_t* scratch_bytes) const;

private:
    void release();
    Result format4DecodeMemory(uint32_t model, const uint8_t* header, uint64_t* decoded_bytes,
                               uint64_t* scratch_bytes) const;
    Pack pack_;
    ModelSet models_;
    Allocator allocator_;
    const uint8_t* bin_ = nullptr; // bytes mode
    RangeReader reader_;
    uint64_t bin_offset_ = 0; // reader mode: file offset of the BIN payload
    uint8_t* json_ = nullptr; // reader mode: the JSON chunk, owned
};

/// The engine's job system: submit() must eventually call run(task) exactly once, on any thread.
/// A null submit runs jobs inline inside Streamer::update (for tools and tests; that blocks).
struct JobSystem {
    void (*submit)(void* user, void (*run)(void* task), void* task) = nullptr;
    void* user = nullptr;
};

/// Zero-initialised means defaults.
struct StreamerOptions {
    Allocator allocator;        // level memory and the streamer's tables
    uint64_t budget_bytes = 0;  // resident + in-flight level, PFRep prefix and decoded cluster page
                                // bytes; 0 = unlimited. Coarsest levels, PFRep directories and root
                                // cluster pages are always loaded and count towards it, but are
                                // never evicted. A growing prefix holds its old
                                // and its new buffer while the step is read: both count.
    uint32_t max_in_flight = 0; // jobs outstanding at once; 0 means 4
    uint32_t pfrep_blocks_per_request = 0; // region blocks (format 5 PFRep) one job reads and lays out;
                                           // 0 means 16; at most kMaxPfrepBlocksPerRequest
};

constexpr uint32_t kMaxPfrepBlocksPerRequest = 64;

struct StreamStats {
    uint64_t resident_bytes = 0;  // level, PFRep prefix and cluster page bytes held now
    uint64_t in_flight_bytes = 0; // level and PFRep prefix buffer bytes being read, and the bytes
                                  // reserved for the cluster pages being read and decoded
    uint64_t streamed_bytes = 0;  // total bytes read since init
    uint32_t resident_levels = 0;
    uint32_t requests = 0;  // jobs submitted since init
    uint32_t evictions = 0; // levels dropped since init
    uint32_t failures = 0;  // levels, PFRep steps, cluster tables or cluster pages whose read or
                            // check failed (never retried)
    uint64_t pfrep_resident_bytes = 0; // PFRep prefix bytes held now (part of resident_bytes)
    uint32_t pfrep_shrinks = 0;        // PFRep prefixes shortened by one step to make room
    // Format 3 whole-blob decodes started; each job allocates two buffers (the decoded blob, and
    // the coded blob with the decoder's scratch) where a read allocates one.
    uint32_t pfrep_decodes = 0;
    uint64_t cluster_resident_bytes = 0; // decoded cluster page bytes held now (part of resident_bytes)
    uint32_t cluster_resident_pages = 0;
    uint32_t cluster_page_reads = 0;     // page reads started since init (each followed by a decode)
    uint32_t cluster_page_evictions = 0; // pages dropped to make room since init
    uint32_t pfrep_blocks_loaded = 0;    // format 5 PFRep region blocks made resident since init
};

enum class LevelState : uint8_t { Absent, Loading, Resident, Failed };

/// None: the model has no LODBAKE_progressive_fans. Absent: not even the directory is resident yet
/// (format 5: the root block). Loading: a step (format 5: a set of blocks) is being read (the
/// previous prefix stays usable). Resident: a prefix (format 5: the root block and any others) is
/// held. Failed: the header, directory, extension object or a step (format 5: the opening or the
/// root block) was bad; a prefix validated before the failure stays usable, but the stream never
/// grows again. A format 5 block other than the root that fails is counted in failures and never
/// read again; the stream stays Resident and refinement never inserts its vertices.
enum class PfrepStreamState : uint8_t { None, Absent, Loading, Resident, Failed };

/// A resident cluster page as clusterPageDecode wrote it: `vertex_count` positions (3 floats each)
/// and `triangle_count` triangles (3 page-local indices each), every cluster's triangles at its
/// ClusterPlace range. Valid until the next update().
struct ClusterPageData {
    const float* positions = nullptr;
    const uint32_t* indices = nullptr;
    uint32_t vertex_count = 0;
    uint32_t triangle_count = 0;
};

class LODRT_API Streamer {
public:
    Streamer() = default;
    /// Waits for outstanding jobs (yielding), then frees everything.
    ~Streamer();
    Streamer(const Streamer&) = delete;
    Streamer& operator=(const Streamer&) = delete;

    /// source must not be null and must outlive the streamer; jobs may be null (jobs run inline in
    /// update). Returns Ok, OutOfMemory, or InvalidArgument.
    Result init(const PackSource* source, const JobSystem* jobs, const StreamerOptions* options);

    /// Frame step: collects finished jobs, evicts, and submits new requests for `demand`
    /// (source->models().modelCount() entries, from accumulateDemand; null = coarsest levels only).
    /// Never waits for a job. Allocates only level buffers for new requests.
    void update(const ModelDemand* demand);

    /// model * kMaxLevels + level -> finest resident level at or coarser than `level`, or kNoLevel.
    /// Valid until the next update(); pass it to selectLevels.
    const uint8_t* residentTable() const { return resident_table_; }
    LevelState state(uint32_t model, uint32_t level) const;
    /// Bytes of a resident level (as PackSource::readLevel wrote them), or null.
    const uint8_t* levelData(uint32_t model, uint32_t level, size_t* size) const;
    StreamStats stats() const { return stats_; }
    /// The model's PFRep as streamed so far: a validated prefix (lodrt/pfrep.h) whose levels
    /// k >= loaded_from can be extracted exactly as from the whole blob, and which selective
    /// refinement can use as is. Null when the model has no PFRep or its directory has not arrived.
    /// The model and the bytes it points to are valid until the next update() (a step that arrives
    /// moves the bytes); criterion_table is always null (attach a table per prefix if wanted).
    /// Instance masks stay valid while the prefix grows; when loaded_from rises (the prefix was
    /// shrunk for the budget) reset them (pfrepMaskCoarsest) before refining again.
    /// Format 5: the region model (`resident` bits set), non-null once the root block is resident;
    /// its address stays the same and blocks only ever arrive, so masks stay valid.
    const PfrepModel* pfrepModel(uint32_t model) const;
    /// Format 5: the opened region blob (directory, block_loaded, loaded_bytes; `model` as above), or
    /// null (another format, or not opened yet). Valid until the next update().
    const PfrepRegions* pfrepRegions(uint32_t model) const;
    /// Format 5: reports one instance's view of `model` (in the model's space, as given to
    /// pfrepRefine) before update(); the blocks it needs (pfrepRegionBlocksNeeded at its insert
    /// threshold: hysteresis 1, no cull band, enough because blocks are never evicted) are wanted
    /// this frame with `priority` (> 0, as ModelDemand::priority; the largest of the views needing a
    /// block counts). Calls accumulate until update(). Tests every block's bounds once; no
    /// allocation; ignores other formats, bad ids and streams not opened yet.
    void wantPfrepBlocks(uint32_t model, const PfrepView& view, float priority);
    PfrepStreamState pfrepState(uint32_t model) const;
    /// Finest chain level whose PFRep level (`levels[l].removals` of the extension) the resident
    /// prefix covers, or kNoLevel (directory only, no PFRep, bad model id).
    uint8_t pfrepLevel(uint32_t model) const;
    /// True when no job is outstanding.
    bool idle() const { return busy_tasks_ == 0; }

    /// The model's open cluster table, or null (no LODBAKE_cluster_lod, or a table that failed to
    /// read or validate: counted in failures, the model's levels stream as usual). Valid while the
    /// streamer lives.
    const ClusterLodPack* clusterPack(uint32_t model) const;
    /// Per group of clusterPack(model): nonzero when the pages of all its input clusters are
    /// resident, closed upward (clusterGroupResidency): the `group_resident` to pass to
    /// selectClusterCutResident. Null until every page holding a root is resident (the hierarchy
    /// cannot be drawn before), and for a model without a table. Valid until the next update().
    const uint8_t* clusterGroupResident(uint32_t model) const;
    /// Absent, Loading (read or decode running), Resident or Failed (read, header or decode failed;
    /// never retried: the cut keeps drawing the coarser clusters there).
    LevelState clusterPageState(uint32_t model, uint32_t page) const;
    /// The decoded page; false when it is not resident.
    bool clusterPageData(uint32_t model, uint32_t page, ClusterPageData* out) const;
    /// Reports this frame's cut of one instance of `model`, before update(): the clusters it drew
    /// (`drawn`, selectClusterCutResident's output) and the groups it listed as missing. The pages
    /// holding the drawn clusters' and missing groups' inputs, and those of every group above them
    /// (the residency closure needs them), are wanted this frame; absent ones are requested, coarser
    /// groups' pages first, with `priority` (> 0, as ModelDemand::priority). Calls accumulate until
    /// update(). No allocation; ignores bad ids.
    void wantClusterPages(uint32_t model, const uint32_t* drawn, uint32_t drawn_count, const uint32_t* missing,
                          uint32_t missing_count, float priority);

    struct Task; // internal

private:
    struct Slot {
        uint8_t* data;
        uint64_t size;
        float usefulness;
        uint32_t task; // index into tasks_ while Loading
        LevelState state;
        uint8_t is_coarsest;
    };
    struct PfrepStream {
        PfrepModel steps[kMaxLevels + 1]; // validated prefix per step 0..step (0: directory only)
        uint64_t step_bytes[kMaxLevels + 1]; // prefix bytes of each step, non-decreasing
        uint32_t removals[kMaxLevels];        // PFRep level of each chain level
        uint8_t header[format::kPfrepHeaderSize];
        uint8_t* data;          // the resident prefix, step_bytes[step] bytes
        uint32_t view;          // buffer view of the blob
        uint64_t view_size;
        uint64_t directory_bytes; // 0 until the header arrived
        float usefulness;       // of the next step (candidate)
        float held_usefulness;  // of the resident top step (eviction)
        int32_t step;           // -1: no prefix yet
        uint32_t step_count;    // chain levels + 1
        PfrepStreamState state;
        uint8_t is_failed;
        uint8_t format;         // 2: streamed as prefixes; 3, 4: read whole and decoded (to format 2)
        size_t scratch_bytes;   // format 3: pfrepDecompress scratch
        // Format 4: LOD0's valence stream, [lod0_offset, + lod0_size) of level 0's bytes (slot
        // lod0_slot), which must be resident when the blob is decoded.
        uint64_t lod0_offset;
        uint64_t lod0_size;
        uint32_t lod0_slot;
        // Format 5 (region blocks): `data` holds the format 2 buffer, the region state and the arrays
        // below (directory_bytes in all, allocated when the opening is requested).
        PfrepRegions regions;
        uint64_t open_bytes; // header, directory and skeleton
        uint32_t block_count;
        uint8_t is_open;
        uint8_t* claimed;                          // ranks staged by the running job
        float* block_priority;                     // per block: this frame's largest wanting priority
        uint8_t* block_state;                      // per block: a LevelState
        uint32_t* needed;                          // per block: scratch of wantPfrepBlocks and the batch choice
        uint32_t batch[kMaxPfrepBlocksPerRequest]; // the next request's blocks, in increasing order
        uint32_t batch_count;
        uint64_t batch_bytes;
    };
    struct ClusterModel {
        ClusterLodPack pack;
        ClusterPackSource source;
        void* memory;             // the table, its open memory and the arrays below, one allocation
        uint8_t* page_resident;   // per page
        uint8_t* group_resident;  // per group
        uint32_t* group_stamp;    // per group: frame of the last wantClusterPages visit
        uint32_t* stack;          // per group
        uint32_t* output_first;   // group_count + 1: each group's outputs' parent groups in output_parent
        uint32_t* output_parent;
        uint32_t first_page;      // into pages_
        uint8_t has_table;
        uint8_t is_dirty;         // page residency changed: rebuild group_resident
        uint8_t is_drawable;      // every root page resident
    };
    struct PageSlot {
        uint8_t* data;         // positions, then indices
        uint64_t size;         // resident bytes
        uint64_t estimate;     // bytes reserved before the header is known (an upper bound)
        uint32_t vertex_bound; // sum of its clusters' vertex counts
        uint32_t vertex_count, triangle_count;
        uint32_t model;
        uint32_t depth;        // of the group whose inputs it holds; 0 for root pages
        uint32_t last_wanted;  // cluster frame
        float priority;        // of the frame it was last wanted in
        float usefulness;
        LevelState state;
        uint8_t is_pinned;
    };
    Result initClusterModel(uint32_t model, uint32_t* page_count);
    bool initClusters();
    void markClusterGroup(ClusterModel& cm, uint32_t group, float priority);
    void markClusterPage(uint32_t page, float priority);
    void scoreClusterPages();
    void evictPage(uint32_t page);
    void collectClusterRead(Task& t);
    void collectClusterDecode(Task& t);
    bool prepareClusterTask(Task& t, uint32_t page, uint64_t size);
    void rebuildClusterResidency();
    void collect();
    void evict(uint32_t slot);
    bool shrinkPfrep(uint32_t stream);
    Result readCompressedHeader(PfrepStream& ps);
    void collectPfrepWhole(Task& t, Result& r);
    bool preparePfrepWhole(Task& t, PfrepStream& ps, uint64_t size);
    void initPfrepStream(uint32_t model);
    Result readRegionHeader(PfrepStream& ps);
    void scoreRegionStream(PfrepStream& ps);
    bool prepareRegionTask(Task& t, PfrepStream& ps, uint64_t size);
    void collectRegionOpen(Task& t, Result& r);
    void collectRegionBlocks(Task& t, Result& r);
    void rebuildResidentTable();
    // update() in steps: score what is wanted, rank the requests, make room, start one.
    void scoreLevels(const ModelDemand* demand);
    void scorePfrepStreams(const ModelDemand* demand);
    float usefulness(uint32_t id) const;
    uint32_t rankCandidates();
    uint64_t requestBytes(uint32_t id, bool* is_pinned) const;
    uint32_t leastUsefulVictim(float useful) const;
    bool makeRoom(uint64_t size, float useful);
    bool prepareTask(uint32_t task_index, uint32_t id, uint64_t size);
    void release();
    const PackSource* source_ = nullptr;
    JobSystem jobs_;
    StreamerOptions options_;
    Slot* slots_ = nullptr; // model.first_level + level
    uint32_t slot_count_ = 0;
    uint32_t* slot_model_ = nullptr;
    uint32_t* candidates_ = nullptr;
    Task* tasks_ = nullptr;
    uint32_t task_count_ = 0;
    uint32_t busy_tasks_ = 0;
    uint8_t* resident_table_ = nullptr;
    PfrepStream* pfrep_ = nullptr; // one per model
    uint32_t pfrep_count_ = 0;
    ClusterModel* clusters_ = nullptr; // one per model
    PageSlot* pages_ = nullptr;        // every model's pages
    uint32_t page_count_ = 0;
    uint32_t cluster_frame_ = 1;
    StreamStats stats_;
};

} // namespace lodrt
